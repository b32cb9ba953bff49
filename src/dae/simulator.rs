//! Public face of the engine: build, initialize, advance, read results.

use super::assembly_moves::assembly_moves;
use super::equations::Layout;
use super::error::EngineError;
use super::init;
use super::options::SimOptions;
use super::problem::MultibodyDae;
use super::radau::{DaeProblem, Radau, Stats};
use super::sparse::{SparseLu, Triplets};
use super::start_values::{START_VALUE_TAG, StartValues};
use crate::mechanics::System;
use crate::model::{Model, ModelError};

/// A running simulation of one model.
pub struct Simulator {
    /// The equations, with the inputs and the Euler-angle reference frames.
    pub(super) dae: MultibodyDae,
    /// The integrator, holding t, y and the step history.
    pub(super) radau: Radau,
    /// The factorization of the acceleration solve (reused across calls).
    pub(super) acc_lu: SparseLu,
    /// Accelerations and multipliers at the current time (None: not yet computed).
    pub(super) acc: Option<(Vec<f64>, Vec<f64>)>,
    /// What initialization wants the user to know (bodies that assembly moved far).
    warnings: Vec<String>,
    /// Whether an output reads accelerations, loads (λ) or user unknowns: only then do
    /// outputs need the acceleration solve (a KKT factorization per communication point).
    pub(super) outputs_need_acc: bool,
    /// Buffers of the outputs' evaluation (every body's index, the inputs, the external
    /// values): reading outputs at each communication point allocates nothing.
    pub(super) obs: ObserveScratch,
}

/// Buffers of [`Simulator::outputs_into`].
#[derive(Debug, Default)]
pub(super) struct ObserveScratch {
    pub(super) ids: Vec<usize>,
    pub(super) inputs: Vec<f64>,
    pub(super) ext: Vec<f64>,
}

impl Simulator {
    /// Build the equations and initialize at `t0` (assembly, consistent velocities,
    /// accelerations and multipliers).
    pub fn new(model: &Model, opts: SimOptions, t0: f64) -> Result<Simulator, EngineError> {
        Self::with_start(model, opts, t0, &StartValues::default())
    }

    /// [`Simulator::new`] with values set on states, met exactly (see [`StartValues`]); a
    /// set that cannot be met is an error naming the values.
    pub fn with_start(model: &Model, opts: SimOptions, t0: f64, start: &StartValues) -> Result<Simulator, EngineError> {
        let mut sys = System::from_model(model).map_err(EngineError::Numeric)?;
        // Values set by name in the model (`--set`, a packed FMU's), then the caller's.
        let start = StartValues::named(&sys, model).map_err(EngineError::Numeric)?.overridden_by(start);
        start.apply(&mut sys);
        let inputs: Vec<f64> = model.inputs.iter().map(|i| i.start.value).collect();
        let lay = Layout::of(&sys);
        let mut q = sys.q_init.clone();
        let mut u = sys.u_init.clone();
        let assembly_tol = (opts.tol * 1e-3).max(1e-14);
        sys.redundant = init::redundant_rows(&sys, &q, t0, &inputs);
        let assembly =
            init::assemble_positions(&mut sys, &mut q, t0, &inputs, assembly_tol).map_err(|e| match e.element {
                Some(b) if b.0.tag == START_VALUE_TAG => EngineError::Numeric(format!(
                    "the start values set cannot be met: {} '{}': {}",
                    b.0.tag, b.0.name, e.msg
                )),
                Some(b) => EngineError::Model(ModelError {
                    file: model.file.clone(),
                    pos: b.0.pos,
                    element: b.0.tag.into(),
                    name: b.0.name.clone(),
                    msg: if b.0.neq > 1 { format!("{} (equation {} of {})", e.msg, b.1, b.0.neq) } else { e.msg },
                }),
                None => EngineError::Numeric(e.msg),
            })?;
        let mut z = vec![0.0; lay.nz()];
        z[..lay.nx].copy_from_slice(&sys.x_init);
        if model.static_analysis {
            u.iter_mut().for_each(|v| *v = 0.0);
            init::user_unknowns(&sys, &q, &u, None, t0, &inputs, &mut z).map_err(EngineError::Numeric)?;
            init::static_equilibrium(&sys, &mut q, &mut z, t0, &inputs, assembly_tol).map_err(EngineError::Numeric)?;
        }
        init::assemble_velocities(&sys, &q, &mut u, t0, &inputs).map_err(EngineError::Numeric)?;
        let mut acc_lu = SparseLu::new();
        let (udot, lam) = init::consistent_accelerations(&sys, &q, &u, t0, &inputs, &mut z, &mut acc_lu)
            .map_err(EngineError::Numeric)?;
        let mut y = lay.assemble(&q, &u, &z, &lam);
        let slopes = vec![0.0; inputs.len()];
        let mut dae = MultibodyDae::new(sys, lay, inputs, slopes, t0);
        dae.accepted(t0, &mut y);
        let mut radau = Radau::new(&dae, t0, y, opts.tol);
        if let Some(h) = opts.max_step {
            radau.max_step = h;
        }
        radau.max_steps = opts.max_steps.max(1);
        let warnings = assembly_moves(model, &dae.sys.q_init, &assembly);
        let outputs_need_acc = dae.sys.outputs.iter().any(|e| {
            let d = crate::model::expr::deps(e);
            d.level >= 2 || !d.loads.is_empty() || !d.variables.is_empty() || !d.diff_dots.is_empty()
        });
        Ok(Simulator {
            dae,
            radau,
            acc_lu,
            acc: Some((udot, lam)),
            warnings,
            outputs_need_acc,
            obs: ObserveScratch::default(),
        })
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.radau.t
    }

