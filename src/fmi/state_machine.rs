//! The state machines of FMI 2.0 Co-Simulation (4.2.4 State Machine of Calling Sequence
//! from Master to Slave) and Model Exchange (3.2.3) and FMI 3.0 Model Exchange (3.3) and
//! Co-Simulation (4.3): each column joins both machines of its version (their states
//! differ after initialization: a Model Exchange instance never reaches StepComplete, a
//! Co-Simulation one never Continuous-Time Mode; FMI 3 Event Mode, which both know, is
//! told apart by the instance's interface where a function belongs to one of them). One const table of
//! each function's C names and the states in which it may be called, a column per FMI
//! version (where the two differ, the table says so), and one guard every export runs
//! first.

use super::variables::Standard;

/// A state of an instance; each is one bit so a set of states is a mask.
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
    /// Event Mode: FMI 3 Co-Simulation (after fmi3ExitInitializationMode when the host
    /// uses event mode, or fmi3EnterEventMode) and Model Exchange of both versions (after
    /// ExitInitializationMode, or EnterEventMode): nothing happens there, the model has
    /// no events.
    EventMode = 256,
    /// Model Exchange Continuous-Time Mode (FMI 2 and 3): the host sets time and states
    /// and reads derivatives.
    ContinuousTimeMode = 512,
}

impl State {
    /// The state's bit.
    pub const fn bit(self) -> u32 {
        self as u32
    }

    /// Every state, for decoding a serialized state (new states go last: a state's
    /// position is its code).
    pub const ALL: [State; 10] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::StepCanceled,
        State::Terminated,
        State::Error,
        State::Fatal,
        State::EventMode,
        State::ContinuousTimeMode,
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
const EVENT: u32 = State::EventMode.bit();
const CONT: u32 = State::ContinuousTimeMode.bit();
/// Every state but Fatal.
const ALIVE: u32 = INST | INIT | DONE | FAIL | CANC | TERM | ERR | EVENT | CONT;
/// Not a function of this FMI version.
const NONE: u32 = 0;
/// States with values to read.
const READABLE: u32 = INIT | DONE | FAIL | CANC | TERM | ERR;
/// States with values to read in FMI 2 (Co-Simulation and Model Exchange).
const READABLE2: u32 = READABLE | EVENT | CONT;
/// States in which FMI 2 hosts set values (Co-Simulation and Model Exchange).
const SETTABLE2: u32 = INST | INIT | DONE | EVENT | CONT;
/// Model Exchange states in which the states and indicators can be read.
const ME_READABLE: u32 = INIT | EVENT | CONT | TERM | ERR;

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
    /// `fmi3GetAdjointDerivative`.
    GetAdjointDerivative,
    /// `fmi3EnterEventMode`.
    EnterEventMode,
    /// `fmi3EnterStepMode`.
    EnterStepMode,
    /// `fmi3UpdateDiscreteStates`.
    UpdateDiscreteStates,
    /// `fmi2NewDiscreteStates`.
    NewDiscreteStates,
    /// `fmi2EnterContinuousTimeMode`.
    EnterContinuousTimeMode,
    /// `fmi2CompletedIntegratorStep`.
    CompletedIntegratorStep,
    /// `fmi2SetTime`.
    SetTime,
    /// `fmi2SetContinuousStates`.
    SetContinuousStates,
    /// `fmi2GetDerivatives`.
    GetDerivatives,
    /// `fmi2GetEventIndicators`.
    GetEventIndicators,
    /// `fmi2GetContinuousStates`.
    GetContinuousStates,
    /// `fmi2GetNominalsOfContinuousStates`.
    GetNominalsOfContinuousStates,
    /// `fmi3GetNumberOfContinuousStates`.
    GetNumberOfContinuousStates,
    /// `fmi3GetNumberOfEventIndicators`.
    GetNumberOfEventIndicators,
    /// The FMI 3 functions of what this FMU does not have (other variable types, clocks,
    /// configuration mode, Scheduled Execution, …): refused in any state with a message naming
    /// the function.
    Unsupported,
}

