//! Consistent accelerations and multipliers when forces or user rows read element loads
//! or accelerations (algebraic loops through the constraint forces or the inertia): u̇,
//! the algebraic user unknowns (Ẋ, V, a) and (λ, ν) solved together by Newton with the
//! exact Jacobian of the equations of motion. Without such a loop it is the linear solve
//! of [`super::accelerations`].

use super::accelerations::accelerations;
use super::user_unknowns::user_unknowns;
use crate::dae::jacobian::jacobian;
use crate::dae::layout::{Layout, Slot};
use crate::dae::residual::{RhsScratch, rhs};
use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::{acceleration_rhs, constraint_jacobian};
use crate::mechanics::mass::body_mass_entries;
use crate::mechanics::nonholonomic_jacobian::{nonholonomic_b, nonholonomic_gamma};

/// Newton iterations before the loop counts as not converging.
const MAX_ITERATIONS: usize = 50;

/// User unknowns, accelerations and multipliers at (q, u, t): the algebraic user unknowns
/// (Ẋ, V) of `z` (in and out; X kept) and returns (u̇, [λ; ν]). When forces or user rows
/// read element loads or accelerations, unknowns (u̇, Ẋ, V, a, λ, ν) and equations (the
/// force balance, the user rows, the acceleration constraints P u̇ + γ = 0 and
/// B u̇ + γ_nh = 0) are solved together.
#[allow(clippy::too_many_arguments)]
pub fn consistent_accelerations(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    z: &mut [f64],
    lu: &mut SparseLu,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    user_unknowns(sys, q, u, None, t, inputs, z)?;
    let ext0 = sys.ext(inputs, z, None, t);
    let (udot0, multipliers0) = accelerations(sys, q, u, t, &ext0, lu)?;
    if sys.load_refs.is_empty() && sys.acc_bodies.is_empty() {
        return Ok((udot0, multipliers0));
    }
    let lay = Layout::of(sys);
    // Start the acceleration unknowns a from the accelerations without the loop.
    lay.set_accelerations(sys, &udot0, z);
    let mut y = lay.assemble(q, u, z, &multipliers0);
    let udot = solve_loop(sys, lay, t, inputs, &mut y, udot0)?;
    z.copy_from_slice(&y[lay.z_range()]);
    Ok((udot, y[lay.multipliers_range()].to_vec()))
}

/// Unknowns and equations of the loop, numbered 0..dim: u̇ (n) and the force balance,
/// then the algebraic user unknowns Z_alg = (Ẋ, V, a) and their rows, then (λ, ν) and the
/// acceleration constraints.
struct LoopIndex {
    lay: Layout,
    /// Number of algebraic user unknowns.
    nalg: usize,
}

impl LoopIndex {
    /// Total number of unknowns (= equations).
    fn dim(&self) -> usize {
        self.lay.n + self.nalg + self.lay.m + self.lay.mn
    }
    /// First acceleration-constraint row (and multiplier column).
    fn constraints(&self) -> usize {
        self.lay.n + self.nalg
    }
    /// The loop column of entry `i` of y (None: held fixed).
    fn col(&self, i: usize) -> Option<usize> {
        let nx = self.lay.nx;
        match self.lay.slot(i) {
            Slot::Z(k) if k >= nx => Some(self.lay.n + k - nx),
            Slot::Lambda(k) => Some(self.constraints() + k),
            Slot::Nu(k) => Some(self.constraints() + self.lay.m + k),
            _ => None,
        }
    }
    /// The loop row of DAE equation `i` (force balance and algebraic user rows; None:
    /// another equation).
    fn row(&self, i: usize) -> Option<usize> {
        let nx = self.lay.nx;
        match self.lay.slot(i) {
            Slot::U(k) => Some(k),
            Slot::Z(k) if k >= nx => Some(self.lay.n + k - nx),
            _ => None,
        }
    }
}

