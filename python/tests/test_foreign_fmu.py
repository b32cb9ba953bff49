"""mbfmu.linearize on an FMU that mbfmu did not build (foreign/vdp.c, compiled with cc):
van der Pol, x0' = x1, x1' = mu (1 - x0^2) x1 - x0 + u, outputs x0, x1 (the states, with
dependencies="") and y = x0 + 2 u. Closed form at the operating point (x0, x1):

    A = [[0, 1], [-2 mu x0 x1 - 1, mu (1 - x0^2)]],  B = [[0], [1]],
    C = [[1, 0], [0, 1], [1, 0]],                    D = [[0], [0], [2]].
"""

import warnings

import numpy as np
import pytest

import mbfmu
from mbfmu.linearization import DIFFERENCES, DIRECTIONAL


def closed_form(x0, x1, mu):
    A = np.array([[0.0, 1.0], [-2 * mu * x0 * x1 - 1, mu * (1 - x0**2)]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    D = np.array([[0.0], [0.0], [2.0]])
    return A, B, C, D


def assert_closed_form(lin, mu, tol):
    x0, x1 = lin.x0
    for got, want in zip((lin.A, lin.B, lin.C, lin.D), closed_form(x0, x1, mu), strict=True):
        assert np.max(np.abs(got - want)) <= tol * max(1.0, np.max(np.abs(want))), (got, want)


@pytest.mark.parametrize("interface", ["CoSimulation", "ModelExchange"])
def test_directional_derivatives_give_the_closed_form(foreign, interface):
    # 1e-9: the FMU's derivatives are exact; the outputs that are states get the unit rows
    # although they declare dependencies="" (Reference-FMUs #657).
    lins = mbfmu.linearize(foreign(), at=[0.0, 1.5, 3.0], start_values={"mu": 1.5}, interface=interface)
    for lin in lins:
        assert lin.method == DIRECTIONAL
        assert lin.states == ["x0", "x1"] and lin.inputs == ["u"] and lin.outputs == ["x0", "x1", "y"]
        assert lin.state_units == ["m", "m/s"] and lin.input_units == ["N"]
        assert_closed_form(lin, 1.5, 1e-9)
    # The state moved (a moving point, not the start): x0 left 2.
    assert abs(lins[2].x0[0] - 2.0) > 0.1


def test_without_directional_derivatives_falls_back_to_central_differences(foreign):
    # 1e-6: central differences with h = eps^(1/3) max(1, |x|) have O(h^2) ≈ 4e-11
    # truncation on this polynomial right-hand side; the bound leaves room for round-off.
    with pytest.warns(mbfmu.DifferencesWarning, match="central differences"):
        lins = mbfmu.linearize(foreign(dd=False), at=[0.0, 2.0], start_values={"mu": 0.7})
    for lin in lins:
        assert lin.method == DIFFERENCES
        assert_closed_form(lin, 0.7, 1e-6)


def test_co_simulation_only_without_directional_derivatives_is_refused(foreign):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mbfmu.DifferencesWarning)
        with pytest.raises(mbfmu.NotLinearizableError, match="no directional derivatives and no Model Exchange"):
            mbfmu.linearize(foreign(dd=False, me=False), at=0.0)


def test_fmu_without_derivatives_is_a_clear_error(foreign):
    with pytest.raises(mbfmu.NotLinearizableError, match=r"declares no <Derivatives>"):
        mbfmu.linearize(foreign(derivatives=False), at=0.0)


def test_inputs_as_fmpy_structured_array(foreign):
    # u(t) = t, linear between the rows: at t = 1 the operating point has u = 1; the
    # linearization itself does not depend on u (closed form), the trajectory does.
    sig = np.array([(0.0, 0.0), (2.0, 2.0)], dtype=[("time", float), ("u", float)])
    free, forced = (mbfmu.linearize(foreign(), at=1.0, inputs=inp)[0] for inp in (None, sig))
    assert forced.u0.tolist() == [1.0]
    assert forced.y0[2] == pytest.approx(forced.x0[0] + 2.0, abs=1e-12)
    assert abs(forced.x0[1] - free.x0[1]) > 1e-3
    assert_closed_form(forced, 1.0, 1e-9)


def test_ignoring_declared_dependencies_gives_the_same_matrices(foreign):
    a = mbfmu.linearize(foreign(), at=1.0)[0]
    b = mbfmu.linearize(foreign(), at=1.0, use_dependencies=False)[0]
    for k in "ABCD":
        assert np.array_equal(getattr(a, k), getattr(b, k))


def test_model_exchange_follows_time_varying_inputs(foreign):
    # u(t) = t through CVode (inputs applied inside the right-hand side) against the
    # Co-Simulation interface, which holds u over each communication step h (first order
    # in h): its Richardson extrapolation 2 x(h/2) - x(h) is O(h^2) ≈ 1e-6 accurate.
    sig = np.array([(0.0, 0.0), (2.0, 2.0)], dtype=[("time", float), ("u", float)])
    me = mbfmu.linearize(foreign(), at=1.5, inputs=sig, interface="ModelExchange")[0]
    cs = [mbfmu.linearize(foreign(), at=1.5, inputs=sig, interface="CoSimulation", step=h)[0].x0 for h in (2e-3, 1e-3)]
    assert me.u0.tolist() == [1.5]
    assert np.max(np.abs(me.x0 - (2 * cs[1] - cs[0]))) < 1e-5
