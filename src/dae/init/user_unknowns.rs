//! The algebraic user unknowns (Ẋ, V) from the user rows (seed Eq. 7a–7b) at a given
//! (q, u, X), by Newton with the exact Jacobian.

use crate::mechanics::System;
use crate::mechanics::external::ExtEntry;
use crate::mechanics::kernels::user_jacobian;

/// Newton iterations before the user rows count as not solvable.
const MAX_ITERATIONS: usize = 50;

/// The algebraic user unknowns (Ẋ, V) from the user rows (Eq. 7a–7b) at given q, u, X
/// (and multipliers λ, for rows that read element loads): Newton with the exact Jacobian;
/// `z` = (X, Ẋ, V) in and out (X is kept). Called at the initial point and whenever the
/// accelerations are recomputed.
#[allow(clippy::too_many_arguments)]
pub fn user_unknowns(
    sys: &System,
    q: &[f64],
    u: &[f64],
    lam: Option<&[f64]>,
    t: f64,
    inputs: &[f64],
    z: &mut [f64],
) -> Result<(), String> {
    let (nx, k) = (sys.nx, sys.user.len());
    if k == 0 {
        return Ok(());
    }
    let lay = sys.ext_layout();
    // The unknowns are Z entries nx..nx + k: (Ẋ, V), in the order of the user rows.
    let unknown = |e: usize| match lay.entry(e) {
        ExtEntry::Z(i) if (nx..nx + k).contains(&i) => Some(i - nx),
        _ => None,
    };
    for _ in 0..MAX_ITERATIONS {
        let ext = sys.ext(inputs, z, lam.map(|l| (q, u, l)), t);
        let mut jac = faer::Mat::<f64>::zeros(k, k);
        let mut r = faer::Mat::<f64>::zeros(k, 1);
        for (row, ue) in sys.user.iter().enumerate() {
            let uj = user_jacobian(sys, ue, q, u, t, &ext);
            r[(row, 0)] = -uj.value;
            for (e, v) in uj.dext {
                if let Some(col) = unknown(e) {
                    jac[(row, col)] += v;
                }
            }
        }
        let worst = (0..k).map(|i| r[(i, 0)].abs()).fold(0.0, f64::max);
        if !worst.is_finite() {
            return Err(format!("user variables/differentials: not finite at t = {t}"));
        }
        if worst <= 1e-13 * (1.0 + z.iter().fold(0.0f64, |a, v| a.max(v.abs()))) {
            return Ok(());
        }
        let dx = faer::linalg::solvers::Solve::solve(&jac.full_piv_lu(), &r);
        for i in 0..k {
            z[nx + i] += dx[(i, 0)];
        }
    }
    Err(format!("user variables/differentials: Newton did not converge at t = {t} (algebraic loop?)"))
}
