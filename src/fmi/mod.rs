//! The FMI 2.0 Co-Simulation layer: a thin shell over the engine. It maps value
//! references, enforces the FMI state machine, logs, and calls the engine; it computes
//! nothing itself.

pub mod guid;
pub mod model_description;
pub mod pack;
pub mod variables;
