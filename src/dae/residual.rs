//! f(t, y) of the stabilized index-2 system M y' = f (see [`super::equations`]), one
//! function per block of equations.

use super::layout::Layout;
use crate::geom::V3;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, Turn, body_turns, qdot_with};
use crate::mechanics::constraint_jacobian::p_row_into;
use crate::mechanics::coords::{gather, global_column, local_columns_into};
use crate::mechanics::flexible;
use crate::mechanics::kernels::{
    ConstraintFirst, Gathered, constraint_first_into, force_values_into, gyroscopic_force, nonholonomic_first,
    user_residual_with,
};
use crate::mechanics::mass::body_mass_times_into;

/// The buffers [`rhs`] works in, owned by its caller and reused from call to call: after
/// the first call, f of a model of rigid bodies and joints allocates nothing (force
/// elements, user rows, non-holonomic elements, flexible bodies and constraints other
/// than rigid joints still allocate inside their kernels).
#[derive(Clone, Debug, Default)]
pub struct RhsScratch {
    /// The external values.
    ext: Vec<f64>,
    /// The [`Turn`] of every body at q.
    turns: Vec<Turn<f64>>,
    /// C, C_q, C_t of one constraint element.
    first: ConstraintFirst,
    /// One row of P, and the global columns of its entries.
    p: Vec<f64>,
    cols: Vec<usize>,
    /// One acceleration body's accelerations a, and M a.
    acc: Vec<f64>,
    ma: Vec<f64>,
    /// One element's local q and u, and its generalized forces.
    gathered: Gathered,
    forces: Vec<f64>,
}

/// Applied generalized forces Q(u, q, t): gravity, gyroscopic terms and force elements.
pub fn applied_forces(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64], out: &mut [f64]) {
    applied_forces_with(sys, q, u, t, inputs, &mut Gathered::default(), &mut Vec::new(), out);
}

/// [`applied_forces`] with reused buffers: `g` for an element's local coordinates,
/// `v` for its generalized forces.
#[allow(clippy::too_many_arguments)]
fn applied_forces_with(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    g: &mut Gathered,
    v: &mut Vec<f64>,
    out: &mut [f64],
) {
    for (b, body) in sys.bodies.iter().enumerate() {
        if let Some(fb) = sys.flex_of(b) {
            // Gravity, quadratic-velocity, elastic and damping forces of a flexible body.
            let (qb, ub) = (gather(sys, &[b], q), gather(sys, &[b], u));
            let fq = flexible::body_forces(&fb.inv, &sys.r0[b], sys.gravity, &qb, &ub);
            for (g, v) in sys.body_dofs(b).into_iter().zip(fq) {
                out[g] = v;
            }
            continue;
        }
        let o = NQ * b;
        for c in 0..3 {
            out[o + c] = body.mass * sys.gravity[c];
        }
        let g = gyroscopic_force(&body.inertia, &V3([u[o + 3], u[o + 4], u[o + 5]]));
        out[o + 3..o + 6].copy_from_slice(&g.0);
    }
    for el in &sys.forces {
        force_values_into(sys, el, q, u, t, inputs, g, v);
        for (a, x) in v.iter().enumerate() {
            out[global_column(sys, &el.bodies, a)] += x;
        }
    }
}

/// f(t, y) of the stabilized index-2 system, computed in the buffers `ws`.
pub fn rhs(sys: &System, lay: Layout, t: f64, y: &[f64], inputs: &[f64], ws: &mut RhsScratch, f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    lay.ext_into(sys, inputs, y, t, &mut ws.ext);
    body_turns(&sys.r0, q, &mut ws.turns);
    user_rows(sys, lay, t, y, &ws.ext, &mut ws.gathered, f);
    for (b, turn) in ws.turns.iter().enumerate() {
        let o = NQ * b;
        f[o..o + NQ].copy_from_slice(&qdot_with(&turn.h, &u[o..o + NQ])); // Eq. 13b
    }
    let modal = sys.modal_columns();
    f[modal.clone()].copy_from_slice(&u[modal]); // η̇ = u_η
    applied_forces_with(sys, q, u, t, &ws.ext, &mut ws.gathered, &mut ws.forces, &mut f[lay.u_range()]);
    nonholonomic_rows(sys, lay, t, y, &ws.ext, f);
    constraint_rows(sys, lay, t, y, ws, f);
    acceleration_rows(sys, lay, y, ws, f);
}

