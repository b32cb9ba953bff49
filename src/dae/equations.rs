//! The equations of motion as the integrator sees them: y = [q; u; Z; λ; μ] and
//!   q̇ = H(q)u − C_qᵀμ            (Eq. 13b, with the GGL stabilizing term; μ = 0 exactly)
//!   M u̇ = Q(u, q, Z, v, t) − Pᵀλ (Eq. 13a, P = C_q H)
//!   Ẋ' = X-rate unknown, 0 = r(q, u, Z, v, t)  (user rows, Eq. 7a–7b; Z = (X, Ẋ, V))
//!   0 = C(q, t)                   (Eq. 13e)
//!   0 = g(q, u, t) = B u + b      (non-holonomic, multipliers ν; Bᵀν joins Pᵀλ)
//!   0 = C_q H u + C_t             (Eq. 13d)
//! with exact sparse Jacobians from the element kernels.

use super::sparse::Triplets;
use crate::mechanics::System;
use crate::mechanics::body::{NQ, h_transpose_times, qdot};
use crate::mechanics::kernels::{
    constraint_first, constraint_second, dhtw_dq, dqdot_dq, force_ext_jacobian, force_jacobian, force_values, gather,
    gyroscopic, nonholonomic_second, user_jacobian, user_residual,
};
use crate::mechanics::loads::{LoadGradient, LoadTerm, NLOAD, load_gradient};

/// Index layout of y.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    pub n: usize,
    pub m: usize,
    /// Differential states X (their rates Ẋ follow them in Z).
    pub nx: usize,
    /// User variables V.
    pub nv: usize,
    /// Non-holonomic equations (multipliers ν).
    pub mn: usize,
    /// Acceleration unknowns a (6 per body whose accelerations forces or user rows read).
    pub na: usize,
}

impl Layout {
    /// The layout of a system's equations.
    pub fn of(sys: &System) -> Layout {
        Layout { n: sys.n(), m: sys.m, nx: sys.nx, nv: sys.nv, mn: sys.mn, na: NQ * sys.acc_bodies.len() }
    }
    /// Number of user unknowns Z = (X, Ẋ, V, a).
    pub fn nz(&self) -> usize {
        2 * self.nx + self.nv + self.na
    }
    /// Offset of the acceleration unknowns a (inside Z).
    pub fn acc(&self) -> usize {
        self.z() + 2 * self.nx + self.nv
    }
    /// Total dimension 2n + nz + 2m + mn.
    pub fn dim(&self) -> usize {
        2 * self.n + self.nz() + 2 * self.m + self.mn
    }
    /// Offset of u.
    pub fn u(&self) -> usize {
        self.n
    }
    /// Offset of Z.
    pub fn z(&self) -> usize {
        2 * self.n
    }
    /// Offset of λ.
    pub fn lam(&self) -> usize {
        2 * self.n + self.nz()
    }
    /// Offset of ν (after λ).
    pub fn nu(&self) -> usize {
        2 * self.n + self.nz() + self.m
    }
    /// Offset of μ.
    pub fn mu(&self) -> usize {
        2 * self.n + self.nz() + self.m + self.mn
    }
    /// The external values [inputs; Z; L] of state `y` at time `t` (see [`System::ext`]).
    pub fn ext(&self, sys: &System, inputs: &[f64], y: &[f64], t: f64) -> Vec<f64> {
        let n = self.n;
        let state = (&y[..n], &y[n..2 * n], &y[self.lam()..self.lam() + self.m]);
        sys.ext(inputs, &y[self.z()..self.z() + self.nz()], Some(state), t)
    }
}

/// Global index of local coordinate `a` of an element touching `bodies`.
#[inline]
fn glob(bodies: &[usize], a: usize) -> usize {
    NQ * bodies[a / NQ] + a % NQ
}

