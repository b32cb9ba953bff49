//! The constraint Jacobian, assembled in this one place for every user: the rows C_q of
//! the holonomic constraints (seed Eq. 1b), their velocity form P = C_q H (Eq. 13a,
//! 13d), with C and C_t alongside, the filter that leaves out redundant rows, and the γ
//! of the acceleration constraints (Eq. 1c).
//!
//! Rows are numbered by the elements' `row` fields; every local entry is kept, zeros
//! included, so the sparsity pattern does not change from one point to the next.

use super::body::{NQ, h_angular, h_transpose_times, h_transpose_times_with};
use super::constraints::ConstraintEl;
use super::coords::{gather, global_column, nql, rates};
use super::kernels::{ConstraintFirst, constraint_first_into, constraint_second, dqdot_dq};
use super::system::System;
use crate::geom::M3;

/// Constraint rows of a set of elements at (q, t).
#[derive(Clone, Debug, Default)]
pub struct ConstraintRows {
    /// C of every row.
    pub c: Vec<f64>,
    /// C_t of every row.
    pub ct: Vec<f64>,
    /// Entries (row, global column, value), row by row in element order.
    pub entries: Vec<(usize, usize, f64)>,
    /// Number of body (non-modal) columns, 6 per body: columns from here on are modal
    /// coordinates, whose velocities are their rates (H = I).
    pub body_cols: usize,
}

/// P row of one equation (local coordinates, see [`super::coords`]) from its C_q row:
/// P = C_q H (Eq. 13a); modal columns are unchanged (H = I there).
pub fn p_row(bodies: &[usize], q: &[f64], cq: &[f64]) -> Vec<f64> {
    let mut p = vec![0.0; cq.len()];
    p_row_into(bodies, |b| h_angular(q[NQ * b + 4], q[NQ * b + 5]), cq, &mut p);
    p
}

/// [`p_row`] into `p` (as long as `cq`), `h(b)` giving body b's angular block of H.
pub fn p_row_into(bodies: &[usize], h: impl Fn(usize) -> M3<f64>, cq: &[f64], p: &mut [f64]) {
    p.copy_from_slice(cq);
    for (k, &b) in bodies.iter().enumerate() {
        let r = h_transpose_times_with(&h(b), &cq[NQ * k..NQ * k + NQ]);
        p[NQ * k..NQ * k + NQ].copy_from_slice(&r);
    }
}

/// C_q rows (Eq. 1b) of the elements `els` at (q, t), with C and C_t; `ext` holds the
/// external values.
pub fn constraint_rows(sys: &System, els: &[ConstraintEl], q: &[f64], t: f64, ext: &[f64]) -> ConstraintRows {
    let nrows = els.iter().map(|e| e.row + e.neq).max().unwrap_or(0);
    let body_cols = sys.modal_columns().start;
    let mut out = ConstraintRows { c: vec![0.0; nrows], ct: vec![0.0; nrows], entries: Vec::new(), body_cols };
    let mut f = ConstraintFirst::default();
    for el in els {
        constraint_first_into(sys, el, q, t, ext, None, &mut f);
        let nql = nql(sys, &el.bodies);
        for e in 0..el.neq {
            let row = el.row + e;
            out.c[row] = f.c[e];
            out.ct[row] = f.ct[e];
            let cq = &f.cq[e * nql..(e + 1) * nql];
            out.entries.extend(cq.iter().enumerate().map(|(a, &v)| (row, global_column(sys, &el.bodies, a), v)));
        }
    }
    out
}

/// The C_q rows of the model's holonomic constraints (`sys.constraints`, m rows).
pub fn constraint_jacobian(sys: &System, q: &[f64], t: f64, ext: &[f64]) -> ConstraintRows {
    let mut rows = constraint_rows(sys, &sys.constraints, q, t, ext);
    rows.c.resize(sys.m, 0.0);
    rows.ct.resize(sys.m, 0.0);
    rows
}

