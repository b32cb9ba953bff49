"""Model Exchange through fmpy: the host integrates the FMU's linearization states (fmpy's
CVode and its explicit Euler, `simulate_fmu(..., fmi_type="ModelExchange")`); the FMU
places the mechanism at every state it is given (coordinate partitioning) and returns ẋ.

References from outside the engine: the pendulum's elliptic-integral time to the bottom,
the Chaplygin sleigh's closed-form heading rate, Euler's first order of convergence, and
the same FMU's Co-Simulation run (the engine's own Radau integrator, a different method
from CVode's BDF).
"""

import math
import re
from ctypes import c_double

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model, FMU2Slave

from fmu_helpers import MODELS, ROOT, LogCapture, pack_model

# Every example whose chosen states parameterize its motion over the first second (blade_y
# linearizes in the blade's y, which stops doing so a quarter turn in: see the last test).
EXAMPLES = [m.stem for m in sorted(MODELS.glob("*.xml")) if m.stem != "blade_y"] + ["flexible/suspension"]


def agm(a: float, b: float) -> float:
    while abs(a - b) > 1e-16 * a:
        a, b = (a + b) / 2, math.sqrt(a * b)
    return a


def state_vrs(md) -> list:
    """The value references of the continuous states, in <Derivatives> order."""
    return [d.variable.derivative.valueReference for d in md.derivatives]


def set_x(me: FMU2Model, x) -> None:
    me.setContinuousStates((c_double * len(x))(*x), len(x))


def get_x(me: FMU2Model, n: int) -> list:
    out = (c_double * n)()
    me.getContinuousStates(out, n)
    return list(out)


def get_dx(me: FMU2Model, n: int) -> list:
    out = (c_double * n)()
    me.getDerivatives(out, n)
    return list(out)


def crossing(t: np.ndarray, y: np.ndarray) -> float:
    """The time of y's sign change, by a cubic through the four samples around it
    (interpolation error O(h^4) of the output grid: < 1e-10 s at h = 1 ms here)."""
    k = int(np.nonzero(np.sign(y[1:]) != np.sign(y[:-1]))[0][0])
    idx = slice(k - 1, k + 3)
    p = np.polynomial.Polynomial.fit(t[idx], y[idx], 3)
    return float(min((r.real for r in p.roots() if abs(r.imag) < 1e-12), key=lambda r: abs(r - t[k])))


def test_pendulum_reaches_the_bottom_at_the_elliptic_integral_time(packed):
    """Released at rest from th0 = 170 deg, (J + m L^2) th'' = -m g L sin th reaches th = 0
    at a quarter period, K(sin(th0/2)) / w0, and th = -th0 at half a period (seed model
    models/pendulum.xml, its comment gives the numbers)."""
    p = packed("pendulum")
    m, L, J, g, th0 = 1.0, 0.5, 0.1, 9.80665, 170 * math.pi / 180
    w0 = math.sqrt(m * g * L / (J + m * L * L))
    k = math.sin(th0 / 2)
    quarter = math.pi / (2 * agm(1.0, math.sqrt(1 - k * k))) / w0
    res = simulate_fmu(
        str(p.fmu),
        fmi_type="ModelExchange",
        solver="CVode",
        relative_tolerance=1e-11,
        output_interval=1e-3,
        stop_time=2.2,
        output=["angle", "energy"],
    )
    t, angle = res["time"], res["angle"]
    assert abs(angle[0] - th0) < 1e-12
    # 1e-7 s: CVode's global error at rtol 1e-11 over ~1 s of a motion whose time scale is
    # 1/w0 = 0.27 s (measured 1e-9); a wrong derivative (even 1e-6 relative in g) fails.
    assert abs(crossing(t, angle) - quarter) < 1e-7
    # The turning point: -th0 at 2 K / w0 (the extreme of a smooth curve: 1e-6 rad).
    i = int(np.argmin(angle))
    assert abs(t[i] - 2 * quarter) <= 1e-3 and abs(angle[i] + th0) < 1e-6
    # Energy is conserved by the mechanism; CVode's error in it is of its tolerance's order.
    e0 = -m * g * L * math.cos(th0)
    assert np.max(np.abs(res["energy"] - e0)) < 1e-7 * e0


