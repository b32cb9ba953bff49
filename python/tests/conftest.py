"""Fixtures of the package tests: mbfmu FMUs packed once per session, the CLI's own
linearization as a reference, and foreign FMUs compiled from foreign/vdp.c with `cc`."""

import json
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

import mbfmu
from mbfmu.pack import cli

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
EXAMPLES = ROOT / "python" / "examples"
FOREIGN = Path(__file__).resolve().parent / "foreign"


@pytest.fixture(scope="session")
def packed(tmp_path_factory):
    """packed(name) -> Path of models/<name>.xml packed by `mbfmu pack` (once); `name` may
    name a subdirectory (`flexible/suspension`)."""
    cache: dict[str, Path] = {}

    def get(name: str) -> Path:
        if name not in cache:
            stem = Path(name).name
            d = tmp_path_factory.mktemp(stem)
            cache[name] = mbfmu.pack(MODELS / f"{name}.xml", d / f"{stem}.fmu")
        return cache[name]

    return get


def cli_linearize(model: Path, at: list[float], tol: float, out: Path, *extra: str) -> list[dict]:
    """`mbfmu linearize MODEL --at ... --tol TOL [EXTRA...] --format json -o OUT`, parsed."""
    args = [str(cli()), "linearize", str(model), "--at", ",".join(repr(t) for t in at), "--tol", repr(tol), *extra]
    r = subprocess.run([*args, "--format", "json", "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(out.read_text())


# --- foreign FMUs -------------------------------------------------------------------

_VARS = """
    <ScalarVariable name="x0" valueReference="0" causality="output" variability="continuous" initial="exact">
      <Real start="2" unit="m"/></ScalarVariable>
    <ScalarVariable name="der(x0)" valueReference="2" causality="local" variability="continuous" initial="calculated">
      <Real derivative="1"/></ScalarVariable>
    <ScalarVariable name="x1" valueReference="1" causality="output" variability="continuous" initial="exact">
      <Real start="0" unit="m/s"/></ScalarVariable>
    <ScalarVariable name="der(x1)" valueReference="3" causality="local" variability="continuous" initial="calculated">
      <Real derivative="3"/></ScalarVariable>
    <ScalarVariable name="mu" valueReference="4" causality="parameter" variability="fixed" initial="exact">
      <Real start="1"/></ScalarVariable>
    <ScalarVariable name="u" valueReference="5" causality="input" variability="continuous">
      <Real start="0" unit="N"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="6" causality="output" variability="continuous" initial="calculated">
      <Real unit="m"/></ScalarVariable>
"""

_STRUCTURE = """
    <Outputs>
      <Unknown index="1" dependencies=""/>
      <Unknown index="3" dependencies=""/>
      <Unknown index="7" dependencies="1 6" dependenciesKind="dependent dependent"/>
    </Outputs>
    {derivatives}
    <InitialUnknowns>
      {initial}
      <Unknown index="7" dependencies="1 6" dependenciesKind="dependent dependent"/>
    </InitialUnknowns>
"""

_DERIVATIVES = """<Derivatives>
      <Unknown index="2" dependencies="3" dependenciesKind="dependent"/>
      <Unknown index="4" dependencies="1 3 6" dependenciesKind="dependent dependent dependent"/>
    </Derivatives>"""

_INITIAL_DERIVS = """<Unknown index="2" dependencies="3" dependenciesKind="dependent"/>
      <Unknown index="4" dependencies="1 3 5 6" dependenciesKind="dependent dependent dependent dependent"/>"""


def _model_description(dd: bool, me: bool, cs: bool, derivatives: bool) -> str:
    flag = "true" if dd else "false"
    parts = []
    if me:
        parts.append(f'<ModelExchange modelIdentifier="vdp" providesDirectionalDerivative="{flag}"/>')
    if cs:
        parts.append(
            f'<CoSimulation modelIdentifier="vdp" canHandleVariableCommunicationStepSize="true" '
            f'providesDirectionalDerivative="{flag}"/>'
        )
    structure = _STRUCTURE.format(
        derivatives=_DERIVATIVES if derivatives else "", initial=_INITIAL_DERIVS if derivatives else ""
    )
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="vdp" guid="{{vdp-mbfmu-test}}"
  numberOfEventIndicators="0" generationTool="hand-written (foreign/vdp.c)">
  {" ".join(parts)}
  <DefaultExperiment startTime="0" stopTime="10" tolerance="1e-10"/>
  <ModelVariables>{_VARS}</ModelVariables>
  <ModelStructure>{structure}</ModelStructure>
</fmiModelDescription>
"""


@pytest.fixture(scope="session")
def foreign(tmp_path_factory):
    """foreign(dd=True, me=True, cs=True, derivatives=True) -> Path of a van der Pol FMU
    compiled from foreign/vdp.c (with or without directional derivatives)."""
    if shutil.which("cc") is None:
        pytest.skip("no C compiler (cc)")
    cache: dict[tuple, Path] = {}

    def get(dd=True, me=True, cs=True, derivatives=True) -> Path:
        key = (dd, me, cs, derivatives)
        if key not in cache:
            d = tmp_path_factory.mktemp("vdp")
            (d / "binaries" / "linux64").mkdir(parents=True)
            args = [
                "cc",
                "-shared",
                "-fPIC",
                "-O2",
                "-o",
                str(d / "binaries" / "linux64" / "vdp.so"),
                str(FOREIGN / "vdp.c"),
                "-lm",
            ]
            if dd:
                args.insert(1, "-DWITH_DD")
            subprocess.run(args, check=True)
            (d / "modelDescription.xml").write_text(_model_description(dd, me, cs, derivatives))
            fmu = d.with_suffix(".fmu")
            with zipfile.ZipFile(fmu, "w") as z:
                for f in ("modelDescription.xml", "binaries/linux64/vdp.so"):
                    z.write(d / f, f)
            cache[key] = fmu
        return cache[key]

    return get
