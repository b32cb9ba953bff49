//! The FMI variables of a model and their value references: parameters first, then
//! inputs, then outputs, then the linearization states: positions S, their derivatives
//! `der(S)` (the velocity states W where W = Ṡ), velocity states that are not such a
//! derivative (non-holonomic models: user `<velocity>`s), the velocity derivatives
//! `der(S,2)` / `der(W)`, then the differential states X, `der(X)` and the user variables
//! V, numbered consecutively from 0 in model order; last the solver settings (the Integer
//! parameter `solver.maxSteps`: a model name has no '.', so it cannot collide, and being
//! last it shifts no other value reference). The packer writes them into
//! modelDescription.xml and the C API resolves value references with them, so both
//! always agree.

use crate::dae::DEFAULT_MAX_STEPS;
use crate::model::Model;
use crate::model::units::per_second;

/// Name of the Integer parameter that bounds the integrator step attempts per fmi2DoStep.
pub const MAX_STEPS_NAME: &str = "solver.maxSteps";

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
    pub name: String,
    pub value_reference: u32,
    pub causality: Causality,
    pub target: Target,
    /// Start value (parameters and inputs; an Integer's is a whole number).
    pub start: Option<f64>,
    pub unit: Option<String>,
    pub description: Option<String>,
    /// For a state derivative: the 1-based ModelVariables index of its state.
    pub derivative: Option<usize>,
    /// As a known of the linearization: its column of A and C (S, W, X order).
    pub known: Option<usize>,
    /// As an unknown of the linearization: its row of A and B (Ṡ, Ẇ, Ẋ order).
    pub unknown: Option<usize>,
}

/// The linearization states an FMU exposes: position states S and velocity states W
/// (`w_of[j]`: the S index whose derivative W_j is, if any).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateLayout {
    pub s: Vec<String>,
    pub w: Vec<String>,
    pub w_of: Vec<Option<usize>>,
    /// Units of S and W (from the coordinate: m, rad, m/s, rad/s; none for a general
    /// expression).
    pub s_units: Vec<Option<String>>,
    pub w_units: Vec<Option<String>>,
    /// What each S and W measures, frame stated (FMI variable descriptions).
    pub s_about: Vec<String>,
    pub w_about: Vec<String>,
}

impl StateLayout {
    /// The velocity state that is Ṡ_k, if any.
    pub fn w_for(&self, k: usize) -> Option<usize> {
        self.w_of.iter().position(|o| *o == Some(k))
    }
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
            known: None,
            unknown: None,
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
            known: None,
            unknown: None,
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
            known: None,
            unknown: None,
        });
    }
    let lay = state_layout(model);
    let (s0, s1) = (lay.s.len(), lay.w.len());
    let var = |name: String, vr: usize, target: Target| Variable {
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
    };
    let first_s = v.len();
    for (k, name) in lay.s.iter().enumerate() {
        let mut x = var(name.clone(), v.len(), Target::State(k));
        x.unit = lay.s_units[k].clone();
        x.description = Some(lay.s_about[k].clone());
        x.known = Some(k);
        v.push(x);
    }
    let first_sd = v.len();
    for (k, name) in lay.s.iter().enumerate() {
        let mut x = var(format!("der({name})"), v.len(), Target::StateDerivative(k));
        x.unit = lay.s_units[k].as_deref().and_then(per_second);
        x.derivative = Some(first_s + k + 1);
        x.known = lay.w_for(k).map(|j| s0 + j);
        x.unknown = Some(k);
        v.push(x);
    }
    // 1-based index of each W_j's variable.
    let mut w_index = vec![0; s1];
    for (j, w) in w_index.iter_mut().enumerate() {
        if let Some(k) = lay.w_of[j] {
            *w = first_sd + k + 1;
        }
    }
    for j in (0..s1).filter(|&j| lay.w_of[j].is_none()) {
        let mut x = var(lay.w[j].clone(), v.len(), Target::Velocity(j));
        x.unit = lay.w_units[j].clone();
        x.description = Some(lay.w_about[j].clone());
        x.known = Some(s0 + j);
        w_index[j] = v.len() + 1;
        v.push(x);
    }
    for (j, &wi) in w_index.iter().enumerate() {
        let name = match lay.w_of[j] {
            Some(k) => format!("der({},2)", lay.s[k]),
            None => format!("der({})", lay.w[j]),
        };
        let mut x = var(name, v.len(), Target::VelocityDerivative(j));
        x.unit = lay.w_units[j].as_deref().and_then(per_second);
        x.derivative = Some(wi);
        x.unknown = Some(s0 + j);
        v.push(x);
    }
    let first_x = v.len();
    for (k, d) in model.differentials.iter().enumerate() {
        let mut x = var(d.name.clone(), v.len(), Target::Diff(k));
        x.description = Some("differential state (seed Eq. 7a)".into());
        x.known = Some(s0 + s1 + k);
        v.push(x);
    }
    for (k, d) in model.differentials.iter().enumerate() {
        let mut x = var(format!("der({})", d.name), v.len(), Target::DiffDerivative(k));
        x.derivative = Some(first_x + k + 1);
        x.unknown = Some(s0 + s1 + k);
        v.push(x);
    }
    for (k, d) in model.variables.iter().enumerate() {
        let mut x = var(d.name.clone(), v.len(), Target::UserVariable(k));
        x.description = Some("user variable (seed Eq. 7b)".into());
        v.push(x);
    }
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
    v
}

/// The linearization states the FMU exposes (selected from the assembled initial
/// configuration); none when the model cannot be initialized or linearized.
pub fn state_layout(model: &Model) -> StateLayout {
    let Ok(sel) = crate::linearize::selection_at_start(model) else { return StateLayout::default() };
    let s: Vec<String> = sel.states.iter().map(|x| x.name.clone()).collect();
    let w: Vec<String> = sel.velocities.iter().map(|x| x.name()).collect();
    let w_of = w.iter().map(|n| s.iter().position(|sn| format!("der({sn})") == *n)).collect();
    let s_units = sel.states.iter().map(|x| x.unit()).collect();
    let w_units = sel.velocities.iter().map(|x| x.unit()).collect();
    let s_about = sel.states.iter().map(|x| x.description()).collect();
    let w_about = sel.velocities.iter().map(|x| x.description()).collect();
    StateLayout { s, w, w_of, s_units, w_units, s_about, w_about }
}
