//! One FMU instance: the model, the values the host set, the experiment, and the engine
//! once initialized. It knows the FMI rules for values (who may set what, when); the
//! exports only translate pointers and statuses.

use super::config::Config;
use super::fmu_state::FmuState;
use super::interface::{Exchange, Interface};
use super::logger::Logger;
use super::state_handles::StateHandles;
use super::state_machine::State;
use super::types::Status;
use super::variables::{Standard, Target, Variable, variables};
use crate::dae::StartValues;
use crate::dae::{DEFAULT_MAX_STEPS, SimOptions, SimState, Simulator};
use crate::linearize::{
    Linearization, Seeded, Selection, StateLayout, StateTarget, linearize, selection_by_name, start_values,
    state_values,
};
use crate::model::Model;

/// The engine, with the configuration it was built from.
pub struct Built {
    /// The engine.
    pub sim: Simulator,
    /// The parameter values it was built with.
    pub params: Vec<f64>,
    /// The tolerance it was built with.
    pub tol: f64,
    /// The linearization states of modelDescription.xml (the instance's [`StateLayout`]),
    /// rebuilt on this engine's system.
    pub sel: Result<Selection, String>,
    /// The last linearization and the engine state it belongs to (cache).
    pub lin: Option<(SimState, Linearization)>,
    /// Eq. 34 factored at the last point FMI 3 derivatives were asked at, and that
    /// point's engine state (cache).
    pub seeded: Option<(SimState, Seeded)>,
}

/// Outcome of fmi2DoStep once its arguments are valid.
pub enum Step {
    /// The step reached its end.
    Done,
    /// The engine stopped early (fmi2Discard), with its message.
    Failed(String),
}

/// An FMU instance (the fmi2Component).
pub struct Instance {
    /// The host's logger and the logging settings.
    pub log: Logger,
    /// Where the instance is in the FMI state machine.
    pub state: State,
    /// GUID of the model text: identifies whose FMU states this instance accepts.
    pub guid: String,
    /// The FMI version the host called fmiXInstantiate… of.
    pub standard: Standard,
    /// FMI 3: the host uses Event Mode (`eventModeUsed`): initialization ends in it.
    pub event_mode: bool,
    /// Co-Simulation (the engine integrates) or Model Exchange (the host does).
    pub interface: Interface,
    /// Model Exchange: the time and states the host set, and whether the engine is there.
    pub exchange: Exchange,
    base: Model,
    /// The linearization states the FMU was packed with.
    pub(super) layout: StateLayout,
    pub(super) vars: Vec<Variable>,
    /// The values and experiment the host chose.
    pub config: Config,
    /// The engine, once built.
    pub built: Option<Built>,
    /// Values changed since the engine was built (rebuild before use).
    pub dirty: bool,
    /// fmi2LastSuccessfulTime.
    pub last_time: f64,
    /// The FMU states handed to the host and not yet freed.
    pub states: StateHandles,
    /// Start values the host set on states before initialization ended: (value reference,
    /// value), each state once, in the order first set; met exactly by initialization.
    pub starts: Vec<(u32, f64)>,
    /// The outputs' values while fmi2GetReal reads them (kept: nothing is allocated).
    outputs: Vec<f64>,
}

impl Instance {
    /// A fresh instance (state Instantiated) of a parsed model whose FMU exposes the
    /// linearization states `layout` (read from its resources, see
    /// [`super::resources::read_layout`]).
    pub fn new(base: Model, guid: String, layout: StateLayout, log: Logger, standard: Standard) -> Instance {
        let vars = variables(&base, &layout, standard);
        let config = Self::default_config(&base);
        let last_time = config.start;
        Instance {
            log,
            state: State::Instantiated,
            guid,
            standard,
            event_mode: false,
            interface: Interface::CoSimulation,
            exchange: Exchange::default(),
            base,
            layout,
            vars,
            config,
            built: None,
            dirty: true,
            last_time,
            states: StateHandles::default(),
            starts: Vec::new(),
            outputs: Vec::new(),
        }
    }

