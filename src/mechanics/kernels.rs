//! Exact derivatives of element equations by forward-mode AD over the element's local
//! coordinates. Each kernel seeds the coordinates of the (few) bodies an element touches,
//! so the cost is independent of the model size and every Jacobian stays sparse.

use super::body::{Turn, h_transpose_times, qdot};
use super::constraints::ConstraintEl;
use super::coords::{gather, gather_into, nql};
use super::forces::ForceEl;
use super::local::LocalCtx;
use super::nonholonomic::NonholonomicEl;
use super::system::System;
use super::user::UserEq;
use super::{joint_gradient, joint_hessian};
use crate::ad::chunked::{by_width, chunks, seed, seed_one};
use crate::ad::{Dual, Real};
use crate::geom::{M3, V3};
use std::ops::Range;

/// C, C_q (local, row-major neq × 6nb) and C_t of one constraint element.
#[derive(Clone, Debug, Default)]
pub struct ConstraintFirst {
    /// C (neq).
    pub c: Vec<f64>,
    /// C_q, neq × 6nb.
    pub cq: Vec<f64>,
    /// C_t (neq).
    pub ct: Vec<f64>,
}

/// C with gradient and Hessian over z = (local q, t); K = nq + 1 (nq local coordinates).
#[derive(Clone, Debug, Default)]
pub struct ConstraintSecond {
    /// Number K of variables z.
    pub k: usize,
    /// C (neq).
    pub c: Vec<f64>,
    /// neq × K.
    pub grad: Vec<f64>,
    /// neq × K × K.
    pub hess: Vec<f64>,
}

impl ConstraintSecond {
    /// All zero, for `neq` equations of `k` variables.
    fn zeros(k: usize, neq: usize) -> Self {
        ConstraintSecond { k, c: vec![0.0; neq], grad: vec![0.0; neq * k], hess: vec![0.0; neq * k * k] }
    }
}

/// Constraint values only.
pub fn constraint_values(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let ql = gather(sys, &el.bodies, q);
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], t, inputs);
    let mut out = vec![0.0; el.neq];
    el.kind.eval(&ctx, &mut out);
    out
}

impl ConstraintFirst {
    /// All zero, for `neq` equations of `nq` local coordinates (the buffers' capacity reused).
    fn reset(&mut self, neq: usize, nq: usize) {
        for (v, len) in [(&mut self.c, neq), (&mut self.cq, neq * nq), (&mut self.ct, neq)] {
            v.clear();
            v.resize(len, 0.0);
        }
    }
}

/// First derivatives of a constraint element (Eq. 1b: C_q, C_t).
/// Joints between rigid bodies take the closed form of [`super::joint_gradient`].
pub fn constraint_first(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintFirst {
    let mut r = ConstraintFirst::default();
    constraint_first_into(sys, el, q, t, inputs, None, &mut r);
    r
}

/// [`constraint_first`] into `r`, with the bodies' turns given (`turns`, indexed by body;
/// None: computed where needed). Allocates nothing once `r` has grown to the element's
/// size, except for elements that take the dual-number kernel.
pub fn constraint_first_into(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    t: f64,
    inputs: &[f64],
    turns: Option<&[Turn<f64>]>,
    r: &mut ConstraintFirst,
) {
    r.reset(el.neq, nql(sys, &el.bodies));
    if !joint_gradient::joint_first_into(sys, el, q, turns, &mut r.c, &mut r.cq) {
        first_ad(sys, el, q, t, inputs, r);
    }
}

/// [`constraint_first`] by dual numbers, for every kind of element.
pub fn constraint_first_ad(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintFirst {
    let mut r = ConstraintFirst::default();
    r.reset(el.neq, nql(sys, &el.bodies));
    first_ad(sys, el, q, t, inputs, &mut r);
    r
}

/// [`constraint_first_ad`] into `r` (zeroed, of the element's size).
fn first_ad(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64], r: &mut ConstraintFirst) {
    let nq = nql(sys, &el.bodies);
    by_width!(nq + 1, first_k, [1, 7, 13, 19, 25, 31, 37](sys, el, q, t, inputs, r));
}

/// The columns `chunk` of z = (local q, t) of [`constraint_first`].
fn first_k<const K: usize>(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    t: f64,
    inputs: &[f64],
    r: &mut ConstraintFirst,
    chunk: Range<usize>,
) {
    let nq = nql(sys, &el.bodies);
    let ql: Vec<Dual<f64, K>> = seed(&gather(sys, &el.bodies, q), 0, &chunk);
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], seed_one(t, nq, &chunk), inputs);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    for (e, o) in out.iter().enumerate() {
        r.c[e] = o.v;
        for z in chunk.clone() {
            let d = o.d[z - chunk.start];
            if z < nq { r.cq[e * nq + z] = d } else { r.ct[e] = d }
        }
    }
}

