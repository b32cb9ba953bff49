//! Element loads `fx(name) fy fz tx ty tz`: the force and torque that a joint, motion or
//! force element applies on its i marker (ground components, torque about the i marker
//! origin), with exact gradients with respect to everything they depend on.
//!
//! A constraint element's load is its share of the constraint forces −Pᵀλ (Eq. 13a,
//! P = C_q H) on the body of its i marker, moved to the i marker origin (when i is on
//! ground: minus the load on j's body). It depends on the element's bodies' q (through
//! C_q, H(q) and the marker pose) and linearly on the element's own multipliers λ. A force
//! element's load is [`ForceEl::load`], a function of q, u and the inputs. User
//! constraints have no i marker, hence no load.
//!
//! One generic implementation serves values (f64) and gradients (dual numbers; C_q inside
//! is itself a dual-number derivative, so constraint loads nest two levels).

use super::body::{NQ, h_transpose_times};
use super::constraints::{ConstraintEl, ConstraintKind};
use super::coords::{gather, local_columns};
use super::forces::ForceEl;
use super::local::LocalCtx;
use super::system::{ElementSlot, System};
use crate::ad::chunked::{by_width, chunks, seed};
use crate::ad::{Dual, Real};
use crate::geom::V3;
use crate::model::expr::{ElementRef, ExprEnv};
use std::ops::Range;

pub use super::load_components::{NLOAD, load_index};

/// An element's load and its exact gradient at one point.
#[derive(Clone, Debug)]
pub struct LoadGradient {
    /// Bodies of the element (global indices): the local order of `dz`.
    pub bodies: Vec<usize>,
    /// Global column of each local coordinate (see [`super::coords`]).
    pub cols: Vec<usize>,
    /// Force and torque on the i marker (ground; torque about the i origin).
    pub value: [f64; NLOAD],
    /// ∂load/∂(local q, local u): NLOAD rows of 12·nb (q of each body, then u), row-major.
    pub dz: Vec<f64>,
    /// First global λ row of the element (constraint elements; 0 for forces).
    pub lam_row: usize,
    /// ∂load/∂λ of the element's rows: NLOAD rows of `neq` (0 for forces), row-major.
    pub dlam: Vec<f64>,
    /// ∂load/∂v: NLOAD rows of one entry per input, row-major.
    pub dv: Vec<f64>,
}

/// What one entry of a load's gradient is a derivative with respect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadTerm {
    /// Global coordinate q_i.
    Q(usize),
    /// Global velocity u_i.
    U(usize),
    /// Global multiplier row λ_r.
    Lam(usize),
    /// External value k (index into the values the gradient was evaluated with).
    Ext(usize),
}

impl LoadGradient {
    /// Number of multiplier columns of `dlam`.
    pub fn neq(&self) -> usize {
        self.dlam.len() / NLOAD
    }

    /// Every nonzero partial derivative of load component `c`, as (what, value): the
    /// chain rule of anything that reads this load walks these.
    pub fn terms(&self, c: usize, mut f: impl FnMut(LoadTerm, f64)) {
        let nlb = self.cols.len();
        for (a, &g) in self.cols.iter().enumerate() {
            f(LoadTerm::Q(g), self.dz[c * 2 * nlb + a]);
            f(LoadTerm::U(g), self.dz[c * 2 * nlb + nlb + a]);
        }
        let neq = self.neq();
        for k in 0..neq {
            f(LoadTerm::Lam(self.lam_row + k), self.dlam[c * neq + k]);
        }
        let next = self.dv.len() / NLOAD;
        for k in 0..next {
            let d = self.dv[c * next + k];
            if d != 0.0 {
                f(LoadTerm::Ext(k), d);
            }
        }
    }
}

/// The load of element `e` at `state` = (q, u, λ) (global vectors), time t and inputs v;
/// None when it has none (a user constraint, or an element between two ground markers).
pub fn load_value(
    sys: &System,
    e: ElementRef,
    state: (&[f64], &[f64], &[f64]),
    t: f64,
    inputs: &[f64],
) -> Option<[f64; NLOAD]> {
    let (q, u, lam) = state;
    match sys.element_slot(e) {
        ElementSlot::Force(k) => {
            let el = sys.forces.get(k)?;
            Some(force_load(sys, el, &gather(sys, &el.bodies, q), &gather(sys, &el.bodies, u), t, inputs, None))
        }
        ElementSlot::Constraint(k) => {
            let el = sys.constraints.get(k)?;
            constraint_load(sys, el, &gather(sys, &el.bodies, q), &lam[el.row..el.row + el.neq], t, inputs)
        }
    }
}