    fn default_config(m: &Model) -> Config {
        Config {
            params: m.param_values(),
            inputs: m.inputs.iter().map(|i| i.start.value).collect(),
            slopes: vec![0.0; m.inputs.len()],
            tol: m.experiment.tolerance.unwrap_or(SimOptions::default().tol),
            start: m.experiment.start.unwrap_or(0.0),
            stop: None,
            max_steps: DEFAULT_MAX_STEPS,
        }
    }

    /// fmi2Reset: back to the state after fmi2Instantiate (logging settings kept).
    pub fn reset(&mut self) {
        self.config = Self::default_config(&self.base);
        self.starts.clear();
        self.exchange = Exchange::default();
        self.built = None;
        self.dirty = true;
        self.last_time = self.config.start;
        self.state = State::Instantiated;
    }

    /// fmi2SetupExperiment (tolerance None: the model's).
    pub fn setup(&mut self, tol: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), String> {
        if let Some(t) = tol {
            if !(t.is_finite() && t > 0.0) {
                return Err(format!("tolerance {t} is not a positive number"));
            }
            self.config.tol = t;
        }
        if !start.is_finite() {
            return Err(format!("startTime {start} is not finite"));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s >= start)
        {
            return Err(format!("stopTime {s} is not a finite time after startTime {start}"));
        }
        self.config.start = start;
        self.config.stop = stop;
        self.last_time = start;
        self.dirty = true;
        Ok(())
    }

    /// The variable of value reference `vr`.
    pub fn var(&self, vr: u32) -> Result<&Variable, String> {
        self.vars
            .get(vr as usize)
            .filter(|v| v.value_reference == vr)
            .ok_or_else(|| format!("unknown value reference {vr}"))
    }

    /// The engine for the current values, built (assembled at the start time) when it is
    /// missing or the values changed before initialization ended.
    pub fn simulator(&mut self) -> Result<&mut Simulator, String> {
        if self.built.is_none() || self.dirty {
            let built = self.build(&self.config.clone())?;
            for w in built.sim.warnings() {
                self.log.log(Status::Warning, &format!("initialization: {w}"));
            }
            self.built = Some(built);
            self.dirty = false;
        }
        Ok(&mut self.built.as_mut().expect("just built").sim)
    }

    /// Build an engine for `cfg`: parameters re-evaluated, inputs and slopes applied.
    pub fn build(&self, cfg: &Config) -> Result<Built, String> {
        let mut model = if bits(&cfg.params) == bits(&self.base.param_values()) {
            self.base.clone()
        } else {
            self.base.with_params(&cfg.params)?
        };
        for (i, &v) in model.inputs.iter_mut().zip(&cfg.inputs) {
            i.start.value = v;
        }
        let start = self.start_values(&model)?;
        let opts = SimOptions { tol: cfg.tol, max_step: None, max_steps: cfg.max_steps };
        let mut sim = Simulator::with_start(&model, opts, cfg.start, &start)
            .map_err(|e| format!("the model cannot be initialized: {e}"))?;
        for (k, &s) in cfg.slopes.iter().enumerate() {
            if s != 0.0 {
                sim.set_input_derivative(k, s);
            }
        }
        let sel = selection_by_name(sim.system(), &self.layout);
        Ok(Built { sim, params: cfg.params.clone(), tol: cfg.tol, sel, lin: None, seeded: None })
    }

    /// The start values set on states, as conditions on the system of `model`.
    fn start_values(&self, model: &Model) -> Result<StartValues, String> {
        if self.starts.is_empty() {
            return Ok(StartValues::default());
        }
        let mut set = Vec::with_capacity(self.starts.len());
        for &(vr, v) in &self.starts {
            let var = self.var(vr)?;
            set.push((var.name.clone(), self.state_target(var)?, v));
        }
        start_values(model, &self.layout, &set)
    }

    /// The state a start value on `var` sets (Err: it is not a settable state).
    fn state_target(&self, var: &Variable) -> Result<StateTarget, String> {
        match var.target {
            Target::State(k) => Ok(StateTarget::Position(k)),
            Target::StateDerivative(k) => self.layout.velocity_of_state(k).map(StateTarget::Velocity).ok_or_else(|| {
                format!(
                    "'{}' is a derivative, not a state (the model's non-holonomic constraints fix it): set its velocity states",
                    var.name
                )
            }),
            Target::Velocity(j) => Ok(StateTarget::Velocity(j)),
            Target::Diff(k) => Ok(StateTarget::Differential(k)),
            _ => Err(format!("'{}' is not a state", var.name)),
        }
    }

