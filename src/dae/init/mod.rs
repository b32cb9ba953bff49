//! Initialization (MODEL_FORMAT "Initial conditions"), one step per file, in the order
//! a simulation start runs them:
//! - [`redundancy`]: which constraint rows depend on others (their λ = 0);
//! - [`positions`]: assemble positions with the smallest change: the drawing made
//!   consistent ([`gauss_newton`], least-norm corrections [I C_qᵀ; C_q 0]), then the
//!   exact conditions reached along a path ([`continuation`]), every joint's orientation
//!   checked ([`orientation`]);
//! - [`placement`]: Model Exchange's coordinate partitioning: the positions at which
//!   given position states hold, by Newton from the last consistent point;
//! - [`statics`]: static equilibrium instead, when the model asks for it;
//! - [`velocities`]: consistent velocities closest to the given ones (P u + C_t = 0,
//!   B u + b = 0, the velocity ICs);
//! - [`accelerations`]: u̇ and the multipliers from [M Pᵀ Bᵀ; P 0 0; B 0 0] (Eq. 1c–1d);
//! - [`user_unknowns`]: the algebraic user unknowns (Ẋ, V) from the user rows (Eq. 7);
//! - [`algebraic_loop`]: u̇, (Ẋ, V, a) and the multipliers together when forces or user
//!   rows read loads or accelerations.
//!
//! [`kkt`] holds the blocks these saddle-point systems share (M, P and Pᵀ).

pub mod accelerations;
pub mod algebraic_loop;
mod continuation;
mod gauss_newton;
mod kkt;
mod orientation;
pub mod placement;
pub mod positions;
pub mod redundancy;
pub mod statics;
pub mod user_unknowns;
pub mod velocities;

pub use accelerations::accelerations;
pub use algebraic_loop::consistent_accelerations;
pub use placement::place_positions;
pub use positions::{Assembly, InitError, assemble_positions};
pub use redundancy::{REDUNDANCY_TOL, redundant_rows};
pub use statics::static_equilibrium;
pub use user_unknowns::user_unknowns;
pub use velocities::{assemble_velocities, assemble_velocities_with};
