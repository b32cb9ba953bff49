//! The Craig–Bampton reduction basis of a structure (K, M): for interface DOFs b and
//! interior DOFs i, the static constraint modes [I; −K_ii⁻¹ K_ib] (a unit displacement of
//! each interface DOF, the interior solved statically) and the first k fixed-interface
//! normal modes [0; φ_i] (K_ii φ = ω² M_ii φ). Orthonormalizing the reduced system (its
//! eigenproblem TᵀKT x = λ TᵀMT x, as ADAMS does) gives modes T x that are mass-normalized
//! with respect to the full M and have modal stiffness diag(λ).

use nalgebra::{Cholesky, DMatrix};

use super::eigen::generalized_eigen;

/// The basis T (n × (|b| + k)), columns: constraint modes in the order of `interface`,
/// then the fixed-interface modes in ascending frequency. Errors say what is wrong.
pub fn basis(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    interface: &[usize],
    fixed_modes: usize,
) -> Result<DMatrix<f64>, String> {
    let n = k.nrows();
    let interior: Vec<usize> = (0..n).filter(|d| !interface.contains(d)).collect();
    let (nb, ni) = (interface.len(), interior.len());
    if fixed_modes > ni {
        return Err(format!("--fixed-modes {fixed_modes}: the interior has only {ni} degrees of freedom"));
    }
    let kii = k.select_rows(&interior).select_columns(&interior);
    let kib = k.select_rows(&interior).select_columns(interface);
    let mii = m.select_rows(&interior).select_columns(&interior);
    let chol = Cholesky::new(kii.clone()).ok_or("the interface does not hold the structure (K_ii is singular)")?;
    let psi = -chol.solve(&kib);
    let (_, phi) = generalized_eigen(&kii, &mii).ok_or("the interior mass matrix is not positive definite")?;
    let mut t = DMatrix::zeros(n, nb + fixed_modes);
    for (c, &d) in interface.iter().enumerate() {
        t[(d, c)] = 1.0;
    }
    for (r, &d) in interior.iter().enumerate() {
        for c in 0..nb {
            t[(d, c)] = psi[(r, c)];
        }
        for c in 0..fixed_modes {
            t[(d, nb + c)] = phi[(r, c)];
        }
    }
    Ok(t)
}

/// The reduced system's eigenpairs, expanded: eigenvalues ascending and the modes T x as
/// columns (mass-normalized with respect to M).
pub fn orthonormal_modes(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    t: &DMatrix<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>), String> {
    let kr = t.transpose() * k * t;
    let mr = t.transpose() * m * t;
    let (lam, x) = generalized_eigen(&kr, &mr).ok_or("the reduced mass matrix is not positive definite")?;
    Ok((lam, t * x))
}
