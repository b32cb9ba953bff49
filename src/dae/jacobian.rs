//! J = ∂f/∂y of the stabilized index-2 system (see [`super::equations`]), exact, from the
//! element kernels; one function per block of equations, pushed in this order.

use super::layout::Layout;
use super::sparse::Triplets;
use crate::ad::chunked;
use crate::geom::M3;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, h_angular};
use crate::mechanics::constraint_jacobian::p_row_into;
use crate::mechanics::coords::{global_column, nql, rates_into};
use crate::mechanics::flexible;
use crate::mechanics::kernels::{
    ConstraintSecond, Gathered, constraint_second_into, dhtw_dq, dqdot_dq, force_ext_jacobian, force_jacobian,
    gyroscopic, nonholonomic_second, user_jacobian,
};
use crate::mechanics::loads::{LoadGradient, LoadTerm, NLOAD, load_gradient};
use crate::mechanics::mass::body_mass_entries;

/// The point J is taken at.
struct At<'a> {
    sys: &'a System,
    lay: Layout,
    t: f64,
    y: &'a [f64],
    q: &'a [f64],
    u: &'a [f64],
    /// External values [inputs; Z; L] at y.
    ext: &'a [f64],
    /// Each body's angular block of H (Eq. 12), formed once per Jacobian: every
    /// constraint equation's P row and (Pᵀλ)_q column reads it.
    h: &'a [M3<f64>],
}

/// J = ∂f/∂y, exact except for the term ∂(C_qᵀμ)/∂q, which vanishes on the solution (μ = 0).
pub fn jacobian(sys: &System, lay: Layout, t: f64, y: &[f64], inputs: &[f64], jac: &mut Triplets) {
    jacobian_with(sys, lay, t, y, inputs, &mut JacScratch::default(), jac);
}

/// The buffers [`jacobian_with`] works in, reused from call to call: the joints between
/// rigid bodies (closed form) and the bodies then allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct JacScratch {
    /// Leave out the part of (Pᵀλ)_q that couples two bodies of a constraint element (the
    /// constraint forces' change on one body with the other's coordinates), keeping each
    /// body's own: the integrator's iteration matrix, whose graph then has no body–body
    /// edges through joints (a third less fill and half the block-LU work on a chain);
    /// false (the default): J exact.
    pub within_bodies: bool,
    /// The external values.
    ext: Vec<f64>,
    /// The bodies' angular blocks of H.
    h: Vec<M3<f64>>,
    rows: RowBuffers,
}

/// Buffers of one constraint element's rows.
#[derive(Clone, Debug, Default)]
struct RowBuffers {
    second: ConstraintSecond,
    /// The element's local q and u.
    local: Gathered,
    rates: BodyRates,
    /// (Pᵀλ)_q, local.
    lq: Vec<f64>,
    /// The element's gradients and Hessians weighted by λ and summed.
    gsum: Vec<f64>,
    hsum: Vec<f64>,
    /// A P row, a Hessian column and its Hᵀ product.
    p: Vec<f64>,
    col: Vec<f64>,
    ht: Vec<f64>,
}

/// [`jacobian`] in the buffers `ws`.
pub fn jacobian_with(
    sys: &System,
    lay: Layout,
    t: f64,
    y: &[f64],
    inputs: &[f64],
    ws: &mut JacScratch,
    jac: &mut Triplets,
) {
    lay.ext_into(sys, inputs, y, t, &mut ws.ext);
    let ext = &ws.ext;
    let q = &y[lay.q_range()];
    ws.h.clear();
    ws.h.extend((0..sys.nb()).map(|b| h_angular(q[NQ * b + 4], q[NQ * b + 5])));
    let at = At { sys, lay, t, y, q, u: &y[lay.u_range()], ext, h: &ws.h };
    let lc = LoadChain::new(sys, lay, y, t, ext);
    user_rows(&at, &lc, jac);
    kinematic_rows(&at, jac);
    flexible_rows(&at, jac);
    nonholonomic_rows(&at, jac);
    force_rows(&at, &lc, jac);
    constraint_rows(&at, ws.within_bodies, &mut ws.rows, jac);
    acceleration_rows(&at, jac);
}

