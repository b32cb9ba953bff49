"""FMI 3.0 Model Exchange through fmpy (`mbfmu pack --fmi 3`, both interfaces in one FMU):
the same engine behind fmi3SetContinuousStates / fmi3GetContinuousStateDerivatives as
behind the FMI 2 functions (tests/python/test_model_exchange.py has the physics in depth).

References from outside the engine: the pendulum's elliptic-integral time to the bottom,
the same FMU's Co-Simulation run (Radau IIA against fmpy's CVode BDF), central
differences of the host-visible derivatives fmi3GetContinuousStateDerivatives against
fmi3GetDirectionalDerivative, and the fold of blade_y's chart at t = pi / (2 w).
"""

import math
import re
import zipfile
from ctypes import c_double, c_size_t
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Model, FMU3Slave

from fmu_helpers import MODELS, run_mbfmu
from test_model_exchange import agm, crossing

# The rigid examples whose chosen states parameterize the first second (as in the FMI 2
# tests; the flexible suspension is covered there, blade_y's fold below).
EXAMPLES = [m.stem for m in sorted(MODELS.glob("*.xml")) if m.stem != "blade_y"]


def pack3(model: Path, dest: Path, *extra: str) -> tuple[Path, Path, object]:
    """`mbfmu pack --fmi 3 model` into dest: (fmu, unzipped dir, model description)."""
    fmu, unzipped = dest / f"{model.stem}.fmu", dest / model.stem
    r = run_mbfmu("pack", str(model), "-o", str(fmu), "--out-dir", str(unzipped), "--fmi", "3", *extra)
    assert r.returncode == 0, r.stderr
    return fmu, unzipped, read_model_description(str(fmu))


@pytest.fixture(scope="module")
def packed3(tmp_path_factory):
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = pack3(MODELS / f"{name}.xml", tmp_path_factory.mktemp(name))
        return cache[name]

    return get


class Log:
    """An fmpy FMI 3 logMessage callback that keeps (status, message)."""

    def __init__(self):
        self.records = []

    def __call__(self, env, status, category, message):
        self.records.append((status, message.decode()))

    def errors(self):
        return [m for s, m in self.records if s == 3]


def started(unzipped: Path, md, log: Log) -> FMU3Model:
    """An FMI 3 Model Exchange instance, initialized and in Continuous-Time Mode."""
    me = FMU3Model(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.modelExchange.modelIdentifier)
    me.instantiate(logMessage=log)
    me.enterInitializationMode(startTime=0.0)
    me.exitInitializationMode()
    assert me.updateDiscreteStates() == (False, False, False, False, False, 0.0)
    me.enterContinuousTimeMode()
    return me


def test_the_description_offers_both_interfaces(packed3):
    fmu, _, md = packed3("double_pendulum")
    assert md.fmiVersion == "3.0" and md.modelExchange is not None and md.coSimulation is not None
    # fmpy calls fmi3CompletedIntegratorStep only when asked to: the fold check needs it.
    assert md.modelExchange.needsCompletedIntegratorStep
    with zipfile.ZipFile(fmu) as z:
        me = ElementTree.fromstring(z.read("modelDescription.xml")).find("ModelExchange")
    assert me.get("providesDirectionalDerivatives") == me.get("providesAdjointDerivatives") == "true"
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == ["alpha1", "alpha2", "der(alpha1)", "der(alpha2)"]


def test_pendulum_reaches_the_bottom_at_the_elliptic_integral_time(packed3):
    """From 170 deg at rest, th = 0 at K(sin(th0/2)) / w0 (models/pendulum.xml's numbers),
    to 1e-7 s (CVode's global error at rtol 1e-11, measured 1e-9 through FMI 2)."""
    fmu, _, _ = packed3("pendulum")
    m, L, J, g, th0 = 1.0, 0.5, 0.1, 9.80665, 170 * math.pi / 180
    w0 = math.sqrt(m * g * L / (J + m * L * L))
    k = math.sin(th0 / 2)
    quarter = math.pi / (2 * agm(1.0, math.sqrt(1 - k * k))) / w0
    res = simulate_fmu(
        str(fmu),
        fmi_type="ModelExchange",
        relative_tolerance=1e-11,
        output_interval=1e-3,
        stop_time=1.2,
        output=["angle"],
    )
    root = crossing(res["time"], res["angle"])
    assert abs(root - quarter) < 1e-7


@pytest.mark.parametrize("name", EXAMPLES)
def test_fmi3_model_exchange_equals_co_simulation(name, packed3):
    """Host-integrated (fmi3 ME, CVode) and self-integrated (fmi3 CS, Radau) at rtol 1e-10
    agree to 1e-6 relative to each output's size, as through FMI 2 (measured < 3e-8)."""
    fmu, _, md = packed3(name)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    opts = dict(relative_tolerance=1e-10, output_interval=0.01, stop_time=1.0, output=outputs)
    me = simulate_fmu(str(fmu), fmi_type="ModelExchange", **opts)
    cs = simulate_fmu(str(fmu), fmi_type="CoSimulation", **opts)
    assert len(me) == len(cs) == 101
    for out in outputs:
        err = np.max(np.abs(me[out] - cs[out])) / (1 + np.max(np.abs(cs[out])))
        assert err < 1e-6, f"{name}.{out}: {err:.2e}"


