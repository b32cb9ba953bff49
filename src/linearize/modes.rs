//! The K eigenvalues of the linearized system nearest a real shift σ without forming A:
//! shift-invert Arnoldi on the sparse pencil (J, M) of the DAE M y' = f(t, y) itself
//! (J = ∂f/∂y, the integrator's exact sparse Jacobian). The operator
//! v ↦ (J − σM)⁻¹ M v, factored once (sparse LU, as the integrator's matrix), has the
//! eigenvalues θ = 1/(λ − σ) for the finite eigenvalues λ of the pencil and θ = 0 for its
//! infinite ones (the constraint directions), so the wanted λ are the θ of largest modulus.
//! Restarts keep the wanted Ritz vectors (a Krylov–Schur-type thick restart, G. W.
//! Stewart, SIAM J. Matrix Anal. Appl. 23, 2001): A W = W G + v gᵀ holds with W spanning
//! real invariant subspaces of the projected matrix, and the Arnoldi process continues
//! from the old residual vector. Memory and work grow with n times the subspace size.
//!
//! The finite spectrum of the pencil is that of A (seed Eq. 36) at an equilibrium, where
//! it does not depend on the coordinates; at a moving operating point the pencil's
//! eigenvalues are those of the engine's redundant coordinates, which differ, so the
//! caller checks for an equilibrium first ([`equilibrium_residual`]).

use crate::dae::sparse::{SparseLu, Triplets};
use faer::{Mat, c64};

/// Relative residual ‖(Op − θ)x‖ ≤ this · |θ| of each wanted Ritz pair: eigenvalues to
/// about 1e-12 relative for well-conditioned ones.
const RESIDUAL_TOL: f64 = 1e-13;
/// Most restarts (each with up to `subspace` operator applications).
const MAX_RESTARTS: usize = 200;

/// What [`shift_invert_modes`] found.
#[derive(Clone, Debug)]
pub struct Modes {
    /// The eigenvalues nearest the shift, nearest first (conjugate pairs kept together).
    pub eigenvalues: Vec<c64>,
    /// The shift used (the one asked for, or moved off a singular pencil).
    pub shift: f64,
    /// Operator applications (sparse triangular solve pairs) and restarts.
    pub solves: usize,
    /// Restarts of the Arnoldi process.
    pub restarts: usize,
    /// Dimension of the Krylov subspace.
    pub subspace: usize,
}

/// Largest |f| over the differential rows (those M acts on), relative to 1 + the largest
/// |y| of the multipliers (`mult` range): zero at an equilibrium.
pub fn equilibrium_residual(f: &[f64], m: &Triplets, y_mult: &[f64]) -> f64 {
    let scale = 1.0 + y_mult.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut worst = 0.0f64;
    for e in &m.idx {
        worst = worst.max(f[e.row].abs());
    }
    worst / scale
}

/// The `k` eigenvalues of the pencil J − λM (n × n, singular M) nearest `shift`, among at
/// most `finite` finite ones. If J − σM is singular (σ an eigenvalue, e.g. 0 with rigid
/// or non-holonomic zero modes) σ moves to −10⁻³, −10⁻², … (rad/s) until it factors.
pub fn shift_invert_modes(
    j: &Triplets,
    m: &Triplets,
    n: usize,
    k: usize,
    finite: usize,
    shift: f64,
) -> Result<Modes, String> {
    let k = k.min(finite);
    if k == 0 || n == 0 {
        return Ok(Modes { eigenvalues: vec![], shift, solves: 0, restarts: 0, subspace: 0 });
    }
    let (mut lu, sigma) = factor_shifted(j, m, n, shift)?;
    // Subspace: room for the wanted pairs and as many again (faster convergence).
    let dim = (2 * k + 20).max(30).min(finite + 1).min(n);
    let mut op = Operator { lu: &mut lu, m, n, tmp: vec![0.0; n], solves: 0 };
    let (eigs, restarts) = arnoldi(&mut op, k, dim)?;
    let eigenvalues = eigs.iter().map(|th| c64::new(sigma, 0.0) + c64::new(1.0, 0.0) / *th).collect();
    Ok(Modes { eigenvalues, shift: sigma, solves: op.solves, restarts, subspace: dim })
}

