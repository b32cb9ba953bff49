//! Which FMI interface an instance serves, and what a Model Exchange host has set there
//! (the value the host changes, apart from the engine; saved with the FMU state).

use crate::dae::Accepted;

/// Which interface the host instantiated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    /// Co-Simulation: fmi2DoStep integrates.
    CoSimulation,
    /// Model Exchange: the host integrates ẋ = f(t, x).
    ModelExchange,
}

/// What a Model Exchange host has set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Exchange {
    /// fmi2SetTime's time.
    pub time: f64,
    /// fmi2SetContinuousStates' x.
    pub x: Vec<f64>,
    /// Whether the engine is at (time, x) (false after either changed).
    pub placed: bool,
    /// The engine's point at the last accepted step (fmi2CompletedIntegratorStep, or the
    /// end of initialization), from which the next accepted step is checked.
    pub accepted: Option<Accepted>,
}