/// Newton on the loop from `y` (q, u held) and u̇ = `udot`: returns u̇, with Z_alg and the
/// multipliers updated in `y`.
fn solve_loop(
    sys: &System,
    lay: Layout,
    t: f64,
    inputs: &[f64],
    y: &mut [f64],
    mut udot: Vec<f64>,
) -> Result<Vec<f64>, String> {
    let ix = LoopIndex { lay, nalg: lay.z_alg_range().len() };
    let (n, dim) = (lay.n, ix.dim());
    let mut nlu = SparseLu::new();
    let scale = 1.0 + udot.iter().chain(&y[lay.multipliers_range()]).fold(0.0f64, |a, v| a.max(v.abs()));
    for _ in 0..MAX_ITERATIONS {
        let (mut r, k) = residual_and_jacobian(sys, &ix, t, inputs, y, &udot);
        let worst = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !worst.is_finite() {
            return Err(format!("the algebraic loop through element loads or accelerations is not finite at t = {t}"));
        }
        if worst <= 1e-12 * scale {
            return Ok(udot);
        }
        nlu.factor(dim, &k).map_err(|e| format!("the algebraic loop at t = {t} is singular ({e})"))?;
        r.iter_mut().for_each(|v| *v = -*v);
        if !nlu.solve(&mut r) {
            return Err(format!("the algebraic loop at t = {t} is singular"));
        }
        for i in 0..n {
            udot[i] += r[i];
        }
        for (i, c) in lay.z_alg_range().enumerate() {
            y[c] += r[n + i];
        }
        for (i, c) in lay.multipliers_range().enumerate() {
            y[c] += r[ix.constraints() + i];
        }
    }
    Err(format!("the algebraic loop through element loads or accelerations does not converge at t = {t}"))
}

/// The loop's residual and Jacobian at (y, u̇): force balance M u̇ − f_u, the algebraic
/// user rows, and the acceleration constraints.
fn residual_and_jacobian(
    sys: &System,
    ix: &LoopIndex,
    t: f64,
    inputs: &[f64],
    y: &[f64],
    udot: &[f64],
) -> (Vec<f64>, Triplets) {
    let lay = ix.lay;
    let mut f = vec![0.0; lay.dim()];
    rhs(sys, lay, t, y, inputs, &mut RhsScratch::default(), &mut f);
    let mut r = vec![0.0; ix.dim()];
    let mut k = Triplets::new();
    // Force balance: M u̇ − f_u = 0; u̇ − a = 0 for the acceleration bodies, whose balance
    // is among the algebraic user rows.
    let q = &y[lay.q_range()];
    for (i, fi) in f[lay.u_range()].iter().enumerate() {
        r[i] = -fi;
    }
    for b in 0..sys.nb() {
        let block: Vec<(usize, usize, f64)> = if sys.acc_bodies.contains(&b) {
            sys.body_dofs(b).into_iter().map(|i| (i, i, 1.0)).collect()
        } else {
            body_mass_entries(sys, b, q)
        };
        for (row, col, v) in block {
            r[row] += v * udot[col];
            k.push(row, col, v);
        }
    }
    for (i, c) in lay.z_alg_range().enumerate() {
        r[lay.n + i] = f[c];
    }
    let mut jt = Triplets::new();
    jacobian(sys, lay, t, y, inputs, &mut jt);
    for (p, &v) in jt.idx.iter().zip(&jt.vals) {
        if let (Some(rr), Some(cc)) = (ix.row(p.row), ix.col(p.col)) {
            k.push(rr, cc, if rr < lay.n { -v } else { v });
        }
    }
    acceleration_constraints(sys, ix, t, inputs, y, udot, &mut r, &mut k);
    (r, k)
}

/// Rows P u̇ + γ = 0 (redundant rows: λ = 0) and B u̇ + γ_nh = 0 of the loop.
#[allow(clippy::too_many_arguments)]
fn acceleration_constraints(
    sys: &System,
    ix: &LoopIndex,
    t: f64,
    inputs: &[f64],
    y: &[f64],
    udot: &[f64],
    r: &mut [f64],
    k: &mut Triplets,
) {
    let lay = ix.lay;
    let (q, u) = (&y[lay.q_range()], &y[lay.u_range()]);
    let ext = lay.ext(sys, inputs, y, t);
    let r0 = ix.constraints();
    let gamma = acceleration_rhs(sys, q, u, t, &ext);
    for (row, g) in gamma.iter().enumerate() {
        if sys.redundant[row] {
            k.push(r0 + row, r0 + row, 1.0);
            r[r0 + row] = y[lay.lam() + row];
        } else {
            r[r0 + row] = *g;
        }
    }
    for &(row, g, p) in &constraint_jacobian(sys, q, t, &ext).velocity_form(q).entries {
        if !sys.redundant[row] {
            k.push(r0 + row, g, p);
            r[r0 + row] += p * udot[g];
        }
    }
    let r0 = r0 + lay.m;
    let (b, _) = nonholonomic_b(sys, q, u, t, &ext);
    for (row, gv) in nonholonomic_gamma(sys, q, u, t, &ext).iter().enumerate() {
        r[r0 + row] = *gv;
    }
    for (row, c, v) in b {
        k.push(r0 + row, c, v);
        r[r0 + row] += v * udot[c];
    }
}