    /// The variable of value reference `vr`, which must be of FMI type Integer (`integer`)
    /// or Real.
    fn typed_var(&self, vr: u32, integer: bool) -> Result<&Variable, String> {
        let v = self.var(vr)?;
        match (v.target.is_integer(), integer) {
            (true, false) => {
                Err(format!("'{}' (vr {vr}) is an Integer variable (use fmi2GetInteger/fmi2SetInteger)", v.name))
            }
            (false, true) => Err(format!("'{}' (vr {vr}) is a Real variable, not an Integer", v.name)),
            _ => Ok(v),
        }
    }

    /// fmi2GetInteger: values of `vrs` (only `solver.maxSteps`) into `out`.
    pub fn get_integers(&self, vrs: &[u32], out: &mut [i32]) -> Result<(), String> {
        for (&vr, o) in vrs.iter().zip(out.iter_mut()) {
            match self.typed_var(vr, true)?.target {
                Target::MaxSteps => *o = i32::try_from(self.config.max_steps).unwrap_or(i32::MAX),
                t => unreachable!("{t:?} is not an Integer variable"),
            }
        }
        Ok(())
    }

    /// fmi2SetInteger: `solver.maxSteps` (at least 1) at any time the state machine allows
    /// (it is tunable: a change after initialization holds from the next fmi2DoStep). All
    /// checked first, then all applied.
    pub fn set_integers(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), String> {
        for (&vr, &v) in vrs.iter().zip(values) {
            let var = self.typed_var(vr, true)?;
            if v < 1 {
                return Err(format!(
                    "value {v} for '{}' (vr {vr}) is not a positive number of integrator steps",
                    var.name
                ));
            }
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            match self.typed_var(vr, true)?.target {
                Target::MaxSteps => {
                    let n = usize::try_from(v).expect("checked positive");
                    self.config.max_steps = n;
                    if let Some(b) = self.built.as_mut() {
                        b.sim.set_max_steps(n);
                    }
                }
                t => unreachable!("{t:?} is not an Integer variable"),
            }
        }
        Ok(())
    }

    /// fmi2GetReal: values of `vrs` into `out`.
    pub fn get_reals(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), String> {
        for &vr in vrs {
            self.typed_var(vr, false)?;
        }
        self.place_if_exchange()?;
        let mut have_outputs = false;
        let mut states: Option<crate::linearize::StateValues> = None;
        for (&vr, o) in vrs.iter().zip(out.iter_mut()) {
            let t = self.typed_var(vr, false)?.target;
            *o = match t {
                Target::Parameter(k) => self.config.params[k],
                Target::Input(k) if self.initialized() => self.built.as_ref().expect("initialized").sim.input(k),
                Target::Input(k) => self.config.inputs[k],
                Target::Output(k) => {
                    if !have_outputs {
                        let mut values = std::mem::take(&mut self.outputs);
                        let sim = self.simulator()?;
                        sim.outputs_into(&mut values).map_err(|e| format!("outputs cannot be evaluated: {e}"))?;
                        self.outputs = values;
                        have_outputs = true;
                    }
                    self.outputs[k]
                }
                Target::State(k) | Target::StateDerivative(k) | Target::Velocity(k) | Target::VelocityDerivative(k) => {
                    if states.is_none() {
                        self.simulator()?;
                        let b = self.built.as_mut().expect("built");
                        let sel = b.sel.as_ref().map_err(|e| e.clone())?;
                        states = Some(
                            state_values(&mut b.sim, sel).map_err(|e| format!("states cannot be evaluated: {e}"))?,
                        );
                    }
                    let v = states.as_ref().expect("evaluated");
                    match t {
                        Target::State(_) => v.s[k],
                        Target::StateDerivative(_) => v.sd[k],
                        Target::Velocity(_) => v.w[k],
                        _ => v.wd[k],
                    }
                }
                Target::Diff(k) | Target::DiffDerivative(k) | Target::UserVariable(k) => {
                    let sim = self.simulator()?;
                    let nx = sim.system().nx;
                    let z = sim.user_values();
                    match t {
                        Target::Diff(_) => z[k],
                        Target::DiffDerivative(_) => z[nx + k],
                        _ => z[2 * nx + k],
                    }
                }
                Target::Time => self.built.as_ref().filter(|_| !self.dirty).map_or(self.config.start, |b| b.sim.time()),
                Target::MaxSteps => unreachable!("refused above: an Integer variable"),
            };
        }
        self.all_finite("fmi2GetReal", vrs, out)
    }

