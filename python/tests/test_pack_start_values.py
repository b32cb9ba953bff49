"""`mbfmu.pack(..., start_values={...})` (`mbfmu pack --set`): the FMU starts from the values
given, exactly as the FMU of an edited copy of the model file does, without any value set
by the host; bad names are ArgumentErrors with the tool's suggestion."""

import math
import re
import zipfile

import numpy as np
import pytest
from conftest import MODELS
from fmpy import simulate_fmu

import mbfmu

G = 9.80665


def _edited(text: str, edits: dict[str, str]) -> str:
    """`text` with the value of each `<parameter name="...">` replaced: the edit a user makes."""
    for name, value in edits.items():
        text, n = re.subn(rf'(<parameter name="{name}" value=")[^"]*"', rf'\g<1>{value}"', text)
        assert n == 1, name
    return text


def _simulate(fmu):
    r = simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.1, relative_tolerance=1e-10)
    return np.array([list(row) for row in r])


def test_start_values_give_the_edited_models_results(tmp_path):
    model = MODELS / "pendulum.xml"
    fmu = mbfmu.pack(model, tmp_path / "set.fmu", start_values={"L": 2.0, "th0": 0.3})
    copy = tmp_path / "edited.xml"
    copy.write_text(_edited(model.read_text(), {"L": "2", "th0": "0.3"}))
    reference = mbfmu.pack(copy, tmp_path / "edited.fmu")
    plain = mbfmu.pack(model, tmp_path / "plain.fmu")

    with zipfile.ZipFile(fmu) as z:
        md = z.read("modelDescription.xml").decode()
        assert z.read("resources/model.xml") == model.read_bytes()
    assert re.search(r'name="L"[^>]*>\s*<Real unit="m" start="2"/>', md), md

    got, want, base = _simulate(fmu), _simulate(reference), _simulate(plain)
    assert got.shape == want.shape == (11, 6)
    assert np.max(np.abs(got - want)) <= 1e-12
    # Independent of the engine: θ(0) = 0.3 and E = -m g L cos θ0 (m = 1), conserved.
    assert got[0, 1] == pytest.approx(0.3, abs=1e-12)
    assert got[:, 5] == pytest.approx(-G * 2.0 * math.cos(0.3), abs=1e-6)
    assert base[0, 1] == pytest.approx(math.radians(170), abs=1e-12)


def test_a_float_round_trips(tmp_path):
    x = 0.1 + 0.2  # not 0.3: needs 17 digits
    fmu = mbfmu.pack(MODELS / "pendulum.xml", tmp_path / "p.fmu", start_values={"Jc": x})
    with zipfile.ZipFile(fmu) as z:
        md = z.read("modelDescription.xml").decode()
    start = re.search(r'name="Jc"[^>]*>\s*<Real unit="kg.m2" start="([^"]*)"/>', md).group(1)
    assert float(start) == x


def test_unknown_names_and_bad_values_are_argument_errors(tmp_path):
    model = MODELS / "pendulum.xml"
    with pytest.raises(mbfmu.ArgumentError, match=r"no parameter 'Lx'; did you mean 'L'\?"):
        mbfmu.pack(model, tmp_path / "a.fmu", start_values={"Lx": 2.0})
    with pytest.raises(mbfmu.ArgumentError, match=r"body 'bob': mass must be positive"):
        mbfmu.pack(model, tmp_path / "b.fmu", start_values={"m": -1.0})
    with pytest.raises(mbfmu.ArgumentError, match=r"finite"):
        mbfmu.pack(model, tmp_path / "c.fmu", start_values={"L": float("inf")})
    with pytest.raises(mbfmu.ArgumentError, match=r"not a number"):
        mbfmu.pack(model, tmp_path / "d.fmu", start_values={"L": "two"})
    assert not any(tmp_path.iterdir())


def test_start_values_on_states_start_the_fmu_there(tmp_path):
    # The pendulum started at θ = 1 rad, ω = -0.5 rad/s by start values on its states:
    # the FMU, told nothing, starts there, with the analytic energy
    # E = ½ (Jc + m L²) ω² − m g L cos θ (m = 1, L = 0.5, Jc = 0.1), conserved.
    fmu = mbfmu.pack(
        MODELS / "pendulum.xml", tmp_path / "s.fmu", start_values={"hinge.angle": 1.0, "der(hinge.angle)": -0.5}
    )
    got = _simulate(fmu)
    assert got[0, 1] == pytest.approx(1.0, abs=1e-12)
    assert got[0, 2] == pytest.approx(-0.5, abs=1e-12)
    e0 = 0.5 * (0.1 + 0.25) * 0.25 - G * 0.5 * math.cos(1.0)
    assert got[:, 5] == pytest.approx(e0, abs=1e-6)
    with pytest.raises(mbfmu.ArgumentError, match=r"did you mean 'hinge.angle'\?"):
        mbfmu.pack(MODELS / "pendulum.xml", tmp_path / "t.fmu", start_values={"hinge.angel": 1.0})
