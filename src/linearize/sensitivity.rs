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
        self.keep_as(col.kinematic(), x)
    }

    /// [`Sensitivities::keep`] for a solution of state columns (`kinematic`) or input
    /// columns, or of a combination of columns of one kind.
    pub fn keep_as(&self, kinematic: bool, x: &[f64]) -> Vec<f64> {
        let eq = &self.eq;
        let mut keep = Vec::with_capacity(eq.ns() + self.grads.len());
        keep.extend_from_slice(&x[eq.col(Unknown::SDot)..][..eq.s0]);
        keep.extend_from_slice(&x[eq.col(Unknown::WDot)..][..eq.s1]);
        let xdot = eq.col(Unknown::Z) + eq.nx; // Z = (X, Ẋ, V, a)
        keep.extend_from_slice(&x[xdot..xdot + eq.nx]);
        keep.extend(self.grads.iter().map(|g| self.sensitivity(g, x, kinematic)));
        keep
    }

    /// An output's sensitivity in solution `x`. Positions and velocities do not depend on
    /// the inputs (`kinematic` false), so input columns take no q and u terms: they are
    /// zero and would carry only the LU's round-off.
    fn sensitivity(&self, g: &OutputGradient, x: &[f64], kinematic: bool) -> f64 {
        let mut v = 0.0;
        self.coefficients(g, kinematic, &mut |at, w| v += w * at.map_or(0.0, |i| x[i]));
        v
    }

    /// The output sensitivity as a linear functional of the solution: calls `f(unknown,
    /// weight)` for each of its terms, `None` for a term that is zero in this column kind
    /// (its weight still counts: a non-finite one makes the derivative non-finite).
    fn coefficients(&self, g: &OutputGradient, kinematic: bool, f: &mut dyn FnMut(Option<usize>, f64)) {
        let eq = &self.eq;
        let nql = g.cols.len();
        for (a, &gi) in g.cols.iter().enumerate() {
            if kinematic {
                f(Some(eq.at(Unknown::Q, gi)), g.dz[a]);
                f(Some(eq.at(Unknown::U, gi)), g.dz[nql + a]);
            }
            f(Some(eq.at(Unknown::UDot, gi)), g.dz[2 * nql + a]);
        }
        for &(row, w) in &g.dlam {
            f(Some(eq.at(Unknown::Lambda, row)), w);
        }
        for (e, &dy) in g.dv.iter().enumerate().skip(self.xl.ni) {
            if dy == 0.0 {
                continue;
            }
            match self.xl.entry(e) {
                ExtEntry::Z(i) => f(Some(eq.at(Unknown::Z, i)), dy),
                ExtEntry::Load(k, c) => {
                    let Some(lg) = self.loads[k].as_ref() else { continue };
                    lg.terms(c, |term, d| f(self.term(term, kinematic), dy * d));
                }
                ExtEntry::Input(_) => unreachable!("inputs are skipped"),
            }
        }
    }

    /// The unknown of one term of a load gradient (None: zero in this column kind).
    fn term(&self, term: LoadTerm, kinematic: bool) -> Option<usize> {
        let eq = &self.eq;
        match term {
            LoadTerm::Q(i) if kinematic => Some(eq.at(Unknown::Q, i)),
            LoadTerm::U(i) if kinematic => Some(eq.at(Unknown::U, i)),
            LoadTerm::Lam(r) => Some(eq.at(Unknown::Lambda, r)),
            LoadTerm::Ext(e) if self.xl.z_range().contains(&e) => Some(eq.at(Unknown::Z, e - self.xl.ni)),
            _ => None,
        }
    }

    /// The functional that gives kept row `r` (as [`Sensitivities::keep`] orders them:
    /// Ṡ, Ẇ, Ẋ, outputs) of a solution of a column of kind `kinematic`, as a dense vector
    /// over the unknowns: the right-hand side of the transposed Eq. 34 that yields that
    /// row for every column at once. Only for a row whose weights are finite
    /// ([`Sensitivities::row_finite`]).
    pub fn functional(&self, r: usize, kinematic: bool, g: &mut [f64]) {
        self.add_functional(r, kinematic, 1.0, g);
    }

    /// Add `w` times kept row `r`'s functional ([`Sensitivities::functional`]) to `g`: a
    /// combination of rows, which one transposed solve yields for every column at once.
    pub fn add_functional(&self, r: usize, kinematic: bool, w: f64, g: &mut [f64]) {
        let eq = &self.eq;
        let (s0, s1, nx) = (eq.s0, eq.s1, eq.nx);
        if r < s0 {
            g[eq.at(Unknown::SDot, r)] += w;
        } else if r < s0 + s1 {
            g[eq.at(Unknown::WDot, r - s0)] += w;
        } else if r < s0 + s1 + nx {
            g[eq.col(Unknown::Z) + nx + (r - s0 - s1)] += w; // Z = (X, Ẋ, V, a)
        } else {
            self.coefficients(&self.grads[r - s0 - s1 - nx], kinematic, &mut |at, c| {
                if let Some(i) = at {
                    g[i] += w * c;
                }
            });
        }
    }

    /// Whether every weight of kept row `r`'s functional is finite (else that row of C or
    /// D is not finite, whatever the solution).
    pub fn row_finite(&self, r: usize, kinematic: bool) -> bool {
        let ns = self.eq.ns();
        let mut finite = true;
        if r >= ns {
            self.coefficients(&self.grads[r - ns], kinematic, &mut |_, w| finite &= w.is_finite());
        }
        finite
    }
}
