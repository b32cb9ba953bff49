//! Applied forces Q(u, q, t) (Eq. 1d / 13a), as generalized forces conjugate to
//! u_b = [v; ω']: a force F at ground point p on body b adds F to Q_v and
//! Aᵀ((p − r) × F) to Q_ω'; a torque τ adds Aᵀτ.

use super::local::LocalCtx;
use crate::ad::Real;
use crate::geom::V3;
use crate::model::SpringType;
use crate::model::expr::{Expr, ExprEnv, MarkerId};

/// What a force element is.
#[derive(Clone, Debug)]
pub enum ForceKind {
    /// Translational (along the line of sight) or rotational (about z_j) spring-damper.
    SpringDamper { kind: SpringType, i: MarkerId, j: MarkerId, k: f64, c: f64, length: f64, preload: f64 },
    /// Single-component force of an expression.
    Sforce { kind: SpringType, i: MarkerId, j: MarkerId, f: Expr, abase: usize },
    /// General force/torque at i in `frame` axes, reaction on j.
    Gforce {
        i: MarkerId,
        j: Option<MarkerId>,
        frame: Option<MarkerId>,
        force: Box<[Expr; 3]>,
        torque: Box<[Expr; 3]>,
        abase: [usize; 6],
    },
    /// Linear six-component spring-damper in marker j's axes: translation of i's origin
    /// relative to j's, small-angle rotation vector of i relative to j, and their rates.
    Bushing { i: MarkerId, j: MarkerId, k: [f64; 6], c: [f64; 6] },
}

/// A force element and the bodies its value depends on or acts on.
#[derive(Clone, Debug)]
pub struct ForceEl {
    pub name: String,
    pub kind: ForceKind,
    pub bodies: Vec<usize>,
    /// Entries of the external values (inputs, user unknowns) its expressions read.
    pub ext_refs: Vec<usize>,
    /// Reference for unwrapping the rotational angle az(i, j) (kept near it).
    pub angle_ref: f64,
}

/// Force and torque (ground) that an element applies on its i marker.
pub struct Load<T: Real> {
    pub force: V3<T>,
    pub torque: V3<T>,
}

impl ForceEl {
    /// az(i, j) unwrapped to the branch nearest `angle_ref`.
    fn unwrapped_az<T: Real>(&self, ctx: &LocalCtx<T>, i: MarkerId, j: MarkerId) -> T {
        let (a, b) = (ctx.pose(i), ctx.pose(j));
        let xi = a.r.col(0);
        let az = xi.dot(&b.r.col(1)).atan2(xi.dot(&b.r.col(0)));
        let two_pi = 2.0 * std::f64::consts::PI;
        az + T::cst(two_pi * ((self.angle_ref - az.val()) / two_pi).round())
    }

    /// Current value of the rotational angle (for updating `angle_ref`), if any.
    pub fn angle<T: Real>(&self, ctx: &LocalCtx<T>) -> Option<f64> {
        match &self.kind {
            ForceKind::SpringDamper { kind: SpringType::Rotational, i, j, .. } => {
                Some(self.unwrapped_az(ctx, *i, *j).val())
            }
            _ => None,
        }
    }

    /// Force/torque on the i marker (ground components, torque about the i origin) and
    /// the application points: returns (load on i, point i, reaction acts on j's body at point).
    pub fn load<T: Real>(&self, ctx: &LocalCtx<T>) -> Load<T> {
        match &self.kind {
            ForceKind::SpringDamper { kind, i, j, k, c, length, preload } => {
                let s = match kind {
                    SpringType::Translational => {
                        let (d, dd) = line_of_sight(ctx, *i, *j);
                        -T::cst(*k) * (d - T::cst(*length)) - T::cst(*c) * dd + T::cst(*preload)
                    }
                    SpringType::Rotational => {
                        let az = self.unwrapped_az(ctx, *i, *j);
                        let zj = ctx.pose(*j).r.col(2);
                        let wz = (ctx.twist(*i).w - ctx.twist(*j).w).dot(&zj);
                        -T::cst(*k) * (az - T::cst(*length)) - T::cst(*c) * wz + T::cst(*preload)
                    }
                };
                scalar_load(ctx, *kind, *i, *j, s)
            }
            ForceKind::Sforce { kind, i, j, f, abase } => {
                let s: T = ctx.eval_expr(f, *abase);
                scalar_load(ctx, *kind, *i, *j, s)
            }
            ForceKind::Gforce { frame, force, torque, abase, .. } => {
                let r = frame.map(|m| ctx.pose(m).r);
                let to_ground = |v: V3<T>| r.map_or(v, |r| r.mv(&v));
                let ev = |k: usize| -> T {
                    if k < 3 { ctx.eval_expr(&force[k], abase[k]) } else { ctx.eval_expr(&torque[k - 3], abase[k]) }
                };
                let f = to_ground(V3([ev(0), ev(1), ev(2)]));
                let t = to_ground(V3([ev(3), ev(4), ev(5)]));
                Load { force: f, torque: t }
            }
            ForceKind::Bushing { i, j, k, c } => bushing_load(ctx, *i, *j, k, c),
        }
    }

