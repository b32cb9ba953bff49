"""A flexible pendulum linearized at a moving state: the FMU's A, B, C, D against an
independent derivation of the same formulation, Lagrange's equations written here with
sympy from the lumped node data (not from the engine's inertia invariants).

The body: five lumped nodes (masses, rotary inertias) on a bent line, three modes with
arbitrary 3-D shapes (translations and rotations at every node but the pinned one), a
full modal stiffness matrix K and damping matrix C. It turns about ground z on a
revolute joint at node 0, under gravity -y, pushed at the tip by the input force F
(ground y), and loaded through its tip node by the reaction of a gforce on a ground
point P: -(H, 0, 0) at P, H an input. That load acts on the material point at P carried
by the tip node: virtual displacement dx_tip + dth_tip x (P - x_tip), dth_tip the node's
virtual rotation (ground axes), so its generalized force has the moment of the offset.
Generalized coordinates q = [th, e1, e2, e3]: the body angle about z and the modal
coordinates, which are also the model's linearization states.

Node i, in body axes: p_i = s_i + sum_k phi_ik e_k; in ground x_i = Rz(th) p_i; spin
W_i = (0, 0, th') + sum_k rho_ik e_k' (body axes). T = sum 1/2 m_i |x_i'|^2 +
1/2 W_i^T J_i W_i, V = -sum m_i g.x_i + 1/2 e^T K e, generalized forces -C e' on the
modal rows, (dx_tip/dq)^T (0, F, 0) and the tip node's (dx_tip/dq)^T (-H, 0, 0) +
(dw_tip/dq')^T ((P - x_tip) x (-H, 0, 0)). With M = d2T/dq'2 and
R(q, q', q'', F) = d/dt dT/dq' - dT/dq + dV/dq - Q, q'' solves R = 0 and
A = [[0, I], [-M^-1 dR/dq, -M^-1 dR/dq']], B = [0; -M^-1 dR/d(F, H)] (exact derivatives by
sympy, evaluated in double precision), C = [d y_tip/dq, 0], D = 0.

Both sides are exact to rounding (measured 2e-14 relative to the largest entry): the
issue's bound 1e-9 leaves a wide margin and still catches a missing or wrong term (without
the offset's moment the difference in A is 168, in B 68; without modal loads at all, 154).
"""

import json

import numpy as np
import sympy as sp

import mbfmu

G = 9.81
NODES = [  # position (body axes), mass, rotary inertia [Ixx, Iyy, Izz]
    ([0.0, 0.0, 0.0], 0.30, [2e-4, 3e-4, 4e-4]),
    ([0.2, 0.01, 0.0], 0.50, [3e-4, 2e-4, 5e-4]),
    ([0.4, 0.02, -0.01], 0.40, [1e-4, 4e-4, 3e-4]),
    ([0.6, 0.0, 0.01], 0.60, [4e-4, 1e-4, 2e-4]),
    ([0.8, -0.02, 0.0], 0.70, [2e-4, 2e-4, 6e-4]),
]
# Per mode, one [dx, dy, dz, rx, ry, rz] per node; node 0 (the pivot) does not move.
SHAPES = [
    [
        [0, 0, 0, 0, 0, 0],
        [0.01, 0.2, 0.03, 0.1, -0.2, 0.9],
        [0.0, 0.5, -0.02, 0.2, 0.1, 1.1],
        [-0.02, 0.8, 0.05, -0.1, 0.3, 1.0],
        [0.03, 1.0, 0.0, 0.2, 0.0, 0.8],
    ],
    [
        [0, 0, 0, 0, 0, 0],
        [0.02, -0.3, 0.1, 0.0, 0.4, -1.2],
        [0.0, -0.2, 0.2, 0.3, 0.2, 0.7],
        [0.05, 0.3, -0.1, 0.1, -0.1, 1.5],
        [0.01, 0.6, 0.2, -0.2, 0.3, -0.4],
    ],
    [
        [0, 0, 0, 0, 0, 0],
        [0.1, 0.05, -0.3, 0.5, 0.0, 0.2],
        [0.2, -0.1, 0.4, -0.3, 0.6, 0.1],
        [-0.1, 0.2, 0.1, 0.2, -0.4, -0.5],
        [0.05, -0.3, 0.5, 0.0, 0.2, 0.3],
    ],
]
K = [[400.0, 30.0, -10.0], [30.0, 900.0, 50.0], [-10.0, 50.0, 2500.0]]
C = [[0.5, 0.1, 0.0], [0.1, 0.8, 0.05], [0.0, 0.05, 1.2]]
TH0, W0, F0, H0 = -1.0, 0.8, 0.3, -0.4
P = [0.9, -0.3, 0.2]
ETA0, ETAD0 = [0.01, -0.005, 0.002], [0.1, -0.2, 0.05]

MODEL = f"""<multibody name="flexpend" version="1">
  <gravity value="0 -{G} 0"/>
  <input name="F" start="{F0}" unit="N"/>
  <input name="H" start="{H0}" unit="N"/>
  <ground>
    <marker name="O" position="0 0 0"/>
    <marker name="P" position="{" ".join(map(str, P))}"/>
  </ground>
  <flexible_body name="beam" modal="pend.json" position="0 0 0" euler313="{TH0} 0 0"
                 angular_velocity="0 0 {W0}" modal_coordinates="{" ".join(map(str, ETA0))}"
                 modal_velocities="{" ".join(map(str, ETAD0))}">
    <marker name="pivot" node="0"/>
    <marker name="tip" node="4"/>
  </flexible_body>
  <joint name="pin" type="revolute" i="beam.pivot" j="ground.O"/>
  <gforce name="push" i="beam.tip" force="0 F 0"/>
  <gforce name="pull" i="ground.P" j="beam.tip" force="H 0 0"/>
  <output name="tip_y" function="dy(beam.tip)"/>
  <linearization>
    <state name="th" function="az(beam.cm, ground.O)"/>
    <state name="e1" function="modal(beam, 1)"/>
    <state name="e2" function="modal(beam, 2)"/>
    <state name="e3" function="modal(beam, 3)"/>
  </linearization>
</multibody>
"""