/// X' = Ẋ, and the user rows r(q, u, Z, v, t) (Eq. 7a–7b).
fn user_rows(sys: &System, lay: Layout, t: f64, y: &[f64], ext: &[f64], g: &mut Gathered, f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    f[lay.x_range()].copy_from_slice(&y[lay.xdot_range()]);
    let r0 = lay.z_alg_range().start;
    for (k, ue) in sys.user.iter().enumerate() {
        f[r0 + k] = user_residual_with(sys, ue, q, u, t, ext, g);
    }
}

/// g = B u + b (ν rows) and −Bᵀν in the force balance.
fn nonholonomic_rows(sys: &System, lay: Layout, t: f64, y: &[f64], ext: &[f64], f: &mut [f64]) {
    let (q, u, nu, nn) = (&y[lay.q_range()], &y[lay.u_range()], lay.u(), lay.nu());
    for el in &sys.nonholonomic {
        let s = nonholonomic_first(sys, el, q, u, t, ext);
        let nql = crate::mechanics::coords::nql(sys, &el.bodies);
        for e in 0..el.neq {
            let nu_e = y[nn + el.row + e];
            f[nn + el.row + e] = s.c[e];
            for a in 0..nql {
                f[nu + global_column(sys, &el.bodies, a)] -= s.grad[e * s.k + nql + a] * nu_e;
            }
        }
    }
}

/// C (Eq. 13e, λ rows), Ċ = P u + C_t (Eq. 13d, μ rows), −Pᵀλ in the force balance and
/// −C_qᵀμ in q̇ (the GGL term, Eq. 13b), element by element with P = C_q H (Eq. 13a) of
/// each row formed in place. A redundant row has λ = μ = 0 instead.
fn constraint_rows(sys: &System, lay: Layout, t: f64, y: &[f64], ws: &mut RhsScratch, f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    let (nu, nl, nm) = (lay.u(), lay.lam(), lay.mu());
    let RhsScratch { ext, turns, first, p, cols, .. } = ws;
    for el in &sys.constraints {
        constraint_first_into(sys, el, q, t, ext, Some(turns), first);
        local_columns_into(sys, &el.bodies, cols);
        let nql = cols.len();
        p.resize(nql, 0.0);
        for e in 0..el.neq {
            let row = el.row + e;
            if sys.redundant[row] {
                f[nl + row] = y[nl + row];
                f[nm + row] = y[nm + row];
                continue;
            }
            let cq = &first.cq[e * nql..(e + 1) * nql];
            p_row_into(&el.bodies, |b| turns[b].h, cq, p);
            let (lam, mu, mut pu) = (y[nl + row], y[nm + row], 0.0);
            for ((&pv, &cv), &g) in p.iter().zip(cq).zip(cols.iter()) {
                pu += pv * u[g];
                f[nu + g] -= pv * lam;
                f[g] -= cv * mu;
            }
            f[nl + row] = first.c[e];
            f[nm + row] = pu + first.ct[e];
        }
    }
}

/// Bodies with acceleration unknowns: u' = a, and M a = Q − Pᵀλ − Bᵀν as algebraic rows
/// (their force balance computed above moves there).
fn acceleration_rows(sys: &System, lay: Layout, y: &[f64], ws: &mut RhsScratch, f: &mut [f64]) {
    let q = &y[lay.q_range()];
    for &b in &sys.acc_bodies {
        ws.acc.clear();
        ws.acc.extend(sys.body_dofs_iter(b).map(|g| y[lay.force_row(&sys.acc_bodies, g)]));
        body_mass_times_into(sys, b, q, &ws.acc, &mut ws.ma);
        for (g, m) in sys.body_dofs_iter(b).zip(&ws.ma) {
            let (ra, o) = (lay.force_row(&sys.acc_bodies, g), lay.u() + g);
            f[ra] = f[o] - m;
            f[o] = y[ra];
        }
    }
}