def test_euler_converges_at_first_order(packed):
    """fmpy's explicit Euler (fmi2CompletedIntegratorStep after every step): the error of
    the pendulum's angle at t = 0.5 s halves with the step, as the method's order says;
    the reference is CVode at rtol 1e-11 (its error is < 1e-9, far below Euler's 1e-3)."""
    p = packed("pendulum")
    ref = simulate_fmu(
        str(p.fmu), fmi_type="ModelExchange", relative_tolerance=1e-11, output_interval=0.01, stop_time=0.5
    )
    errors = []
    for h in (1e-3, 5e-4, 2.5e-4):
        # fmpy's Euler takes one step per output interval: the interval is the step.
        r = simulate_fmu(
            str(p.fmu), fmi_type="ModelExchange", solver="Euler", step_size=h, output_interval=h, stop_time=0.5
        )
        assert r["time"][-1] == pytest.approx(0.5)
        errors.append(abs(r["angle"][-1] - ref["angle"][-1]))
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    # First order: each ratio is 2 up to the O(h) term of the error (measured 2.0x).
    assert all(1.8 < q < 2.2 for q in ratios), (errors, ratios)


@pytest.mark.parametrize("name", EXAMPLES)
def test_model_exchange_trajectory_equals_co_simulation(name, packed):
    """The same FMU integrated by the host (ME, CVode BDF) and by itself (CS, Radau IIA),
    both at rtol 1e-10: the outputs agree to 1e-6 relative to each output's size (two
    methods' global errors at that tolerance, measured below 3e-8; a derivative wrong
    anywhere on the way, e.g. a 2 pi jump of an angle state, is O(1)). The flexible
    suspension for 0.05 s at rtol 1e-6, to 1e-5: with its stiff modal coordinates (nominal
    1, so absolute tolerance = rtol) CVode takes ~300 derivative calls per 0.01 s and
    exceeds fmpy's step limit at rtol <= 1e-8 (measured: 1 s at 1e-6 agrees to 4.9e-7 but
    takes 400 s)."""
    p = packed(name)
    flexible = "suspension" in name
    opts = dict(
        relative_tolerance=1e-6 if flexible else 1e-10,
        output_interval=0.01,
        stop_time=0.05 if flexible else 1.0,
        output=p.outputs,
    )
    me = simulate_fmu(str(p.fmu), fmi_type="ModelExchange", **opts)
    cs = simulate_fmu(str(p.fmu), fmi_type="CoSimulation", **opts)
    assert len(me) == len(cs) == (6 if flexible else 101)
    for out in p.outputs:
        scale = 1 + np.max(np.abs(cs[out]))
        err = np.max(np.abs(me[out] - cs[out])) / scale
        assert err < (1e-5 if flexible else 1e-6), f"{name}.{out}: {err:.2e}"


def test_user_ode_and_input_through_model_exchange(packed):
    """The PID cart (user variables and a differential state, the input r): tracking a step
    of r, ME follows CS to 1e-6, and the integral state drives the angle to r."""
    p = packed("cart_pendulum_pid")
    opts = dict(
        relative_tolerance=1e-10,
        output_interval=0.01,
        stop_time=5.0,
        start_values={"r": 0.1},
        output=p.outputs,
    )
    me = simulate_fmu(str(p.fmu), fmi_type="ModelExchange", **opts)
    cs = simulate_fmu(str(p.fmu), fmi_type="CoSimulation", **opts)
    for out in p.outputs:
        assert np.max(np.abs(me[out] - cs[out])) < 1e-6 * (1 + np.max(np.abs(cs[out]))), out
    assert np.max(np.abs(me["angle"])) > 0.05  # it moved
    assert abs(me["angle"][-1] - 0.1) < 1e-2  # the integral term removes the offset


