//! Exact derivatives of element equations by forward-mode AD over the element's local
//! coordinates. Each kernel seeds the coordinates of the (few) bodies an element touches,
//! so the cost is independent of the model size and every Jacobian stays sparse.

use super::body::{h_transpose_times, qdot};
use super::constraints::ConstraintEl;
use super::coords::{gather, nql};
use super::forces::ForceEl;
use super::local::LocalCtx;
use super::nonholonomic::NonholonomicEl;
use super::system::System;
use super::user::UserEq;
use crate::ad::{Dual, Real};

/// C, C_q (local, row-major neq × 6nb) and C_t of one constraint element.
pub struct ConstraintFirst {
    /// C (neq).
    pub c: Vec<f64>,
    /// C_q, neq × 6nb.
    pub cq: Vec<f64>,
    /// C_t (neq).
    pub ct: Vec<f64>,
}

/// C with gradient and Hessian over z = (local q, t); K = 6nb + 1.
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

/// Call `f::<K>` with the smallest width K of the list that holds `n` variables (the
/// list ends at the widest the model reader allows: [`MAX_LOCAL`] local coordinates).
macro_rules! by_width {
    ($n:expr, $f:ident, [$($k:literal),+] ( $($a:expr),* )) => {{
        let n: usize = $n;
        by_width!(@go n, $f, [$($k),+] ($($a),*))
    }};
    (@go $n:ident, $f:ident, [$k:literal] ( $($a:expr),* )) => {{
        assert!($n <= $k, "{} variables exceed the widest dual number ({})", $n, $k);
        $f::<$k>($($a),*)
    }};
    (@go $n:ident, $f:ident, [$k:literal, $($rest:literal),+] ( $($a:expr),* )) => {
        if $n <= $k { $f::<$k>($($a),*) } else { by_width!(@go $n, $f, [$($rest),+] ($($a),*)) }
    };
}

/// The most local coordinates an element may have (six per body it touches, plus the
/// modal coordinates of the flexible ones): the widest dual numbers are built for it.
pub const MAX_LOCAL: usize = 36;

/// Constraint values only.
pub fn constraint_values(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let ql = gather(sys, &el.bodies, q);
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], t, inputs);
    let mut out = vec![0.0; el.neq];
    el.kind.eval(&ctx, &mut out);
    out
}

/// First derivatives of a constraint element (Eq. 1b: C_q, C_t).
pub fn constraint_first(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintFirst {
    by_width!(nql(sys, &el.bodies) + 1, first_k, [1, 7, 13, 19, 25, 31, 37](sys, el, q, t, inputs))
}

fn first_k<const K: usize>(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintFirst {
    let nq = nql(sys, &el.bodies);
    let ql: Vec<Dual<f64, K>> = gather(sys, &el.bodies, q).iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], Dual::var(t, nq), inputs);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    let mut r = ConstraintFirst { c: vec![], cq: Vec::with_capacity(el.neq * nq), ct: vec![] };
    for e in &out {
        r.c.push(e.v);
        r.cq.extend_from_slice(&e.d[..nq]);
        r.ct.push(e.d[nq]);
    }
    r
}

/// Second derivatives of a constraint element (for Ċ_q, (Pᵀλ)_q and the γ of Eq. 1c).
pub fn constraint_second(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintSecond {
    by_width!(nql(sys, &el.bodies) + 1, second_k, [1, 7, 13, 19, 25, 31, 37](sys, el, q, t, inputs))
}

fn second_k<const K: usize>(sys: &System, el: &ConstraintEl, q: &[f64], t: f64, inputs: &[f64]) -> ConstraintSecond {
    let nq = nql(sys, &el.bodies);
    let k = nq + 1;
    let seed = |v: f64, i: usize| Dual::<Dual<f64, K>, K> {
        v: Dual::var(v, i),
        d: std::array::from_fn(|j| if j == i { Dual::one() } else { Dual::zero() }),
    };
    let ql: Vec<_> = gather(sys, &el.bodies, q).iter().enumerate().map(|(i, &v)| seed(v, i)).collect();
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &[], &[], seed(t, nq), inputs);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    let mut r = ConstraintSecond { k, c: vec![], grad: vec![], hess: vec![] };
    for e in &out {
        r.c.push(e.v.v);
        r.grad.extend(e.v.d[..k].iter().copied());
        for a in 0..k {
            r.hess.extend(e.d[a].d[..k].iter().copied());
        }
    }
    r
}

