//! Position assembly: q with C(q, t) = 0 and every exact condition (joint ICs, motions at
//! t0) met exactly, changing the given q as little as possible, in three steps:
//! 1. the drawn pose is made consistent with the joints and other constraints, the drives
//!    left free (least-norm Newton corrections, [`super::gauss_newton`]);
//! 2. the drives are moved from their values there to their targets along a path
//!    ([`super::continuation`]), so the mechanism stays on its own branch;
//! 3. every joint's orientation condition is checked ([`super::orientation`]): a joint
//!    put together inside out is an error naming it, never a silent start.

use super::continuation::{self, Drive};
use super::gauss_newton::{self, Failure};
use super::orientation;
use crate::dae::sparse::SparseLu;
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::constraint_jacobian::constraint_rows;
use crate::mechanics::constraints::ConstraintEl;
use crate::mechanics::local::LocalCtx;

/// Newton iterations before the first step (the drawn pose made consistent) gives up.
const MAX_ITERATIONS: usize = 100;

/// An initialization failure, located at the constraint element to blame when there is one.
#[derive(Clone, Debug)]
pub struct InitError {
    /// The element and which of its equations (1-based).
    pub element: Option<Box<(ConstraintEl, usize)>>,
    /// What went wrong.
    pub msg: String,
}

/// What assembly did, for the user's information.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Coordinates after step 1: the drawn pose made consistent with the constraints
    /// (what the drawing itself lacked), before the exact conditions moved it.
    pub drawn: Vec<f64>,
    /// The elements the drawn pose did not meet (tag, name, largest |C|), worst first.
    pub drawing_unmet: Vec<(&'static str, String, f64)>,
}

/// An error blamed on the element holding constraint row `row`.
fn at_row(els: &[ConstraintEl], row: usize, msg: String) -> InitError {
    let element =
        els.iter().find(|e| row >= e.row && row < e.row + e.neq).map(|e| Box::new((e.clone(), row - e.row + 1)));
    InitError { element, msg }
}

/// An error blamed on the whole element `el` (its first equation).
fn at_element(el: &ConstraintEl, msg: String) -> InitError {
    InitError { element: Some(Box::new((el.clone(), 1))), msg }
}

/// Assemble positions: q closest to `q` with C(q, t) = 0, the exact ICs and the motions
/// met exactly on the mechanism's own branch. Updates the system's Euler frames and
/// angle branches along the way (so `ic_angle="4"` reads 4).
pub fn assemble_positions(
    sys: &mut System,
    q: &mut [f64],
    t: f64,
    inputs: &[f64],
    tol: f64,
) -> Result<Assembly, InitError> {
    let els: Vec<ConstraintEl> = sys.constraints.iter().chain(sys.ic_constraints.iter()).cloned().collect();
    let scale = super::placement::size(q);
    let limit = tol * scale;
    let zeros = vec![0.0; sys.n()];
    // 1. The drawing made consistent; drives left free.
    let free: Vec<ConstraintEl> = els.iter().filter(|e| !continuation::is_drive(e)).cloned().collect();
    let drawing_unmet =
        unmet_list(sys, &free, q, t, inputs, limit).into_iter().map(|(e, r)| (e.tag, e.name.clone(), r)).collect();
    let mut lu = SparseLu::new();
    gauss_newton::solve(sys, &free, q, t, inputs, limit, MAX_ITERATIONS, &mut lu)
        .map_err(|f| failure(sys, &free, q, t, inputs, limit, f))?;
    if let Some(v) = orientation::violation(sys, &free, q, t, inputs) {
        return Err(at_element(&free[v.index], format!("cannot be assembled as drawn: {}", v.msg)));
    }
    sys.rebase_frames(q);
    sys.record_angles(t, q, &zeros, inputs);
    let drawn = q.to_vec();
    // 2. The drives to their targets, along the way.
    let drives = continuation::drives(sys, &els, q, t, inputs);
    if !drives.is_empty() {
        let size = model_size(sys, q);
        let done = continuation::follow(sys, &els, &drives, q, t, inputs, limit, size)
            .map_err(|st| stalled(sys, &st, &drives, q, t, inputs, limit))?;
        // 3. Orientation conditions of the assembled mechanism (checked along the way too).
        if let Some(v) = orientation::violation(sys, &done, q, t, inputs) {
            return Err(at_element(&done[v.index], format!("cannot be assembled: {}", v.msg)));
        }
        continuation::wind(sys, &done, &drives);
    }
    Ok(Assembly { drawn, drawing_unmet })
}

