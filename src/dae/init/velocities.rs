//! Consistent velocities: u closest to the given u with P u + C_t = 0 (Eq. 13d), the
//! non-holonomic constraints B u + b = 0 (Eq. 7) and the exact velocity ICs, from one
//! saddle-point system [I Pᵀ Bᵀ Aᵀ; P 0; B 0; A 0] (A: the rows of the velocity ICs).

use super::kkt::push_p_blocks;
use crate::ad::{Dual, Real, chunked};
use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::coords::{gather, global_column};
use crate::mechanics::local::LocalCtx;
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;

/// Consistent velocities: u closest to `u` with P u + C_t = 0 and exact velocity ICs.
pub fn assemble_velocities(sys: &System, q: &[f64], u: &mut [f64], t: f64, inputs: &[f64]) -> Result<(), String> {
    let (n, m, nic, mn) = (sys.n(), sys.m, sys.ic_velocities.len(), sys.mn);
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
    for (k, ic) in sys.ic_velocities.iter().enumerate() {
        // Linear in u: residual(u) = a·u − value; a from dual numbers seeded on u.
        let ql = gather(sys, &ic.bodies, q);
        let (res, a) = chunked::jacobian(&gather(sys, &ic.bodies, u), |ul| {
            let ql: Vec<_> = ql.iter().map(|&v| Dual::cst(v)).collect();
            vec![ic.eval(&LocalCtx::new(sys, &ic.bodies, &ql, ul, &[], Dual::cst(t), inputs))]
        });
        let r = ic0 + k;
        let mut au = 0.0;
        for (c, &d) in a.iter().enumerate() {
            let g = global_column(sys, &ic.bodies, c);
            kkt.push(r, g, d);
            kkt.push(g, r, d);
            au += d * u[g];
        }
        rhs[r] = au - res[0];
    }
    let mut lu = SparseLu::new();
    lu.factor(dim, &kkt).map_err(|e| format!("cannot make velocities consistent: {e}"))?;
    if !lu.solve(&mut rhs) {
        return Err("cannot make velocities consistent: singular velocity constraints".into());
    }
    u.copy_from_slice(&rhs[..n]);
    Ok(())
}
