//! The sparsity of the linearization, from the structure of the mechanism: which states
//! and inputs each unknown (Ṡ_k, Ẇ_j, Ẋ_k, output o) can depend on at a communication
//! point (the nonzero pattern of the rows of A, B, C, D, Eq. 36), and which parameters
//! and inputs in Initialization Mode. What the FMU's `<ModelStructure>` declares.
//!
//! Knowns are indices: a state is its column of A and C (S, W, X order, as
//! [`super::Linearization::states`]), an input its index in the model. Positions and
//! velocities are functions of the states of their component only (Eq. 34e–f, h: C(q) = 0,
//! s(q) = S, Ċ = 0, ṡ = W), accelerations and multipliers of the states and the force
//! inputs of their component (Eq. 34a, c). Bodies are joined into components by constraint
//! and force elements and by the states themselves (a state that reads bodies of two
//! mechanisms makes their positions depend on each other's states), see
//! [`crate::mechanics::components`].
//!
//! - Ṡ_k = W_j where W_j is the velocity state Ṡ_k (Eq. 34g).
//! - Ẇ_j (Eq. 34a, c, i): the states of its component and the inputs its force elements read.
//! - An output (Eq. 36, rows of C and D): the states of the components of the bodies it
//!   reads; the inputs it reads directly; the inputs of the force elements whose loads it
//!   reads; and, when it reads accelerations or a joint, motion or constraint load, the
//!   inputs of that component.
//!
//! User variables and differentials (Eq. 7a–b) can couple any bodies, and with
//! non-holonomic constraints velocity states are not paired with position states: then
//! every unknown depends on every state (and the dynamic ones on every force input),
//! conservative and correct.

use super::select::Selection;
use crate::mechanics::System;
use crate::mechanics::components::{components, force_inputs};
use crate::mechanics::system::ElementSlot;
use crate::model::Model;
use crate::model::expr::{Expr, deps};
use std::collections::BTreeSet;

/// The knowns one unknown depends on at a communication point.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Dependencies {
    /// States, as columns of A and C (S, W, X order).
    pub states: BTreeSet<usize>,
    /// Inputs (indices into the model's inputs).
    pub inputs: BTreeSet<usize>,
}

/// The knowns one unknown depends on in Initialization Mode, where states are computed
/// from the parameters and inputs (assembly).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct InitialDependencies {
    /// Parameters (indices into the model's parameters).
    pub parameters: BTreeSet<usize>,
    /// Inputs (indices into the model's inputs).
    pub inputs: BTreeSet<usize>,
}

/// What every unknown of the linearization of a model depends on.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ModelStructure {
    /// Ṡ_k for each position state S_k.
    pub position_rates: Vec<Dependencies>,
    /// Ẇ_j for each velocity state W_j.
    pub velocity_rates: Vec<Dependencies>,
    /// Ẋ_k for each differential state X_k.
    pub diff_rates: Vec<Dependencies>,
    /// Each output.
    pub outputs: Vec<Dependencies>,
    /// Number of parameters of the model.
    parameters: usize,
    /// Inputs every unknown depends on in Initialization Mode (see [`ModelStructure::initial`]).
    static_inputs: BTreeSet<usize>,
}

impl ModelStructure {
    /// The structure of `model` linearized in the states of `sel` (None: the selection
    /// failed, no states).
    pub fn of(model: &Model, sel: Option<&Selection>) -> ModelStructure {
        let mech = Mechanism::of(model, sel);
        let (s0, s1) = sel.map_or((0, 0), |s| (s.states.len(), s.velocities.len()));
        let ns = s0 + s1 + model.differentials.len();
        let velocity_of_state = |k: usize| sel.and_then(|s| s.velocity_of_state(k));
        let state_of_velocity = |j: usize| sel.and_then(|s| s.state_of_velocity(j));
        // Columns of S_k and its W, or every column in global mode.
        let columns = |ks: &BTreeSet<usize>| -> BTreeSet<usize> {
            if mech.global {
                return (0..ns).collect();
            }
            ks.iter().flat_map(|&k| std::iter::once(k).chain(velocity_of_state(k).map(|j| s0 + j))).collect()
        };
        let dependencies = |d: KDependencies| Dependencies { states: columns(&d.states), inputs: d.inputs };
        let all_forces = || KDependencies { states: (0..s0).collect(), inputs: mech.all_force_inputs.clone() };
        let position_rates = (0..s0)
            .map(|k| match velocity_of_state(k) {
                Some(j) => Dependencies { states: [s0 + j].into(), inputs: BTreeSet::new() },
                // ṡ(q, u) of a position state without a velocity state: every state.
                None => dependencies(KDependencies::default()),
            })
            .collect();
        let velocity_rates = (0..s1)
            .map(|j| {
                if mech.global {
                    return dependencies(all_forces());
                }
                dependencies(state_of_velocity(j).map(|k| mech.acceleration(k)).unwrap_or_default())
            })
            .collect();
        let diff_rates = model.differentials.iter().map(|_| dependencies(all_forces())).collect();
        let outputs = model
            .outputs
            .iter()
            .map(|o| {
                let d = mech.output(&o.function);
                if !mech.global {
                    return dependencies(d);
                }
                let e = deps(&o.function);
                let user = !(e.variables.is_empty() && e.diffs.is_empty() && e.diff_dots.is_empty());
                let states = if !e.markers.is_empty() || !e.loads.is_empty() || user {
                    (0..ns).collect()
                } else {
                    BTreeSet::new()
                };
                Dependencies { states, inputs: d.inputs }
            })
            .collect();
        let static_inputs = if model.static_analysis { mech.all_force_inputs.clone() } else { BTreeSet::new() };
        ModelStructure {
            position_rates,
            velocity_rates,
            diff_rates,
            outputs,
            parameters: model.parameters.len(),
            static_inputs,
        }
    }

