"""Exact linearization through the FMU: fmi2GetDirectionalDerivative gives the rows and
columns of A, B, C, D (seed Eq. 34) at communication points and in initialization mode.

References: the seed paper's helicopter blade (Fig. 1), Eq. 21 and Eq. 23 in closed form;
and, for an arbitrary seed vector, the product of the assembled matrices with the seed.
"""

import math

import numpy as np
import pytest

from fmu_helpers import initialize, new_slave


def jacobian(s, p, unknown_names, known_names):
    """Assemble d(unknowns)/d(knowns) column by column with unit seeds."""
    vr = p.vr
    unknowns = [vr[n] for n in unknown_names]
    cols = []
    for name in known_names:
        cols.append(s.getDirectionalDerivative(unknowns, [vr[name]], [1.0]))
    return np.array(cols).T


def state_names(p):
    """States (S then W) and their derivatives, from the Derivatives of the model description."""
    md = p.md
    derivs = [d.variable for d in md.derivatives]
    states = [d.derivative.name for d in derivs]
    return states, [d.name for d in derivs]


@pytest.mark.parametrize(
    "model,closed_form",
    [
        # Eq. 21: lambda = +-i w sqrt(m e l / (I + m l^2)), m=3, I=10, e=2, l=10, w=10.
        ("blade_alpha", 10.0 * math.sqrt(3 * 2 * 10 / (10 + 3 * 100))),
        # Eq. 23: lambda = +-i w sqrt(m e l / (I + m l^2) + 1).
        ("blade_y", 10.0 * math.sqrt(3 * 2 * 10 / (10 + 3 * 100) + 1)),
    ],
)
def test_blade_eigenvalues_through_the_fmu_match_the_seed(packed, model, closed_form):
    # 1e-9 relative: the linearization is exact; only round-off remains.
    p = packed(model)
    s = new_slave(p)
    initialize(s, tol=1e-10)
    states, derivs = state_names(p)
    assert len(states) == 2
    a = jacobian(s, p, derivs, states)
    ev = np.linalg.eigvals(a)
    assert np.all(np.abs(ev.real) < 1e-9 * closed_form), ev
    assert np.allclose(sorted(np.abs(ev.imag)), [closed_form, closed_form], rtol=1e-9, atol=0), ev
    s.terminate()
    s.freeInstance()


def test_blade_eigenvalues_in_initialization_mode(packed):
    p = packed("blade_alpha")
    s = new_slave(p)
    s.setupExperiment(tolerance=1e-10, startTime=0.0)
    s.enterInitializationMode()
    states, derivs = state_names(p)
    a = jacobian(s, p, derivs, states)
    want = 10.0 * math.sqrt(3 * 2 * 10 / (10 + 3 * 100))
    assert np.allclose(sorted(np.abs(np.linalg.eigvals(a).imag)), [want, want], rtol=1e-9, atol=0)
    s.exitInitializationMode()
    s.terminate()
    s.freeInstance()


def test_directional_derivative_of_an_arbitrary_seed_is_the_matrix_product(packed):
    # Unknowns: state derivatives and outputs; knowns: states. The FMU's answer for a
    # random seed must equal [A; C] @ seed assembled from unit seeds (1e-12: same numbers,
    # summed in a different order).
    p = packed("double_pendulum")
    s = new_slave(p)
    initialize(s, tol=1e-8)
    s.doStep(0.0, 0.3)
    states, derivs = state_names(p)
    unknown_names = derivs + p.outputs
    full = jacobian(s, p, unknown_names, states)
    rng = np.random.default_rng(3)
    seed = rng.normal(size=len(states))
    vr = p.vr
    got = s.getDirectionalDerivative([vr[n] for n in unknown_names], [vr[n] for n in states], list(seed))
    assert np.allclose(got, full @ seed, rtol=1e-12, atol=1e-12)
    # The states are readable: der(S) of the state list equals the W values.
    values = s.getReal([vr[n] for n in states])
    assert all(math.isfinite(v) for v in values)
    s.terminate()
    s.freeInstance()


@pytest.mark.parametrize("model", ["cart_pendulum_pid", "chaplygin_sleigh", "rolling_disc"])
def test_user_elements_and_nonholonomic_fmus_give_the_cli_matrices(packed, model, tmp_path):
    # The FMU lists every state (S, W, differential states X) with its derivative, and
    # fmi2GetDirectionalDerivative reproduces A, B, C, D of `mbfmu linearize` at t = 0.3
    # (same engine, same tolerance, same steps: 1e-9 relative covers the different
    # summation order only).
    import json

    from fmu_helpers import run_mbfmu

    p = packed(model)
    out = tmp_path / "lin.json"
    r = run_mbfmu("linearize", str(p.model), "--at", "0.3", "--format", "json", "--tol", "1e-10", "--out", str(out))
    assert r.returncode == 0, r.stderr
    ref = json.loads(out.read_text())[0]
    s = new_slave(p)
    initialize(s, tol=1e-10)
    s.doStep(0.0, 0.3)
    states, derivs = state_names(p)
    assert states == ref["states"]
    inputs = [v.name for v in p.md.modelVariables if v.causality == "input"]
    assert inputs == ref["inputs"]
    a = jacobian(s, p, derivs, states)
    scale = max(1.0, np.abs(np.array(ref["A"])).max())
    assert np.allclose(a, ref["A"], rtol=0, atol=1e-9 * scale)
    if inputs:
        b = jacobian(s, p, derivs, inputs)
        assert np.allclose(b, ref["B"], rtol=0, atol=1e-9 * scale)
        d = jacobian(s, p, p.outputs, inputs)
        assert np.allclose(d, ref["D"], rtol=0, atol=1e-9 * scale)
    c = jacobian(s, p, p.outputs, states)
    assert np.allclose(c, ref["C"], rtol=0, atol=1e-9 * scale)
    # Every state is readable and finite.
    assert all(math.isfinite(v) for v in s.getReal([p.vr[n] for n in states + derivs]))
    s.terminate()
    s.freeInstance()


def test_benchmark_bicycle_eigenvalues_through_the_fmu(packed):
    # Meijaard et al. (2007) benchmark at v = 5 m/s: the published lean/steer eigenvalues
    # -14.0783897, -0.3228664, -0.7753419 +- 4.4648677i (7 digits printed in the paper's
    # Table 2 style; 1e-6 relative) among the FMU's A from fmi2GetDirectionalDerivative,
    # the other six zero (s0 = 7 position, s1 = 3 velocity states).
    p = packed("benchmark_bicycle")
    s = new_slave(p)
    initialize(s, tol=1e-10)
    states, derivs = state_names(p)
    assert len(states) == 10
    ev = np.linalg.eigvals(jacobian(s, p, derivs, states))
    for want in (-14.0783897, -0.3228664, complex(-0.7753419, 4.4648677), complex(-0.7753419, -4.4648677)):
        assert np.min(np.abs(ev - want)) < 1e-6 * abs(want), (want, ev)
    assert np.sum(np.abs(ev) < 1e-5) == 6, ev
    s.terminate()
    s.freeInstance()
