//! mbfmu: multibody model file -> FMI 2.0 Co-Simulation FMU with exact linearization
//! (Negrut & Ortiz, "On an approach for the linearization of the DAEs of multibody dynamics").
//!
//! Data flows one way: [`modal`] -> [`model`] -> [`mechanics`] -> [`dae`] -> `linearize` -> `fmi`/`cli`.

pub mod ad;
pub mod cli;
pub mod dae;
pub mod fmi;
pub mod geom;
pub mod linearize;
pub mod mechanics;
pub mod modal;
pub mod model;
pub mod pack;
