//! Coordinate partitioning (Wehage & Haug 1982), position level: the coordinates q at
//! which the constraints C(q, t) = 0 hold together with given values of the position
//! states, s(q, t) = S, by Newton's method on the square system [C; s − S] from the last
//! consistent q (the least-norm corrections of [`super::gauss_newton`] are the Newton
//! steps of a square system). Model Exchange calls it at every state the host sets.

use super::gauss_newton::{self, Failure};
use crate::dae::sparse::SparseLu;
use crate::dae::start_values::{START_VALUE_TAG, StartValue};
use crate::mechanics::System;
use crate::mechanics::constraints::{ConstraintEl, ConstraintKind};
use crate::mechanics::measures::StateKind;
use crate::model::SrcPos;

/// Newton iterations before the placement gives up: from a nearby consistent point
/// Newton converges in 2–4; more means the states do not determine the positions there.
const MAX_ITERATIONS: usize = 30;

/// Newton iterations past `limit` towards round-off (each kept only while it halves the
/// residual; from 1e-12 two reach it).
const POLISH_ITERATIONS: usize = 3;

/// q with C(q, t) = 0 and every position state at its value in `states`, by Newton from
/// the `q` given (on success q is the solution; on failure the message names the states
/// and why, and q is unchanged). `limit`: the largest |C| or |s − S| accepted.
pub fn place_positions(
    sys: &System,
    states: &[StartValue<StateKind>],
    q: &mut [f64],
    t: f64,
    inputs: &[f64],
    limit: f64,
    lu: &mut SparseLu,
) -> Result<(), String> {
    let mut els: Vec<ConstraintEl> = sys.constraints.clone();
    let mut row = els.iter().map(|c| c.row + c.neq).max().unwrap_or(0);
    for s in states {
        let kind = ConstraintKind::State { kind: s.kind.clone(), value: s.value };
        let mut el = ConstraintEl::new(s.name.clone(), kind, s.bodies.clone(), START_VALUE_TAG, SrcPos::default());
        el.row = row;
        row += el.neq;
        els.push(el);
    }
    let mut trial = q.to_vec();
    match gauss_newton::solve(sys, &els, &mut trial, t, inputs, limit, MAX_ITERATIONS, lu) {
        Ok(()) => {
            // Down to round-off: the host differentiates ẋ(x) by differences of states
            // far smaller than `limit` (CVODE's increments of a zero state are ~1e-15);
            // positions stopped at `limit` would make ẋ a staircase at that scale and
            // the host's Jacobian garbage.
            gauss_newton::polish(sys, &els, &mut trial, t, inputs, POLISH_ITERATIONS, lu);
            q.copy_from_slice(&trial);
            Ok(())
        }
        Err(f) => {
            let blame = |row: usize| {
                els.iter()
                    .find(|e| row >= e.row && row < e.row + e.neq)
                    .map_or_else(String::new, |e| format!(" (worst: {} '{}')", e.tag, e.name))
            };
            let why = match f {
                Failure::NotFinite { row } => format!("the equations are not finite{}", blame(row)),
                Failure::Singular { row, residual } => format!(
                    "the states do not determine the positions there (singular [C_q; s_q], residual {residual:.3e}{})",
                    blame(row)
                ),
                Failure::NoConvergence { row, residual } => format!(
                    "Newton did not converge in {MAX_ITERATIONS} iterations (residual {residual:.3e}{})",
                    blame(row)
                ),
            };
            Err(format!("no configuration at t = {t} has the position states ({}): {why}", listed(states)))
        }
    }
}

/// The states with their values, "name = value, …", as the messages name them.
pub fn listed(states: &[StartValue<StateKind>]) -> String {
    states.iter().map(|s| format!("{} = {}", s.name, s.value)).collect::<Vec<_>>().join(", ")
}

/// 1 + max|q|: the size of a model at q, which position tolerances are relative to.
pub fn size(q: &[f64]) -> f64 {
    1.0 + q.iter().fold(0.0f64, |a, v| a.max(v.abs()))
}