/// Applied generalized forces Q(u, q, t): gravity, gyroscopic terms and force elements.
pub fn applied_forces(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64], out: &mut [f64]) {
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = NQ * b;
        for c in 0..3 {
            out[o + c] = body.mass * sys.gravity[c];
        }
        let (g, _) = gyroscopic(&body.inertia, &u[o + 3..o + 6]);
        out[o + 3..o + 6].copy_from_slice(&g);
    }
    for el in &sys.forces {
        let v = force_values(sys, el, q, u, t, inputs);
        for (a, x) in v.iter().enumerate() {
            out[glob(&el.bodies, a)] += x;
        }
    }
}

/// P row of one equation (local, 6 per body) from its C_q row: P = C_q H.
pub fn p_row(bodies: &[usize], q: &[f64], cq: &[f64]) -> Vec<f64> {
    let mut p = vec![0.0; cq.len()];
    for (k, &b) in bodies.iter().enumerate() {
        let r = h_transpose_times(&q[NQ * b..NQ * b + NQ], &cq[NQ * k..NQ * k + NQ]);
        p[NQ * k..NQ * k + NQ].copy_from_slice(&r);
    }
    p
}

/// f(t, y) of the stabilized index-2 system.
pub fn rhs(sys: &System, lay: Layout, t: f64, y: &[f64], inputs: &[f64], f: &mut [f64]) {
    let (n, nu, nl, nm) = (lay.n, lay.u(), lay.lam(), lay.mu());
    let (q, u) = (&y[..n], &y[nu..nu + n]);
    let ext = lay.ext(sys, inputs, y, t);
    let inputs = &ext[..];
    let nz = lay.z();
    for i in 0..lay.nx {
        f[nz + i] = y[nz + lay.nx + i]; // X' = Ẋ
    }
    for (k, ue) in sys.user.iter().enumerate() {
        f[nz + lay.nx + k] = user_residual(sys, ue, q, u, t, inputs); // Eq. 7a–7b
    }
    for b in 0..sys.nb() {
        let o = NQ * b;
        f[o..o + NQ].copy_from_slice(&qdot(&q[o..o + NQ], &u[o..o + NQ]));
    }
    applied_forces(sys, q, u, t, inputs, &mut f[nu..nu + n]);
    let nn = lay.nu();
    for el in &sys.nonholonomic {
        let s = nonholonomic_second(sys, el, q, u, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            let nu_e = y[nn + el.row + e];
            f[nn + el.row + e] = s.c[e]; // g = B u + b = 0
            for a in 0..nql {
                f[nu + glob(&el.bodies, a)] -= s.grad[e * s.k + nql + a] * nu_e; // −Bᵀν
            }
        }
    }
    for el in &sys.constraints {
        let cf = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        let ul = gather(&el.bodies, u);
        for e in 0..el.neq {
            let row = el.row + e;
            if sys.redundant[row] {
                // Redundant row: λ = μ = 0 replace C = 0 and Ċ = 0.
                f[nl + row] = y[nl + row];
                f[nm + row] = y[nm + row];
                continue;
            }
            let cq = &cf.cq[e * nql..(e + 1) * nql];
            let p = p_row(&el.bodies, q, cq);
            let (lam, mu) = (y[nl + row], y[nm + row]);
            f[nl + row] = cf.c[e];
            f[nm + row] = p.iter().zip(&ul).map(|(a, b)| a * b).sum::<f64>() + cf.ct[e];
            for a in 0..nql {
                let g = glob(&el.bodies, a);
                f[nu + g] -= p[a] * lam;
                f[g] -= cq[a] * mu;
            }
        }
    }
    // Bodies with acceleration unknowns: u' = a, and M a = Q − Pᵀλ − Bᵀν as algebraic rows.
    for (k, &b) in sys.acc_bodies.iter().enumerate() {
        let (o, ra) = (nu + NQ * b, lay.acc() + NQ * k);
        let ma = mass_times(&sys.bodies[b], &y[ra..ra + NQ]);
        for c in 0..NQ {
            f[ra + c] = f[o + c] - ma[c];
            f[o + c] = y[ra + c];
        }
    }
}

