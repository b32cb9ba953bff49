//! Body coordinates: q_b = [r; ψ θ φ] (3-1-3 angles relative to a reference frame R0_b),
//! u_b = [v; ω'] with v the CM velocity in ground and ω' the angular velocity in body axes.
//! u = T(q) q̇ (Eq. 12) with T = blockdiag(I, B(θ, φ)); we use H = T⁻¹.

use crate::ad::Real;
use crate::geom::{M3, V3, rot_x, rot313, rot313_sc};

/// Number of coordinates (and velocities) per body.
pub const NQ: usize = 6;

/// Angles (0, π/2, 0): far from the 3-1-3 singularity; R0 is chosen so a body starts there.
pub const FAR_FROM_SINGULAR: [f64; 3] = [0.0, std::f64::consts::FRAC_PI_2, 0.0];

/// R0 such that R0 · R313(FAR_FROM_SINGULAR) = `a`.
pub fn rebased_reference(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    M3::cst(a).mm(&rot_x(std::f64::consts::FRAC_PI_2).t()).val()
}

/// Ground position and rotation of a body from its coordinates: A = R0 · Rz(ψ)Rx(θ)Rz(φ).
pub fn body_frame<T: Real>(q: &[T], r0: &[[f64; 3]; 3]) -> (V3<T>, M3<T>) {
    let r = V3([q[0], q[1], q[2]]);
    let a = M3::cst(r0).mm(&rot313(q[3], q[4], q[5]));
    (r, a)
}

/// The angular block of H = T⁻¹ (Eq. 12): ė = Hω(θ, φ) ω'. Rows ψ̇ θ̇ φ̇, columns ω'x ω'y ω'z.
pub fn h_angular<T: Real>(theta: T, phi: T) -> M3<T> {
    h_angular_sc(theta.sin(), theta.cos(), phi.sin(), phi.cos())
}

/// [`h_angular`] from sin θ, cos θ, sin φ, cos φ.
fn h_angular_sc<T: Real>(s2: T, c2: T, s3: T, c3: T) -> M3<T> {
    let z = T::zero();
    M3([[s3 / s2, c3 / s2, z], [c3, -s3, z], [-(c2 * s3) / s2, -(c2 * c3) / s2, T::one()]])
}

/// The sines and cosines of a body's Euler angles `e` = (ψ, θ, φ).
pub fn sin_cos<T: Real>(e: &[T]) -> ([T; 3], [T; 3]) {
    (std::array::from_fn(|k| e[k].sin()), std::array::from_fn(|k| e[k].cos()))
}

/// ∂R/∂θ of R = Rz(ψ)Rx(θ)Rz(φ), written out from the sines `s` and cosines `c`.
fn d_theta_sc<T: Real>(s: [T; 3], c: [T; 3]) -> M3<T> {
    let ([s1, s2, s3], [c1, c2, c3]) = (s, c);
    M3([[s1 * s2 * s3, s1 * s2 * c3, s1 * c2], [-(c1 * s2 * s3), -(c1 * s2 * c3), -(c1 * c2)], [c2 * s3, c2 * c3, -s2]])
}

/// What a body's Euler angles give, from one sine and cosine of each: its rotation
/// A = R0 · Rz(ψ)Rx(θ)Rz(φ), the partial derivatives ∂A/∂(ψ, θ, φ), and the angular
/// block of H (Eq. 12). Computed once per body and evaluation, read by every element
/// that touches the body.
#[derive(Clone, Copy, Debug)]
pub struct Turn<T: Real> {
    /// A.
    pub a: M3<T>,
    /// ∂A/∂ψ, ∂A/∂θ, ∂A/∂φ.
    pub da: [M3<T>; 3],
    /// The angular block of H ([`h_angular`]).
    pub h: M3<T>,
}

impl<T: Real> Turn<T> {
    /// The turn of a body with reference frame `r0` at Euler angles `e` = (ψ, θ, φ).
    /// With R = Rz(ψ)Rx(θ)Rz(φ) and E = ∂Rz/∂ψ at 0 (the cross product with z, last row
    /// and column zero): ∂R/∂ψ = E R, ∂R/∂φ = R E, ∂R/∂θ written out.
    pub fn of(r0: &[[f64; 3]; 3], e: &[T]) -> Turn<T> {
        let (s, c) = sin_cos(e);
        Turn::of_sc(r0, s, c)
    }

    /// [`Turn::of`] from the sines `s` and cosines `c` of the Euler angles.
    pub fn of_sc(r0: &[[f64; 3]; 3], s: [T; 3], c: [T; 3]) -> Turn<T> {
        let ([_, s2, s3], [_, c2, c3]) = (s, c);
        let (r, z) = (rot313_sc(s, c), T::zero());
        let m = &r.0;
        let d_psi = M3([[-m[1][0], -m[1][1], -m[1][2]], m[0], [z; 3]]);
        let d_theta = d_theta_sc(s, c);
        let d_phi = M3(std::array::from_fn(|i| [m[i][1], -m[i][0], z]));
        let r0 = M3::cst(r0);
        Turn { a: r0.mm(&r), da: [r0.mm(&d_psi), r0.mm(&d_theta), r0.mm(&d_phi)], h: h_angular_sc(s2, c2, s3, c3) }
    }
}

