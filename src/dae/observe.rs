//! Reading a simulation: outputs and their time derivatives, body states, energy,
//! constraint residuals, state names and values.

use super::error::EngineError;
use super::simulator::{ObserveScratch, Simulator};
use crate::geom::V3;
use crate::mechanics::body::{NQ, body_frame};
use crate::mechanics::loads::{load_index, load_value};
use crate::mechanics::local::LocalCtx;
use crate::mechanics::mass::body_kinetic_energy;
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;
use crate::model::expr::{ElementRef, LoadFn};

/// Kinematic state of one body, ground components.
#[derive(Clone, Copy, Debug)]
pub struct BodyState {
    /// CM position.
    pub position: [f64; 3],
    /// Rotation matrix (row-major; columns = body axes in ground).
    pub rotation: [[f64; 3]; 3],
    /// CM velocity.
    pub velocity: [f64; 3],
    /// Angular velocity.
    pub angular_velocity: [f64; 3],
}

impl Simulator {
    /// Names of the model's `<output>`s, in order.
    pub fn output_names(&self) -> Vec<String> {
        self.dae.sys.output_names.clone()
    }

    /// Values of the `<output>`s at the current time.
    pub fn outputs(&mut self) -> Result<Vec<f64>, EngineError> {
        let mut out = Vec::new();
        self.outputs_into(&mut out)?;
        Ok(out)
    }

