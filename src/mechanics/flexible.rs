//! Equations of motion of a modal flexible body in the floating frame of reference, from
//! the inertia invariants of [`crate::modal::invariants`]; every function is generic in
//! the scalar, so its exact derivatives come from dual numbers like every other kernel.
//!
//! The body's coordinates are q_b = [r; ψ θ φ; η] and velocities u_b = [v; ω'; η̇]: r and
//! v the position and velocity of the body frame's origin (ground), ω' the angular
//! velocity in body axes, η the modal coordinates. Node i sits at p_i = s_i + Φt_i η in
//! the body frame and turns by Φr_i η (small); its lumped mass m_i moves with velocity
//! v + A(ω' × p_i + Φt_i η̇), its rotary inertia J_i (body axes) spins at ω' + Φr_i η̇.
//! The kinetic energy T = ½ u_bᵀ M(q_b) u_b of these nodes defines the model:
//!
//!   M(q_b) u̇_b + h(q_b, u_b) = Q_b,
//!
//! with the full inertia coupling (M depends on η, and on the orientation through the
//! translation rows) and the quadratic-velocity vector h (centrifugal, Coriolis,
//! gyroscopic), so that energy and momenta are conserved exactly by the continuous
//! equations. Not modelled: geometric stiffening (the modal stiffness K is constant) and
//! the rotation of the nodes' rotary inertias by their small rotations.

// Index loops here mirror the subscripts of the formulas they compute.
#![allow(clippy::needless_range_loop)]

use crate::ad::Real;
use crate::geom::{M3, V3};
use crate::modal::invariants::{Invariants, Mat3};

fn m3<T: Real>(m: &Mat3) -> M3<T> {
    M3::cst(m)
}

/// Per-evaluation quantities of the deformed body: S(η) = Σ m_i p_i, the particle second
/// moment Σ m_i p_i p_iᵀ, and E_l = Σ m_i φ_il p_iᵀ for every mode l.
struct Deformed<T: Real> {
    s: V3<T>,
    ipp: M3<T>,
    e: Vec<M3<T>>,
}

fn scaled_add<T: Real>(acc: &mut M3<T>, m: &Mat3, s: T) {
    for a in 0..3 {
        for b in 0..3 {
            acc.0[a][b] += s * T::cst(m[a][b]);
        }
    }
}

fn deformed<T: Real>(inv: &Invariants, eta: &[T]) -> Deformed<T> {
    let nm = inv.nm;
    let mut s = V3::cst(inv.s0);
    for (k, &x) in eta.iter().enumerate() {
        s = s + V3::cst(inv.psi[k]).mul_s(x);
    }
    let mut e = Vec::with_capacity(nm);
    for l in 0..nm {
        let mut el = m3::<T>(&inv.p1[l]).t();
        for (k, &x) in eta.iter().enumerate() {
            scaled_add(&mut el, &inv.p2[l * nm + k], x);
        }
        e.push(el);
    }
    // Σ m p pᵀ = P0 + Σ_k η_k P1_k + Σ_k η_k E_k.
    let mut ipp = m3::<T>(&inv.p0);
    for (k, &x) in eta.iter().enumerate() {
        scaled_add(&mut ipp, &inv.p1[k], x);
        for a in 0..3 {
            for b in 0..3 {
                ipp.0[a][b] += x * e[k].0[a][b];
            }
        }
    }
    Deformed { s, ipp, e }
}

/// The inertia tensor about the body frame's origin of point masses with second moment
/// `ipp` = Σ m p pᵀ: tr(ipp) I − ipp.
fn point_inertia<T: Real>(ipp: &M3<T>) -> M3<T> {
    let tr = ipp.0[0][0] + ipp.0[1][1] + ipp.0[2][2];
    let mut j = M3(ipp.0.map(|r| r.map(|x| -x)));
    for a in 0..3 {
        j.0[a][a] += tr;
    }
    j
}

