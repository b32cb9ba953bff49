//! Velocity-level state selection (the seed's closing remark on non-holonomic systems):
//! with non-holonomic constraints there are s1 = s0 − (non-holonomic equations) velocity
//! states W, chosen separately from the position states S by the same weighted full-pivot
//! factorization (Eq. 33, tier by tier as in [`super::tiers`]), written in q̇:
//! J1 = [C_q 0; B T 0; −w_q̇ D] with u = T(q) q̇. Tiers: user `<velocity>` expressions, then
//! the time derivatives of the position candidates in their own tiers (user states, joint
//! coordinates); every q̇_i (`der(body.x)` ...) completes the set.

use super::candidates::{Candidate, TIERS};
use super::jets::jets;
use super::states::{StateFn, VelState, internal_state, user_velocities};
use super::tiers::{CandidateRow, TierError, choose_in_tiers, constraint_rows, gradient_row};
use super::tolerances::RANK_TOL;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, block_times_t};
use crate::mechanics::coords::{global_column, nql};
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;
use std::collections::BTreeMap;

/// Sparse entries of a dense row.
/// A sparse u-space row (global columns, any order, repeated columns summed) as the same
/// linear form in q̇ (times T(q)): sorted by column, zeros left out.
fn qdot_row(sys: &System, q: &[f64], entries: impl IntoIterator<Item = (usize, f64)>) -> Vec<(usize, f64)> {
    let body_cols = sys.modal_columns().start;
    let mut by_body: BTreeMap<usize, [f64; NQ]> = BTreeMap::new();
    let mut modal: BTreeMap<usize, f64> = BTreeMap::new(); // T = I for modal velocities
    for (c, v) in entries {
        if c >= body_cols {
            *modal.entry(c).or_insert(0.0) += v;
        } else {
            by_body.entry(c / NQ).or_insert([0.0; NQ])[c % NQ] += v;
        }
    }
    let blocks = by_body.into_iter().flat_map(|(b, mut r)| {
        block_times_t(&q[NQ * b..NQ * (b + 1)], &mut r);
        (0..NQ).map(move |c| (NQ * b + c, r[c]))
    });
    blocks.chain(modal).filter(|&(_, v)| v != 0.0).collect()
}

/// Where a velocity candidate comes from (the index relation to the position level).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VelOrigin {
    /// The user's `<velocity>` k (its index among [`user_velocities`]).
    User(usize),
    /// The time derivative of position candidate i (its index in the `pos` argument).
    Candidate(usize),
    /// The time derivative q̇_c of coordinate c (a body coordinate completing the set).
    Coordinate(usize),
}

/// The outcome of [`select_velocities`].
#[derive(Clone, Debug, Default)]
pub struct VelocityChoice {
    /// The velocity states W, in order, with their origins.
    pub chosen: Vec<(VelState, VelOrigin)>,
    /// The user's candidates (`<velocity>`s and derivatives of user states) not chosen.
    pub dropped: Vec<(VelState, VelOrigin)>,
}

/// Choose the velocity states W at (q, u, t) among the user's `<velocity>` expressions
/// and the derivatives of the position candidates `pos`.
pub fn select_velocities(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
    pos: &[Candidate],
) -> Result<VelocityChoice, String> {
    let n = sys.n();
    let zeros = vec![0.0; n];
    // (candidate, its origin, a user's) by tier, with their q̇-rows.
    let mut cands: Vec<Vec<(VelState, VelOrigin, bool)>> = vec![Vec::new(); TIERS + 1];
    let mut tiers: Vec<Vec<CandidateRow>> = vec![Vec::new(); TIERS + 1];
    let mut push = |tier: usize, c: VelState, origin: VelOrigin, user: bool, row: CandidateRow| {
        if row.entries.iter().any(|(_, v)| !v.is_finite()) {
            return Err(format!("velocity candidate '{}' has no finite derivative here", c.name()));
        }
        tiers[tier].push(row);
        cands[tier].push((c, origin, user));
        Ok(())
    };
    for (k, v) in user_velocities(sys).into_iter().enumerate() {
        let j = &jets(sys, &v, q, u, &zeros, t, ext)[0];
        let nql = nql(sys, &v.bodies);
        let row = qdot_row(sys, q, (0..nql).map(|a| (global_column(sys, &v.bodies, a), j.dg[nql + a])));
        push(0, VelState::User(v), VelOrigin::User(k), true, CandidateRow { entries: row })?;
    }
    for (i, Candidate { state: s, tier, user }) in pos.iter().enumerate() {
        // d/dt s(q) = s_q q̇: the position gradient is the q̇-row.
        let j = &jets(sys, s, q, u, &zeros, t, ext)[0];
        let row = gradient_row(sys, &s.bodies, &j.dg);
        push(tier + 1, VelState::Derivative(s.clone()), VelOrigin::Candidate(i), *user, row)?;
    }
    let (mut fixed, mut nf) = constraint_rows(sys, q, t, ext);
    let (b, _) = nonholonomic_b(sys, q, u, t, ext);
    let mut brows = vec![Vec::new(); sys.mn];
    for (r, c, v) in b {
        brows[r].push((c, v));
    }
    for row in brows {
        fixed.extend(qdot_row(sys, q, row).into_iter().map(|(c, v)| (nf, c, v)));
        nf += 1;
    }
    // Sparse complete pivoting (as at position level); the (independent) holonomic rows
    // and the non-holonomic rows must be independent together.
    let choice = choose_in_tiers(n, nf, &fixed, &tiers, RANK_TOL * RANK_TOL, true).map_err(|e| match e {
        TierError::NotFinite(e) => format!("the velocity constraint Jacobian is not finite here ({e})"),
        TierError::Dependent => "the non-holonomic constraints are not independent of the others".into(),
    })?;
    let mut out = VelocityChoice::default();
    for (tier, cs) in cands.into_iter().enumerate() {
        for (k, (c, origin, user)) in cs.into_iter().enumerate() {
            if choice.chosen[tier].get(k).copied().unwrap_or(false) {
                out.chosen.push((c, origin));
            } else if user {
                out.dropped.push((c, origin));
            }
        }
    }
    out.chosen
        .extend(choice.free.iter().map(|&c| (VelState::Derivative(internal_state(sys, c)), VelOrigin::Coordinate(c))));
    Ok(out)
}

/// W = Ṡ for every position state (no non-holonomic constraints: s1 = s0).
pub fn derivative_states(states: &[StateFn]) -> Vec<VelState> {
    states.iter().cloned().map(VelState::Derivative).collect()
}