/// The second derivatives ∂²A/∂e_m∂e_n of a body's rotation A = R0 · Rz(ψ)Rx(θ)Rz(φ) by
/// its Euler angles e = (ψ, θ, φ) (symmetric in m, n). With E as in [`Turn::of`]
/// (E² = −diag(1, 1, 0)): R_ψψ = E²R, R_φφ = RE², R_ψφ = ERE, R_ψθ = E R_θ, R_θφ = R_θ E,
/// and R_θθ = −R + (Rz(ψ) x)(Rz(φ)ᵀ x)ᵀ (x the first axis: Rx'' = −Rx + x xᵀ). From the
/// sines `s` and cosines `c` of the angles ([`sin_cos`]).
pub fn rotation_second(r0: &[[f64; 3]; 3], s: [f64; 3], c: [f64; 3]) -> [[M3<f64>; 3]; 3] {
    let (r, rt) = (rot313_sc(s, c).0, d_theta_sc(s, c).0);
    let ([s1, _, s3], [c1, _, c3]) = (s, c);
    // E M: rows (−M₁, M₀, 0); M E: columns (M·₁, −M·₀, 0).
    let el = |m: &[[f64; 3]; 3]| [[-m[1][0], -m[1][1], -m[1][2]], m[0], [0.0; 3]];
    let er = |m: &[[f64; 3]; 3]| std::array::from_fn(|i| [m[i][1], -m[i][0], 0.0]);
    let (u, v) = ([c1, s1, 0.0], [c3, -s3, 0.0]);
    let tt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| u[i] * v[j] - r[i][j]));
    let (pp, ff, pf) = (el(&el(&r)), er(&er(&r)), el(&er(&r)));
    let (pt, tf) = (el(&rt), er(&rt));
    let r0 = M3::cst(r0);
    let a = |m: [[f64; 3]; 3]| r0.mm(&M3(m));
    let (pp, pt, pf, tt, tf, ff) = (a(pp), a(pt), a(pf), a(tt), a(tf), a(ff));
    [[pp, pt, pf], [pt, tt, tf], [pf, tf, ff]]
}

/// The [`Turn`] of every body at global q (six coordinates per body; `r0`: the bodies'
/// reference frames), into `out` (its capacity reused).
pub fn body_turns(r0: &[[[f64; 3]; 3]], q: &[f64], out: &mut Vec<Turn<f64>>) {
    out.clear();
    out.extend(r0.iter().enumerate().map(|(b, r)| Turn::of(r, &q[NQ * b + 3..NQ * b + NQ])));
}

/// q̇_b = H(q_b) u_b for one body (Eq. 13b solved for q̇).
pub fn qdot<T: Real>(q: &[T], u: &[T]) -> [T; NQ] {
    qdot_with(&h_angular(q[4], q[5]), u)
}

/// [`qdot`] with the body's angular block `h` of H given.
pub fn qdot_with<T: Real>(h: &M3<T>, u: &[T]) -> [T; NQ] {
    let e = h.mv(&V3([u[3], u[4], u[5]]));
    [u[0], u[1], u[2], e.0[0], e.0[1], e.0[2]]
}

/// Hᵀ w for one body: maps a row-vector of q-derivatives to u-space.
pub fn h_transpose_times<T: Real>(q: &[T], w: &[T]) -> [T; NQ] {
    h_transpose_times_with(&h_angular(q[4], q[5]), w)
}

/// [`h_transpose_times`] with the body's angular block `h` of H given.
pub fn h_transpose_times_with<T: Real>(h: &M3<T>, w: &[T]) -> [T; NQ] {
    let e = h.tv(&V3([w[3], w[4], w[5]]));
    [w[0], w[1], w[2], e.0[0], e.0[1], e.0[2]]
}

/// A u-space row `r` (global: 6 per body for `nb` bodies, then modal entries, which T
/// leaves alone) times T(q), with u = T(q) q̇: the same linear form in q̇ (T = H⁻¹ per
/// body; T_angular maps 3-1-3 rates to body-axis ω').
pub fn row_times_t(nb: usize, q: &[f64], r: &mut [f64]) {
    for b in 0..nb {
        let o = NQ * b;
        block_times_t(&q[o..o + NQ], &mut r[o..o + NQ]);
    }
}

/// One body's block `r` (6 entries) of a u-space row times T(q_b) (see [`row_times_t`]).
pub fn block_times_t(qb: &[f64], r: &mut [f64]) {
    let (st, ct, sp, cp) = (qb[4].sin(), qb[4].cos(), qb[5].sin(), qb[5].cos());
    let t = [[st * sp, cp, 0.0], [st * cp, -sp, 0.0], [ct, 0.0, 1.0]];
    let w = [r[3], r[4], r[5]];
    for c in 0..3 {
        r[3 + c] = (0..3).map(|k| w[k] * t[k][c]).sum();
    }
}