/// Σ m_i p_i × φ_il from E_l = Σ m_i φ_il p_iᵀ (its antisymmetric part).
fn cross_of<T: Real>(e: &M3<T>) -> V3<T> {
    let e = &e.0;
    V3([e[2][1] - e[1][2], e[0][2] - e[2][0], e[1][0] - e[0][1]])
}

/// Σ m_i φ_ik × φ_il from P2_kl = Σ m_i φ_ik φ_ilᵀ.
fn mode_cross(p2: &Mat3) -> [f64; 3] {
    [p2[1][2] - p2[2][1], p2[2][0] - p2[0][2], p2[0][1] - p2[1][0]]
}

/// M(q_b) a for body accelerations a = [v̇ (ground); ω̇' (body); η̈], at orientation `a_rot`
/// (columns = body axes in ground) and modal coordinates `eta`: 6 + n_m entries.
pub fn mass_times<T: Real>(inv: &Invariants, a_rot: &M3<T>, eta: &[T], acc: &[T]) -> Vec<T> {
    let d = deformed(inv, eta);
    let nm = inv.nm;
    let vdot_b = a_rot.tv(&V3([acc[0], acc[1], acc[2]]));
    let wdot = V3([acc[3], acc[4], acc[5]]);
    let etadd = &acc[6..6 + nm];
    let (mut psi_e, mut n_e) = (V3::zero(), V3::zero());
    let n: Vec<V3<T>> = (0..nm).map(|l| cross_of(&d.e[l]) + V3::cst(inv.jphi[l])).collect();
    for l in 0..nm {
        psi_e = psi_e + V3::cst(inv.psi[l]).mul_s(etadd[l]);
        n_e = n_e + n[l].mul_s(etadd[l]);
    }
    let mut out = Vec::with_capacity(6 + nm);
    let f = vdot_b.mul_s(T::cst(inv.mass)) + wdot.cross(&d.s) + psi_e;
    out.extend(a_rot.mv(&f).0);
    let jw = point_inertia(&d.ipp).mv(&wdot) + m3::<T>(&inv.j0).mv(&wdot);
    out.extend((d.s.cross(&vdot_b) + jw + n_e).0);
    for l in 0..nm {
        let mut x = V3::cst(inv.psi[l]).dot(&vdot_b) + n[l].dot(&wdot);
        for (k, &y) in etadd.iter().enumerate() {
            x += T::cst(inv.modal_mass[l * nm + k]) * y;
        }
        out.push(x);
    }
    out
}

/// The quadratic-velocity vector h(q_b, u_b) of M u̇ + h = Q (6 + n_m entries):
/// centrifugal and Coriolis terms of the nodes' masses, gyroscopic terms of their rotary
/// inertias; `w` is ω' (body axes), `etad` is η̇.
pub fn quadratic_velocity<T: Real>(inv: &Invariants, a_rot: &M3<T>, eta: &[T], w: &V3<T>, etad: &[T]) -> Vec<T> {
    let d = deformed(inv, eta);
    let nm = inv.nm;
    let mut psi_ed = V3::zero();
    let mut dmat = M3([[T::zero(); 3]; 3]); // D = Σ m d_i p_iᵀ, d_i = Φt_i η̇
    let mut jphi_ed = V3::zero();
    for (l, &x) in etad.iter().enumerate() {
        psi_ed = psi_ed + V3::cst(inv.psi[l]).mul_s(x);
        jphi_ed = jphi_ed + V3::cst(inv.jphi[l]).mul_s(x);
        for a in 0..3 {
            for b in 0..3 {
                dmat.0[a][b] += x * d.e[l].0[a][b];
            }
        }
    }
    let two = T::cst(2.0);
    let mut out = Vec::with_capacity(6 + nm);
    let hv = w.cross(&w.cross(&d.s)) + w.cross(&psi_ed).mul_s(two);
    out.extend(a_rot.mv(&hv).0);
    let tr_d = dmat.0[0][0] + dmat.0[1][1] + dmat.0[2][2];
    let spin = m3::<T>(&inv.j0).mv(w) + jphi_ed;
    let hw = w.cross(&point_inertia(&d.ipp).mv(w)) + (w.mul_s(tr_d) - dmat.mv(w)).mul_s(two) + w.cross(&spin);
    out.extend(hw.0);
    let w2 = w.dot(w);
    for l in 0..nm {
        let el = &d.e[l];
        let tr = el.0[0][0] + el.0[1][1] + el.0[2][2];
        let mut c = V3::zero();
        for (k, &x) in etad.iter().enumerate() {
            c = c + V3::cst(mode_cross(&inv.p2[k * nm + l])).mul_s(x);
        }
        out.push(w.dot(&el.mv(w)) - w2 * tr + two * w.dot(&c));
    }
    out
}