/// One row of the table.
pub struct Rule {
    /// The function of this row; rows are in `Func` order, so `RULES[f as usize].func == f`.
    pub func: Func,
    /// The C name in FMI 2 ("" if none), used in every message.
    pub name2: &'static str,
    /// States in which the FMI 2 call is legal.
    pub allowed2: u32,
    /// The C name in FMI 3 ("" if none).
    pub name3: &'static str,
    /// States in which the FMI 3 call is legal.
    pub allowed3: u32,
    /// A panic inside may have left the engine half-updated: the instance turns Fatal.
    pub panic_is_fatal: bool,
}

const fn rule(
    func: Func,
    (name2, allowed2): (&'static str, u32),
    (name3, allowed3): (&'static str, u32),
    panic_is_fatal: bool,
) -> Rule {
    Rule { func, name2, allowed2, name3, allowed3, panic_is_fatal }
}

/// States with values to read in FMI 3 (Event Mode too).
const READABLE3: u32 = READABLE | EVENT | CONT;
/// States in which FMI 3 hosts set values.
const SETTABLE3: u32 = INST | INIT | DONE | EVENT;
/// States in which FMI 3 hosts set Float64 values (inputs in Continuous-Time Mode too).
const SETTABLE3_REAL: u32 = SETTABLE3 | CONT;
/// FMI 3 Model Exchange states in which the derivatives, states and indicators can be
/// read.
const ME_READABLE3: u32 = INIT | EVENT | CONT | TERM;

/// Allowed states per function, in `Func` order: FMI 2 masks follow the FMI 2.0 CS and ME
/// state machines, FMI 3 masks the FMI 3.0 CS one, as modelica/Reference-FMUs encodes them.
pub const RULES: [Rule; 47] = [
    rule(Func::SetDebugLogging, ("fmi2SetDebugLogging", ALIVE), ("fmi3SetDebugLogging", ALIVE), false),
    rule(Func::FreeInstance, ("fmi2FreeInstance", ALIVE | FATAL), ("fmi3FreeInstance", ALIVE | FATAL), false),
    rule(Func::SetupExperiment, ("fmi2SetupExperiment", INST), ("", NONE), false),
    rule(
        Func::EnterInitializationMode,
        ("fmi2EnterInitializationMode", INST),
        ("fmi3EnterInitializationMode", INST),
        false,
    ),
    rule(
        Func::ExitInitializationMode,
        ("fmi2ExitInitializationMode", INIT),
        ("fmi3ExitInitializationMode", INIT),
        true,
    ),
    rule(
        Func::Terminate,
        ("fmi2Terminate", DONE | FAIL | ERR | EVENT | CONT),
        ("fmi3Terminate", DONE | FAIL | ERR | EVENT | CONT),
        false,
    ),
    rule(Func::Reset, ("fmi2Reset", ALIVE), ("fmi3Reset", ALIVE), true),
    rule(Func::GetReal, ("fmi2GetReal", READABLE2), ("fmi3GetFloat64", READABLE3), false),
    rule(Func::GetInteger, ("fmi2GetInteger", READABLE2), ("fmi3GetInt32", READABLE3), false),
    rule(Func::GetBoolean, ("fmi2GetBoolean", READABLE2), ("fmi3GetBoolean", READABLE3), false),
    rule(Func::GetString, ("fmi2GetString", READABLE2), ("fmi3GetString", READABLE3), false),
    rule(Func::SetReal, ("fmi2SetReal", SETTABLE2), ("fmi3SetFloat64", SETTABLE3_REAL), true),
    rule(Func::SetInteger, ("fmi2SetInteger", INST | INIT | DONE | EVENT), ("fmi3SetInt32", SETTABLE3), false),
    rule(Func::SetBoolean, ("fmi2SetBoolean", INST | INIT | DONE | EVENT), ("fmi3SetBoolean", SETTABLE3), false),
    rule(Func::SetString, ("fmi2SetString", INST | INIT | DONE | EVENT), ("fmi3SetString", SETTABLE3), false),
    rule(Func::GetFmuState, ("fmi2GetFMUstate", ALIVE), ("fmi3GetFMUState", ALIVE), false),
    rule(Func::SetFmuState, ("fmi2SetFMUstate", ALIVE), ("fmi3SetFMUState", ALIVE), true),
    rule(Func::FreeFmuState, ("fmi2FreeFMUstate", ALIVE), ("fmi3FreeFMUState", ALIVE), false),
    rule(
        Func::SerializedFmuStateSize,
        ("fmi2SerializedFMUstateSize", ALIVE),
        ("fmi3SerializedFMUStateSize", ALIVE),
        false,
    ),
    rule(Func::SerializeFmuState, ("fmi2SerializeFMUstate", ALIVE), ("fmi3SerializeFMUState", ALIVE), false),
    rule(Func::DeSerializeFmuState, ("fmi2DeSerializeFMUstate", ALIVE), ("fmi3DeserializeFMUState", ALIVE), false),
    rule(
        Func::GetDirectionalDerivative,
        ("fmi2GetDirectionalDerivative", READABLE2),
        ("fmi3GetDirectionalDerivative", INIT | DONE | FAIL | TERM | EVENT | CONT),
        false,
    ),
    rule(Func::SetRealInputDerivatives, ("fmi2SetRealInputDerivatives", INST | INIT | DONE), ("", NONE), true),
    rule(
        Func::GetRealOutputDerivatives,
        ("fmi2GetRealOutputDerivatives", DONE | FAIL | CANC | TERM | ERR),
        ("fmi3GetOutputDerivatives", DONE | FAIL | TERM),
        false,
    ),
    rule(Func::DoStep, ("fmi2DoStep", DONE), ("fmi3DoStep", DONE), true),
    rule(Func::CancelStep, ("fmi2CancelStep", DONE | FAIL | CANC), ("", NONE), false),
    rule(Func::GetStatus, ("fmi2GetStatus", DONE | FAIL | CANC | TERM), ("", NONE), false),
    rule(Func::GetRealStatus, ("fmi2GetRealStatus", DONE | FAIL | CANC | TERM), ("", NONE), false),
    rule(Func::GetIntegerStatus, ("fmi2GetIntegerStatus", DONE | FAIL | CANC | TERM), ("", NONE), false),
    rule(Func::GetBooleanStatus, ("fmi2GetBooleanStatus", DONE | FAIL | CANC | TERM), ("", NONE), false),
    rule(Func::GetStringStatus, ("fmi2GetStringStatus", DONE | FAIL | CANC | TERM), ("", NONE), false),
    rule(
        Func::GetAdjointDerivative,
        ("", NONE),
        ("fmi3GetAdjointDerivative", INIT | DONE | FAIL | TERM | EVENT | CONT),
        false,
    ),
    rule(Func::EnterEventMode, ("fmi2EnterEventMode", EVENT | CONT), ("fmi3EnterEventMode", DONE | CONT), false),
    rule(Func::EnterStepMode, ("", NONE), ("fmi3EnterStepMode", EVENT), false),
    rule(Func::UpdateDiscreteStates, ("", NONE), ("fmi3UpdateDiscreteStates", EVENT), false),
    rule(Func::NewDiscreteStates, ("fmi2NewDiscreteStates", EVENT), ("", NONE), false),
    rule(
        Func::EnterContinuousTimeMode,
        ("fmi2EnterContinuousTimeMode", EVENT),
        ("fmi3EnterContinuousTimeMode", EVENT),
        false,
    ),
    rule(
        Func::CompletedIntegratorStep,
        ("fmi2CompletedIntegratorStep", CONT),
        ("fmi3CompletedIntegratorStep", CONT),
        true,
    ),
    rule(Func::SetTime, ("fmi2SetTime", EVENT | CONT), ("fmi3SetTime", EVENT | CONT), false),
    rule(Func::SetContinuousStates, ("fmi2SetContinuousStates", CONT), ("fmi3SetContinuousStates", CONT), false),
    rule(
        Func::GetDerivatives,
        ("fmi2GetDerivatives", EVENT | CONT | TERM | ERR),
        ("fmi3GetContinuousStateDerivatives", ME_READABLE3),
        true,
    ),
    rule(
        Func::GetEventIndicators,
        ("fmi2GetEventIndicators", ME_READABLE),
        ("fmi3GetEventIndicators", ME_READABLE3),
        false,
    ),
    rule(
        Func::GetContinuousStates,
        ("fmi2GetContinuousStates", ME_READABLE),
        ("fmi3GetContinuousStates", ME_READABLE3),
        false,
    ),
    rule(
        Func::GetNominalsOfContinuousStates,
        ("fmi2GetNominalsOfContinuousStates", INST | EVENT | CONT | TERM | ERR),
        ("fmi3GetNominalsOfContinuousStates", ME_READABLE3),
        false,
    ),
    rule(Func::GetNumberOfContinuousStates, ("", NONE), ("fmi3GetNumberOfContinuousStates", ME_READABLE3), false),
    rule(Func::GetNumberOfEventIndicators, ("", NONE), ("fmi3GetNumberOfEventIndicators", ME_READABLE3), false),
    rule(Func::Unsupported, ("", NONE), ("an FMI 3 function", ALIVE), false),
];

impl Func {
    /// This function's row of [`RULES`].
    pub fn rule(self) -> &'static Rule {
        &RULES[self as usize]
    }

    /// The C name in FMI version `standard`.
    pub fn name_in(self, standard: Standard) -> &'static str {
        let r = self.rule();
        match standard {
            Standard::Fmi2 => r.name2,
            Standard::Fmi3 => r.name3,
        }
    }

    /// The C name (FMI 2's, else FMI 3's).
    pub fn name(self) -> &'static str {
        let r = self.rule();
        if r.name2.is_empty() { r.name3 } else { r.name2 }
    }
}

