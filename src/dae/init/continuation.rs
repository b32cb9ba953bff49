//! The way from the drawn pose to the exact conditions: the drives (exact joint ICs
//! `ic_angle` / `ic_displacement`, motions at t0, start values set on states) are moved together from the values
//! they have in the drawn (joint-consistent) pose to their targets in small steps, each
//! solved by Newton from the last, so that assembly follows the mechanism's own branch
//! (continuation in the target values). A step is taken again at half the size when
//! Newton fails, a joint turns inside out, an exact angle lands on its spurious root
//! f + π, or a body turns by more than [`MAX_BODY_TURN`]. After each step the Euler
//! frames are re-based and the angle measures recorded, so that every angle stays
//! continuous along the way.

use super::gauss_newton::{self, Failure};
use super::orientation;
use crate::dae::sparse::SparseLu;
use crate::geom::rot313;
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::constraints::{ConstraintEl, ConstraintKind};
use crate::mechanics::coords::gather;
use crate::mechanics::forces::ForceKind;
use crate::mechanics::local::LocalCtx;
use crate::mechanics::measures::StateKind;
use crate::model::SpringType;
use crate::model::expr::{Expr, ExprEnv, KinFn};
use crate::model::units;

/// Largest change of an exact angle in one step (rad).
pub(super) const ANGLE_STEP: f64 = std::f64::consts::PI / 16.0;
/// Largest change of an exact displacement in one step, relative to the model's size.
pub(super) const DISPLACEMENT_STEP: f64 = 0.1;
/// Largest rotation of any body in one step (rad); a larger one is taken as a jump to
/// another branch of the mechanism, and the step is halved.
pub(super) const MAX_BODY_TURN: f64 = 0.6;
/// Smallest step, as a fraction of the whole way, before the way is given up.
const MIN_STEP: f64 = 1.0 / 4096.0;
/// Newton iterations past convergence at the end of the way (down to round-off).
const POLISH_ITERATIONS: usize = 3;
/// Newton iterations per step of the way (a step starts close to its solution).
const STEP_ITERATIONS: usize = 12;

/// A driven coordinate: element `index` of the assembled list moves its measure from
/// `start` (the drawn pose) to `end`, which equals `target` (for an angle, up to whole
/// turns: the way is the shorter one).
#[derive(Clone, Debug)]
pub(super) struct Drive {
    /// Index of the element in the list assembled.
    pub index: usize,
    /// The measure in the drawn pose.
    pub start: f64,
    /// Where the way ends.
    pub end: f64,
    /// What the model asks for.
    pub target: f64,
    /// An angle (rad), else a displacement (m).
    pub angular: bool,
}

/// Whether element `el` is a drive (its value is set by the model, not by the drawing).
pub(super) fn is_drive(el: &ConstraintEl) -> bool {
    matches!(
        el.kind,
        ConstraintKind::Rotation { .. } | ConstraintKind::Translation { .. } | ConstraintKind::State { .. }
    )
}

/// The drives among `els`, measured at q (the drawn pose made consistent with the joints).
pub(super) fn drives(sys: &System, els: &[ConstraintEl], q: &[f64], t: f64, inputs: &[f64]) -> Vec<Drive> {
    let mut out = Vec::new();
    for (index, el) in els.iter().enumerate() {
        let ql = gather(sys, &el.bodies, q);
        let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], t, inputs);
        let (start, target, angular) = match &el.kind {
            ConstraintKind::Rotation { i, j, f, abase } => {
                let (a, b) = (ctx.pose(*i).r, ctx.pose(*j).r);
                let xi = a.col(0);
                (xi.dot(&b.col(1)).atan2(xi.dot(&b.col(0))), ctx.eval_expr(f, *abase), true)
            }
            ConstraintKind::Translation { i, j, f, abase } => {
                let (a, b) = (ctx.pose(*i), ctx.pose(*j));
                ((a.p - b.p).dot(&b.r.col(2)), ctx.eval_expr(f, *abase), false)
            }
            // A state's measure is continuous (angles unwrapped along the way): the way
            // goes straight to the value, whole turns included. Steps of a length are
            // sized as displacements, of anything else as angles (in its own unit).
            ConstraintKind::State { kind, value } => {
                let length = matches!(kind, StateKind::Position { .. })
                    || matches!(kind, StateKind::Joint { f, .. } | StateKind::User { f, .. }
                        if units::of_expr(f) == Some("m"));
                let start = kind.eval(&ctx);
                out.push(Drive { index, start, end: *value, target: *value, angular: !length });
                continue;
            }
            _ => continue,
        };
        let two_pi = 2.0 * std::f64::consts::PI;
        let end = if angular { target - two_pi * ((target - start) / two_pi).round() } else { target };
        out.push(Drive { index, start, end, target, angular });
    }
    out
}

/// `els` with each drive's function replaced by its value at fraction `s` of the way.
fn at(els: &[ConstraintEl], drives: &[Drive], s: f64) -> Vec<ConstraintEl> {
    let mut out = els.to_vec();
    for d in drives {
        let v = if s >= 1.0 { d.end } else { d.start + s * (d.end - d.start) };
        match &mut out[d.index].kind {
            ConstraintKind::Rotation { f, .. } | ConstraintKind::Translation { f, .. } => *f = Expr::Num(v),
            ConstraintKind::State { value, .. } => *value = v,
            _ => unreachable!("a drive is a rotation, a translation or a state"),
        }
    }
    out
}

