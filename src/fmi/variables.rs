//! The FMI variables of a model and their value references: parameters first, then
//! inputs, then outputs, then the linearization states: positions S, their derivatives
//! `der(S)` (the velocity states W where W = Ṡ), velocity states that are not such a
//! derivative (non-holonomic models: user `<velocity>`s), the velocity derivatives
//! `der(S,2)` / `der(W)`, then the differential states X, `der(X)` and the user variables
//! V, numbered consecutively from 0 in model order; last the solver settings (the Integer
//! parameter `solver.maxSteps`: a model name has no '.', so it cannot collide, and being
//! last it shifts no other value reference). The linearization states are those of the
//! [`StateLayout`] the packer decided and stored in the FMU; the packer writes the
//! variables into modelDescription.xml and the C API resolves value references with them,
//! so both always agree.

use crate::dae::DEFAULT_MAX_STEPS;
use crate::linearize::{StateLayout, derivative_name};
use crate::model::Model;
use crate::model::units::per_second;

/// The FMI version an FMU or instance follows; where the two differ, code says so
/// with this.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Standard {
    /// FMI 2.0.
    Fmi2,
    /// FMI 3.0.
    Fmi3,
}

/// Name of the Integer parameter that bounds the integrator step attempts per fmi2DoStep.
pub const MAX_STEPS_NAME: &str = "solver.maxSteps";

/// FMI causality of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// A model parameter or a solver setting.
    Parameter,
    /// A model input.
    Input,
    /// A model output.
    Output,
    /// Linearization states and their derivatives.
    Local,
    /// The independent variable, time (FMI 3 only).
    Independent,
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
    /// Position state S_k.
    State(usize),
    /// der(S_k): the velocity state W_j where W_j = Ṡ_k, otherwise a derivative only.
    StateDerivative(usize),
    /// Velocity state W_j that is not the derivative of a position state.
    Velocity(usize),
    /// der(W_j) (`der(S_k,2)` where W_j = Ṡ_k).
    VelocityDerivative(usize),
    /// Differential state X_k (`<differential>`, a state).
    Diff(usize),
    /// Its derivative der(X_k).
    DiffDerivative(usize),
    /// User variable V_k (`<variable>`).
    UserVariable(usize),
    /// `solver.maxSteps` (Integer, tunable): most integrator step attempts per fmi2DoStep.
    MaxSteps,
    /// Time, the independent variable (FMI 3 only).
    Time,
}

impl Target {
    /// Whether the variable is an FMI Integer (else Real).
    pub fn is_integer(self) -> bool {
        matches!(self, Target::MaxSteps)
    }
}

/// One FMI scalar variable (Real, except `solver.maxSteps`: see [`Target::is_integer`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// FMI name.
    pub name: String,
    /// FMI value reference (its index in [`variables`]).
    pub value_reference: u32,
    /// FMI causality.
    pub causality: Causality,
    /// What it denotes in the engine.
    pub target: Target,
    /// Start value (parameters and inputs; an Integer's is a whole number).
    pub start: Option<f64>,
    /// Unit, if any.
    pub unit: Option<String>,
    /// FMI description, if any.
    pub description: Option<String>,
    /// For a state derivative: the 1-based ModelVariables index of its state.
    pub derivative: Option<usize>,
    /// As a known of the linearization: its column of A and C (S, W, X order).
    pub known: Option<usize>,
    /// As an unknown of the linearization: its row of A and B (Ṡ, Ẇ, Ẋ order).
    pub unknown: Option<usize>,
}

/// All FMI variables of a model whose FMU (of FMI version `standard`) exposes the
/// linearization states `lay`, in ModelVariables order (index + 1 = FMI 2 index). FMI 3
/// adds the independent variable `time`, last.
pub fn variables(model: &Model, lay: &StateLayout, standard: Standard) -> Vec<Variable> {
    let mut v = Vec::new();
    push_parameters(&mut v, model);
    push_inputs(&mut v, model);
    push_outputs(&mut v, model);
    let first_sd = push_positions(&mut v, lay);
    push_velocities(&mut v, lay, first_sd);
    push_differentials(&mut v, model, lay.positions.len() + lay.velocities.len());
    push_user_variables(&mut v, model);
    push_max_steps(&mut v);
    if standard == Standard::Fmi3 {
        let mut t = local("time".into(), v.len(), Target::Time);
        t.causality = Causality::Independent;
        t.unit = Some("s".into());
        t.description = Some("Simulation time".into());
        v.push(t);
    }
    v
}

/// The model parameters (causality parameter, with start value, unit and description).
fn push_parameters(v: &mut Vec<Variable>, model: &Model) {
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
            known: None,
            unknown: None,
        });
    }
}

/// The model inputs (causality input, with start value and unit).
fn push_inputs(v: &mut Vec<Variable>, model: &Model) {
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
            known: None,
            unknown: None,
        });
    }
}

/// The model outputs (causality output, with unit).
fn push_outputs(v: &mut Vec<Variable>, model: &Model) {
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
            known: None,
            unknown: None,
        });
    }
}

