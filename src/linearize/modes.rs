//! The K eigenvalues of the linearized system nearest a shift σ without forming A:
//! shift-invert Arnoldi on the sparse pencil (J, M) of the DAE M y' = f(t, y) itself
//! (J = ∂f/∂y, the integrator's exact sparse Jacobian). The operator
//! v ↦ (J − σM)⁻¹ M v, factored once (sparse LU, as the integrator's matrix), has the
//! eigenvalues θ = 1/(λ − σ) for the finite eigenvalues λ of the pencil and θ = 0 for its
//! infinite ones (the constraint directions), so the wanted λ are the θ of largest modulus.
//! Restarts keep the wanted Ritz vectors (a Krylov–Schur-type thick restart, G. W.
//! Stewart, SIAM J. Matrix Anal. Appl. 23, 2001): A W = W G + v gᵀ holds with W spanning
//! real invariant subspaces of the projected matrix, and the Arnoldi process continues
//! from the old residual vector. Memory and work grow with n times the subspace size.
//! A real σ keeps the arithmetic real (conjugate pairs stay together); a complex σ (the
//! modes near a frequency ω: σ = iω) runs the same process in complex arithmetic on the
//! complex factorization of J − σM.
//!
//! The finite spectrum of the pencil is that of A (seed Eq. 36) at an equilibrium, where
//! it does not depend on the coordinates; at a moving operating point the pencil's
//! eigenvalues are those of the engine's redundant coordinates, which differ, so the
//! caller checks for an equilibrium first ([`equilibrium_residual`]).

use crate::dae::sparse::LuScalar;
use crate::dae::sparse::{SparseLu, Triplets};
use faer::{Mat, c64};
use std::ops::{Add, Mul, Sub, SubAssign};

/// Relative residual ‖(Op − θ)x‖ ≤ this · |θ| of each wanted Ritz pair: eigenvalues to
/// about 1e-12 relative for well-conditioned ones.
const RESIDUAL_TOL: f64 = 1e-13;
/// Most restarts (each with up to `subspace` operator applications).
const MAX_RESTARTS: usize = 200;

