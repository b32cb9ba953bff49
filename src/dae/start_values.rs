//! Start values a host sets on states (FMI start values, `--set` on the command line):
//! initialization meets them exactly, like the exact joint ICs — positions in assembly
//! (as drives of its continuation), velocities in the consistent-velocity solve,
//! differential states as their initial value.

use crate::mechanics::System;
use crate::mechanics::constraints::{ConstraintEl, ConstraintKind, VelocityIc, VelocityIcKind};
use crate::mechanics::measures::StateKind;
use crate::model::SrcPos;

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
