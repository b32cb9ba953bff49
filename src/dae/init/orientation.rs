//! The orientation conditions that joint equations written with dot products cannot
//! tell apart: z_i·x_j = z_i·y_j = 0 holds with z_i = z_j and with z_i = −z_j alike, and
//! x_i·y_j cos f − x_i·x_j sin f = 0 holds at the angle f and at f + π. Assembly checks
//! them after each step: a joint's markers agree with its definition (MODEL_FORMAT
//! "Joints": z_i ∥ z_j pointing the same way, x_i too where the joint fixes it), and an
//! exact angle is met on its own branch.

use crate::mechanics::System;
use crate::mechanics::constraints::{ConstraintEl, ConstraintKind};
use crate::mechanics::coords::gather;
use crate::mechanics::local::LocalCtx;
use crate::model::JointType;
use crate::model::expr::{Expr, ExprEnv};

/// What is wrong with element `els[index]`'s orientation at q.
pub(super) struct Violation {
    /// Index of the element in the list checked.
    pub index: usize,
    /// What is wrong, in words (with the offending dot product).
    pub msg: String,
}

/// The first element of `els` whose markers violate their orientation condition at q
/// (None: all hold). Exact angles are checked at their value in `els` (a number).
pub(super) fn violation(sys: &System, els: &[ConstraintEl], q: &[f64], t: f64, inputs: &[f64]) -> Option<Violation> {
    els.iter().enumerate().find_map(|(index, el)| {
        let ql = gather(sys, &el.bodies, q);
        let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], t, inputs);
        check(&ctx, &el.kind).map(|msg| Violation { index, msg })
    })
}

/// The orientation condition of one element, None when it holds.
fn check(ctx: &LocalCtx<f64>, kind: &ConstraintKind) -> Option<String> {
    match kind {
        ConstraintKind::Joint { kind, i, j } => {
            let (a, b) = (ctx.pose(*i).r, ctx.pose(*j).r);
            let (zz, xx) = (a.col(2).dot(&b.col(2)), a.col(0).dot(&b.col(0)));
            let z_parallel = !matches!(kind, JointType::Universal | JointType::Spherical);
            let x_parallel = matches!(kind, JointType::Fixed | JointType::Translational);
            if z_parallel && zz <= 0.0 {
                Some(format!(
                    "its markers' z axes point opposite ways (z_i·z_j = {zz:.3}): the joint would be put \
                     together inside out"
                ))
            } else if x_parallel && xx <= 0.0 {
                Some(format!(
                    "its markers' x axes point opposite ways (x_i·x_j = {xx:.3}): the joint would be put \
                     together turned by half a turn about z"
                ))
            } else {
                None
            }
        }
        ConstraintKind::Rotation { i, j, f: Expr::Num(f), .. } => {
            let (a, b) = (ctx.pose(*i).r, ctx.pose(*j).r);
            let xi = a.col(0);
            let along = xi.dot(&b.col(0)) * f.cos() + xi.dot(&b.col(1)) * f.sin();
            (along <= 0.0)
                .then(|| format!("the angle reached is {f} + π, not {f} (x_i·(x_j cos f + y_j sin f) = {along:.3})"))
        }
        _ => None,
    }
}