@pytest.mark.parametrize("name", ["double_pendulum", "benchmark_bicycle"])
def test_directional_derivatives_are_the_slopes_of_the_host_visible_derivatives(name, packed3):
    """At a state the host sets mid-swing, fmi3GetDirectionalDerivative of the state
    derivatives along each state equals the central difference of
    fmi3GetContinuousStateDerivatives (h = 1e-6 relative: truncation ~1e-12, the
    placement's round-off / h ~1e-9), to 1e-6 of the column's size."""
    _, unzipped, md = packed3(name)
    me = started(unzipped, md, Log())
    n = len(md.derivatives)
    assert me.getNumberOfContinuousStates() == n and me.getNumberOfEventIndicators() == 0
    x0 = (c_double * n)()
    me.getContinuousStates(x0, n)
    x = np.array(x0) + 0.05 * np.cos(np.arange(n))
    me.setTime(0.3)

    def dx(at):
        me.setContinuousStates((c_double * n)(*at), n)
        out = (c_double * n)()
        me.getContinuousStateDerivatives(out, n)
        return np.array(out)

    dx(x)
    ders = [d.variable.valueReference for d in md.derivatives]
    states = [d.variable.derivative.valueReference for d in md.derivatives]
    for j in range(n):
        h = 1e-6 * (1 + abs(x[j]))
        e = np.zeros(n)
        e[j] = h
        fd = (dx(x + e) - dx(x - e)) / (2 * h)
        dx(x)
        col = np.array(me.getDirectionalDerivative(ders, [states[j]], [1.0]))
        assert np.max(np.abs(col - fd)) < 1e-6 * (1 + np.max(np.abs(fd))), (j, col, fd)
    me.terminate()
    me.freeInstance()


def test_calls_of_the_other_interface_are_errors_and_the_instance_goes_on(packed3):
    """An ME instance refuses fmi3EnterStepMode and fmi3DoStep (fmi3Error, logged) and stays
    usable; the wrong state count is refused; nominals are read in Initialization Mode."""
    _, unzipped, md = packed3("pendulum")
    log = Log()
    me = FMU3Model(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.modelExchange.modelIdentifier)
    me.instantiate(logMessage=log)
    me.enterInitializationMode(startTime=0.0)
    n = me.getNumberOfContinuousStates()
    assert n == len(md.derivatives) == 2
    nominal = (c_double * n)()
    me.getNominalsOfContinuousStates(nominal, n)
    assert list(nominal) == [1.0, 1.0]
    me.exitInitializationMode()
    with pytest.raises(Exception, match="fmi3EnterStepMode failed with status 3"):
        me.fmi3EnterStepMode(me.component)
    assert "Co-Simulation function" in log.errors()[-1]
    me.enterContinuousTimeMode()
    bad = (c_double * 3)()
    with pytest.raises(Exception, match="fmi3SetContinuousStates failed with status 3"):
        me.fmi3SetContinuousStates(me.component, bad, c_size_t(3))
    assert "nx = 3" in log.errors()[-1]
    x = (c_double * n)()
    me.getContinuousStates(x, n)
    d = (c_double * n)()
    me.getContinuousStateDerivatives(d, n)
    # At rest at 170 deg: the angle's rate is 0 and the acceleration -m g L sin(th0) / J_O.
    assert d[0] == 0.0 and d[1] == pytest.approx(-9.80665 * 0.5 * math.sin(x[0]) / 0.35, rel=1e-12)
    me.terminate()
    me.freeInstance()


def test_a_co_simulation_only_fmu_refuses_model_exchange(tmp_path):
    fmu, unzipped, md = pack3(MODELS / "pendulum.xml", tmp_path, "--kind", "cs")
    assert md.modelExchange is None
    log = Log()
    me = FMU3Model(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.coSimulation.modelIdentifier)
    with pytest.raises(Exception, match="Failed to instantiate"):
        me.instantiate(logMessage=log)
    assert "packed without Model Exchange" in log.errors()[-1]
    me.freeLibrary()
    (tmp_path / "me").mkdir()
    fmu, unzipped, md = pack3(MODELS / "pendulum.xml", tmp_path / "me", "--kind", "me")
    assert md.coSimulation is None
    cs = FMU3Slave(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.modelExchange.modelIdentifier)
    with pytest.raises(Exception, match="Failed to instantiate"):
        cs.instantiate(logMessage=Log())
    cs.freeLibrary()


def test_a_step_through_the_fold_of_the_chart_is_an_error(packed3, tmp_path):
    """blade_y's y reaches its bound 12 m at t = pi / (2 w) = 0.1571 s, a fold of the chart;
    fmpy's CVode run through FMI 3 stops with fmi3Error from fmi3CompletedIntegratorStep
    in the output interval containing it, naming the state."""
    fmu, _, _ = pack3(MODELS / "blade_y.xml", tmp_path)
    errors = []

    def logger(env, status, category, message):
        if status == 3:
            errors.append(message.decode())

    with pytest.raises(Exception, match="fmi3CompletedIntegratorStep"):
        simulate_fmu(
            str(fmu),
            fmi_type="ModelExchange",
            relative_tolerance=1e-8,
            output_interval=1e-2,
            stop_time=1.0,
            logger=logger,
        )
    fold = [m for m in errors if "do not parameterize" in m]
    assert fold and "yb = " in fold[-1], errors
    t0, t1 = (float(v) for v in re.search(r"between t = (\S+) and t = (\S+) ", fold[-1]).groups())
    assert t0 <= math.pi / 20 < t1 and t1 - t0 <= 1e-2 * (1 + 1e-9)