/// Generalized gravity forces (6 + n_m) for gravity `g` (ground).
pub fn gravity<T: Real>(inv: &Invariants, a_rot: &M3<T>, eta: &[T], g: [f64; 3]) -> Vec<T> {
    let d = deformed(inv, eta);
    let gb = a_rot.tv(&V3::cst(g));
    let mut out: Vec<T> = g.iter().map(|&x| T::cst(inv.mass * x)).collect();
    out.extend(d.s.cross(&gb).0);
    out.extend(inv.psi.iter().map(|p| V3::cst(*p).dot(&gb)));
    out
}

/// Elastic and damping forces K η + C η̇ (n_m entries; they enter Q with a minus sign).
pub fn elastic<T: Real>(inv: &Invariants, eta: &[T], etad: &[T]) -> Vec<T> {
    let nm = inv.nm;
    (0..nm)
        .map(|l| {
            let mut x = T::zero();
            for k in 0..nm {
                x += T::cst(inv.stiffness[l * nm + k]) * eta[k] + T::cst(inv.damping[l * nm + k]) * etad[k];
            }
            x
        })
        .collect()
}

/// The body-frame rotation A = R0 · R313(ψ, θ, φ) of body coordinates `qb`.
pub fn rotation<T: Real>(r0: &Mat3, qb: &[T]) -> M3<T> {
    M3::cst(r0).mm(&crate::geom::rot313(qb[3], qb[4], qb[5]))
}

/// The body's own generalized forces Q_b − h (6 + n_m): gravity `g`, minus the
/// quadratic-velocity vector, minus K η + C η̇ in the modal rows; `qb`, `ub` are the
/// body's coordinates and velocities [r; ψθφ; η], [v; ω'; η̇].
pub fn body_forces<T: Real>(inv: &Invariants, r0: &Mat3, g: [f64; 3], qb: &[T], ub: &[T]) -> Vec<T> {
    let a = rotation(r0, qb);
    let (eta, etad) = (&qb[6..], &ub[6..]);
    let mut out = gravity(inv, &a, eta, g);
    let h = quadratic_velocity(inv, &a, eta, &V3([ub[3], ub[4], ub[5]]), etad);
    for (o, x) in out.iter_mut().zip(&h) {
        *o -= *x;
    }
    for (o, x) in out[6..].iter_mut().zip(elastic(inv, eta, etad)) {
        *o -= x;
    }
    out
}

/// M(q_b) a_b for the body's coordinates `qb` and accelerations `ab` = [v̇; ω̇'; η̈].
pub fn body_mass_times<T: Real>(inv: &Invariants, r0: &Mat3, qb: &[T], ab: &[T]) -> Vec<T> {
    mass_times(inv, &rotation(r0, qb), &qb[6..], ab)
}

