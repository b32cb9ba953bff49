//! Residuals of the user rows (seed Eq. 7a–7b) in an element context.

use super::local::LocalCtx;
use super::user::{UserEq, UserKind};
use crate::ad::Real;

impl UserEq {
    /// The residual r (zero on the solution).
    pub fn residual<T: Real>(&self, ctx: &LocalCtx<T>) -> T {
        let f = ctx.eval_expr(&self.f, self.abase);
        match self.kind {
            UserKind::Explicit => f - ctx.ext_value(self.own),
            UserKind::Implicit => f,
            UserKind::Variable => f - ctx.ext_value(self.own),
        }
    }
}
