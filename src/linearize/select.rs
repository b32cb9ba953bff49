//! State selection (seed Eq. 30–33): factor J = [C_q 0; −ŝ_q D] with full pivoting, rows of
//! user states weighted up and D a small diagonal, so the pivots (dependent coordinates)
//! are taken among q first and the user states stay independent. The columns left without
//! a pivot are the states S: user states first, completed with internal coordinates when
//! the user gave too few; user states that found a pivot are dropped (too many).

use super::jets::{PositionFn, jets};
use super::select_velocity::{derivative_states, select_velocities};
use super::states::{StateFn, VelState, internal_state, user_states};
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::kernels::constraint_first;
use faer::Mat;

/// Weight of user-state rows relative to constraint rows (Eq. 33's row weighting).
pub const USER_ROW_WEIGHT: f64 = 1e3;
/// The small diagonal D replacing the identity in Eq. 33 (biases column pivoting).
pub const D_SMALL: f64 = 1e-3;
/// A pivot below this fraction of the largest |J| entry counts as zero (rank decision).
pub const RANK_TOL: f64 = 1e-9;

/// The chosen states and what was dropped.
#[derive(Clone, Debug)]
pub struct Selection {
    /// Position-level states S (s0 of them).
    pub states: Vec<StateFn>,
    /// Velocity-level states W (s1 ≤ s0; the derivatives of S without non-holonomic
    /// constraints).
    pub velocities: Vec<VelState>,
    /// Names of user states dropped because they were not independent (too many).
    pub dropped: Vec<String>,
    /// Number of independent constraint equations (m minus redundant ones).
    pub rank: usize,
}

/// Select s = n − rank(C_q) states at (q, t), favouring the model's user states.
pub fn select_states(sys: &System, q: &[f64], t: f64, inputs: &[f64]) -> Result<Selection, String> {
    let n = sys.n();
    let m = sys.m;
    let users = user_states(sys);
    let nu = users.len();
    let (rows, cols) = (m + nu, n + nu);
    let mut j = Mat::<f64>::zeros(rows, cols);
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            if sys.redundant[el.row + e] {
                continue; // left as a zero row: it adds no rank
            }
            for a in 0..nql {
                j[(el.row + e, NQ * el.bodies[a / NQ] + a % NQ)] += f.cq[e * nql + a];
            }
        }
    }
    let zeros = vec![0.0; n];
    for (k, s) in users.iter().enumerate() {
        let g = &jets(sys, s, q, &zeros, &zeros, t, inputs)[0];
        if !g.g.is_finite() || g.dg.iter().any(|v| !v.is_finite()) {
            return Err(format!("linearization state '{}' has no finite value or derivative here", s.name));
        }
        for (a, &b) in s.bodies().iter().enumerate() {
            for c in 0..NQ {
                j[(m + k, NQ * b + c)] = -USER_ROW_WEIGHT * g.dg[NQ * a + c];
            }
        }
        j[(m + k, n + k)] = USER_ROW_WEIGHT * D_SMALL;
    }
    // Full-pivot Gaussian elimination; faer's full_piv_lu gives the column order.
    let lu = j.full_piv_lu();
    let u = lu.U();
    let big = (0..rows.min(cols)).map(|i| u[(i, i)].abs()).fold(0.0, f64::max).max(1.0);
    let rank = (0..rows.min(cols)).take_while(|&i| u[(i, i)].abs() > RANK_TOL * big).count();
    let perm = lu.Q().arrays().0.to_vec();
    let free: Vec<usize> = perm[rank..].to_vec();
    let pivoted: Vec<usize> = perm[..rank].to_vec();
    let mut states: Vec<StateFn> = Vec::new();
    for (k, user) in users.iter().enumerate() {
        if free.contains(&(n + k)) {
            states.push(user.clone());
        }
    }
    let mut internal: Vec<usize> = free.iter().copied().filter(|&c| c < n).collect();
    internal.sort_unstable();
    states.extend(internal.iter().map(|&c| internal_state(sys, c)));
    let mut dropped: Vec<String> =
        (0..nu).filter(|k| pivoted.contains(&(n + k))).map(|k| users[k].name.clone()).collect();
    let velocities = if sys.mn == 0 {
        derivative_states(&states)
    } else {
        // B and the candidates' u-gradients do not depend on u (linear in velocities).
        let (v, d) = select_velocities(sys, q, &vec![0.0; n], t, inputs)?;
        dropped.extend(d.into_iter().filter(|d| !states.iter().any(|s| format!("der({})", s.name) == *d)));
        v
    };
    Ok(Selection { states, velocities, dropped, rank: rank.saturating_sub(nu) })
}
