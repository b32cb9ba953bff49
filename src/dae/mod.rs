//! The DAE layer: residual and sparse Jacobians of the equations of motion (Eq. 13a–13e),
//! initialization (assembly), and the integrator (Radau IIA on the stabilized system).

mod assembly_moves;
pub mod block_lu;
mod branch;
pub mod bytes;
pub mod counts;
pub mod equations;
mod error;
pub mod init;
mod iteration_lu;
pub mod jacobian;
pub mod layout;
mod observe;
mod options;
mod partitioned;
mod problem;
pub mod radau;
mod radau_tableau;
pub mod rank;
pub mod residual;
mod simulator;
mod snapshot;
pub mod sparse;
mod start_values;

pub use branch::Accepted;
pub use error::EngineError;
pub use observe::BodyState;
pub use options::SimOptions;
pub use partitioned::{Check, PLACEMENT_TOL};
pub use radau::{BATCH_MAX_STEPS, DEFAULT_MAX_STEPS};
pub use simulator::Simulator;
pub use snapshot::SimState;
pub use start_values::{START_VALUE_TAG, StartValue, StartValues};