/// ∂/∂y of X' = Ẋ and of the user rows (Eq. 7a–7b), loads chained through [`LoadChain`].
fn user_rows(at: &At, lc: &LoadChain, jac: &mut Triplets) {
    let (sys, lay) = (at.sys, at.lay);
    let (nz, nu, ni) = (lay.z(), lay.u(), sys.ni());
    for i in 0..lay.nx {
        jac.push(nz + i, nz + lay.nx + i, 1.0);
    }
    for (k, ue) in sys.user.iter().enumerate() {
        let row = nz + lay.nx + k;
        let uj = user_jacobian(sys, ue, at.q, at.u, at.t, at.ext);
        let nql = nql(sys, &ue.bodies);
        for a in 0..nql {
            let g = global_column(sys, &ue.bodies, a);
            jac.push(row, g, uj.dqu[a]);
            jac.push(row, nu + g, uj.dqu[nql + a]);
        }
        for (e, v) in uj.dext {
            if e >= ni + lay.nz() {
                lc.push(jac, row, e, v);
            } else if e >= ni {
                jac.push(row, nz + e - ni, v);
            }
        }
    }
}

/// ∂/∂(q, u) of q̇ = H(q) u (Eq. 13b; η̇ = u_η for modal coordinates) and of the
/// gyroscopic terms of Q of the rigid bodies, body by body.
fn kinematic_rows(at: &At, jac: &mut Triplets) {
    let nu = at.lay.u();
    for g in at.lay.body_cols..at.lay.n {
        jac.push(g, nu + g, 1.0);
    }
    for (b, body) in at.sys.bodies.iter().enumerate() {
        let o = NQ * b;
        let (qb, ub) = (&at.q[o..o + NQ], &at.u[o..o + NQ]);
        let dq = dqdot_dq(qb, ub);
        for r in 3..6 {
            for c in 3..6 {
                jac.push(o + r, o + c, dq[r * 6 + c]);
            }
        }
        // ∂q̇/∂u = H: identity for v, the Euler block for ω'.
        for c in 0..3 {
            jac.push(o + c, nu + o + c, 1.0);
        }
        let h = &at.h[b];
        for r in 0..3 {
            for c in 0..3 {
                jac.push(o + 3 + r, nu + o + 3 + c, h.0[r][c]);
            }
        }
        if at.sys.flex_of(b).is_some() {
            continue; // its inertia forces are in `flexible_rows`
        }
        let (_, gj) = gyroscopic(&body.inertia, &ub[3..6]);
        for r in 0..3 {
            for c in 0..3 {
                jac.push(nu + o + 3 + r, nu + o + 3 + c, gj[r * 3 + c]);
            }
        }
    }
}

/// ∂/∂(q_b, u_b) of a flexible body's own forces (gravity, quadratic velocity, elastic,
/// damping; [`flexible::body_forces`]), exact, seeded a chunk at a time.
fn flexible_rows(at: &At, jac: &mut Triplets) {
    let (sys, nu) = (at.sys, at.lay.u());
    for fb in &sys.flex {
        let dofs = sys.body_dofs(fb.body);
        let nb = dofs.len();
        let x: Vec<f64> = dofs.iter().map(|&g| at.q[g]).chain(dofs.iter().map(|&g| at.u[g])).collect();
        let (_, j) = chunked::jacobian(&x, |x| {
            flexible::body_forces(&fb.inv, &sys.r0[fb.body], sys.gravity, &x[..nb], &x[nb..])
        });
        for (r, &gr) in dofs.iter().enumerate() {
            for (c, &gc) in dofs.iter().enumerate() {
                jac.push(nu + gr, gc, j[r * 2 * nb + c]);
                jac.push(nu + gr, nu + gc, j[r * 2 * nb + nb + c]);
            }
        }
    }
}

/// ∂/∂y of g = B u + b (ν rows) and of −Bᵀν in the force balance.
fn nonholonomic_rows(at: &At, jac: &mut Triplets) {
    let (nu, nn) = (at.lay.u(), at.lay.nu());
    for el in &at.sys.nonholonomic {
        let s = nonholonomic_second(at.sys, el, at.q, at.u, at.t, at.ext);
        let (nql, k) = (nql(at.sys, &el.bodies), s.k);
        let mut bq = vec![0.0; 2 * nql * nql]; // Σ ν_e ∂B_e/∂(q, u), rows = u entries
        for e in 0..el.neq {
            let row = nn + el.row + e;
            let g = &s.grad[e * k..(e + 1) * k];
            let hs = &s.hess[e * k * k..(e + 1) * k * k];
            let nu_e = at.y[row];
            for a in 0..nql {
                let ga = global_column(at.sys, &el.bodies, a);
                jac.push(row, ga, g[a]);
                jac.push(row, nu + ga, g[nql + a]);
                jac.push(nu + ga, row, -g[nql + a]);
                if nu_e != 0.0 {
                    for c in 0..2 * nql {
                        bq[a * 2 * nql + c] += nu_e * hs[(nql + a) * k + c];
                    }
                }
            }
        }
        for a in 0..nql {
            let ga = global_column(at.sys, &el.bodies, a);
            for c in 0..2 * nql {
                let gc = global_column(at.sys, &el.bodies, c % nql) + if c < nql { 0 } else { nu };
                jac.push(nu + ga, gc, -bq[a * 2 * nql + c]);
            }
        }
    }
}

