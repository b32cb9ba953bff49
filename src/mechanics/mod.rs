//! Mechanics: bodies, markers, joints and forces; mass matrix M, constraints C and their
//! Jacobians, generalized forces Q and the kinematic map T (Eq. 1, 12, 13a–13e).
//! Every element is evaluated generically over [`crate::ad::Real`]; derivatives come
//! from [`crate::ad::Dual`] numbers through the kernels in [`kernels`].

pub mod body;
pub mod components;
pub mod constraint_jacobian;
pub mod constraints;
pub mod forces;
pub mod joint_coords;
pub mod kernels;
pub mod loads;
pub mod local;
pub mod mass;
pub mod nonholonomic;
pub mod nonholonomic_jacobian;
pub mod system;
pub mod user;

pub use system::{MarkerGeom, System};
