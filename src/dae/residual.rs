//! f(t, y) of the stabilized index-2 system M y' = f (see [`super::equations`]), one
//! function per block of equations.

use super::layout::Layout;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, qdot};
use crate::mechanics::constraint_jacobian::constraint_jacobian;
use crate::mechanics::coords::{gather, global_column};
use crate::mechanics::flexible;
use crate::mechanics::kernels::{force_values, gyroscopic, nonholonomic_first, user_residual};
use crate::mechanics::mass::body_mass_times;

/// Applied generalized forces Q(u, q, t): gravity, gyroscopic terms and force elements.
pub fn applied_forces(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64], out: &mut [f64]) {
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
        let (g, _) = gyroscopic(&body.inertia, &u[o + 3..o + 6]);
        out[o + 3..o + 6].copy_from_slice(&g);
    }
    for el in &sys.forces {
        let v = force_values(sys, el, q, u, t, inputs);
        for (a, x) in v.iter().enumerate() {
            out[global_column(sys, &el.bodies, a)] += x;
        }
    }
}

/// f(t, y) of the stabilized index-2 system.
pub fn rhs(sys: &System, lay: Layout, t: f64, y: &[f64], inputs: &[f64], f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    let ext = lay.ext(sys, inputs, y, t);
    user_rows(sys, lay, t, y, &ext, f);
    for b in 0..sys.nb() {
        let o = NQ * b;
        f[o..o + NQ].copy_from_slice(&qdot(&q[o..o + NQ], &u[o..o + NQ])); // Eq. 13b
    }
    let modal = sys.modal_columns();
    f[modal.clone()].copy_from_slice(&u[modal]); // η̇ = u_η
    applied_forces(sys, q, u, t, &ext, &mut f[lay.u_range()]);
    nonholonomic_rows(sys, lay, t, y, &ext, f);
    constraint_rows(sys, lay, t, y, &ext, f);
    acceleration_rows(sys, lay, y, f);
}

/// X' = Ẋ, and the user rows r(q, u, Z, v, t) (Eq. 7a–7b).
fn user_rows(sys: &System, lay: Layout, t: f64, y: &[f64], ext: &[f64], f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    f[lay.x_range()].copy_from_slice(&y[lay.xdot_range()]);
    let r0 = lay.z_alg_range().start;
    for (k, ue) in sys.user.iter().enumerate() {
        f[r0 + k] = user_residual(sys, ue, q, u, t, ext);
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
/// −C_qᵀμ in q̇ (the GGL term, Eq. 13b). A redundant row has λ = μ = 0 instead.
fn constraint_rows(sys: &System, lay: Layout, t: f64, y: &[f64], ext: &[f64], f: &mut [f64]) {
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    let (nu, nl, nm) = (lay.u(), lay.lam(), lay.mu());
    let cq = constraint_jacobian(sys, q, t, ext);
    let p = cq.velocity_form(q);
    let mut pu = vec![0.0; sys.m];
    for (&(row, g, pv), &(_, _, cv)) in p.entries.iter().zip(&cq.entries) {
        if sys.redundant[row] {
            continue;
        }
        pu[row] += pv * u[g];
        f[nu + g] -= pv * y[nl + row];
        f[g] -= cv * y[nm + row];
    }
    for row in 0..sys.m {
        if sys.redundant[row] {
            f[nl + row] = y[nl + row];
            f[nm + row] = y[nm + row];
        } else {
            f[nl + row] = cq.c[row];
            f[nm + row] = pu[row] + cq.ct[row];
        }
    }
}

/// Bodies with acceleration unknowns: u' = a, and M a = Q − Pᵀλ − Bᵀν as algebraic rows
/// (their force balance computed above moves there).
fn acceleration_rows(sys: &System, lay: Layout, y: &[f64], f: &mut [f64]) {
    let q = &y[lay.q_range()];
    for &b in &sys.acc_bodies {
        let dofs = sys.body_dofs(b);
        let rows: Vec<usize> = dofs.iter().map(|&g| lay.force_row(&sys.acc_bodies, g)).collect();
        let a: Vec<f64> = rows.iter().map(|&r| y[r]).collect();
        let ma = body_mass_times(sys, b, q, &a);
        for ((&g, &ra), m) in dofs.iter().zip(&rows).zip(ma) {
            let o = lay.u() + g;
            f[ra] = f[o] - m;
            f[o] = y[ra];
        }
    }
}
