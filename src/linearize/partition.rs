//! Whether the linearization states still parameterize the positions (the determinant
//! condition after seed Eq. 36): [C_q; s_q] must be nonsingular for Eq. 34e–f to be
//! solvable for q.

use super::jets::jets;
use super::select::Selection;
use crate::dae::EngineError;
use crate::dae::rank::full_pivot;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::{IndependentRows, constraint_jacobian};
use crate::mechanics::coords::{global_column, nql};

/// The smallest pivot of [C_q; s_q] relative to the largest, below which the states no
/// longer parameterize the positions.
const PARTITION_TOL: f64 = 1e-8;

/// Check that the states still parameterize the motion at (q, t): sparse
/// complete-pivoting elimination of the square [C_q; s_q] (independent constraint rows,
/// then one row per position state); `ext` holds the external values.
pub fn check_partition(sys: &System, sel: &Selection, q: &[f64], t: f64, ext: &[f64]) -> Result<(), EngineError> {
    let n = sys.n();
    let rows = IndependentRows::of(sys);
    let mut j: Vec<(usize, usize, f64)> = constraint_jacobian(sys, q, t, ext).independent(&rows).collect();
    let zeros = vec![0.0; n];
    for (i, st) in sel.states.iter().enumerate().take(n.saturating_sub(rows.count)) {
        let jet = &jets(sys, st, q, &zeros, &zeros, t, ext)[0];
        let row = rows.count + i;
        let dq = &jet.dg[..nql(sys, &st.bodies)]; // ∂s/∂q (the jet also holds ∂s/∂u)
        j.extend(dq.iter().enumerate().map(|(a, &v)| (row, global_column(sys, &st.bodies, a), v)));
    }
    // Stops at the first pivot ≤ PARTITION_TOL·largest: then the next candidate is the ratio.
    let ratio = match full_pivot(n, n, j, PARTITION_TOL, 0.0) {
        Ok(p) if p.rank == n => {
            let small = p.magnitudes.iter().copied().fold(f64::INFINITY, f64::min);
            small / p.largest()
        }
        Ok(p) => p.remaining / p.largest().max(p.remaining),
        Err(_) => f64::NAN,
    };
    if ratio.is_nan() || ratio <= PARTITION_TOL {
        return Err(EngineError::Numeric(format!(
            "at t = {t}: the linearization states ({}) no longer parameterize the motion (singular partition, \
             pivot ratio {:.1e}); choose user states (<linearization>) that stay independent",
            sel.states.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", "),
            ratio
        )));
    }
    Ok(())
}
