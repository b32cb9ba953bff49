//! Sparse LU (faer) with the symbolic analysis cached while the sparsity pattern is
//! unchanged: the pattern is compared entry by entry, numeric values are re-factored.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut};

/// A matrix under construction, as (row, col, value) entries; duplicates are summed.
#[derive(Clone, Debug, Default)]
pub struct Triplets {
    pub idx: Vec<Pair<usize, usize>>,
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
    /// y += A x.
    pub fn mul_add(&self, x: &[f64], y: &mut [f64]) {
        for (p, v) in self.idx.iter().zip(&self.vals) {
            y[p.row] += v * x[p.col];
        }
    }
}

struct Symbolic {
    n: usize,
    pattern: Vec<Pair<usize, usize>>,
    mat: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    lu: SymbolicLu<usize>,
}

/// A square sparse LU factorization that reuses its symbolic analysis.
#[derive(Default)]
pub struct SparseLu {
    symbolic: Option<Symbolic>,
    lu: Option<Lu<usize, f64>>,
    /// Number of symbolic analyses performed (for tests and benchmarks).
    pub analyses: usize,
}

impl SparseLu {
    /// New, empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factor the n×n matrix given by `t`.
    pub fn factor(&mut self, n: usize, t: &Triplets) -> Result<(), String> {
        let reuse = matches!(&self.symbolic, Some(s) if s.n == n && s.pattern == t.idx);
        if !reuse {
            let (mat, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &t.idx)
                .map_err(|e| format!("sparse pattern: {e:?}"))?;
            let lu = SymbolicLu::try_new(mat.as_ref()).map_err(|e| format!("symbolic LU: {e:?}"))?;
            self.symbolic = Some(Symbolic { n, pattern: t.idx.clone(), mat, argsort, lu });
            self.analyses += 1;
        }
        let s = self.symbolic.as_ref().expect("symbolic analysis present");
        if t.vals.iter().any(|v| !v.is_finite()) {
            self.lu = None;
            return Err("matrix has non-finite entries".into());
        }
        let a = SparseColMat::new_from_argsort(s.mat.clone(), &s.argsort, &t.vals)
            .map_err(|e| format!("sparse values: {e:?}"))?;
        match Lu::try_new_with_symbolic(s.lu.clone(), a.as_ref()) {
            Ok(lu) => {
                self.lu = Some(lu);
                Ok(())
            }
            Err(e) => {
                self.lu = None;
                Err(format!("singular matrix ({e:?})"))
            }
        }
    }

    /// Solve A x = b in place; false if the result is not finite (singular matrix).
    pub fn solve(&self, b: &mut [f64]) -> bool {
        let Some(lu) = &self.lu else { return false };
        let n = b.len();
        let mut m = MatMut::from_column_major_slice_mut(b, n, 1);
        lu.solve_in_place(m.as_mut());
        b.iter().all(|v| v.is_finite())
    }

    /// Solve A X = B in place for several right-hand sides (columns of `b`).
    pub fn solve_many(&self, b: &mut Mat<f64>) -> bool {
        let Some(lu) = &self.lu else { return false };
        lu.solve_in_place(b.as_mut());
        (0..b.ncols()).all(|j| (0..b.nrows()).all(|i| b[(i, j)].is_finite()))
    }
}
