//! Exact linearization of the multibody DAE (Negrut & Ortiz): state selection (Eq. 30–33),
//! the augmented sensitivity system (Eq. 34, Table 1) solved with one sparse LU for all
//! right-hand sides, and the eigenvalue table (Tables 2–4).

pub mod augmented;
pub mod eigen;
pub mod jets;
pub mod outputs;
pub mod select;
pub mod states;

pub use augmented::{Linearization, linearize};
pub use select::{Selection, select_states};