/// A local variable `name` with value reference `vr`, no start, unit, description, or
/// linearization role yet.
fn local(name: String, vr: usize, target: Target) -> Variable {
    Variable {
        name,
        value_reference: vr as u32,
        causality: Causality::Local,
        target,
        start: None,
        unit: None,
        description: None,
        derivative: None,
        known: None,
        unknown: None,
    }
}

/// The position states S (knowns 0..s0), then their derivatives der(S) (unknowns
/// 0..s0); returns the 0-based index of the first der(S).
fn push_positions(v: &mut Vec<Variable>, lay: &StateLayout) -> usize {
    let s0 = lay.positions.len();
    let first_s = v.len();
    for (k, s) in lay.positions.iter().enumerate() {
        let mut x = local(s.name.clone(), v.len(), Target::State(k));
        x.unit = s.unit.clone();
        x.description = Some(s.description.clone());
        x.known = Some(k);
        v.push(x);
    }
    // der(S_k): the velocity state W_j = Ṡ_k where there is one (its name), else a derivative only.
    let first_sd = v.len();
    for (k, s) in lay.positions.iter().enumerate() {
        let w = lay.velocity_of_state(k);
        let name = w.map_or_else(|| derivative_name(&s.name), |j| lay.velocities[j].name.clone());
        let mut x = local(name, v.len(), Target::StateDerivative(k));
        x.unit = s.unit.as_deref().and_then(per_second);
        x.derivative = Some(first_s + k + 1);
        x.known = w.map(|j| s0 + j);
        x.unknown = Some(k);
        v.push(x);
    }
    first_sd
}

/// The velocity states W that are no der(S) (knowns s0 + j), then every der(W) (unknowns
/// s0 + j); `first_sd` is the 0-based index of the first der(S).
fn push_velocities(v: &mut Vec<Variable>, lay: &StateLayout, first_sd: usize) {
    let (s0, s1) = (lay.positions.len(), lay.velocities.len());
    // 1-based index of each W_j's variable.
    let mut w_index = vec![0; s1];
    for (j, w) in w_index.iter_mut().enumerate() {
        if let Some(k) = lay.state_of_velocity(j) {
            *w = first_sd + k + 1;
        }
    }
    for j in (0..s1).filter(|&j| lay.state_of_velocity(j).is_none()) {
        let w = &lay.velocities[j];
        let mut x = local(w.name.clone(), v.len(), Target::Velocity(j));
        x.unit = w.unit.clone();
        x.description = Some(w.description.clone());
        x.known = Some(s0 + j);
        w_index[j] = v.len() + 1;
        v.push(x);
    }
    for (j, &wi) in w_index.iter().enumerate() {
        let name = match lay.state_of_velocity(j) {
            Some(k) => format!("der({},2)", lay.positions[k].name),
            None => derivative_name(&lay.velocities[j].name),
        };
        let mut x = local(name, v.len(), Target::VelocityDerivative(j));
        x.unit = lay.velocities[j].unit.as_deref().and_then(per_second);
        x.derivative = Some(wi);
        x.unknown = Some(s0 + j);
        v.push(x);
    }
}

/// The differential states X, then their derivatives der(X); `offset` = s0 + s1 is the
/// known (and unknown) index of X_0 (of der(X_0)).
fn push_differentials(v: &mut Vec<Variable>, model: &Model, offset: usize) {
    let first_x = v.len();
    for (k, d) in model.differentials.iter().enumerate() {
        let mut x = local(d.name.clone(), v.len(), Target::Diff(k));
        x.description = Some("differential state (seed Eq. 7a)".into());
        x.known = Some(offset + k);
        v.push(x);
    }
    for (k, d) in model.differentials.iter().enumerate() {
        let mut x = local(derivative_name(&d.name), v.len(), Target::DiffDerivative(k));
        x.derivative = Some(first_x + k + 1);
        x.unknown = Some(offset + k);
        v.push(x);
    }
}

/// The user variables V (locals, no linearization role).
fn push_user_variables(v: &mut Vec<Variable>, model: &Model) {
    for (k, d) in model.variables.iter().enumerate() {
        let mut x = local(d.name.clone(), v.len(), Target::UserVariable(k));
        x.description = Some("user variable (seed Eq. 7b)".into());
        v.push(x);
    }
}

/// The Integer parameter [`MAX_STEPS_NAME`], last.
fn push_max_steps(v: &mut Vec<Variable>) {
    v.push(Variable {
        name: MAX_STEPS_NAME.into(),
        value_reference: v.len() as u32,
        causality: Causality::Parameter,
        target: Target::MaxSteps,
        start: Some(DEFAULT_MAX_STEPS as f64),
        unit: None,
        description: Some(format!(
            "most internal integrator steps (accepted and rejected) per fmi2DoStep, like CVODE's mxstep \
             (default {DEFAULT_MAX_STEPS}); a step that needs more returns fmi2Discard with \
             fmi2LastSuccessfulTime = the time reached; at least 1, tunable between steps"
        )),
        derivative: None,
        known: None,
        unknown: None,
    });
}
