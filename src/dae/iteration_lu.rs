//! The LU of one of the integrator's iteration matrices: the block LU along the
//! mechanism's graph ([`super::block_lu`]) when the DAE names groups of unknowns and it
//! factors the matrix, else the general sparse LU with row pivoting
//! ([`super::sparse::SparseLu`]). The choice is made at each factorization from the
//! matrix alone, so a run repeated from a saved state factors the same way.

use super::block_lu::BlockLu;
use super::sparse::{LuScalar, SparseLu};
use faer::sparse::Pair;

/// One iteration matrix's factorization (module docs).
pub struct IterationLu<T: LuScalar> {
    block: BlockLu<T>,
    general: SparseLu<T>,
    on_block: bool,
    /// [`general_only`], read once (not in the step loop).
    general_only: bool,
}

impl<T: LuScalar> Default for IterationLu<T> {
    fn default() -> Self {
        IterationLu {
            block: BlockLu::default(),
            general: SparseLu::default(),
            on_block: false,
            general_only: general_only(),
        }
    }
}

/// Whether the block LU is off (`MBFMU_LU=general`, `simplicial` or `supernodal`: the
/// general LU alone, to compare in benchmarks; README, Benchmark).
fn general_only() -> bool {
    matches!(std::env::var("MBFMU_LU").as_deref(), Ok("general" | "simplicial" | "supernodal"))
}

impl<T: LuScalar> IterationLu<T> {
    /// Factor the n×n matrix with entries `vals` at `idx` (duplicates summed); unknown i
    /// belongs to group `groups[i]` (empty: no groups, the general LU).
    pub fn factor(&mut self, n: usize, idx: &[Pair<usize, usize>], vals: &[T], groups: &[usize]) -> Result<(), String> {
        self.on_block = !groups.is_empty() && !self.general_only && self.block.factor(n, idx, vals, groups).is_ok();
        if self.on_block { Ok(()) } else { self.general.factor_values(n, idx, vals) }
    }

    /// Solve A x = b in place with the last factorization; false if the result is not
    /// finite.
    pub fn solve(&mut self, b: &mut [T]) -> bool {
        if self.on_block { self.block.solve(b) } else { self.general.solve(b) }
    }

    /// Symbolic analyses performed by either LU.
    pub fn analyses(&self) -> usize {
        self.block.analyses + self.general.analyses
    }

    /// Whether the last factorization was the block LU (for the statistics).
    pub fn on_block(&self) -> bool {
        self.on_block
    }
}