    /// Err naming the first value of `out` (for `vrs`) that is not finite: a host must
    /// never read NaN or an infinity with fmi2OK (the motion or the parameters overflowed).
    fn all_finite(&self, what: &str, vrs: &[u32], out: &[f64]) -> Result<(), String> {
        match vrs.iter().zip(out).find(|(_, v)| !v.is_finite()) {
            None => Ok(()),
            Some((&vr, v)) => {
                let name = self.var(vr).map(|x| x.name.as_str()).unwrap_or("?");
                Err(format!(
                    "{what} of '{name}' (vr {vr}) is {v} at t = {}: the motion or the values set overflow",
                    self.last_time
                ))
            }
        }
    }

    /// Whether the engine runs (initialization has ended).
    fn initialized(&self) -> bool {
        !matches!(self.state, State::Instantiated | State::InitializationMode) && self.built.is_some()
    }

    /// fmi2SetReal: all checked first, then all applied (a refused call changes nothing).
    pub fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), String> {
        let mut targets = Vec::with_capacity(vrs.len());
        for (&vr, &v) in vrs.iter().zip(values) {
            let var = self.typed_var(vr, false)?;
            if !v.is_finite() {
                return Err(format!("value {v} for '{}' (vr {vr}) is not finite", var.name));
            }
            match var.target {
                Target::Output(_) => return Err(format!("'{}' (vr {vr}) is an output and cannot be set", var.name)),
                Target::State(_) | Target::StateDerivative(_) | Target::Velocity(_) | Target::Diff(_)
                    if self.initialized() =>
                {
                    return Err(format!(
                        "state '{}' (vr {vr}) cannot be set after initialization (state {:?}): its start value is \
                         set before fmi2ExitInitializationMode; later states follow the motion (fmi2SetFMUstate \
                         restores a saved one)",
                        var.name, self.state
                    ));
                }
                Target::State(_) | Target::StateDerivative(_) | Target::Velocity(_) | Target::Diff(_) => {
                    self.state_target(var).map_err(|e| format!("{e} (vr {vr}) and cannot be set"))?;
                    targets.push((var.target, v));
                }
                Target::VelocityDerivative(_) | Target::DiffDerivative(_) | Target::UserVariable(_) | Target::Time => {
                    return Err(format!("'{}' (vr {vr}) is computed by the engine and cannot be set", var.name));
                }
                Target::Parameter(_) if self.initialized() => {
                    return Err(format!(
                        "parameter '{}' (vr {vr}) cannot be set after initialization (state {:?})",
                        var.name, self.state
                    ));
                }
                t => targets.push((t, v)),
            }
        }
        let mut moved = false;
        for (&vr, (t, v)) in vrs.iter().zip(targets) {
            match t {
                Target::State(_) | Target::StateDerivative(_) | Target::Velocity(_) | Target::Diff(_) => {
                    match self.starts.iter_mut().find(|s| s.0 == vr) {
                        Some(s) => s.1 = v,
                        None => self.starts.push((vr, v)),
                    }
                    self.dirty = true;
                }
                Target::Parameter(k) => {
                    self.config.params[k] = v;
                    self.dirty = true;
                }
                Target::Input(k) => {
                    self.config.inputs[k] = v;
                    self.config.slopes[k] = 0.0;
                    if self.initialized() {
                        let sim = &mut self.built.as_mut().expect("initialized").sim;
                        // Setting the value an input already has (fmpy sets every input at
                        // every step) leaves the engine state, and so the trajectory, alone.
                        if sim.inputs()[k] != v || sim.input_slope(k) != 0.0 {
                            sim.set_input(k, v);
                            moved = true;
                        }
                    } else {
                        self.dirty = true;
                    }
                }
                _ => unreachable!("refused above"),
            }
        }
        if moved && self.interface == Interface::ModelExchange {
            // Model Exchange: the point is solved anew, with the new inputs, when next read.
            self.exchange.placed = false;
        } else if moved {
            let sim = &mut self.built.as_mut().expect("initialized").sim;
            sim.resolve_user_unknowns().map_err(|e| format!("the user variables cannot follow the new inputs: {e}"))?;
        }
        Ok(())
    }

    /// The linearization at the current point, computed once per engine state (cached
    /// until the state, an input or a parameter changes).
    fn linearization(&mut self) -> Result<&Linearization, String> {
        self.simulator()?;
        let b = self.built.as_mut().expect("built");
        let key = b.sim.snapshot();
        if b.lin.as_ref().is_none_or(|(k, _)| *k != key) {
            let sel = b.sel.as_ref().map_err(|e| format!("no linearization states: {e}"))?;
            let lin = linearize(&mut b.sim, sel, 2).map_err(|e| e.to_string())?;
            b.lin = Some((key, lin));
        }
        Ok(&b.lin.as_ref().expect("cached").1)
    }

    /// fmi2GetDirectionalDerivative: Δunknown = (∂unknown/∂known) Δknown with unknowns
    /// state derivatives and outputs, knowns states and inputs (rows and columns of
    /// A, B, C, D at the current point).
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        let (rows, cols) = self.positions(unknowns, knowns)?;
        let ns = self.state_count();
        if let Some(v) = dv.iter().find(|v| !v.is_finite()) {
            return Err(format!("seed value {v} is not finite"));
        }
        self.place_if_exchange()?;
        let lin = self.linearization()?;
        for (o, &r) in out.iter_mut().zip(&rows) {
            let mut acc = 0.0;
            for (&c, &d) in cols.iter().zip(dv) {
                acc += d * match (r < ns, c < ns) {
                    (true, true) => lin.a[(r, c)],
                    (true, false) => lin.b[(r, c - ns)],
                    (false, true) => lin.c[(r - ns, c)],
                    (false, false) => lin.d[(r - ns, c - ns)],
                };
            }
            *o = acc;
        }
        self.all_finite("the directional derivative", unknowns, out)
    }

    /// The number of linearization states (columns of A).
    pub(super) fn state_count(&self) -> usize {
        self.vars.iter().filter(|v| v.known.is_some()).count()
    }

    /// The rows (state derivatives, then outputs) of the unknowns `unknowns` and the
    /// columns (states S, W, X, then inputs) of the knowns `knowns` of [A B; C D].
    fn positions(&self, unknowns: &[u32], knowns: &[u32]) -> Result<(Vec<usize>, Vec<usize>), String> {
        let ns = self.state_count();
        let mut cols = Vec::with_capacity(knowns.len());
        for &vr in knowns {
            let v = self.var(vr)?;
            let c = match v.target {
                Target::Input(i) => Some(ns + i),
                _ => v.known,
            };
            cols.push(c.ok_or_else(|| format!("known '{}' (vr {vr}) is neither a state nor an input", v.name))?);
        }
        let mut rows = Vec::with_capacity(unknowns.len());
        for &vr in unknowns {
            let v = self.var(vr)?;
            let r = match v.target {
                Target::Output(o) => Some(ns + o),
                _ => v.unknown,
            };
            rows.push(r.ok_or_else(|| {
                format!("unknown '{}' (vr {vr}) is neither a state derivative nor an output", v.name)
            })?);
        }
        Ok((rows, cols))
    }

    /// Eq. 34 factored at the current point, once per engine state (cached until the
    /// state, an input or a parameter changes).
    fn seeded(&mut self) -> Result<&mut Seeded, String> {
        self.simulator()?;
        let b = self.built.as_mut().expect("built");
        let key = b.sim.snapshot();
        if b.seeded.as_ref().is_none_or(|(k, _)| *k != key) {
            let sel = b.sel.as_ref().map_err(|e| format!("no linearization states: {e}"))?;
            let s = Seeded::at(&mut b.sim, sel).map_err(|e| e.to_string())?;
            b.seeded = Some((key, s));
        }
        Ok(&mut b.seeded.as_mut().expect("cached").1)
    }

    /// FMI 3 derivatives at the current point, each one solve of Eq. 34 per column kind
    /// ([`Seeded`]): `adjoint` false: sensitivity = J·seed (fmi3GetDirectionalDerivative,
    /// a seed per known, a sensitivity per unknown); true: sensitivityᵀ = seedᵀ·J
    /// (fmi3GetAdjointDerivative, a seed per unknown, a sensitivity per known); J the
    /// rows `unknowns` and columns `knowns` of [A B; C D].
    pub fn seeded_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
        adjoint: bool,
    ) -> Result<(), String> {
        let (rows, cols) = self.positions(unknowns, knowns)?;
        let (seed_at, out_at) = if adjoint { (&rows, &cols) } else { (&cols, &rows) };
        if seed.len() != seed_at.len() || out.len() != out_at.len() {
            return Err(format!(
                "nSeed = {} and nSensitivity = {} must be {} and {} (the numbers of {})",
                seed.len(),
                out.len(),
                seed_at.len(),
                out_at.len(),
                if adjoint { "unknowns and knowns" } else { "knowns and unknowns" }
            ));
        }
        if let Some(v) = seed.iter().find(|v| !v.is_finite()) {
            return Err(format!("seed value {v} is not finite"));
        }
        let s = self.seeded()?;
        let mut full = vec![0.0; if adjoint { s.unknowns() } else { s.knowns() }];
        for (&p, &v) in seed_at.iter().zip(seed) {
            full[p] += v;
        }
        let product = if adjoint { s.adjoint(&full) } else { s.directional(&full) }.map_err(|e| e.to_string())?;
        for (o, &p) in out.iter_mut().zip(out_at.iter()) {
            *o = product[p];
        }
        let named = if adjoint { knowns } else { unknowns };
        self.all_finite("the derivative", named, out)
    }

    /// fmi2SetRealInputDerivatives (order 1 only: inputs change linearly over a step).
    pub fn set_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Result<(), String> {
        if self.interface == Interface::ModelExchange {
            return Err("input derivatives are a Co-Simulation function (in Model Exchange the host integrates)".into());
        }
        let mut todo = Vec::with_capacity(vrs.len());
        for ((&vr, &order), &v) in vrs.iter().zip(orders).zip(values) {
            let var = self.var(vr)?;
            let Target::Input(k) = var.target else {
                return Err(format!("'{}' (vr {vr}) is not an input", var.name));
            };
            if order != 1 {
                return Err(format!(
                    "derivative order {order} for '{}' (vr {vr}): only order 1 is supported",
                    var.name
                ));
            }
            if !v.is_finite() {
                return Err(format!("derivative {v} for '{}' (vr {vr}) is not finite", var.name));
            }
            todo.push((k, v));
        }
        for (k, v) in todo {
            self.config.slopes[k] = v;
            if self.initialized() {
                self.built.as_mut().expect("initialized").sim.set_input_derivative(k, v);
            } else {
                self.dirty = true;
            }
        }
        Ok(())
    }

    /// fmi2ExitInitializationMode: build the engine with the values set (parameters
    /// re-evaluated); on failure the instance stays in initialization mode.
    pub fn exit_initialization(&mut self) -> Result<(), String> {
        let t = self.simulator()?.time();
        self.last_time = t;
        if self.interface == Interface::ModelExchange {
            self.start_exchange()?;
            self.state = State::EventMode;
        } else {
            self.state = State::StepComplete;
        }
        Ok(())
    }

    /// fmi3EnterStepMode (Co-Simulation instances only: a Model Exchange one in Event Mode
    /// goes on to Continuous-Time Mode).
    pub fn enter_step_mode(&mut self) -> Result<(), String> {
        if self.interface == Interface::ModelExchange {
            return Err("a Co-Simulation function, and this is a Model Exchange instance".into());
        }
        self.state = State::StepComplete;
        Ok(())
    }

    /// fmi2DoStep from `t` over `h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Step, String> {
        if !(h.is_finite() && h >= 0.0) {
            return Err(format!("communicationStepSize {h} is not a non-negative number"));
        }
        let stop = self.config.stop;
        let sim = &mut self.built.as_mut().ok_or("no engine (not initialized)")?.sim;
        let now = sim.time();
        if !t.is_finite() || (t - now).abs() > 1e-9 * now.abs().max(1.0) {
            return Err(format!("currentCommunicationPoint {t} is not the current time {now}"));
        }
        let target = t + h;
        if let Some(s) = stop
            && target > s + 1e-9 * s.abs().max(1.0)
        {
            return Err(format!("step to {target} goes beyond stopTime {s}"));
        }
        match sim.advance(target) {
            Ok(()) => {
                self.last_time = sim.time();
                Ok(Step::Done)
            }
            Err(e) => {
                self.last_time = sim.time();
                self.state = State::StepFailed;
                Ok(Step::Failed(format!("step from {t} to {target} stopped at {}: {e}", self.last_time)))
            }
        }
    }

    /// fmi2GetRealOutputDerivatives (order 1).
    pub fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32], out: &mut [f64]) -> Result<(), String> {
        let mut ks = Vec::with_capacity(vrs.len());
        for (&vr, &order) in vrs.iter().zip(orders) {
            let var = self.var(vr)?;
            let Target::Output(k) = var.target else {
                return Err(format!("'{}' (vr {vr}) is not an output", var.name));
            };
            if order != 1 {
                return Err(format!(
                    "derivative order {order} for '{}' (vr {vr}): only order 1 is supported",
                    var.name
                ));
            }
            ks.push(k);
        }
        if ks.is_empty() {
            return Ok(());
        }
        let d = self.simulator()?.output_derivatives().map_err(|e| e.to_string())?;
        for (o, k) in out.iter_mut().zip(ks) {
            *o = d[k];
        }
        self.all_finite("the derivative", vrs, out)
    }

    /// Log a message through the host's logger.
    pub fn log(&mut self, status: Status, msg: &str) {
        self.log.log(status, msg);
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Saved FMU states (2.1.8).
impl Instance {
    /// fmi2GetFMUstate: the complete state. A state taken after fmi2DoStep returned fmi2Discard (StepFailed)
    /// holds the engine at fmi2LastSuccessfulTime, the last accepted integrator step, which
    /// is a valid communication point: it is recorded as StepComplete, so that restoring
    /// it lets the host continue from the time reached (e.g. with a larger
    /// `solver.maxSteps` or a shorter step).
    pub fn save_state(&self) -> FmuState {
        FmuState {
            guid: self.guid.clone(),
            state: if self.state == State::StepFailed { State::StepComplete } else { self.state },
            config: self.config.clone(),
            last_time: self.last_time,
            sim: if self.dirty { None } else { self.built.as_ref().map(|b| b.sim.snapshot()) },
            exchange: (self.interface == Interface::ModelExchange).then(|| self.exchange.clone()),
        }
    }

    /// fmi2SetFMUstate: `saved` into this instance (it may have been saved by another
    /// instance of the same model).
    pub fn restore_state(&mut self, saved: &FmuState) -> Result<(), String> {
        if saved.guid != self.guid {
            return Err(format!("the state belongs to FMU {}, not to this FMU {}", saved.guid, self.guid));
        }
        let saved_me = saved.exchange.is_some();
        if saved_me != (self.interface == Interface::ModelExchange) {
            let name = |me: bool| if me { "Model Exchange" } else { "Co-Simulation" };
            return Err(format!(
                "the state was saved by a {} instance; this one is {}",
                name(saved_me),
                name(!saved_me)
            ));
        }
        match &saved.sim {
            None => {
                self.built = None;
                self.dirty = true;
            }
            Some(s) => {
                let reusable = self.built.as_ref().is_some_and(|b| {
                    !self.dirty
                        && b.tol.to_bits() == saved.config.tol.to_bits()
                        && same(&b.params, &saved.config.params)
                });
                if !reusable {
                    self.built = Some(self.build(&saved.config)?);
                }
                let sim = &mut self.built.as_mut().expect("built").sim;
                sim.restore(s).map_err(|e| e.to_string())?;
                sim.set_max_steps(saved.config.max_steps);
                self.dirty = false;
            }
        }
        self.config = saved.config.clone();
        self.last_time = saved.last_time;
        self.state = saved.state;
        self.exchange = saved.exchange.clone().unwrap_or_default();
        Ok(())
    }
}

/// Bitwise equality of two value lists.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}