/// The load of element `e` at `state` = (q, u, λ), t, v and its exact gradient (see
/// [`LoadGradient`]).
pub fn load_gradient(
    sys: &System,
    e: ElementRef,
    state: (&[f64], &[f64], &[f64]),
    t: f64,
    inputs: &[f64],
) -> Option<LoadGradient> {
    let (q, u, lam) = state;
    match sys.element_slot(e) {
        ElementSlot::Force(k) => {
            let el = sys.forces.get(k)?;
            let (ql, ul) = (gather(sys, &el.bodies, q), gather(sys, &el.bodies, u));
            let n = 2 * ql.len();
            let mut grad = ([0.0; NLOAD], vec![0.0; NLOAD * n]);
            by_width!(n, force_grad_k, [1, 12, 24, 36, 48](sys, el, (&ql, &ul), t, inputs, &mut grad));
            let (value, dz) = grad;
            let dv = force_input_gradient(sys, el, &ql, &ul, t, inputs);
            Some(LoadGradient {
                bodies: el.bodies.clone(),
                cols: local_columns(sys, &el.bodies),
                value,
                dz,
                lam_row: 0,
                dlam: vec![],
                dv,
            })
        }
        ElementSlot::Constraint(k) => {
            let el = sys.constraints.get(k)?;
            let ql = gather(sys, &el.bodies, q);
            let lam = &lam[el.row..el.row + el.neq];
            if el.bodies.is_empty() {
                return None;
            }
            let n = ql.len() + lam.len();
            let mut grad: Option<ConstraintLoadGrad> =
                Some(([0.0; NLOAD], vec![0.0; NLOAD * ql.len()], vec![0.0; NLOAD * lam.len()]));
            by_width!(n, constraint_grad_k, [1, 12, 18, 24, 30](sys, el, (&ql, lam), t, inputs, &mut grad));
            let (value, dq, dlam) = grad?;
            // The load does not depend on u (λ is given): zero u columns.
            let nql = ql.len();
            let mut dz = vec![0.0; NLOAD * 2 * nql];
            for c in 0..NLOAD {
                dz[c * 2 * nql..c * 2 * nql + nql].copy_from_slice(&dq[c * nql..(c + 1) * nql]);
            }
            let dv = vec![0.0; NLOAD * inputs.len()];
            Some(LoadGradient {
                bodies: el.bodies.clone(),
                cols: local_columns(sys, &el.bodies),
                value,
                dz,
                lam_row: el.row,
                dlam,
                dv,
            })
        }
    }
}

/// Force element load over any scalar: [`ForceEl::load`] on local q, u (and inputs).
fn force_load<T: Real>(
    sys: &System,
    el: &ForceEl,
    ql: &[T],
    ul: &[T],
    t: f64,
    inputs: &[f64],
    input_values: Option<Vec<T>>,
) -> [T; NLOAD] {
    let mut ctx = LocalCtx::new(sys, &el.bodies, ql, ul, &[], T::cst(t), inputs);
    ctx.input_values = input_values;
    let l = el.load(&ctx);
    let (f, m) = (l.force.0, l.torque.0);
    [f[0], f[1], f[2], m[0], m[1], m[2]]
}

/// The columns `chunk` of z = (local q, local u) of the gradient of a force element's
/// load (NLOAD rows of 2·nq), and its value.
fn force_grad_k<const K: usize>(
    sys: &System,
    el: &ForceEl,
    (ql, ul): (&[f64], &[f64]),
    t: f64,
    inputs: &[f64],
    (value, dz): &mut ([f64; NLOAD], Vec<f64>),
    chunk: Range<usize>,
) {
    let n = 2 * ql.len();
    let qd: Vec<Dual<f64, K>> = seed(ql, 0, &chunk);
    let ud: Vec<Dual<f64, K>> = seed(ul, ql.len(), &chunk);
    let l = force_load(sys, el, &qd, &ud, t, inputs, None);
    *value = l.map(|c| c.v);
    for (c, x) in l.iter().enumerate() {
        for z in chunk.clone() {
            dz[c * n + z] = x.d[z - chunk.start];
        }
    }
}

/// ∂load/∂v of a force element: one dual pass per input (NLOAD rows × ni, row-major).
fn force_input_gradient(sys: &System, el: &ForceEl, ql: &[f64], ul: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let ni = inputs.len();
    let lift = |x: &[f64]| -> Vec<Dual<f64, 1>> { x.iter().map(|&v| Dual::cst(v)).collect() };
    let mut dv = vec![0.0; NLOAD * ni];
    for k in 0..ni {
        let seeded = inputs.iter().enumerate().map(|(i, &v)| if i == k { Dual::var(v, 0) } else { Dual::cst(v) });
        let l = force_load(sys, el, &lift(ql), &lift(ul), t, inputs, Some(seeded.collect()));
        for (c, x) in l.iter().enumerate() {
            dv[c * ni + k] = x.d[0];
        }
    }
    dv
}

/// A constraint element's load, its ∂/∂(local q) (NLOAD × nq) and ∂/∂λ (NLOAD × neq).
type ConstraintLoadGrad = ([f64; NLOAD], Vec<f64>, Vec<f64>);