/// Potential energy of gravity `g` and of the modal stiffness: −g·(m r + A S(η)) + ½ ηᵀKη.
pub fn potential(inv: &Invariants, r0: &Mat3, g: [f64; 3], qb: &[f64]) -> f64 {
    let a = rotation(r0, qb);
    let eta = &qb[6..];
    let s = deformed(inv, eta).s;
    let first = V3([qb[0], qb[1], qb[2]]).mul_s(inv.mass) + a.mv(&s);
    let k: f64 = eta
        .iter()
        .enumerate()
        .map(|(l, x)| x * (0..inv.nm).map(|c| inv.stiffness[l * inv.nm + c] * eta[c]).sum::<f64>())
        .sum();
    -first.dot(&V3(g)) + 0.5 * k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ad::Dual;
    use crate::geom::rot313;
    use crate::mechanics::body::qdot;
    use crate::modal::data::{ModalDamping, ModalData, ModalStiffness, Node};

    /// Three nodes off the origin, two modes with translational and rotational shapes.
    fn body() -> ModalData {
        ModalData {
            description: None,
            nodes: vec![
                Node { id: 0, position: [0.1, -0.2, 0.05], mass: 1.5, inertia: [0.02, 0.03, 0.01] },
                Node { id: 1, position: [0.6, 0.1, -0.1], mass: 0.8, inertia: [0.01, 0.0, 0.04] },
                Node { id: 2, position: [1.1, 0.3, 0.2], mass: 2.1, inertia: [0.05, 0.02, 0.02] },
            ],
            modes: vec![
                vec![
                    [0.0, 0.1, 0.02, 0.3, 0.0, 0.1],
                    [0.05, -0.2, 0.1, 0.0, 0.2, -0.1],
                    [0.1, 0.3, -0.05, 0.1, 0.1, 0.4],
                ],
                vec![
                    [0.2, 0.0, -0.1, 0.0, 0.5, 0.0],
                    [-0.1, 0.15, 0.0, 0.2, -0.3, 0.1],
                    [0.0, -0.2, 0.3, -0.2, 0.0, 0.2],
                ],
            ],
            stiffness: ModalStiffness::Matrix(vec![vec![40.0, 3.0], vec![3.0, 90.0]]),
            damping: ModalDamping::None,
        }
    }

    struct Pt {
        q: Vec<f64>,
        u: Vec<f64>,
    }

    fn point() -> Pt {
        Pt { q: vec![0.3, -0.1, 0.7, 0.4, 1.1, -0.6, 0.08, -0.05], u: vec![0.5, -0.3, 0.2, 1.3, -0.7, 2.1, 0.9, -1.4] }
    }

    fn rot<T: Real>(q: &[T]) -> M3<T> {
        rot313(q[3], q[4], q[5])
    }

    /// Per node: ground velocity of its mass, and its angular velocity (body axes), as
    /// linear maps of u_b (3 × (6 + n_m) each) — the kinematics written out directly.
    fn node_maps(data: &ModalData, q: &[f64], i: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let nm = data.modes.len();
        let a = rot::<f64>(q);
        let mut p = data.nodes[i].position;
        for k in 0..nm {
            for c in 0..3 {
                p[c] += data.modes[k][i][c] * q[6 + k];
            }
        }
        let mut tv = Vec::new();
        let mut tw = Vec::new();
        for j in 0..6 + nm {
            let mut w = [0.0; 3];
            let v = match j {
                0..3 => std::array::from_fn(|c| if c == j { 1.0 } else { 0.0 }),
                3..6 => {
                    let mut e = V3::<f64>::zero();
                    e.0[j - 3] = 1.0;
                    w = e.0;
                    a.mv(&e.cross(&V3(p))).0
                }
                _ => {
                    let s = &data.modes[j - 6][i];
                    w = [s[3], s[4], s[5]];
                    a.mv(&V3([s[0], s[1], s[2]])).0
                }
            };
            tv.push(v);
            tw.push(w);
        }
        (tv, tw)
    }

    fn mass_matrix_by_nodes(data: &ModalData, q: &[f64]) -> Vec<Vec<f64>> {
        let n = 6 + data.modes.len();
        let mut m = vec![vec![0.0; n]; n];
        for (i, node) in data.nodes.iter().enumerate() {
            let (tv, tw) = node_maps(data, q, i);
            for r in 0..n {
                for c in 0..n {
                    m[r][c] += (0..3)
                        .map(|a| node.mass * tv[r][a] * tv[c][a] + node.inertia[a] * tw[r][a] * tw[c][a])
                        .sum::<f64>();
                }
            }
        }
        m
    }

    fn mass_matrix_by_invariants(inv: &Invariants, q: &[f64]) -> Vec<Vec<f64>> {
        let n = 6 + inv.nm;
        let cols: Vec<Vec<f64>> = (0..n)
            .map(|c| {
                let e: Vec<f64> = (0..n).map(|r| if r == c { 1.0 } else { 0.0 }).collect();
                mass_times(inv, &rot(q), &q[6..], &e)
            })
            .collect();
        (0..n).map(|r| (0..n).map(|c| cols[c][r]).collect()).collect()
    }

    /// M from the invariants equals Σ over nodes of (velocity map)ᵀ m (velocity map) plus
    /// the rotary terms, to rounding (1e-13: sums of a few dozen O(1) products).
    #[test]
    fn mass_matrix_equals_the_sum_over_nodes() {
        let (data, p) = (body(), point());
        let inv = Invariants::of(&data);
        let (a, b) = (mass_matrix_by_invariants(&inv, &p.q), mass_matrix_by_nodes(&data, &p.q));
        for r in 0..a.len() {
            for c in 0..a.len() {
                assert!((a[r][c] - b[r][c]).abs() < 1e-13, "M[{r}][{c}] = {} vs {}", a[r][c], b[r][c]);
            }
        }
    }

    /// The state at time t along q̇ = H u, u̇ = `udot` (first order, dual in t).
    fn moving(p: &Pt, udot: &[f64]) -> (Vec<Dual<f64, 1>>, Vec<Dual<f64, 1>>) {
        let qd = qdot(&p.q[..6], &p.u[..6]);
        let q = (0..p.q.len()).map(|i| Dual { v: p.q[i], d: [if i < 6 { qd[i] } else { p.u[i] }] }).collect();
        let u = (0..p.u.len()).map(|i| Dual { v: p.u[i], d: [udot[i]] }).collect();
        (q, u)
    }

    /// Free motion u̇ = −M⁻¹h conserves T, the linear momentum and the angular momentum
    /// about the ground origin, all computed node by node (not from the invariants) and
    /// differentiated exactly in time: their rates vanish to rounding. This is what makes
    /// h the quadratic-velocity vector of this M (it fails if any term of h is dropped:
    /// see the next test).
    #[test]
    fn free_motion_conserves_energy_and_momenta() {
        let (data, p) = (body(), point());
        let inv = Invariants::of(&data);
        let m = mass_matrix_by_invariants(&inv, &p.q);
        let h = quadratic_velocity(&inv, &rot(&p.q), &p.q[6..], &V3([p.u[3], p.u[4], p.u[5]]), &p.u[6..]);
        let (rate, scale) = invariant_rates(&data, &p, &m, &h);
        assert!(rate < 1e-12 * scale, "largest rate of T, P, H: {rate:e}");
    }

    /// The variants the issue asks for: free motion computed with M's η-dependent terms
    /// left out (M at η = 0), or with the quadratic-velocity vector left out (h = 0), or
    /// with only its modal-rate (Coriolis) terms left out (h at η̇ = 0), does not conserve
    /// T, P and H: the largest rate is over 1e-4 of their size (measured 8.8e-2, 1.4, 1.1),
    /// against 1e-12 with the full terms.
    #[test]
    fn leaving_out_eta_dependent_mass_or_quadratic_velocity_terms_breaks_conservation() {
        let (data, p) = (body(), point());
        let inv = Invariants::of(&data);
        let w = V3([p.u[3], p.u[4], p.u[5]]);
        let m = mass_matrix_by_invariants(&inv, &p.q);
        let h = quadratic_velocity(&inv, &rot(&p.q), &p.q[6..], &w, &p.u[6..]);
        let mut q_rigid = p.q.clone();
        q_rigid[6..].iter_mut().for_each(|x| *x = 0.0);
        let m_rigid = mass_matrix_by_invariants(&inv, &q_rigid);
        let h_no_coriolis = quadratic_velocity(&inv, &rot(&p.q), &p.q[6..], &w, &vec![0.0; inv.nm]);
        let variants =
            [("M at η = 0", &m_rigid, h.clone()), ("h = 0", &m, vec![0.0; h.len()]), ("h at η̇ = 0", &m, h_no_coriolis)];
        for (what, m, h) in variants {
            let (rate, scale) = invariant_rates(&data, &p, m, &h);
            eprintln!("{what}: largest rate of T, P, H {:e} (relative)", rate / scale);
            assert!(rate > 1e-4 * scale, "{what}: largest rate {rate:e} of {scale:e}");
        }
    }

    /// The largest |d/dt| of the kinetic energy and of the components of the linear and
    /// angular momentum (computed node by node, exactly in time) under u̇ = −M⁻¹h, and
    /// their size |T| + 1.
    fn invariant_rates(data: &ModalData, p: &Pt, m: &[Vec<f64>], h: &[f64]) -> (f64, f64) {
        let n = m.len();
        let nm = n - 6;
        let mm = nalgebra::DMatrix::from_fn(n, n, |r, c| m[r][c]);
        let udot = mm.lu().solve(&nalgebra::DVector::from_iterator(n, h.iter().map(|x| -x))).expect("M is regular");
        let (q, u) = moving(p, udot.as_slice());
        let a = rot(&q);
        let (mut energy, mut lin, mut ang) = (Dual::zero(), V3::<Dual<f64, 1>>::zero(), V3::<Dual<f64, 1>>::zero());
        let w = V3([u[3], u[4], u[5]]);
        for (i, node) in data.nodes.iter().enumerate() {
            let mut pb = V3::cst(node.position);
            let (mut db, mut spin) = (V3::zero(), w);
            for k in 0..nm {
                let s = &data.modes[k][i];
                pb = pb + V3::cst([s[0], s[1], s[2]]).mul_s(q[6 + k]);
                db = db + V3::cst([s[0], s[1], s[2]]).mul_s(u[6 + k]);
                spin = spin + V3::cst([s[3], s[4], s[5]]).mul_s(u[6 + k]);
            }
            let x = V3([q[0], q[1], q[2]]) + a.mv(&pb);
            let v = V3([u[0], u[1], u[2]]) + a.mv(&(w.cross(&pb) + db));
            let mi = Dual::cst(node.mass);
            let js = V3([
                spin.0[0] * Dual::cst(node.inertia[0]),
                spin.0[1] * Dual::cst(node.inertia[1]),
                spin.0[2] * Dual::cst(node.inertia[2]),
            ]);
            energy += Dual::cst(0.5) * (mi * v.dot(&v) + spin.dot(&js));
            lin = lin + v.mul_s(mi);
            ang = ang + x.cross(&v).mul_s(mi) + a.mv(&js);
        }
        let rates = [energy.d[0]].into_iter().chain((0..3).flat_map(|c| [lin.0[c].d[0], ang.0[c].d[0]]));
        (rates.fold(0.0, |acc: f64, r| acc.max(r.abs())), energy.v.abs() + 1.0)
    }

    /// Node by node, for any scalar: ground position and velocity of each node's mass,
    /// and its angular velocity (body axes), written out from the kinematics.
    fn nodes<T: Real>(data: &ModalData, q: &[T], u: &[T]) -> Vec<(V3<T>, V3<T>, V3<T>)> {
        let (a, w) = (rot(q), V3([u[3], u[4], u[5]]));
        (0..data.nodes.len())
            .map(|i| {
                let mut pb = V3::cst(data.nodes[i].position);
                let (mut db, mut spin) = (V3::zero(), w);
                for (k, mode) in data.modes.iter().enumerate() {
                    let s = &mode[i];
                    pb = pb + V3::cst([s[0], s[1], s[2]]).mul_s(q[6 + k]);
                    db = db + V3::cst([s[0], s[1], s[2]]).mul_s(u[6 + k]);
                    spin = spin + V3::cst([s[3], s[4], s[5]]).mul_s(u[6 + k]);
                }
                (V3([q[0], q[1], q[2]]) + a.mv(&pb), V3([u[0], u[1], u[2]]) + a.mv(&(w.cross(&pb) + db)), spin)
            })
            .collect()
    }

    /// Kinetic energy and ∂T/∂η̇ (n_m), node by node.
    fn energy_and_modal_momenta<T: Real>(data: &ModalData, q: &[T], u: &[T]) -> (T, Vec<T>) {
        let (mut t, mut p) = (T::zero(), vec![T::zero(); data.modes.len()]);
        let a = rot(q);
        for (i, (_, v, spin)) in nodes(data, q, u).into_iter().enumerate() {
            let (m, j) = (T::cst(data.nodes[i].mass), data.nodes[i].inertia);
            let js = V3([spin.0[0] * T::cst(j[0]), spin.0[1] * T::cst(j[1]), spin.0[2] * T::cst(j[2])]);
            t += T::cst(0.5) * (m * v.dot(&v) + spin.dot(&js));
            for (k, mode) in data.modes.iter().enumerate() {
                let s = &mode[i];
                p[k] += m * v.dot(&a.mv(&V3::cst([s[0], s[1], s[2]]))) + js.dot(&V3::cst([s[3], s[4], s[5]]));
            }
        }
        (t, p)
    }

    /// The modal rows of M u̇ + h are Lagrange's equations d/dt(∂T/∂η̇) − ∂T/∂η for T
    /// computed node by node and differentiated exactly (the modal coordinates are true
    /// coordinates): with u̇ = 0, h_η = d/dt(∂T/∂η̇) − ∂T/∂η to rounding. (Conservation
    /// alone cannot see power-free modal terms such as the modal Coriolis coupling.)
    #[test]
    fn modal_rows_are_lagranges_equations() {
        let (data, p) = (body(), point());
        let inv = Invariants::of(&data);
        let h = quadratic_velocity(&inv, &rot(&p.q), &p.q[6..], &V3([p.u[3], p.u[4], p.u[5]]), &p.u[6..]);
        let (q, u) = moving(&p, &vec![0.0; p.u.len()]);
        let (_, pm) = energy_and_modal_momenta(&data, &q, &u);
        for l in 0..inv.nm {
            let mut qe: Vec<Dual<f64, 1>> = p.q.iter().map(|&x| Dual::cst(x)).collect();
            qe[6 + l] = Dual::var(p.q[6 + l], 0);
            let ue: Vec<Dual<f64, 1>> = p.u.iter().map(|&x| Dual::cst(x)).collect();
            let (t, _) = energy_and_modal_momenta(&data, &qe, &ue);
            let lagrange = pm[l].d[0] - t.d[0];
            assert!(
                (h[6 + l] - lagrange).abs() < 1e-12 * (1.0 + lagrange.abs()),
                "mode {l}: h = {} vs {lagrange}",
                h[6 + l]
            );
        }
    }

    /// Gravity's generalized forces are the power of the node weights: for any u,
    /// uᵀQ_g = Σ m_i g·v_i (nodes' velocities written out directly).
    #[test]
    fn gravity_does_the_work_of_the_node_weights() {
        let (data, p) = (body(), point());
        let inv = Invariants::of(&data);
        let g = [0.0, -9.81, 1.5];
        let qg = gravity(&inv, &rot(&p.q), &p.q[6..], g);
        let power: f64 = qg.iter().zip(&p.u).map(|(a, b)| a * b).sum();
        let mut by_nodes = 0.0;
        for (i, node) in data.nodes.iter().enumerate() {
            let (tv, _) = node_maps(&data, &p.q, i);
            for (j, uj) in p.u.iter().enumerate() {
                by_nodes += node.mass * uj * (0..3).map(|c| g[c] * tv[j][c]).sum::<f64>();
            }
        }
        assert!((power - by_nodes).abs() < 1e-12, "{power} vs {by_nodes}");
    }
}
