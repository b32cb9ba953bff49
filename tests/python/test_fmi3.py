"""The FMI 3.0 Co-Simulation FMU (`mbfmu pack --fmi 3`) through fmpy's FMI 3 API, on every
example model, against the FMI 2.0 FMU of the same model (itself checked against
independent references by test_fmu_linearization.py and test_fmu_results.py):

- A, B, C, D from fmi3GetDirectionalDerivative (one seed per known) and from
  fmi3GetAdjointDerivative (one seed per unknown) equal the FMI 2 FMU's
  fmi2GetDirectionalDerivative matrices to 1e-12 relative (one LU of Eq. 34 in all three;
  they differ only in which triangular solves run, round-off ~1e-15 here);
- fmpy.simulate_fmu gives the FMI 2 trajectory bit for bit (one engine);
- fmpy.validation.validate_fmu reports no problem;
- bad calls return fmi3Error with a message and leave the instance usable; a step cut
  short by solver.maxSteps returns fmi3Discard with lastSuccessfulTime the time reached.

fmpy 0.3.x quirks (NOTES.md): getAdjointDerivative sizes its result by the unknowns unless
nSensitivity is passed (the number of knowns is); its reader looks for the FMI 2 spelling
providesDirectionalDerivative, so the flags are read from the XML here.
"""

import xml.etree.ElementTree as ET
import zipfile
from ctypes import byref
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64
from fmpy.validation import validate_fmu

from fmu_helpers import MODELS, run_mbfmu

EXAMPLES = sorted(p.stem for p in MODELS.glob("*.xml"))


def pack(model: Path, dest: Path, fmi: str) -> Path:
    fmu = dest / f"{model.stem}-fmi{fmi}.fmu"
    r = run_mbfmu("pack", str(model), "-o", str(fmu), "--fmi", fmi)
    assert r.returncode == 0, r.stderr
    return fmu


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """fmus(name) -> (FMI 2 FMU, FMI 3 FMU) of models/<name>.xml, packed once."""
    cache = {}

    def get(name):
        if name not in cache:
            d = tmp_path_factory.mktemp(f"fmi3-{name}")
            cache[name] = (pack(MODELS / f"{name}.xml", d, "2"), pack(MODELS / f"{name}.xml", d, "3"))
        return cache[name]

    return get


def instance(fmu: Path, cls, messages=None):
    md = read_model_description(str(fmu))
    kwargs = dict(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier)
    f = cls(instanceName="t", **kwargs)
    if cls is FMU3Slave:
        log = None if messages is None else (lambda env, status, cat, msg: messages.append(msg.decode()))
        f.instantiate(logMessage=log)
    else:
        f.instantiate()
    return md, f


def started(fmu2: Path, fmu3: Path, steps: int = 10, h: float = 0.005):
    """Both FMUs initialized at t = 0 and stepped `steps` times by `h`."""
    md2, f2 = instance(fmu2, FMU2Slave)
    md3, f3 = instance(fmu3, FMU3Slave)
    f2.setupExperiment(startTime=0.0)
    f2.enterInitializationMode()
    f2.exitInitializationMode()
    f3.enterInitializationMode(startTime=0.0)
    f3.exitInitializationMode()
    for k in range(steps):
        f2.doStep(k * h, h)
        f3.doStep(k * h, h)
    return md2, f2, md3, f3


def knowns_unknowns(md):
    """States and inputs (knowns), state derivatives and outputs (unknowns): value references."""
    states = [v for v in md.modelVariables if v.derivative is not None]
    knowns = [v.derivative.valueReference for v in states]
    knowns += [v.valueReference for v in md.modelVariables if v.causality == "input"]
    unknowns = [v.valueReference for v in states] + [u.variable.valueReference for u in md.outputs]
    return knowns, unknowns


@pytest.mark.parametrize("name", EXAMPLES)
def test_directional_and_adjoint_derivatives_equal_the_fmi2_matrices(fmus, name):
    fmu2, fmu3 = fmus(name)
    md2, f2, md3, f3 = started(fmu2, fmu3)
    knowns, unknowns = knowns_unknowns(md3)
    assert (knowns, unknowns) == knowns_unknowns(md2)
    if not knowns:
        pytest.skip(f"{name} has no states and no inputs (a driven mechanism): no derivative to compare")
    eye_k, eye_u = np.eye(len(knowns)), np.eye(len(unknowns))
    j2 = np.array([f2.getDirectionalDerivative(unknowns, knowns, list(e)) for e in eye_k]).T
    j3 = np.array([f3.getDirectionalDerivative(unknowns, knowns, list(e)) for e in eye_k]).T
    j3a = np.array([f3.getAdjointDerivative(unknowns, knowns, list(e), nSensitivity=len(knowns)) for e in eye_u])
    scale = 1.0 + np.abs(j2).max()
    assert np.abs(j3 - j2).max() <= 1e-12 * scale, name
    assert np.abs(j3a - j2).max() <= 1e-12 * scale, name
    # Any seed: a matrix-vector product (one solve per column kind).
    s = np.linspace(-1.0, 1.0, len(knowns))
    assert np.abs(np.array(f3.getDirectionalDerivative(unknowns, knowns, list(s))) - j2 @ s).max() <= 1e-12 * scale
    w = np.linspace(1.0, -0.5, len(unknowns))
    adj = f3.getAdjointDerivative(unknowns, knowns, list(w), nSensitivity=len(knowns))
    assert np.abs(np.array(adj) - w @ j2).max() <= 1e-12 * scale
    for f in (f2, f3):
        f.terminate()
        f.freeInstance()