/// g of a non-holonomic element with its gradient over z = (local q, local u, t) and the
/// mixed second derivatives ∂²g/∂u∂(q, t) (what (Bᵀν)_q needs), in the layout of
/// [`ConstraintSecond`] with K = 12nb + 1; the (q, q) and (u, u) blocks are left zero
/// (g is linear in u). Nested duals: outer over u (6nb), inner over (q, t).
pub fn nonholonomic_second(
    sys: &System,
    el: &NonholonomicEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> ConstraintSecond {
    match nql(sys, &el.bodies) {
        0 => nh_second_k::<1, 1>(sys, el, q, u, t, ext),
        1..=6 => nh_second_k::<7, 6>(sys, el, q, u, t, ext),
        7..=12 => nh_second_k::<13, 12>(sys, el, q, u, t, ext),
        13..=18 => nh_second_k::<19, 18>(sys, el, q, u, t, ext),
        19..=24 => nh_second_k::<25, 24>(sys, el, q, u, t, ext),
        25..=30 => nh_second_k::<31, 30>(sys, el, q, u, t, ext),
        _ => nh_second_k::<37, 36>(sys, el, q, u, t, ext),
    }
}

/// A nested dual constant in the outer variables.
fn outer_cst<const KQ: usize, const KU: usize>(v: Dual<f64, KQ>) -> Dual<Dual<f64, KQ>, KU> {
    Dual { v, d: [Dual::zero(); KU] }
}

fn nh_second_k<const KQ: usize, const KU: usize>(
    sys: &System,
    el: &NonholonomicEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    ext: &[f64],
) -> ConstraintSecond {
    let nq = nql(sys, &el.bodies);
    let k = 2 * nq + 1;
    type D2<const KQ: usize, const KU: usize> = Dual<Dual<f64, KQ>, KU>;
    let ql: Vec<D2<KQ, KU>> =
        gather(sys, &el.bodies, q).iter().enumerate().map(|(i, &v)| outer_cst(Dual::var(v, i))).collect();
    let ul: Vec<D2<KQ, KU>> = gather(sys, &el.bodies, u)
        .iter()
        .enumerate()
        .map(|(i, &v)| Dual {
            v: Dual::cst(v),
            d: std::array::from_fn(|j| if j == i { Dual::one() } else { Dual::zero() }),
        })
        .collect();
    let tt: D2<KQ, KU> = outer_cst(Dual::var(t, nq));
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], tt, ext);
    let mut out = vec![Dual::zero(); el.neq];
    el.kind.eval(&ctx, &mut out);
    let mut r = ConstraintSecond { k, c: vec![], grad: vec![], hess: vec![] };
    for e in &out {
        r.c.push(e.v.v);
        let mut g = vec![0.0; k];
        g[..nq].copy_from_slice(&e.v.d[..nq]);
        for a in 0..nq {
            g[nq + a] = e.d[a].v;
        }
        g[2 * nq] = e.v.d[nq];
        r.grad.extend(g);
        let mut h = vec![0.0; k * k];
        for a in 0..nq {
            for c in 0..nq {
                h[(nq + a) * k + c] = e.d[a].d[c];
                h[c * k + nq + a] = e.d[a].d[c];
            }
            h[(nq + a) * k + 2 * nq] = e.d[a].d[nq];
            h[2 * nq * k + nq + a] = e.d[a].d[nq];
        }
        r.hess.extend(h);
    }
    r
}

