//! Consistent velocities: u closest to the given u with P u + C_t = 0 (Eq. 13d), the
//! non-holonomic constraints B u + b = 0 (Eq. 7) and the exact velocity ICs, from one
//! saddle-point system [I Pᵀ Bᵀ Aᵀ; P 0; B 0; A 0] (A: the rows of the velocity ICs).

use super::kkt::push_p_blocks;
use crate::ad::{Dual, Real, chunked};
use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::p_row;
use crate::mechanics::constraints::{VelocityIc, VelocityIcKind};
use crate::mechanics::coords::{gather, global_column};
use crate::mechanics::local::LocalCtx;
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;

/// Consistent velocities: u closest to `u` with P u + C_t = 0 and exact velocity ICs.
pub fn assemble_velocities(sys: &System, q: &[f64], u: &mut [f64], t: f64, inputs: &[f64]) -> Result<(), String> {
    assemble_velocities_with(sys, &sys.ic_velocities, q, u, t, inputs)
}

/// [`assemble_velocities`] with the velocity conditions `ics` instead of the system's own
/// (Model Exchange: the velocity states the host sets; with as many conditions as the
/// velocities have freedoms, u is the unique solution).
pub fn assemble_velocities_with(
    sys: &System,
    ics: &[VelocityIc],
    q: &[f64],
    u: &mut [f64],
    t: f64,
    inputs: &[f64],
) -> Result<(), String> {
    let (n, m, nic, mn) = (sys.n(), sys.m, ics.len(), sys.mn);
    // Rows: u (n), constraints (m), velocity ICs (nic), non-holonomic (mn).
    let (ic0, nh0, dim) = (n + m, n + m + nic, n + m + nic + mn);
    let mut kkt = Triplets::new();
    for i in 0..n {
        kkt.push(i, i, 1.0);
    }
    let mut rhs = vec![0.0; dim];
    rhs[..n].copy_from_slice(u);
    for (r, ct) in push_p_blocks(sys, q, t, inputs, n, &mut kkt).into_iter().enumerate() {
        rhs[n + r] = if sys.redundant[r] { 0.0 } else { -ct };
    }
    // Non-holonomic rows: B u = B u_given − g(u_given) = −b.
    let (b, g) = nonholonomic_b(sys, q, u, t, inputs);
    for (r, gv) in g.iter().enumerate() {
        rhs[nh0 + r] = -gv;
    }
    for (r, c, v) in b {
        kkt.push(nh0 + r, c, v);
        kkt.push(c, nh0 + r, v);
        rhs[nh0 + r] += v * u[c];
    }
    for (k, ic) in ics.iter().enumerate() {
        let (res, a) = velocity_ic_row(sys, ic, q, u, t, inputs);
        let r = ic0 + k;
        let mut au = 0.0;
        for (c, &d) in a.iter().enumerate() {
            let g = global_column(sys, &ic.bodies, c);
            kkt.push(r, g, d);
            kkt.push(g, r, d);
            au += d * u[g];
        }
        rhs[r] = au - res;
    }
    // Velocity conditions that conflict with each other or with the constraints make the
    // system singular: name them.
    let conditions = || {
        let names: Vec<String> = ics.iter().map(|ic| format!("'{}' = {}", ic.name, ic.value)).collect();
        if names.is_empty() { String::new() } else { format!(" (velocity conditions: {})", names.join(", ")) }
    };
    let mut lu = SparseLu::new();
    lu.factor(dim, &kkt).map_err(|e| format!("cannot make velocities consistent: {e}{}", conditions()))?;
    if !lu.solve(&mut rhs) {
        return Err(format!("cannot make velocities consistent: singular velocity constraints{}", conditions()));
    }
    u.copy_from_slice(&rhs[..n]);
    Ok(())
}

/// A velocity IC as a row linear in the local u: (residual at `u`, coefficients a).
/// Joint and user-expression kinds: a from dual numbers seeded on u. The rate of a
/// position measure s(q, t): ṡ = s_q H u + s_t, so a = s_q H (as P = C_q H, Eq. 13a)
/// and the residual a·u + s_t − value.
fn velocity_ic_row(sys: &System, ic: &VelocityIc, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> (f64, Vec<f64>) {
    let ql = gather(sys, &ic.bodies, q);
    let ul = gather(sys, &ic.bodies, u);
    match &ic.kind {
        VelocityIcKind::Rate(kind) => {
            let mut x = ql.clone();
            x.push(t);
            let nq = ql.len();
            let (_, g) = chunked::jacobian(&x, |xl| {
                let ctx = LocalCtx::new(sys, &ic.bodies, &xl[..nq], &[], &[], xl[nq], inputs);
                vec![kind.eval(&ctx)]
            });
            let a = p_row(&ic.bodies, q, &g[..nq]);
            let sdot: f64 = a.iter().zip(&ul).map(|(x, y)| x * y).sum::<f64>() + g[nq];
            (sdot - ic.value, a)
        }
        _ => {
            let (res, a) = chunked::jacobian(&ul, |ul| {
                let ql: Vec<_> = ql.iter().map(|&v| Dual::cst(v)).collect();
                vec![ic.eval(&LocalCtx::new(sys, &ic.bodies, &ql, ul, &[], Dual::cst(t), inputs))]
            });
            (res[0], a)
        }
    }
}
