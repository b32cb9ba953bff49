//! The FMI 2.0 Co-Simulation state machine (4.2.4 State Machine of Calling Sequence from
//! Master to Slave): one const table of the states in which each function may be called,
//! and one guard every export runs first.

/// A state of a Co-Simulation instance; each is one bit so a set of states is a mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// instantiated: after fmi2Instantiate or fmi2Reset, before
    /// fmi2EnterInitializationMode.
    Instantiated = 1,
    /// initializationMode: between fmi2EnterInitializationMode and
    /// fmi2ExitInitializationMode.
    InitializationMode = 2,
    /// slaveInitialized: after fmi2ExitInitializationMode and every successful fmi2DoStep.
    StepComplete = 4,
    /// fmi2DoStep returned fmi2Discard.
    StepFailed = 8,
    /// stepCanceled: never entered by this FMU (fmi2DoStep is synchronous, fmi2CancelStep
    /// is refused).
    StepCanceled = 16,
    /// terminated: after fmi2Terminate.
    Terminated = 32,
    /// error: after a panic in a function that cannot have left the engine half-updated.
    Error = 64,
    /// fatal: after a panic in a function that may have left the engine half-updated;
    /// only fmi2FreeInstance is allowed.
    Fatal = 128,
}

impl State {
    /// The state's bit.
    pub const fn bit(self) -> u32 {
        self as u32
    }

    /// Every state, for decoding a serialized state.
    pub const ALL: [State; 8] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::StepCanceled,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];
}

const INST: u32 = State::Instantiated.bit();
const INIT: u32 = State::InitializationMode.bit();
const DONE: u32 = State::StepComplete.bit();
const FAIL: u32 = State::StepFailed.bit();
const CANC: u32 = State::StepCanceled.bit();
const TERM: u32 = State::Terminated.bit();
const ERR: u32 = State::Error.bit();
const FATAL: u32 = State::Fatal.bit();
/// Every state but Fatal.
const ALIVE: u32 = INST | INIT | DONE | FAIL | CANC | TERM | ERR;
/// States with values to read.
const READABLE: u32 = INIT | DONE | FAIL | CANC | TERM | ERR;

/// An FMI function that takes an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// `fmi2SetDebugLogging`.
    SetDebugLogging,
    /// `fmi2FreeInstance`.
    FreeInstance,
    /// `fmi2SetupExperiment`.
    SetupExperiment,
    /// `fmi2EnterInitializationMode`.
    EnterInitializationMode,
    /// `fmi2ExitInitializationMode`.
    ExitInitializationMode,
    /// `fmi2Terminate`.
    Terminate,
    /// `fmi2Reset`.
    Reset,
    /// `fmi2GetReal`.
    GetReal,
    /// `fmi2GetInteger`.
    GetInteger,
    /// `fmi2GetBoolean`.
    GetBoolean,
    /// `fmi2GetString`.
    GetString,
    /// `fmi2SetReal`.
    SetReal,
    /// `fmi2SetInteger`.
    SetInteger,
    /// `fmi2SetBoolean`.
    SetBoolean,
    /// `fmi2SetString`.
    SetString,
    /// `fmi2GetFMUstate`.
    GetFmuState,
    /// `fmi2SetFMUstate`.
    SetFmuState,
    /// `fmi2FreeFMUstate`.
    FreeFmuState,
    /// `fmi2SerializedFMUstateSize`.
    SerializedFmuStateSize,
    /// `fmi2SerializeFMUstate`.
    SerializeFmuState,
    /// `fmi2DeSerializeFMUstate`.
    DeSerializeFmuState,
    /// `fmi2GetDirectionalDerivative`.
    GetDirectionalDerivative,
    /// `fmi2SetRealInputDerivatives`.
    SetRealInputDerivatives,
    /// `fmi2GetRealOutputDerivatives`.
    GetRealOutputDerivatives,
    /// `fmi2DoStep`.
    DoStep,
    /// `fmi2CancelStep`.
    CancelStep,
    /// `fmi2GetStatus`.
    GetStatus,
    /// `fmi2GetRealStatus`.
    GetRealStatus,
    /// `fmi2GetIntegerStatus`.
    GetIntegerStatus,
    /// `fmi2GetBooleanStatus`.
    GetBooleanStatus,
    /// `fmi2GetStringStatus`.
    GetStringStatus,
}

/// One row of the table.
pub struct Rule {
    /// The function of this row; rows are in `Func` order, so `RULES[f as usize].func == f`.
    pub func: Func,
    /// The C name, used in every message.
    pub name: &'static str,
    /// States in which the call is legal.
    pub allowed: u32,
    /// A panic inside may have left the engine half-updated: the instance turns Fatal.
    pub panic_is_fatal: bool,
}

