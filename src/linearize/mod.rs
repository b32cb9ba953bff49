//! Exact linearization of the multibody DAE (Negrut & Ortiz): state selection (Eq. 30–33),
//! the augmented sensitivity system (Eq. 34, Table 1) solved with one sparse LU for all
//! right-hand sides, and the eigenvalue table (Tables 2–4).

pub mod augmented;
pub mod candidates;
pub mod eigen;
pub mod eq34;
pub mod jets;
pub mod outputs;
pub mod select;
pub mod select_velocity;
pub mod states;
pub mod tiers;

pub use augmented::{Linearization, linearize};
pub use candidates::Candidates;
pub use select::{Selection, select_states, select_states_among};

use crate::dae::{EngineError, SimOptions, Simulator};
use crate::mechanics::System;
use crate::model::Model;
use jets::jets;
use states::{VelState, internal_state, joint_states, user_states};

/// The states an FMU of `model` exposes: selected (Eq. 33) from the assembled initial
/// configuration with the model's own parameter values and experiment start.
pub fn selection_at_start(model: &Model) -> Result<Selection, EngineError> {
    let t0 = model.experiment.start.unwrap_or(0.0);
    let tol = model.experiment.tolerance.unwrap_or(SimOptions::default().tol);
    let sim = Simulator::new(model, SimOptions { tol, max_step: None, ..Default::default() }, t0)?;
    select_states(sim.system(), sim.q(), t0, &sim.inputs()).map_err(EngineError::Numeric)
}

/// Rebuild a selection from state names: position states (user state names, joint
/// coordinates `joint.angle` ..., or `body.x|y|z|psi|theta|phi`, the angles relative to
/// each body's current reference frame)
/// and velocity states (`der(<position state>)`, a user `<velocity>`, or `der(body.x)` ...).
pub fn selection_by_name(sys: &System, names: &[String], w_names: &[String]) -> Result<Selection, String> {
    let mut users = user_states(sys);
    users.extend(joint_states(sys));
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
    let uv = states::user_velocities(sys);
    let velocities = w_names
        .iter()
        .map(|w| {
            if let Some(v) = uv.iter().find(|v| &v.name == w) {
                return Ok(VelState::User(v.clone()));
            }
            let inner = w.strip_prefix("der(").and_then(|x| x.strip_suffix(')'));
            let Some(inner) = inner else { return Err(format!("unknown velocity state '{w}'")) };
            if let Some(s) = states.iter().find(|s| s.name == inner) {
                return Ok(VelState::Derivative(s.clone()));
            }
            selection_by_name(sys, &[inner.to_string()], &[]).map(|sel| VelState::Derivative(sel.states[0].clone()))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Selection { states, velocities, dropped: vec![], rank: sys.redundant.iter().filter(|r| !**r).count() })
}

/// Values at the current point of the position states S, their rates Ṡ, the velocity
/// states W and their rates Ẇ.
#[derive(Clone, Debug, Default)]
pub struct StateValues {
    pub s: Vec<f64>,
    pub sd: Vec<f64>,
    pub w: Vec<f64>,
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