SLEIGH = """<multibody name="sleigh" version="1">
  <parameter name="m" value="3"/>
  <parameter name="I" value="0.4"/>
  <parameter name="a" value="0.5"/>
  <parameter name="v0" value="0.5"/>
  <parameter name="w0" value="2"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="sled" mass="m" inertia="0.1 0.2 I" position="a 0 0"
        velocity="v0, a*w0, 0" angular_velocity="0 0 w0">
    <marker name="P" position="-a 0 0"/>
  </body>
  <joint name="plane" type="planar" i="sled.cm" j="ground.O"/>
  <knife_edge name="blade" marker="sled.P"/>
  <output name="heading_rate" function="wz(sled.cm)"/>
  <output name="speed" function="vx(sled.P, ground.O, sled.P)"/>
  <experiment stop="3" step="0.01" tolerance="1e-10"/>
</multibody>
"""


def test_non_holonomic_sleigh_follows_its_closed_form(tmp_path):
    """The Chaplygin sleigh (a knife edge: a velocity state that is no position state's
    rate) turning: with J = I + m a^2, v' = a w^2 and J w' = -m a v w conserve
    m v^2 + J w^2 = m c^2, so v = c tanh(m a c t / J + atanh(v0 / c)) and
    w = sqrt(m / J) c sech(...) (Neimark & Fufaev). ME with CVode at rtol 1e-10 to 1e-7."""
    model = tmp_path / "sleigh.xml"
    model.write_text(SLEIGH)
    p = pack_model(model, tmp_path)
    res = simulate_fmu(
        str(p.fmu), fmi_type="ModelExchange", relative_tolerance=1e-10, output_interval=0.01, stop_time=3.0
    )
    m, i_cm, a, v0, w0 = 3.0, 0.4, 0.5, 0.5, 2.0
    J = i_cm + m * a * a
    c = math.sqrt(v0 * v0 + J * w0 * w0 / m)
    arg = m * a * c * res["time"] / J + math.atanh(v0 / c)
    np.testing.assert_allclose(res["speed"], c * np.tanh(arg), rtol=0, atol=1e-7)
    np.testing.assert_allclose(res["heading_rate"], math.sqrt(m / J) * c / np.cosh(arg), rtol=0, atol=1e-7)


def test_algebraic_loop_through_a_constraint_force(tmp_path):
    """Pin friction proportional to the pin's reaction (which depends on the acceleration,
    which depends on the friction): at every ME output the torque is -mu r |F| tanh(w/eps)
    of that output's own reaction and rate (1e-9: the loop is solved in fmi2GetDerivatives,
    not lagged), and ME follows CS to 1e-6."""
    p = pack_model(ROOT / "tests" / "models" / "pin_friction.xml", tmp_path)
    opts = dict(relative_tolerance=1e-10, output_interval=0.01, stop_time=2.0)
    me = simulate_fmu(str(p.fmu), fmi_type="ModelExchange", **opts)
    cs = simulate_fmu(str(p.fmu), fmi_type="CoSimulation", **opts)
    want = -0.3 * 0.05 * np.sqrt(me["normal"] ** 2 + 1e-6) * np.tanh(me["omega"] / 0.05)
    np.testing.assert_allclose(me["torque"], want, rtol=0, atol=1e-9)
    assert np.max(np.abs(me["torque"])) > 1e-3  # friction acts
    for out in ("normal", "torque", "omega"):
        assert np.max(np.abs(me[out] - cs[out])) < 1e-6 * (1 + np.max(np.abs(cs[out]))), out


