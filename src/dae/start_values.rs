//! Start values a host sets on states (FMI start values, `--set` on the command line):
//! initialization meets them exactly, like the exact joint ICs — positions in assembly
//! (as drives of its continuation), velocities in the consistent-velocity solve,
//! differential states as their initial value.

use crate::mechanics::System;
use crate::mechanics::constraints::{ConstraintEl, ConstraintKind, VelocityIc, VelocityIcKind};
use crate::mechanics::measure_names::{derivative_of_name, expr_bodies, measure_by_name, measure_names};
use crate::mechanics::measures::StateKind;
use crate::model::{Model, SrcPos};

/// The element tag of a start value's assembly condition (how its errors are told apart).
pub const START_VALUE_TAG: &str = "start value";

/// One value set on a state.
#[derive(Clone, Debug)]
pub struct StartValue<K> {
    /// The state's name (as the FMU lists it).
    pub name: String,
    /// What it measures.
    pub kind: K,
    /// The bodies it reads (global indices, sorted).
    pub bodies: Vec<usize>,
    /// The value asked for.
    pub value: f64,
}

/// Values set on states, to be met exactly at initialization.
#[derive(Clone, Debug, Default)]
pub struct StartValues {
    /// Position-level states S.
    pub positions: Vec<StartValue<StateKind>>,
    /// Velocity-level states W (`der(S)` or a `<velocity>`).
    pub velocities: Vec<StartValue<VelocityIcKind>>,
    /// Differential states X: (index, value).
    pub differentials: Vec<(usize, f64)>,
}

impl StartValues {
    /// The start values `model.state_starts` sets by name, resolved on `sys` (built from
    /// `model`): a position state's measure (`hinge.angle`, `arm.x`, a `<linearization>`
    /// state), `der(...)` of one (its rate), a `<linearization><velocity>`, a differential.
    /// An unknown name is an error naming it, with the closest name as a suggestion.
    pub fn named(sys: &System, model: &Model) -> Result<StartValues, String> {
        let mut out = StartValues::default();
        for (name, value) in &model.state_starts {
            let value = *value;
            if let Some(k) = model.differentials.iter().position(|d| d.name == *name) {
                out.differentials.push((k, value));
            } else if let Some((_, f, abase)) = sys.lin_velocities.iter().find(|v| v.0 == *name) {
                let bodies = expr_bodies(sys, f);
                let kind = VelocityIcKind::User { f: f.clone(), abase: *abase };
                out.velocities.push(StartValue { name: name.clone(), kind, bodies, value });
            } else if let Some((kind, bodies)) = derivative_of_name(name).and_then(|s| measure_by_name(sys, s)) {
                let kind = VelocityIcKind::Rate(kind);
                out.velocities.push(StartValue { name: name.clone(), kind, bodies, value });
            } else if let Some((kind, bodies)) = measure_by_name(sys, name) {
                out.positions.push(StartValue { name: name.clone(), kind, bodies, value });
            } else {
                let mut names = measure_names(sys);
                names.extend(names.clone().iter().map(|n| format!("der({n})")));
                names.extend(sys.lin_velocities.iter().map(|v| v.0.clone()));
                names.extend(model.differentials.iter().map(|d| d.name.clone()));
                return Err(model.unknown_override(name, &names));
            }
        }
        Ok(out)
    }

    /// Check that every name `model.state_starts` sets is a state of `model` (the error of
    /// [`StartValues::named`] otherwise), before anything is run.
    pub fn check_names(model: &Model) -> Result<(), String> {
        if model.state_starts.is_empty() {
            return Ok(());
        }
        Self::named(&System::from_model(model)?, model).map(|_| ())
    }

    /// These values, then `other`'s: a state `other` sets is taken from `other` only (an
    /// FMU host's value replaces the one the FMU was packed with).
    pub fn overridden_by(mut self, other: &StartValues) -> StartValues {
        let set =
            |n: &String| other.positions.iter().any(|p| p.name == *n) || other.velocities.iter().any(|v| v.name == *n);
        self.positions.retain(|p| !set(&p.name));
        self.velocities.retain(|v| !set(&v.name));
        self.differentials.retain(|(k, _)| !other.differentials.iter().any(|o| o.0 == *k));
        self.positions.extend(other.positions.iter().cloned());
        self.velocities.extend(other.velocities.iter().cloned());
        self.differentials.extend(other.differentials.iter().copied());
        self
    }

    /// Whether nothing is set.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty() && self.velocities.is_empty() && self.differentials.is_empty()
    }

    /// Add the conditions to `sys`: position ones after its exact ICs (rows after theirs),
    /// velocity ones after its velocity ICs, differential starts over the model's.
    pub fn apply(&self, sys: &mut System) {
        let mut row = sys.constraints.iter().chain(&sys.ic_constraints).map(|c| c.row + c.neq).max().unwrap_or(0);
        for p in &self.positions {
            let kind = ConstraintKind::State { kind: p.kind.clone(), value: p.value };
            let mut el = ConstraintEl::new(p.name.clone(), kind, p.bodies.clone(), START_VALUE_TAG, SrcPos::default());
            el.row = row;
            row += el.neq;
            sys.ic_constraints.push(el);
        }
        for v in &self.velocities {
            sys.ic_velocities.push(VelocityIc {
                name: v.name.clone(),
                kind: v.kind.clone(),
                value: v.value,
                bodies: v.bodies.clone(),
            });
        }
        for &(k, x) in &self.differentials {
            sys.x_init[k] = x;
        }
    }
}
