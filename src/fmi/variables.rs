//! The FMI variables of a model and their value references: parameters first, then
//! inputs, then outputs, then the linearization states S, their velocities `der(S)` (also
//! states) and accelerations `der(S,2)`, then the differential states X, `der(X)` and the
//! user variables V, numbered consecutively from 0 in model order. The
//! packer writes them into modelDescription.xml and the C API resolves value references
//! with them, so both always agree.

use crate::model::Model;

/// FMI causality of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
    /// Linearization states and their derivatives.
    Local,
}

/// What a value reference denotes in the engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Index into `Model::parameters`.
    Parameter(usize),
    /// Index into `Model::inputs`.
    Input(usize),
    /// Index into `Model::outputs`.
    Output(usize),
    /// Linearization state S_k.
    State(usize),
    /// Its velocity W_k = der(S_k) (a state too).
    StateDerivative(usize),
    /// Its acceleration der(S_k, 2) = der(W_k).
    StateSecondDerivative(usize),
    /// Differential state X_k (`<differential>`, a state).
    Diff(usize),
    /// Its derivative der(X_k).
    DiffDerivative(usize),
    /// User variable V_k (`<variable>`).
    UserVariable(usize),
}

/// One FMI scalar variable (all are Real).
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub causality: Causality,
    pub target: Target,
    /// Start value (parameters and inputs).
    pub start: Option<f64>,
    pub unit: Option<String>,
    pub description: Option<String>,
    /// For a state derivative: the 1-based ModelVariables index of its state.
    pub derivative: Option<usize>,
}

/// All FMI variables of a model, in ModelVariables order (index + 1 = FMI index).
pub fn variables(model: &Model) -> Vec<Variable> {
    let mut v = Vec::new();
    for (k, p) in model.parameters.iter().enumerate() {
        v.push(Variable {
            name: p.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Parameter,
            target: Target::Parameter(k),
            start: Some(p.value.value),
            unit: p.unit.clone(),
            description: p.description.clone(),
            derivative: None,
        });
    }
    for (k, i) in model.inputs.iter().enumerate() {
        v.push(Variable {
            name: i.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Input,
            target: Target::Input(k),
            start: Some(i.start.value),
            unit: i.unit.clone(),
            description: None,
            derivative: None,
        });
    }
    for (k, o) in model.outputs.iter().enumerate() {
        v.push(Variable {
            name: o.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Output,
            target: Target::Output(k),
            start: None,
            unit: o.unit.clone(),
            description: None,
            derivative: None,
        });
    }
    let names = state_names(model);
    let first = v.len();
    let s = names.len();
    for (level, (prefix, suffix)) in [("", ""), ("der(", ")"), ("der(", ",2)")].into_iter().enumerate() {
        for (k, name) in names.iter().enumerate() {
            let target = match level {
                0 => Target::State(k),
                1 => Target::StateDerivative(k),
                _ => Target::StateSecondDerivative(k),
            };
            v.push(Variable {
                name: format!("{prefix}{name}{suffix}"),
                value_reference: v.len() as u32,
                causality: Causality::Local,
                target,
                start: None,
                unit: None,
                description: (level == 0).then(|| "linearization state (seed Eq. 33)".to_string()),
                // 1-based index of the variable this one is the derivative of.
                derivative: (level > 0).then(|| first + (level - 1) * s + k + 1),
            });
        }
    }
    let first_x = v.len();
    for (k, d) in model.differentials.iter().enumerate() {
        v.push(Variable {
            name: d.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Local,
            target: Target::Diff(k),
            start: None,
            unit: None,
            description: Some("differential state (seed Eq. 7a)".into()),
            derivative: None,
        });
    }
    for (k, d) in model.differentials.iter().enumerate() {
        v.push(Variable {
            name: format!("der({})", d.name),
            value_reference: v.len() as u32,
            causality: Causality::Local,
            target: Target::DiffDerivative(k),
            start: None,
            unit: None,
            description: None,
            derivative: Some(first_x + k + 1),
        });
    }
    for (k, d) in model.variables.iter().enumerate() {
        v.push(Variable {
            name: d.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Local,
            target: Target::UserVariable(k),
            start: None,
            unit: None,
            description: Some("user variable (seed Eq. 7b)".into()),
            derivative: None,
        });
    }
    v
}

/// Names of the linearization states the FMU exposes (selected from the assembled initial
/// configuration); none when the model cannot be initialized or linearized.
pub fn state_names(model: &Model) -> Vec<String> {
    crate::linearize::selection_at_start(model)
        .map(|sel| sel.states.iter().map(|s| s.name.clone()).collect())
        .unwrap_or_default()
}