@pytest.mark.parametrize("name", EXAMPLES)
def test_simulate_fmu_gives_the_fmi2_trajectory(fmus, name):
    fmu2, fmu3 = fmus(name)
    r2 = simulate_fmu(str(fmu2), stop_time=0.5, output_interval=0.01)
    r3 = simulate_fmu(str(fmu3), stop_time=0.5, output_interval=0.01)
    r3e = simulate_fmu(str(fmu3), stop_time=0.5, output_interval=0.01, use_event_mode=True)
    assert r2.dtype.names == r3.dtype.names and len(r2) == len(r3) == 51
    for n in r2.dtype.names:
        assert np.array_equal(r2[n], r3[n]), n
        assert np.array_equal(r2[n], r3e[n]), n


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_fmu_validates_and_declares_both_derivatives(fmus, name):
    _, fmu3 = fmus(name)
    assert validate_fmu(str(fmu3)) == []
    with zipfile.ZipFile(fmu3) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        assert any(n.startswith("binaries/x86_64-linux/") for n in z.namelist())
    cs = root.find("CoSimulation")
    assert root.get("fmiVersion") == "3.0"
    assert cs.get("providesDirectionalDerivatives") == "true"
    assert cs.get("providesAdjointDerivatives") == "true"
    # Every state derivative is a ContinuousStateDerivative, every output an Output.
    md = read_model_description(str(fmu3))
    derivs = {v.valueReference for v in md.modelVariables if v.derivative is not None}
    listed = {int(e.get("valueReference")) for e in root.find("ModelStructure").findall("ContinuousStateDerivative")}
    assert listed == derivs


def test_bad_calls_are_refused_with_a_message_and_the_instance_stays_usable(fmus):
    fmu2, fmu3 = fmus("cart_pendulum_pid")
    messages = []
    md, f = instance(fmu3, FMU3Slave, messages)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    with pytest.raises(FMICallException):
        f.doStep(0.0, 0.01)  # not initialized
    assert any("fmi3DoStep: not allowed in state Instantiated" in m for m in messages), messages
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    knowns, unknowns = knowns_unknowns(md)
    param = next(v.valueReference for v in md.modelVariables if v.causality == "parameter")
    with pytest.raises(FMICallException):
        f.getDirectionalDerivative(unknowns, [param], [1.0])
    assert any("is neither a state nor an input" in m for m in messages), messages
    with pytest.raises(FMICallException):
        f.getAdjointDerivative(unknowns, knowns, [1.0] * len(unknowns), nSensitivity=len(unknowns) + 1)
    assert any("nSensitivity" in m for m in messages), messages
    with pytest.raises(FMICallException):
        f.getFloat64([10**6])
    with pytest.raises(FMICallException):
        f.setFloat64([vr["time"]], [1.0])
    # Still usable: steps and derivatives work.
    f.doStep(0.0, 0.01)
    assert f.getFloat64([vr["time"]]) == [pytest.approx(0.01, abs=1e-15)]
    assert len(f.getDirectionalDerivative(unknowns, knowns, [1.0] * len(knowns))) == len(unknowns)
    f.terminate()
    f.freeInstance()


def test_a_step_cut_by_max_steps_is_discarded_at_the_time_reached(fmus):
    _, fmu3 = fmus("double_pendulum")
    messages = []
    md, f = instance(fmu3, FMU3Slave, messages)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    f.setInt32([vr["solver.maxSteps"]], [2])
    flags = [fmi3Boolean() for _ in range(3)]
    last = fmi3Float64()
    status = f.dll.fmi3DoStep(
        f.component, fmi3Float64(0.0), fmi3Float64(5.0), fmi3Boolean(True), *map(byref, flags), byref(last)
    )
    assert status == 2  # fmi3Discard
    assert [b.value for b in flags] == [False, False, False]
    assert 0.0 < last.value < 5.0
    assert f.getFloat64([vr["time"]]) == [last.value]
    assert any("fmi3DoStep" in m and "stopped" in m for m in messages), messages
    f.terminate()
    f.freeInstance()


def test_derivatives_in_initialization_mode_are_those_at_the_start(fmus):
    # FMI 3 allows both derivative functions in Initialization Mode: the engine is built
    # there with the values set, so they equal those right after initialization (t = 0).
    fmu2, fmu3 = fmus("cart_pendulum_pid")
    md, f = instance(fmu3, FMU3Slave)
    knowns, unknowns = knowns_unknowns(md)
    f.enterInitializationMode(startTime=0.0)
    seed = list(np.linspace(0.5, -1.0, len(knowns)))
    weights = list(np.linspace(-1.0, 2.0, len(unknowns)))
    during = f.getDirectionalDerivative(unknowns, knowns, seed)
    during_adj = f.getAdjointDerivative(unknowns, knowns, weights, nSensitivity=len(knowns))
    f.exitInitializationMode()
    assert f.getDirectionalDerivative(unknowns, knowns, seed) == during
    assert f.getAdjointDerivative(unknowns, knowns, weights, nSensitivity=len(knowns)) == during_adj
    f.terminate()
    f.freeInstance()