/// J − σM factored, with σ moved off the spectrum if it is singular there.
fn factor_shifted(j: &Triplets, m: &Triplets, n: usize, shift: f64) -> Result<(SparseLu, f64), String> {
    let mut idx = j.idx.clone();
    idx.extend_from_slice(&m.idx);
    let mut last = String::new();
    for attempt in 0..6 {
        let sigma = if attempt == 0 { shift } else { shift - 10f64.powi(attempt - 4) };
        let mut vals = j.vals.clone();
        vals.extend(m.vals.iter().map(|v| -sigma * v));
        let mut lu = SparseLu::new();
        match lu.factor_values(n, &idx, &vals) {
            Ok(()) => {
                // A singular matrix may factor with a tiny pivot: check a solve.
                let mut b = vec![1.0; n];
                if lu.solve(&mut b) && b.iter().all(|v| v.is_finite() && v.abs() < 1e14) {
                    return Ok((lu, sigma));
                }
                last = "a solve with it is not finite".into();
            }
            Err(e) => last = e,
        }
    }
    Err(format!("J − σM is singular near σ = {shift}: {last}"))
}

/// v ↦ (J − σM)⁻¹ M v.
struct Operator<'a> {
    lu: &'a mut SparseLu,
    m: &'a Triplets,
    n: usize,
    tmp: Vec<f64>,
    solves: usize,
}

impl Operator<'_> {
    fn apply(&mut self, v: &[f64], out: &mut [f64]) -> Result<(), String> {
        out.fill(0.0);
        self.m.mul_add(v, out);
        self.tmp.copy_from_slice(out);
        if !self.lu.solve(&mut self.tmp) {
            return Err("shift-invert solve failed".into());
        }
        out.copy_from_slice(&self.tmp);
        self.solves += 1;
        Ok(())
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Orthogonalize w against the basis (classical Gram–Schmidt, twice), returning the
/// coefficients.
fn orthogonalize(basis: &[Vec<f64>], w: &mut [f64]) -> Vec<f64> {
    let mut h = vec![0.0; basis.len()];
    for _ in 0..2 {
        for (i, v) in basis.iter().enumerate() {
            let c = dot(v, w);
            h[i] += c;
            for (wi, vi) in w.iter_mut().zip(v) {
                *wi -= c * vi;
            }
        }
    }
    h
}

/// A deterministic start vector with every component nonzero, made to lie in the range
/// of the operator (two applications remove the components of the infinite eigenvalues,
/// whose Jordan chains are at most of length 2 in the stabilized index-2 form).
fn start_vector(op: &mut Operator) -> Result<Vec<f64>, String> {
    let n = op.n;
    let mut v: Vec<f64> = (0..n).map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0).collect();
    let mut w = vec![0.0; n];
    for _ in 0..2 {
        op.apply(&v, &mut w)?;
        let s = norm(&w);
        if !(s > 0.0 && s.is_finite()) {
            return Err("the operator maps the start vector to zero".into());
        }
        for (vi, wi) in v.iter_mut().zip(&w) {
            *vi = wi / s;
        }
    }
    Ok(v)
}