/// The guard: `Err("<name>: not allowed in state Z")` when `func` is illegal in `state` for
/// an instance of FMI version `standard`; `name` is the C name the call came in by (the
/// table's, or that of an FMI 3 function sharing [`Func::Unsupported`]'s row).
pub fn check(state: State, func: Func, standard: Standard, name: &str) -> Result<(), String> {
    let r = func.rule();
    let allowed = match standard {
        Standard::Fmi2 => r.allowed2,
        Standard::Fmi3 => r.allowed3,
    };
    if allowed & state.bit() != 0 { Ok(()) } else { Err(format!("{name}: not allowed in state {state:?}")) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_sits_at_its_function_index() {
        for (k, r) in RULES.iter().enumerate() {
            assert_eq!(r.func as usize, k, "{}", r.func.name());
        }
    }

    #[test]
    fn do_step_is_legal_only_after_initialization() {
        let check = |s, f: Func, standard| check(s, f, standard, f.name_in(standard));
        assert!(check(State::StepComplete, Func::DoStep, Standard::Fmi2).is_ok());
        let e = check(State::Instantiated, Func::DoStep, Standard::Fmi2).unwrap_err();
        assert_eq!(e, "fmi2DoStep: not allowed in state Instantiated");
        let e = check(State::EventMode, Func::DoStep, Standard::Fmi3).unwrap_err();
        assert_eq!(e, "fmi3DoStep: not allowed in state EventMode");
    }

    #[test]
    fn a_function_of_one_version_is_never_legal_in_the_other() {
        for r in &RULES {
            assert_eq!(r.name2.is_empty(), r.allowed2 == 0, "{}", r.name3);
            assert_eq!(r.name3.is_empty(), r.allowed3 == 0, "{}", r.name2);
        }
    }
}