/// J = ∂f/∂y, exact except for the term ∂(C_qᵀμ)/∂q, which vanishes on the solution (μ = 0).
pub fn jacobian(sys: &System, lay: Layout, t: f64, y: &[f64], inputs: &[f64], jac: &mut Triplets) {
    let (n, nu, nl, nm) = (lay.n, lay.u(), lay.lam(), lay.mu());
    let (q, u) = (&y[..n], &y[nu..nu + n]);
    let ext = lay.ext(sys, inputs, y, t);
    let inputs = &ext[..];
    let (nz, ni) = (lay.z(), sys.ni());
    let lc = LoadChain::new(sys, lay, y, t, &ext);
    for i in 0..lay.nx {
        jac.push(nz + i, nz + lay.nx + i, 1.0);
    }
    for (k, ue) in sys.user.iter().enumerate() {
        let row = nz + lay.nx + k;
        let uj = user_jacobian(sys, ue, q, u, t, inputs);
        let nql = NQ * ue.bodies.len();
        for a in 0..nql {
            let g = glob(&ue.bodies, a);
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
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = NQ * b;
        let (qb, ub) = (&q[o..o + NQ], &u[o..o + NQ]);
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
        let h = crate::mechanics::body::h_angular(qb[4], qb[5]);
        for r in 0..3 {
            for c in 0..3 {
                jac.push(o + 3 + r, nu + o + 3 + c, h.0[r][c]);
            }
        }
        let (_, gj) = gyroscopic(&body.inertia, &ub[3..6]);
        for r in 0..3 {
            for c in 0..3 {
                jac.push(nu + o + 3 + r, nu + o + 3 + c, gj[r * 3 + c]);
            }
        }
    }
    let nn = lay.nu();
    for el in &sys.nonholonomic {
        let s = nonholonomic_second(sys, el, q, u, t, inputs);
        let (nql, k) = (NQ * el.bodies.len(), s.k);
        let mut bq = vec![0.0; 2 * nql * nql]; // Σ ν_e ∂B_e/∂(q, u), rows = u entries
        for e in 0..el.neq {
            let row = nn + el.row + e;
            let g = &s.grad[e * k..(e + 1) * k];
            let hs = &s.hess[e * k * k..(e + 1) * k * k];
            let nu_e = y[row];
            for a in 0..nql {
                let ga = glob(&el.bodies, a);
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
            let ga = glob(&el.bodies, a);
            for c in 0..2 * nql {
                let gc = glob(&el.bodies, c % nql) + if c < nql { 0 } else { nu };
                jac.push(nu + ga, gc, -bq[a * 2 * nql + c]);
            }
        }
    }
    for el in &sys.forces {
        let nql = NQ * el.bodies.len();
        let (_, fj) = force_jacobian(sys, el, q, u, t, inputs);
        for r in 0..nql {
            let gr = nu + glob(&el.bodies, r);
            for a in 0..nql {
                let ga = glob(&el.bodies, a);
                jac.push(gr, ga, fj[r * 2 * nql + a]);
                jac.push(gr, nu + ga, fj[r * 2 * nql + nql + a]);
            }
        }
        for (e, col) in force_ext_jacobian(sys, el, q, u, t, inputs) {
            for (r, v) in col.iter().enumerate() {
                if e >= ni + lay.nz() {
                    lc.push(jac, nu + glob(&el.bodies, r), e, *v);
                } else if e >= ni {
                    jac.push(nu + glob(&el.bodies, r), nz + e - ni, *v);
                }
            }
        }
    }
    for el in &sys.constraints {
        let s = constraint_second(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        let k = s.k;
        let ql = gather(&el.bodies, q);
        let ul = gather(&el.bodies, u);
        let mut qd = vec![0.0; nql];
        let mut dq = Vec::with_capacity(el.bodies.len());
        for kb in 0..el.bodies.len() {
            let r = NQ * kb..NQ * kb + NQ;
            qd[r.clone()].copy_from_slice(&qdot(&ql[r.clone()], &ul[r.clone()]));
            dq.push(dqdot_dq(&ql[r.clone()], &ul[r]));
        }
        let mut lq = vec![0.0; nql * nql];
        for e in 0..el.neq {
            let row = el.row + e;
            if sys.redundant[row] {
                jac.push(nl + row, nl + row, 1.0);
                jac.push(nm + row, nm + row, 1.0);
                continue;
            }
            let lam = y[nl + row];
            let g = &s.grad[e * k..(e + 1) * k];
            let hs = &s.hess[e * k * k..(e + 1) * k * k];
            let p = p_row(&el.bodies, q, &g[..nql]);
            for a in 0..nql {
                let ga = glob(&el.bodies, a);
                // C_q (Eq. 13e rows), −C_qᵀ (q̇ rows, μ column), −Pᵀ (u rows, λ column), P (Ċ rows).
                jac.push(nl + row, ga, g[a]);
                jac.push(ga, nm + row, -g[a]);
                jac.push(nu + ga, nl + row, -p[a]);
                jac.push(nm + row, nu + ga, p[a]);
                // Ċ_q = Σ_c C_qc,qa q̇_c + C_q ∂q̇/∂q_a + C_t,qa.
                let kb = a / NQ;
                let mut v = hs[a * k + nql];
                for c in 0..nql {
                    v += hs[c * k + a] * qd[c];
                }
                for c in 0..NQ {
                    v += g[NQ * kb + c] * dq[kb][c * 6 + a % NQ];
                }
                jac.push(nm + row, ga, v);
            }
            if lam != 0.0 {
                // (Pᵀλ)_q = λ [Hᵀ ∂C_q/∂q + ∂(Hᵀ w)/∂q |_{w = C_q}].
                for a in 0..nql {
                    let col: Vec<f64> = (0..nql).map(|c| hs[c * k + a]).collect();
                    let ht = p_row(&el.bodies, q, &col);
                    for r in 0..nql {
                        lq[r * nql + a] += lam * ht[r];
                    }
                }
                for (kb, &b) in el.bodies.iter().enumerate() {
                    let d = dhtw_dq(&q[NQ * b..NQ * b + NQ], &g[NQ * kb..NQ * kb + NQ]);
                    for r in 0..NQ {
                        for c in 0..NQ {
                            lq[(NQ * kb + r) * nql + NQ * kb + c] += lam * d[r * 6 + c];
                        }
                    }
                }
            }
        }
        for r in 0..nql {
            for a in 0..nql {
                jac.push(nu + glob(&el.bodies, r), glob(&el.bodies, a), -lq[r * nql + a]);
            }
        }
    }
    // Bodies with acceleration unknowns: their u-row entries belong to the algebraic rows
    // M a − (Q − Pᵀλ − Bᵀν) (moved, then −M), and the u rows become u' = a.
    if !sys.acc_bodies.is_empty() {
        let mut row_of = std::collections::HashMap::new();
        for (k, &b) in sys.acc_bodies.iter().enumerate() {
            for c in 0..NQ {
                row_of.insert(nu + NQ * b + c, lay.acc() + NQ * k + c);
            }
        }
        for p in jac.idx.iter_mut() {
            if let Some(&r) = row_of.get(&p.row) {
                p.row = r;
            }
        }
        for (k, &b) in sys.acc_bodies.iter().enumerate() {
            let ra = lay.acc() + NQ * k;
            let body = &sys.bodies[b];
            for c in 0..3 {
                jac.push(ra + c, ra + c, -body.mass);
            }
            for r in 0..3 {
                for c in 0..3 {
                    jac.push(ra + 3 + r, ra + 3 + c, -body.inertia[r][c]);
                }
            }
            for c in 0..NQ {
                jac.push(nu + NQ * b + c, ra + c, 1.0);
            }
        }
    }
}

/// The constant mass matrix diag(I, M, [I 0 0], 0, 0) of the integrator's M y' = f.
pub fn mass_matrix(sys: &System, lay: Layout, m: &mut Triplets) {
    for i in 0..lay.n {
        m.push(i, i, 1.0);
    }
    for i in 0..lay.nx {
        m.push(lay.z() + i, lay.z() + i, 1.0);
    }
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = lay.u() + NQ * b;
        if sys.acc_bodies.contains(&b) {
            for c in 0..NQ {
                m.push(o + c, o + c, 1.0); // u' = a
            }
            continue;
        }
        for c in 0..3 {
            m.push(o + c, o + c, body.mass);
        }
        for r in 0..3 {
            for c in 0..3 {
                m.push(o + 3 + r, o + 3 + c, body.inertia[r][c]);
            }
        }
    }
}

/// γ of the acceleration constraint P u̇ + γ = 0 (Eq. 1c): the part of C̈ free of u̇.
pub fn acceleration_rhs(sys: &System, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> Vec<f64> {
    let mut gamma = vec![0.0; sys.m];
    for el in &sys.constraints {
        let s = constraint_second(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        let k = s.k;
        let ql = gather(&el.bodies, q);
        let ul = gather(&el.bodies, u);
        // z' = (q̇, 1): γ = z'ᵀ ∇²C z' + C_q (∂q̇/∂q) q̇.
        let mut zd = vec![1.0; k];
        let mut extra = vec![0.0; nql];
        for kb in 0..el.bodies.len() {
            let r = NQ * kb..NQ * kb + NQ;
            let qd = qdot(&ql[r.clone()], &ul[r.clone()]);
            zd[r.clone()].copy_from_slice(&qd);
            let dq = dqdot_dq(&ql[r.clone()], &ul[r]);
            for i in 0..NQ {
                extra[NQ * kb + i] = (0..NQ).map(|c| dq[i * 6 + c] * qd[c]).sum();
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

/// γ of the non-holonomic acceleration constraint B u̇ + γ = 0: ġ at u̇ = 0, i.e.
/// g_q q̇ + g_t.
pub fn nonholonomic_gamma(sys: &System, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> Vec<f64> {
    let mut gamma = vec![0.0; sys.mn];
    for el in &sys.nonholonomic {
        let s = nonholonomic_second(sys, el, q, u, t, ext);
        let nql = NQ * el.bodies.len();
        let (ql, ul) = (gather(&el.bodies, q), gather(&el.bodies, u));
        let mut qd = vec![0.0; nql];
        for kb in 0..el.bodies.len() {
            let r = NQ * kb..NQ * kb + NQ;
            qd[r.clone()].copy_from_slice(&qdot(&ql[r.clone()], &ul[r]));
        }
        for e in 0..el.neq {
            let g = &s.grad[e * s.k..(e + 1) * s.k];
            gamma[el.row + e] = (0..nql).map(|a| g[a] * qd[a]).sum::<f64>() + g[2 * nql];
        }
    }
    gamma
}

/// B = ∂g/∂u of the non-holonomic constraints as (row, global column, value), with g.
pub fn nonholonomic_b(sys: &System, q: &[f64], u: &[f64], t: f64, ext: &[f64]) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let mut b = Vec::new();
    let mut g = vec![0.0; sys.mn];
    for el in &sys.nonholonomic {
        let s = nonholonomic_second(sys, el, q, u, t, ext);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            g[el.row + e] = s.c[e];
            for a in 0..nql {
                b.push((el.row + e, glob(&el.bodies, a), s.grad[e * s.k + nql + a]));
            }
        }
    }
    (b, g)
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
        let (n, ni) = (lay.n, sys.ni());
        let base = &ext[..ni + lay.nz()];
        let state = (&y[..n], &y[n..2 * n], &y[lay.lam()..lay.lam() + lay.m]);
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

/// M_b a for one body (a = [v̇; ω̇'], constant mass matrix).
fn mass_times(body: &crate::mechanics::system::BodyProps, a: &[f64]) -> [f64; NQ] {
    let mut out = [0.0; NQ];
    for c in 0..3 {
        out[c] = body.mass * a[c];
        out[3 + c] = (0..3).map(|k| body.inertia[c][k] * a[3 + k]).sum();
    }
    out
}