/// What [`shift_invert_modes`] found.
#[derive(Clone, Debug)]
pub struct Modes {
    /// The eigenvalues nearest the shift, nearest first (for a real shift, conjugate pairs
    /// are kept together).
    pub eigenvalues: Vec<c64>,
    /// The shift used (the one asked for, or moved off a singular pencil).
    pub shift: c64,
    /// Operator applications (sparse triangular solve pairs).
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
/// or non-holonomic zero modes) σ moves to σ − 10⁻³, σ − 10⁻², … (rad/s) until it
/// factors. A real shift runs in real arithmetic, a complex one in complex arithmetic.
pub fn shift_invert_modes(
    j: &Triplets,
    m: &Triplets,
    n: usize,
    k: usize,
    finite: usize,
    shift: c64,
) -> Result<Modes, String> {
    let k = k.min(finite);
    if k == 0 || n == 0 {
        return Ok(Modes { eigenvalues: vec![], shift, solves: 0, restarts: 0, subspace: 0 });
    }
    // Subspace: room for the wanted pairs and as many again (faster convergence).
    let dim = (2 * k + 20).max(30).min(finite + 1).min(n);
    if shift.im == 0.0 { modes_in::<f64>(j, m, n, k, dim, shift) } else { modes_in::<c64>(j, m, n, k, dim, shift) }
}

/// [`shift_invert_modes`] in the arithmetic `T` (f64 for a real shift).
fn modes_in<T: Scalar>(
    j: &Triplets,
    m: &Triplets,
    n: usize,
    k: usize,
    dim: usize,
    shift: c64,
) -> Result<Modes, String> {
    let (mut lu, sigma) = factor_shifted::<T>(j, m, n, shift)?;
    let mut op = Operator { lu: &mut lu, m, n, tmp: vec![T::zero(); n], solves: 0 };
    let (eigs, restarts) = arnoldi(&mut op, k, dim)?;
    let eigenvalues = eigs.iter().map(|th| sigma + c64::new(1.0, 0.0) / *th).collect();
    Ok(Modes { eigenvalues, shift: sigma, solves: op.solves, restarts, subspace: dim })
}

/// The arithmetic of the Arnoldi process: f64 (real shift) or c64 (complex shift).
trait Scalar:
    LuScalar
    + faer::traits::ComplexField<Real = f64>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Mul<f64, Output = Self>
    + SubAssign
{
    /// Whether the arithmetic is real (then conjugate pairs are kept together).
    const REAL: bool;
    /// The real number x.
    fn re(x: f64) -> Self;
    /// The shift in this arithmetic (its real part for f64).
    fn of(z: c64) -> Self;
    /// Complex conjugate.
    fn cj(self) -> Self;
    /// Squared modulus.
    fn abs2(self) -> f64;
    /// The vectors spanning what a Ritz vector `col` (length m) of eigenvalue `lam`
    /// contributes to the restart space: for real arithmetic its real and imaginary
    /// parts (once per conjugate pair, none for the pair's negative member).
    fn ritz_parts(col: &[c64], lam: c64) -> Vec<Vec<Self>>;
}

impl Scalar for f64 {
    const REAL: bool = true;
    fn re(x: f64) -> Self {
        x
    }
    fn of(z: c64) -> Self {
        z.re
    }
    fn cj(self) -> Self {
        self
    }
    fn abs2(self) -> f64 {
        self * self
    }
    fn ritz_parts(col: &[c64], lam: c64) -> Vec<Vec<Self>> {
        if lam.im == 0.0 {
            vec![col.iter().map(|z| z.re).collect()]
        } else if lam.im > 0.0 {
            vec![col.iter().map(|z| z.re).collect(), col.iter().map(|z| z.im).collect()]
        } else {
            vec![]
        }
    }
}

impl Scalar for c64 {
    const REAL: bool = false;
    fn re(x: f64) -> Self {
        c64::new(x, 0.0)
    }
    fn of(z: c64) -> Self {
        z
    }
    fn cj(self) -> Self {
        self.conj()
    }
    fn abs2(self) -> f64 {
        self.norm_sqr()
    }
    fn ritz_parts(col: &[c64], _lam: c64) -> Vec<Vec<Self>> {
        vec![col.to_vec()]
    }
}

/// J − σM factored, with σ moved off the spectrum if it is singular there; σ as used.
fn factor_shifted<T: Scalar>(j: &Triplets, m: &Triplets, n: usize, shift: c64) -> Result<(SparseLu<T>, c64), String> {
    let mut idx = j.idx.clone();
    idx.extend_from_slice(&m.idx);
    let mut last = String::new();
    for attempt in 0..6 {
        let sigma = if attempt == 0 { shift } else { shift - 10f64.powi(attempt - 4) };
        let s = T::of(sigma);
        let mut vals: Vec<T> = j.vals.iter().map(|v| T::re(*v)).collect();
        vals.extend(m.vals.iter().map(|v| T::zero() - s * T::re(*v)));
        let mut lu = SparseLu::<T>::default();
        match lu.factor_values(n, &idx, &vals) {
            Ok(()) => {
                // A singular matrix may factor with a tiny pivot: check a solve.
                let mut b = vec![T::re(1.0); n];
                if lu.solve(&mut b) && b.iter().all(|v| v.finite() && v.abs2() < 1e28) {
                    return Ok((lu, sigma));
                }
                last = "a solve with it is not finite".into();
            }
            Err(e) => last = e,
        }
    }
    Err(format!("J − σM is singular near σ = {}: {last}", format_shift(shift)))
}

/// A shift as text: `2`, `0+12.5i`, `-1-3i`.
pub fn format_shift(z: c64) -> String {
    if z.im == 0.0 { format!("{}", z.re) } else { format!("{}{:+}i", z.re, z.im) }
}

/// v ↦ (J − σM)⁻¹ M v.
struct Operator<'a, T: Scalar> {
    lu: &'a mut SparseLu<T>,
    m: &'a Triplets,
    n: usize,
    tmp: Vec<T>,
    solves: usize,
}