/// Second derivatives of a constraint element (for Ċ_q, (Pᵀλ)_q and the γ of Eq. 1c).
/// Joints between rigid bodies take the closed forms of [`super::joint_hessian`].
pub fn constraint_second(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintSecond {
    let mut r = ConstraintSecond::default();
    constraint_second_into(sys, el, q, t, inputs, &mut r);
    r
}

/// [`constraint_second`] into `r` (the closed form of rigid joints reuses its buffers;
/// the dual-number route replaces them).
pub fn constraint_second_into(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    t: f64,
    inputs: &[f64],
    r: &mut ConstraintSecond,
) {
    if joint_hessian::joint_second_into(sys, el, q, &mut r.c, &mut r.grad, &mut r.hess) {
        r.k = nql(sys, &el.bodies) + 1;
    } else {
        *r = constraint_second_ad(sys, el, q, t, inputs);
    }
}

/// [`constraint_second`] by nested dual numbers, for every kind of element.
pub fn constraint_second_ad(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintSecond {
    let k = nql(sys, &el.bodies) + 1;
    let mut r = ConstraintSecond::zeros(k, el.neq);
    by_width!(k, second_k, [1, 7, 13, 19](sys, el, q, t, inputs, &mut r));
    r
}

/// The rows `outer` of the Hessians of [`constraint_second`] (and the gradient): nested
/// duals, the outer level seeded on `outer`, the inner on each chunk of z from `outer`
/// on (the Hessian is symmetric: each block is written to both of its places).
fn second_k<const K: usize>(
    sys: &System,
    el: &ConstraintEl,
    q: &[f64],
    t: f64,
    inputs: &[f64],
    r: &mut ConstraintSecond,
    outer: Range<usize>,
) {
    let (nq, k) = (nql(sys, &el.bodies), r.k);
    let z: Vec<f64> = gather(sys, &el.bodies, q).into_iter().chain([t]).collect();
    for inner in chunks(k, K).filter(|c| c.end > outer.start) {
        let zd: Vec<Dual<Dual<f64, K>, K>> = z
            .iter()
            .enumerate()
            .map(|(i, &v)| Dual {
                v: seed_one(v, i, &inner),
                d: std::array::from_fn(|j| if outer.start + j == i { Dual::one() } else { Dual::zero() }),
            })
            .collect();
        let ctx = LocalCtx::new(sys, &el.bodies, &zd[..nq], &[], &[], zd[nq], inputs);
        let mut out = vec![Dual::zero(); el.neq];
        el.kind.eval(&ctx, &mut out);
        for (e, o) in out.iter().enumerate() {
            r.c[e] = o.v.v;
            let h = &mut r.hess[e * k * k..(e + 1) * k * k];
            for b in inner.clone() {
                r.grad[e * k + b] = o.v.d[b - inner.start];
                for a in outer.clone() {
                    let x = o.d[a - outer.start].d[b - inner.start];
                    h[a * k + b] = x;
                    h[b * k + a] = x;
                }
            }
        }
    }
}

/// g of a non-holonomic element with its gradient over z = (local q, local u, t).
pub struct NonholonomicFirst {
    /// Number K = 2nq + 1 of variables z.
    pub k: usize,
    /// g (neq).
    pub c: Vec<f64>,
    /// neq × K.
    pub grad: Vec<f64>,
}

/// g and ∂g/∂(q, u, t) of a non-holonomic element: B and γ need no more.
pub fn nonholonomic_first(
    sys: &System,
    el: &NonholonomicEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> NonholonomicFirst {
    let k = 2 * nql(sys, &el.bodies) + 1;
    let mut r = NonholonomicFirst { k, c: vec![0.0; el.neq], grad: vec![0.0; el.neq * k] };
    by_width!(k, nh_first_k, [1, 13, 25, 37, 49, 61, 73]((sys, el, q, u, t, ext), &mut r));
    r
}

/// The columns `chunk` of [`nonholonomic_first`].
fn nh_first_k<const K: usize>((sys, el, q, u, t, ext): NhArgs, r: &mut NonholonomicFirst, chunk: Range<usize>) {
    let nq = nql(sys, &el.bodies);
    let ql: Vec<Dual<f64, K>> = seed(&gather(sys, &el.bodies, q), 0, &chunk);
    let ul: Vec<Dual<f64, K>> = seed(&gather(sys, &el.bodies, u), nq, &chunk);
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], seed_one(t, 2 * nq, &chunk), ext);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    for (e, o) in out.iter().enumerate() {
        r.c[e] = o.v;
        for z in chunk.clone() {
            r.grad[e * r.k + z] = o.d[z - chunk.start];
        }
    }
}

/// g of a non-holonomic element with its gradient over z = (local q, local u, t) and the
/// mixed second derivatives ∂²g/∂u∂(q, t) (what (Bᵀν)_q needs), in the layout of
/// [`ConstraintSecond`] with K = 2nq + 1; the (q, q) and (u, u) blocks are left zero
/// (g is linear in u). Nested duals: outer over u, inner over (q, t), each seeded a
/// chunk at a time past 18 coordinates.
pub fn nonholonomic_second(
    sys: &System,
    el: &NonholonomicEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> ConstraintSecond {
    let nq = nql(sys, &el.bodies);
    let k = 2 * nq + 1;
    let mut r = ConstraintSecond::zeros(k, el.neq);
    let mut go = |f: fn(NhArgs, &mut ConstraintSecond, Range<usize>, Range<usize>), w: usize| {
        for cu in chunks(nq, w) {
            for cq in chunks(nq + 1, w + 1) {
                f((sys, el, q, u, t, ext), &mut r, cu.clone(), cq);
            }
        }
    };
    match nq {
        0 => go(nh_second_k::<1, 1>, 1),
        1..=6 => go(nh_second_k::<7, 6>, 6),
        7..=12 => go(nh_second_k::<13, 12>, 12),
        _ => go(nh_second_k::<19, 18>, 18),
    }
    r
}

/// The arguments of [`nonholonomic_second`].
type NhArgs<'a> = (&'a System, &'a NonholonomicEl, &'a [f64], &'a [f64], f64, &'a [f64]);

/// A nested dual constant in the outer variables.
fn outer_cst<const KQ: usize, const KU: usize>(v: Dual<f64, KQ>) -> Dual<Dual<f64, KQ>, KU> {
    Dual { v, d: [Dual::zero(); KU] }
}

/// The part of [`nonholonomic_second`] from the u in `cu` (outer duals) and the (q, t) in
/// `cq` (inner duals; t is variable nq).
fn nh_second_k<const KQ: usize, const KU: usize>(
    (sys, el, q, u, t, ext): NhArgs,
    r: &mut ConstraintSecond,
    cu: Range<usize>,
    cq: Range<usize>,
) {
    let nq = nql(sys, &el.bodies);
    let k = r.k;
    type D2<const KQ: usize, const KU: usize> = Dual<Dual<f64, KQ>, KU>;
    let ql: Vec<D2<KQ, KU>> = seed(&gather(sys, &el.bodies, q), 0, &cq).into_iter().map(outer_cst).collect();
    let ul: Vec<D2<KQ, KU>> = gather(sys, &el.bodies, u)
        .iter()
        .enumerate()
        .map(|(i, &v)| Dual {
            v: Dual::cst(v),
            d: std::array::from_fn(|j| if cu.start + j == i { Dual::one() } else { Dual::zero() }),
        })
        .collect();
    let tt: D2<KQ, KU> = outer_cst(seed_one(t, nq, &cq));
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], tt, ext);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    // Column of z = (q, u, t) of inner variable `z` (q, or t at nq).
    let col = |z: usize| if z < nq { z } else { 2 * nq };
    for (e, o) in out.iter().enumerate() {
        r.c[e] = o.v.v;
        let g = &mut r.grad[e * k..(e + 1) * k];
        for z in cq.clone() {
            g[col(z)] = o.v.d[z - cq.start];
        }
        for a in cu.clone() {
            g[nq + a] = o.d[a - cu.start].v;
        }
        let h = &mut r.hess[e * k * k..(e + 1) * k * k];
        for a in cu.clone() {
            for z in cq.clone() {
                let x = o.d[a - cu.start].d[z - cq.start];
                h[(nq + a) * k + col(z)] = x;
                h[col(z) * k + nq + a] = x;
            }
        }
    }
}

