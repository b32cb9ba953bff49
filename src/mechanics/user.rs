//! User differential equations and variables (seed Eq. 7a–7b) as rows of the DAE over the
//! user unknowns Z = (X, Ẋ, V): Ẋ is an unknown of its own, so explicit (Ẋ = f) and
//! implicit (f(Ẋ, X, …) = 0) differentials and variables (V = g) are all algebraic rows
//! r(q, u, Z, v, t) = 0, and X' = Ẋ is the differential part. Their residuals are in
//! [`super::user_rows`].

use crate::model::expr::Expr;

/// What a user row is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UserKind {
    /// Ẋ_i − f = 0 (Eq. 7a, explicit).
    Explicit,
    /// f(Ẋ, X, …) = 0 (Eq. 7a, implicit).
    Implicit,
    /// g − V_i = 0 (Eq. 7b).
    Variable,
}

/// One user row; row k of `System::user` determines Z entry nx + k (Ẋ_k, then V).
#[derive(Clone, Debug)]
pub struct UserEq {
    /// Name of the differential or variable.
    pub name: String,
    /// What the row is.
    pub kind: UserKind,
    /// Its expression f (or g).
    pub f: Expr,
    /// First angle-unwrapping slot of `f`.
    pub abase: usize,
    /// Bodies whose coordinates `f` reads.
    pub bodies: Vec<usize>,
    /// Entries of the external values it reads (its own unknown included).
    pub ext_refs: Vec<usize>,
    /// Its own unknown in the external values (Ẋ_k or V_k).
    pub own: usize,
}
