//! Exact linearization of the multibody DAE (Negrut & Ortiz): state selection (Eq. 30–33),
//! the augmented sensitivity system (Eq. 34, Table 1) solved with one sparse LU for all
//! right-hand sides, and the eigenvalue table (Tables 2–4).

pub mod assemble;
pub mod augmented;
pub mod candidates;
pub mod eigen;
pub mod eq34;
pub mod exchange;
pub mod extract;
pub mod jets;
pub mod layout;
pub mod linearization;
pub mod modes;
pub mod operating_point;
pub mod outputs;
pub mod partition;
pub mod rhs;
pub mod seeded;
pub mod select;
pub mod select_velocity;
pub mod sensitivity;
pub mod start;
pub mod states;
pub mod structure;
pub mod tiers;
pub mod tolerances;

pub use augmented::{Route, linearize, linearize_with};
pub use candidates::Candidates;
pub use exchange::{accept_step, place_states, state_count, state_derivatives, state_vector};
pub use layout::{StateInfo, StateLayout, selection_by_name};
pub use linearization::Linearization;
pub use seeded::Seeded;
pub use select::{Selection, select_states, select_states_among};
pub use start::{StateTarget, start_values};
pub use states::derivative_name;
pub use structure::{Dependencies, ModelStructure};

use crate::dae::{EngineError, Simulator};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::IndependentRows;
use crate::model::Model;
use jets::jets;

/// The linearization states of `model`, as both `mbfmu linearize` and its FMU use them:
/// selected (Eq. 33) from the initial configuration assembled with the model's own
/// parameter and input values at its experiment start, with [`tolerances::SELECTION_TOL`].
pub fn selection_at_start(model: &Model) -> Result<Selection, EngineError> {
    let t0 = model.experiment.start.unwrap_or(0.0);
    let sim = Simulator::new(model, tolerances::selection_options(), t0)?;
    select_states(sim.system(), sim.q(), t0, &sim.inputs()).map_err(EngineError::Numeric)
}

/// The numbers of position, velocity and differential states any selection on `sys` has
/// (s0 = n − independent constraint rows, s1 = s0 − non-holonomic rows, nx): the count of
/// finite eigenvalues, without selecting them.
pub fn state_counts(sys: &System) -> (usize, usize, usize) {
    let s0 = sys.n() - IndependentRows::of(sys).count;
    (s0, s0.saturating_sub(sys.mn), sys.nx)
}

/// What the FMU of a model carries of its linearization, decided once when it is packed.
#[derive(Clone, Debug, PartialEq)]
pub struct FmuLinearization {
    /// The states it exposes (none, with the reason, when the selection fails).
    pub layout: StateLayout,
    /// What each unknown depends on, in those states.
    pub structure: ModelStructure,
    /// The states' values in the assembled model at its start (the FMU's start values;
    /// empty without states).
    pub starts: StateValues,
}

/// The linearization states of `model`'s FMU ([`selection_at_start`], one engine run) and
/// the structure of its linearization in them.
pub fn for_fmu(model: &Model) -> FmuLinearization {
    let t0 = model.experiment.start.unwrap_or(0.0);
    let run = || -> Result<(Selection, StateValues), EngineError> {
        let mut sim = Simulator::new(model, tolerances::selection_options(), t0)?;
        let sel = select_states(sim.system(), sim.q(), t0, &sim.inputs()).map_err(EngineError::Numeric)?;
        let starts = state_values(&mut sim, &sel)?;
        Ok((sel, starts))
    };
    match run() {
        Ok((sel, starts)) => {
            FmuLinearization { layout: StateLayout::of(&sel), structure: ModelStructure::of(model, Some(&sel)), starts }
        }
        Err(e) => FmuLinearization {
            layout: StateLayout::unavailable(e.to_string()),
            structure: ModelStructure::of(model, None),
            starts: StateValues::default(),
        },
    }
}

/// Values at the current point of the position states S, their rates Ṡ, the velocity
/// states W and their rates Ẇ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateValues {
    /// S.
    pub s: Vec<f64>,
    /// Ṡ.
    pub sd: Vec<f64>,
    /// W.
    pub w: Vec<f64>,
    /// Ẇ.
    pub wd: Vec<f64>,
}

/// Values of S, Ṡ, W, Ẇ at the current point.
pub fn state_values(sim: &mut Simulator, sel: &Selection) -> Result<StateValues, EngineError> {
    let (udot, _) = sim.accelerations()?;
    let (t, ext) = (sim.time(), sim.ext());
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let mut v = StateValues::default();
    for s in &sel.states {
        let j = &jets(sim.system(), s, &q, &u, &udot, t, &ext)[0];
        v.s.push(j.g);
        v.sd.push(j.g1);
    }
    for w in &sel.velocities {
        let j = w.jet(sim.system(), &q, &u, &udot, t, &ext);
        v.w.push(j.w);
        v.wd.push(j.wd);
    }
    Ok(v)
}
