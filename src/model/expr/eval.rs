//! Evaluation of an [`Expr`], generic over the scalar: with dual numbers the result
//! carries exact derivatives with respect to whatever the environment seeded.

use super::ast::{BinOp, Expr, KinFn, MarkerId, MathFn};
use super::env::{ExprEnv, Pose, Twist};
use crate::ad::Real;
use crate::geom::{M3, V3, euler313_from_matrix, ypr_from_matrix};

/// Evaluate `e` in `env`.
///
/// Markers `j`, `k` that are `None` stand for the ground frame (origin 0, axes = identity,
/// at rest). Division by zero and domain errors give inf/NaN; the caller checks
/// finiteness. Angle measures pass through [`ExprEnv::unwrap_angle`] with `slot` = the
/// ordinal (from 0) of the angle node in the expression's depth-first, left-to-right order
/// (see [`angle_count`]).
pub fn eval<T: Real, E: ExprEnv<T> + ?Sized>(e: &Expr, env: &E) -> T {
    let mut slot = 0;
    ev(e, env, &mut slot)
}

/// Number of angle measures (`ax ay az psi theta phi yaw pitch roll`) in `e`: the
/// unwrapping slots `0..angle_count(e)` that [`eval`] uses.
pub fn angle_count(e: &Expr) -> usize {
    match e {
        Expr::Kin(f, ..) => usize::from(f.is_angle()),
        Expr::Neg(a) => angle_count(a),
        Expr::Bin(_, a, b) => angle_count(a) + angle_count(b),
        Expr::Math(_, args) => args.iter().map(angle_count).sum(),
        _ => 0,
    }
}

fn ev<T: Real, E: ExprEnv<T> + ?Sized>(e: &Expr, env: &E, slot: &mut usize) -> T {
    match e {
        Expr::Num(v) => T::cst(*v),
        Expr::Time => env.time(),
        Expr::Param(i) => env.param(*i),
        Expr::Input(i) => env.input(*i),
        Expr::Variable(i) => env.variable(*i),
        Expr::Diff(i) => env.diff(*i),
        Expr::DiffDot(i) => env.diff_dot(*i),
        Expr::Neg(a) => -ev(a, env, slot),
        Expr::Bin(op, a, b) => {
            let (a, b) = (ev(a, env, slot), ev(b, env, slot));
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => a.pow(b),
            }
        }
        Expr::Math(f, args) => math(*f, args, env, slot),
        Expr::Kin(f, i, j, k) => {
            let v = kin(*f, *i, *j, *k, env);
            if f.is_angle() {
                let s = *slot;
                *slot += 1;
                env.unwrap_angle(s, v)
            } else {
                v
            }
        }
        Expr::Load(f, el) => env.load(*f, *el),
        Expr::Modal(f, m, k) => env.modal(*f, *m, *k),
    }
}

/// A math function of its argument expressions. Every argument is evaluated (also the
/// branch `if` does not take) so that angle slots do not depend on the branch; a missing
/// argument (impossible for parsed expressions) reads as NaN.
fn math<T: Real, E: ExprEnv<T> + ?Sized>(f: MathFn, args: &[Expr], env: &E, slot: &mut usize) -> T {
    let mut arg = |n: usize| args.get(n).map_or(T::cst(f64::NAN), |a| ev(a, env, slot));
    let a = arg(0);
    match f {
        MathFn::Sin => a.sin(),
        MathFn::Cos => a.cos(),
        MathFn::Tan => a.tan(),
        MathFn::Asin => a.asin(),
        MathFn::Acos => a.acos(),
        MathFn::Atan => a.atan(),
        MathFn::Atan2 => a.atan2(arg(1)),
        MathFn::Sinh => a.sinh(),
        MathFn::Cosh => a.cosh(),
        MathFn::Tanh => a.tanh(),
        MathFn::Exp => a.exp(),
        MathFn::Log => a.ln(),
        MathFn::Sqrt => a.sqrt(),
        MathFn::Abs => a.abs(),
        MathFn::Sign => {
            let v = a.val();
            T::cst(if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            })
        }
        MathFn::Min => {
            let b = arg(1);
            if a.val() <= b.val() { a } else { b }
        }
        MathFn::Max => {
            let b = arg(1);
            if a.val() >= b.val() { a } else { b }
        }
        MathFn::Step => {
            let (x, x0, h0, x1, h1) = (a, arg(1), arg(2), arg(3), arg(4));
            if x.val() <= x0.val() {
                h0
            } else if x.val() >= x1.val() {
                h1
            } else {
                let s = (x - x0) / (x1 - x0);
                h0 + (h1 - h0) * s * s * (T::cst(3.0) - s.scale(2.0))
            }
        }
        MathFn::If => {
            let (b, c) = (arg(1), arg(2));
            if a.val() > 0.0 { b } else { c }
        }
    }
}

