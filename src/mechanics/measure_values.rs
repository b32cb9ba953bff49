//! The value of a [`StateKind`] measure in an element context.

use super::local::LocalCtx;
use super::measures::StateKind;
use crate::ad::Real;
use crate::geom::{M3, euler313_from_matrix};

impl StateKind {
    /// The measure in an element context whose bodies are the state's (a body
    /// coordinate's context holds that one body).
    pub fn eval<T: Real>(&self, ctx: &LocalCtx<T>) -> T {
        match self {
            StateKind::User { f, abase } | StateKind::Joint { f, abase, .. } => ctx.eval_expr(f, *abase),
            StateKind::Position { k } => ctx.bodies[0].r.0[*k],
            StateKind::Modal { k } => ctx.modal_coordinate(0, *k),
            StateKind::Angle { k, r0 } => euler313_from_matrix(&M3::cst(r0).t().mm(&ctx.bodies[0].a))[*k],
        }
    }
}
