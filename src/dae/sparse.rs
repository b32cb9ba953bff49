//! Sparse LU (faer) with the symbolic analysis cached while the sparsity pattern is
//! unchanged: the pattern is compared entry by entry, numeric values are re-factored.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{LuRef, LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{Pair, SparseColMatRef, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{Conj, Mat, MatMut, Par, c64};

/// A matrix under construction, as (row, col, value) entries; duplicates are summed.
#[derive(Clone, Debug, Default)]
pub struct Triplets {
    /// (row, column) of each entry, in push order; a position may repeat (values summed).
    pub idx: Vec<Pair<usize, usize>>,
    /// Value of each entry, parallel to `idx`.
    pub vals: Vec<f64>,
}

impl Triplets {
    /// Empty.
    pub fn new() -> Self {
        Self::default()
    }
    /// Add `v` at (r, c) (kept even when zero, so the pattern is stable).
    #[inline]
    pub fn push(&mut self, r: usize, c: usize, v: f64) {
        self.idx.push(Pair::new(r, c));
        self.vals.push(v);
    }
    /// Remove all entries.
    pub fn clear(&mut self) {
        self.idx.clear();
        self.vals.clear();
    }
    /// y += A x (x and y real or complex).
    pub fn mul_add<T: Copy + std::ops::AddAssign + std::ops::Mul<f64, Output = T>>(&self, x: &[T], y: &mut [T]) {
        for (p, v) in self.idx.iter().zip(&self.vals) {
            y[p.row] += x[p.col] * *v;
        }
    }
}

/// Right-hand sides solved at once by [`SparseLu::solve_columns`].
const SOLVE_BLOCK: usize = 16;

/// A scalar the LU factors: f64, or c64 for the complex-pair block of the integrator.
pub trait LuScalar:
    ComplexField
    + Copy
    + std::ops::AddAssign
    + std::ops::SubAssign
    + std::ops::MulAssign
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    /// Whether the value is finite.
    fn finite(&self) -> bool;
    /// Zero.
    fn zero() -> Self;
    /// One.
    fn one() -> Self;
    /// |re| + |im|: the size pivoting compares (LAPACK's cabs1).
    fn magnitude(&self) -> f64;
    /// Whether the value is exactly zero (a product the elimination may skip).
    fn is_zero(&self) -> bool;
}

impl LuScalar for f64 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
    fn zero() -> Self {
        0.0
    }
    fn one() -> Self {
        1.0
    }
    fn magnitude(&self) -> f64 {
        self.abs()
    }
    fn is_zero(&self) -> bool {
        *self == 0.0
    }
}