    /// Change the limit on integrator step attempts per [`Simulator::advance`] call (at
    /// least 1).
    pub fn set_max_steps(&mut self, n: usize) {
        self.radau.max_steps = n.max(1);
    }

    /// The limit on integrator step attempts per [`Simulator::advance`] call.
    pub fn max_steps(&self) -> usize {
        self.radau.max_steps
    }

    /// Integrate to `t_end` exactly (the last step lands on it). On an error (the step
    /// limit, a step-size collapse) the simulation stays at the last accepted step:
    /// [`Simulator::time`] is the time reached.
    pub fn advance(&mut self, t_end: f64) -> Result<(), EngineError> {
        if t_end < self.radau.t {
            return Err(EngineError::Numeric(format!("cannot integrate backwards from {} to {t_end}", self.radau.t)));
        }
        self.acc = None;
        // The step size, Jacobian and factorization carry over from the last interval (a
        // saved state holds them, so a restored one reproduces the run bit for bit).
        self.radau.new_interval();
        self.radau.advance(&mut self.dae, t_end).map_err(EngineError::Numeric)
    }

    /// The pencil (J, M) of the DAE M y' = f(t, y) at the current point, J = ∂f/∂y exact
    /// and sparse, with f there and the multipliers (λ, ν) of y.
    pub fn pencil(&mut self) -> Result<(Triplets, Triplets, Vec<f64>, Vec<f64>), EngineError> {
        let (t, y) = (self.radau.t, self.radau.y.clone());
        let mut j = Triplets::new();
        // The exact J, not the integrator's iteration approximation (it asks for its own
        // kind again before its next Jacobian).
        self.dae.set_exact_jacobian(true);
        self.dae.jacobian(t, &y, &mut j).map_err(EngineError::Numeric)?;
        let mut m = Triplets::new();
        self.dae.mass(&mut m);
        let mut f = vec![0.0; y.len()];
        self.dae.rhs(t, &y, &mut f).map_err(EngineError::Numeric)?;
        let mult = y[self.dae.lay.multipliers_range()].to_vec();
        Ok((j, m, f, mult))
    }

    /// Integrator statistics so far.
    pub fn stats(&self) -> Stats {
        self.radau.stats
    }

    /// The mechanical system (with its current Euler-angle reference frames).
    pub fn system(&self) -> &System {
        &self.dae.sys
    }

    /// Current coordinates q.
    pub fn q(&self) -> &[f64] {
        &self.radau.y[self.dae.lay.q_range()]
    }

    /// Current velocities u.
    pub fn u(&self) -> &[f64] {
        &self.radau.y[self.dae.lay.u_range()]
    }

    /// Accelerations u̇ and multipliers λ at the current time (Eq. 1c–1d).
    pub fn accelerations(&mut self) -> Result<(Vec<f64>, Vec<f64>), EngineError> {
        if self.acc.is_none() {
            let (q, u) = (self.q().to_vec(), self.u().to_vec());
            let s = &self.dae;
            let t = self.radau.t;
            self.acc = Some(if s.sys.load_refs.is_empty() && s.sys.acc_bodies.is_empty() {
                let ext = self.ext();
                init::accelerations(&s.sys, &q, &u, t, &ext, &mut self.acc_lu).map_err(EngineError::Numeric)?
            } else {
                // Loads in the loop: λ (and the loads) solved together, as at initialization.
                let mut z = self.user_values().to_vec();
                let inputs = s.inputs_at(t);
                init::consistent_accelerations(&s.sys, &q, &u, t, &inputs, &mut z, &mut self.acc_lu)
                    .map_err(EngineError::Numeric)?
            });
        }
        Ok(self.acc.clone().expect("just computed"))
    }

