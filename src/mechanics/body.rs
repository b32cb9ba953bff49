//! Body coordinates: q_b = [r; ψ θ φ] (3-1-3 angles relative to a reference frame R0_b),
//! u_b = [v; ω'] with v the CM velocity in ground and ω' the angular velocity in body axes.
//! u = T(q) q̇ (Eq. 12) with T = blockdiag(I, B(θ, φ)); we use H = T⁻¹.

use crate::ad::Real;
use crate::geom::{M3, V3, rot_x, rot313};

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
    let (s2, c2) = (theta.sin(), theta.cos());
    let (s3, c3) = (phi.sin(), phi.cos());
    let z = T::zero();
    M3([[s3 / s2, c3 / s2, z], [c3, -s3, z], [-(c2 * s3) / s2, -(c2 * c3) / s2, T::one()]])
}

/// q̇_b = H(q_b) u_b for one body (Eq. 13b solved for q̇).
pub fn qdot<T: Real>(q: &[T], u: &[T]) -> [T; NQ] {
    let e = h_angular(q[4], q[5]).mv(&V3([u[3], u[4], u[5]]));
    [u[0], u[1], u[2], e.0[0], e.0[1], e.0[2]]
}

/// Hᵀ w for one body: maps a row-vector of q-derivatives to u-space.
pub fn h_transpose_times<T: Real>(q: &[T], w: &[T]) -> [T; NQ] {
    let e = h_angular(q[4], q[5]).tv(&V3([w[3], w[4], w[5]]));
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
