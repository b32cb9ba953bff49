//! The generalized symmetric eigenproblem K φ = λ M φ with M symmetric positive definite
//! (diagonal for a lumped mass matrix, dense for a reduced one): M = L Lᵀ (Cholesky; for
//! a diagonal M, L = M^{1/2}), the standard problem L⁻¹ K L⁻ᵀ ψ = λ ψ solved by nalgebra's
//! SymmetricEigen, φ = L⁻ᵀ ψ. The φ are mass-orthonormal (ΦᵀMΦ = I, ΦᵀKΦ = diag(λ)).

use nalgebra::{Cholesky, DMatrix};

/// Eigenvalues ascending and the mass-normalized eigenvectors as columns (each signed so
/// that its entry of largest magnitude is positive); `None` if M is not positive definite.
pub fn generalized_eigen(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let n = k.nrows();
    let l = Cholesky::new(symmetric(m))?.l();
    let linv_k = l.solve_lower_triangular(&symmetric(k))?;
    let a = l.solve_lower_triangular(&linv_k.transpose())?;
    let eig = nalgebra::SymmetricEigen::new(symmetric(&a));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let psi = DMatrix::from_fn(n, n, |r, c| eig.eigenvectors[(r, order[c])]);
    let mut phi = l.transpose().solve_upper_triangular(&psi)?;
    for mut col in phi.column_iter_mut() {
        let big = col.iter().copied().fold(0.0_f64, |b, v| if v.abs() > b.abs() { v } else { b });
        if big < 0.0 {
            col.neg_mut();
        }
    }
    Some((order.iter().map(|&i| eig.eigenvalues[i]).collect(), phi))
}

/// (A + Aᵀ)/2: removes the rounding asymmetry of products.
fn symmetric(a: &DMatrix<f64>) -> DMatrix<f64> {
    (a + a.transpose()) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-DOF spring chain with masses 1 and 2: λ from the characteristic polynomial
    /// det(K − λM) = 2λ² − 7λ + 2 = 0 → λ = (7 ∓ √33)/4 (up to the solver's rounding: 1e-12).
    #[test]
    fn eigenpairs_are_mass_orthonormal_and_sorted() {
        let k = DMatrix::from_row_slice(2, 2, &[3.0, -1.0, -1.0, 1.0]);
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 2.0]);
        let (lam, phi) = generalized_eigen(&k, &m).unwrap();
        let root = 33.0_f64.sqrt();
        assert!((lam[0] - (7.0 - root) / 4.0).abs() < 1e-12 && (lam[1] - (7.0 + root) / 4.0).abs() < 1e-12, "{lam:?}");
        let i = phi.transpose() * &m * &phi;
        assert!((i - DMatrix::identity(2, 2)).amax() < 1e-12);
        let d = phi.transpose() * &k * &phi;
        assert!((d - DMatrix::from_diagonal(&nalgebra::DVector::from_vec(lam))).amax() < 1e-12);
    }
}
