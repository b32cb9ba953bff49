//! The operating point of a linearization (q, u, u̇, λ, t and the external values) with
//! the layouts of the systems it reads: the DAE's ([`Layout`]) and Eq. 34's ([`Eq34`]).

use super::eq34::Eq34;
use super::select::Selection;
use crate::dae::equations::Layout;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::IndependentRows;

/// The operating point of a linearization, and the layouts of the systems it reads.
pub struct OperatingPoint<'a> {
    /// The mechanical system.
    pub sys: &'a System,
    /// The linearization states.
    pub sel: &'a Selection,
    /// Layout of Eq. 34.
    pub eq: Eq34,
    /// Layout of the DAE, whose exact Jacobian gives most rows of Eq. 34.
    pub lay: Layout,
    /// The independent constraint rows (those of Eq. 34d–e).
    pub rows: IndependentRows,
    /// Coordinates q.
    pub q: Vec<f64>,
    /// Velocities u.
    pub u: Vec<f64>,
    /// Accelerations u̇.
    pub udot: Vec<f64>,
    /// λ, then ν.
    pub lam: Vec<f64>,
    /// Time.
    pub t: f64,
    /// External values [inputs; Z; L] (see [`crate::mechanics::external::ExtLayout`]).
    pub ext: Vec<f64>,
}

impl OperatingPoint<'_> {
    /// Number of inputs v.
    pub fn ni(&self) -> usize {
        self.sys.ni()
    }

    /// The operating point as the output gradients take it.
    pub fn point(&self) -> super::outputs::Point<'_> {
        let (q, u, udot, lam) = (&self.q[..], &self.u[..], &self.udot[..], &self.lam[..]);
        super::outputs::Point { q, u, udot, lam, t: self.t, inputs: &self.ext }
    }
}