impl LuScalar for c64 {
    fn finite(&self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
    fn zero() -> Self {
        c64::new(0.0, 0.0)
    }
    fn one() -> Self {
        c64::new(1.0, 0.0)
    }
    fn magnitude(&self) -> f64 {
        self.re.abs() + self.im.abs()
    }
    fn is_zero(&self) -> bool {
        self.re == 0.0 && self.im == 0.0
    }
}

struct Symbolic {
    n: usize,
    pattern: Vec<Pair<usize, usize>>,
    mat: SymbolicSparseColMat<usize>,
    /// Per entry of `pattern`: its slot in the compressed values (duplicates share one).
    slot: Vec<usize>,
    lu: SymbolicLu<usize>,
}

/// A square sparse LU factorization that reuses its symbolic analysis, its value buffer
/// and its scratch memory (a refactorization with an unchanged pattern allocates
/// nothing); sequential (no thread pool is touched inside a host process).
pub struct SparseLu<T: LuScalar = f64> {
    symbolic: Option<Symbolic>,
    values: Vec<T>,
    numeric: Option<NumericLu<usize, T>>,
    scratch: Option<MemBuffer>,
    /// Number of symbolic analyses performed (for tests and benchmarks).
    pub analyses: usize,
}

impl<T: LuScalar> Default for SparseLu<T> {
    fn default() -> Self {
        SparseLu { symbolic: None, values: Vec::new(), numeric: None, scratch: None, analyses: 0 }
    }
}

/// faer's LU variant: supernodal (the default: 2× faster than simplicial on the chains
/// of `bench/`), or simplicial when the environment variable `MBFMU_LU=simplicial` is set,
/// to compare the two in benchmarks (README, Benchmark). Results agree to round-off.
fn supernodal_threshold() -> SupernodalThreshold {
    match std::env::var("MBFMU_LU").as_deref() {
        Ok("simplicial") => SupernodalThreshold::FORCE_SIMPLICIAL,
        Ok("supernodal") => SupernodalThreshold::FORCE_SUPERNODAL,
        _ => SupernodalThreshold::FORCE_SUPERNODAL,
    }
}

impl SparseLu<f64> {
    /// New, empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factor the n×n matrix given by `t`.
    pub fn factor(&mut self, n: usize, t: &Triplets) -> Result<(), String> {
        self.factor_values(n, &t.idx, &t.vals)
    }
}

impl<T: LuScalar> SparseLu<T> {
    /// Factor the n×n matrix with entries `vals` at `idx` (duplicates summed). The
    /// symbolic analysis is redone only when `idx` differs from the last one.
    pub fn factor_values(&mut self, n: usize, idx: &[Pair<usize, usize>], vals: &[T]) -> Result<(), String> {
        let reuse = matches!(&self.symbolic, Some(s) if s.n == n && s.pattern == idx);
        if !reuse {
            self.analyze(n, idx)?;
        }
        let s = self.symbolic.as_ref().expect("symbolic analysis present");
        if vals.iter().any(|v| !v.finite()) {
            self.numeric = Some(NumericLu::new());
            return Err("matrix has non-finite entries".into());
        }
        self.values.iter_mut().for_each(|v| *v = <T as LuScalar>::zero());
        for (&k, &v) in s.slot.iter().zip(vals) {
            self.values[k] += v;
        }
        let numeric = self.numeric.as_mut().expect("numeric storage present");
        let scratch = self.scratch.as_mut().expect("scratch present");
        let a = SparseColMatRef::new(s.mat.as_ref(), &self.values);
        match s.lu.factorize_numeric_lu(numeric, a, Par::Seq, MemStack::new(scratch), Default::default()) {
            Ok(_) => Ok(()),
            Err(e) => {
                // A failed factorization leaves the numeric part unusable: start afresh.
                self.numeric = Some(NumericLu::new());
                self.symbolic = None;
                Err(format!("singular matrix ({e:?})"))
            }
        }
    }

    /// The symbolic analysis of the pattern `idx`, with the slots of its entries.
    fn analyze(&mut self, n: usize, idx: &[Pair<usize, usize>]) -> Result<(), String> {
        let (mat, _) =
            SymbolicSparseColMat::try_new_from_indices(n, n, idx).map_err(|e| format!("sparse pattern: {e:?}"))?;
        let (col_ptr, row_idx) = (mat.col_ptr(), mat.row_idx());
        let slot = idx
            .iter()
            .map(|p| {
                let rows = &row_idx[col_ptr[p.col]..col_ptr[p.col + 1]];
                col_ptr[p.col] + rows.binary_search(&p.row).expect("entry in its own pattern")
            })
            .collect();
        let params = LuSymbolicParams { supernodal_flop_ratio_threshold: supernodal_threshold(), ..Default::default() };
        let lu = factorize_symbolic_lu(mat.as_ref(), params).map_err(|e| format!("symbolic LU: {e:?}"))?;
        let req = StackReq::any_of(&[
            lu.factorize_numeric_lu_scratch::<T>(Par::Seq, Default::default()),
            lu.solve_in_place_scratch::<T>(1, Par::Seq),
        ]);
        self.scratch = Some(MemBuffer::try_new(req).map_err(|_| "out of memory".to_string())?);
        self.values = vec![<T as LuScalar>::zero(); row_idx.len()];
        self.symbolic = Some(Symbolic { n, pattern: idx.to_vec(), mat, slot, lu });
        self.numeric = Some(NumericLu::new());
        self.analyses += 1;
        Ok(())
    }

    /// Solve A x = b in place; false if the result is not finite (singular matrix).
    pub fn solve(&mut self, b: &mut [T]) -> bool {
        let n = b.len();
        let m = MatMut::from_column_major_slice_mut(b, n, 1);
        self.solve_mat(m)
    }

