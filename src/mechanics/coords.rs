//! The coordinates of the system and of one element, the one place that maps between
//! them.
//!
//! Global q (and u): six per body, [r; ψ θ φ] ([v; ω']), in body order, then the modal
//! coordinates η (η̇) of each flexible body, in body order ([`System::modal_range`]).
//! An element touching `bodies` sees its local coordinates in the same pattern: six per
//! body it touches (in its order), then the modal coordinates of those of them that are
//! flexible. A rigid element's local block of body k is `6k..6k + 6` either way.

use super::body::{NQ, qdot};
use super::system::System;
use std::ops::Range;

/// Number of local coordinates of an element touching `bodies`.
pub fn nql(sys: &System, bodies: &[usize]) -> usize {
    NQ * bodies.len() + bodies.iter().map(|&b| sys.modal_range(b).len()).sum::<usize>()
}

/// The global column of every local coordinate of an element touching `bodies`.
pub fn local_columns(sys: &System, bodies: &[usize]) -> Vec<usize> {
    columns(sys, bodies).collect()
}

/// [`local_columns`] into `out` (its capacity reused).
pub fn local_columns_into(sys: &System, bodies: &[usize], out: &mut Vec<usize>) {
    out.clear();
    out.extend(columns(sys, bodies));
}

/// The global columns of `bodies`' local coordinates, in local order.
fn columns<'a>(sys: &'a System, bodies: &'a [usize]) -> impl Iterator<Item = usize> + 'a {
    let rigid = bodies.iter().flat_map(|&b| NQ * b..NQ * b + NQ);
    rigid.chain(bodies.iter().flat_map(|&b| sys.modal_range(b)))
}

/// Global column of local coordinate `a` of an element touching `bodies`.
pub fn global_column(sys: &System, bodies: &[usize], a: usize) -> usize {
    if a < NQ * bodies.len() {
        return NQ * bodies[a / NQ] + a % NQ;
    }
    let mut r = a - NQ * bodies.len();
    for &b in bodies {
        let m = sys.modal_range(b);
        if r < m.len() {
            return m.start + r;
        }
        r -= m.len();
    }
    panic!("local coordinate {a} beyond the {} of bodies {bodies:?}", nql(sys, bodies))
}

/// The local coordinates of an element touching `bodies`, gathered from a global vector.
pub fn gather(sys: &System, bodies: &[usize], x: &[f64]) -> Vec<f64> {
    columns(sys, bodies).map(|g| x[g]).collect()
}

/// [`gather`] into `out` (its capacity reused).
pub fn gather_into(sys: &System, bodies: &[usize], x: &[f64], out: &mut Vec<f64>) {
    out.clear();
    out.extend(columns(sys, bodies).map(|g| x[g]));
}

/// Where local body `k`'s modal coordinates sit among an element's local coordinates.
pub fn local_modal_range(sys: &System, bodies: &[usize], k: usize) -> Range<usize> {
    let start = NQ * bodies.len() + bodies[..k].iter().map(|&b| sys.modal_range(b).len()).sum::<usize>();
    start..start + sys.modal_range(bodies[k]).len()
}

/// q̇ of coordinates `q` with velocities `u` in this layout, global or an element's local
/// one with `nbodies` bodies: H(q_b) u_b for each body's six, then the modal coordinates'
/// rates, which are their velocities (H = I there).
pub fn rates(nbodies: usize, q: &[f64], u: &[f64]) -> Vec<f64> {
    let mut qd = Vec::new();
    rates_into(nbodies, q, u, &mut qd);
    qd
}

/// [`rates`] into `qd` (its capacity reused).
pub fn rates_into(nbodies: usize, q: &[f64], u: &[f64], qd: &mut Vec<f64>) {
    qd.clear();
    qd.extend_from_slice(u);
    for b in 0..nbodies {
        let r = NQ * b..NQ * b + NQ;
        qd[r.clone()].copy_from_slice(&qdot(&q[r.clone()], &u[r]));
    }
}
