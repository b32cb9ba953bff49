//! Public face of the engine: build, initialize, advance, read results.

use crate::model::Model;

/// Engine failure (assembly, integration, evaluation).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct EngineError(pub String);

/// Integrator options.
#[derive(Clone, Copy, Debug)]
pub struct SimOptions {
    /// Local error tolerance (relative and absolute) of positions and velocities.
    pub tol: f64,
    /// Largest step the integrator may take (None: unlimited).
    pub max_step: Option<f64>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions { tol: 1e-6, max_step: None }
    }
}

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

/// A running simulation of one model.
pub struct Simulator {
    _private: (),
}

impl Simulator {
    /// Build the equations and initialize at `t0` (assembly, consistent velocities,
    /// accelerations and multipliers).
    pub fn new(model: &Model, opts: SimOptions, t0: f64) -> Result<Simulator, EngineError> {
        let _ = (model, opts, t0);
        Err(EngineError("engine not implemented".into()))
    }
    /// Current time.
    pub fn time(&self) -> f64 {
        0.0
    }
    /// Integrate to `t_end` exactly (the last step lands on it).
    pub fn advance(&mut self, t_end: f64) -> Result<(), EngineError> {
        let _ = t_end;
        Err(EngineError("engine not implemented".into()))
    }
    /// Names of the model's `<output>`s, in order.
    pub fn output_names(&self) -> Vec<String> {
        vec![]
    }
    /// Values of the `<output>`s at the current time.
    pub fn outputs(&mut self) -> Result<Vec<f64>, EngineError> {
        Err(EngineError("engine not implemented".into()))
    }
    /// Largest |C_i(q, t)| over the holonomic constraints at the current time.
    pub fn constraint_residual(&self) -> f64 {
        f64::NAN
    }
    /// State of body `b` (model order).
    pub fn body_state(&self, b: usize) -> BodyState {
        let _ = b;
        BodyState { position: [0.0; 3], rotation: [[0.0; 3]; 3], velocity: [0.0; 3], angular_velocity: [0.0; 3] }
    }
    /// Kinetic + gravitational potential + spring potential energy.
    pub fn mechanical_energy(&self) -> f64 {
        f64::NAN
    }
    /// Names of every coordinate q and velocity u (`body.x`, ..., `body.wx`, ...).
    pub fn state_names(&self) -> Vec<String> {
        vec![]
    }
    /// Current q and u, in the order of [`Simulator::state_names`].
    pub fn states(&self) -> Vec<f64> {
        vec![]
    }
}
