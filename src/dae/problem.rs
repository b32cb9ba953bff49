//! The multibody DAE as the integrator sees it: residual, Jacobian, mass matrix and index
//! of each component, inputs interpolated over a step, and what happens after each
//! accepted step (re-based Euler frames, recorded angle branches).

use super::equations::{self, Layout};
use super::radau::DaeProblem;
use super::sparse::Triplets;
use crate::mechanics::System;

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
        let (qs, us) = (self.lay.q_range(), self.lay.u_range());
        let changed = self.sys.rebase_frames(&mut y[qs.clone()]);
        let ext = self.lay.ext(&self.sys, &self.inputs_at(t), y, t);
        self.sys.record_angles(t, &y[qs], &y[us], &ext);
        changed
    }
}

impl MultibodyDae {
    /// Inputs at time t: held values plus slope · (t − t_in).
    pub(super) fn inputs_at(&self, t: f64) -> Vec<f64> {
        self.inputs.iter().zip(&self.slopes).map(|(v, s)| v + s * (t - self.t_in)).collect()
    }
}
