//! FMI 3.0 common functions (2.3 Common Functions): inquiry, instantiation, the
//! lifecycle, getting and setting values, FMU states and partial derivatives. Each is a
//! thin entry over the shell the FMI 2 exports use: the same guard, state-machine table
//! (its FMI 3 column), instance and engine; where FMI 3 only renames or adds an argument,
//! the FMI 2 export's body runs.
//!
//! Safety of every export: the host calls it as FMI 3.0 specifies (valid pointers with
//! the stated lengths, an instance from fmi3InstantiateCoSimulation or
//! fmi3InstantiateModelExchange not yet freed, one
//! thread per instance at a time); NULL pointers are checked and refused, never
//! dereferenced.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::exports_common as fmi2;
use super::exports_state as state2;
use super::guard::{guarded, put, slice, slice_mut, text, with_stack};
use super::handle::create;
use super::instance::Instance;
use super::interface::Interface;
use super::logger::{Logger, Sink};
use super::state_machine::{Func, State};
use super::types::{Component, ComponentEnvironment, FmiString, FmuStatePtr, LogMessageFn, Status, ValueReference};
use super::variables::Standard;
use libc::{c_char, c_void, size_t};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// fmi3Boolean: C `bool`, one byte.
pub type Bool3 = u8;

/// fmi3GetVersion: "3.0".
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// fmi3SetDebugLogging: as fmi2SetDebugLogging.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    c: Component,
    loggingOn: Bool3,
    nCategories: size_t,
    categories: *const FmiString,
) -> Status {
    // SAFETY: per the module's contract.
    unsafe { fmi2::fmi2SetDebugLogging(c, (loggingOn != 0) as i32, nCategories, categories) }
}

/// The instance of `interface` that an FMI 3 instantiation function (`func`, its C name)
/// asks for, or NULL with the reason logged through `logMessage`.
///
/// # Safety
/// The strings are NULL or NUL-terminated, per FMI.
#[allow(clippy::too_many_arguments)]
unsafe fn instantiate(
    func: &str,
    interface: Interface,
    instanceName: FmiString,
    instantiationToken: FmiString,
    resourcePath: FmiString,
    loggingOn: Bool3,
    eventModeUsed: bool,
    instanceEnvironment: ComponentEnvironment,
    logMessage: Option<LogMessageFn>,
) -> Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a NUL-terminated string or NULL per FMI.
        let name = unsafe { text(instanceName, "instanceName") };
        let sink = Sink::fmi3(logMessage, instanceEnvironment, name.as_deref().unwrap_or("?"));
        // Parsing the model (recursive over its expressions) needs the engine's stack.
        let made = with_stack(|| {
            let name = name?;
            let fail = |m: String| format!("instance '{name}': {m}");
            // SAFETY: NUL-terminated strings or NULL per FMI.
            let token = unsafe { text(instantiationToken, "instantiationToken") }.map_err(fail)?;
            // SAFETY: as above.
            let res = unsafe { text(resourcePath, "resourcePath") }.map_err(fail)?;
            let dir = PathBuf::from(res);
            let (model, guid, layout) =
                super::resources::load_for(&dir, interface, "instantiationToken", &token).map_err(fail)?;
            let mut inst = Instance::new(model, guid, layout, Logger::new(loggingOn != 0), Standard::Fmi3);
            inst.interface = interface;
            inst.event_mode = eventModeUsed;
            Ok::<_, String>(inst)
        });
        match made {
            Ok(inst) => create(inst, sink),
            Err(msg) => {
                sink.emit(Status::Error, &format!("{func}: {msg}"));
                std::ptr::null_mut()
            }
        }
    }));
    made.unwrap_or(std::ptr::null_mut())
}

