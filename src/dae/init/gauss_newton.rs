//! The Newton solve behind position assembly: from the current q, corrections of least
//! norm that bring a set of constraint elements to C(q, t) = 0, each from
//! [I C_qᵀ; C_q 0][Δq; κ] = [0; −C] (Gauss–Newton for an underdetermined system).

use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::{ConstraintRows, constraint_rows};
use crate::mechanics::constraints::ConstraintEl;

/// Why a Newton solve stopped without meeting its equations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Failure {
    /// An equation evaluated to NaN or an infinity (at `row`).
    NotFinite { row: usize },
    /// The KKT matrix was singular; `row` held the worst residual, `residual`.
    Singular { row: usize, residual: f64 },
    /// The iterations ran out; `row` held the worst residual, `residual`.
    NoConvergence { row: usize, residual: f64 },
}

/// The rows of a set of elements: those it covers must all be met; those of them not
/// found redundant (rows beyond `sys.m`, exact initial conditions, never are) are the
/// ones the Newton corrections use (a redundant row is met when the others are, or the
/// constraints conflict).
struct ActiveRows {
    /// Number of rows (the largest row + 1 of the set).
    count: usize,
    /// Per row: covered by the set.
    covered: Vec<bool>,
    /// Per row: covered and not redundant.
    active: Vec<bool>,
}

impl ActiveRows {
    /// The enforced rows of `els`.
    fn of(sys: &System, els: &[ConstraintEl]) -> ActiveRows {
        let count = els.iter().map(|e| e.row + e.neq).max().unwrap_or(0);
        let (mut covered, mut active) = (vec![false; count], vec![false; count]);
        for e in els {
            for r in e.row..e.row + e.neq {
                covered[r] = true;
                active[r] = !(r < sys.m && sys.redundant[r]);
            }
        }
        ActiveRows { count, covered, active }
    }

    /// The covered row of the largest |C| and that value.
    fn worst(&self, c: &[f64]) -> (usize, f64) {
        let mut w = (0, 0.0f64);
        for (r, v) in c.iter().enumerate().filter(|(r, _)| self.covered[*r]) {
            if !v.is_finite() {
                return (r, f64::INFINITY);
            }
            if v.abs() > w.1 {
                w = (r, v.abs());
            }
        }
        w
    }
}

/// Newton iterations from `q` on the elements `els` until the worst covered |C| is at
/// most `limit`, at most `max_iterations` corrections. On success q is the solution; on
/// failure q is where the iterations stopped.
#[allow(clippy::too_many_arguments)]
pub(super) fn solve(
    sys: &System,
    els: &[ConstraintEl],
    q: &mut [f64],
    t: f64,
    inputs: &[f64],
    limit: f64,
    max_iterations: usize,
    lu: &mut SparseLu,
) -> Result<(), Failure> {
    let n = sys.n();
    let rows = ActiveRows::of(sys, els);
    for iteration in 0..=max_iterations {
        let cr = constraint_rows(sys, els, q, t, inputs);
        let (row, residual) = rows.worst(&cr.c);
        if !residual.is_finite() {
            return Err(Failure::NotFinite { row });
        }
        if residual <= limit {
            return Ok(());
        }
        if iteration == max_iterations {
            return Err(Failure::NoConvergence { row, residual });
        }
        let mut rhs = vec![0.0; n + rows.count];
        if !correction(n, &rows, &cr, &mut rhs, lu) {
            return Err(Failure::Singular { row, residual });
        }
        for (qi, d) in q.iter_mut().zip(&rhs[..n]) {
            *qi += d;
        }
    }
    unreachable!("the loop returns at its last iteration")
}

/// The least-norm correction Δq (into `rhs[..n]`) of one Newton step; false when the
/// KKT matrix is singular.
fn correction(n: usize, rows: &ActiveRows, cr: &ConstraintRows, rhs: &mut [f64], lu: &mut SparseLu) -> bool {
    let mut kkt = Triplets::new();
    for i in 0..n {
        kkt.push(i, i, 1.0);
    }
    for &(r, g, v) in cr.entries.iter().filter(|e| rows.active[e.0]) {
        kkt.push(n + r, g, v);
        kkt.push(g, n + r, v);
    }
    for r in (0..rows.count).filter(|&r| !rows.active[r]) {
        kkt.push(n + r, n + r, 1.0);
    }
    for (r, v) in cr.c.iter().enumerate() {
        rhs[n + r] = if rows.active[r] { -v } else { 0.0 };
    }
    lu.factor(n + rows.count, &kkt).is_ok() && lu.solve(rhs)
}

/// Newton iterations past convergence, down to round-off: at most `max_iterations`, each
/// kept only while it halves the worst enforced |C|, so that exact conditions are met
/// exactly (not just to the assembly tolerance).
pub(super) fn polish(
    sys: &System,
    els: &[ConstraintEl],
    q: &mut [f64],
    t: f64,
    inputs: &[f64],
    max_iterations: usize,
    lu: &mut SparseLu,
) {
    let n = sys.n();
    let rows = ActiveRows::of(sys, els);
    let mut cr = constraint_rows(sys, els, q, t, inputs);
    let mut residual = rows.worst(&cr.c).1;
    for _ in 0..max_iterations {
        if residual == 0.0 || !residual.is_finite() {
            return;
        }
        let mut rhs = vec![0.0; n + rows.count];
        if !correction(n, &rows, &cr, &mut rhs, lu) {
            return;
        }
        let next: Vec<f64> = q.iter().zip(&rhs[..n]).map(|(a, d)| a + d).collect();
        let next_rows = constraint_rows(sys, els, &next, t, inputs);
        let next_residual = rows.worst(&next_rows.c).1;
        if next_residual.is_nan() || next_residual > 0.5 * residual {
            return;
        }
        q.copy_from_slice(&next);
        (cr, residual) = (next_rows, next_residual);
    }
}
