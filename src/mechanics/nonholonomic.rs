//! Non-holonomic constraints g(q, u, t) = B(q, t) u + b(q, t) = 0 (seed remark (1) after
//! Eq. 13: the strictly non-holonomic part of C̃): knife edges, the rolling part of rolling
//! wheels, and user velocity constraints. Their multipliers ν enter the equations of motion
//! as Bᵀν (B = ∂g/∂u).

use super::local::LocalCtx;
use crate::ad::Real;
use crate::geom::V3;
use crate::model::SrcPos;
use crate::model::expr::{Expr, ExprEnv, MarkerId};

/// What a non-holonomic element constrains.
#[derive(Clone, Debug)]
pub enum NonholonomicKind {
    /// No velocity of the marker origin along the marker's y axis.
    KnifeEdge { m: MarkerId },
    /// The wheel's material point at the contact has no velocity in the plane (2 rows:
    /// along the rolling direction a × n and across it).
    Rolling { m: MarkerId, radius: f64, plane: Option<MarkerId> },
    /// User expression f(q, u, t) = 0.
    User { f: Expr, abase: usize },
}

/// One non-holonomic element: rows `row..row+neq` of g.
#[derive(Clone, Debug)]
pub struct NonholonomicEl {
    pub name: String,
    pub kind: NonholonomicKind,
    pub bodies: Vec<usize>,
    pub neq: usize,
    pub row: usize,
    pub tag: &'static str,
    pub pos: SrcPos,
}

impl NonholonomicEl {
    /// An element from model element `tag` at `pos`; its rows are laid out later.
    pub fn new(name: String, kind: NonholonomicKind, bodies: Vec<usize>, tag: &'static str, pos: SrcPos) -> Self {
        let neq = if matches!(kind, NonholonomicKind::Rolling { .. }) { 2 } else { 1 };
        NonholonomicEl { name, kind, bodies, neq, row: 0, tag, pos }
    }
}

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