/// Where the way stopped: the fraction reached and the last failure.
pub(super) struct Stalled {
    /// Fraction of the way reached.
    pub reached: f64,
    /// Why the last step failed.
    pub why: String,
    /// The elements at the targets (for reporting what is not met).
    pub els: Vec<ConstraintEl>,
}

/// Follow the way from s = 0 (q meets `els` with the drives at their start) to s = 1,
/// ending with every element met to `limit`; `size` is the model's size (m).
#[allow(clippy::too_many_arguments)]
pub(super) fn follow(
    sys: &mut System,
    els: &[ConstraintEl],
    drives: &[Drive],
    q: &mut [f64],
    t: f64,
    inputs: &[f64],
    limit: f64,
    size: f64,
) -> Result<Vec<ConstraintEl>, Stalled> {
    let way = drives
        .iter()
        .map(|d| (d.end - d.start).abs() / if d.angular { ANGLE_STEP } else { DISPLACEMENT_STEP * size })
        .fold(0.0f64, f64::max);
    let max_step = if way > 1.0 { 1.0 / way } else { 1.0 };
    let mut lu = SparseLu::new();
    let (mut s, mut ds) = (0.0f64, max_step);
    let zeros = vec![0.0; sys.n()];
    let mut why = String::new();
    while s < 1.0 {
        if ds < MIN_STEP {
            return Err(Stalled { reached: s, why, els: at(els, drives, 1.0) });
        }
        let s_try = if s + ds > 1.0 - 1e-12 { 1.0 } else { s + ds };
        let step_els = at(els, drives, s_try);
        let mut q_try = q.to_vec();
        let step_limit = if s_try >= 1.0 { limit } else { limit.max(1e-10 * size) };
        let result = gauss_newton::solve(sys, &step_els, &mut q_try, t, inputs, step_limit, STEP_ITERATIONS, &mut lu);
        let rejected = match result {
            Err(f) => Some(describe(f, &step_els)),
            Ok(()) => orientation::violation(sys, &step_els, &q_try, t, inputs)
                .map(|v| format!("{} '{}': {}", step_els[v.index].tag, step_els[v.index].name, v.msg))
                .or_else(|| {
                    let turn = largest_turn(sys, q, &q_try);
                    (turn > MAX_BODY_TURN).then(|| format!("a body turned by {turn:.3} rad in one step"))
                }),
        };
        match rejected {
            Some(w) => {
                why = w;
                ds /= 2.0;
            }
            None => {
                q.copy_from_slice(&q_try);
                s = s_try;
                sys.rebase_frames(q);
                sys.record_angles(t, q, &zeros, inputs);
                ds = (2.0 * ds).min(max_step);
            }
        }
    }
    let done = at(els, drives, 1.0);
    gauss_newton::polish(sys, &done, q, t, inputs, POLISH_ITERATIONS, &mut lu);
    Ok(done)
}

/// A Newton failure in words.
fn describe(f: Failure, els: &[ConstraintEl]) -> String {
    let at_row = |row: usize| {
        els.iter()
            .find(|e| row >= e.row && row < e.row + e.neq)
            .map_or(String::new(), |e| format!(" at {} '{}'", e.tag, e.name))
    };
    match f {
        Failure::NotFinite { row } => format!("equations not finite{}", at_row(row)),
        Failure::Singular { row, residual } => {
            format!("constraint Jacobian singular (worst residual {residual:.3e}{})", at_row(row))
        }
        Failure::NoConvergence { row, residual } => {
            format!("Newton did not converge (worst residual {residual:.3e}{})", at_row(row))
        }
    }
}

/// The largest rotation of any body between coordinates `a` and `b` (same frames R0).
fn largest_turn(sys: &System, a: &[f64], b: &[f64]) -> f64 {
    (0..sys.nb())
        .map(|k| {
            let o = NQ * k + 3;
            let ra = rot313(a[o], a[o + 1], a[o + 2]);
            let rb = rot313(b[o], b[o + 1], b[o + 2]);
            let r = ra.t().mm(&rb).val();
            let cos = ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0).clamp(-1.0, 1.0);
            cos.acos()
        })
        .fold(0.0, f64::max)
}

/// Angles asked for beyond the shorter way (a drive whose target is not its end): the
/// measures of that joint's rotation (its joint coordinate, linearization states and
/// outputs that are exactly `az(i, j)`, rotational springs between i and j) are put on
/// the target's branch, so that `ic_angle="4"` reads 4, not 4 − 2π.
pub(super) fn wind(sys: &mut System, els: &[ConstraintEl], drives: &[Drive]) {
    for d in drives.iter().filter(|d| d.angular && d.end != d.target) {
        let ConstraintKind::Rotation { i, j, .. } = els[d.index].kind else { continue };
        let az = Expr::Kin(KinFn::Az, i, Some(j), None);
        let mut slots: Vec<usize> = sys.joint_coords.iter().filter(|c| c.f == az).map(|c| c.abase).collect();
        slots.extend(sys.lin_states.iter().filter(|s| s.1 == az).map(|s| s.2));
        slots.extend(sys.outputs.iter().zip(&sys.output_bases).filter(|(e, _)| **e == az).map(|(_, b)| *b));
        for g in slots {
            sys.angle_refs[g] = d.target;
            sys.angle_rates[g] = 0.0;
        }
        for f in &mut sys.forces {
            if let ForceKind::SpringDamper { kind: SpringType::Rotational, i: fi, j: fj, .. } = f.kind
                && (fi, fj) == (i, j)
            {
                f.angle_ref = d.target;
            }
        }
    }
}
