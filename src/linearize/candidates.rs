//! The candidate set of state selection (seed Eq. 33): the functions that may become the
//! states S, in tiers of strict preference (see [`super::tiers`]): user states, then
//! joint coordinates of joints to ground, of joints between bodies, a spherical joint's
//! three angles last; body coordinates (the q columns themselves) fill in whatever the
//! candidates leave.

use super::jets::jets;
use super::states::{StateFn, joint_states, user_states};
use crate::mechanics::System;
use crate::mechanics::joint_coords::CoordRank;

/// A spherical joint's angles are candidates only while |pitch| stays below this (rad):
/// z-y-x angles are singular at ±π/2.
pub const MAX_SPHERICAL_PITCH: f64 = std::f64::consts::FRAC_PI_3;

/// Which internal candidates selection considers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Candidates {
    /// Joint coordinates, then body coordinates (the default).
    #[default]
    Joints,
    /// Body coordinates only (CM position and 3-1-3 angles of every body).
    BodiesOnly,
}

/// One position-level candidate.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The function that would be the state.
    pub state: StateFn,
    /// Its tier: 0 user states, then 1 + the joint coordinate's [`CoordRank`].
    pub tier: usize,
    /// A user `<linearization><state>` (reported when dropped).
    pub user: bool,
}

/// Number of tiers.
pub const TIERS: usize = 4;

/// The tier of a joint coordinate of rank `r`.
fn joint_tier(r: CoordRank) -> usize {
    match r {
        CoordRank::Grounded => 1,
        CoordRank::Relative => 2,
        CoordRank::Spherical => 3,
    }
}

/// The candidates at (q, t): user states, then (with [`Candidates::Joints`]) the joints'
/// free coordinates; a spherical joint's angles are left out near their singularity.
pub fn position_candidates(sys: &System, q: &[f64], t: f64, inputs: &[f64], which: Candidates) -> Vec<Candidate> {
    let mut out: Vec<Candidate> =
        user_states(sys).into_iter().map(|state| Candidate { state, tier: 0, user: true }).collect();
    if which == Candidates::BodiesOnly {
        return out;
    }
    let zeros = vec![0.0; sys.n()];
    let coords = joint_states(sys);
    for (state, c) in coords.iter().zip(&sys.joint_coords) {
        if c.rank == CoordRank::Spherical {
            // The joint's yaw, pitch and roll stand or fall together, on its pitch.
            let joint = c.name.rsplit_once('.').map_or("", |(j, _)| j);
            let pitch = coords.iter().find(|s| s.name == format!("{joint}.pitch"));
            let p = pitch.map_or(f64::NAN, |s| jets(sys, s, q, &zeros, &zeros, t, inputs)[0].g);
            if p.is_nan() || p.abs() > MAX_SPHERICAL_PITCH {
                continue;
            }
        }
        out.push(Candidate { state: state.clone(), tier: joint_tier(c.rank), user: false });
    }
    out
}