/// fmi3InstantiateCoSimulation: a Co-Simulation instance of the model in
/// `<resourcePath>/model.xml`, or NULL (with the reason logged). Intermediate updates are
/// not used (the FMU never returns early); with `eventModeUsed` initialization ends in
/// Event Mode, where nothing happens (the model has no events).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: FmiString,
    instantiationToken: FmiString,
    resourcePath: FmiString,
    _visible: Bool3,
    loggingOn: Bool3,
    eventModeUsed: Bool3,
    _earlyReturnAllowed: Bool3,
    _requiredIntermediateVariables: *const ValueReference,
    _nRequiredIntermediateVariables: size_t,
    instanceEnvironment: ComponentEnvironment,
    logMessage: Option<LogMessageFn>,
    _intermediateUpdate: *const c_void,
) -> Component {
    let (name, token, res, env) = (instanceName, instantiationToken, resourcePath, instanceEnvironment);
    let func = "fmi3InstantiateCoSimulation";
    // SAFETY: per the module's contract.
    unsafe {
        instantiate(func, Interface::CoSimulation, name, token, res, loggingOn, eventModeUsed != 0, env, logMessage)
    }
}

/// fmi3InstantiateModelExchange: a Model Exchange instance of the model in
/// `<resourcePath>/model.xml` (its continuous states are the linearization states), or
/// NULL with the reason logged (also when the FMU was packed without Model Exchange).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: FmiString,
    instantiationToken: FmiString,
    resourcePath: FmiString,
    _visible: Bool3,
    loggingOn: Bool3,
    instanceEnvironment: ComponentEnvironment,
    logMessage: Option<LogMessageFn>,
) -> Component {
    let (name, token, res, env) = (instanceName, instantiationToken, resourcePath, instanceEnvironment);
    let func = "fmi3InstantiateModelExchange";
    // SAFETY: per the module's contract.
    unsafe { instantiate(func, Interface::ModelExchange, name, token, res, loggingOn, false, env, logMessage) }
}

/// Log `msg` through the host's logMessage (if any) and return NULL: an interface type
/// this FMU does not provide.
fn refuse_instance(log: Option<LogMessageFn>, env: ComponentEnvironment, name: FmiString, msg: &str) -> Component {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a NUL-terminated string or NULL per FMI.
        let name = unsafe { text(name, "instanceName") }.unwrap_or_else(|_| "?".into());
        Sink::fmi3(log, env, &name).emit(Status::Error, msg);
    }));
    std::ptr::null_mut()
}

/// fmi3InstantiateScheduledExecution: NULL, the FMU offers Model Exchange and
/// Co-Simulation only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instanceName: FmiString,
    _instantiationToken: FmiString,
    _resourcePath: FmiString,
    _visible: Bool3,
    _loggingOn: Bool3,
    instanceEnvironment: ComponentEnvironment,
    logMessage: Option<LogMessageFn>,
    _clockUpdate: *const c_void,
    _lockPreemption: *const c_void,
    _unlockPreemption: *const c_void,
) -> Component {
    let msg = "fmi3InstantiateScheduledExecution: Scheduled Execution is not supported (this FMU offers Model \
               Exchange and Co-Simulation)";
    refuse_instance(logMessage, instanceEnvironment, instanceName, msg)
}

/// fmi3FreeInstance: as fmi2FreeInstance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(c: Component) {
    // SAFETY: per the module's contract.
    unsafe { fmi2::fmi2FreeInstance(c) }
}

/// fmi3EnterInitializationMode: the experiment (fmi2SetupExperiment's arguments) and
/// Initialization Mode.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    c: Component,
    toleranceDefined: Bool3,
    tolerance: f64,
    startTime: f64,
    stopTimeDefined: Bool3,
    stopTime: f64,
) -> Status {
    guarded(c, Func::EnterInitializationMode, |inst| {
        inst.setup(
            (toleranceDefined != 0).then_some(tolerance),
            startTime,
            (stopTimeDefined != 0).then_some(stopTime),
        )?;
        inst.state = State::InitializationMode;
        Ok(Status::Ok)
    })
}

