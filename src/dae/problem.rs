//! The multibody DAE as the integrator sees it: residual, Jacobian, mass matrix and index
//! of each component, inputs interpolated over a step, and what happens after each
//! accepted step (re-based Euler frames, recorded angle branches).

use super::equations::{self, JacScratch, Layout};
use super::radau::DaeProblem;
use super::residual::RhsScratch;
use super::sparse::Triplets;
use crate::mechanics::System;
use crate::mechanics::angles::AngleScratch;

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
    /// The inputs at the time of the last [`DaeProblem::rhs`], and that function's buffers.
    inputs_now: Vec<f64>,
    ws: RhsScratch,
    /// The Jacobian's buffers.
    jws: JacScratch,
    /// Buffers of the angle-branch recording at accepted steps: the inputs, the external
    /// values and the recording's own.
    accepted_inputs: Vec<f64>,
    accepted_ext: Vec<f64>,
    angles: AngleScratch,
}

impl DaeProblem for MultibodyDae {
    fn dim(&self) -> usize {
        self.lay.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), String> {
        interpolate(&self.inputs, &self.slopes, t - self.t_in, &mut self.inputs_now);
        equations::rhs(&self.sys, self.lay, t, y, &self.inputs_now, &mut self.ws, f);
        if f.iter().all(|v| v.is_finite()) { Ok(()) } else { Err("non-finite equations".into()) }
    }
    fn jacobian(&mut self, t: f64, y: &[f64], j: &mut Triplets) -> Result<(), String> {
        interpolate(&self.inputs, &self.slopes, t - self.t_in, &mut self.inputs_now);
        equations::jacobian_with(&self.sys, self.lay, t, y, &self.inputs_now, &mut self.jws, j);
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
    fn groups(&self) -> Vec<usize> {
        self.lay.groups(&self.sys)
    }
    fn set_exact_jacobian(&mut self, exact: bool) {
        self.jws.within_bodies = !exact;
    }
    fn accepted(&mut self, t: f64, y: &mut [f64]) -> bool {
        let (qs, us) = (self.lay.q_range(), self.lay.u_range());
        let changed = self.sys.rebase_frames(&mut y[qs.clone()]);
        interpolate(&self.inputs, &self.slopes, t - self.t_in, &mut self.accepted_inputs);
        self.lay.ext_into(&self.sys, &self.accepted_inputs, y, t, &mut self.accepted_ext);
        self.sys.record_angles_with(&mut self.angles, t, &y[qs], &y[us], &self.accepted_ext);
        changed
    }
}

impl MultibodyDae {
    /// The DAE of `sys` (laid out by `lay`) with inputs `inputs` at `t_in`, changing at
    /// `slopes`.
    pub(super) fn new(sys: System, lay: Layout, inputs: Vec<f64>, slopes: Vec<f64>, t_in: f64) -> MultibodyDae {
        MultibodyDae {
            sys,
            lay,
            inputs,
            slopes,
            t_in,
            inputs_now: Vec::new(),
            ws: RhsScratch::default(),
            jws: JacScratch::default(),
            accepted_inputs: Vec::new(),
            accepted_ext: Vec::new(),
            angles: AngleScratch::default(),
        }
    }

    /// Inputs at time t: held values plus slope · (t − t_in).
    pub(super) fn inputs_at(&self, t: f64) -> Vec<f64> {
        let mut v = Vec::new();
        self.inputs_into(t, &mut v);
        v
    }

    /// [`MultibodyDae::inputs_at`] into `v` (its capacity reused).
    pub(super) fn inputs_into(&self, t: f64, v: &mut Vec<f64>) {
        interpolate(&self.inputs, &self.slopes, t - self.t_in, v);
    }
}

/// `values` + `slopes` · `dt` into `out` (its capacity reused).
fn interpolate(values: &[f64], slopes: &[f64], dt: f64, out: &mut Vec<f64>) {
    out.clear();
    out.extend(values.iter().zip(slopes).map(|(v, s)| v + s * dt));
}
