//! The DAE vector y = [q; u; Z; λ; ν; μ] and where each part lives in it: the one
//! place that knows its offsets.
//!
//! - q (n): coordinates, u (n): velocities (Eq. 12: u = T(q) q̇);
//! - Z = (X, Ẋ, V, a): differential states X (nx), their rates Ẋ (nx), user variables V
//!   (nv) (seed Eq. 7a–7b), and the accelerations a (6 per body whose accelerations
//!   forces or user rows read);
//! - λ (m): multipliers of the holonomic constraints (Eq. 13a), ν (mn): of the
//!   non-holonomic ones, μ (m): of the GGL velocity stabilization (Eq. 13b; 0 on the
//!   solution).

use crate::mechanics::System;
use crate::mechanics::body::NQ;
use std::ops::Range;

/// Index layout of y.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Coordinates (= velocities) n.
    pub n: usize,
    /// Holonomic constraint equations m (multipliers λ and μ).
    pub m: usize,
    /// Differential states X (their rates Ẋ follow them in Z).
    pub nx: usize,
    /// User variables V.
    pub nv: usize,
    /// Non-holonomic equations (multipliers ν).
    pub mn: usize,
    /// Acceleration unknowns a: 6 per acceleration body (`System::acc_bodies`: every
    /// flexible body, and every body whose accelerations forces or user rows read), then
    /// the modal accelerations η̈ of the flexible bodies.
    pub na: usize,
    /// Number of body (non-modal) coordinates: 6 per body; the modal ones follow.
    pub body_cols: usize,
    /// Number of rigid-motion acceleration unknowns: 6 per acceleration body.
    pub acc_rigid: usize,
}

/// What one entry of y is (index within its part).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// q_i.
    Q(usize),
    /// u_i.
    U(usize),
    /// Z_i (X, Ẋ, V, a).
    Z(usize),
    /// λ_i.
    Lambda(usize),
    /// ν_i.
    Nu(usize),
    /// μ_i.
    Mu(usize),
}

