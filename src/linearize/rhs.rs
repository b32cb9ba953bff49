//! The right-hand sides of the augmented system (seed Eq. 34, Table 1): one per state,
//! ∂/∂S̄ (34k), ∂/∂W̄ (34j), ∂/∂X̄, then one per input, ∂/∂v (34a: +∂Q/∂v; user rows:
//! −∂r/∂v). Their solutions are the columns of A and B (Eq. 36).

use super::assemble::equation_of;
use super::eq34::{Eq34, Equation};
use super::operating_point::OperatingPoint;
use crate::mechanics::coords::global_column;
use crate::mechanics::kernels::{force_ext_jacobian, user_jacobian};

/// What a right-hand side (a column of A or B) differentiates with respect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Column {
    /// Position state S_i.
    S(usize),
    /// Velocity state W_i.
    W(usize),
    /// Differential state X_i.
    X(usize),
    /// Input v_i.
    Input(usize),
}

impl Column {
    /// Whether positions and velocities can depend on it: on a state, yes; on an input,
    /// no (Eq. 34d–f, h, j–k hold no input terms).
    pub fn kinematic(self) -> bool {
        !matches!(self, Column::Input(_))
    }
}

/// The right-hand sides at an operating point.
pub(super) struct RightHandSides {
    eq: Eq34,
    /// Per input: the sparse ∂/∂v column (row of Eq. 34, value).
    by_input: Vec<Vec<(usize, f64)>>,
}

impl RightHandSides {
    /// The right-hand sides at `p`.
    pub fn of(p: &OperatingPoint) -> RightHandSides {
        let (sys, ni) = (p.sys, p.ni());
        let mut by_input: Vec<Vec<(usize, f64)>> = vec![Vec::new(); ni];
        // Row r of f (sign s in Eq. 34) depends on v by ∂f_r/∂v: the right-hand side is −s ∂f_r/∂v.
        let mut push = |v: usize, r: usize, val: f64| {
            if let Some((row, sign)) = equation_of(p, r) {
                by_input[v].push((row, -sign * val));
            }
        };
        for el in &sys.forces {
            for (v, col) in force_ext_jacobian(sys, el, &p.q, &p.u, p.t, &p.ext) {
                if v < ni {
                    for (a, &val) in col.iter().enumerate() {
                        push(v, p.lay.force_row(&sys.acc_bodies, global_column(sys, &el.bodies, a)), val);
                    }
                }
            }
        }
        let r0 = p.lay.z_alg_range().start;
        for (r, ue) in sys.user.iter().enumerate() {
            for (v, val) in user_jacobian(sys, ue, &p.q, &p.u, p.t, &p.ext).dext {
                if v < ni {
                    push(v, r0 + r, val);
                }
            }
        }
        RightHandSides { eq: p.eq, by_input }
    }

    /// Solution column `col` (states S, W, X, then inputs) as a [`Column`].
    pub fn column(&self, col: usize) -> Column {
        let (s0, s1, ns) = (self.eq.s0, self.eq.s1, self.eq.ns());
        if col < s0 {
            Column::S(col)
        } else if col < s0 + s1 {
            Column::W(col - s0)
        } else if col < ns {
            Column::X(col - s0 - s1)
        } else {
            Column::Input(col - ns)
        }
    }

    /// Right-hand side `col` applied to `z` (its dot product with `z`): a solution of
    /// the transposed system for a kept row gives that row's entry of every column so.
    pub fn apply(&self, col: Column, z: &[f64]) -> f64 {
        match col {
            Column::S(i) => z[self.eq.row_at(Equation::Eq34k, i)],
            Column::W(i) => z[self.eq.row_at(Equation::Eq34j, i)],
            Column::X(i) => z[self.eq.row_at(Equation::XBar, i)],
            Column::Input(v) => self.by_input[v].iter().map(|&(r, val)| val * z[r]).sum(),
        }
    }

    /// Write right-hand side `col` into the zeroed `b`.
    pub fn fill(&self, col: Column, b: &mut [f64]) {
        self.add(col, 1.0, b);
    }

    /// Add `w` times right-hand side `col` to `b` (a combination of columns: one solve
    /// gives the same combination of their solutions).
    pub fn add(&self, col: Column, w: f64, b: &mut [f64]) {
        match col {
            Column::S(i) => b[self.eq.row_at(Equation::Eq34k, i)] += w,
            Column::W(i) => b[self.eq.row_at(Equation::Eq34j, i)] += w,
            Column::X(i) => b[self.eq.row_at(Equation::XBar, i)] += w,
            Column::Input(v) => {
                for &(r, val) in &self.by_input[v] {
                    b[r] += w * val;
                }
            }
        }
    }
}
