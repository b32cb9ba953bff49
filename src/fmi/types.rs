//! FMI 2.0 C types (fmi2TypesPlatform.h, fmi2FunctionTypes.h) in Rust, with `libc` scalars;
//! FMI 3.0 shares them where the two agree (pointers, status values), and adds its own
//! in `fmi3`'s exports.
//! C enums the host passes in (fmi2Type, fmi2StatusKind) arrive as `c_int` and are checked,
//! never transmuted.

use libc::{c_char, c_int, c_uint, c_void, size_t};

/// fmi2Component: the instance pointer returned by fmi2Instantiate.
pub type Component = *mut c_void;
/// fmi2ComponentEnvironment: the host's opaque pointer, handed back to the logger.
pub type ComponentEnvironment = *mut c_void;
/// fmi2FMUstate: an opaque pointer to a saved FMU state.
pub type FmuStatePtr = *mut c_void;
/// fmi2ValueReference.
pub type ValueReference = c_uint;
/// fmi2Real.
pub type Real = f64;
/// fmi2Integer.
pub type Integer = c_int;
/// fmi2Boolean (fmi2True = 1, fmi2False = 0).
pub type Boolean = c_int;
/// fmi2String.
pub type FmiString = *const c_char;
/// fmi2Byte.
pub type Byte = c_char;

/// fmi2True.
pub const TRUE: Boolean = 1;
/// fmi2False.
pub const FALSE: Boolean = 0;

/// fmi2Status (2.1.3 Status Returned by Functions).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// fmi2OK: all well.
    Ok = 0,
    /// fmi2Warning: something is not quite right, but the computation can continue.
    Warning = 1,
    /// fmi2Discard: the call was carried out only partly; for fmi2DoStep, the step stopped
    /// at fmi2LastSuccessfulTime.
    Discard = 2,
    /// fmi2Error: the call failed.
    Error = 3,
    /// fmi2Fatal: the instance is unusable; only fmi2FreeInstance may follow.
    Fatal = 4,
    /// fmi2Pending: an asynchronous fmi2DoStep is still running (never returned here:
    /// fmi2DoStep is synchronous).
    Pending = 5,
}

/// fmi2Type value fmi2ModelExchange.
pub const MODEL_EXCHANGE: c_int = 0;
/// fmi2Type value fmi2CoSimulation.
pub const CO_SIMULATION: c_int = 1;

/// fmi2StatusKind value fmi2DoStepStatus (4.2.3 Retrieving Status Information from the Slave).
pub const DO_STEP_STATUS: c_int = 0;
/// fmi2StatusKind value fmi2PendingStatus.
pub const PENDING_STATUS: c_int = 1;
/// fmi2StatusKind value fmi2LastSuccessfulTime.
pub const LAST_SUCCESSFUL_TIME: c_int = 2;
/// fmi2StatusKind value fmi2Terminated.
pub const TERMINATED: c_int = 3;

/// fmi2CallbackLogger: `(env, instanceName, status, category, message, ...)`; the message
/// is a printf format, so it is always called with `"%s"` and the text.
pub type LoggerFn = unsafe extern "C" fn(ComponentEnvironment, FmiString, c_int, FmiString, FmiString, ...);
/// fmi3LogMessageCallback: `(instanceEnvironment, status, category, message)`.
pub type LogMessageFn = unsafe extern "C" fn(ComponentEnvironment, c_int, FmiString, FmiString);
/// fmi2CallbackAllocateMemory.
pub type AllocateMemoryFn = unsafe extern "C" fn(size_t, size_t) -> *mut c_void;
/// fmi2CallbackFreeMemory.
pub type FreeMemoryFn = unsafe extern "C" fn(*mut c_void);
/// fmi2StepFinished.
pub type StepFinishedFn = unsafe extern "C" fn(ComponentEnvironment, c_int);

/// fmi2CallbackFunctions (2.1.5 Creation, Destruction and Logging of FMU Instances).
/// NULL function pointers are `None`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CallbackFunctions {
    /// `logger` (fmi2CallbackLogger): receives every message, with `componentEnvironment`;
    /// NULL: messages are dropped.
    pub logger: Option<LoggerFn>,
    /// `allocateMemory` (fmi2CallbackAllocateMemory): not used, the FMU allocates with
    /// Rust's allocator.
    pub allocate_memory: Option<AllocateMemoryFn>,
    /// `freeMemory` (fmi2CallbackFreeMemory): not used either.
    pub free_memory: Option<FreeMemoryFn>,
    /// `stepFinished` (fmi2StepFinished): for asynchronous fmi2DoStep; not used (fmi2DoStep
    /// is synchronous).
    pub step_finished: Option<StepFinishedFn>,
    /// `componentEnvironment` (fmi2ComponentEnvironment): the host's pointer, passed back
    /// as the logger's first argument.
    pub component_environment: ComponentEnvironment,
}

/// fmi2EventInfo (3.2.2 Evaluation of the Model Equations), filled by
/// fmi2NewDiscreteStates.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct EventInfo {
    /// `newDiscreteStatesNeeded`.
    pub new_discrete_states_needed: Boolean,
    /// `terminateSimulation`.
    pub terminate_simulation: Boolean,
    /// `nominalsOfContinuousStatesChanged`.
    pub nominals_changed: Boolean,
    /// `valuesOfContinuousStatesChanged`.
    pub values_changed: Boolean,
    /// `nextEventTimeDefined`.
    pub next_event_time_defined: Boolean,
    /// `nextEventTime`.
    pub next_event_time: Real,
}