impl Layout {
    /// The layout of a system's equations.
    pub fn of(sys: &System) -> Layout {
        let (n, body_cols, acc_rigid) = (sys.n(), sys.modal_columns().start, NQ * sys.acc_bodies.len());
        Layout { n, m: sys.m, nx: sys.nx, nv: sys.nv, mn: sys.mn, na: acc_rigid + n - body_cols, body_cols, acc_rigid }
    }
    /// Number of user unknowns Z = (X, Ẋ, V, a).
    pub fn nz(&self) -> usize {
        2 * self.nx + self.nv + self.na
    }
    /// Total dimension 2n + nz + 2m + mn.
    pub fn dim(&self) -> usize {
        2 * self.n + self.nz() + 2 * self.m + self.mn
    }
    /// Offset of u.
    pub fn u(&self) -> usize {
        self.n
    }
    /// Offset of Z.
    pub fn z(&self) -> usize {
        2 * self.n
    }
    /// Offset of the acceleration unknowns a (inside Z).
    pub fn acc(&self) -> usize {
        self.z() + 2 * self.nx + self.nv
    }
    /// Copy the accelerations `udot` (n, global) of the bodies with acceleration unknowns
    /// into their entries of Z (`z`, not y).
    pub fn set_accelerations(&self, sys: &System, udot: &[f64], z: &mut [f64]) {
        for &b in &sys.acc_bodies {
            for g in sys.body_dofs(b) {
                z[self.acc_row(&sys.acc_bodies, g).expect("an acceleration body") - self.z()] = udot[g];
            }
        }
    }
    /// Offset of λ.
    pub fn lam(&self) -> usize {
        self.z() + self.nz()
    }
    /// Offset of ν (after λ).
    pub fn nu(&self) -> usize {
        self.lam() + self.m
    }
    /// Offset of μ.
    pub fn mu(&self) -> usize {
        self.nu() + self.mn
    }
    /// Where q lives.
    pub fn q_range(&self) -> Range<usize> {
        0..self.n
    }
    /// Where u lives.
    pub fn u_range(&self) -> Range<usize> {
        self.u()..self.u() + self.n
    }
    /// Where Z = (X, Ẋ, V, a) lives.
    pub fn z_range(&self) -> Range<usize> {
        self.z()..self.z() + self.nz()
    }
    /// Where X lives (the differential part of Z).
    pub fn x_range(&self) -> Range<usize> {
        self.z()..self.z() + self.nx
    }
    /// Where Ẋ lives.
    pub fn xdot_range(&self) -> Range<usize> {
        self.z() + self.nx..self.z() + 2 * self.nx
    }
    /// Where the algebraic user unknowns (Ẋ, V, a) live: Z after X, in the order of the
    /// user rows (`System::user`) followed by the acceleration bodies' force balances.
    pub fn z_alg_range(&self) -> Range<usize> {
        self.z() + self.nx..self.z() + self.nz()
    }
    /// Where V lives.
    pub fn v_range(&self) -> Range<usize> {
        self.z() + 2 * self.nx..self.acc()
    }
    /// Where a lives.
    pub fn acc_range(&self) -> Range<usize> {
        self.acc()..self.acc() + self.na
    }
    /// Where λ lives.
    pub fn lam_range(&self) -> Range<usize> {
        self.lam()..self.lam() + self.m
    }
    /// Where λ and then ν live (contiguous: the multipliers of the acceleration solve).
    pub fn multipliers_range(&self) -> Range<usize> {
        self.lam()..self.lam() + self.m + self.mn
    }
    /// Where ν lives.
    pub fn nu_range(&self) -> Range<usize> {
        self.nu()..self.nu() + self.mn
    }
    /// Where μ lives.
    pub fn mu_range(&self) -> Range<usize> {
        self.mu()..self.mu() + self.m
    }
    /// The groups of unknowns the block LU eliminates together (`dae::block_lu`), one
    /// id per entry of y: each body's coordinates, velocities and acceleration unknowns
    /// (modal ones included); each constraint element's λ and μ; each non-holonomic
    /// element's ν; the user unknowns X, Ẋ, V together.
    pub fn groups(&self, sys: &System) -> Vec<usize> {
        let mut g = vec![usize::MAX; self.dim()];
        let mut next = 0;
        for b in 0..sys.nb() {
            for d in sys.body_dofs_iter(b) {
                g[d] = next;
                g[self.u() + d] = next;
                if let Some(r) = self.acc_row(&sys.acc_bodies, d) {
                    g[r] = next;
                }
            }
            next += 1;
        }
        for c in sys.constraints.iter().filter(|c| c.row + c.neq <= self.m) {
            for r in c.row..c.row + c.neq {
                g[self.lam() + r] = next;
                g[self.mu() + r] = next;
            }
            next += 1;
        }
        for e in sys.nonholonomic.iter().filter(|e| e.row + e.neq <= self.mn) {
            for r in e.row..e.row + e.neq {
                g[self.nu() + r] = next;
            }
            next += 1;
        }
        for v in g.iter_mut().filter(|v| **v == usize::MAX) {
            *v = next;
        }
        g
    }
    /// What entry `i` of y is.
    pub fn slot(&self, i: usize) -> Slot {
        if i < self.u() {
            Slot::Q(i)
        } else if i < self.z() {
            Slot::U(i - self.u())
        } else if i < self.lam() {
            Slot::Z(i - self.z())
        } else if i < self.nu() {
            Slot::Lambda(i - self.lam())
        } else if i < self.mu() {
            Slot::Nu(i - self.nu())
        } else {
            Slot::Mu(i - self.mu())
        }
    }
    /// The row of f that holds the force balance of coordinate `g`: its u row, or for
    /// a body with acceleration unknowns (`acc_bodies`) its algebraic row
    /// M a = Q − Pᵀλ − Bᵀν among the user rows.
    pub fn force_row(&self, acc_bodies: &[usize], g: usize) -> usize {
        self.acc_row(acc_bodies, g).unwrap_or(self.u() + g)
    }
    /// Where in y the acceleration unknown of velocity `g` lives, if its body has
    /// acceleration unknowns: six per acceleration body in `acc_bodies` order, then the
    /// modal accelerations (every modal coordinate's body has them).
    pub fn acc_row(&self, acc_bodies: &[usize], g: usize) -> Option<usize> {
        if g >= self.body_cols {
            return Some(self.acc() + self.acc_rigid + g - self.body_cols);
        }
        acc_bodies.iter().position(|&b| b == g / NQ).map(|k| self.acc() + NQ * k + g % NQ)
    }
    /// A state vector y from its parts (μ = 0); `multipliers` holds λ then ν.
    pub fn assemble(&self, q: &[f64], u: &[f64], z: &[f64], multipliers: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.dim()];
        y[self.q_range()].copy_from_slice(q);
        y[self.u_range()].copy_from_slice(u);
        y[self.z_range()].copy_from_slice(z);
        y[self.lam()..self.lam() + multipliers.len()].copy_from_slice(multipliers);
        y
    }
    /// The external values [inputs; Z; L] of state `y` at time `t` (see [`System::ext`]).
    pub fn ext(&self, sys: &System, inputs: &[f64], y: &[f64], t: f64) -> Vec<f64> {
        let mut e = Vec::new();
        self.ext_into(sys, inputs, y, t, &mut e);
        e
    }
    /// [`Layout::ext`] into `e` (its capacity reused).
    pub fn ext_into(&self, sys: &System, inputs: &[f64], y: &[f64], t: f64, e: &mut Vec<f64>) {
        let state = (&y[self.q_range()], &y[self.u_range()], &y[self.lam_range()]);
        sys.ext_into(inputs, &y[self.z_range()], Some(state), t, e);
    }
}
