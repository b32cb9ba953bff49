"""Every example model packs into an FMU that fmpy validates.

fmpy's validate_fmu checks modelDescription.xml against the FMI 2.0 XSD, the variable
names (structured convention), start values, causality/variability/initial
combinations, units and the ModelStructure (Outputs, InitialUnknowns, dependency
lengths). It does not load the shared library, so these tests do not need the C API.

The release binary is the one `cargo test --release` built (.ci/run runs cargo first);
set MBFMU_BIN to use another.
"""

import os
import re
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
# The example models, those with flexible bodies (models/flexible/) included.
MODELS = sorted((ROOT / "models").glob("*.xml")) + sorted((ROOT / "models" / "flexible").glob("*.xml"))


def mbfmu() -> Path:
    if "MBFMU_BIN" in os.environ:
        return Path(os.environ["MBFMU_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "mbfmu"


def pack(model: Path, *args: str) -> subprocess.CompletedProcess:
    exe = mbfmu()
    assert exe.is_file(), f"{exe} is missing: run `cargo build --release` first"
    return subprocess.run([str(exe), "pack", str(model), *args], capture_output=True, text=True, cwd=ROOT)


def test_there_are_example_models():
    assert len(MODELS) >= 7


@pytest.mark.parametrize("model", MODELS, ids=[m.stem for m in MODELS])
def test_packed_fmu_validates(model: Path, tmp_path: Path):
    fmu = tmp_path / f"{model.stem}.fmu"
    out_dir = tmp_path / model.stem
    r = pack(model, "-o", str(fmu), "--out-dir", str(out_dir))
    assert r.returncode == 0, r.stderr

    assert validate_fmu(str(fmu)) == []
    assert validate_fmu(str(out_dir)) == []

    md = read_model_description(str(fmu), validate=True)
    assert md.fmiVersion == "2.0"
    # The default kind is both interfaces, one shared library (the linearization states are
    # the Model Exchange states; every example model has them).
    assert md.coSimulation is not None and md.modelExchange is not None
    identifier = md.coSimulation.modelIdentifier
    assert md.modelExchange.modelIdentifier == identifier
    assert md.modelExchange.providesDirectionalDerivative
    # A flexible body's modal data file travels in resources/, under the path the model gives.
    modal = [f"resources/{f}" for f in re.findall(r'modal="([^"]+)"', model.read_text())]
    with zipfile.ZipFile(fmu) as z:
        assert sorted(z.namelist()) == sorted(
            [
                "modelDescription.xml",
                f"binaries/linux64/{identifier}.so",
                "resources/model.xml",
                "resources/states.txt",
                "resources/interfaces.txt",
                *modal,
            ]
        )
        assert z.read("resources/model.xml") == model.read_bytes()
        assert z.read("resources/interfaces.txt").decode().split() == ["ModelExchange", "CoSimulation"]

    # The variables are the model's parameters, inputs and outputs, in file order, then the
    # linearization states S, their velocities der(S) and accelerations der(S,2) (in general
    # der(W)), then X, der(X), V, and last the Integer solver.maxSteps; value references
    # 0, 1, 2, ...
    root = ET.parse(model).getroot()
    expected = [
        (e.get("name"), c)
        for tag, c in (("parameter", "parameter"), ("input", "input"), ("output", "output"))
        for e in root.iter(tag)
    ]
    last = md.modelVariables[-1]
    assert (last.name, last.type, last.causality, last.variability) == (
        "solver.maxSteps",
        "Integer",
        "parameter",
        "tunable",
    )
    assert all(v.type == "Real" for v in md.modelVariables[:-1])
    actual = [(v.name, v.causality) for v in md.modelVariables[:-1]]
    assert actual[: len(expected)] == expected
    local = [name for name, c in actual[len(expected) :]]
    assert all(c == "local" for _, c in actual[len(expected) :])
    # ... then differential states X, der(X) and user variables V last.
    diffs = [e.get("name") for e in root.iter("differential")]
    tail = diffs + [f"der({d})" for d in diffs] + [e.get("name") for e in root.iter("variable")]
    assert local[len(local) - len(tail) :] == tail
    lin = local[: len(local) - len(tail)]
    # Linearization states: S, der(S), velocity states that are no der(S) (non-holonomic
    # models), then der(W) (named der(S,2) where W = der(S)).
    # (Model names have no parentheses: S and W are the names that are no der(...).)
    descr = {v.name: v.description for v in md.modelVariables}
    s = next((k for k, n in enumerate(lin) if n.startswith("der(")), len(lin))
    assert lin[s : 2 * s] == [f"der({n})" for n in lin[:s]]
    extra = [n for n in lin[2 * s :] if not n.startswith("der(")]
    assert lin[2 * s : 2 * s + len(extra)] == extra
    # Each S and W says what it measures.
    assert all(descr[n] for n in lin[:s] + extra)
    if not root.findall("rolling_wheel") + root.findall("knife_edge") + root.findall("velocity_constraint"):
        assert extra == [] and lin[2 * s :] == [f"der({n},2)" for n in lin[:s]]
    assert [v.valueReference for v in md.modelVariables] == list(range(len(actual) + 1))
    assert md.defaultExperiment is not None

    # Every unit used is defined (validate_fmu checks it too) and none is unused.
    used = {v.unit for v in md.modelVariables if v.unit is not None}
    assert {u.name for u in md.unitDefinitions} == used


@pytest.mark.parametrize("kind", ["me", "cs", "both"])
def test_pack_kind(kind: str, tmp_path: Path):
    model = ROOT / "models" / "double_pendulum.xml"
    fmu = tmp_path / f"{kind}.fmu"
    r = pack(model, "-o", str(fmu), "--kind", kind)
    assert r.returncode == 0, r.stderr
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu), validate=True)
    assert (md.modelExchange is not None) == (kind != "cs")
    assert (md.coSimulation is not None) == (kind != "me")
    names = {"me": ["ModelExchange"], "cs": ["CoSimulation"], "both": ["ModelExchange", "CoSimulation"]}
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/interfaces.txt").decode().split() == names[kind]
    # The continuous states are the linearization states: two joint angles and their rates;
    # each derivative names its state (fmpy resolves <Derivatives> to variables).
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == ["alpha1", "alpha2", "der(alpha1)", "der(alpha2)"]


def test_pack_kind_me_fmi3_offers_model_exchange_only(tmp_path: Path):
    r = pack(ROOT / "models" / "double_pendulum.xml", "-o", str(tmp_path / "x.fmu"), "--fmi", "3", "--kind", "me")
    assert r.returncode == 0, r.stderr
    assert validate_fmu(str(tmp_path / "x.fmu")) == []
    md = read_model_description(str(tmp_path / "x.fmu"), validate=True)
    assert md.modelExchange is not None and md.coSimulation is None
