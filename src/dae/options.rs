//! Integrator options of a simulation.

use super::radau::DEFAULT_MAX_STEPS;

/// Integrator options.
#[derive(Clone, Copy, Debug)]
pub struct SimOptions {
    /// Local error tolerance (relative and absolute) of positions and velocities; also
    /// the assembly tolerance of the constraints.
    pub tol: f64,
    /// Largest step the integrator may take (None: unlimited).
    pub max_step: Option<f64>,
    /// Most integrator step attempts (accepted and rejected) per [`Simulator::advance`]
    /// call; more is an error at the time reached (default [`DEFAULT_MAX_STEPS`]).
    pub max_steps: usize,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions { tol: 1e-6, max_step: None, max_steps: DEFAULT_MAX_STEPS }
    }
}