/// The model's size: the diagonal of the box around the bodies' origins and the ground
/// origin, at least 1 m.
fn model_size(sys: &System, q: &[f64]) -> f64 {
    let (mut lo, mut hi) = ([0.0f64; 3], [0.0f64; 3]);
    for b in 0..sys.nb() {
        for k in 0..3 {
            lo[k] = lo[k].min(q[NQ * b + k]);
            hi[k] = hi[k].max(q[NQ * b + k]);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt().max(1.0)
}

/// The error of a failed Newton solve of `els` (step 1), at the element of the worst row.
fn failure(sys: &System, els: &[ConstraintEl], q: &[f64], t: f64, inputs: &[f64], limit: f64, f: Failure) -> InitError {
    match f {
        Failure::NotFinite { row } => at_row(els, row, "cannot be assembled: its equations are not finite".into()),
        Failure::Singular { row, residual } => {
            let unmet = unmet(sys, els, q, t, inputs, limit);
            at_row(
                els,
                row,
                format!(
                    "cannot be assembled: the constraint Jacobian is singular (redundant or conflicting \
                     constraints); worst residual {residual:.3e} is here; equations not met: {unmet}"
                ),
            )
        }
        Failure::NoConvergence { row, residual } => at_row(
            els,
            row,
            format!(
                "cannot be assembled: worst constraint residual {residual:.3e} after {MAX_ITERATIONS} iterations; \
                 equations not met: {}",
                unmet(sys, els, q, t, inputs, limit)
            ),
        ),
    }
}

/// The error of a way that stalled (step 2), at the drive farthest from its target.
fn stalled(
    sys: &System,
    st: &continuation::Stalled,
    drives: &[Drive],
    q: &[f64],
    t: f64,
    inputs: &[f64],
    limit: f64,
) -> InitError {
    let remaining = |d: &Drive| (1.0 - st.reached) * (d.end - d.start).abs();
    let d = drives.iter().max_by(|a, b| remaining(a).total_cmp(&remaining(b))).expect("a way has drives");
    let asked: Vec<String> = drives
        .iter()
        .map(|d| {
            let now = d.start + st.reached * (d.end - d.start);
            format!("{} '{}' {:.6} (reached {now:.6})", st.els[d.index].tag, st.els[d.index].name, d.target)
        })
        .collect();
    at_element(
        &st.els[d.index],
        format!(
            "cannot be assembled: the exact conditions cannot be reached from the drawn pose: the way there \
             stops at {:.1}% ({}); asked: {}; equations not met there: {}",
            100.0 * st.reached,
            st.why,
            asked.join(", "),
            unmet(sys, &st.els, q, t, inputs, limit)
        ),
    )
}

/// The elements of `els` not met at q (some |C_i| above `limit`) with their largest |C|,
/// worst first.
fn unmet_list<'a>(
    sys: &System,
    els: &'a [ConstraintEl],
    q: &[f64],
    t: f64,
    inputs: &[f64],
    limit: f64,
) -> Vec<(&'a ConstraintEl, f64)> {
    let c = constraint_rows(sys, els, q, t, inputs).c;
    let mut bad: Vec<(&ConstraintEl, f64)> = els
        .iter()
        .map(|e| (e, c[e.row..e.row + e.neq].iter().fold(0.0f64, |a, v| a.max(v.abs()))))
        .filter(|(_, r)| *r > limit || !r.is_finite())
        .collect();
    bad.sort_by(|a, b| b.1.total_cmp(&a.1));
    bad
}

/// The elements not met at q, in words, with, for two-marker elements, how far apart
/// their markers are in the model as written (its initial positions).
fn unmet(sys: &System, els: &[ConstraintEl], q: &[f64], t: f64, inputs: &[f64], limit: f64) -> String {
    use crate::mechanics::constraints::ConstraintKind;
    use crate::model::expr::{Expr, KinFn};
    let ids: Vec<usize> = (0..sys.nb()).collect();
    let zeros = vec![0.0; sys.n()];
    let ctx = LocalCtx::new(sys, &ids, &sys.q_init, &zeros, &zeros, t, inputs);
    unmet_list(sys, els, q, t, inputs, limit)
        .iter()
        .map(|(e, r)| {
            let markers = match &e.kind {
                ConstraintKind::Joint { i, j, .. }
                | ConstraintKind::Rotation { i, j, .. }
                | ConstraintKind::Translation { i, j, .. } => Some((*i, *j)),
                _ => None,
            };
            let gap = markers
                .map(|(i, j)| ctx.eval_expr(&Expr::Kin(KinFn::Dm, i, Some(j), None), 0))
                .filter(|d: &f64| d.is_finite())
                .map_or(String::new(), |d| format!(", markers {d:.3e} m apart as written"));
            format!("{} '{}' (residual {r:.3e}{gap})", e.tag, e.name)
        })
        .collect::<Vec<_>>()
        .join(", ")
}
