"""`mbfmu.eigenvalues(model, at, modes=K, shift=σ)`: the K eigenvalues nearest a shift of a
model file (the tool's shift-invert route) and of its FMU (dense eigenvalues of the
directional-derivative A), against the closed forms in the example models' headers and
against each other."""

import numpy as np
import pytest
from conftest import MODELS

import mbfmu
from mbfmu import ArgumentError

G = 9.80665
# Double pendulum (m = L = 1, models/double_pendulum.xml): ω² = (g/L)(3 ∓ 6/√7).
W = [np.sqrt(G * (3 - 6 / np.sqrt(7))), np.sqrt(G * (3 + 6 / np.sqrt(7)))]
HANGING = {"th1": 0.0, "th2": 0.0}
# 1e-9 relative: the tool's Arnoldi converges to 1e-13 relative residual; the integrator
# tolerance 1e-10 bounds what the operating point adds.
REL = 1e-9


def by_imag(ev):
    """Sorted by imaginary part (rounded: real parts of round-off size must not decide)."""
    ev = np.asarray(ev)
    return ev[np.lexsort((ev.real, np.round(ev.imag, 6)))]


def test_the_lowest_modes_of_a_model_file_are_the_closed_form():
    (s,) = mbfmu.eigenvalues(MODELS / "double_pendulum.xml", modes=2, start_values=HANGING, tolerance=1e-10)
    assert s.route == mbfmu.spectrum.SHIFT_INVERT and s.shift == 0
    assert sorted(s.eigenvalues.imag) == pytest.approx([-W[0], W[0]], rel=REL)
    assert np.all(np.abs(s.eigenvalues.real) < REL * W[0])
    rows = s.eigen_table()
    assert len(rows) == 1 and rows[0].frequency == pytest.approx(W[0], rel=REL)
    assert "2 eigenvalues nearest 0 (shift-invert" in str(s)


def test_a_complex_shift_picks_the_mode_nearest_a_frequency():
    # Damped spring-mass at equilibrium (x0 = 0): λ = −1 ± 9.9498743710662i (its header).
    (s,) = mbfmu.eigenvalues(MODELS / "spring_mass_damper.xml", modes=1, shift=10j, start_values={"x0": 0.0})
    assert s.eigenvalues[0] == pytest.approx(complex(-1.0, 9.9498743710662), rel=REL)
    (s,) = mbfmu.eigenvalues(MODELS / "double_pendulum.xml", modes=1, shift=-1.1j * W[1], start_values=HANGING)
    assert s.eigenvalues[0] == pytest.approx(complex(0.0, -W[1]), abs=REL * W[1])
    (row,) = s.eigen_table()  # shown as its pair, Im ≥ 0
    assert f"nearest 0{-1.1 * W[1]:+g}i" in str(s)
    assert row.imag == pytest.approx(W[1], rel=REL)


def test_the_fmu_and_the_model_file_agree(packed, tmp_path):
    fmu = mbfmu.pack(MODELS / "double_pendulum.xml", tmp_path / "dp.fmu", start_values=HANGING)
    for shift in (0.0, 6.0, 1j * W[1]):
        (a,) = mbfmu.eigenvalues(fmu, modes=2, shift=shift, tolerance=1e-10)
        (b,) = mbfmu.eigenvalues(MODELS / "double_pendulum.xml", modes=2, shift=shift, start_values=HANGING)
        assert a.route == mbfmu.spectrum.FULL_FMU
        assert by_imag(a.eigenvalues) == pytest.approx(by_imag(b.eigenvalues), abs=REL * W[1])
    # All of them: the model file's full route and the FMU's A.
    (a,) = mbfmu.eigenvalues(fmu, tolerance=1e-10)
    (b,) = mbfmu.eigenvalues(MODELS / "double_pendulum.xml", start_values=HANGING, tolerance=1e-10)
    assert b.route == mbfmu.spectrum.FULL_MODEL and len(a.eigenvalues) == len(b.eigenvalues) == 4
    assert by_imag(a.eigenvalues) == pytest.approx(by_imag(b.eigenvalues), abs=REL * W[1])


def test_times_come_back_in_the_order_asked():
    # The full route at two times of a swinging pendulum: each equals its own call, to
    # what two integrations at tolerance 1e-11 along different step sequences share.
    model = MODELS / "double_pendulum.xml"
    both = mbfmu.eigenvalues(model, at=[0.4, 0.1], tolerance=1e-11)
    assert [s.time for s in both] == [0.4, 0.1]
    for s in both:
        (one,) = mbfmu.eigenvalues(model, at=s.time, tolerance=1e-11)
        assert by_imag(s.eigenvalues) == pytest.approx(by_imag(one.eigenvalues), rel=1e-7)


def test_bad_arguments_raise_one_clear_error(tmp_path):
    model = MODELS / "double_pendulum.xml"
    with pytest.raises(ArgumentError, match="is not an equilibrium"):
        mbfmu.eigenvalues(model, modes=2)  # the default pose swings
    for bad in ({"modes": 0}, {"modes": 2.5}, {"modes": 2, "shift": float("nan")}, {"modes": 2, "shift": "x"}):
        with pytest.raises(ArgumentError):
            mbfmu.eigenvalues(model, **bad)
    with pytest.raises(ArgumentError, match="before the start"):
        mbfmu.eigenvalues(model, at=-1.0)
    with pytest.raises(mbfmu.FMUNotFoundError):
        mbfmu.eigenvalues(tmp_path / "missing.xml")
