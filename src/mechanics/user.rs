//! User differential equations and variables (seed Eq. 7a–7b) as rows of the DAE over the
//! user unknowns Z = (X, Ẋ, V): Ẋ is an unknown of its own, so explicit (Ẋ = f) and
//! implicit (f(Ẋ, X, …) = 0) differentials and variables (V = g) are all algebraic rows
//! r(q, u, Z, v, t) = 0, and X' = Ẋ is the differential part.

use super::body::NQ;
use super::loads::NLOAD;
use super::local::LocalCtx;
use super::system::System;
use crate::ad::Real;
use crate::model::expr::{ElementRef, Expr, deps};

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

/// Entries of the external values (inputs, X, Ẋ, V, accelerations A, element loads L)
/// that the expressions `es` read; `acc_bodies` and `load_refs` list the bodies whose
/// accelerations and the elements whose loads are external values; `body_of` maps markers.
pub fn ext_refs(
    sys_ni: usize,
    nx: usize,
    nv: usize,
    acc_bodies: &[usize],
    load_refs: &[ElementRef],
    body_of: &dyn Fn(usize) -> Option<usize>,
    es: &[&Expr],
) -> Vec<usize> {
    let mut r = Vec::new();
    let a0 = sys_ni + 2 * nx + nv;
    let l0 = a0 + NQ * acc_bodies.len();
    for e in es {
        let d = deps(e);
        if d.level >= 2 {
            for b in d.markers.iter().filter_map(|&m| body_of(m)) {
                if let Some(k) = acc_bodies.iter().position(|&x| x == b) {
                    r.extend((0..NQ).map(|c| a0 + NQ * k + c));
                }
            }
        }
        r.extend(d.inputs.iter().copied());
        r.extend(d.diffs.iter().map(|&i| sys_ni + i));
        r.extend(d.diff_dots.iter().map(|&i| sys_ni + nx + i));
        r.extend(d.variables.iter().map(|&i| sys_ni + 2 * nx + i));
        for l in &d.loads {
            if let Some(k) = load_refs.iter().position(|x| x == l) {
                r.extend((0..NLOAD).map(|c| l0 + NLOAD * k + c));
            }
        }
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
        2 * self.nx + self.nv + NQ * self.acc_bodies.len()
    }
    /// External-value index of the first acceleration component (v̇, then ω̇' in body axes)
    /// of body `b`, if forces or user elements read its accelerations.
    pub fn ext_acc(&self, b: usize) -> Option<usize> {
        self.acc_bodies.iter().position(|&x| x == b).map(|k| self.ni() + 2 * self.nx + self.nv + NQ * k)
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
    /// External-value index of the first load component of `load_refs[k]`.
    pub fn ext_load(&self, k: usize) -> usize {
        self.ni() + self.nz() + NLOAD * k
    }
    /// External-value index of element `e`'s load component `c`, if forces or user
    /// elements read that element's loads.
    pub fn ext_load_of(&self, e: ElementRef, c: usize) -> Option<usize> {
        self.load_refs.iter().position(|x| *x == e).map(|k| self.ext_load(k) + c)
    }
    /// The external values [inputs; Z; L] that element contexts read; the loads L are
    /// evaluated at `state` = (q, u, λ) (see [`super::loads`]); without λ (None) they are 0.
    pub fn ext(&self, inputs: &[f64], z: &[f64], state: Option<(&[f64], &[f64], &[f64])>, t: f64) -> Vec<f64> {
        let mut e = Vec::with_capacity(inputs.len() + z.len() + NLOAD * self.load_refs.len());
        e.extend_from_slice(inputs);
        e.extend_from_slice(z);
        let base = e.clone();
        for &r in &self.load_refs {
            let v = state.and_then(|s| super::loads::load_value(self, r, s, t, &base)).unwrap_or([0.0; NLOAD]);
            e.extend_from_slice(&v);
        }
        e
    }
}
