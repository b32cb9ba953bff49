//! What each unknown of `<ModelStructure>` depends on at a communication point, from the
//! structure of the mechanism (see [`crate::mechanics::components`]).
//!
//! The knowns are the linearization states S, W (selected when the FMU is packed) and the
//! inputs. Positions and velocities are functions of the states of their component only
//! (Eq. 34e–f, h: C(q) = 0, s(q) = S, Ċ = 0, ṡ = W), and accelerations and multipliers of
//! the states and the force inputs of their component (Eq. 34a, c). Bodies are joined into
//! components by constraint and force elements and by the states themselves (a state that
//! reads bodies of two mechanisms makes their positions depend on each other's states).
//!
//! - der(S_k) = W_k (Eq. 34g).
//! - der(W_k): the states of its component and the inputs its force elements read.
//! - An output: the states of the components of the bodies it reads; the inputs it reads
//!   directly; the inputs of the force elements whose loads it reads; and, when it reads
//!   accelerations or a joint, motion or constraint load, the inputs of that component.

use crate::linearize::selection_at_start;
use crate::mechanics::System;
use crate::mechanics::components::{components, force_inputs};
use crate::mechanics::system::ElementSlot;
use crate::model::Model;
use crate::model::expr::{Expr, deps};
use std::collections::BTreeSet;

/// Dependencies as indices: linearization states k (S_k and W_k together) and inputs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Dependencies {
    pub states: BTreeSet<usize>,
    pub inputs: BTreeSet<usize>,
}

/// The components of a model's mechanism and what each one's states and forces are.
pub struct Structure {
    /// None when the model cannot be built into a system (it has no states then).
    sys: Option<System>,
    /// Component of each body.
    body_comp: Vec<usize>,
    /// Component of each linearization state (None: it reads no body).
    state_comp: Vec<Option<usize>>,
    /// Inputs read by the force elements of each component.
    comp_inputs: Vec<BTreeSet<usize>>,
    /// Inputs read by any force element (when there is no system), and with user elements
    /// also by any variable or differential.
    all_force_inputs: BTreeSet<usize>,
    /// One component for everything: user variables and differentials can couple any
    /// bodies (through the elements that read them), and with non-holonomic constraints the
    /// velocity states are not paired with position states. Conservative and correct.
    global: bool,
}

impl Structure {
    /// The structure of `model` with the linearization states selected at pack time
    /// (the same selection as [`super::variables::state_names`]).
    pub fn of(model: &Model) -> Structure {
        let Ok(sys) = System::from_model(model) else {
            let mut all = BTreeSet::new();
            for f in &model.sforces {
                all.extend(deps(&f.function).inputs);
            }
            for g in &model.gforces {
                all.extend(g.force.iter().chain(&g.torque).flat_map(|e| deps(e).inputs));
            }
            // No system, no states: outputs depend on inputs only.
            let (body_comp, state_comp, comp_inputs) = (vec![], vec![], vec![]);
            return Structure { sys: None, body_comp, state_comp, comp_inputs, all_force_inputs: all, global: false };
        };
        let states: Vec<Vec<usize>> = selection_at_start(model)
            .map(|sel| sel.states.iter().map(|s| s.bodies.clone()).collect())
            .unwrap_or_default();
        let groups: Vec<&[usize]> = states.iter().map(|b| b.as_slice()).collect();
        let body_comp = components(&sys, &groups);
        let ncomp = body_comp.iter().map(|c| c + 1).max().unwrap_or(0);
        let mut comp_inputs = vec![BTreeSet::new(); ncomp];
        let mut all_force_inputs = BTreeSet::new();
        for f in &sys.forces {
            let inputs = force_inputs(f);
            if let Some(&b) = f.bodies.first() {
                comp_inputs[body_comp[b]].extend(&inputs);
            }
            all_force_inputs.extend(inputs);
        }
        let state_comp = states.iter().map(|b| b.first().map(|&b| body_comp[b])).collect();
        let global = !sys.user.is_empty() || sys.mn > 0;
        if global {
            for u in &sys.user {
                all_force_inputs.extend(deps(&u.f).inputs);
            }
        }
        Structure { sys: Some(sys), body_comp, state_comp, comp_inputs, all_force_inputs, global }
    }

    /// Inputs read by any force element (and user element).
    pub fn force_inputs(&self) -> &BTreeSet<usize> {
        &self.all_force_inputs
    }

    /// Whether every state and force input counts for every unknown (see `global`).
    pub fn is_global(&self) -> bool {
        self.global
    }

    /// States of the components `comps`.
    fn states_in(&self, comps: &BTreeSet<usize>) -> BTreeSet<usize> {
        let of = |k: &(usize, &Option<usize>)| k.1.is_some_and(|c| comps.contains(&c));
        self.state_comp.iter().enumerate().filter(of).map(|(k, _)| k).collect()
    }

    /// What der(W_k) depends on.
    pub fn acceleration(&self, k: usize) -> Dependencies {
        let Some(c) = self.state_comp.get(k).copied().flatten() else { return Dependencies::default() };
        let comps = [c].into();
        Dependencies { states: self.states_in(&comps), inputs: self.comp_inputs[c].clone() }
    }

    /// What the output expression `e` depends on (in global mode the `states` are left
    /// empty: the caller adds every state when `reads_motion`).
    pub fn output(&self, e: &Expr) -> Dependencies {
        let d = deps(e);
        let mut inputs: BTreeSet<usize> = d.inputs.iter().copied().collect();
        if self.global {
            let user = !(d.variables.is_empty() && d.diffs.is_empty() && d.diff_dots.is_empty());
            if d.level >= 2 || !d.loads.is_empty() || user {
                inputs.extend(&self.all_force_inputs);
            }
            return Dependencies { states: BTreeSet::new(), inputs };
        }
        let Some(sys) = &self.sys else {
            if d.level >= 2 || !d.loads.is_empty() {
                inputs.extend(&self.all_force_inputs);
            }
            return Dependencies { states: BTreeSet::new(), inputs };
        };
        // Components read (their states count) and those whose force inputs count.
        let mut comps = BTreeSet::new();
        let mut whole = BTreeSet::new();
        for b in d.markers.iter().filter_map(|&m| sys.markers[m].body) {
            comps.insert(self.body_comp[b]);
            if d.level >= 2 {
                whole.insert(self.body_comp[b]);
            }
        }
        for &r in &d.loads {
            match sys.element_slot(r) {
                ElementSlot::Constraint(k) => {
                    for &b in sys.constraints.get(k).map_or(&[][..], |c| &c.bodies) {
                        comps.insert(self.body_comp[b]);
                        whole.insert(self.body_comp[b]);
                    }
                }
                ElementSlot::Force(k) => {
                    if let Some(f) = sys.forces.get(k) {
                        comps.extend(f.bodies.iter().map(|&b| self.body_comp[b]));
                        inputs.extend(force_inputs(f));
                    }
                }
            }
        }
        for c in &whole {
            inputs.extend(&self.comp_inputs[*c]);
        }
        Dependencies { states: self.states_in(&comps), inputs }
    }
}