/// Generalized forces of one element on its bodies (6 per local body).
pub fn force_values(sys: &System, el: &ForceEl, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    force_values_into(sys, el, q, u, t, inputs, &mut Gathered::default(), &mut out);
    out
}

/// An element's local coordinates and velocities, gathered into reused buffers.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    ql: Vec<f64>,
    ul: Vec<f64>,
}

impl Gathered {
    /// Gather `bodies`' local q and u from the global ones.
    pub fn of(&mut self, sys: &System, bodies: &[usize], q: &[f64], u: &[f64]) -> (&[f64], &[f64]) {
        gather_into(sys, bodies, q, &mut self.ql);
        gather_into(sys, bodies, u, &mut self.ul);
        (&self.ql, &self.ul)
    }
}

/// [`force_values`] into `out`, gathering into `g` (capacities reused).
#[allow(clippy::too_many_arguments)]
pub fn force_values_into(
    sys: &System,
    el: &ForceEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    g: &mut Gathered,
    out: &mut Vec<f64>,
) {
    let (ql, ul) = g.of(sys, &el.bodies, q, u);
    let ctx = LocalCtx::new(sys, &el.bodies, ql, ul, &[], t, inputs);
    out.clear();
    out.resize(nql(sys, &el.bodies), 0.0);
    el.generalized(&ctx, out);
}

