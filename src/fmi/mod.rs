//! The FMI layer, what runs inside a host: one thin shell over the engine (handles,
//! guard, state-machine table, instance, logger) under two tables of exports, FMI 2.0
//! (`exports_*`: Co-Simulation and Model Exchange) and FMI 3.0 (`exports3_*`:
//! Co-Simulation and Model Exchange). It maps value references, enforces
//! the state machine, logs, and calls the engine; it computes nothing itself. The
//! build-time packer is [`crate::pack`].

pub mod config;
pub mod exchange;
pub mod exports3_common;
pub mod exports3_cs;
pub mod exports3_me;
pub mod exports3_other;
pub mod exports_common;
pub mod exports_cs;
pub mod exports_me;
pub mod exports_state;
pub mod fmu_state;
pub mod guard;
pub mod guid;
pub mod handle;
pub mod instance;
pub mod interface;
pub mod logger;
pub mod resources;
pub mod state_handles;
pub mod state_machine;
pub mod types;
pub mod uri;
pub mod variables;
