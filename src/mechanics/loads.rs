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
use crate::ad::{Dual, Real};
use crate::geom::V3;
use crate::model::expr::{ElementRef, ExprEnv};

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
            let (value, dz) = match el.bodies.len() {
                0 => force_grad_k::<1>(sys, el, &ql, &ul, t, inputs),
                1 => force_grad_k::<12>(sys, el, &ql, &ul, t, inputs),
                2 => force_grad_k::<24>(sys, el, &ql, &ul, t, inputs),
                3 => force_grad_k::<36>(sys, el, &ql, &ul, t, inputs),
                _ => force_grad_k::<48>(sys, el, &ql, &ul, t, inputs),
            };
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
            let (value, dq, dlam) = match el.bodies.len() {
                0 => return None,
                1 => constraint_grad_k::<12>(sys, el, &ql, lam, t, inputs)?,
                2 => constraint_grad_k::<18>(sys, el, &ql, lam, t, inputs)?,
                3 => constraint_grad_k::<24>(sys, el, &ql, lam, t, inputs)?,
                _ => constraint_grad_k::<30>(sys, el, &ql, lam, t, inputs)?,
            };
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

/// Value and ∂/∂(local q, local u) of a force element's load; K ≥ 12·nb.
fn force_grad_k<const K: usize>(
    sys: &System,
    el: &ForceEl,
    ql: &[f64],
    ul: &[f64],
    t: f64,
    inputs: &[f64],
) -> ([f64; NLOAD], Vec<f64>) {
    let nq = ql.len();
    let qd: Vec<Dual<f64, K>> = ql.iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ud: Vec<Dual<f64, K>> = ul.iter().enumerate().map(|(k, &v)| Dual::var(v, nq + k)).collect();
    let l = force_load(sys, el, &qd, &ud, t, inputs, None);
    (l.map(|c| c.v), l.iter().flat_map(|c| c.d[..2 * nq].to_vec()).collect())
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

/// Value, ∂/∂(local q) (NLOAD × 6nb) and ∂/∂λ (NLOAD × neq) of a constraint element's
/// load; K ≥ 6·nb + neq (at most 6 equations per element).
fn constraint_grad_k<const K: usize>(
    sys: &System,
    el: &ConstraintEl,
    ql: &[f64],
    lam: &[f64],
    t: f64,
    inputs: &[f64],
) -> Option<([f64; NLOAD], Vec<f64>, Vec<f64>)> {
    let nq = ql.len();
    let qd: Vec<Dual<f64, K>> = ql.iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ld: Vec<Dual<f64, K>> = lam.iter().enumerate().map(|(e, &v)| Dual::var(v, nq + e)).collect();
    let l = constraint_load(sys, el, &qd, &ld, t, inputs)?;
    let dq = l.iter().flat_map(|c| c.d[..nq].to_vec()).collect();
    let dlam = l.iter().flat_map(|c| c.d[nq..nq + lam.len()].to_vec()).collect();
    Some((l.map(|c| c.v), dq, dlam))
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
        ConstraintKind::User { .. } | ConstraintKind::WheelContact { .. } => return None,
    };
    let cq = match el.bodies.len() {
        0 => return None,
        1 => constraint_jacobian::<T, 6>(sys, el, ql, t, inputs),
        2 => constraint_jacobian::<T, 12>(sys, el, ql, t, inputs),
        3 => constraint_jacobian::<T, 18>(sys, el, ql, t, inputs),
        _ => constraint_jacobian::<T, 24>(sys, el, ql, t, inputs),
    };
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

/// C_q of a constraint element (neq × 6nb, row-major) over any scalar: one dual level
/// above `T`, seeded on the local q; K ≥ 6·nb.
fn constraint_jacobian<T: Real, const K: usize>(
    sys: &System,
    el: &ConstraintEl,
    ql: &[T],
    t: f64,
    inputs: &[f64],
) -> Vec<T> {
    let nq = ql.len();
    let qd: Vec<Dual<T, K>> = ql.iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ctx = LocalCtx::new(sys, &el.bodies, &qd, &[], &[], Dual::cst(t), inputs);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    out.iter().flat_map(|e| e.d[..nq].to_vec()).collect()
}
