//! Modal flexible bodies (floating frame of reference): the modal data of a body and its
//! file, and a generator of such data for a straight beam.
//!
//! - [`data`]: [`ModalData`], nodes with lumped masses and rotary inertias, mode shapes,
//!   modal stiffness (frequencies of mass-normalized modes, K = diag((2πf)²), or a matrix)
//!   and damping (ratios, C = diag(2ζω), or a matrix).
//! - [`read()`] / [`write()`]: the modal data file (JSON, MODEL_FORMAT.md "Modal data
//!   files"), validated on reading; errors are `path: entry: what is wrong` ([`ModalError`]).
//! - [`matrix_checks`]: symmetric, positive semidefinite, mass-normalized.
//! - [`beam()`]: a straight Euler–Bernoulli beam ([`beam_fe`], lumped mass) reduced to
//!   free-interface normal modes ([`eigen`]) or by Craig–Bampton ([`craig_bampton`]).
//!
//! This layer sits below `model` (which reads modal files) and uses only `ad` and `geom`.

pub mod beam;
pub mod beam_fe;
pub mod craig_bampton;
pub mod data;
pub mod eigen;
pub mod error;
pub mod invariants;
pub mod matrix_checks;
pub mod read;
pub mod write;

pub use beam::{BeamSpec, Reduction, beam};
pub use beam_fe::{Material, Section};
pub use data::{ModalDamping, ModalData, ModalStiffness, Node};
pub use error::ModalError;
pub use read::{parse, read};
pub use write::write;
