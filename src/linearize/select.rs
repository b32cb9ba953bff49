//! State selection (seed Eq. 30–33): factor J = [C_q 0; −ŝ_q D] with full pivoting (sparse), rows of
//! candidate states ŝ weighted up and D a small diagonal, so the pivots (dependent
//! coordinates) are taken among q first and independent candidates stay free — tier by
//! tier ([`super::tiers`]): user states, then joint coordinates ([`super::candidates`]).
//! The columns left without a pivot are the states S: the chosen candidates, completed
//! with body coordinates when they are too few; user states that found a pivot are
//! dropped (too many) and reported.

use super::candidates::{Candidate, Candidates, TIERS, position_candidates};
use super::jets::{PositionFn, jets};
use super::select_velocity::{VelOrigin, derivative_states, select_velocities};
use super::states::{StateFn, VelState, internal_state};
use super::tiers::{CandidateRow, TierError, choose_in_tiers, constraint_rows, gradient_row};
use super::tolerances::RANK_TOL;
use crate::mechanics::System;

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
    /// For each W_j, the k with W_j = Ṡ_k (see [`Selection::state_of_velocity`]).
    velocity_of: Vec<Option<usize>>,
}

impl Selection {
    /// A selection of `states` and `velocities` where W_j = Ṡ_k for `velocity_of[j] ==
    /// Some(k)` (one entry per velocity state; `velocities[j]` is then the derivative of
    /// `states[k]`).
    pub(crate) fn new(
        states: Vec<StateFn>,
        velocities: Vec<VelState>,
        velocity_of: Vec<Option<usize>>,
        dropped: Vec<String>,
        rank: usize,
    ) -> Selection {
        debug_assert_eq!(velocity_of.len(), velocities.len());
        debug_assert!(velocity_of.iter().zip(&velocities).all(|(k, w)| match k {
            Some(k) => matches!(w, VelState::Derivative(s) if *s == states[*k]),
            None => true,
        }));
        Selection { states, velocities, dropped, rank, velocity_of }
    }

    /// The index k of the position state S_k whose time derivative the velocity state W_j
    /// is (Eq. 34g–h: W_j = Ṡ_k); None for a user `<velocity>` or a velocity state that is
    /// not the derivative of a selected position state (non-holonomic models).
    pub fn state_of_velocity(&self, j: usize) -> Option<usize> {
        self.velocity_of.get(j).copied().flatten()
    }

    /// The index j of the velocity state W_j = Ṡ_k, if S_k has one.
    pub fn velocity_of_state(&self, k: usize) -> Option<usize> {
        self.velocity_of.iter().position(|o| *o == Some(k))
    }
}

/// Select s = n − rank(C_q) states at (q, t), favouring the model's user states, then
/// joint coordinates.
pub fn select_states(sys: &System, q: &[f64], t: f64, inputs: &[f64]) -> Result<Selection, String> {
    select_states_among(sys, q, t, inputs, Candidates::default())
}

/// Scale down each modal-coordinate column of the selection matrix (constraint rows
/// `fixed` and candidate rows `tiers`) whose largest |entry| exceeds one, to largest
/// |entry| one. Modal coordinates carry the data's normalization (a mass-normalized rotation shape
/// at a light node can be hundreds of rad per unit η), which would otherwise set the rank
/// tolerance (relative to the largest pivot) for the rigid columns too. Columns are never
/// scaled up: that would lift round-off (a mode's shape components of 1e-12 where it has
/// none) to the size of real entries. A column scaling is a change of units: it changes
/// neither the rank nor which coordinates stay free; rigid models have no modal columns
/// and are untouched.
fn scale_modal_columns(sys: &System, fixed: &mut [(usize, usize, f64)], tiers: &mut [Vec<CandidateRow>]) {
    let modal = sys.modal_columns();
    if modal.is_empty() {
        return;
    }
    let (first, mut big) = (modal.start, vec![1.0f64; modal.len()]);
    let rows = tiers.iter().flatten().flat_map(|r| r.entries.iter().map(|&(c, v)| (c, v)));
    for (c, v) in fixed.iter().map(|&(_, c, v)| (c, v)).chain(rows) {
        if c >= first {
            big[c - first] = big[c - first].max(v.abs());
        }
    }
    let scale = |c: usize, v: &mut f64| {
        if c >= first {
            *v /= big[c - first];
        }
    };
    fixed.iter_mut().for_each(|(_, c, v)| scale(*c, v));
    tiers.iter_mut().flatten().flat_map(|r| r.entries.iter_mut()).for_each(|(c, v)| scale(*c, v));
}

