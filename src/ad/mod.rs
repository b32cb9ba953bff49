//! Forward-mode automatic differentiation: the engine's only source of derivatives.
//!
//! Every element (joint, force, expression) is written once, generic over [`Real`];
//! evaluating it with [`Dual`] numbers yields exact first derivatives, and with
//! `Dual<Dual<f64, N>, N>` exact second derivatives. Nothing is finite-differenced.

pub mod chunked;
mod dual;
mod real;

pub use dual::Dual;
pub use real::Real;
