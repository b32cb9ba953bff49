//! Start values set on the FMU's states, by name of layout entry, turned into the
//! measures initialization meets ([`StartValues`]): a position state S_k its measure
//! s(q, t), a velocity state W_j the rate of its S (or its `<velocity>` expression), a
//! differential state its initial value.

use super::layout::{StateLayout, selection_by_name};
use super::states::VelState;
use crate::dae::{StartValue, StartValues};
use crate::mechanics::System;
use crate::mechanics::constraints::VelocityIcKind;
use crate::model::Model;

/// A state of the layout that a start value sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateTarget {
    /// Position state S_k.
    Position(usize),
    /// Velocity state W_j.
    Velocity(usize),
    /// Differential state X_k.
    Differential(usize),
}

/// The start values `set` (name, state, value) as conditions on the system of `model`
/// (whose states `layout` lists).
pub fn start_values(
    model: &Model,
    layout: &StateLayout,
    set: &[(String, StateTarget, f64)],
) -> Result<StartValues, String> {
    let mut out = StartValues::default();
    // The states' measures, resolved only when a position or velocity state is set (a
    // model without linearization states has differential states only): on a system built
    // as the simulator builds its own (same frames, same angle slots).
    let needs_measures = set.iter().any(|(_, t, _)| !matches!(t, StateTarget::Differential(_)));
    let sel = if needs_measures { Some(selection_by_name(&System::from_model(model)?, layout)?) } else { None };
    let selection = || sel.as_ref().expect("resolved when a position or velocity state is set");
    for (name, target, value) in set {
        match *target {
            StateTarget::Position(k) => {
                let s = &selection().states[k];
                out.positions.push(StartValue {
                    name: name.clone(),
                    kind: s.kind.clone(),
                    bodies: s.bodies.clone(),
                    value: *value,
                });
            }
            StateTarget::Velocity(j) => {
                let (kind, bodies) = match &selection().velocities[j] {
                    VelState::Derivative(s) => (VelocityIcKind::Rate(s.kind.clone()), s.bodies.clone()),
                    VelState::User(u) => (VelocityIcKind::User { f: u.f.clone(), abase: u.abase }, u.bodies.clone()),
                };
                out.velocities.push(StartValue { name: name.clone(), kind, bodies, value: *value });
            }
            StateTarget::Differential(k) => out.differentials.push((k, *value)),
        }
    }
    Ok(out)
}