/// The columns `chunk` of z = (local q, λ) of a [`ConstraintLoadGrad`] (set to `None`
/// when the element has no load).
fn constraint_grad_k<const K: usize>(
    sys: &System,
    el: &ConstraintEl,
    (ql, lam): (&[f64], &[f64]),
    t: f64,
    inputs: &[f64],
    grad: &mut Option<ConstraintLoadGrad>,
    chunk: Range<usize>,
) {
    let (nq, ne) = (ql.len(), lam.len());
    let qd: Vec<Dual<f64, K>> = seed(ql, 0, &chunk);
    let ld: Vec<Dual<f64, K>> = seed(lam, nq, &chunk);
    let (Some(l), Some((value, dq, dlam))) = (constraint_load(sys, el, &qd, &ld, t, inputs), grad.as_mut()) else {
        *grad = None;
        return;
    };
    *value = l.map(|c| c.v);
    for (c, x) in l.iter().enumerate() {
        for z in chunk.clone() {
            let d = x.d[z - chunk.start];
            if z < nq { dq[c * nq + z] = d } else { dlam[c * ne + z - nq] = d }
        }
    }
}

/// Constraint element load over any scalar, from local q and the element's λ rows.
fn constraint_load<T: Real>(
    sys: &System,
    el: &ConstraintEl,
    ql: &[T],
    lam: &[T],
    t: f64,
    inputs: &[f64],
) -> Option<[T; NLOAD]> {
    let (mi, mj) = match &el.kind {
        ConstraintKind::Joint { i, j, .. }
        | ConstraintKind::Rotation { i, j, .. }
        | ConstraintKind::Translation { i, j, .. } => (*i, *j),
        ConstraintKind::User { .. } | ConstraintKind::WheelContact { .. } | ConstraintKind::State { .. } => {
            return None;
        }
    };
    if el.bodies.is_empty() {
        return None;
    }
    let cq = constraint_jacobian(sys, el, ql, t, inputs);
    // Generalized constraint force on the element's bodies: −Σ_e P_eᵀ λ_e (Eq. 13a),
    // P_e = C_q,e H body by body.
    let nql = ql.len();
    let mut genf = vec![T::zero(); nql];
    for (e, &l) in lam.iter().enumerate() {
        for k in 0..el.bodies.len() {
            let r = NQ * k..NQ * k + NQ;
            let p = h_transpose_times(&ql[r.clone()], &cq[e * nql + NQ * k..e * nql + NQ * k + NQ]);
            for (g, pa) in genf[r].iter_mut().zip(p) {
                *g -= pa * l;
            }
        }
    }
    let ctx = LocalCtx::new(sys, &el.bodies, ql, &[], &[], T::cst(t), inputs);
    let pi = ctx.pose(mi).p;
    // Force and torque about the CM (Q_ω' = Aᵀ τ_cm), moved to the point p_i.
    let on_body = |b: usize| -> [T; NLOAD] {
        let k = ctx.local(b);
        let body = &ctx.bodies[k];
        let fo = V3([genf[NQ * k], genf[NQ * k + 1], genf[NQ * k + 2]]);
        let tc = body.a.mv(&V3([genf[NQ * k + 3], genf[NQ * k + 4], genf[NQ * k + 5]]));
        let ti = tc - (pi - body.r).cross(&fo);
        [fo.0[0], fo.0[1], fo.0[2], ti.0[0], ti.0[1], ti.0[2]]
    };
    match (sys.markers[mi].body, sys.markers[mj].body) {
        (Some(b), _) => Some(on_body(b)),
        (None, Some(b)) => Some(on_body(b).map(|x| -x)),
        _ => None,
    }
}

/// C_q of a constraint element (neq × nq, row-major) over any scalar: one dual level
/// above `T`, seeded on the local q (at most 24 at a time).
fn constraint_jacobian<T: Real>(sys: &System, el: &ConstraintEl, ql: &[T], t: f64, inputs: &[f64]) -> Vec<T> {
    let nq = ql.len();
    let mut cq = vec![T::zero(); el.neq * nq];
    let args = (sys, el, ql, t, inputs);
    match nq {
        0..=6 => cq_chunk::<T, 6>(args, &mut cq, 0..nq),
        7..=12 => cq_chunk::<T, 12>(args, &mut cq, 0..nq),
        13..=18 => cq_chunk::<T, 18>(args, &mut cq, 0..nq),
        _ => chunks(nq, 24).for_each(|c| cq_chunk::<T, 24>(args, &mut cq, c)),
    }
    cq
}

/// The columns `chunk` of [`constraint_jacobian`].
fn cq_chunk<T: Real, const K: usize>(
    (sys, el, ql, t, inputs): (&System, &ConstraintEl, &[T], f64, &[f64]),
    cq: &mut [T],
    chunk: Range<usize>,
) {
    let nq = ql.len();
    let qd: Vec<Dual<T, K>> = ql
        .iter()
        .enumerate()
        .map(|(k, &v)| if chunk.contains(&k) { Dual::var(v, k - chunk.start) } else { Dual { v, d: [T::zero(); K] } })
        .collect();
    let ctx = LocalCtx::new(sys, &el.bodies, &qd, &[], &[], Dual::cst(t), inputs);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    for (e, o) in out.iter().enumerate() {
        for k in chunk.clone() {
            cq[e * nq + k] = o.d[k - chunk.start];
        }
    }
}