    /// [`Simulator::outputs`] into `out` (its capacity reused: when no output reads
    /// accelerations, loads or user unknowns, nothing is allocated once warm).
    pub fn outputs_into(&mut self, out: &mut Vec<f64>) -> Result<(), EngineError> {
        out.clear();
        if !self.outputs_need_acc && self.acc.is_none() {
            // Positions and velocities only: no acceleration solve.
            let (t, lay, sys) = (self.radau.t, self.dae.lay, &self.dae.sys);
            let ObserveScratch { ids, inputs, ext } = &mut self.obs;
            ids.clear();
            ids.extend(0..sys.nb());
            self.dae.inputs_into(t, inputs);
            lay.ext_into(sys, inputs, &self.radau.y, t, ext);
            let ctx = LocalCtx::new(sys, ids, &self.radau.y[lay.q_range()], &self.radau.y[lay.u_range()], &[], t, ext);
            out.extend(sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b)));
            return Ok(());
        }
        let (udot, lam) = self.accelerations()?;
        let sys = &self.dae.sys;
        let ids: Vec<usize> = (0..sys.nb()).collect();
        let ctx_loads = |f: LoadFn, e: ElementRef| self.load_component(f, e, &lam);
        let inputs = self.ext_with(&lam);
        let mut ctx = LocalCtx::new(sys, &ids, self.q(), self.u(), &udot, self.radau.t, &inputs);
        ctx.loads = Some(&ctx_loads);
        out.extend(sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b)));
        Ok(())
    }

    /// Component `f` of the load element `e` applies on its i marker (NaN if it has none),
    /// from [`crate::mechanics::loads`].
    fn load_component(&self, f: LoadFn, e: ElementRef, lam: &[f64]) -> f64 {
        let t = self.radau.t;
        load_value(&self.dae.sys, e, (self.q(), self.u(), lam), t, &self.ext_with(lam))
            .map_or(f64::NAN, |l| l[load_index(f)])
    }

    /// Largest |g_i(q, u, t)| over the non-holonomic constraints at the current time.
    pub fn nonholonomic_residual(&self) -> f64 {
        let s = &self.dae.sys;
        let ext = self.ext();
        let (_, g) = nonholonomic_b(s, self.q(), self.u(), self.radau.t, &ext);
        g.iter().fold(0.0, |a: f64, v| a.max(v.abs()))
    }

    /// Largest |C_i(q, t)| over the holonomic constraints at the current time.
    pub fn constraint_residual(&self) -> f64 {
        let s = &self.dae.sys;
        s.constraints
            .iter()
            .flat_map(|el| {
                crate::mechanics::kernels::constraint_values(
                    s,
                    el,
                    self.q(),
                    self.radau.t,
                    &self.dae.inputs_at(self.radau.t),
                )
            })
            .fold(0.0, |a: f64, v| a.max(v.abs()))
    }

    /// State of body `b` (model order).
    pub fn body_state(&self, b: usize) -> BodyState {
        let o = NQ * b;
        let (r, a) = body_frame(&self.q()[o..o + NQ], &self.dae.sys.r0[b]);
        let u = self.u();
        let w = a.mv(&V3([u[o + 3], u[o + 4], u[o + 5]]));
        BodyState { position: r.0, rotation: a.0, velocity: [u[o], u[o + 1], u[o + 2]], angular_velocity: w.0 }
    }

    /// Kinetic + gravitational potential + spring potential energy.
    pub fn mechanical_energy(&self) -> f64 {
        let s = &self.dae.sys;
        let (q, u) = (self.q(), self.u());
        let mut e = 0.0;
        for (b, body) in s.bodies.iter().enumerate() {
            e += body_kinetic_energy(s, b, q, u);
            match s.flex_of(b) {
                Some(f) => {
                    let qb = crate::mechanics::coords::gather(s, &[b], q);
                    e += crate::mechanics::flexible::potential(&f.inv, &s.r0[b], s.gravity, &qb);
                }
                None => e -= body.mass * (0..3).map(|c| s.gravity[c] * q[NQ * b + c]).sum::<f64>(),
            }
        }
        for el in &s.forces {
            let ql = crate::mechanics::coords::gather(s, &el.bodies, q);
            let ul = crate::mechanics::coords::gather(s, &el.bodies, u);
            let inputs = self.ext();
            let ctx = LocalCtx::new(s, &el.bodies, &ql, &ul, &[], self.radau.t, &inputs);
            e += el.potential(&ctx);
        }
        e
    }

    /// Names of every coordinate q and velocity u (`body.x`, ..., `body.wz`).
    pub fn state_names(&self) -> Vec<String> {
        let qn = ["x", "y", "z", "psi", "theta", "phi"];
        let un = ["vx", "vy", "vz", "wx", "wy", "wz"];
        let s = &self.dae.sys;
        let mut v: Vec<String> =
            s.bodies.iter().flat_map(|b| qn.iter().map(move |c| format!("{}.{c}", b.name))).collect();
        let modal = |prefix: &'static str| {
            s.flex
                .iter()
                .flat_map(move |f| (1..=f.eta.len()).map(move |k| format!("{}.{prefix}{k}", s.bodies[f.body].name)))
        };
        v.extend(modal("eta"));
        v.extend(s.bodies.iter().flat_map(|b| un.iter().map(move |c| format!("{}.{c}", b.name))));
        v.extend(modal("etadot"));
        v
    }

    /// Current q and u, in the order of [`Simulator::state_names`]. Angles are relative
    /// to each body's current reference frame; `wx..wz` are body-axis components.
    pub fn states(&self) -> Vec<f64> {
        let mut v = self.q().to_vec();
        v.extend_from_slice(self.u());
        v
    }

    /// First time derivatives of the `<output>`s at the current time (FMI
    /// `fmi2GetRealOutputDerivatives`, order 1).
    ///
    /// Exact (by dual numbers along the motion: q̇ = H u, u̇ from the equations of motion,
    /// input slopes, time) for outputs of positions, velocities, time and inputs. Outputs of
    /// accelerations also need the jerk, taken from the integrator's collocation polynomial
    /// over the last step (zero right after a state was restored); loads count as constant.
    pub fn output_derivatives(&mut self) -> Result<Vec<f64>, EngineError> {
        use crate::ad::{Dual, Real};
        type D = Dual<f64, 1>;
        let (udot, lam) = self.accelerations()?;
        let n = self.dae.lay.n;
        let jerk = self.radau.derivatives_at_end().map(|(_, d2)| d2[n..2 * n].to_vec());
        let (q, u) = (self.q().to_vec(), self.u().to_vec());
        let qd = crate::mechanics::coords::rates(self.dae.sys.nb(), &q, &u);
        let mk = |v: &[f64], d: &[f64]| -> Vec<D> { v.iter().zip(d).map(|(&v, &d)| D { v, d: [d] }).collect() };
        let qv = mk(&q, &qd);
        let uv = mk(&u, &udot);
        let av = mk(&udot, jerk.as_deref().unwrap_or(&vec![0.0; n]));
        let t = self.radau.t;
        let inputs = self.ext();
        let lay = self.dae.lay;
        // Rates of the external values: input slopes; X' = Ẋ; Ẋ', V' from the collocation
        // polynomial (zero right after a restore).
        let mut rates = self.dae.slopes.clone();
        let zd = self.radau.derivatives_at_end().map(|(d1, _)| d1[lay.z()..lay.z() + lay.nz()].to_vec());
        for i in 0..lay.nz() {
            rates.push(if i < lay.nx { self.user_values()[lay.nx + i] } else { zd.as_ref().map_or(0.0, |d| d[i]) });
        }
        let sys = &self.dae.sys;
        let ids: Vec<usize> = (0..sys.nb()).collect();
        let ctx_loads = |f: LoadFn, e: ElementRef| D::cst(self.load_component(f, e, &lam));
        let mut ctx = LocalCtx::new(sys, &ids, &qv, &uv, &av, D { v: t, d: [1.0] }, &inputs);
        ctx.input_values = Some(mk(&inputs, &rates));
        ctx.loads = Some(&ctx_loads);
        Ok(sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| ctx.eval_expr(e, b).d[0]).collect())
    }
}