fn ground_pose<T: Real>() -> Pose<T> {
    Pose { p: V3::zero(), r: M3::identity() }
}

fn at_rest<T: Real>() -> Twist<T> {
    Twist { v: V3::zero(), w: V3::zero() }
}

fn pose_of<T: Real, E: ExprEnv<T> + ?Sized>(m: Option<MarkerId>, env: &E) -> Pose<T> {
    m.map_or_else(ground_pose, |m| env.pose(m))
}

fn twist_of<T: Real, E: ExprEnv<T> + ?Sized>(m: Option<MarkerId>, env: &E) -> Twist<T> {
    m.map_or_else(at_rest, |m| env.twist(m))
}

fn accel_of<T: Real, E: ExprEnv<T> + ?Sized>(m: Option<MarkerId>, env: &E) -> Twist<T> {
    m.map_or_else(at_rest, |m| env.accel(m))
}

/// Components of ground vector `u` in the axes of marker `k` (ground if `None`).
fn in_frame<T: Real, E: ExprEnv<T> + ?Sized>(u: V3<T>, k: Option<MarkerId>, env: &E) -> V3<T> {
    match k {
        None => u,
        Some(k) => env.pose(k).r.tv(&u),
    }
}

/// A kinematic measure of marker `i` relative to `j`, components in `k`. Only the
/// environment data the measure's level needs is requested.
fn kin<T: Real, E: ExprEnv<T> + ?Sized>(f: KinFn, i: MarkerId, j: Option<MarkerId>, k: Option<MarkerId>, env: &E) -> T {
    use KinFn::*;
    let comp = |c: usize, u: V3<T>| in_frame(u, k, env).at(c);
    match f {
        Dx | Dy | Dz | Dm => {
            let d = env.pose(i).p - pose_of(j, env).p;
            match f {
                Dx => comp(0, d),
                Dy => comp(1, d),
                Dz => comp(2, d),
                _ => d.norm(),
            }
        }
        Vx | Vy | Vz | Vm => {
            let v = env.twist(i).v - twist_of(j, env).v;
            match f {
                Vx => comp(0, v),
                Vy => comp(1, v),
                Vz => comp(2, v),
                _ => v.norm(),
            }
        }
        Vr => {
            let d = env.pose(i).p - pose_of(j, env).p;
            let v = env.twist(i).v - twist_of(j, env).v;
            v.dot(&d) / d.norm()
        }
        Wx | Wy | Wz | Wm => {
            let w = env.twist(i).w - twist_of(j, env).w;
            match f {
                Wx => comp(0, w),
                Wy => comp(1, w),
                Wz => comp(2, w),
                _ => w.norm(),
            }
        }
        Accx | Accy | Accz => {
            let a = env.accel(i).v - accel_of(j, env).v;
            comp(axis(f), a)
        }
        Wdtx | Wdty | Wdtz => {
            let a = env.accel(i).w - accel_of(j, env).w;
            comp(axis(f), a)
        }
        Ax | Ay | Az => {
            let (ri, rj) = (env.pose(i).r, pose_of(j, env).r);
            // Rotation about j's axis n of i's axis a: atan2(a_i·b_j, a_i·a_j) with
            // (n, a, b) cyclic: ax (x, y, z), ay (y, z, x), az (z, x, y).
            let (a, b) = match f {
                Ax => (1, 2),
                Ay => (2, 0),
                _ => (0, 1),
            };
            let ai = ri.col(a);
            ai.dot(&rj.col(b)).atan2(ai.dot(&rj.col(a)))
        }
        Psi | Theta | Phi | Yaw | Pitch | Roll => {
            let rel = pose_of(j, env).r.t().mm(&env.pose(i).r);
            let angles = match f {
                Psi | Theta | Phi => euler313_from_matrix(&rel),
                _ => ypr_from_matrix(&rel),
            };
            angles[axis(f)]
        }
    }
}

/// Which component (or which of three angles) a measure picks.
fn axis(f: KinFn) -> usize {
    use KinFn::*;
    match f {
        Accx | Wdtx | Psi | Yaw => 0,
        Accy | Wdty | Theta | Pitch => 1,
        _ => 2,
    }
}
