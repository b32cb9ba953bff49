//! What the host chose for an instance: parameter and input values, input slopes,
//! experiment and solver settings (kept apart so that a saved FMU state holds it
//! without knowing the instance).

/// What the host chose: parameter and input values, input slopes, experiment, solver
/// settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Parameter values (model order).
    pub params: Vec<f64>,
    /// Input values (model order).
    pub inputs: Vec<f64>,
    /// Input slopes (fmi2SetRealInputDerivatives).
    pub slopes: Vec<f64>,
    /// Integration tolerance.
    pub tol: f64,
    /// Start time.
    pub start: f64,
    /// Stop time, if the host gave one.
    pub stop: Option<f64>,
    /// `solver.maxSteps`: most integrator step attempts per fmi2DoStep (at least 1).
    pub max_steps: usize,
}
