//! `<ModelStructure>` of both FMI versions, before it is written: each unknown (output,
//! state derivative, and in Initialization Mode also each state) with the knowns it
//! depends on, as positions in the variable list. FMI 2 writes a position as its 1-based
//! index, FMI 3 as its value reference.

use std::collections::BTreeSet;

use crate::fmi::variables::{Target, Variable};
use crate::linearize::{Dependencies, ModelStructure};
use crate::model::Model;

/// The unknowns and their dependencies (0-based positions in the variable list).
pub(super) struct Unknowns {
    /// Outputs, at communication points: on states and inputs.
    pub outputs: Vec<(usize, BTreeSet<usize>)>,
    /// State derivatives, at communication points: on states and inputs.
    pub derivatives: Vec<(usize, BTreeSet<usize>)>,
    /// Outputs, state derivatives and states in Initialization Mode: on parameters and
    /// inputs.
    pub initial: Vec<(usize, BTreeSet<usize>)>,
}

/// The unknowns of `vars` (the variables of `model`) with the dependencies `st`.
pub(super) fn unknowns(model: &Model, vars: &[Variable], st: &ModelStructure) -> Unknowns {
    let mut param_pos = vec![0; model.parameters.len()];
    let mut input_pos = vec![0; model.inputs.len()];
    let mut state_pos = vec![0; vars.iter().filter(|v| v.known.is_some()).count()];
    for (k, v) in vars.iter().enumerate() {
        match v.target {
            Target::Parameter(p) => param_pos[p] = k,
            Target::Input(i) => input_pos[i] = k,
            _ => {}
        }
        if let Some(c) = v.known {
            state_pos[c] = k;
        }
    }
    let running = |d: &Dependencies| -> BTreeSet<usize> {
        let states = d.states.iter().map(|&c| state_pos[c]);
        states.chain(d.inputs.iter().map(|&i| input_pos[i])).collect()
    };
    let none = Dependencies::default();
    let mut u = Unknowns { outputs: Vec::new(), derivatives: Vec::new(), initial: Vec::new() };
    for (k, v) in vars.iter().enumerate() {
        let d = match v.target {
            Target::Output(o) => &st.outputs[o],
            Target::StateDerivative(i) => &st.position_rates[i],
            Target::VelocityDerivative(j) => &st.velocity_rates[j],
            Target::DiffDerivative(i) => &st.diff_rates[i],
            Target::State(_) | Target::Velocity(_) | Target::Diff(_) => &none,
            _ => continue,
        };
        match v.target {
            Target::Output(_) => u.outputs.push((k, running(d))),
            Target::StateDerivative(_) | Target::VelocityDerivative(_) | Target::DiffDerivative(_) => {
                u.derivatives.push((k, running(d)))
            }
            _ => {}
        }
        let init = st.initial(d);
        let params = init.parameters.iter().map(|&p| param_pos[p]);
        u.initial.push((k, params.chain(init.inputs.iter().map(|&i| input_pos[i])).collect()));
    }
    u
}
