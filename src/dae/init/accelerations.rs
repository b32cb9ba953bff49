//! Accelerations u̇ and multipliers (λ; ν) at a given (q, u, t) (Eq. 1c–1d):
//! [M Pᵀ Bᵀ; P 0 0; B 0 0][u̇; λ; ν] = [Q; −γ; −γ_nh], one sparse LU.

use super::kkt::{push_mass, push_p_blocks};
use crate::dae::residual::applied_forces;
use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::acceleration_rhs;
use crate::mechanics::nonholonomic_jacobian::{nonholonomic_b, nonholonomic_gamma};

/// Accelerations u̇ and multipliers (λ; ν): [M Pᵀ Bᵀ; P 0 0; B 0 0][u̇; λ; ν] = [Q; −γ; −γ_nh].
/// `ext` holds the external values; `lu` is reused from call to call.
pub fn accelerations(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
    lu: &mut SparseLu,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (n, m, mn) = (sys.n(), sys.m, sys.mn);
    let mut kkt = Triplets::new();
    push_mass(sys, q, &mut kkt);
    let mut rhs = vec![0.0; n + m + mn];
    applied_forces(sys, q, u, t, ext, &mut rhs[..n]);
    push_p_blocks(sys, q, t, ext, n, &mut kkt);
    let gamma = acceleration_rhs(sys, q, u, t, ext);
    for (r, g) in gamma.iter().enumerate().filter(|(r, _)| !sys.redundant[*r]) {
        rhs[n + r] = -g;
    }
    // Non-holonomic rows: B u̇ = −γ_nh; Bᵀν in the equations of motion.
    let (b, _) = nonholonomic_b(sys, q, u, t, ext);
    for (r, c, v) in b {
        kkt.push(n + m + r, c, v);
        kkt.push(c, n + m + r, v);
    }
    for (r, gm) in nonholonomic_gamma(sys, q, u, t, ext).into_iter().enumerate() {
        rhs[n + m + r] = -gm;
    }
    lu.factor(n + m + mn, &kkt).map_err(|e| format!("cannot solve accelerations: {e}"))?;
    if !lu.solve(&mut rhs) {
        return Err("cannot solve accelerations: singular (redundant constraints?)".into());
    }
    Ok((rhs[..n].to_vec(), rhs[n..].to_vec()))
}