/// Generalized forces and their exact Jacobian: rows 6nb, columns (local q, local u).
pub fn force_jacobian(
    sys: &System,
    el: &ForceEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let nq = nql(sys, &el.bodies);
    let mut r = (vec![0.0; nq], vec![0.0; nq * 2 * nq]);
    by_width!(2 * nq, force_jac_k, [1, 12, 24, 36, 48, 60, 72](sys, el, q, u, t, inputs, &mut r));
    r
}

/// The columns `chunk` of z = (local q, local u) of [`force_jacobian`].
#[allow(clippy::too_many_arguments)]
fn force_jac_k<const K: usize>(
    sys: &System,
    el: &ForceEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    (vals, jac): &mut (Vec<f64>, Vec<f64>),
    chunk: Range<usize>,
) {
    let nq = nql(sys, &el.bodies);
    let ql: Vec<Dual<f64, K>> = seed(&gather(sys, &el.bodies, q), 0, &chunk);
    let ul: Vec<Dual<f64, K>> = seed(&gather(sys, &el.bodies, u), nq, &chunk);
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], Dual::cst(t), inputs);
    let mut out = vec![Dual::zero(); nq];
    el.generalized(&ctx, &mut out);
    for (i, e) in out.iter().enumerate() {
        vals[i] = e.v;
        for z in chunk.clone() {
            jac[i * 2 * nq + z] = e.d[z - chunk.start];
        }
    }
}

/// ∂q̇_b/∂q_b (6×6, row-major) for one body: only the Euler-angle rows depend on θ, φ.
pub fn dqdot_dq(q: &[f64], u: &[f64]) -> [f64; 36] {
    let qd: [Dual<f64, 6>; 6] = std::array::from_fn(|k| Dual::var(q[k], k));
    let ud: [Dual<f64, 6>; 6] = std::array::from_fn(|k| Dual::cst(u[k]));
    let r = qdot(&qd, &ud);
    std::array::from_fn(|i| r[i / 6].d[i % 6])
}

