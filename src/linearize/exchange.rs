//! The mechanism as an ODE in its linearization states, x = [S; W; X] (FMI Model
//! Exchange): x → the consistent point ([`Simulator::place`], coordinate partitioning),
//! checked to be one the states parameterize ([`check_partition`]), and ẋ = [Ṡ; Ẇ; Ẋ]
//! there from the acceleration solve (seed Eq. 1, 7). The ODE is never integrated here;
//! its Jacobian is Eq. 34's A at the same point.

use super::partition::check_partition;
use super::select::Selection;
use super::state_values;
use super::states::VelState;
use crate::dae::{Accepted, EngineError, Simulator, StartValue, StartValues};
use crate::mechanics::constraints::VelocityIcKind;

/// Number of ODE states of `sel` on `sim`'s system: s0 + s1 + nx.
pub fn state_count(sim: &Simulator, sel: &Selection) -> usize {
    sel.states.len() + sel.velocities.len() + sim.system().nx
}

/// The conditions x = [S; W; X] puts on the engine (x must have [`state_count`] entries).
pub fn conditions(sel: &Selection, x: &[f64]) -> StartValues {
    let (s0, s1) = (sel.states.len(), sel.velocities.len());
    let positions = sel
        .states
        .iter()
        .zip(x)
        .map(|(s, &value)| StartValue { name: s.name.clone(), kind: s.kind.clone(), bodies: s.bodies.clone(), value })
        .collect();
    let velocities = sel
        .velocities
        .iter()
        .zip(&x[s0..])
        .map(|(w, &value)| {
            let kind = match w {
                VelState::Derivative(s) => VelocityIcKind::Rate(s.kind.clone()),
                VelState::User(u) => VelocityIcKind::User { f: u.f.clone(), abase: u.abase },
            };
            StartValue { name: w.name(), kind, bodies: w.bodies().to_vec(), value }
        })
        .collect();
    let differentials = x[s0 + s1..].iter().copied().enumerate().collect();
    StartValues { positions, velocities, differentials }
}

/// Put `sim` at time `t` and states `x`: the consistent point, which the states must
/// still parameterize (else an error naming them and the configuration, and `sim` stays
/// where it was).
pub fn place_states(sim: &mut Simulator, sel: &Selection, t: f64, x: &[f64]) -> Result<(), EngineError> {
    let n = state_count(sim, sel);
    if x.len() != n {
        return Err(EngineError::Numeric(format!("{} state values given, the model has {n}", x.len())));
    }
    sim.place(t, &conditions(sel, x), &|sys, q, t, ext| check_partition(sys, sel, q, t, ext))
}

/// The host accepted a step to the engine's current point, placed at states `x`: Err if
/// the motion from `prev` (the last accepted point) went through a fold of the states'
/// chart on the way ([`Simulator::check_branch`]), else the point to check the next
/// step from.
pub fn accept_step(
    sim: &mut Simulator,
    sel: &Selection,
    x: &[f64],
    prev: Option<&Accepted>,
) -> Result<Accepted, EngineError> {
    if let Some(prev) = prev {
        sim.check_branch(prev, &conditions(sel, x))?;
    }
    Ok(sim.accepted_point())
}

/// x = [S; W; X] at the engine's current point.
pub fn state_vector(sim: &mut Simulator, sel: &Selection) -> Result<Vec<f64>, EngineError> {
    let v = state_values(sim, sel)?;
    let nx = sim.system().nx;
    Ok(v.s.into_iter().chain(v.w).chain(sim.user_values()[..nx].iter().copied()).collect())
}

/// ẋ = [Ṡ; Ẇ; Ẋ] at the engine's current point.
pub fn state_derivatives(sim: &mut Simulator, sel: &Selection) -> Result<Vec<f64>, EngineError> {
    let v = state_values(sim, sel)?;
    let nx = sim.system().nx;
    Ok(v.sd.into_iter().chain(v.wd).chain(sim.user_values()[nx..2 * nx].iter().copied()).collect())
}