impl<T: Scalar> Operator<'_, T> {
    fn apply(&mut self, v: &[T], out: &mut [T]) -> Result<(), String> {
        self.tmp.fill(T::zero());
        self.m.mul_add(v, &mut self.tmp);
        if !self.lu.solve(&mut self.tmp) {
            return Err("shift-invert solve failed".into());
        }
        out.copy_from_slice(&self.tmp);
        self.solves += 1;
        Ok(())
    }
}

/// aᴴb, in four independent partial sums (which the compiler vectorizes; one running
/// sum cannot be reordered).
fn dot<T: Scalar>(a: &[T], b: &[T]) -> T {
    let mut acc = [T::zero(); 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail = ca.remainder().iter().zip(cb.remainder()).fold(T::zero(), |s, (x, y)| s + x.cj() * *y);
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k].cj() * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn norm<T: Scalar>(a: &[T]) -> f64 {
    a.iter().map(|x| x.abs2()).sum::<f64>().sqrt()
}

/// Orthogonalize w against the basis (classical Gram–Schmidt, twice), returning the
/// coefficients.
fn orthogonalize<T: Scalar>(basis: &[Vec<T>], w: &mut [T]) -> Vec<T> {
    let mut h = vec![T::zero(); basis.len()];
    for _ in 0..2 {
        for (i, v) in basis.iter().enumerate() {
            let c = dot(v, w);
            h[i] += c;
            for (wi, vi) in w.iter_mut().zip(v) {
                *wi -= c * *vi;
            }
        }
    }
    h
}

/// w / s.
fn scaled<T: Scalar>(w: &[T], s: f64) -> Vec<T> {
    let r = T::re(1.0 / s);
    w.iter().map(|v| *v * r).collect()
}

/// A deterministic start vector with every component nonzero, made to lie in the range
/// of the operator (two applications remove the components of the infinite eigenvalues,
/// whose Jordan chains are at most of length 2 in the stabilized index-2 form).
fn start_vector<T: Scalar>(op: &mut Operator<T>) -> Result<Vec<T>, String> {
    let n = op.n;
    let mut v: Vec<T> = (0..n).map(|i| T::re(1.0 + ((i * 7919) % 101) as f64 / 101.0)).collect();
    let mut w = vec![T::zero(); n];
    for _ in 0..2 {
        op.apply(&v, &mut w)?;
        let s = norm(&w);
        if !(s > 0.0 && s.is_finite()) {
            return Err("the operator maps the start vector to zero".into());
        }
        v = scaled(&w, s);
    }
    Ok(v)
}

/// The `k` eigenvalues θ of largest modulus of the operator (in real arithmetic with
/// conjugates kept together), and the number of restarts.
fn arnoldi<T: Scalar>(op: &mut Operator<T>, k: usize, dim: usize) -> Result<(Vec<c64>, usize), String> {
    let n = op.n;
    let mut basis: Vec<Vec<T>> = vec![start_vector(op)?];
    // hbar: (dim + 1) × dim, A V_dim = V_{dim+1} hbar.
    let mut hbar = Mat::<T>::zeros(dim + 1, dim);
    let mut w = vec![T::zero(); n];
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
            hbar[(jcol + 1, jcol)] = T::re(beta);
            let scale = h.iter().fold(beta, |a, v| a.max(v.abs2().sqrt()));
            if beta <= 1e-14 * scale {
                // An invariant subspace: its eigenvalues are exact.
                m = jcol + 1;
                break;
            }
            basis.push(scaled(&w, beta));
        }
        let h = hbar.submatrix(0, 0, m, m).to_owned();
        let eig = h.eigen().map_err(|e| format!("eigenvalues of the projected matrix: {e:?}"))?;
        let (s, u) = (eig.S(), eig.U());
        let theta = |i: usize| s.column_vector()[i];
        let mut order: Vec<usize> = (0..m).collect();
        let modulus = |i: usize| theta(i).norm();
        order.sort_by(|&a, &b| modulus(b).total_cmp(&modulus(a)).then(theta(a).im.total_cmp(&theta(b).im)));
        // The wanted: the k largest, and (real arithmetic) a conjugate pair cut in two
        // completed.
        let mut want = k.min(m);
        if T::REAL && want < m {
            let (a, b) = (theta(order[want - 1]), theta(order[want]));
            if a.im != 0.0
                && (a.re - b.re).abs() <= 1e-12 * modulus(order[0])
                && (a.im + b.im).abs() <= 1e-12 * modulus(order[0])
            {
                want += 1;
            }
        }
        let beta = if m < dim || m == basis.len() { 0.0 } else { hbar[(m, m - 1)].abs2().sqrt() };
        let ritz = |i: usize| -> Vec<c64> { (0..m).map(|r| u.col(i)[r]).collect() };
        let residual = |i: usize| {
            let col = ritz(i);
            beta * col[m - 1].norm() / col.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt()
        };
        let converged = order[..want].iter().all(|&i| residual(i) <= RESIDUAL_TOL * modulus(i));
        if converged || m < dim || restarts >= MAX_RESTARTS {
            if !converged && m == dim {
                return Err(format!(
                    "shift-invert Arnoldi did not converge in {MAX_RESTARTS} restarts (subspace {dim})"
                ));
            }
            let ev = order[..want].iter().map(|&i| theta(i)).collect();
            return Ok((ev, restarts));
        }
        // Thick restart: keep the invariant subspace of the wanted Ritz vectors (real, in
        // real arithmetic) and as many more (half the rest), orthonormalized.
        restarts += 1;
        let keep = (want + (dim - want) / 2).min(dim - 1);
        let mut z: Vec<Vec<T>> = Vec::new();
        for (taken, &i) in order.iter().enumerate() {
            if taken >= keep || z.len() + 2 > dim - 1 {
                break;
            }
            for mut p in T::ritz_parts(&ritz(i), theta(i)) {
                orthogonalize(&z, &mut p);
                let s = norm(&p);
                if s > 1e-10 {
                    z.push(scaled(&p, s));
                }
            }
        }
        let p = z.len();
        // G = Zᴴ H Z, g = β e_mᵀ Z, W = V_m Z, and the old residual vector continues.
        let mut g = Mat::<T>::zeros(p, p);
        for (c, zc) in z.iter().enumerate() {
            let hz: Vec<T> = (0..m).map(|r| (0..m).fold(T::zero(), |a, q| a + h[(r, q)] * zc[q])).collect();
            for (r, zr) in z.iter().enumerate() {
                g[(r, c)] = dot(zr, &hz);
            }
        }
        let residual_vec = basis[m].clone();
        let mut new_basis: Vec<Vec<T>> = Vec::with_capacity(dim + 1);
        for zc in &z {
            let mut v = vec![T::zero(); n];
            for (q, coef) in zc.iter().enumerate() {
                for (vi, bi) in v.iter_mut().zip(&basis[q]) {
                    *vi += *coef * *bi;
                }
            }
            new_basis.push(v);
        }
        new_basis.push(residual_vec);
        basis = new_basis;
        hbar = Mat::<T>::zeros(dim + 1, dim);
        for r in 0..p {
            for c in 0..p {
                hbar[(r, c)] = g[(r, c)];
            }
        }
        for (c, zc) in z.iter().enumerate() {
            hbar[(p, c)] = T::re(beta) * zc[m - 1];
        }
        first = p;
    }
}
