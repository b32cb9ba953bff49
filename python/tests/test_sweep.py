"""Sweeps: the benchmark bicycle's eigenvalues against forward speed (Meijaard et al.
2007, Fig. 3 and Table 2), serial and on a Dask LocalCluster, and the picture."""

import numpy as np
import pytest

import mbfmu

SPEEDS = [0.5, 2.0, 4.292382, 5.0, 6.024262, 8.0]


@pytest.fixture(scope="module")
def serial(packed):
    return mbfmu.sweep(packed("benchmark_bicycle"), "v", SPEEDS, at=0.0, tolerance=1e-10)


def lean_steer(ev: np.ndarray) -> np.ndarray:
    """The lean/steer eigenvalues: all but the six structural zeros (|λ| < 1e-6)."""
    return np.sort_complex(ev[np.abs(ev) > 1e-6])


def test_sweep_reproduces_table_2_and_the_stability_limits(serial):
    ev = serial.eigenvalues()
    assert ev.shape == (len(SPEEDS), 10)
    at5 = lean_steer(ev[SPEEDS.index(5.0)])
    want = np.sort_complex(np.array([-14.0783897, -0.3228664, -0.7753419 + 4.4648677j, -0.7753419 - 4.4648677j]))
    assert np.max(np.abs(at5 - want)) < 1e-6
    # The paper's weave speed 4.292382 m/s (the weave pair crosses Re = 0) and capsize
    # speed 6.024262 m/s (the capsize root crosses 0), printed to 7 digits: there the weave
    # pair has |Re| < 1e-5, and the capsize root joins the six structural zeros (|λ| < 1e-6;
    # at 5 m/s only the six are that small).
    weave = lean_steer(ev[SPEEDS.index(4.292382)])
    assert min(abs(z.real) for z in weave if abs(z.imag) > 1) < 1e-5
    small = [int(np.sum(np.abs(ev[SPEEDS.index(v)]) < 1e-6)) for v in (5.0, 6.024262)]
    assert small == [6, 7]
    assert serial.unit == "m/s"
    assert serial.linearizations[0][0].model == "benchmark_bicycle"


def test_dask_local_cluster_gives_bit_identical_results(packed, serial):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        with distributed.Client(c) as client:
            remote = mbfmu.sweep(packed("benchmark_bicycle"), "v", SPEEDS, at=0.0, tolerance=1e-10, client=client)
    for a, b in zip(serial.linearizations, remote.linearizations, strict=True):
        for k in "ABCD":
            assert np.array_equal(getattr(a[0], k), getattr(b[0], k))
    assert np.array_equal(serial.eigenvalues(), remote.eigenvalues())


def test_plot_writes_a_png_with_the_expected_axes(serial, tmp_path):
    path = tmp_path / "bicycle.png"
    ax = serial.plot(path)
    assert path.stat().st_size > 10_000
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert ax.get_xlabel() == "v (m/s)"
    assert "eigenvalue" in ax.get_ylabel()
    real_lines = [line for line in ax.get_lines() if line.get_linestyle() == "-" and len(line.get_xdata()) > 2]
    assert len(real_lines) == 10
    # The plotted real parts are the sweep's eigenvalues.
    ev = serial.eigenvalues()
    assert np.allclose(np.array([line.get_ydata() for line in real_lines]).T, ev.real)
    assert np.allclose(real_lines[0].get_xdata(), SPEEDS)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["Re λ", "Im λ"]


def test_progress_bar_and_start_values_combine(packed):
    s = mbfmu.sweep(
        packed("cart_pendulum_pid"), "kd", [5.0, 10.0], at=[0.0, 0.2], start_values={"r": 0.0}, progress=True
    )
    assert s.times == [0.0, 0.2]
    assert len(s.linearizations) == 2 and len(s.linearizations[0]) == 2
    # kd only enters A through the der(th) column of the der(th,2) row: they must differ.
    assert not np.array_equal(s.linearizations[0][0].A, s.linearizations[1][0].A)


def test_unknown_parameter_is_named(packed):
    with pytest.raises(mbfmu.ArgumentError, match=r"no variable 'speed'.*'v'|no variable 'speed'"):
        mbfmu.sweep(packed("benchmark_bicycle"), "speed", [1.0, 2.0])
