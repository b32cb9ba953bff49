"""Linearization objects: files (round trip exact; the CLI's files readable; MATLAB files
readable by scipy), the eigenvalue table (the CLI's rows), python-control conversion."""

import subprocess

import numpy as np
import pytest
from conftest import MODELS

import mbfmu
from mbfmu.pack import cli


@pytest.fixture(scope="module")
def lins(packed):
    # cart_pendulum_pid: 5 states, 1 input, 2 outputs, D != 0 (force reads r).
    return mbfmu.linearize(packed("cart_pendulum_pid"), at=[0.0, 0.5], start_values={"r": 0.05}, tolerance=1e-8)


def same(a: mbfmu.Linearization, b: mbfmu.Linearization):
    assert a.time == b.time
    for k in ("states", "inputs", "outputs", "state_units", "input_units", "output_units", "method", "model"):
        assert getattr(a, k) == getattr(b, k), k
    for k in ("A", "B", "C", "D", "x0", "u0", "y0"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k


@pytest.mark.parametrize("ext", [".npz", ".mat", ".json"])
def test_save_and_load_round_trip_exactly(lins, tmp_path, ext):
    one = tmp_path / f"one{ext}"
    lins[0].save(one)
    (back,) = mbfmu.load(one)
    same(back, lins[0])
    several = tmp_path / f"several{ext}"
    mbfmu.save(lins, several)
    for a, b in zip(mbfmu.load(several), lins, strict=True):
        same(a, b)


def test_mat_file_is_read_by_scipy_with_names(lins, tmp_path):
    from scipy.io import loadmat

    path = tmp_path / "lin.mat"
    lins[1].save(path)
    m = loadmat(path)
    assert np.array_equal(m["A"], lins[1].A) and np.array_equal(m["D"], lins[1].D)
    assert [s.rstrip() for s in m["states"]] == lins[1].states
    assert [s.rstrip() for s in m["outputs"]] == lins[1].outputs
    assert m["time"][0, 0] == 0.5


@pytest.mark.parametrize("fmt", ["json", "npz", "mat"])
def test_files_written_by_the_cli_are_loaded(packed, tmp_path, fmt):
    out = tmp_path / f"cli.{fmt}"
    r = subprocess.run(
        [
            str(cli()),
            "linearize",
            str(MODELS / "cart_pendulum_pid.xml"),
            "--at",
            "0,0.5",
            "--tol",
            "1e-8",
            "--format",
            fmt,
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    got = mbfmu.load(out)
    assert [g.time for g in got] == [0.0, 0.5]
    # The same numbers as the package's (the 1e-9 of test_linearize_mbfmu).
    refs = mbfmu.linearize(packed("cart_pendulum_pid"), at=[0.0, 0.5], tolerance=1e-8)
    for g, ref in zip(got, refs, strict=True):
        for k in "ABCD":
            want = getattr(ref, k)
            assert np.max(np.abs(getattr(g, k) - want)) <= 1e-9 * max(1.0, np.max(np.abs(want))), k
        assert g.states == ref.states and g.inputs == ref.inputs and g.outputs == ref.outputs


def test_eigen_table_has_the_rows_of_the_cli(packed):
    # The CLI prints 7 significant digits; its rows (order, pairs, damping) must be ours.
    r = subprocess.run(
        [str(cli()), "linearize", str(MODELS / "double_pendulum.xml"), "--tol", "1e-10"], capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if "Undmp. Freq." in line) + 1
    # Columns: rad/s, Hz, damping ratio, real, imaginary.
    cli_rows = [[float(x) for x in line.split()] for line in lines[start:] if line.strip()]
    rows = mbfmu.linearize(packed("double_pendulum"), tolerance=1e-10)[0].eigen_table()
    assert len(rows) == len(cli_rows) == 2
    for ours, theirs in zip(rows, cli_rows, strict=True):
        got = [ours.frequency, ours.frequency_hz, ours.damping, ours.real, ours.imag]
        for g, t in zip(got, theirs, strict=True):
            assert g == pytest.approx(t, rel=1e-6, abs=1e-12) or (np.isnan(g) and np.isnan(t))
    assert [r.frequency_hz for r in rows] == pytest.approx([r.frequency / (2 * np.pi) for r in rows], rel=1e-15)


def test_to_control_keeps_names_and_poles(lins):
    import control

    sys = lins[1].to_control()
    assert isinstance(sys, control.StateSpace)
    assert sys.state_labels == lins[1].states
    assert sys.input_labels == lins[1].inputs and sys.output_labels == lins[1].outputs
    poles = np.sort_complex(sys.poles())
    assert np.max(np.abs(poles - np.sort_complex(lins[1].eigenvalues()))) < 1e-12
    wn, zeta, _ = control.damp(sys, doprint=False)
    rows = lins[1].eigen_table()
    assert max(wn) == pytest.approx(max(r.frequency for r in rows), rel=1e-12)


def test_str_shows_the_table(lins):
    text = str(lins[0])
    assert "cart_pendulum_pid" in text and "Damping Ratio" in text and "(Hz)" in text


def test_files_without_names_get_positional_names(tmp_path):
    # Files from before the CLI wrote names (only A B C D time) still load.
    path = tmp_path / "old.npz"
    np.savez(path, A=np.eye(2), B=np.ones((2, 1)), C=np.ones((1, 2)), D=np.zeros((1, 1)), time=np.array([[0.5]]))
    (lin,) = mbfmu.load(path)
    assert lin.states == ["x1", "x2"] and lin.inputs == ["u1"] and lin.outputs == ["y1"]
    assert lin.time == 0.5
