//! The DAE layer: residual and sparse Jacobians of the equations of motion (Eq. 13a–13e),
//! initialization (assembly), and the integrator (Radau IIA on the stabilized system).

pub mod counts;
pub mod equations;
pub mod init;
pub mod jacobian;
pub mod layout;
pub mod radau;
mod radau_tableau;
pub mod rank;
pub mod residual;
mod simulator;
pub mod sparse;

pub use radau::{BATCH_MAX_STEPS, DEFAULT_MAX_STEPS};
pub use simulator::{BodyState, EngineError, SimOptions, SimState, Simulator};
