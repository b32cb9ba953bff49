//! Redundant constraint rows: those that depend on others at (q, t) (e.g. a planar loop
//! of revolutes modelled in 3-D). Their multipliers are held at 0 and their equations
//! left out of every saddle-point system.

use crate::dae::rank::full_pivot_sparse;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::constraint_jacobian;

/// Relative pivot size below which a constraint row counts as redundant.
pub const REDUNDANCY_TOL: f64 = 1e-6;

/// Constraint rows that depend on others at (q, t): sparse complete-pivoting elimination
/// of C_qᵀ (ties to the sparser row: only the pivoted columns matter here); the rows that
/// get no pivot are redundant. A non-finite C_q counts as independent (assembly reports
/// it).
pub fn redundant_rows(sys: &System, q: &[f64], t: f64, inputs: &[f64]) -> Vec<bool> {
    let (n, m) = (sys.n(), sys.m);
    if m == 0 {
        return Vec::new();
    }
    let ct: Vec<_> = constraint_jacobian(sys, q, t, inputs).entries.into_iter().map(|(r, g, v)| (g, r, v)).collect();
    match full_pivot_sparse(n, m, ct, REDUNDANCY_TOL, 0.0) {
        Ok(p) => p.pivoted_cols(m).iter().map(|&pivoted| !pivoted).collect(),
        Err(_) => vec![false; m],
    }
}
