//! Checks of the square matrices of a modal data file: symmetric (relative 1e-12) and
//! positive semidefinite (every eigenvalue ≥ −1e-12 × the largest in magnitude), and of
//! mode shapes given with frequencies: mass-normalized, ΦᵀMΦ = I to 1e-6.

use nalgebra::{DMatrix, SymmetricEigen};

/// Relative tolerance of symmetry, |a_ij − a_ji| ≤ SYMMETRY_TOL · max |a|.
pub const SYMMETRY_TOL: f64 = 1e-12;
/// Relative tolerance of semidefiniteness, λ_min ≥ −PSD_TOL · max |λ|.
pub const PSD_TOL: f64 = 1e-12;
/// Absolute tolerance of mass normalization, |ΦᵀMΦ − I| ≤ NORMALIZATION_TOL entrywise.
pub const NORMALIZATION_TOL: f64 = 1e-6;

/// The first (i, j), i < j, where `a` is not symmetric, with both values.
pub fn asymmetry(a: &[Vec<f64>]) -> Option<(usize, usize)> {
    let scale = a.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    (0..a.len())
        .flat_map(|i| (i + 1..a.len()).map(move |j| (i, j)))
        .find(|&(i, j)| (a[i][j] - a[j][i]).abs() > SYMMETRY_TOL * scale)
}

/// The smallest and the largest-magnitude eigenvalue of a symmetric `a`, when the
/// smallest is below −PSD_TOL times the largest magnitude (not semidefinite).
pub fn indefinite(a: &[Vec<f64>]) -> Option<(f64, f64)> {
    let n = a.len();
    if n == 0 {
        return None;
    }
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let eig = SymmetricEigen::new(m).eigenvalues;
    let min = eig.iter().copied().fold(f64::INFINITY, f64::min);
    let max = eig.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    (min < -PSD_TOL * max).then_some((min, max))
}

/// The first entry (k, l), k ≤ l, of the modal mass where it differs from the identity
/// by more than NORMALIZATION_TOL, with its value.
pub fn not_normalized(modal_mass: &[Vec<f64>]) -> Option<(usize, usize, f64)> {
    let n = modal_mass.len();
    (0..n).flat_map(|k| (k..n).map(move |l| (k, l))).find_map(|(k, l)| {
        let want = if k == l { 1.0 } else { 0.0 };
        let v = modal_mass[k][l];
        ((v - want).abs() > NORMALIZATION_TOL || !v.is_finite()).then_some((k, l, v))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact small matrices: eigenvalues of [[1, 2], [2, 1]] are 3 and −1.
    #[test]
    fn symmetric_semidefinite_and_normalized_are_told_apart() {
        assert_eq!(asymmetry(&[vec![1.0, 2.0], vec![2.0, 1.0]]), None);
        assert_eq!(asymmetry(&[vec![1.0, 2.0], vec![2.5, 1.0]]), Some((0, 1)));
        let (min, max) = indefinite(&[vec![1.0, 2.0], vec![2.0, 1.0]]).unwrap();
        assert!((min + 1.0).abs() < 1e-14 && (max - 3.0).abs() < 1e-14);
        assert_eq!(indefinite(&[vec![1.0, 1.0], vec![1.0, 1.0]]), None);
        assert_eq!(indefinite(&[]), None);
        assert_eq!(not_normalized(&[vec![1.0, 0.0], vec![0.0, 1.0 + 1e-9]]), None);
        assert_eq!(not_normalized(&[vec![1.0, 0.5], vec![0.5, 1.0]]), Some((0, 1, 0.5)));
    }
}
