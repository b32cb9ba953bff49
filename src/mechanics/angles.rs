//! What changes as the mechanism moves, apart from its coordinates: the Euler-angle
//! reference frames R0 (re-based away from the 3-1-3 singularity) and the branches of
//! the angle measures (unwrapped continuously). The integrator updates them after each
//! accepted step, assembly after each step of its continuation path. Rotational springs'
//! own branches (`ForceEl::angle_ref`) are recorded with the rest.

use super::body::{FAR_FROM_SINGULAR, NQ, rebased_reference};
use super::coords::{gather, rates};
use super::local::LocalCtx;
use super::system::System;
use crate::ad::{Dual, Real};
use crate::geom::{M3, rot313};

/// A body is re-based when |sin θ| falls below this (its 3-1-3 angles near singular).
const REBASE_SIN_THETA: f64 = 0.3;

impl System {
    /// Re-base the reference frame R0 of every body whose angles in `q` are near the
    /// 3-1-3 singularity or past ±π, so that its orientation reads
    /// [`FAR_FROM_SINGULAR`]; the pose is unchanged. Returns whether any body changed.
    pub fn rebase_frames(&mut self, q: &mut [f64]) -> bool {
        let mut changed = false;
        for b in 0..self.nb() {
            let o = NQ * b;
            let (psi, th, phi) = (q[o + 3], q[o + 4], q[o + 5]);
            let near_singular = th.sin().abs() < REBASE_SIN_THETA;
            let wrapped = psi.abs() > std::f64::consts::PI || phi.abs() > std::f64::consts::PI;
            if near_singular || wrapped {
                let a = M3::cst(&self.r0[b]).mm(&rot313(psi, th, phi)).val();
                self.r0[b] = rebased_reference(&a);
                q[o + 3..o + 6].copy_from_slice(&FAR_FROM_SINGULAR);
                changed = true;
            }
        }
        changed
    }

    /// Store the current value and rate of every angle measure at (t, q, u), so that
    /// expressions stay on its branch. Rates come from one evaluation with scalars seeded
    /// along the motion (q̇ = H(q) u, ṫ = 1; angle measures depend on positions only);
    /// `ext` holds the external values (a shorter slice reads the rest as NaN).
    pub fn record_angles(&mut self, t: f64, q: &[f64], u: &[f64], ext: &[f64]) {
        if self.angle_refs.is_empty() {
            return;
        }
        let rec = std::cell::RefCell::new(Vec::new());
        {
            let sys = &*self;
            let ids: Vec<usize> = (0..sys.nb()).collect();
            type D1 = Dual<f64, 1>;
            let rates = rates(sys.nb(), q, u);
            let qd: Vec<D1> = q.iter().zip(rates).map(|(&v, d)| D1 { v, d: [d] }).collect();
            let ud: Vec<D1> = u.iter().map(|&v| D1::cst(v)).collect();
            let mut ctx = LocalCtx::new(sys, &ids, &qd, &ud, &[], D1 { v: t, d: [1.0] }, ext);
            ctx.record = Some(&rec);
            for ue in &sys.user {
                ue.residual(&ctx);
            }
            for el in &sys.constraints {
                let mut out = vec![D1::zero(); el.neq];
                el.kind.eval(&ctx, &mut out);
            }
            for el in &sys.forces {
                el.load(&ctx);
            }
            for (e, &b) in sys.outputs.iter().zip(&sys.output_bases) {
                ctx.eval_expr(e, b);
            }
            for (_, e, b) in sys.lin_states.iter().chain(&sys.lin_velocities) {
                ctx.eval_expr(e, *b);
            }
            for c in &sys.joint_coords {
                ctx.eval_expr(&c.f, c.abase);
            }
            for el in &sys.nonholonomic {
                let mut out = vec![D1::zero(); el.neq];
                el.kind.eval(&ctx, &mut out);
            }
        }
        for (g, v, rate) in rec.into_inner() {
            // A measure that could not be evaluated (it reads a value not given) keeps its branch.
            if v.is_finite() {
                self.angle_refs[g] = v;
                self.angle_rates[g] = if rate.is_finite() { rate } else { 0.0 };
            }
        }
        self.angle_time = t;
        // Rotational springs keep their own branch (their unwrapped az).
        for k in 0..self.forces.len() {
            let el = &self.forces[k];
            let ql = gather(self, &el.bodies, q);
            let ctx = LocalCtx::new(self, &el.bodies, &ql, &[], &[], t, ext);
            if let Some(a) = el.angle(&ctx).filter(|a| a.is_finite()) {
                self.forces[k].angle_ref = a;
            }
        }
    }
}