/// ∂Q/∂y of the force elements (over q, u, and the external values they read).
fn force_rows(at: &At, lc: &LoadChain, jac: &mut Triplets) {
    let (sys, lay) = (at.sys, at.lay);
    let (nz, nu, ni) = (lay.z(), lay.u(), sys.ni());
    for el in &sys.forces {
        let nql = nql(at.sys, &el.bodies);
        let (_, fj) = force_jacobian(sys, el, at.q, at.u, at.t, at.ext);
        for r in 0..nql {
            let gr = nu + global_column(at.sys, &el.bodies, r);
            for a in 0..nql {
                let ga = global_column(at.sys, &el.bodies, a);
                jac.push(gr, ga, fj[r * 2 * nql + a]);
                jac.push(gr, nu + ga, fj[r * 2 * nql + nql + a]);
            }
        }
        for (e, col) in force_ext_jacobian(sys, el, at.q, at.u, at.t, at.ext) {
            for (r, v) in col.iter().enumerate() {
                if e >= ni + lay.nz() {
                    lc.push(jac, nu + global_column(at.sys, &el.bodies, r), e, *v);
                } else if e >= ni {
                    jac.push(nu + global_column(at.sys, &el.bodies, r), nz + e - ni, *v);
                }
            }
        }
    }
}

/// ∂/∂y of C (λ rows), Ċ (μ rows), −Pᵀλ (force balance) and −C_qᵀμ (q̇ rows); a
/// redundant row has the identity (λ = μ = 0).
fn constraint_rows(at: &At, within_bodies: bool, ws: &mut RowBuffers, jac: &mut Triplets) {
    let (nl, nm) = (at.lay.lam(), at.lay.mu());
    for el in &at.sys.constraints {
        constraint_second_into(at.sys, el, at.q, at.t, at.ext, &mut ws.second);
        let s = &ws.second;
        let nql = nql(at.sys, &el.bodies);
        let k = s.k;
        body_rates_into(at.sys, &el.bodies, at.q, at.u, &mut ws.local, &mut ws.rates);
        ws.lq.clear();
        ws.lq.resize(nql * nql, 0.0);
        // Σ_e λ_e ∇C_e and Σ_e λ_e ∇²C_e: (Pᵀλ)_q is linear in them.
        ws.gsum.clear();
        ws.gsum.resize(k, 0.0);
        ws.hsum.clear();
        ws.hsum.resize(k * k, 0.0);
        let mut any = false;
        for e in 0..el.neq {
            let row = el.row + e;
            if at.sys.redundant[row] {
                jac.push(nl + row, nl + row, 1.0);
                jac.push(nm + row, nm + row, 1.0);
                continue;
            }
            let lam = at.y[nl + row];
            let g = &s.grad[e * k..(e + 1) * k];
            let hs = &s.hess[e * k * k..(e + 1) * k * k];
            constraint_row(at, &el.bodies, row, g, hs, &ws.rates, &mut ws.p, jac);
            if lam != 0.0 {
                any = true;
                ws.gsum.iter_mut().zip(g).for_each(|(o, v)| *o += lam * v);
                ws.hsum.iter_mut().zip(hs).for_each(|(o, v)| *o += lam * v);
            }
        }
        if any {
            add_pt_lambda_q(at, &el.bodies, &ws.gsum, &ws.hsum, (&mut ws.col, &mut ws.ht), &mut ws.lq);
        }
        push_pt_lambda_q(at, &el.bodies, &ws.lq, within_bodies, jac);
    }
}

/// q̇ = H(q) u of an element's bodies and ∂q̇/∂q of each body.
#[derive(Clone, Debug, Default)]
struct BodyRates {
    /// q̇, local (6 per body, then the modal rates η̇).
    qd: Vec<f64>,
    /// ∂q̇/∂q of each body (6 × 6, row-major).
    dq: Vec<[f64; 36]>,
}

