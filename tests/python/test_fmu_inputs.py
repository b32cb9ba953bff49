"""An input torque drives the rotor (conftest.ROTOR) exactly as J w' = T(t) says."""

import pytest

from fmu_helpers import initialize, new_slave

J = 0.5  # the rotor's moment of inertia (parameter J)
T = 2.0
H = 0.1
N = 10


def _run(rotor, slope: float | None, in_init: bool):
    vr = rotor.vr
    s = new_slave(rotor, "rotor")
    try:
        if in_init:
            # Input (and slope) set in initialization mode, before the engine is built.
            s.setupExperiment(tolerance=1e-8, startTime=0.0)
            s.enterInitializationMode()
            s.setReal([vr["T"]], [T])
            if slope is not None:
                s.setRealInputDerivatives([vr["T"]], [1], [slope])
            s.exitInitializationMode()
        else:
            # Set at the first communication point (step mode), the usual CS place.
            initialize(s, 1e-8)
            assert s.getReal([vr["w"]]) == [0.0]
            s.setReal([vr["T"]], [T])
            if slope is not None:
                # fmpy: setRealInputDerivatives(vr, order, value), one order per vr.
                s.setRealInputDerivatives([vr["T"]], [1], [slope])
        w = []
        for k in range(N):
            t = k * H
            s.doStep(currentCommunicationPoint=t, communicationStepSize=(k + 1) * H - t)
            w.append(((k + 1) * H, s.getReal([vr["w"]])[0]))
        return w
    finally:
        s.terminate()
        s.freeInstance()


# Tolerance 1e-10 (absolute, on w up to 4 + 3 rad/s): the exact solutions are polynomials
# of degree 1 and 2 in t, which Radau IIA (order 5, stage order 3) integrates exactly, so
# only round-off and the Newton stopping test remain (both far below 1e-10).


@pytest.mark.parametrize("in_init", [False, True], ids=["step_mode", "init_mode"])
def test_constant_input_torque_gives_w_equal_T_t_over_J(rotor, in_init):
    for t, w in _run(rotor, None, in_init):
        assert w == pytest.approx(T * t / J, abs=1e-10), t


@pytest.mark.parametrize("in_init", [False, True], ids=["step_mode", "init_mode"])
def test_input_slope_gives_w_equal_T_t_plus_s_t2_over_2_over_J(rotor, in_init):
    s = 3.0  # dT/dt: T(t) = T + s t from t = 0 on, until the input is set again
    for t, w in _run(rotor, s, in_init):
        assert w == pytest.approx((T * t + s * t * t / 2) / J, abs=1e-10), t


def test_setting_the_input_again_ends_the_slope(rotor):
    vr = rotor.vr
    sl = new_slave(rotor, "rotor")
    try:
        initialize(sl, 1e-8)
        sl.setReal([vr["T"]], [T])
        sl.setRealInputDerivatives([vr["T"]], [1], [3.0])
        sl.doStep(0.0, 0.5)  # T(t) = 2 + 3 t on [0, 0.5]: w(0.5) = (1 + 0.375) / J
        assert sl.getReal([vr["w"]])[0] == pytest.approx(1.375 / J, abs=1e-10)
        sl.setReal([vr["T"]], [1.0])  # constant again: mbfmu resets the slope on fmi2SetReal
        sl.doStep(0.5, 0.5)
        assert sl.getReal([vr["w"]])[0] == pytest.approx((1.375 + 0.5) / J, abs=1e-10)
    finally:
        sl.terminate()
        sl.freeInstance()


def test_outputs_and_user_variables_follow_an_input_set_at_a_communication_point(packed):
    # cart_pendulum_pid: e = theta - r and force = kp e + ki xi + kd theta' are algebraic
    # (seed Eq. 7b): setting r at a communication point must move them at once (the
    # coupled-system master reads outputs right after setting inputs). Upright at rest,
    # r = 0.1 gives e = -0.1 and force = 60 * -0.1 = -6 exactly (1e-12: one Newton solve).
    p = packed("cart_pendulum_pid")
    s = new_slave(p)
    initialize(s, tol=1e-8)
    vr = p.vr
    assert s.getReal([vr["force"]])[0] == 0.0
    s.setReal([vr["r"]], [0.1])
    force, e = s.getReal([vr["force"], vr["e"]])
    assert abs(force + 6.0) < 1e-12 and abs(e + 0.1) < 1e-12
    s.doStep(0.0, 0.01)
    s.setReal([vr["r"]], [0.0])
    theta, force, e = s.getReal([vr["angle"], vr["force"], vr["e"]])
    assert abs(e - theta) < 1e-12
    s.terminate()
    s.freeInstance()
