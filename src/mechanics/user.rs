//! User differential equations and variables (seed Eq. 7a–7b) as rows of the DAE over the
//! user unknowns Z = (X, Ẋ, V): Ẋ is an unknown of its own, so explicit (Ẋ = f) and
//! implicit (f(Ẋ, X, …) = 0) differentials and variables (V = g) are all algebraic rows
//! r(q, u, Z, v, t) = 0, and X' = Ẋ is the differential part.

use super::local::LocalCtx;
use super::system::System;
use crate::ad::Real;
use crate::model::expr::{Expr, deps};

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
    pub name: String,
    pub kind: UserKind,
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

impl UserEq {
    /// The residual r (zero on the solution).
    pub fn residual<T: Real>(&self, ctx: &LocalCtx<T>) -> T {
        let f = ctx.eval_expr(&self.f, self.abase);
        match self.kind {
            UserKind::Explicit => f - ctx.ext_value(self.own),
            UserKind::Implicit => f,
            UserKind::Variable => f - ctx.ext_value(self.own),
        }
    }
}

/// Entries of the external values (inputs, X, Ẋ, V) that the expressions `es` read.
pub fn ext_refs(sys_ni: usize, nx: usize, es: &[&Expr]) -> Vec<usize> {
    let mut r = Vec::new();
    for e in es {
        let d = deps(e);
        r.extend(d.inputs.iter().copied());
        r.extend(d.diffs.iter().map(|&i| sys_ni + i));
        r.extend(d.diff_dots.iter().map(|&i| sys_ni + nx + i));
        r.extend(d.variables.iter().map(|&i| sys_ni + 2 * nx + i));
    }
    r.sort_unstable();
    r.dedup();
    r
}

impl System {
    /// Number of inputs.
    pub fn ni(&self) -> usize {
        self.input_names.len()
    }
    /// Number of user unknowns Z = (X, Ẋ, V).
    pub fn nz(&self) -> usize {
        2 * self.nx + self.nv
    }
    /// External-value index of differential state X_i.
    pub fn ext_diff(&self, i: usize) -> usize {
        self.ni() + i
    }
    /// External-value index of Ẋ_i.
    pub fn ext_diff_dot(&self, i: usize) -> usize {
        self.ni() + self.nx + i
    }
    /// External-value index of variable V_i.
    pub fn ext_variable(&self, i: usize) -> usize {
        self.ni() + 2 * self.nx + i
    }
    /// The external values [inputs; Z] that element contexts read.
    pub fn ext(&self, inputs: &[f64], z: &[f64]) -> Vec<f64> {
        let mut e = Vec::with_capacity(inputs.len() + z.len());
        e.extend_from_slice(inputs);
        e.extend_from_slice(z);
        e
    }
}
