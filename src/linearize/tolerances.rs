//! The tolerances of state selection (seed Eq. 33), in one place: the rank decision, and
//! the configuration the states are selected from (the same for the command line and the
//! FMU, so both expose the same states).

use crate::dae::SimOptions;

/// A pivot below this fraction of the largest pivot (at least 1) counts as zero (rank decision).
pub const RANK_TOL: f64 = 1e-9;

/// Integration tolerance of the engine whose assembled initial configuration the
/// linearization states are selected from, by `mbfmu linearize`, `run`, `check` and when
/// an FMU is packed, whatever tolerance the user or the host later integrates with.
///
/// Why 1e-8: assembly then meets the constraints to 1e-11 relative (the engine assembles
/// to 1e-3 of the integration tolerance), well below [`RANK_TOL`], so the residual cannot
/// tip a rank decision; 1e-6 would leave it at the rank tolerance itself. Tighter settings
/// approach round-off, where assembly of large models (the bicycle) may fail to confirm.
/// A fixed value (not the experiment's tolerance) makes the states a property of the
/// model alone.
pub const SELECTION_TOL: f64 = 1e-8;

/// The engine options of the configuration states are selected from ([`SELECTION_TOL`]).
pub fn selection_options() -> SimOptions {
    SimOptions { tol: SELECTION_TOL, max_step: None, ..Default::default() }
}
