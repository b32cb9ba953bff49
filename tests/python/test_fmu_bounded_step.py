"""Bounded fmi2DoStep through fmpy (issue 12 item 2): the Integer parameter
solver.maxSteps, fmi2Discard with fmi2LastSuccessfulTime = the time reached and a
message of status fmi2Discard, and a retry from a saved FMU state."""

import math

import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException  # fmpy raises it for every status above fmi2Warning
from fmpy.fmi2 import fmi2Discard, fmi2Error

from fmu_helpers import ROOT, LogCapture, initialize, new_slave, pack_model

LAST_SUCCESSFUL_TIME = 2  # fmi2LastSuccessfulTime
DEFAULT_MAX_STEPS = 10_000

# tests/models/fourbar_toggle.xml: crank a, coupler b, rocker c, ground d, crank speed w.
A, B, C, D, W = 0.4, 0.5, 0.35, 0.6, 1.0
# The toggle: |A - O2| = b + c, cos(w t*) = (a^2 + d^2 - (b + c)^2) / (2 a d).
T_STAR = math.acos((A * A + D * D - (B + C) ** 2) / (2 * A * D)) / W


@pytest.fixture(scope="module")
def toggle(tmp_path_factory):
    return pack_model(ROOT / "tests" / "models" / "fourbar_toggle.xml", tmp_path_factory.mktemp("toggle"))


def discarded(call, log: LogCapture) -> str:
    """`call()` raises FMICallException(fmi2DoStep, fmi2Discard) and logs its reason with
    status fmi2Discard (category logStatusDiscard). Returns the message."""
    log.clear()
    with pytest.raises(FMICallException) as e:
        call()
    assert (e.value.function, e.value.status) == ("fmi2DoStep", fmi2Discard)
    found = [r for r in log.records if r[1] == fmi2Discard]
    assert len(found) == 1, log.records
    assert found[0][2] == "logStatusDiscard"
    return found[0][4]


def test_the_model_description_declares_solver_max_steps_last(toggle):
    v = toggle.md.modelVariables[-1]
    assert (v.name, v.type, v.causality, v.variability, v.initial) == (
        "solver.maxSteps",
        "Integer",
        "parameter",
        "tunable",
        "exact",
    )
    assert int(v.start) == DEFAULT_MAX_STEPS
    assert v.valueReference == len(toggle.md.modelVariables) - 1
    assert "fmi2Discard" in v.description


def test_a_toggle_is_discarded_at_the_toggle_time_and_a_shorter_step_from_a_saved_state_succeeds(toggle):
    vr = toggle.vr
    outs = [vr["crank_angle"], vr["closure"], vr["reach"]]
    assert T_STAR == pytest.approx(2.00630869785933, abs=1e-13)
    log = LogCapture()
    s = new_slave(toggle, "toggle", log=log, logging_on=True)
    try:
        initialize(s, 1e-6)
        t = 0.0
        for k in range(1, 20):
            s.doStep(t, k * 0.1 - t)
            t = k * 0.1
        state = s.getFMUstate()
        text = discarded(lambda: s.doStep(t, 0.2), log)
        reached = s.getRealStatus(LAST_SUCCESSFUL_TIME)
        assert text.startswith(f"fmi2DoStep: step from {t!r} to ") and "step size collapsed" in text, text
        assert repr(reached) in text
        # The time reached is the toggle time (tests/it/bounded_step.rs: measured 5.0e-10 s
        # before it; 1e-7 s asserted), where coupler and rocker are aligned (reach ~ 0).
        assert t < reached < T_STAR and T_STAR - reached < 1e-7, (reached, T_STAR)
        crank, closure, reach = s.getReal(outs)
        assert crank == pytest.approx(W * reached, abs=1e-9)
        assert abs(closure) < 1e-8 and 0.0 <= reach < 0.26 * 1e-7
        # Restore, then a step that stays before the toggle.
        s.setFMUstate(state)
        assert s.getRealStatus(LAST_SUCCESSFUL_TIME) == t
        s.doStep(t, 0.1)
        crank, closure, reach = s.getReal(outs)
        assert crank == pytest.approx(2.0, abs=1e-9)
        assert abs(closure) < 4e-9 and reach > 1e-3
        s.freeFMUstate(state)
    finally:
        s.terminate()
        s.freeInstance()


def test_a_runaway_step_returns_discard_at_solver_max_steps(packed):
    p = packed("cart_pendulum_pid")
    vr = p.vr
    log = LogCapture()
    s = new_slave(p, "runaway", log=log, logging_on=True)
    try:
        # The sequence: an input slope, initialize, one step of 1e6 s.
        s.setRealInputDerivatives([vr["r"]], [1], [1.0])
        s.setInteger([vr["solver.maxSteps"]], [200])
        initialize(s, 1e-6)
        assert s.getInteger([vr["solver.maxSteps"]]) == [200]
        text = discarded(lambda: s.doStep(0.0, 1e6), log)
        reached = s.getRealStatus(LAST_SUCCESSFUL_TIME)
        assert 0.0 < reached < 1e6
        # The runaway ends at the limit, counted by the FMU: 200 attempts (measured: t = 2.5
        # reached), not a hang.
        assert "step limit reached: 200 integrator steps" in text and "solver.maxSteps" in text, text
    finally:
        s.terminate()
        s.freeInstance()


def test_solver_max_steps_below_one_is_an_error_and_the_instance_still_works(packed):
    p = packed("pendulum")
    vr = p.vr["solver.maxSteps"]
    log = LogCapture()
    s = new_slave(p, "checked", log=log)
    try:
        s.setupExperiment(tolerance=1e-6, startTime=0.0)
        s.enterInitializationMode()
        for bad in (0, -1):
            log.clear()
            with pytest.raises(FMICallException) as e:
                s.setInteger([vr], [bad])
            assert (e.value.function, e.value.status) == ("fmi2SetInteger", fmi2Error)
            want = f"fmi2SetInteger: value {bad} for 'solver.maxSteps' (vr {vr}) is not a positive number of "
            assert log.messages(fmi2Error) == [want + "integrator steps"]
        assert s.getInteger([vr]) == [DEFAULT_MAX_STEPS]
        s.exitInitializationMode()
        s.doStep(0.0, 0.1)
    finally:
        s.terminate()
        s.freeInstance()


def test_fmpy_sets_solver_max_steps_as_a_start_value(packed):
    p = packed("pendulum")
    # Enough for 0.01 s steps; one attempt per step is not (fmpy raises on the discard).
    r = simulate_fmu(str(p.fmu), stop_time=0.5, output_interval=0.01, start_values={"solver.maxSteps": 1000})
    assert len(r) == 51
    with pytest.raises(Exception, match="fmi2DoStep"):
        simulate_fmu(str(p.fmu), stop_time=0.5, output_interval=0.5, start_values={"solver.maxSteps": 1})
