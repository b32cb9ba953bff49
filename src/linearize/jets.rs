//! Position-level functions g(q, t) (constraints, linearization states) with their first
//! and second time derivatives along the motion, ġ(q, u, t) and g̈(q, u, u̇, t), and the
//! exact gradients of all three with respect to the local q, u, u̇ — the rows of Eq. 34c–e
//! and 34f, h, i.
//!
//! One evaluation does it: the coordinates are time jets q + τ q̇ + τ²/2 q̈ written as
//! nested dual numbers (q̇ = H u, q̈ = d(Hu)/dt), whose base scalar is itself a dual
//! number seeded on (q, u, u̇, t).

use crate::ad::chunked::{by_width, seed, seed_one};
use crate::ad::{Dual, Real};
use crate::mechanics::System;
use crate::mechanics::body::{NQ, qdot};
use crate::mechanics::constraints::ConstraintEl;
use crate::mechanics::coords::{gather, nql};
use crate::mechanics::local::LocalCtx;
use std::ops::Range;

/// A function of body poses and time, evaluated generically.
pub trait PositionFn {
    /// Bodies it depends on (global indices).
    fn bodies(&self) -> &[usize];
    /// Number of components.
    fn components(&self) -> usize;
    /// Evaluate into `out`.
    fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]);
    /// Whether it reads velocities (a velocity-level function w(q, u, t): its jet gives w
    /// and ẇ exactly; the second derivative is not available and reads as if ü = 0).
    fn reads_velocities(&self) -> bool {
        false
    }
}

impl PositionFn for crate::mechanics::nonholonomic::NonholonomicEl {
    fn bodies(&self) -> &[usize] {
        &self.bodies
    }
    fn components(&self) -> usize {
        self.neq
    }
    fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        self.kind.eval(ctx, out)
    }
    fn reads_velocities(&self) -> bool {
        true
    }
}

impl PositionFn for ConstraintEl {
    fn bodies(&self) -> &[usize] {
        &self.bodies
    }
    fn components(&self) -> usize {
        self.neq
    }
    fn eval<T: Real>(&self, ctx: &LocalCtx<T>, out: &mut [T]) {
        self.kind.eval(ctx, out)
    }
}

/// g, ġ, g̈ of one component with gradients over z = (local q, local u, local u̇, t).
#[derive(Clone, Debug)]
pub struct Jet {
    /// g(q, t) (w(q, u, t) for a velocity-level function).
    pub g: f64,
    /// ġ = dg/dt along the motion (q̇ = H u).
    pub g1: f64,
    /// g̈ = d²g/dt² along the motion (for a velocity-level function, ẅ as if ü = 0).
    pub g2: f64,
    /// ∂g/∂z, length 18·nb + 1 for nb bodies: q of every body (6 each, in
    /// [`PositionFn::bodies`] order), then u, then u̇, then t.
    pub dg: Vec<f64>,
    /// ∂ġ/∂z, same layout as `dg`.
    pub dg1: Vec<f64>,
    /// ∂g̈/∂z, same layout as `dg`.
    pub dg2: Vec<f64>,
}

/// Jets of every component of `f` at (q, u, u̇, t) (global vectors).
pub fn jets<F: PositionFn>(
    sys: &System,
    f: &F,
    q: &[f64],
    u: &[f64],
    udot: &[f64],
    t: f64,
    inputs: &[f64],
) -> Vec<Jet> {
    // q, u and u̇ of every local coordinate, and t.
    let k = 3 * nql(sys, f.bodies()) + 1;
    let zero = Jet { g: 0.0, g1: 0.0, g2: 0.0, dg: vec![0.0; k], dg1: vec![0.0; k], dg2: vec![0.0; k] };
    let mut out = vec![zero; f.components()];
    by_width!(k, jets_k, [1, 19, 37, 55, 73, 91, 109](sys, f, q, u, udot, t, inputs, &mut out));
    out
}

/// The columns `chunk` of z = (q, u, u̇, t) of [`jets`].
#[allow(clippy::too_many_arguments)]
fn jets_k<const K: usize>(
    sys: &System,
    f: &impl PositionFn,
    q: &[f64],
    u: &[f64],
    udot: &[f64],
    t: f64,
    inputs: &[f64],
    jets: &mut [Jet],
    chunk: Range<usize>,
) {
    type B<const K: usize> = Dual<f64, K>;
    let bodies = f.bodies();
    let nq = nql(sys, bodies);
    let qb: Vec<B<K>> = seed(&gather(sys, bodies, q), 0, &chunk);
    let ub: Vec<B<K>> = seed(&gather(sys, bodies, u), nq, &chunk);
    let ab: Vec<B<K>> = seed(&gather(sys, bodies, udot), 2 * nq, &chunk);
    let tb: B<K> = seed_one(t, 3 * nq, &chunk);
    let mut qj = Vec::with_capacity(nq);
    let uj: Vec<_> =
        if f.reads_velocities() { ub.iter().zip(&ab).map(|(&v, &d)| jet(v, d, B::zero())).collect() } else { vec![] };
    for k in 0..bodies.len() {
        let r = NQ * k..NQ * k + NQ;
        let qd = qdot(&qb[r.clone()], &ub[r.clone()]);
        // q̈ = d/dt (H(q) u) = directional derivative along (q̇, u̇).
        let qe: Vec<Dual<B<K>, 1>> = qb[r.clone()].iter().zip(&qd).map(|(&v, &d)| Dual { v, d: [d] }).collect();
        let ue: Vec<Dual<B<K>, 1>> = ub[r.clone()].iter().zip(&ab[r]).map(|(&v, &d)| Dual { v, d: [d] }).collect();
        let qdd = qdot(&qe, &ue);
        for i in 0..NQ {
            qj.push(jet(qb[NQ * k + i], qd[i], qdd[i].d[0]));
        }
    }
    // Modal coordinates: η̇ and η̈ are their velocities and accelerations (H = I).
    for i in NQ * bodies.len()..nq {
        qj.push(jet(qb[i], ub[i], ab[i]));
    }
    let tj = jet(tb, B::one(), B::zero());
    let ctx = LocalCtx::new(sys, bodies, &qj, &uj, &[], tj, inputs);
    let mut out = vec![Dual::zero(); f.components()];
    f.eval(&ctx, &mut out);
    for (j, o) in jets.iter_mut().zip(&out) {
        (j.g, j.g1, j.g2) = (o.v.v.v, o.v.d[0].v, o.d[0].d[0].v);
        for z in chunk.clone() {
            let c = z - chunk.start;
            (j.dg[z], j.dg1[z], j.dg2[z]) = (o.v.v.d[c], o.v.d[0].d[c], o.d[0].d[0].d[c]);
        }
    }
}

/// x(τ) = x0 + τ x1 + τ²/2 x2 as nested duals: first and second τ-derivatives exact.
fn jet<T: Real>(x0: T, x1: T, x2: T) -> Dual<Dual<T, 1>, 1> {
    Dual { v: Dual { v: x0, d: [x1] }, d: [Dual { v: x1, d: [x2] }] }
}