/// The `k` eigenvalues θ of largest modulus of the operator (with conjugates kept
/// together), and the number of restarts.
fn arnoldi(op: &mut Operator, k: usize, dim: usize) -> Result<(Vec<c64>, usize), String> {
    let n = op.n;
    let mut basis: Vec<Vec<f64>> = vec![start_vector(op)?];
    // hbar: (dim + 1) × dim, A V_dim = V_{dim+1} hbar.
    let mut hbar = Mat::<f64>::zeros(dim + 1, dim);
    let mut w = vec![0.0; n];
    let mut restarts = 0;
    let mut first = 0;
    loop {
        let mut m = dim;
        for jcol in first..dim {
            op.apply(&basis[jcol], &mut w)?;
            let h = orthogonalize(&basis, &mut w);
            for (i, hi) in h.iter().enumerate() {
                hbar[(i, jcol)] = *hi;
            }
            let beta = norm(&w);
            hbar[(jcol + 1, jcol)] = beta;
            let scale = h.iter().fold(beta, |a, v| a.max(v.abs()));
            if beta <= 1e-14 * scale {
                // An invariant subspace: its eigenvalues are exact.
                m = jcol + 1;
                break;
            }
            basis.push(w.iter().map(|v| v / beta).collect());
        }
        let h = hbar.submatrix(0, 0, m, m).to_owned();
        let eig = h.eigen().map_err(|e| format!("eigenvalues of the projected matrix: {e:?}"))?;
        let (s, u) = (eig.S(), eig.U());
        let mut order: Vec<usize> = (0..m).collect();
        let modulus = |i: usize| {
            let z = s.column_vector()[i];
            z.re.hypot(z.im)
        };
        order.sort_by(|&a, &b| {
            modulus(b).total_cmp(&modulus(a)).then(s.column_vector()[a].im.total_cmp(&s.column_vector()[b].im))
        });
        // The wanted: the k largest, and a conjugate cut in two completed.
        let mut want = k.min(m);
        if want < m {
            let (a, b) = (s.column_vector()[order[want - 1]], s.column_vector()[order[want]]);
            if a.im != 0.0
                && (a.re - b.re).abs() <= 1e-12 * modulus(order[0])
                && (a.im + b.im).abs() <= 1e-12 * modulus(order[0])
            {
                want += 1;
            }
        }
        let beta = if m < dim || m == basis.len() { 0.0 } else { hbar[(m, m - 1)] };
        let residual = |i: usize| {
            let col = u.col(i);
            let nrm = (0..m).map(|r| col[r].re * col[r].re + col[r].im * col[r].im).sum::<f64>().sqrt();
            beta * col[m - 1].re.hypot(col[m - 1].im) / nrm
        };
        let converged = order[..want].iter().all(|&i| residual(i) <= RESIDUAL_TOL * modulus(i));
        if converged || m < dim || restarts >= MAX_RESTARTS {
            if !converged && m == dim {
                return Err(format!(
                    "shift-invert Arnoldi did not converge in {MAX_RESTARTS} restarts (subspace {dim})"
                ));
            }
            let ev = order[..want].iter().map(|&i| s.column_vector()[i]).collect();
            return Ok((ev, restarts));
        }
        // Thick restart: keep the real invariant subspace of the wanted Ritz vectors and
        // as many more (half the rest), orthonormalized.
        restarts += 1;
        let keep = (want + (dim - want) / 2).min(dim - 1);
        let mut z: Vec<Vec<f64>> = Vec::new();
        let mut taken = 0;
        for &i in &order {
            if taken >= keep || z.len() + 2 > dim - 1 {
                break;
            }
            let col = u.col(i);
            let lam = s.column_vector()[i];
            let parts: Vec<Vec<f64>> = if lam.im == 0.0 {
                vec![(0..m).map(|r| col[r].re).collect()]
            } else if lam.im > 0.0 {
                vec![(0..m).map(|r| col[r].re).collect(), (0..m).map(|r| col[r].im).collect()]
            } else {
                // The partner of a pair whose positive member carries the subspace.
                taken += 1;
                continue;
            };
            for mut p in parts {
                orthogonalize(&z, &mut p);
                let s = norm(&p);
                if s > 1e-10 {
                    p.iter_mut().for_each(|v| *v /= s);
                    z.push(p);
                }
            }
            taken += 1;
        }
        let p = z.len();
        // G = Zᵀ H Z, g = β e_mᵀ Z, W = V_m Z, and the old residual vector continues.
        let mut g = Mat::<f64>::zeros(p, p);
        for (c, zc) in z.iter().enumerate() {
            let hz: Vec<f64> = (0..m).map(|r| (0..m).map(|q| h[(r, q)] * zc[q]).sum()).collect();
            for (r, zr) in z.iter().enumerate() {
                g[(r, c)] = dot(zr, &hz);
            }
        }
        let residual_vec = basis[m].clone();
        let mut new_basis: Vec<Vec<f64>> = Vec::with_capacity(dim + 1);
        for zc in &z {
            let mut v = vec![0.0; n];
            for (q, coef) in zc.iter().enumerate() {
                for (vi, bi) in v.iter_mut().zip(&basis[q]) {
                    *vi += coef * bi;
                }
            }
            new_basis.push(v);
        }
        new_basis.push(residual_vec);
        basis = new_basis;
        hbar = Mat::<f64>::zeros(dim + 1, dim);
        for r in 0..p {
            for c in 0..p {
                hbar[(r, c)] = g[(r, c)];
            }
        }
        for (c, zc) in z.iter().enumerate() {
            hbar[(p, c)] = beta * zc[m - 1];
        }
        first = p;
    }
}
