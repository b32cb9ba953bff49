"""Coupled systems: the example SSP (examples/cart_pendulum_ssp: the cart-pendulum plant
and its PID controller, two FMUs packed by mbfmu) against the single model
models/cart_pendulum_pid.xml, which contains the same controller."""

import runpy
import zipfile

import numpy as np
import pytest
from conftest import EXAMPLES, MODELS

import mbfmu

MONO_STATES = ["x", "th", "der(x)", "der(th)", "xi"]
SSP_STATES = ["plant.x", "plant.th", "plant.der(x)", "plant.der(th)", "controller.xi"]


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    build = runpy.run_path(str(EXAMPLES / "cart_pendulum_ssp" / "build_ssp.py"))["build"]
    return build(tmp_path_factory.mktemp("ssp") / "cart_pendulum_pid.ssp")


def moving_model(tmp_path, theta0, omega0):
    """models/cart_pendulum_pid.xml with the hinge's initial angle and rate set."""
    text = (MODELS / "cart_pendulum_pid.xml").read_text()
    old = '<joint name="hinge" type="revolute" i="pend.hinge" j="cart.hinge"/>'
    assert old in text
    text = text.replace(old, old[:-2] + f' ic_angle="{theta0!r}" ic_angular_speed="{omega0!r}"/>')
    path = tmp_path / "cart_pendulum_moving.xml"
    path.write_text(text)
    return mbfmu.pack(path, tmp_path / "cart_pendulum_moving.fmu")


def assert_same_system(sys_lin, mono, tol):
    perm = [sys_lin.states.index(s) for s in SSP_STATES]
    assert mono.states == MONO_STATES
    assert sys_lin.inputs == mono.inputs == ["r"]
    assert sys_lin.outputs == mono.outputs == ["force", "angle"]
    got = {"A": sys_lin.A[np.ix_(perm, perm)], "B": sys_lin.B[perm], "C": sys_lin.C[:, perm], "D": sys_lin.D}
    for k, g in got.items():
        want = getattr(mono, k)
        assert np.max(np.abs(g - want)) <= tol * max(1.0, np.max(np.abs(want))), k


def test_coupled_system_at_rest_equals_the_single_model(ssp, packed):
    # 1e-8: both are exact linearizations of the same equations; the combination
    # (I - D K)^-1 is exact, so only round-off separates them (measured 7e-15).
    (lin,) = mbfmu.linearize_system(ssp, at=0.0, tolerance=1e-10)
    (mono,) = mbfmu.linearize(packed("cart_pendulum_pid"), at=0.0, tolerance=1e-10)
    assert_same_system(lin, mono, 1e-8)
    assert lin.states == SSP_STATES
    assert lin.method == "directional derivatives"


def test_coupled_system_at_a_moving_state_equals_the_single_model(ssp, tmp_path):
    # Pendulum at 0.2 rad turning at 0.5 rad/s: the controller's feedthrough (D = [kp, kd,
    # -kp]) and the plant's state-dependent A meet in the loop.
    (lin,) = mbfmu.linearize_system(
        ssp, at=0.0, start_values={"plant.theta0": 0.2, "plant.omega0": 0.5}, tolerance=1e-10
    )
    (mono,) = mbfmu.linearize(moving_model(tmp_path, 0.2, 0.5), at=0.0, tolerance=1e-10)
    assert_same_system(lin, mono, 1e-8)
    perm = [lin.states.index(s) for s in SSP_STATES]
    assert np.allclose(lin.x0[perm], mono.x0, atol=1e-12)
    assert lin.y0 == pytest.approx(mono.y0, abs=1e-9)  # force = kp 0.2 + kd 0.5 = 17


