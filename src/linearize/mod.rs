//! Exact linearization of the multibody DAE (Negrut & Ortiz): state selection (Eq. 30–33),
//! the augmented sensitivity system (Eq. 34, Table 1) solved with one sparse LU for all
//! right-hand sides, and the eigenvalue table (Tables 2–4).

pub mod augmented;
pub mod eigen;
pub mod jets;
pub mod outputs;
pub mod select;
pub mod select_velocity;
pub mod states;

pub use augmented::{Linearization, linearize};
pub use select::{Selection, select_states};

use crate::dae::{EngineError, SimOptions, Simulator};
use crate::mechanics::System;
use crate::model::Model;
use jets::jets;
use states::{internal_state, user_states};

/// The states an FMU of `model` exposes: selected (Eq. 33) from the assembled initial
/// configuration with the model's own parameter values and experiment start.
pub fn selection_at_start(model: &Model) -> Result<Selection, EngineError> {
    let t0 = model.experiment.start.unwrap_or(0.0);
    let tol = model.experiment.tolerance.unwrap_or(SimOptions::default().tol);
    let sim = Simulator::new(model, SimOptions { tol, max_step: None }, t0)?;
    select_states(sim.system(), sim.q(), t0, &sim.inputs()).map_err(EngineError::Numeric)
}

/// Rebuild a selection from state names (user state names, or `body.x|y|z|psi|theta|phi`,
/// the angles relative to each body's current reference frame).
pub fn selection_by_name(sys: &System, names: &[String]) -> Result<Selection, String> {
    let users = user_states(sys);
    let coord = ["x", "y", "z", "psi", "theta", "phi"];
    let states = names
        .iter()
        .map(|name| {
            if let Some(u) = users.iter().find(|u| &u.name == name) {
                return Ok(u.clone());
            }
            let (body, c) = name.rsplit_once('.').ok_or_else(|| format!("unknown linearization state '{name}'"))?;
            let b = sys.bodies.iter().position(|x| x.name == body);
            let k = coord.iter().position(|x| *x == c);
            match (b, k) {
                (Some(b), Some(k)) => Ok(internal_state(sys, 6 * b + k)),
                _ => Err(format!("unknown linearization state '{name}'")),
            }
        })
        .collect::<Result<Vec<_>, String>>()?;
    let velocities = select_velocity::derivative_states(&states);
    Ok(Selection { states, velocities, dropped: vec![], rank: sys.redundant.iter().filter(|r| !**r).count() })
}

/// Values of the states S, their velocities W = Ṡ and accelerations Ẇ at the current point.
pub fn state_values(sim: &mut Simulator, sel: &Selection) -> Result<[Vec<f64>; 3], EngineError> {
    let (udot, _) = sim.accelerations()?;
    let (t, inputs) = (sim.time(), sim.inputs());
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let mut v: [Vec<f64>; 3] = Default::default();
    for s in &sel.states {
        let j = &jets(sim.system(), s, &q, &u, &udot, t, &inputs)[0];
        v[0].push(j.g);
        v[1].push(j.g1);
        v[2].push(j.g2);
    }
    Ok(v)
}
