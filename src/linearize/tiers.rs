//! Seed Eq. 33 applied tier by tier. Candidates come in tiers of strict preference (user
//! states, then joint coordinates to ground, ...). For each tier in turn the weighted
//! matrix J = [F 0; −W g D] (F: the constraint rows plus the rows of every candidate chosen
//! in earlier tiers, g: this tier's candidate gradients, D a small diagonal) is factored
//! with complete pivoting; a candidate whose D column stays without a pivot is independent
//! of F and is chosen. One factorization with all tiers at once would rank candidates by
//! the size of their D entries, which geometry (lever arms, units) can overturn; tiers make
//! the preference exact. After the last tier, the coordinates whose columns stay without a
//! pivot complete the set (body coordinates).

use crate::dae::rank::full_pivot;
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::{IndependentRows, constraint_jacobian};

/// Weight W of candidate rows relative to constraint rows (Eq. 33's row weighting).
pub const ROW_WEIGHT: f64 = 1e3;
/// The small diagonal D replacing the identity in Eq. 33 (biases column pivoting).
pub const D_SMALL: f64 = 1e-3;

/// One candidate row: its gradient over the n coordinates (sparse).
#[derive(Clone, Debug, Default)]
pub struct CandidateRow {
    /// (coordinate, ∂s/∂q) pairs.
    pub entries: Vec<(usize, f64)>,
}

/// The gradient `dg` of a function of `bodies` (NQ entries per body, local order) as a
/// candidate row over the global coordinates.
pub fn gradient_row(sys: &System, bodies: &[usize], dg: &[f64]) -> CandidateRow {
    let cols = crate::mechanics::coords::local_columns(sys, bodies);
    CandidateRow { entries: cols.into_iter().zip(dg).map(|(g, &v)| (g, v)).collect() }
}

/// The independent (non-redundant) rows of C_q at (q, t) as (row, col, value), and their
/// number: the constraint rows F of every tier (redundant rows add no rank).
pub fn constraint_rows(sys: &System, q: &[f64], t: f64, ext: &[f64]) -> (Vec<(usize, usize, f64)>, usize) {
    let rows = IndependentRows::of(sys);
    (constraint_jacobian(sys, q, t, ext).independent(&rows).collect(), rows.count)
}

/// Why [`choose_in_tiers`] gave no choice.
#[derive(Clone, Debug)]
pub enum TierError {
    /// An entry is not finite (the message of [`full_pivot`]).
    NotFinite(String),
    /// The constraint rows are not independent (asked for with `full_rank`).
    Dependent,
}

/// The outcome: per tier, which candidates were chosen; the coordinates left free.
#[derive(Clone, Debug)]
pub struct TierChoice {
    /// Per tier, per candidate: whether it was chosen.
    pub chosen: Vec<Vec<bool>>,
    /// Coordinates (columns of F) without a pivot after the last tier.
    pub free: Vec<usize>,
    /// Rank of F's constraint rows alone.
    pub rank: usize,
}

/// Choose among `tiers` of candidates given `nf` constraint rows `fixed` (row, col, value)
/// over `n` coordinates. Pivots below `tol`·max(largest, 1) count as zero. With
/// `full_rank`, constraint rows that are not independent are an error.
pub fn choose_in_tiers(
    n: usize,
    nf: usize,
    fixed: &[(usize, usize, f64)],
    tiers: &[Vec<CandidateRow>],
    tol: f64,
    full_rank: bool,
) -> Result<TierChoice, TierError> {
    let mut rows: Vec<(usize, usize, f64)> = fixed.to_vec();
    let mut nrows = nf;
    let mut chosen = Vec::with_capacity(tiers.len());
    let mut last = None;
    let mut rank = None;
    for tier in tiers {
        if tier.is_empty() {
            chosen.push(vec![]);
            continue;
        }
        let nc = tier.len();
        let mut j = rows.clone();
        for (k, c) in tier.iter().enumerate() {
            j.extend(c.entries.iter().map(|&(col, v)| (nrows + k, col, -ROW_WEIGHT * v)));
            j.push((nrows + k, n + k, ROW_WEIGHT * D_SMALL));
        }
        let piv = full_pivot(nrows + nc, n + nc, j, tol, 1.0).map_err(TierError::NotFinite)?;
        // Every candidate row has its own D column: J has full row rank exactly when F has.
        if full_rank && piv.rank < nrows + nc {
            return Err(TierError::Dependent);
        }
        rank.get_or_insert(piv.rank - nc);
        let pivoted = piv.pivoted_cols(n + nc);
        let picks: Vec<bool> = (0..nc).map(|k| !pivoted[n + k]).collect();
        for c in tier.iter().zip(&picks).filter(|x| *x.1).map(|x| x.0) {
            rows.extend(c.entries.iter().map(|&(col, v)| (nrows, col, ROW_WEIGHT * v)));
            nrows += 1;
        }
        chosen.push(picks);
        last = Some(pivoted);
    }
    let pivoted = match last {
        Some(p) => p,
        None => {
            let piv = full_pivot(nrows, n, rows, tol, 1.0).map_err(TierError::NotFinite)?;
            if full_rank && piv.rank < nrows {
                return Err(TierError::Dependent);
            }
            rank = Some(piv.rank);
            piv.pivoted_cols(n)
        }
    };
    let free = (0..n).filter(|&c| !pivoted[c]).collect();
    Ok(TierChoice { chosen, free, rank: rank.unwrap_or(0) })
}