@pytest.mark.parametrize("name", ["double_pendulum", "cart_pendulum_pid", "benchmark_bicycle"])
def test_directional_derivatives_equal_co_simulation_at_a_mid_run_state(name, packed):
    """At t = 0.37 of a CS run, the state x and [A B; C D] (fmi2GetDirectionalDerivative,
    unknowns = state derivatives and outputs, knowns = states and inputs); an ME instance
    set to the same (t, x) gives the same matrix to 1e-9 of its size (the ME point is placed
    by Newton from another point, agreeing with the CS one to ~1e-13 in q; measured 1e-12)."""
    p = packed(name)
    md = read_model_description(str(p.fmu))
    xs = state_vrs(md)
    dx = [d.variable.valueReference for d in md.derivatives]
    ins = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    outs = p.output_vrs
    known, unknown = xs + ins, dx + outs

    def jacobian(f) -> np.ndarray:
        cols = []
        for k in range(len(known)):
            seed = [0.0] * len(known)
            seed[k] = 1.0
            cols.append(f.getDirectionalDerivative(unknown, known, seed))
        return np.array(cols).T

    t = 0.37
    cs = FMU2Slave(guid=md.guid, unzipDirectory=str(p.unzipped), modelIdentifier=md.coSimulation.modelIdentifier)
    cs.instantiate()
    cs.setupExperiment(tolerance=1e-10, startTime=0.0)
    cs.enterInitializationMode()
    cs.exitInitializationMode()
    cs.doStep(0.0, t)
    x = cs.getReal(xs)
    j_cs = jacobian(cs)
    cs.terminate()
    cs.freeInstance()

    me = FMU2Model(guid=md.guid, unzipDirectory=str(p.unzipped), modelIdentifier=md.modelExchange.modelIdentifier)
    me.instantiate()
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    me.newDiscreteStates()
    me.enterContinuousTimeMode()
    me.setTime(t)
    set_x(me, x)
    j_me = jacobian(me)
    me.terminate()
    me.freeInstance()

    assert j_me.shape == (len(unknown), len(known))
    assert np.max(np.abs(j_me - j_cs)) <= 1e-9 * (1 + np.max(np.abs(j_cs)))


@pytest.mark.parametrize("interval", [1e-3, 1e-2])
def test_states_the_mechanism_cannot_take_are_an_error_naming_them(tmp_path, interval):
    """blade_y's state is the blade's y, whose range is |y| <= e + l = 12 m: a y beyond it
    is fmi2Error from fmi2GetDerivatives with a message naming the state, the instance
    stays usable (a reachable y afterwards works). The blade turns with the hub (alpha =
    w t, the CS run), so y = 12 sin(w t) reaches that bound, a fold of the chart y, at
    t = pi / (2 w) = 0.1571 s; the ODE in y turns back there on the branch it came from
    (smooth, and wrong: the blade would swing back). fmpy's CVode run stops with
    fmi2Error at the first accepted step past it (fmi2CompletedIntegratorStep, once per
    output interval), naming the state and the step's times, instead of integrating that
    motion."""
    p = pack_model(MODELS / "blade_y.xml", tmp_path)
    md = p.md
    log = LogCapture()
    me = FMU2Model(guid=md.guid, unzipDirectory=str(p.unzipped), modelIdentifier=md.modelExchange.modelIdentifier)
    me.instantiate(callbacks=log.callbacks)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    me.newDiscreteStates()
    me.enterContinuousTimeMode()
    x0 = get_x(me, 2)
    assert abs(x0[0]) < 1e-12  # y = 0 at t = 0
    set_x(me, [12.5, x0[1]])
    with pytest.raises(Exception, match="fmi2GetDerivatives"):
        get_dx(me, 2)
    errors = log.messages(3)
    assert errors and "yb = 12.5" in errors[-1], errors
    set_x(me, [0.1, x0[1]])
    assert np.all(np.isfinite(get_dx(me, 2)))
    me.terminate()
    me.freeInstance()

    errors = []

    def logger(component, name, status, category, message):
        if status == 3:
            errors.append(message.decode())

    with pytest.raises(Exception, match="fmi2CompletedIntegratorStep"):
        simulate_fmu(
            str(p.fmu),
            fmi_type="ModelExchange",
            relative_tolerance=1e-8,
            output_interval=interval,
            stop_time=1.0,
            logger=logger,
        )
    fold = [m for m in errors if "do not parameterize" in m]
    assert fold and "yb = " in fold[-1], errors
    t0, t1 = (float(v) for v in re.search(r"between t = (\S+) and t = (\S+) ", fold[-1]).groups())
    # The step the fold falls in: one output interval, ending past pi / (2 w).
    assert t0 <= math.pi / 20 < t1 and t1 - t0 <= interval * (1 + 1e-9)