/// fmi3ExitInitializationMode: the engine is built with the values set; Step Mode, or
/// Event Mode when the host uses it.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(c: Component) -> Status {
    guarded(c, Func::ExitInitializationMode, |inst| {
        inst.exit_initialization()?;
        if inst.event_mode {
            inst.state = State::EventMode;
        }
        Ok(Status::Ok)
    })
}

/// fmi3EnterEventMode: Event Mode (nothing to handle: the model has no events).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterEventMode(c: Component) -> Status {
    guarded(c, Func::EnterEventMode, |inst| {
        inst.state = State::EventMode;
        Ok(Status::Ok)
    })
}

/// fmi3UpdateDiscreteStates: no discrete states, no event ahead.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    c: Component,
    discreteStatesNeedUpdate: *mut Bool3,
    terminateSimulation: *mut Bool3,
    nominalsOfContinuousStatesChanged: *mut Bool3,
    valuesOfContinuousStatesChanged: *mut Bool3,
    nextEventTimeDefined: *mut Bool3,
    nextEventTime: *mut f64,
) -> Status {
    guarded(c, Func::UpdateDiscreteStates, |_| {
        for (p, what) in [
            (discreteStatesNeedUpdate, "discreteStatesNeedUpdate"),
            (terminateSimulation, "terminateSimulation"),
            (nominalsOfContinuousStatesChanged, "nominalsOfContinuousStatesChanged"),
            (valuesOfContinuousStatesChanged, "valuesOfContinuousStatesChanged"),
            (nextEventTimeDefined, "nextEventTimeDefined"),
        ] {
            // SAFETY: a writable fmi3Boolean per FMI.
            unsafe { put(p, 0, what) }?;
        }
        // SAFETY: a writable fmi3Float64 per FMI.
        unsafe { put(nextEventTime, 0.0, "nextEventTime") }?;
        Ok(Status::Ok)
    })
}

/// fmi3Terminate: as fmi2Terminate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(c: Component) -> Status {
    // SAFETY: per the module's contract.
    unsafe { fmi2::fmi2Terminate(c) }
}

/// fmi3Reset: as fmi2Reset.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(c: Component) -> Status {
    // SAFETY: per the module's contract.
    unsafe { fmi2::fmi2Reset(c) }
}

/// Err unless `nValues` equals `nValueReferences` (every variable is a scalar).
pub(super) fn scalars(nvr: size_t, nvalues: size_t) -> Result<(), String> {
    if nvr == nvalues {
        Ok(())
    } else {
        Err(format!("nValues = {nvalues} but the {nvr} variables are scalars (nValues must equal nValueReferences)"))
    }
}

/// Getters and setters of the FMU's variable types: `(instance, valueReferences,
/// nValueReferences, values, nValues)`, every variable a scalar; the body is the
/// instance's FMI 2 one.
macro_rules! values {
    ($($(#[$doc:meta])* $name:ident, $func:expr, $ptr:ty, $array:ident, $method:ident;)*) => {$(
        $(#[$doc])*
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(
            c: Component,
            vr: *const ValueReference,
            nvr: size_t,
            values: $ptr,
            nValues: size_t,
        ) -> Status {
            guarded(c, $func, |inst| {
                scalars(nvr, nValues)?;
                // SAFETY: nvr elements each, per FMI.
                let (vr, values) = unsafe { (slice(vr, nvr, "valueReferences")?, $array(values, nvr, "values")?) };
                inst.$method(vr, values)?;
                Ok(Status::Ok)
            })
        }
    )*};
}

values! {
    /// fmi3GetFloat64: as fmi2GetReal (and `time`).
    fmi3GetFloat64, Func::GetReal, *mut f64, slice_mut, get_reals;
    /// fmi3SetFloat64: as fmi2SetReal.
    fmi3SetFloat64, Func::SetReal, *const f64, slice, set_reals;
    /// fmi3GetInt32: `solver.maxSteps`.
    fmi3GetInt32, Func::GetInteger, *mut i32, slice_mut, get_integers;
    /// fmi3SetInt32: `solver.maxSteps` (tunable), at least 1.
    fmi3SetInt32, Func::SetInteger, *const i32, slice, set_integers;
}

/// fmi3GetFMUState: as fmi2GetFMUstate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(c: Component, FMUState: *mut FmuStatePtr) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2GetFMUstate(c, FMUState) }
}

/// fmi3SetFMUState: as fmi2SetFMUstate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(c: Component, FMUState: FmuStatePtr) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2SetFMUstate(c, FMUState) }
}

