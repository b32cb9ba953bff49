//! Mechanics: bodies, markers, joints and forces; mass matrix M, constraints C and their
//! Jacobians, generalized forces Q and the kinematic map T (Eq. 1, 12, 13a–13e).
//! Every element is evaluated generically over [`crate::ad::Real`]; derivatives come
//! from [`crate::ad::Dual`] numbers through the kernels in [`kernels`].
//!
//! Files bottom-up (each uses only files above it):
//! - [`body`]: body coordinates q, u, the map H = T⁻¹ and the reference frames R0.
//! - [`load_components`]: the six components of an element load and their order.
//! - [`joint_coords`]: the free coordinates of each joint, as expressions.
//! - [`measures`]: what a linearization state measures (and a start value sets), data.
//! - [`constraints`]: holonomic constraint elements and velocity initial conditions (data).
//! - [`nonholonomic`]: non-holonomic constraint elements (data).
//! - [`forces`]: force elements (data).
//! - [`user`]: user rows, differentials and variables (data).
//! - [`system`]: the [`System`] struct: elements, row and slot layout, per-simulation state.
//! - [`external`]: layout of the external values [inputs; Z; L] ([`external::ExtLayout`]).
//! - [`from_model`]: [`System::from_model`], step by step.
//! - [`measure_names`]: state names (`hinge.angle`, `arm.x`, `arm.eta2`) and the measures they name.
//! - [`local`]: the element context [`local::LocalCtx`] that element equations read.
//! - [`measure_values`]: the value of a measure in an element context.
//! - [`nonholonomic_equations`]: equations g of the non-holonomic elements, wheel contact.
//! - [`constraint_equations`]: equations C of the constraint elements and velocity ICs.
//! - [`force_laws`]: loads and generalized forces of the force elements.
//! - [`user_rows`]: residuals of the user rows.
//! - [`joint_table`]: the equations of each joint type over its marker frames.
//! - [`joint_gradient`]: C and C_q of a joint between rigid bodies in closed form.
//! - [`joint_hessian`]: its Hessians in closed form.
//! - [`kernels`]: exact derivatives of the element equations (forward-mode AD; rigid
//!   joints through the two files above).
//! - [`loads`]: element loads `fx(name)` … and their exact gradients.
//! - [`external_values`]: [`System::ext`], the external values at a state.
//! - [`components`]: connected components of the mechanism.
//! - [`angles`]: re-based Euler frames and recorded angle branches (what motion changes).
//! - [`mass`]: the mass matrix M(q) (Eq. 1a), body by body.
//! - [`constraint_jacobian`]: the one assembly of C_q, its transpose, the velocity form P
//!   and the filter of redundant rows (Eq. 1b–1c).
//! - [`nonholonomic_jacobian`]: B and γ of the non-holonomic rows (Eq. 7).

pub mod angles;
pub mod body;
pub mod components;
pub mod constraint_equations;
pub mod constraint_jacobian;
pub mod constraints;
pub mod coords;
pub mod external;
pub mod external_values;
pub mod flexible;
pub mod force_laws;
pub mod forces;
pub mod from_model;
pub mod joint_coords;
pub mod joint_gradient;
pub mod joint_hessian;
pub mod joint_table;
pub mod kernels;
pub mod load_components;
pub mod loads;
pub mod local;
pub mod mass;
pub mod measure_names;
pub mod measure_values;
pub mod measures;
pub mod nonholonomic;
pub mod nonholonomic_equations;
pub mod nonholonomic_jacobian;
pub mod system;
pub mod user;
pub mod user_rows;

pub use system::{MarkerGeom, System};