/// The [`BodyRates`] of `bodies` at global (q, u) into `out`, gathering into `local`.
fn body_rates_into(sys: &System, bodies: &[usize], q: &[f64], u: &[f64], local: &mut Gathered, out: &mut BodyRates) {
    let (ql, ul) = local.of(sys, bodies, q, u);
    rates_into(bodies.len(), ql, ul, &mut out.qd);
    out.dq.clear();
    out.dq.extend((0..bodies.len()).map(|kb| dqdot_dq(&ql[NQ * kb..NQ * kb + NQ], &ul[NQ * kb..NQ * kb + NQ])));
}

/// The entries of one non-redundant constraint equation `row` with gradient `g` and
/// Hessian `hs` (local q then t, k = g.len()): C_q in its λ row, −C_qᵀ in its μ column
/// (q̇ rows), −Pᵀ in its λ column (u rows), P and Ċ_q in its μ row (`p`: a buffer).
#[allow(clippy::too_many_arguments)]
fn constraint_row(
    at: &At,
    bodies: &[usize],
    row: usize,
    g: &[f64],
    hs: &[f64],
    rates: &BodyRates,
    p: &mut Vec<f64>,
    jac: &mut Triplets,
) {
    let (nu, nl, nm) = (at.lay.u(), at.lay.lam(), at.lay.mu());
    let (nql, k) = (nql(at.sys, bodies), g.len());
    p.resize(nql, 0.0);
    p_row_into(bodies, |b| at.h[b], &g[..nql], p);
    for a in 0..nql {
        let ga = global_column(at.sys, bodies, a);
        // C_q (Eq. 13e rows), −C_qᵀ (q̇ rows, μ column), −Pᵀ (u rows, λ column), P (Ċ rows).
        jac.push(nl + row, ga, g[a]);
        jac.push(ga, nm + row, -g[a]);
        jac.push(nu + ga, nl + row, -p[a]);
        jac.push(nm + row, nu + ga, p[a]);
        // Ċ_q = Σ_c C_qc,qa q̇_c + C_q ∂q̇/∂q_a + C_t,qa (row a of the symmetric Hessian; a
        // modal rate η̇ does not depend on q).
        let (kb, ha) = (a / NQ, &hs[a * k..(a + 1) * k]);
        let mut v = ha[..nql].iter().zip(&rates.qd[..nql]).fold(ha[nql], |v, (h, d)| v + h * d);
        if let Some(dq) = rates.dq.get(kb) {
            let col = a % NQ;
            for (c, gc) in g[NQ * kb..NQ * kb + NQ].iter().enumerate() {
                v += gc * dq[c * 6 + col];
            }
        }
        jac.push(nm + row, ga, v);
    }
}

/// Add an element's (Pᵀλ)_q = Hᵀ ∂(C_qᵀλ)/∂q + ∂(Hᵀ w)/∂q |_{w = C_qᵀλ} to `lq` (local,
/// row-major nql × nql), from its equations' gradients and Hessians weighted by their λ
/// and summed, `g` and `hs` (`bufs`: two buffers).
fn add_pt_lambda_q(
    at: &At,
    bodies: &[usize],
    g: &[f64],
    hs: &[f64],
    bufs: (&mut Vec<f64>, &mut Vec<f64>),
    lq: &mut [f64],
) {
    let (q, nql, k) = (at.q, nql(at.sys, bodies), g.len());
    let (col, ht) = bufs;
    ht.resize(nql, 0.0);
    for a in 0..nql {
        col.clear();
        col.extend((0..nql).map(|c| hs[c * k + a]));
        p_row_into(bodies, |b| at.h[b], col, ht);
        for r in 0..nql {
            lq[r * nql + a] += ht[r];
        }
    }
    for (kb, &b) in bodies.iter().enumerate() {
        let d = dhtw_dq(&q[NQ * b..NQ * b + NQ], &g[NQ * kb..NQ * kb + NQ]);
        for r in 0..NQ {
            for c in 0..NQ {
                lq[(NQ * kb + r) * nql + NQ * kb + c] += d[r * 6 + c];
            }
        }
    }
}