def test_coupled_linearization_after_motion_converges_with_the_step(ssp, tmp_path):
    # At t = 0.5 the co-simulated state differs from the single model's by O(h) (Jacobi
    # with inputs held over a step), and so does A: halving h halves the error (measured
    # ratios 2.2 and 2.1 for h = 2, 1, 0.5 ms: the O(h^2) term still shows).
    mono = mbfmu.linearize(moving_model(tmp_path, 0.2, 0.5), at=0.5, tolerance=1e-10)[0]
    errs = []
    for h in (0.002, 0.001, 0.0005):
        (lin,) = mbfmu.linearize_system(
            ssp, at=0.5, step=h, start_values={"plant.theta0": 0.2, "plant.omega0": 0.5}, tolerance=1e-10
        )
        perm = [lin.states.index(s) for s in SSP_STATES]
        errs.append(np.max(np.abs(lin.A[np.ix_(perm, perm)] - mono.A)))
    rates = [errs[i] / errs[i + 1] for i in range(2)]
    assert all(1.8 < r < 2.5 for r in rates), (errs, rates)
    assert errs[-1] < 1e-2


def test_the_ssp_runs_in_fmpy_and_approaches_the_single_model(ssp, tmp_path):
    from fmpy import simulate_fmu
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet

    mono = simulate_fmu(
        str(moving_model(tmp_path, 0.2, 0.5)),
        stop_time=1.0,
        output_interval=0.001,
        relative_tolerance=1e-10,
        output=["angle"],
    )
    params = ParameterSet(
        parameters=[
            Parameter(name="plant.theta0", type="Real", value=0.2),
            Parameter(name="plant.omega0", type="Real", value=0.5),
        ]
    )
    errs = []
    for h in (0.01, 0.005, 0.0025):
        res = simulate_ssp(str(ssp), stop_time=1.0, step_size=h, parameter_set=params)
        t = res["time"] + h  # fmpy records each row after the step from `time`
        ref = np.interp(t, mono["time"], mono["angle"])
        errs.append(np.max(np.abs(res["plant.angle"] - ref)))
    # First order in h (rows of 0.01 and 0.005: ratio 2 within 15 %).
    rates = [errs[i] / errs[i + 1] for i in range(2)]
    assert all(1.7 < r < 2.3 for r in rates), (errs, rates)


SINGULAR_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" version="1.0" name="loop">
  <ssd:System name="loop">
    <ssd:Elements>
      <ssd:Component name="c1" source="resources/pid.fmu"/>
      <ssd:Component name="c2" source="resources/pid.fmu"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="c1" startConnector="force" endElement="c2" endConnector="angle"/>
      <ssd:Connection startElement="c2" startConnector="force" endElement="c1" endConnector="angle"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


def test_singular_algebraic_loop_is_a_clear_error(ssp, tmp_path):
    # Two controllers feeding each other's angle with kp = 1: I - D K = [[1, -1], [-1, 1]].
    loop = tmp_path / "loop.ssp"
    with zipfile.ZipFile(ssp) as src, zipfile.ZipFile(loop, "w") as z:
        z.writestr("SystemStructure.ssd", SINGULAR_SSD)
        z.writestr("resources/pid.fmu", src.read("resources/pid.fmu"))
    with pytest.raises(mbfmu.NotLinearizableError, match="algebraic loop"):
        mbfmu.linearize_system(loop, at=0.0, start_values={"c1.kp": 1.0, "c2.kp": 1.0})
    # With kp = 0.5 the loop is regular, and unconnected inputs become system inputs.
    (lin,) = mbfmu.linearize_system(loop, at=0.0, start_values={"c1.kp": 0.5, "c2.kp": 0.5})
    assert lin.inputs == ["c1.rate", "c1.r", "c2.rate", "c2.r"]
    assert lin.outputs == ["c1.force", "c2.force"]
    # y = (I - D K)^-1 (C x + D E w): d(c1.force)/d(c1.xi) = ki / (1 - kp^2) = 30 / 0.75.
    assert lin.C[0, 0] == pytest.approx(40.0, rel=1e-12)


def test_missing_ssp_is_named(tmp_path):
    with pytest.raises(mbfmu.FMUNotFoundError, match="nope.ssp"):
        mbfmu.linearize_system(tmp_path / "nope.ssp", at=0.0)
