"""Bad input gets one clear exception each, naming the problem (and the instance is freed)."""

import numpy as np
import pytest

import mbfmu


def test_missing_fmu_path(tmp_path):
    with pytest.raises(mbfmu.FMUNotFoundError, match=r"'.*nowhere\.fmu' does not exist"):
        mbfmu.linearize(tmp_path / "nowhere.fmu", at=0.0)
    assert issubclass(mbfmu.FMUNotFoundError, FileNotFoundError)


def test_not_an_fmu(tmp_path):
    junk = tmp_path / "junk.fmu"
    junk.write_bytes(b"not a zip")
    with pytest.raises(mbfmu.MbfmuError, match="cannot be read"):
        mbfmu.linearize(junk, at=0.0)


@pytest.mark.parametrize(
    "at,match", [(-1.0, "before the start time 0"), (float("nan"), "not finite"), ([], "no times")]
)
def test_bad_times(packed, at, match):
    with pytest.raises(mbfmu.ArgumentError, match=match):
        mbfmu.linearize(packed("pendulum"), at=at)


def test_unknown_parameter_with_a_suggestion(packed):
    with pytest.raises(mbfmu.ArgumentError, match=r"has no variable 'rhoo'; did you mean 'rho'"):
        mbfmu.linearize(packed("fourbar"), start_values={"rhoo": 1.0})


def test_start_value_of_a_computed_variable(packed):
    with pytest.raises(mbfmu.ArgumentError, match=r"'force'.*cannot be given a start value"):
        mbfmu.linearize(packed("cart_pendulum_pid"), start_values={"force": 1.0})


def test_failed_fmu_call_carries_the_fmu_log(packed):
    # A crank 25 times longer than the ground link: the four-bar cannot be assembled.
    with pytest.raises(mbfmu.FMUCallError, match=r"fmi2ExitInitializationMode failed(.|\n)*rocker_pin"):
        mbfmu.linearize(packed("fourbar"), at=0.1, start_values={"a": 5.0})


def test_bad_step_and_tolerance(packed):
    with pytest.raises(mbfmu.ArgumentError, match="step"):
        mbfmu.linearize(packed("pendulum"), at=0.1, step=0.0)
    with pytest.raises(mbfmu.ArgumentError, match="tolerance"):
        mbfmu.linearize(packed("pendulum"), at=0.1, tolerance=-1.0)


def test_pack_reports_the_model_error_with_its_location(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text(
        '<multibody name="bad" version="1">\n  <body name="b" mass="-1" inertia="1 1 1" '
        'position="0 0 0"/>\n</multibody>\n'
    )
    with pytest.raises(mbfmu.ArgumentError, match=r"bad\.xml:2:\d+: body 'b'"):
        mbfmu.pack(bad, tmp_path / "bad.fmu")
    with pytest.raises(mbfmu.FMUNotFoundError):
        mbfmu.pack(tmp_path / "missing.xml")


def test_sweep_needs_values(packed):
    with pytest.raises(mbfmu.ArgumentError, match="no parameter values"):
        mbfmu.sweep(packed("pendulum"), "L", np.array([]))


def test_load_rejects_unknown_files(tmp_path):
    with pytest.raises(mbfmu.ArgumentError, match="unknown file type"):
        mbfmu.load(tmp_path / "x.csv")
    with pytest.raises(mbfmu.FMUNotFoundError):
        mbfmu.load(tmp_path / "x.json")