/// Push −(Pᵀλ)_q of an element (`lq`, local, from [`add_pt_lambda_q`]) into its bodies'
/// u rows and q columns (`within_bodies`: only each body's rows × its own columns; a
/// flexible body's modal columns count as its own).
fn push_pt_lambda_q(at: &At, bodies: &[usize], lq: &[f64], within_bodies: bool, jac: &mut Triplets) {
    let (nu, nql) = (at.lay.u(), nql(at.sys, bodies));
    for r in 0..nql {
        let row = global_column(at.sys, bodies, r);
        let row_body = at.sys.body_of_coordinate(row);
        for a in 0..nql {
            let col = global_column(at.sys, bodies, a);
            if within_bodies && at.sys.body_of_coordinate(col) != row_body {
                continue;
            }
            jac.push(nu + row, col, -lq[r * nql + a]);
        }
    }
}

/// Bodies with acceleration unknowns: their u-row entries belong to the algebraic rows
/// M a − (Q − Pᵀλ − Bᵀν) (moved, then −M), and the u rows become u' = a.
fn acceleration_rows(at: &At, jac: &mut Triplets) {
    let (sys, lay) = (at.sys, at.lay);
    if sys.acc_bodies.is_empty() {
        return;
    }
    let nu = lay.u();
    let acc = |g: usize| lay.acc_row(&sys.acc_bodies, g).expect("a velocity of an acceleration body");
    let mut row_of = std::collections::HashMap::new();
    for &b in &sys.acc_bodies {
        for g in sys.body_dofs(b) {
            row_of.insert(nu + g, acc(g));
        }
    }
    for p in jac.idx.iter_mut() {
        if let Some(&r) = row_of.get(&p.row) {
            p.row = r;
        }
    }
    for &b in &sys.acc_bodies {
        for (r, c, v) in body_mass_entries(sys, b, at.q) {
            jac.push(acc(r), acc(c), -v);
        }
        for g in sys.body_dofs(b) {
            jac.push(nu + g, acc(g), 1.0);
        }
        if let Some(fb) = sys.flex_of(b) {
            // −∂(M(q) a)/∂q: a flexible body's mass depends on its orientation and η.
            let dofs = sys.body_dofs(b);
            let a: Vec<f64> = dofs.iter().map(|&g| at.y[acc(g)]).collect();
            let qb: Vec<f64> = dofs.iter().map(|&g| at.q[g]).collect();
            let (_, j) = chunked::jacobian(&qb, |x| {
                let ad: Vec<crate::ad::Dual<f64, { chunked::CHUNK }>> =
                    a.iter().map(|&v| crate::ad::Real::cst(v)).collect();
                flexible::body_mass_times(&fb.inv, &sys.r0[b], x, &ad)
            });
            for (r, &gr) in dofs.iter().enumerate() {
                for (c, &gc) in dofs.iter().enumerate() {
                    jac.push(acc(gr), gc, -j[r * dofs.len() + c]);
                }
            }
        }
    }
}

/// The chain rule through element loads read as external values (`System::load_refs`):
/// ∂r/∂L · ∂L/∂(q, u, λ, Z), with each load's exact gradient from [`crate::mechanics::loads`].
struct LoadChain {
    lay: Layout,
    ni: usize,
    grads: Vec<Option<LoadGradient>>,
}

impl LoadChain {
    fn new(sys: &System, lay: Layout, y: &[f64], t: f64, ext: &[f64]) -> LoadChain {
        let ni = sys.ni();
        let base = &ext[..ni + lay.nz()];
        let state = (&y[lay.q_range()], &y[lay.u_range()], &y[lay.lam_range()]);
        let grads = sys.load_refs.iter().map(|&r| load_gradient(sys, r, state, t, base)).collect();
        LoadChain { lay, ni, grads }
    }

    /// Add coeff · ∂L_e/∂(unknowns) to row `row` (e: external-value index of a load).
    fn push(&self, jac: &mut Triplets, row: usize, e: usize, coeff: f64) {
        let lay = self.lay;
        let k = e - self.ni - lay.nz();
        let Some(g) = &self.grads[k / NLOAD] else { return };
        g.terms(k % NLOAD, |term, d| match term {
            LoadTerm::Q(i) => jac.push(row, i, coeff * d),
            LoadTerm::U(i) => jac.push(row, lay.u() + i, coeff * d),
            LoadTerm::Lam(r) => jac.push(row, lay.lam() + r, coeff * d),
            LoadTerm::Ext(x) if x >= self.ni && x < self.ni + lay.nz() => {
                jac.push(row, lay.z() + x - self.ni, coeff * d)
            }
            LoadTerm::Ext(_) => {}
        });
    }
}