def modal_file() -> str:
    return json.dumps(
        {
            "format": "mbfmu-modal",
            "version": 1,
            "nodes": [{"id": i, "position": p, "mass": m, "inertia": j} for i, (p, m, j) in enumerate(NODES)],
            "modes": [{"shape": s} for s in SHAPES],
            "stiffness": K,
            "damping": C,
        },
        indent=1,
    )


def reference():
    """A, B, C, D of the Lagrange equations above at (TH0, ETA0, W0, ETAD0, F0)."""
    n = 4
    q = sp.Matrix(sp.symbols("th e1 e2 e3"))
    qd = sp.Matrix(sp.symbols("thd e1d e2d e3d"))
    qdd = sp.Matrix(sp.symbols("thdd e1dd e2dd e3dd"))
    f, h = sp.symbols("F H")
    th, eta, etad = q[0], q[1:, 0], qd[1:, 0]
    rz = sp.Matrix([[sp.cos(th), -sp.sin(th), 0], [sp.sin(th), sp.cos(th), 0], [0, 0, 1]])
    kin, pot = sp.Integer(0), sp.Integer(0)
    x_tip, w_tip = None, None
    for i, (s, m, j) in enumerate(NODES):
        p = sp.Matrix(s) + sum((sp.Matrix(SHAPES[k][i][:3]) * eta[k] for k in range(3)), sp.zeros(3, 1))
        x = rz * p
        v = x.jacobian(q) * qd
        w = sp.Matrix([0, 0, qd[0]]) + sum((sp.Matrix(SHAPES[k][i][3:]) * etad[k] for k in range(3)), sp.zeros(3, 1))
        kin += sp.Rational(1, 2) * m * (v.T * v)[0] + sp.Rational(1, 2) * sum(j[c] * w[c] ** 2 for c in range(3))
        pot += m * G * x[1]
        x_tip, w_tip = x, rz * w
    kmat, cmat = sp.Matrix(K), sp.Matrix(C)
    pot += sp.Rational(1, 2) * (eta.T * kmat * eta)[0]
    push, pull = sp.Matrix([0, f, 0]), sp.Matrix([-h, 0, 0])
    q_gen = x_tip.jacobian(q).T * (push + pull) + w_tip.jacobian(qd).T * (sp.Matrix(P) - x_tip).cross(pull)
    q_gen -= sp.Matrix([0, *(cmat * etad)])
    dtdqd = sp.Matrix([sp.diff(kin, a) for a in qd])
    mass = dtdqd.jacobian(qd)
    res = mass * qdd + dtdqd.jacobian(q) * qd - sp.Matrix([sp.diff(kin, a) for a in q])
    res += sp.Matrix([sp.diff(pot, a) for a in q]) - q_gen

    point = dict(zip(list(q) + list(qd) + [f, h], [TH0, *ETA0, W0, *ETAD0, F0, H0], strict=True))

    def value(e, subs):
        """The expression `e` evaluated (double precision) at the symbol values `subs`."""
        return np.array(sp.lambdify(list(subs), e, "numpy")(*subs.values()), dtype=float)

    m0 = value(mass, point)
    acc = np.linalg.solve(m0, -value(res.subs(dict.fromkeys(qdd, 0)), point).ravel())
    at = {**point, **dict(zip(qdd, acc, strict=True))}
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.linalg.solve(m0, value(res.jacobian(q), at))
    a[n:, n:] = -np.linalg.solve(m0, value(res.jacobian(qd), at))
    b = np.zeros((2 * n, 2))
    b[n:, :] = -np.linalg.solve(m0, value(res.jacobian(sp.Matrix([f, h])), at))
    c = np.zeros((1, 2 * n))
    c[:, :n] = value(sp.Matrix([x_tip[1]]).jacobian(q), point)
    return a, b, c, np.zeros((1, 2))


def test_flexible_pendulum_matches_lagrange_equations_from_the_node_data(tmp_path):
    (tmp_path / "pend.json").write_text(modal_file())
    (tmp_path / "flexpend.xml").write_text(MODEL)
    fmu = mbfmu.pack(tmp_path / "flexpend.xml", tmp_path / "flexpend.fmu")
    lin = mbfmu.linearize(fmu, at=0.0, tolerance=1e-10)[0]
    assert lin.states == ["th", "e1", "e2", "e3", "der(th)", "der(e1)", "der(e2)", "der(e3)"]
    assert (lin.inputs, lin.outputs) == (["F", "H"], ["tip_y"])
    want = reference()
    for name, got, ref in zip("ABCD", (lin.A, lin.B, lin.C, lin.D), want, strict=True):
        scale = max(1.0, float(np.max(np.abs(ref))))
        err = float(np.max(np.abs(got - ref)))
        assert err <= 1e-9 * scale, f"{name}: max |engine - Lagrange| = {err:.3e} (scale {scale:.3e})"
    # A moving, deformed, damped state: the terms the comparison checks are all present.
    assert abs(want[0][4, 5]) > 1e-3 and abs(want[0][5, 4]) > 1e-3
