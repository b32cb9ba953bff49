//! Holonomic constraint elements C(q, t) = 0 (Eq. 1a): joints, motions, user constraints,
//! and the exact joint initial conditions used during assembly.

use super::local::LocalCtx;
use crate::ad::Real;
use crate::model::expr::{Expr, ExprEnv, MarkerId};
use crate::model::{JointType, SrcPos};

/// What a constraint element constrains.
#[derive(Clone, Debug)]
pub enum ConstraintKind {
    /// A joint between markers i and j (equations in the model format's table).
    Joint { kind: JointType, i: MarkerId, j: MarkerId },
    /// Relative rotation of i about z_j equals f(t): x_i·y_j cos f − x_i·x_j sin f = 0.
    Rotation { i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// Displacement of i along z_j equals f(t): (p_i − p_j)·z_j − f = 0.
    Translation { i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// User constraint f(q, t) = 0.
    User { f: Expr, abase: usize },
    /// A rolling wheel's contact point stays on its plane: (P − o)·n = 0.
    WheelContact { m: MarkerId, radius: f64, plane: Option<MarkerId> },
}

/// One constraint element: its equations occupy rows `row..row+neq` of C.
#[derive(Clone, Debug)]
pub struct ConstraintEl {
    pub name: String,
    pub kind: ConstraintKind,
    /// Bodies whose coordinates the equations depend on (global indices).
    pub bodies: Vec<usize>,
    pub neq: usize,
    pub row: usize,
    /// The model element it comes from (tag and position), for located messages.
    pub tag: &'static str,
    pub pos: SrcPos,
}

impl ConstraintEl {
    /// An element from model element `tag` at `pos`; its rows are laid out later.
    pub fn new(name: String, kind: ConstraintKind, bodies: Vec<usize>, tag: &'static str, pos: SrcPos) -> Self {
        let neq = kind.neq();
        ConstraintEl { name, kind, bodies, neq, row: 0, tag, pos }
    }
}

impl ConstraintKind {
    /// Number of equations.
    pub fn neq(&self) -> usize {
        match self {
            ConstraintKind::Joint { kind, .. } => kind.equations(),
            _ => 1,
        }
    }

    /// Evaluate the equations into `out` (length `neq`).
    pub fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        match self {
            ConstraintKind::Joint { kind, i, j } => joint_equations(*kind, ctx, *i, *j, out),
            ConstraintKind::Rotation { i, j, f, abase } => {
                let (pi, pj) = (ctx.pose(*i), ctx.pose(*j));
                let xi = pi.r.col(0);
                let fv: T = ctx.eval_expr(f, *abase);
                out[0] = xi.dot(&pj.r.col(1)) * fv.cos() - xi.dot(&pj.r.col(0)) * fv.sin();
            }
            ConstraintKind::Translation { i, j, f, abase } => {
                let (pi, pj) = (ctx.pose(*i), ctx.pose(*j));
                let fv: T = ctx.eval_expr(f, *abase);
                out[0] = (pi.p - pj.p).dot(&pj.r.col(2)) - fv;
            }
            ConstraintKind::User { f, abase } => out[0] = ctx.eval_expr(f, *abase),
            ConstraintKind::WheelContact { m, radius, plane } => {
                let (pc, n, o, _) = super::nonholonomic::wheel_contact(ctx, *m, *radius, *plane);
                out[0] = (pc - o).dot(&n);
            }
        }
    }
}

/// Joint equations (Adams-style definitions, MODEL_FORMAT.md table).
fn joint_equations<T: Real>(kind: JointType, ctx: &LocalCtx<T>, i: MarkerId, j: MarkerId, out: &mut [T]) {
    let (a, b) = (ctx.pose(i), ctx.pose(j));
    let d = a.p - b.p;
    let (xi, yi, zi) = (a.r.col(0), a.r.col(1), a.r.col(2));
    let _ = yi;
    let (xj, yj, zj) = (b.r.col(0), b.r.col(1), b.r.col(2));
    let rows: Vec<T> = match kind {
        JointType::Fixed => vec![d.0[0], d.0[1], d.0[2], zi.dot(&xj), zi.dot(&yj), xi.dot(&yj)],
        JointType::Revolute => vec![d.0[0], d.0[1], d.0[2], zi.dot(&xj), zi.dot(&yj)],
        JointType::Translational => vec![zi.dot(&xj), zi.dot(&yj), xi.dot(&yj), d.dot(&xj), d.dot(&yj)],
        JointType::Cylindrical => vec![zi.dot(&xj), zi.dot(&yj), d.dot(&xj), d.dot(&yj)],
        JointType::Universal => vec![d.0[0], d.0[1], d.0[2], zi.dot(&zj)],
        JointType::Spherical => vec![d.0[0], d.0[1], d.0[2]],
        JointType::Planar => vec![zi.dot(&xj), zi.dot(&yj), d.dot(&zj)],
    };
    out.copy_from_slice(&rows);
}

/// A velocity-level initial condition (exact `ic_angular_speed` / `ic_speed`), linear in u.
#[derive(Clone, Debug)]
pub struct VelocityIc {
    pub name: String,
    /// Relative angular velocity about z_j (true) or relative velocity along z_j (false).
    pub angular: bool,
    pub i: MarkerId,
    pub j: MarkerId,
    pub value: f64,
    pub bodies: Vec<usize>,
}

impl VelocityIc {
    /// Residual (ω_i − ω_j)·z_j − value, or (v_i − v_j)·z_j − value.
    pub fn eval<T: Real>(&self, ctx: &LocalCtx<T>) -> T {
        let zj = ctx.pose(self.j).r.col(2);
        let (a, b) = (ctx.twist(self.i), ctx.twist(self.j));
        let rel = if self.angular { a.w - b.w } else { a.v - b.v };
        rel.dot(&zj) - T::cst(self.value)
    }
}
