//! The force laws: loads and generalized forces of the force elements (Eq. 1d / 13a),
//! evaluated in an element context.

use super::coords::local_modal_range;
use super::forces::{ForceEl, ForceKind, Load};
use super::local::LocalCtx;
use crate::ad::Real;
use crate::geom::V3;
use crate::model::SpringType;
use crate::model::expr::{ExprEnv, MarkerId};

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

    /// Force and torque on the i marker (ground components, torque about the i origin);
    /// the reaction on j is their opposite (see [`ForceEl::generalized`]).
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

    /// Generalized forces on the context's bodies, accumulated into `q` (local coordinates:
    /// 6 per body, then the modal ones of the flexible bodies; see [`super::coords`]).
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

/// Add force `f` at ground point `p` and torque `t` to the body of marker `m` (if any),
/// by virtual work: the six rigid rows, and, for a marker on a flexible body's node, the
/// modal rows. The point p moves with the node: δx_p = δx_n + δθ_n × (p − x_n), with
/// δx_n = A φ_k δη_k and δθ_n = A ρ_k δη_k from mode k, so
/// Q_ηk = φ_k·(Aᵀ f) + ρ_k·(Aᵀ (t + (p − x_n) × f)).
fn apply<T: Real>(ctx: &LocalCtx<T>, m: MarkerId, p: V3<T>, f: V3<T>, t: V3<T>, q: &mut [T]) {
    let Some(b) = ctx.sys.markers[m].body else { return };
    let k = ctx.local(b);
    let body = &ctx.bodies[k];
    let tq = body.a.tv(&((p - body.r).cross(&f) + t));
    for c in 0..3 {
        q[6 * k + c] += f.0[c];
        q[6 * k + 3 + c] += tq.0[c];
    }
    if let Some(shape) = &ctx.sys.markers[m].node {
        let fb = body.a.tv(&f);
        let tb = body.a.tv(&(t + (p - ctx.pose(m).p).cross(&f)));
        let rows = local_modal_range(ctx.sys, ctx.ids, k);
        for ((r, phi), rho) in rows.zip(&shape.phi).zip(&shape.rho) {
            q[r] += fb.dot(&V3::cst(*phi)) + tb.dot(&V3::cst(*rho));
        }
    }
}
