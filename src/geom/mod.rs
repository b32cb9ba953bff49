//! Small 3-D vectors and matrices generic over [`Real`], so that kinematics written once
//! evaluates with `f64` or with dual numbers. (nalgebra serves the `f64`-only places.)

mod euler;
mod mat3;
mod vec3;

pub use euler::{euler313_from_matrix, omega_to_euler_rates, rot_x, rot_z, rot313, rot313_sc, ypr_from_matrix};
pub use mat3::M3;
pub use vec3::V3;
