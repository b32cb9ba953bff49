//! The equations g of the non-holonomic elements, evaluated in an element context, and
//! the wheel contact geometry that rolling wheels share with their holonomic part.

use super::local::LocalCtx;
use super::nonholonomic::NonholonomicKind;
use crate::ad::Real;
use crate::geom::V3;
use crate::model::expr::{ExprEnv, MarkerId};

/// Contact geometry of a wheel (centre c, axle a) on a plane (origin o, normal n):
/// returns (contact point P = c − r p/|p| with p = n − (n·a)a, n, o, a).
pub fn wheel_contact<T: Real>(
    ctx: &LocalCtx<T>,
    m: MarkerId,
    radius: f64,
    plane: Option<MarkerId>,
) -> (V3<T>, V3<T>, V3<T>, V3<T>) {
    let w = ctx.pose(m);
    let (c, a) = (w.p, w.r.col(2));
    let (o, n) = match plane {
        Some(pm) => {
            let p = ctx.pose(pm);
            (p.p, p.r.col(2))
        }
        None => (V3::zero(), V3([T::zero(), T::zero(), T::one()])),
    };
    let p = n - a.mul_s(n.dot(&a));
    let contact = c - p.mul_s(T::cst(radius) / p.norm());
    (contact, n, o, a)
}

impl NonholonomicKind {
    /// Evaluate g into `out` (length neq).
    pub fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        match self {
            NonholonomicKind::KnifeEdge { m } => {
                out[0] = ctx.twist(*m).v.dot(&ctx.pose(*m).r.col(1));
            }
            NonholonomicKind::Rolling { m, radius, plane } => {
                let (pc, n, o, a) = wheel_contact(ctx, *m, *radius, *plane);
                let tw = ctx.twist(*m);
                let mut v = tw.v + tw.w.cross(&(pc - ctx.pose(*m).p));
                if let Some(pm) = plane {
                    let tp = ctx.twist(*pm);
                    v = v - (tp.v + tp.w.cross(&(pc - o)));
                }
                let t1 = a.cross(&n);
                let t1 = t1.mul_s(T::one() / t1.norm());
                let t2 = n.cross(&t1);
                out[0] = v.dot(&t1);
                out[1] = v.dot(&t2);
            }
            NonholonomicKind::User { f, abase } => out[0] = ctx.eval_expr(f, *abase),
        }
    }
}
