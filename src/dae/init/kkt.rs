//! The blocks that the saddle-point systems of initialization share: the mass matrix M
//! (Eq. 13a) and the velocity form P = C_q H of the constraints with its transpose
//! (Eq. 13a, 13d), both from their one assembly in `mechanics`.

use crate::dae::sparse::Triplets;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::constraint_jacobian;
use crate::mechanics::mass::body_mass_entries;

/// Add M(q) to the top-left block of `kkt`.
pub fn push_mass(sys: &System, q: &[f64], kkt: &mut Triplets) {
    for b in 0..sys.nb() {
        for (r, c, v) in body_mass_entries(sys, b, q) {
            kkt.push(r, c, v);
        }
    }
}

/// Add the symmetric blocks P and Pᵀ of a KKT matrix whose constraint rows start at row
/// `n`; a redundant row gets a unit diagonal instead (its multiplier is 0 for a zero
/// right-hand side). Returns C_t of every constraint row (m).
pub fn push_p_blocks(sys: &System, q: &[f64], t: f64, ext: &[f64], n: usize, kkt: &mut Triplets) -> Vec<f64> {
    let rows = constraint_jacobian(sys, q, t, ext);
    for (r, _) in sys.redundant.iter().enumerate().filter(|(_, red)| **red) {
        kkt.push(n + r, n + r, 1.0);
    }
    for &(r, g, v) in &rows.velocity_form(q).entries {
        if !sys.redundant[r] {
            kkt.push(n + r, g, v);
            kkt.push(g, n + r, v);
        }
    }
    rows.ct
}