    /// What an unknown that depends on `d` at communication points (a state: nothing)
    /// depends on in Initialization Mode: every parameter (they are `initial="exact"`, and
    /// setting one re-evaluates the whole model), its inputs, and with `<analysis
    /// static="true"/>` every input a force reads (the equilibrium moves with them).
    pub fn initial(&self, d: &Dependencies) -> InitialDependencies {
        let inputs = d.inputs.iter().chain(&self.static_inputs).copied().collect();
        InitialDependencies { parameters: (0..self.parameters).collect(), inputs }
    }
}

/// Dependencies with states as position-state indices k (S_k with its W).
#[derive(Clone, Debug, Default)]
struct KDependencies {
    states: BTreeSet<usize>,
    inputs: BTreeSet<usize>,
}

/// The components of a model's mechanism and what each one's states and forces are.
struct Mechanism {
    /// None when the model cannot be built into a system (it has no states then).
    sys: Option<System>,
    /// Component of each body.
    body_comp: Vec<usize>,
    /// Component of each position state (None: it reads no body).
    state_comp: Vec<Option<usize>>,
    /// Inputs read by the force elements of each component.
    comp_inputs: Vec<BTreeSet<usize>>,
    /// Inputs read by any force element (when there is no system), and with user elements
    /// also by any variable or differential.
    all_force_inputs: BTreeSet<usize>,
    /// One component for everything (see the module documentation).
    global: bool,
}

impl Mechanism {
    fn of(model: &Model, sel: Option<&Selection>) -> Mechanism {
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
            return Mechanism { sys: None, body_comp, state_comp, comp_inputs, all_force_inputs: all, global: false };
        };
        let states: Vec<&[usize]> =
            sel.map(|s| s.states.iter().map(|s| s.bodies.as_slice()).collect()).unwrap_or_default();
        let body_comp = components(&sys, &states);
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
        Mechanism { sys: Some(sys), body_comp, state_comp, comp_inputs, all_force_inputs, global }
    }

    /// Position states of the components `comps`.
    fn states_in(&self, comps: &BTreeSet<usize>) -> BTreeSet<usize> {
        let of = |k: &(usize, &Option<usize>)| k.1.is_some_and(|c| comps.contains(&c));
        self.state_comp.iter().enumerate().filter(of).map(|(k, _)| k).collect()
    }

    /// What the acceleration of position state k (Ẇ of its W) depends on.
    fn acceleration(&self, k: usize) -> KDependencies {
        let Some(c) = self.state_comp.get(k).copied().flatten() else { return KDependencies::default() };
        let comps = [c].into();
        KDependencies { states: self.states_in(&comps), inputs: self.comp_inputs[c].clone() }
    }

    /// What the output expression `e` depends on (in global mode the `states` are left
    /// empty: the caller adds every state when it reads the motion).
    fn output(&self, e: &Expr) -> KDependencies {
        let d = deps(e);
        let mut inputs: BTreeSet<usize> = d.inputs.iter().copied().collect();
        if self.global {
            let user = !(d.variables.is_empty() && d.diffs.is_empty() && d.diff_dots.is_empty());
            if d.level >= 2 || !d.loads.is_empty() || user {
                inputs.extend(&self.all_force_inputs);
            }
            return KDependencies { states: BTreeSet::new(), inputs };
        }
        let Some(sys) = &self.sys else {
            if d.level >= 2 || !d.loads.is_empty() {
                inputs.extend(&self.all_force_inputs);
            }
            return KDependencies { states: BTreeSet::new(), inputs };
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
        KDependencies { states: self.states_in(&comps), inputs }
    }
}