/// fmi3FreeFMUState: as fmi2FreeFMUstate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(c: Component, FMUState: *mut FmuStatePtr) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2FreeFMUstate(c, FMUState) }
}

/// fmi3SerializedFMUStateSize: as fmi2SerializedFMUstateSize.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(c: Component, FMUState: FmuStatePtr, size: *mut size_t) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2SerializedFMUstateSize(c, FMUState, size) }
}

/// fmi3SerializeFMUState: as fmi2SerializeFMUstate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    c: Component,
    FMUState: FmuStatePtr,
    serializedState: *mut u8,
    size: size_t,
) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2SerializeFMUstate(c, FMUState, serializedState.cast(), size) }
}

/// fmi3DeserializeFMUState: as fmi2DeSerializeFMUstate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    c: Component,
    serializedState: *const u8,
    size: size_t,
    FMUState: *mut FmuStatePtr,
) -> Status {
    // SAFETY: per the module's contract.
    unsafe { state2::fmi2DeSerializeFMUstate(c, serializedState.cast(), size, FMUState) }
}

/// The body of both FMI 3 derivative functions (see [`Instance::seeded_derivative`]).
///
/// # Safety
/// The arrays have the stated lengths, per FMI.
#[allow(clippy::too_many_arguments)]
unsafe fn derivative(
    c: Component,
    func: Func,
    unknowns: *const ValueReference,
    nUnknowns: size_t,
    knowns: *const ValueReference,
    nKnowns: size_t,
    seed: *const f64,
    nSeed: size_t,
    sensitivity: *mut f64,
    nSensitivity: size_t,
) -> Status {
    guarded(c, func, |inst| {
        // SAFETY: per this function's contract.
        let (u, k, s, out) = unsafe {
            (
                slice(unknowns, nUnknowns, "unknowns")?,
                slice(knowns, nKnowns, "knowns")?,
                slice(seed, nSeed, "seed")?,
                slice_mut(sensitivity, nSensitivity, "sensitivity")?,
            )
        };
        inst.seeded_derivative(u, k, s, out, func == Func::GetAdjointDerivative)?;
        Ok(Status::Ok)
    })
}

/// fmi3GetDirectionalDerivative: sensitivity = J·seed, J the rows `unknowns` (state
/// derivatives, outputs) and columns `knowns` (states, inputs) of the exact A, B, C, D
/// (seed Eq. 34) at the current point; one solve of Eq. 34 per column kind.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    c: Component,
    unknowns: *const ValueReference,
    nUnknowns: size_t,
    knowns: *const ValueReference,
    nKnowns: size_t,
    seed: *const f64,
    nSeed: size_t,
    sensitivity: *mut f64,
    nSensitivity: size_t,
) -> Status {
    let f = Func::GetDirectionalDerivative;
    // SAFETY: per the module's contract.
    unsafe { derivative(c, f, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity) }
}

/// fmi3GetAdjointDerivative: sensitivityᵀ = seedᵀ·J (J as for the directional
/// derivative): one solve of the transposed Eq. 34 per column kind, whatever the number
/// of knowns.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    c: Component,
    unknowns: *const ValueReference,
    nUnknowns: size_t,
    knowns: *const ValueReference,
    nKnowns: size_t,
    seed: *const f64,
    nSeed: size_t,
    sensitivity: *mut f64,
    nSensitivity: size_t,
) -> Status {
    let f = Func::GetAdjointDerivative;
    // SAFETY: per the module's contract.
    unsafe { derivative(c, f, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity) }
}
