//! The velocity-level Jacobian of the non-holonomic constraints g(q, u, t) = B u + b = 0:
//! B = ∂g/∂u with g, and the γ of their acceleration form B u̇ + γ = 0, assembled in this
//! one place for every user.

use super::coords::{gather, global_column, rates};
use super::kernels::nonholonomic_first;
use super::system::System;

/// γ of the non-holonomic acceleration constraint B u̇ + γ = 0: ġ at u̇ = 0, i.e.
/// g_q q̇ + g_t (q̇ of modal coordinates: their rates).
pub fn nonholonomic_gamma(sys: &System, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> Vec<f64> {
    let mut gamma = vec![0.0; sys.mn];
    for el in &sys.nonholonomic {
        let s = nonholonomic_first(sys, el, q, u, t, ext);
        let nql = crate::mechanics::coords::nql(sys, &el.bodies);
        let (ql, ul) = (gather(sys, &el.bodies, q), gather(sys, &el.bodies, u));
        let qd = rates(el.bodies.len(), &ql, &ul);
        for e in 0..el.neq {
            let g = &s.grad[e * s.k..(e + 1) * s.k];
            gamma[el.row + e] = (0..nql).map(|a| g[a] * qd[a]).sum::<f64>() + g[2 * nql];
        }
    }
    gamma
}

/// B = ∂g/∂u of the non-holonomic constraints as (row, global column, value), with g.
pub fn nonholonomic_b(sys: &System, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let mut b = Vec::new();
    let mut g = vec![0.0; sys.mn];
    for el in &sys.nonholonomic {
        let s = nonholonomic_first(sys, el, q, u, t, ext);
        let nql = crate::mechanics::coords::nql(sys, &el.bodies);
        for e in 0..el.neq {
            g[el.row + e] = s.c[e];
            for a in 0..nql {
                b.push((el.row + e, global_column(sys, &el.bodies, a), s.grad[e * s.k + nql + a]));
            }
        }
    }
    (b, g)
}