    /// The external values [inputs; Z] at the current time (see [`System::ext`]).
    pub fn ext(&self) -> Vec<f64> {
        self.dae.lay.ext(&self.dae.sys, &self.dae.inputs_at(self.radau.t), &self.radau.y, self.radau.t)
    }

    /// The external values with the element loads evaluated at multipliers `lam` (those of
    /// [`Simulator::accelerations`], so outputs and linearization see one consistent λ).
    pub fn ext_with(&self, lam: &[f64]) -> Vec<f64> {
        let (lay, t) = (self.dae.lay, self.radau.t);
        let y = &self.radau.y;
        let state = (&y[lay.q_range()], &y[lay.u_range()], &lam[..lay.m]);
        let mut z = self.user_values().to_vec();
        // Acceleration unknowns: those of the same solve as λ.
        if let Some((udot, _)) = &self.acc {
            lay.set_accelerations(&self.dae.sys, udot, &mut z);
        }
        self.dae.sys.ext(&self.dae.inputs_at(t), &z, Some(state), t)
    }

    /// Current user unknowns Z = (X, Ẋ, V).
    pub fn user_values(&self) -> &[f64] {
        let l = &self.dae.lay;
        &self.radau.y[l.z_range()]
    }

    /// Number of inputs.
    pub fn n_inputs(&self) -> usize {
        self.dae.inputs.len()
    }

    /// Current input values.
    pub fn inputs(&self) -> Vec<f64> {
        self.dae.inputs_at(self.radau.t)
    }

    /// Input `i` at the current time (as [`Simulator::inputs`], without a vector).
    pub fn input(&self, i: usize) -> f64 {
        self.dae.inputs[i] + self.dae.slopes[i] * (self.radau.t - self.dae.t_in)
    }

    /// Current slope of input `i` (0 unless set by [`Simulator::set_input_derivative`]).
    pub fn input_slope(&self, i: usize) -> f64 {
        self.dae.slopes[i]
    }

    /// Set input `i` from now on: held constant (slope 0) until changed.
    pub fn set_input(&mut self, i: usize, v: f64) {
        self.rebase_inputs();
        self.dae.inputs[i] = v;
        self.dae.slopes[i] = 0.0;
        self.acc = None;
    }

    /// Warnings of initialization (bodies that assembly moved far), for the user.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Re-solve, at the current point, the unknowns that follow the inputs at once: the
    /// algebraic user unknowns Ẋ, V (seed Eq. 7b holds at every instant) and the
    /// acceleration unknowns, with the multipliers, as at initialization. Called after
    /// inputs change at a communication point, so that outputs, user variables and the
    /// linearization read there see the new inputs.
    pub fn resolve_user_unknowns(&mut self) -> Result<(), EngineError> {
        let l = &self.dae.lay;
        if l.nz() == l.nx {
            return Ok(());
        }
        let (zs, lam0) = (l.z_range(), l.lam());
        let (q, u) = (self.q().to_vec(), self.u().to_vec());
        let t = self.radau.t;
        let mut z = self.user_values().to_vec();
        let inputs = self.dae.inputs_at(t);
        let (udot, lam) = init::consistent_accelerations(&self.dae.sys, &q, &u, t, &inputs, &mut z, &mut self.acc_lu)
            .map_err(EngineError::Numeric)?;
        self.radau.y[zs].copy_from_slice(&z);
        self.radau.y[lam0..lam0 + lam.len()].copy_from_slice(&lam); // λ then ν
        self.acc = Some((udot, lam));
        Ok(())
    }

    /// Set the time derivative of input `i`: from now on it changes linearly (FMI
    /// `fmi2SetRealInputDerivatives`, order 1) until set again.
    pub fn set_input_derivative(&mut self, i: usize, slope: f64) {
        self.rebase_inputs();
        self.dae.slopes[i] = slope;
        self.acc = None;
    }

    /// Move the inputs' reference time to now (values unchanged).
    fn rebase_inputs(&mut self) {
        let t = self.radau.t;
        self.dae.inputs = self.dae.inputs_at(t);
        self.dae.t_in = t;
    }
}
