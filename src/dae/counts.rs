//! Honest equation counts of an assembled model: holonomic equations C(q, t) = 0, how
//! many are independent at the assembled configuration (the rank of C_q) and which are
//! redundant; at velocity level the non-holonomic rows g = B u + b that are independent
//! of the velocity form P u of the holonomic ones. Degrees of freedom are n − rank C_q
//! (positions) and that minus the independent non-holonomic rows (velocities).

use super::init::REDUNDANCY_TOL;
use super::rank::full_pivot;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::{IndependentRows, constraint_jacobian};
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;

/// The counts, with the redundant rows named by element.
#[derive(Clone, Debug, PartialEq)]
pub struct Counts {
    /// Coordinates n.
    pub coordinates: usize,
    /// Holonomic equations m.
    pub equations: usize,
    /// Rank of C_q at the assembled configuration.
    pub independent: usize,
    /// ("kind 'name'" of the element, number of its equations found redundant), in model order.
    pub redundant: Vec<(String, usize)>,
    /// Non-holonomic equations.
    pub nonholonomic: usize,
    /// Of those, independent of each other and of the holonomic velocity rows.
    pub nonholonomic_independent: usize,
}

impl Counts {
    /// Position-level degrees of freedom n − rank C_q.
    pub fn dof(&self) -> usize {
        self.coordinates - self.independent
    }

    /// Velocity-level degrees of freedom.
    pub fn velocity_dof(&self) -> usize {
        self.dof() - self.nonholonomic_independent
    }
}

/// Counts at (q, u, t); `sys.redundant` must hold the redundancy found at initialization
/// (Simulator::new), `inputs` the input values and `ext` the external vector.
pub fn counts(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64], ext: &[f64]) -> Counts {
    let n = sys.n();
    let redundant = sys
        .constraints
        .iter()
        .map(|el| (el, (0..el.neq).filter(|&e| sys.redundant[el.row + e]).count()))
        .filter(|&(_, k)| k > 0)
        .map(|(el, k)| (format!("{} '{}'", el.tag, el.name), k))
        .collect();
    // Pᵀ of the independent rows, then Bᵀ: (coordinate, column, value).
    let rows = IndependentRows::of(sys);
    let p = constraint_jacobian(sys, q, t, inputs).velocity_form(q);
    let mut pt: Vec<(usize, usize, f64)> = p.independent(&rows).map(|(r, c, v)| (c, r, v)).collect();
    let independent = rows.count;
    let mut nh_independent = 0;
    if sys.mn > 0 {
        let (b, _) = nonholonomic_b(sys, q, u, t, ext);
        pt.extend(b.into_iter().map(|(r, c, v)| (c, independent + r, v)));
        let total = independent + sys.mn;
        nh_independent = match full_pivot(n, total, pt, REDUNDANCY_TOL, 0.0) {
            Ok(p) => p.pivoted_cols(total)[independent..].iter().filter(|&&x| x).count(),
            Err(_) => sys.mn,
        };
    }
    Counts {
        coordinates: n,
        equations: sys.m,
        independent,
        redundant,
        nonholonomic: sys.mn,
        nonholonomic_independent: nh_independent,
    }
}
