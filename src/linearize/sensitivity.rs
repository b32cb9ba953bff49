//! What is kept of each solution of the augmented system (seed Eq. 34): Ṡ, Ẇ, Ẋ (a
//! column of A or B, Eq. 36) and the outputs' sensitivities (a column of C or D without
//! the direct ∂y/∂v), by the chain rule through the q, u, u̇, λ and Z unknowns.

use super::eq34::{Eq34, Unknown};
use super::operating_point::OperatingPoint;
use super::outputs::{OutputGradient, output_gradient};
use super::rhs::Column;
use crate::mechanics::external::{ExtEntry, ExtLayout};
use crate::mechanics::loads::{LoadGradient, LoadTerm, load_gradient};

/// The outputs' gradients at an operating point, and what to keep of a solution.
pub(super) struct Sensitivities {
    eq: Eq34,
    xl: ExtLayout,
    /// One per output.
    grads: Vec<OutputGradient>,
    /// Exact gradients of the loads that forces and user rows read (external values),
    /// for outputs that depend on them indirectly (e.g. the load of a force that reads a
    /// load); one per `System::load_refs`.
    loads: Vec<Option<LoadGradient>>,
}

impl Sensitivities {
    /// The gradients at `p`.
    pub fn of(p: &OperatingPoint) -> Sensitivities {
        let sys = p.sys;
        let grads = sys.outputs.iter().zip(&sys.output_bases).map(|(e, &b)| output_gradient(sys, e, b, p.point()));
        let xl = sys.ext_layout();
        let state = (&p.q[..], &p.u[..], &p.lam[..sys.m]);
        let end = xl.z_range().end;
        let loads = sys.load_refs.iter().map(|&r| load_gradient(sys, r, state, p.t, &p.ext[..end])).collect();
        Sensitivities { eq: p.eq, xl, grads: grads.collect(), loads }
    }

    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.grads.len()
    }

    /// The direct ∂y_o/∂v_i (the part of D not through the unknowns).
    pub fn direct(&self, o: usize, i: usize) -> f64 {
        self.grads[o].dv[self.xl.input(i)]
    }

    /// Kept of solution `x` of right-hand side `col`: Ṡ, Ẇ, Ẋ, then each output's
    /// sensitivity.
    pub fn keep(&self, col: Column, x: &[f64]) -> Vec<f64> {
        let eq = &self.eq;
        let mut keep = Vec::with_capacity(eq.ns() + self.grads.len());
        keep.extend_from_slice(&x[eq.col(Unknown::SDot)..][..eq.s0]);
        keep.extend_from_slice(&x[eq.col(Unknown::WDot)..][..eq.s1]);
        let xdot = eq.col(Unknown::Z) + eq.nx; // Z = (X, Ẋ, V, a)
        keep.extend_from_slice(&x[xdot..xdot + eq.nx]);
        keep.extend(self.grads.iter().map(|g| self.sensitivity(g, x, col.kinematic())));
        keep
    }

    /// An output's sensitivity in solution `x`. Positions and velocities do not depend on
    /// the inputs (`kinematic` false), so input columns take no q and u terms: they are
    /// zero and would carry only the LU's round-off.
    fn sensitivity(&self, g: &OutputGradient, x: &[f64], kinematic: bool) -> f64 {
        let eq = &self.eq;
        let nql = g.cols.len();
        let mut v = 0.0;
        for (a, &gi) in g.cols.iter().enumerate() {
            if kinematic {
                v += g.dz[a] * x[eq.at(Unknown::Q, gi)] + g.dz[nql + a] * x[eq.at(Unknown::U, gi)];
            }
            v += g.dz[2 * nql + a] * x[eq.at(Unknown::UDot, gi)];
        }
        for &(row, w) in &g.dlam {
            v += w * x[eq.at(Unknown::Lambda, row)];
        }
        for (e, &dy) in g.dv.iter().enumerate().skip(self.xl.ni) {
            if dy == 0.0 {
                continue;
            }
            match self.xl.entry(e) {
                ExtEntry::Z(i) => v += dy * x[eq.at(Unknown::Z, i)],
                ExtEntry::Load(k, c) => {
                    let Some(lg) = self.loads[k].as_ref() else { continue };
                    lg.terms(c, |term, d| v += dy * d * self.term(term, x, kinematic));
                }
                ExtEntry::Input(_) => unreachable!("inputs are skipped"),
            }
        }
        v
    }

    /// The solution's entry for one term of a load gradient.
    fn term(&self, term: LoadTerm, x: &[f64], kinematic: bool) -> f64 {
        let eq = &self.eq;
        match term {
            LoadTerm::Q(i) if kinematic => x[eq.at(Unknown::Q, i)],
            LoadTerm::U(i) if kinematic => x[eq.at(Unknown::U, i)],
            LoadTerm::Lam(r) => x[eq.at(Unknown::Lambda, r)],
            LoadTerm::Ext(e) if self.xl.z_range().contains(&e) => x[eq.at(Unknown::Z, e - self.xl.ni)],
            _ => 0.0,
        }
    }
}