/// [`select_states`] with a chosen internal candidate set.
pub fn select_states_among(
    sys: &System,
    q: &[f64],
    t: f64,
    inputs: &[f64],
    which: Candidates,
) -> Result<Selection, String> {
    let n = sys.n();
    let zeros = vec![0.0; n];
    // Each candidate with its gradient ŝ_q; a joint coordinate without a finite one here
    // (e.g. an angle whose axes are degenerate) is no candidate.
    let mut cands: Vec<Candidate> = Vec::new();
    let mut tiers: Vec<Vec<CandidateRow>> = vec![Vec::new(); TIERS];
    let mut of_tier: Vec<Vec<usize>> = vec![Vec::new(); TIERS];
    for c in position_candidates(sys, q, t, inputs, which) {
        let g = jets(sys, &c.state, q, &zeros, &zeros, t, inputs).swap_remove(0);
        if !g.g.is_finite() || g.dg.iter().any(|v| !v.is_finite()) {
            if c.user {
                return Err(format!("linearization state '{}' has no finite value or derivative here", c.state.name));
            }
            continue;
        }
        tiers[c.tier].push(gradient_row(sys, c.state.bodies(), &g.dg));
        of_tier[c.tier].push(cands.len());
        cands.push(c);
    }
    let (mut fixed, nf) = constraint_rows(sys, q, t, inputs);
    scale_modal_columns(sys, &mut fixed, &mut tiers);
    // Sparse Gaussian elimination with complete pivoting (Eq. 33); pivots > RANK_TOL·max(largest, 1).
    let choice = choose_in_tiers(n, nf, &fixed, &tiers, RANK_TOL, false).map_err(|e| match e {
        TierError::NotFinite(e) => format!("the constraint Jacobian is not finite here ({e})"),
        TierError::Dependent => "the constraints are not independent".into(), // (not asked for)
    })?;
    let mut picked = vec![false; cands.len()];
    for (t, ks) in of_tier.iter().enumerate() {
        for (k, &c) in ks.iter().enumerate() {
            picked[c] = choice.chosen[t].get(k).copied().unwrap_or(false);
        }
    }
    // S: the chosen candidates, then the free coordinates; the S index of each.
    let mut states: Vec<StateFn> = Vec::new();
    let mut of_candidate = vec![None; cands.len()];
    for c in (0..cands.len()).filter(|&c| picked[c]) {
        of_candidate[c] = Some(states.len());
        states.push(cands[c].state.clone());
    }
    let first_free = states.len();
    states.extend(choice.free.iter().map(|&c| internal_state(sys, c)));
    let of_coordinate = |c: usize| choice.free.iter().position(|&f| f == c).map(|i| first_free + i);
    let mut dropped: Vec<String> =
        (0..cands.len()).filter(|&c| !picked[c] && cands[c].user).map(|c| cands[c].state.name.clone()).collect();
    if sys.mn == 0 {
        let velocity_of = (0..states.len()).map(Some).collect();
        return Ok(Selection::new(states.clone(), derivative_states(&states), velocity_of, dropped, choice.rank));
    }
    // B and the candidates' u-gradients do not depend on u (linear in velocities).
    let v = select_velocities(sys, q, &vec![0.0; n], t, inputs, &cands)?;
    // The S index of the position function a velocity candidate is the derivative of.
    let state_of = |o: VelOrigin| match o {
        VelOrigin::User(_) => None,
        VelOrigin::Candidate(c) => of_candidate[c],
        VelOrigin::Coordinate(c) => of_coordinate(c),
    };
    // A user state that is a position state stays one even without its derivative.
    dropped.extend(v.dropped.iter().filter(|(_, o)| state_of(*o).is_none()).map(|(w, _)| w.name()));
    let velocity_of = v.chosen.iter().map(|(_, o)| state_of(*o)).collect();
    let velocities = v.chosen.into_iter().map(|(w, _)| w).collect();
    Ok(Selection::new(states, velocities, velocity_of, dropped, choice.rank))
}
