//! The equations of the holonomic constraint elements (Eq. 1a) and of the velocity
//! initial conditions, evaluated in an element context.

use super::constraints::{ConstraintKind, VelocityIc, VelocityIcKind};
use super::local::LocalCtx;
use super::measures::StateKind;
use super::nonholonomic_equations::wheel_contact;
use crate::ad::Real;
use crate::model::JointType;
use crate::model::expr::{ExprEnv, MarkerId};

impl ConstraintKind {
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
                let (pc, n, o, _) = wheel_contact(ctx, *m, *radius, *plane);
                out[0] = (pc - o).dot(&n);
            }
            ConstraintKind::State { kind, value } => {
                let d = kind.eval(ctx) - T::cst(*value);
                out[0] = match kind {
                    // A body's 3-1-3 angle reads in (−π, π]: the state's value is met on
                    // any branch (whole turns off the residual), so a spin state runs
                    // past ±π without a jump.
                    StateKind::Angle { .. } => {
                        let turn = 2.0 * std::f64::consts::PI;
                        d - T::cst(turn * (d.val() / turn).round())
                    }
                    _ => d,
                };
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

impl VelocityIc {
    /// Residual (ω_i − ω_j)·z_j − value, (v_i − v_j)·z_j − value, or w(q, u, t) − value.
    /// A [`VelocityIcKind::Rate`] has no such form here (it reads as NaN): its row comes
    /// from the measure's gradient (`dae::init::velocities`).
    pub fn eval<T: Real>(&self, ctx: &LocalCtx<T>) -> T {
        let rel = match &self.kind {
            VelocityIcKind::Joint { angular, i, j } => {
                let zj = ctx.pose(*j).r.col(2);
                let (a, b) = (ctx.twist(*i), ctx.twist(*j));
                let rel = if *angular { a.w - b.w } else { a.v - b.v };
                rel.dot(&zj)
            }
            VelocityIcKind::User { f, abase } => ctx.eval_expr(f, *abase),
            VelocityIcKind::Rate(_) => T::cst(f64::NAN),
        };
        rel - T::cst(self.value)
    }
}
