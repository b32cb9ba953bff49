//! Whether a host's states went past a fold of their chart (Model Exchange). Chosen
//! position states S = s(q) parameterize the positions only where [C_q; s_q] is
//! nonsingular; a motion that runs through a configuration where it is singular (a blade's
//! y at its largest, a four-bar's rocker angle at a dead point) crosses into the other
//! branch of s⁻¹, while the ODE in S turns back on the branch it came from, smooth and
//! wrong. Placement alone cannot see it (every point it is given has a configuration); the
//! motion can: from the last accepted point, the positions extrapolated along its rates
//! lead Newton to the configuration the motion continues to. If that is another one than
//! the engine reached, the same states hold at two configurations on either side of a
//! fold the step went through.

use super::error::EngineError;
use super::init;
use super::init::placement::{listed, size};
use super::partitioned::PLACEMENT_TOL;
use super::simulator::Simulator;
use super::start_values::StartValues;
use crate::mechanics::coords::rates;

/// Two placed configurations closer than this (relative to 1 + max|q|) are the same one:
/// far above the placement's round-off (1e-12 with a condition of 1e4), far below the
/// distance of two branches a step apart.
const SAME_CONFIGURATION: f64 = 1e-8;

/// The engine's point at a host's accepted step: time, positions, their rates, and the
/// bodies' Euler reference frames the positions are read in (row-major, nine per body).
#[derive(Clone, Debug, PartialEq)]
pub struct Accepted {
    /// Time.
    pub t: f64,
    /// Positions q.
    pub q: Vec<f64>,
    /// q̇ = H(q) u.
    pub qdot: Vec<f64>,
    /// R0 of every body.
    pub frames: Vec<f64>,
}

impl Simulator {
    /// The current point as an [`Accepted`] one.
    pub fn accepted_point(&self) -> Accepted {
        let sys = self.system();
        Accepted {
            t: self.time(),
            q: self.q().to_vec(),
            qdot: rates(sys.nb(), self.q(), self.u()),
            frames: frames(self),
        }
    }

    /// Err if the current point (placed with the position states of `set`) is not the one
    /// the motion from `prev` continues to: Newton on the same states from
    /// q(prev) + (t − t(prev)) q̇(prev) finds another configuration. Not checked (Ok) when
    /// time did not advance, when Euler frames were re-based in between (the coordinates
    /// differ), or when that Newton fails (the step too long to tell).
    pub fn check_branch(&mut self, prev: &Accepted, set: &StartValues) -> Result<(), EngineError> {
        let (t, h) = (self.time(), self.time() - prev.t);
        if h.is_nan() || h <= 0.0 || frames(self) != prev.frames || prev.q.len() != self.q().len() {
            return Ok(());
        }
        let mut q: Vec<f64> = prev.q.iter().zip(&prev.qdot).map(|(q, v)| q + h * v).collect();
        let scale = size(self.q());
        let inputs = self.dae.inputs_at(t);
        let sys = &self.dae.sys;
        let placed =
            init::place_positions(sys, &set.positions, &mut q, t, &inputs, PLACEMENT_TOL * scale, &mut self.acc_lu);
        if placed.is_err() {
            return Ok(());
        }
        let apart = q.iter().zip(self.q()).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        if apart <= SAME_CONFIGURATION * scale {
            return Ok(());
        }
        Err(EngineError::Numeric(format!(
            "between t = {} and t = {t} the position states went through a configuration they do not \
             parameterize: at t = {t} the states ({}) hold at two configurations {apart:.3e} apart, the one \
             reached from the last point and the one the motion continues to (a fold of the states' chart: \
             choose <linearization> states that stay independent along the motion)",
            prev.t,
            listed(&set.positions)
        )))
    }
}

/// The bodies' reference frames, flattened.
fn frames(sim: &Simulator) -> Vec<f64> {
    sim.system().r0.iter().flat_map(|r| r.iter().flatten().copied()).collect()
}