/// ∂(Hᵀw)/∂q_b (6×6, row-major) for one body at fixed w.
pub fn dhtw_dq(q: &[f64], w: &[f64]) -> [f64; 36] {
    let qd: [Dual<f64, 6>; 6] = std::array::from_fn(|k| Dual::var(q[k], k));
    let wd: [Dual<f64, 6>; 6] = std::array::from_fn(|k| Dual::cst(w[k]));
    let r = h_transpose_times(&qd, &wd);
    std::array::from_fn(|i| r[i / 6].d[i % 6])
}

/// Gyroscopic generalized force −ω'×(Jω') of one body (inertia `j`, body axes).
pub fn gyroscopic_force<T: Real>(j: &[[f64; 3]; 3], w: &V3<T>) -> V3<T> {
    let jw = M3::cst(j).mv(w);
    -w.cross(&jw)
}

/// [`gyroscopic_force`] and its 3×3 Jacobian in ω'.
pub fn gyroscopic(j: &[[f64; 3]; 3], w: &[f64]) -> ([f64; 3], [f64; 9]) {
    let wd = V3([Dual::<f64, 3>::var(w[0], 0), Dual::var(w[1], 1), Dual::var(w[2], 2)]);
    let g = gyroscopic_force(j, &wd);
    (g.val(), std::array::from_fn(|i| g.0[i / 3].d[i % 3]))
}

