//! The DAE layer: residual and sparse Jacobians of the equations of motion (Eq. 13a–13e),
//! initialization (assembly), and the index-3 integrator.

mod simulator;

pub use simulator::{BodyState, EngineError, SimOptions, Simulator};
