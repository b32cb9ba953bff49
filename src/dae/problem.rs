//! The multibody DAE as the integrator sees it: residual, Jacobian, mass matrix and index
//! of each component, inputs interpolated over a step, and what happens after each
//! accepted step (re-based Euler frames, recorded angle branches).

use super::equations::{self, Layout};
use super::radau::DaeProblem;
use super::sparse::Triplets;
use crate::ad::Real;
use crate::geom::{M3, rot313};
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::local::LocalCtx;
use crate::mechanics::system::{FAR_FROM_SINGULAR, rebased_reference};

/// The multibody DAE handed to the integrator.
pub(super) struct MultibodyDae {
    /// The mechanical system (with its current Euler-angle reference frames).
    pub(super) sys: System,
    /// Where q, u, Z and the multipliers sit in y.
    pub(super) lay: Layout,
    /// Input values at time `t_in`, and their slopes (linear interpolation over a step).
    pub(super) inputs: Vec<f64>,
    pub(super) slopes: Vec<f64>,
    pub(super) t_in: f64,
}

impl DaeProblem for MultibodyDae {
    fn dim(&self) -> usize {
        self.lay.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), String> {
        equations::rhs(&self.sys, self.lay, t, y, &self.inputs_at(t), f);
        if f.iter().all(|v| v.is_finite()) { Ok(()) } else { Err("non-finite equations".into()) }
    }
    fn jacobian(&mut self, t: f64, y: &[f64], j: &mut Triplets) -> Result<(), String> {
        equations::jacobian(&self.sys, self.lay, t, y, &self.inputs_at(t), j);
        Ok(())
    }
    fn mass(&self, m: &mut Triplets) {
        equations::mass_matrix(&self.sys, self.lay, m);
    }
    fn index(&self) -> Vec<u8> {
        // q, u, X and the index-1 user unknowns (Ẋ, V): error-controlled; accelerations a
        // (solved with λ from the velocity constraints), λ, ν, μ: index 2.
        let a0 = self.lay.acc();
        (0..self.lay.dim()).map(|i| if i < a0 { 0 } else { 2 }).collect()
    }
    fn accepted(&mut self, t: f64, y: &mut [f64]) -> bool {
        let mut changed = false;
        for b in 0..self.sys.nb() {
            let o = NQ * b;
            let (th, psi, phi) = (y[o + 4], y[o + 3], y[o + 5]);
            let near_singular = th.sin().abs() < 0.3;
            let wrapped = psi.abs() > std::f64::consts::PI || phi.abs() > std::f64::consts::PI;
            if near_singular || wrapped {
                // Re-base: choose R0 so the body's current orientation has angles (0, π/2, 0).
                let a = M3::cst(&self.sys.r0[b]).mm(&rot313(psi, th, phi)).val();
                self.sys.r0[b] = rebased_reference(&a);
                y[o + 3..o + 6].copy_from_slice(&FAR_FROM_SINGULAR);
                changed = true;
            }
        }
        let (qs, us) = (self.lay.q_range(), self.lay.u_range());
        let ext = self.lay.ext(&self.sys, &self.inputs_at(t), y, t);
        self.record_angles(t, &y[qs.clone()], &y[us], &ext);
        let inputs = ext;
        for k in 0..self.sys.forces.len() {
            let el = &self.sys.forces[k];
            let ql = crate::mechanics::coords::gather(&self.sys, &el.bodies, &y[qs.clone()]);
            let ctx = LocalCtx::new(&self.sys, &el.bodies, &ql, &[], &[], t, &inputs);
            if let Some(a) = el.angle(&ctx) {
                self.sys.forces[k].angle_ref = a;
            }
        }
        changed
    }
}

impl MultibodyDae {
    /// Inputs at time t: held values plus slope · (t − t_in).
    pub(super) fn inputs_at(&self, t: f64) -> Vec<f64> {
        self.inputs.iter().zip(&self.slopes).map(|(v, s)| v + s * (t - self.t_in)).collect()
    }

    /// Store the current value and rate of every angle measure, so expressions stay on
    /// its branch. Rates come from one evaluation with scalars seeded along the motion
    /// (q̇ = H(q) u, ṫ = 1; angle measures depend on positions only).
    fn record_angles(&mut self, t: f64, q: &[f64], u: &[f64], inputs: &[f64]) {
        if self.sys.angle_refs.is_empty() {
            return;
        }
        let rec = std::cell::RefCell::new(Vec::new());
        {
            let sys = &self.sys;
            let ids: Vec<usize> = (0..sys.nb()).collect();
            type D1 = crate::ad::Dual<f64, 1>;
            let rates = crate::mechanics::coords::rates(sys.nb(), q, u);
            let qd: Vec<D1> = q.iter().zip(rates).map(|(&v, d)| D1 { v, d: [d] }).collect();
            let ud: Vec<D1> = u.iter().map(|&v| D1::cst(v)).collect();
            let mut ctx = LocalCtx::new(sys, &ids, &qd, &ud, &[], D1 { v: t, d: [1.0] }, inputs);
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
            self.sys.angle_refs[g] = v;
            self.sys.angle_rates[g] = rate;
        }
        self.sys.angle_time = t;
    }
}
