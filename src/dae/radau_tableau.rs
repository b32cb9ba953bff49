//! The 3-stage Radau IIA tableau (order 5) and the transformation T that block-diagonalizes
//! A⁻¹ into one real eigenvalue γ and a complex pair α ± iβ (Hairer & Wanner IV.8).

use nalgebra::Matrix3;

/// Radau IIA constants used by the integrator.
#[derive(Clone, Copy, Debug)]
pub struct Tableau {
    /// Collocation nodes.
    pub c: [f64; 3],
    /// Real eigenvalue of A⁻¹.
    pub gamma: f64,
    /// Real part α of the complex eigenvalue pair α ± iβ of A⁻¹.
    pub alpha: f64,
    /// Imaginary part β (> 0) of that pair.
    pub beta: f64,
    /// T, row-major, columns: the real eigenvector of A⁻¹, then the real and imaginary
    /// parts of the one for α + iβ; the stage increments are Z = (T ⊗ I) W.
    pub t: [[f64; 3]; 3],
    /// T⁻¹, row-major: W = (T⁻¹ ⊗ I) Z.
    pub ti: [[f64; 3]; 3],
    /// Embedded error estimate weights (err = (γ/h M − J)⁻¹ (f0 + M Σ dd_i Z_i / h)).
    pub dd: [f64; 3],
}

/// The Radau IIA (s = 3) coefficient matrix A in closed form.
fn radau_a() -> Matrix3<f64> {
    let s6 = 6f64.sqrt();
    Matrix3::new(
        (88.0 - 7.0 * s6) / 360.0,
        (296.0 - 169.0 * s6) / 1800.0,
        (-2.0 + 3.0 * s6) / 225.0,
        (296.0 + 169.0 * s6) / 1800.0,
        (88.0 + 7.0 * s6) / 360.0,
        (-2.0 - 3.0 * s6) / 225.0,
        (16.0 - s6) / 36.0,
        (16.0 + s6) / 36.0,
        1.0 / 9.0,
    )
}

impl Tableau {
    /// Build from the closed-form coefficients of Radau IIA (s = 3).
    pub fn new() -> Tableau {
        let s6 = 6f64.sqrt();
        let a = radau_a();
        let ainv = a.try_inverse().expect("Radau IIA A is invertible");
        let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
        let gamma = 30.0 / (6.0 + c81 - c9);
        let (a0, b0) = ((12.0 - c81 + c9) / 60.0, (c81 + c9) * 3f64.sqrt() / 60.0);
        let cno = a0 * a0 + b0 * b0;
        let (alpha, beta) = (a0 / cno, b0 / cno);
        // Real eigenvector: null vector of A⁻¹ − γI (cross product of two rows).
        let m = ainv - Matrix3::identity() * gamma;
        let v1 = m.row(0).transpose().cross(&m.row(1).transpose());
        // Complex eigenvector for α + iβ: cross product of two rows of A⁻¹ − (α + iβ)I.
        let row = |i: usize| -> [(f64, f64); 3] {
            std::array::from_fn(|j| (ainv[(i, j)] - if i == j { alpha } else { 0.0 }, if i == j { -beta } else { 0.0 }))
        };
        let mul = |x: (f64, f64), y: (f64, f64)| (x.0 * y.0 - x.1 * y.1, x.0 * y.1 + x.1 * y.0);
        let sub = |x: (f64, f64), y: (f64, f64)| (x.0 - y.0, x.1 - y.1);
        let (r0, r1) = (row(0), row(1));
        let v2: [(f64, f64); 3] = [
            sub(mul(r0[1], r1[2]), mul(r0[2], r1[1])),
            sub(mul(r0[2], r1[0]), mul(r0[0], r1[2])),
            sub(mul(r0[0], r1[1]), mul(r0[1], r1[0])),
        ];
        let t = Matrix3::new(v1[0], v2[0].0, v2[0].1, v1[1], v2[1].0, v2[1].1, v1[2], v2[2].0, v2[2].1);
        let ti = t.try_inverse().expect("eigenvectors are independent");
        let to_arr =
            |m: &Matrix3<f64>| -> [[f64; 3]; 3] { std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])) };
        Tableau {
            c: [(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0],
            gamma,
            alpha,
            beta,
            t: to_arr(&t),
            ti: to_arr(&ti),
            dd: [-(13.0 + 7.0 * s6) / 3.0, (-13.0 + 7.0 * s6) / 3.0, -1.0 / 3.0],
        }
    }
}

impl Default for Tableau {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transformation_block_diagonalizes_a_inverse() {
        let tb = Tableau::new();
        let t = Matrix3::from_fn(|i, j| tb.t[i][j]);
        let ti = Matrix3::from_fn(|i, j| tb.ti[i][j]);
        let a = radau_a();
        let lam = ti * a.try_inverse().unwrap() * t;
        let want = Matrix3::new(tb.gamma, 0.0, 0.0, 0.0, tb.alpha, tb.beta, 0.0, -tb.beta, tb.alpha);
        assert!((lam - want).abs().max() < 1e-12, "{lam}");
        // Known value of the real eigenvalue of A^-1 (Hairer & Wanner): 3.637834252744496.
        assert!((tb.gamma - 3.637834252744496).abs() < 1e-12);
    }
}