/// The independent constraint rows: those not found redundant at initialization
/// (`System::redundant`), numbered compactly in their order. Redundant rows keep λ = 0
/// and leave their equations out (Eq. 34d–e have `count` rows).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IndependentRows {
    /// Compact index of each of the m rows (None: redundant).
    pub of_row: Vec<Option<usize>>,
    /// Number of independent rows (m minus the redundant ones).
    pub count: usize,
}

impl IndependentRows {
    /// The independent rows of `sys`.
    pub fn of(sys: &System) -> IndependentRows {
        let mut count = 0;
        let of_row = sys
            .redundant
            .iter()
            .map(|&r| {
                (!r).then(|| {
                    count += 1;
                    count - 1
                })
            })
            .collect();
        IndependentRows { of_row, count }
    }
}

impl ConstraintRows {
    /// The velocity form P = C_q H (Eq. 13a, 13d) of C_q rows at q: the same rows as a
    /// linear form in the velocities u (C and C_t unchanged).
    pub fn velocity_form(&self, q: &[f64]) -> ConstraintRows {
        let mut entries = Vec::with_capacity(self.entries.len());
        // Every row holds NQ consecutive entries per body it touches, then its modal
        // entries, one each (see `constraint_rows` and `super::coords`).
        let mut i = 0;
        while i < self.entries.len() {
            let (row, c0, v) = self.entries[i];
            if c0 >= self.body_cols {
                entries.push((row, c0, v));
                i += 1;
                continue;
            }
            let chunk = &self.entries[i..i + NQ];
            debug_assert!(chunk.iter().enumerate().all(|(k, e)| e.0 == row && e.1 == c0 + k));
            let cq: [f64; NQ] = std::array::from_fn(|k| chunk[k].2);
            let p = h_transpose_times(&q[c0..c0 + NQ], &cq);
            entries.extend(p.iter().enumerate().map(|(k, &v)| (row, c0 + k, v)));
            i += NQ;
        }
        ConstraintRows { c: self.c.clone(), ct: self.ct.clone(), entries, body_cols: self.body_cols }
    }

    /// The entries of the independent rows, renumbered compactly (see [`IndependentRows`]).
    pub fn independent<'a>(&'a self, rows: &'a IndependentRows) -> impl Iterator<Item = (usize, usize, f64)> + 'a {
        self.entries.iter().filter_map(|&(r, c, v)| rows.of_row.get(r).copied().flatten().map(|k| (k, c, v)))
    }
}

/// γ of the acceleration constraint P u̇ + γ = 0 (Eq. 1c): the part of C̈ free of u̇.
pub fn acceleration_rhs(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let mut gamma = vec![0.0; sys.m];
    for el in &sys.constraints {
        let s = constraint_second(sys, el, q, t, inputs);
        let nql = nql(sys, &el.bodies);
        let k = s.k;
        let ql = gather(sys, &el.bodies, q);
        let ul = gather(sys, &el.bodies, u);
        // z' = (q̇, 1): γ = z'ᵀ ∇²C z' + C_q (∂q̇/∂q) q̇; modal rates are η̇ (H = I).
        let mut zd = rates(el.bodies.len(), &ql, &ul);
        zd.push(1.0);
        let mut extra = vec![0.0; nql];
        for kb in 0..el.bodies.len() {
            let r = NQ * kb..NQ * kb + NQ;
            let dq = dqdot_dq(&ql[r.clone()], &ul[r.clone()]);
            for i in 0..NQ {
                extra[NQ * kb + i] = (0..NQ).map(|c| dq[i * 6 + c] * zd[NQ * kb + c]).sum();
            }
        }
        for e in 0..el.neq {
            let g = &s.grad[e * k..(e + 1) * k];
            let hs = &s.hess[e * k * k..(e + 1) * k * k];
            let mut v = 0.0;
            for a in 0..k {
                for c in 0..k {
                    v += zd[a] * hs[a * k + c] * zd[c];
                }
            }
            v += (0..nql).map(|a| g[a] * extra[a]).sum::<f64>();
            gamma[el.row + e] = v;
        }
    }
    gamma
}
