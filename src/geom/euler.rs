//! Body 3-1-3 Euler angles (seed paper, Introduction): R = Rz(ψ)·Rx(θ)·Rz(φ).

use super::{M3, V3};
use crate::ad::Real;

/// Rotation about x by `a`.
pub fn rot_x<T: Real>(a: T) -> M3<T> {
    let (s, c, o, z) = (a.sin(), a.cos(), T::one(), T::zero());
    M3([[o, z, z], [z, c, -s], [z, s, c]])
}

/// Rotation about z by `a`.
pub fn rot_z<T: Real>(a: T) -> M3<T> {
    let (s, c, o, z) = (a.sin(), a.cos(), T::one(), T::zero());
    M3([[c, -s, z], [s, c, z], [z, z, o]])
}

/// R = Rz(ψ)·Rx(θ)·Rz(φ), written out.
pub fn rot313<T: Real>(psi: T, theta: T, phi: T) -> M3<T> {
    rot313_sc([psi.sin(), theta.sin(), phi.sin()], [psi.cos(), theta.cos(), phi.cos()])
}

/// [`rot313`] from the sines `s` and cosines `c` of (ψ, θ, φ).
pub fn rot313_sc<T: Real>(s: [T; 3], c: [T; 3]) -> M3<T> {
    let ([s1, s2, s3], [c1, c2, c3]) = (s, c);
    M3([
        [c1 * c3 - s1 * c2 * s3, -c1 * s3 - s1 * c2 * c3, s1 * s2],
        [s1 * c3 + c1 * c2 * s3, -s1 * s3 + c1 * c2 * c3, -c1 * s2],
        [s2 * s3, s2 * c3, c2],
    ])
}

/// Euler-angle rates from body-frame angular velocity: ė = B(e)⁻¹ ω' (the H = T⁻¹ of Eq. 12).
/// Singular at sin θ = 0; the engine re-bases each body's reference frame to stay away.
pub fn omega_to_euler_rates<T: Real>(theta: T, phi: T, w: &V3<T>) -> V3<T> {
    let (s2, c2) = (theta.sin(), theta.cos());
    let (s3, c3) = (phi.sin(), phi.cos());
    let a = (w.0[0] * s3 + w.0[1] * c3) / s2;
    V3([a, w.0[0] * c3 - w.0[1] * s3, w.0[2] - c2 * a])
}

/// (ψ, θ, φ) with θ ∈ [0, π] solving R = Rz(ψ)Rx(θ)Rz(φ).
pub fn euler313_from_matrix<T: Real>(r: &M3<T>) -> [T; 3] {
    let a = &r.0;
    let c2 = a[2][2];
    let theta = if c2.val() >= 1.0 {
        T::zero()
    } else if c2.val() <= -1.0 {
        T::cst(std::f64::consts::PI)
    } else {
        c2.acos()
    };
    if theta.val().sin().abs() < 1e-12 {
        // Gimbal lock: ψ + φ (or ψ − φ) is defined only; put everything into ψ.
        return [a[1][0].atan2(a[0][0]), theta, T::zero()];
    }
    [a[0][2].atan2(-a[1][2]), theta, a[2][0].atan2(a[2][1])]
}

/// (yaw, pitch, roll) with pitch ∈ [−π/2, π/2] solving R = Rz(yaw)Ry(pitch)Rx(roll).
pub fn ypr_from_matrix<T: Real>(r: &M3<T>) -> [T; 3] {
    let a = &r.0;
    let sp = -a[2][0];
    let pitch = if sp.val() >= 1.0 {
        T::cst(std::f64::consts::FRAC_PI_2)
    } else if sp.val() <= -1.0 {
        T::cst(-std::f64::consts::FRAC_PI_2)
    } else {
        sp.asin()
    };
    [a[1][0].atan2(a[0][0]), pitch, a[2][1].atan2(a[2][2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rot313_matches_product_and_inverts() {
        let (p, t, f) = (0.3, 1.1, -2.0);
        let r = rot313(p, t, f);
        let q = rot_z(p).mm(&rot_x(t)).mm(&rot_z(f));
        for i in 0..3 {
            for j in 0..3 {
                assert!((r.0[i][j] - q.0[i][j]).abs() < 1e-15);
            }
        }
        let e = euler313_from_matrix(&r);
        assert!((e[0] - p).abs() < 1e-12 && (e[1] - t).abs() < 1e-12 && (e[2] - f).abs() < 1e-12);
    }
}