/// ∂Q/∂w of one force element for each external value w it reads (`ForceEl::ext_refs`,
/// see [`System::ext`]): (index into `ext`, 6nb entries).
pub fn force_ext_jacobian(
    sys: &System,
    el: &ForceEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> Vec<(usize, Vec<f64>)> {
    let (ql, ul) = (gather(sys, &el.bodies, q), gather(sys, &el.bodies, u));
    el.ext_refs
        .iter()
        .map(|&k| {
            let (qd, ud) = (lift(&ql), lift(&ul));
            let mut ctx = LocalCtx::new(sys, &el.bodies, &qd, &ud, &[], Dual::cst(t), ext);
            ctx.input_values = Some(seed_ext(ext, k));
            let mut out = vec![Dual::zero(); nql(sys, &el.bodies)];
            el.generalized(&ctx, &mut out);
            (k, out.iter().map(|e| e.d[0]).collect())
        })
        .collect()
}

/// Constants as dual numbers.
fn lift(x: &[f64]) -> Vec<Dual<f64, 1>> {
    x.iter().map(|&v| Dual::cst(v)).collect()
}

/// External values with entry `k` seeded.
fn seed_ext(ext: &[f64], k: usize) -> Vec<Dual<f64, 1>> {
    ext.iter().enumerate().map(|(i, &v)| if i == k { Dual::var(v, 0) } else { Dual::cst(v) }).collect()
}

/// Residual of a user row (Eq. 7a–7b).
pub fn user_residual(sys: &System, ue: &UserEq, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> f64 {
    user_residual_with(sys, ue, q, u, t, ext, &mut Gathered::default())
}

/// [`user_residual`], gathering into `g` (capacities reused).
pub fn user_residual_with(
    sys: &System,
    ue: &UserEq,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
    g: &mut Gathered,
) -> f64 {
    let (ql, ul) = g.of(sys, &ue.bodies, q, u);
    ue.residual(&LocalCtx::new(sys, &ue.bodies, ql, ul, &[], t, ext))
}

/// Exact derivatives of a user row: ∂r/∂(local q, local u) (12nb) and ∂r/∂w for each
/// external value it reads.
pub struct UserJacobian {
    /// The residual r.
    pub value: f64,
    /// ∂r/∂(local q, local u): 12nb entries (all q, then all u).
    pub dqu: Vec<f64>,
    /// (index into `ext`, ∂r/∂w) for each external value w in `UserEq::ext_refs`.
    pub dext: Vec<(usize, f64)>,
}

/// Value and exact derivatives of a user row.
pub fn user_jacobian(sys: &System, ue: &UserEq, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> UserJacobian {
    let n = 2 * nql(sys, &ue.bodies);
    let (mut value, mut dqu) = (0.0, vec![0.0; n]);
    by_width!(n, user_qu_k, [1, 12, 24, 36, 48, 60, 72](sys, ue, q, u, t, ext, &mut value, &mut dqu));
    let (ql, ul) = (gather(sys, &ue.bodies, q), gather(sys, &ue.bodies, u));
    let dext = ue
        .ext_refs
        .iter()
        .map(|&k| {
            let (qd, ud) = (lift(&ql), lift(&ul));
            let mut ctx = LocalCtx::new(sys, &ue.bodies, &qd, &ud, &[], Dual::cst(t), ext);
            ctx.input_values = Some(seed_ext(ext, k));
            (k, ue.residual(&ctx).d[0])
        })
        .collect();
    UserJacobian { value, dqu, dext }
}

/// The columns `chunk` of z = (local q, local u) of a user row's gradient.
#[allow(clippy::too_many_arguments)]
fn user_qu_k<const K: usize>(
    sys: &System,
    ue: &UserEq,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
    value: &mut f64,
    dqu: &mut [f64],
    chunk: Range<usize>,
) {
    let nq = nql(sys, &ue.bodies);
    let ql: Vec<Dual<f64, K>> = seed(&gather(sys, &ue.bodies, q), 0, &chunk);
    let ul: Vec<Dual<f64, K>> = seed(&gather(sys, &ue.bodies, u), nq, &chunk);
    let r = ue.residual(&LocalCtx::new(sys, &ue.bodies, &ql, &ul, &[], Dual::cst(t), ext));
    *value = r.v;
    for z in chunk.clone() {
        dqu[z] = r.d[z - chunk.start];
    }
}

#[cfg(test)]
mod joint_tests {
    use super::*;
    use crate::mechanics::joint_gradient::joint_first;
    use crate::mechanics::joint_hessian::joint_second;

    /// Every joint type of the model format, between two bodies at random poses and to
    /// ground, agrees with the dual-number kernels to round-off: C, C_q and the Hessians
    /// to 1e-14 (relative to 1 + |value|).
    #[test]
    fn closed_form_matches_the_dual_number_kernels() {
        let kinds = ["fixed", "revolute", "translational", "cylindrical", "universal", "spherical", "planar"];
        let mut seed = 0x2545f4914f6cdd1du64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-14 * (1.0 + y.abs());
        let mut checked = 0;
        for kind in kinds {
            for j in ["b.m", "ground.g"] {
                let xml = format!(
                    r#"<multibody name="t" version="1"><ground><marker name="g" position="0.3 -0.2 0.1" z_axis="0.2 1 0.3"/></ground>
<body name="a" mass="1" inertia="1 1 1" position="0 0 0"><marker name="m" position="0.1 0.2 -0.3" z_axis="1 0.4 -0.2"/></body>
<body name="b" mass="1" inertia="1 1 1" position="0.5 0 0"><marker name="m" position="-0.2 0.1 0.4" z_axis="0.3 -1 0.5"/></body>
<joint name="j" type="{kind}" i="a.m" j="{j}"/></multibody>"#
                );
                let model = crate::model::parse::load_str(&xml, "t.xml").unwrap();
                let sys = System::from_model(&model).unwrap();
                let el = &sys.constraints[0];
                for _ in 0..20 {
                    let q: Vec<f64> = (0..sys.n()).map(|_| 2.0 * rnd()).collect();
                    let ((c, cq), ad) =
                        (joint_first(&sys, el, &q).unwrap(), constraint_first_ad(&sys, el, &q, 0.0, &[]));
                    assert_eq!((c.len(), cq.len()), (ad.c.len(), ad.cq.len()));
                    assert!(ad.ct.iter().all(|&v| v == 0.0));
                    for (x, y) in c.iter().zip(&ad.c).chain(cq.iter().zip(&ad.cq)) {
                        assert!(close(*x, *y), "{kind} {j}: {x} vs {y}");
                    }
                    let ((c, grad, hess), ad) =
                        (joint_second(&sys, el, &q).unwrap(), constraint_second_ad(&sys, el, &q, 0.0, &[]));
                    assert_eq!((grad.len(), hess.len()), (ad.grad.len(), ad.hess.len()));
                    for (x, y) in c.iter().zip(&ad.c).chain(grad.iter().zip(&ad.grad)).chain(hess.iter().zip(&ad.hess))
                    {
                        assert!(close(*x, *y), "{kind} {j}: {x} vs {y}");
                    }
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 7 * 2 * 20);
    }
}
