//! Velocity-level state selection (the seed's closing remark on non-holonomic systems):
//! with non-holonomic constraints there are s1 = s0 − (non-holonomic equations) velocity
//! states W, chosen separately from the position states S by the same weighted full-pivot
//! factorization (Eq. 33), written in q̇: J1 = [C_q 0; B T 0; −w_q̇ D] with u = T(q) q̇.
//! Candidates: user `<velocity>` expressions (weighted most), the time derivatives of the
//! user position states, then every q̇_i (`der(body.x)` ...).

use super::jets::jets;
use super::select::{D_SMALL, RANK_TOL, USER_ROW_WEIGHT};
use super::states::{StateFn, VelState, internal_state, user_states, user_velocities};
use crate::dae::equations::nonholonomic_b;
use crate::dae::rank::full_pivot;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, row_times_t};
use crate::mechanics::kernels::constraint_first;

/// Preference of explicit `<velocity>` candidates over derivatives of user position states:
/// their rows weigh this much more and their D entries this much less, so full pivoting
/// eliminates them first and, between two dependent candidates, pivots (drops) the other.
const VELOCITY_PREFERENCE: f64 = 10.0;

/// Choose the velocity states W at (q, u, t) given the position selection `states`.
pub fn select_velocities(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> Result<(Vec<VelState>, Vec<String>), String> {
    let n = sys.n();
    let zeros = vec![0.0; n];
    // (candidate, its q̇-row, row weight, its D entry)
    let mut cands: Vec<(VelState, Vec<f64>, f64, f64)> = Vec::new();
    for v in user_velocities(sys) {
        let j = &jets(sys, &v, q, u, &zeros, t, ext)[0];
        let nql = NQ * v.bodies.len();
        let mut row = vec![0.0; n];
        for a in 0..nql {
            row[NQ * v.bodies[a / NQ] + a % NQ] = j.dg[nql + a];
        }
        row_times_t(q, &mut row);
        cands.push((VelState::User(v), row, USER_ROW_WEIGHT * VELOCITY_PREFERENCE, D_SMALL / VELOCITY_PREFERENCE));
    }
    for s in user_states(sys) {
        let j = &jets(sys, &s, q, u, &zeros, t, ext)[0];
        let mut row = vec![0.0; n];
        for (a, &b) in s.bodies.iter().enumerate() {
            for c in 0..NQ {
                row[NQ * b + c] = j.dg[NQ * a + c];
            }
        }
        cands.push((VelState::Derivative(s), row, USER_ROW_WEIGHT, D_SMALL));
    }
    let nc = cands.len();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, t, ext);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            if sys.redundant[el.row + e] {
                continue;
            }
            let mut row = vec![0.0; n];
            for a in 0..nql {
                row[NQ * el.bodies[a / NQ] + a % NQ] += f.cq[e * nql + a];
            }
            rows.push(row);
        }
    }
    let (b, _) = nonholonomic_b(sys, q, u, t, ext);
    let mut brows = vec![vec![0.0; n]; sys.mn];
    for (r, c, v) in b {
        brows[r][c] += v;
    }
    for mut row in brows {
        row_times_t(q, &mut row);
        rows.push(row);
    }
    let nr = rows.len();
    let mut j: Vec<(usize, usize, f64)> = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        j.extend(row.iter().enumerate().filter(|(_, v)| **v != 0.0).map(|(c, &v)| (r, c, v)));
    }
    for (k, (c, row, w, dk)) in cands.iter().enumerate() {
        if row.iter().any(|v| !v.is_finite()) {
            return Err(format!("velocity candidate '{}' has no finite derivative here", c.name()));
        }
        j.extend(row.iter().enumerate().filter(|(_, v)| **v != 0.0).map(|(col, &v)| (nr + k, col, -w * v)));
        j.push((nr + k, n + k, w * dk));
    }
    // Sparse complete pivoting (as at position level). Every candidate row has its own D
    // column, so J1 has full row rank exactly when the (independent) holonomic rows and the
    // non-holonomic rows are independent together.
    let piv = full_pivot(nr + nc, n + nc, j, RANK_TOL * RANK_TOL, 1.0)
        .map_err(|e| format!("the velocity constraint Jacobian is not finite here ({e})"))?;
    if piv.rank < nr + nc {
        return Err("the non-holonomic constraints are not independent of the others".into());
    }
    let pivoted = piv.pivoted_cols(n + nc);
    let mut out: Vec<VelState> = Vec::new();
    let mut dropped = Vec::new();
    for (k, (c, _, _, _)) in cands.into_iter().enumerate() {
        if !pivoted[n + k] {
            out.push(c);
        } else {
            dropped.push(c.name());
        }
    }
    out.extend((0..n).filter(|&c| !pivoted[c]).map(|c| VelState::Derivative(internal_state(sys, c))));
    Ok((out, dropped))
}

/// W = Ṡ for every position state (no non-holonomic constraints: s1 = s0).
pub fn derivative_states(states: &[StateFn]) -> Vec<VelState> {
    states.iter().cloned().map(VelState::Derivative).collect()
}
