//! Velocity-level state selection (the seed's closing remark on non-holonomic systems):
//! with non-holonomic constraints there are s1 = s0 − (non-holonomic equations) velocity
//! states W, chosen separately from the position states S by the same weighted full-pivot
//! factorization (Eq. 33, tier by tier as in [`super::tiers`]), written in q̇:
//! J1 = [C_q 0; B T 0; −w_q̇ D] with u = T(q) q̇. Tiers: user `<velocity>` expressions, then
//! the time derivatives of the position candidates in their own tiers (user states, joint
//! coordinates); every q̇_i (`der(body.x)` ...) completes the set.

use super::candidates::{Candidate, TIERS};
use super::jets::jets;
use super::select::RANK_TOL;
use super::states::{StateFn, VelState, internal_state, user_velocities};
use super::tiers::{CandidateRow, TierError, choose_in_tiers, constraint_rows, gradient_row};
use crate::dae::equations::nonholonomic_b;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, row_times_t};

/// Sparse entries of a dense row.
fn sparse(row: &[f64]) -> Vec<(usize, f64)> {
    row.iter().enumerate().filter(|(_, v)| **v != 0.0).map(|(c, &v)| (c, v)).collect()
}

/// Choose the velocity states W at (q, u, t) among the user's `<velocity>` expressions
/// and the derivatives of the position candidates `pos`; also returns the names of
/// dropped user candidates.
pub fn select_velocities(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
    pos: &[Candidate],
) -> Result<(Vec<VelState>, Vec<String>), String> {
    let n = sys.n();
    let zeros = vec![0.0; n];
    // (candidate, a user's) by tier, with their q̇-rows.
    let mut cands: Vec<Vec<(VelState, bool)>> = vec![Vec::new(); TIERS + 1];
    let mut tiers: Vec<Vec<CandidateRow>> = vec![Vec::new(); TIERS + 1];
    let mut push = |tier: usize, c: VelState, user: bool, row: CandidateRow| {
        if row.entries.iter().any(|(_, v)| !v.is_finite()) {
            return Err(format!("velocity candidate '{}' has no finite derivative here", c.name()));
        }
        tiers[tier].push(row);
        cands[tier].push((c, user));
        Ok(())
    };
    for v in user_velocities(sys) {
        let j = &jets(sys, &v, q, u, &zeros, t, ext)[0];
        let nql = NQ * v.bodies.len();
        let mut row = vec![0.0; n];
        for a in 0..nql {
            row[NQ * v.bodies[a / NQ] + a % NQ] = j.dg[nql + a];
        }
        row_times_t(q, &mut row);
        push(0, VelState::User(v), true, CandidateRow { entries: sparse(&row) })?;
    }
    for Candidate { state: s, tier, user } in pos {
        // d/dt s(q) = s_q q̇: the position gradient is the q̇-row.
        let j = &jets(sys, s, q, u, &zeros, t, ext)[0];
        push(tier + 1, VelState::Derivative(s.clone()), *user, gradient_row(&s.bodies, &j.dg))?;
    }
    let (mut fixed, mut nf) = constraint_rows(sys, q, t, ext);
    let (b, _) = nonholonomic_b(sys, q, u, t, ext);
    let mut brows = vec![vec![0.0; n]; sys.mn];
    for (r, c, v) in b {
        brows[r][c] += v;
    }
    for mut row in brows {
        row_times_t(q, &mut row);
        fixed.extend(sparse(&row).into_iter().map(|(c, v)| (nf, c, v)));
        nf += 1;
    }
    // Sparse complete pivoting (as at position level); the (independent) holonomic rows
    // and the non-holonomic rows must be independent together.
    let choice = choose_in_tiers(n, nf, &fixed, &tiers, RANK_TOL * RANK_TOL, true).map_err(|e| match e {
        TierError::NotFinite(e) => format!("the velocity constraint Jacobian is not finite here ({e})"),
        TierError::Dependent => "the non-holonomic constraints are not independent of the others".into(),
    })?;
    let mut out: Vec<VelState> = Vec::new();
    let mut dropped = Vec::new();
    for (tier, cs) in cands.into_iter().enumerate() {
        for (k, (c, user)) in cs.into_iter().enumerate() {
            if choice.chosen[tier].get(k).copied().unwrap_or(false) {
                out.push(c);
            } else if user {
                dropped.push(c.name());
            }
        }
    }
    out.extend(choice.free.iter().map(|&c| VelState::Derivative(internal_state(sys, c))));
    Ok((out, dropped))
}

/// W = Ṡ for every position state (no non-holonomic constraints: s1 = s0).
pub fn derivative_states(states: &[StateFn]) -> Vec<VelState> {
    states.iter().cloned().map(VelState::Derivative).collect()
}
