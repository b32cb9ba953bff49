//! State selection (seed Eq. 30–33): factor J = [C_q 0; −ŝ_q D] with full pivoting (sparse), rows of
//! user states weighted up and D a small diagonal, so the pivots (dependent coordinates)
//! are taken among q first and the user states stay independent. The columns left without
//! a pivot are the states S: user states first, completed with internal coordinates when
//! the user gave too few; user states that found a pivot are dropped (too many).

use super::jets::{PositionFn, jets};
use super::select_velocity::{derivative_states, select_velocities};
use super::states::{StateFn, VelState, internal_state, user_states};
use crate::dae::rank::full_pivot;
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::kernels::constraint_first;

/// Weight of user-state rows relative to constraint rows (Eq. 33's row weighting).
pub const USER_ROW_WEIGHT: f64 = 1e3;
/// The small diagonal D replacing the identity in Eq. 33 (biases column pivoting).
pub const D_SMALL: f64 = 1e-3;
/// A pivot below this fraction of the largest pivot (at least 1) counts as zero (rank decision).
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
    let mut j: Vec<(usize, usize, f64)> = Vec::new();
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            if sys.redundant[el.row + e] {
                continue; // left out: it adds no rank
            }
            for a in 0..nql {
                j.push((el.row + e, NQ * el.bodies[a / NQ] + a % NQ, f.cq[e * nql + a]));
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
                j.push((m + k, NQ * b + c, -USER_ROW_WEIGHT * g.dg[NQ * a + c]));
            }
        }
        j.push((m + k, n + k, USER_ROW_WEIGHT * D_SMALL));
    }
    // Sparse Gaussian elimination with complete pivoting (Eq. 33); pivots > RANK_TOL·max(largest, 1).
    let piv = full_pivot(rows, cols, j, RANK_TOL, 1.0)
        .map_err(|e| format!("the constraint Jacobian is not finite here ({e})"))?;
    let rank = piv.rank;
    let pivoted = piv.pivoted_cols(cols);
    let mut states: Vec<StateFn> = Vec::new();
    for (k, user) in users.iter().enumerate() {
        if !pivoted[n + k] {
            states.push(user.clone());
        }
    }
    let internal: Vec<usize> = (0..n).filter(|&c| !pivoted[c]).collect();
    states.extend(internal.iter().map(|&c| internal_state(sys, c)));
    let mut dropped: Vec<String> = (0..nu).filter(|&k| pivoted[n + k]).map(|k| users[k].name.clone()).collect();
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