    /// Solve A X = B in place for several right-hand sides (columns of `b`).
    pub fn solve_many(&mut self, b: &mut Mat<T>) -> bool {
        self.solve_mat(b.as_mut())
    }

    fn solve_mat(&mut self, mut b: MatMut<'_, T>) -> bool {
        let (Some(s), Some(numeric)) = (&self.symbolic, &self.numeric) else { return false };
        let req = s.lu.solve_in_place_scratch::<T>(b.ncols(), Par::Seq);
        let mut local;
        let buf = match &mut self.scratch {
            Some(buf) if b.ncols() == 1 => buf,
            _ => {
                local = MemBuffer::new(req);
                &mut local
            }
        };
        LuRef::new_unchecked(&s.lu, numeric).solve_in_place_with_conj(
            Conj::No,
            b.as_mut(),
            Par::Seq,
            MemStack::new(buf),
        );
        (0..b.ncols()).all(|j| (0..b.nrows()).all(|i| b[(i, j)].finite()))
    }
}

impl SparseLu<f64> {
    /// Solve A x = b (Aᵀ x = b with `transpose`) for `ncols` right-hand sides without
    /// holding them all: `fill(j, b)` writes column j into a zeroed b, `take(j, x)` keeps what is needed of its
    /// solution. Columns go in blocks of `SOLVE_BLOCK` over `threads` threads (each
    /// with its own block and scratch; the factorization is shared read-only), so the
    /// memory is threads·dim·SOLVE_BLOCK. None if a solution is not finite (singular).
    pub fn solve_columns<T: Send>(
        &self,
        ncols: usize,
        threads: usize,
        transpose: bool,
        fill: impl Fn(usize, &mut [f64]) + Sync,
        take: impl Fn(usize, &[f64]) -> T + Sync,
    ) -> Option<Vec<T>> {
        let (Some(s), Some(numeric)) = (&self.symbolic, &self.numeric) else { return None };
        let dim = s.n;
        let solve_range = |cols: std::ops::Range<usize>| -> Option<Vec<T>> {
            let mut out = Vec::with_capacity(cols.len());
            let width = SOLVE_BLOCK.min(cols.len());
            let mut block = Mat::<f64>::zeros(dim, width);
            let req = if transpose {
                s.lu.solve_transpose_in_place_scratch::<f64>(width, Par::Seq)
            } else {
                s.lu.solve_in_place_scratch::<f64>(width, Par::Seq)
            };
            let mut buf = MemBuffer::new(req);
            for start in cols.clone().step_by(SOLVE_BLOCK) {
                let w = SOLVE_BLOCK.min(cols.end - start);
                let mut b = block.as_mut().subcols_mut(0, w);
                for j in 0..w {
                    let col = b.rb_mut().col_mut(j).try_as_col_major_mut().expect("contiguous column").as_slice_mut();
                    col.fill(0.0);
                    fill(start + j, col);
                }
                let lu = LuRef::new_unchecked(&s.lu, numeric);
                let stack = MemStack::new(&mut buf);
                if transpose {
                    lu.solve_transpose_in_place_with_conj(Conj::No, b.rb_mut(), Par::Seq, stack);
                } else {
                    lu.solve_in_place_with_conj(Conj::No, b.rb_mut(), Par::Seq, stack);
                }
                for j in 0..w {
                    let x = b.rb().col(j).try_as_col_major().expect("contiguous column").as_slice();
                    if x.iter().any(|v| !v.is_finite()) {
                        return None;
                    }
                    out.push(take(start + j, x));
                }
            }
            Some(out)
        };
        let threads = threads.clamp(1, ncols.div_ceil(SOLVE_BLOCK).max(1));
        if threads == 1 {
            return solve_range(0..ncols);
        }
        let chunk = ncols.div_ceil(threads);
        std::thread::scope(|sc| {
            let handles: Vec<_> = (0..ncols)
                .step_by(chunk)
                .map(|a| {
                    let solve_range = &solve_range;
                    sc.spawn(move || solve_range(a..(a + chunk).min(ncols)))
                })
                .collect();
            let mut all = Vec::with_capacity(ncols);
            for h in handles {
                match h.join() {
                    Ok(part) => all.extend(part?),
                    Err(panic) => std::panic::resume_unwind(panic),
                }
            }
            Some(all)
        })
    }
}
