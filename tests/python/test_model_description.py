"""Every example model packs into an FMU that fmpy validates.

fmpy's validate_fmu checks modelDescription.xml against the FMI 2.0 XSD, the variable
names (structured convention), start values, causality/variability/initial
combinations, units and the ModelStructure (Outputs, InitialUnknowns, dependency
lengths). It does not load the shared library, so these tests do not need the C API.

The release binary is the one `cargo test --release` built (.ci/run runs cargo first);
set MBFMU_BIN to use another.
"""

import os
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
MODELS = sorted((ROOT / "models").glob("*.xml"))


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
    assert md.coSimulation is not None and md.modelExchange is None
    identifier = md.coSimulation.modelIdentifier
    with zipfile.ZipFile(fmu) as z:
        assert sorted(z.namelist()) == sorted(
            ["modelDescription.xml", f"binaries/linux64/{identifier}.so", "resources/model.xml"]
        )
        assert z.read("resources/model.xml") == model.read_bytes()

    # The variables are the model's parameters, inputs and outputs, in file order, then the
    # linearization states S, their velocities der(S) and accelerations der(S,2); value
    # references 0, 1, 2, ...
    root = ET.parse(model).getroot()
    expected = [(e.get("name"), c) for tag, c in (("parameter", "parameter"), ("input", "input"), ("output", "output"))
                for e in root.iter(tag)]
    actual = [(v.name, v.causality) for v in md.modelVariables]
    assert actual[: len(expected)] == expected
    local = [name for name, c in actual[len(expected):]]
    assert all(c == "local" for _, c in actual[len(expected):])
    s = len(local) // 3
    assert len(local) == 3 * s
    assert local[s:2 * s] == [f"der({n})" for n in local[:s]]
    assert local[2 * s:] == [f"der({n},2)" for n in local[:s]]
    assert [v.valueReference for v in md.modelVariables] == list(range(len(actual)))
    assert md.defaultExperiment is not None

    # Every unit used is defined (validate_fmu checks it too) and none is unused.
    used = {v.unit for v in md.modelVariables if v.unit is not None}
    assert {u.name for u in md.unitDefinitions} == used
