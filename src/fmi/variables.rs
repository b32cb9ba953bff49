//! The FMI variables of a model and their value references: parameters first, then
//! inputs, then outputs, numbered consecutively from 0 in model order. The packer writes
//! them into modelDescription.xml and the C API resolves value references with them, so
//! both always agree.

use crate::model::Model;

/// FMI causality of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
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
        });
    }
    v
}