const fn rule(func: Func, name: &'static str, allowed: u32, panic_is_fatal: bool) -> Rule {
    Rule { func, name, allowed, panic_is_fatal }
}

/// Allowed states per function, in `Func` order (masks follow the FMI 2.0 CS state
/// machine as modelica/Reference-FMUs encodes it).
pub const RULES: [Rule; 31] = [
    rule(Func::SetDebugLogging, "fmi2SetDebugLogging", ALIVE, false),
    rule(Func::FreeInstance, "fmi2FreeInstance", ALIVE | FATAL, false),
    rule(Func::SetupExperiment, "fmi2SetupExperiment", INST, false),
    rule(Func::EnterInitializationMode, "fmi2EnterInitializationMode", INST, false),
    rule(Func::ExitInitializationMode, "fmi2ExitInitializationMode", INIT, true),
    rule(Func::Terminate, "fmi2Terminate", DONE | FAIL | ERR, false),
    rule(Func::Reset, "fmi2Reset", ALIVE, true),
    rule(Func::GetReal, "fmi2GetReal", READABLE, false),
    rule(Func::GetInteger, "fmi2GetInteger", READABLE, false),
    rule(Func::GetBoolean, "fmi2GetBoolean", READABLE, false),
    rule(Func::GetString, "fmi2GetString", READABLE, false),
    rule(Func::SetReal, "fmi2SetReal", INST | INIT | DONE, true),
    rule(Func::SetInteger, "fmi2SetInteger", INST | INIT | DONE, false),
    rule(Func::SetBoolean, "fmi2SetBoolean", INST | INIT | DONE, false),
    rule(Func::SetString, "fmi2SetString", INST | INIT | DONE, false),
    rule(Func::GetFmuState, "fmi2GetFMUstate", ALIVE, false),
    rule(Func::SetFmuState, "fmi2SetFMUstate", ALIVE, true),
    rule(Func::FreeFmuState, "fmi2FreeFMUstate", ALIVE, false),
    rule(Func::SerializedFmuStateSize, "fmi2SerializedFMUstateSize", ALIVE, false),
    rule(Func::SerializeFmuState, "fmi2SerializeFMUstate", ALIVE, false),
    rule(Func::DeSerializeFmuState, "fmi2DeSerializeFMUstate", ALIVE, false),
    rule(Func::GetDirectionalDerivative, "fmi2GetDirectionalDerivative", READABLE, false),
    rule(Func::SetRealInputDerivatives, "fmi2SetRealInputDerivatives", INST | INIT | DONE, true),
    rule(Func::GetRealOutputDerivatives, "fmi2GetRealOutputDerivatives", DONE | FAIL | CANC | TERM | ERR, false),
    rule(Func::DoStep, "fmi2DoStep", DONE, true),
    rule(Func::CancelStep, "fmi2CancelStep", DONE | FAIL | CANC, false),
    rule(Func::GetStatus, "fmi2GetStatus", DONE | FAIL | CANC | TERM, false),
    rule(Func::GetRealStatus, "fmi2GetRealStatus", DONE | FAIL | CANC | TERM, false),
    rule(Func::GetIntegerStatus, "fmi2GetIntegerStatus", DONE | FAIL | CANC | TERM, false),
    rule(Func::GetBooleanStatus, "fmi2GetBooleanStatus", DONE | FAIL | CANC | TERM, false),
    rule(Func::GetStringStatus, "fmi2GetStringStatus", DONE | FAIL | CANC | TERM, false),
];

impl Func {
    /// This function's row of [`RULES`].
    pub fn rule(self) -> &'static Rule {
        &RULES[self as usize]
    }

    /// The C name.
    pub fn name(self) -> &'static str {
        self.rule().name
    }
}

/// The guard: `Err("fmi2X: not allowed in state Y")` when `func` is illegal in `state`.
pub fn check(state: State, func: Func) -> Result<(), String> {
    let r = func.rule();
    if r.allowed & state.bit() != 0 { Ok(()) } else { Err(format!("{}: not allowed in state {state:?}", r.name)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_sits_at_its_function_index() {
        for (k, r) in RULES.iter().enumerate() {
            assert_eq!(r.func as usize, k, "{}", r.name);
        }
    }

    #[test]
    fn do_step_is_legal_only_after_initialization() {
        assert!(check(State::StepComplete, Func::DoStep).is_ok());
        let e = check(State::Instantiated, Func::DoStep).unwrap_err();
        assert_eq!(e, "fmi2DoStep: not allowed in state Instantiated");
    }
}