/// Generalized forces of one element on its bodies (6 per local body).
pub fn force_values(sys: &System, el: &ForceEl, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let (ql, ul) = (gather(sys, &el.bodies, q), gather(sys, &el.bodies, u));
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], t, inputs);
    let mut out = vec![0.0; nql(sys, &el.bodies)];
    el.generalized(&ctx, &mut out);
    out
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
    by_width!(2 * nql(sys, &el.bodies) + 1, force_jac_k, [1, 13, 25, 37, 49, 61, 73](sys, el, q, u, t, inputs))
}

fn force_jac_k<const K: usize>(
    sys: &System,
    el: &ForceEl,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let nq = nql(sys, &el.bodies);
    let ql: Vec<Dual<f64, K>> = gather(sys, &el.bodies, q).iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ul: Vec<Dual<f64, K>> =
        gather(sys, &el.bodies, u).iter().enumerate().map(|(k, &v)| Dual::var(v, nq + k)).collect();
    let ctx = LocalCtx::new(sys, &el.bodies, &ql, &ul, &[], Dual::cst(t), inputs);
    let mut out = vec![Dual::zero(); nq];
    el.generalized(&ctx, &mut out);
    let vals = out.iter().map(|e| e.v).collect();
    let jac = out.iter().flat_map(|e| e.d[..2 * nq].to_vec()).collect();
    (vals, jac)
}

/// ∂q̇_b/∂q_b (6×6, row-major) for one body: only the Euler-angle rows depend on θ, φ.
pub fn dqdot_dq(q: &[f64], u: &[f64]) -> [f64; 36] {
    let qd: Vec<Dual<f64, 6>> = q.iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ud: Vec<Dual<f64, 6>> = u.iter().map(|&v| Dual::cst(v)).collect();
    let r = qdot(&qd, &ud);
    std::array::from_fn(|i| r[i / 6].d[i % 6])
}

/// ∂(Hᵀw)/∂q_b (6×6, row-major) for one body at fixed w.
pub fn dhtw_dq(q: &[f64], w: &[f64]) -> [f64; 36] {
    let qd: Vec<Dual<f64, 6>> = q.iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let wd: Vec<Dual<f64, 6>> = w.iter().map(|&v| Dual::cst(v)).collect();
    let r = h_transpose_times(&qd, &wd);
    std::array::from_fn(|i| r[i / 6].d[i % 6])
}

/// Gyroscopic generalized force −ω'×(Jω') of one body and its 3×3 Jacobian in ω'.
pub fn gyroscopic(j: &[[f64; 3]; 3], w: &[f64]) -> ([f64; 3], [f64; 9]) {
    use crate::geom::{M3, V3};
    let wd = V3([Dual::<f64, 3>::var(w[0], 0), Dual::var(w[1], 1), Dual::var(w[2], 2)]);
    let jw = M3::cst(j).mv(&wd);
    let g = -wd.cross(&jw);
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
    let (ql, ul) = (gather(sys, &ue.bodies, q), gather(sys, &ue.bodies, u));
    ue.residual(&LocalCtx::new(sys, &ue.bodies, &ql, &ul, &[], t, ext))
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
    let (value, dqu) =
        by_width!(2 * nql(sys, &ue.bodies), user_qu_k, [1, 12, 24, 36, 48, 60, 72](sys, ue, q, u, t, ext));
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

fn user_qu_k<const K: usize>(sys: &System, ue: &UserEq, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> (f64, Vec<f64>) {
    let nq = nql(sys, &ue.bodies);
    let ql: Vec<Dual<f64, K>> = gather(sys, &ue.bodies, q).iter().enumerate().map(|(k, &v)| Dual::var(v, k)).collect();
    let ul: Vec<Dual<f64, K>> =
        gather(sys, &ue.bodies, u).iter().enumerate().map(|(k, &v)| Dual::var(v, nq + k)).collect();
    let r = ue.residual(&LocalCtx::new(sys, &ue.bodies, &ql, &ul, &[], Dual::cst(t), ext));
    (r.v, r.d[..2 * nq].to_vec())
}