    /// Markers (i, j) between which the element acts.
    pub fn markers(&self) -> (MarkerId, Option<MarkerId>) {
        match &self.kind {
            ForceKind::SpringDamper { i, j, .. } | ForceKind::Sforce { i, j, .. } => (*i, Some(*j)),
            ForceKind::Gforce { i, j, .. } => (*i, *j),
            ForceKind::Bushing { i, j, .. } => (*i, Some(*j)),
        }
    }

    /// Generalized forces on the context's bodies, accumulated into `q` (6 per local body).
    pub fn generalized<T: Real>(&self, ctx: &LocalCtx<T>, q: &mut [T]) {
        let l = self.load(ctx);
        let (i, j) = self.markers();
        let pi = ctx.pose(i).p;
        apply(ctx, i, pi, l.force, l.torque, q);
        if let Some(j) = j {
            // Reaction: −F at the point of j's body instantaneously at p_i, −τ.
            apply(ctx, j, pi, -l.force, -l.torque, q);
        }
    }

    /// Potential energy stored in a spring (for energy checks), else 0.
    pub fn potential(&self, ctx: &LocalCtx<f64>) -> f64 {
        match &self.kind {
            ForceKind::SpringDamper { kind, i, j, k, length, preload, .. } => {
                let x = match kind {
                    SpringType::Translational => line_of_sight(ctx, *i, *j).0,
                    SpringType::Rotational => self.unwrapped_az(ctx, *i, *j),
                };
                0.5 * k * (x - length).powi(2) - preload * x
            }
            _ => 0.0,
        }
    }
}

/// Bushing load on i (ground axes): in j's axes F = −K d − C ḋ, τ = −K_r θ − C_r ω with
/// d = R_jᵀ(p_i − p_j), ḋ = R_jᵀ(ṗ_i − ṗ_j), θ = vee(skew(R_jᵀR_i)) (= the rotation vector
/// to first order) and ω = R_jᵀ(ω_i − ω_j).
fn bushing_load<T: Real>(ctx: &LocalCtx<T>, i: MarkerId, j: MarkerId, k: &[f64; 6], c: &[f64; 6]) -> Load<T> {
    let (pi, pj) = (ctx.pose(i), ctx.pose(j));
    let (ti, tj) = (ctx.twist(i), ctx.twist(j));
    let d = pj.r.tv(&(pi.p - pj.p));
    let dd = pj.r.tv(&(ti.v - tj.v));
    let r = pj.r.t().mm(&pi.r);
    let half = T::cst(0.5);
    let th = V3([(r.0[2][1] - r.0[1][2]) * half, (r.0[0][2] - r.0[2][0]) * half, (r.0[1][0] - r.0[0][1]) * half]);
    let w = pj.r.tv(&(ti.w - tj.w));
    let comp = |x: &V3<T>, xd: &V3<T>, o: usize| {
        V3(std::array::from_fn(|a| -T::cst(k[o + a]) * x.0[a] - T::cst(c[o + a]) * xd.0[a]))
    };
    Load { force: pj.r.mv(&comp(&d, &dd, 0)), torque: pj.r.mv(&comp(&th, &w, 3)) }
}

/// Distance |p_i − p_j| and its rate.
fn line_of_sight<T: Real>(ctx: &LocalCtx<T>, i: MarkerId, j: MarkerId) -> (T, T) {
    let d = ctx.pose(i).p - ctx.pose(j).p;
    let l = d.norm();
    let dv = ctx.twist(i).v - ctx.twist(j).v;
    (l, d.dot(&dv) / l)
}

/// A scalar along the line of sight (translational) or about z_j (rotational), on i.
fn scalar_load<T: Real>(ctx: &LocalCtx<T>, kind: SpringType, i: MarkerId, j: MarkerId, s: T) -> Load<T> {
    match kind {
        SpringType::Translational => {
            let d = ctx.pose(i).p - ctx.pose(j).p;
            let e = d.mul_s(T::one() / d.norm());
            Load { force: e.mul_s(s), torque: V3::zero() }
        }
        SpringType::Rotational => Load { force: V3::zero(), torque: ctx.pose(j).r.col(2).mul_s(s) },
    }
}

/// Add force `f` at ground point `p` and torque `t` to the body of marker `m` (if any).
fn apply<T: Real>(ctx: &LocalCtx<T>, m: MarkerId, p: V3<T>, f: V3<T>, t: V3<T>, q: &mut [T]) {
    let Some(b) = ctx.sys.markers[m].body else { return };
    let k = ctx.local(b);
    let body = &ctx.bodies[k];
    let tq = body.a.tv(&((p - body.r).cross(&f) + t));
    for c in 0..3 {
        q[6 * k + c] += f.0[c];
        q[6 * k + 3 + c] += tq.0[c];
    }
}
