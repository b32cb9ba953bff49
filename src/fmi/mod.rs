//! The FMI 2.0 Co-Simulation layer: a thin shell over the engine. It maps value
//! references, enforces the FMI state machine, logs, and calls the engine; it computes
//! nothing itself.

pub mod config;
pub mod exports_common;
pub mod exports_cs;
pub mod exports_me;
pub mod exports_state;
pub mod fmu_state;
pub mod guard;
pub mod guid;
pub mod handle;
pub mod instance;
pub mod logger;
pub mod resources;
pub mod state_handles;
pub mod state_machine;
pub mod types;
pub mod uri;
pub mod variables;
