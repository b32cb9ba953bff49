//! FMI 2.0 common functions (2.1 FMI Application Programming Interface): inquiry,
//! instance lifecycle, initialization, and getting/setting values.
//!
//! Safety of every export: the host calls it as FMI 2.0 specifies (valid pointers with
//! the stated lengths, a component from fmi2Instantiate not yet freed, one thread per
//! instance at a time); NULL pointers are checked and refused, never dereferenced.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::guard::{get, guarded, slice, slice_mut, text, with_stack};
use super::handle::{create, destroy};
use super::instance::Instance;
use super::interface::Interface;
use super::logger::{Logger, Sink};
use super::state_machine::{Func, State};
use super::types::{
    Boolean, CO_SIMULATION, CallbackFunctions, Component, FmiString, Integer, MODEL_EXCHANGE, Real, Status, TRUE,
    ValueReference,
};
use super::uri::file_uri_to_path;
use super::variables::Standard;
use libc::{c_char, c_int, size_t};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// fmi2GetTypesPlatform: "default" (2.1.4 Inquire Platform and Version Number).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// fmi2GetVersion: "2.0".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// fmi2SetDebugLogging (2.1.5): logging on/off and the categories (none: all).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Component,
    loggingOn: Boolean,
    nCategories: size_t,
    categories: *const FmiString,
) -> Status {
    guarded(c, Func::SetDebugLogging, |inst| {
        // SAFETY: nCategories strings per the FMI contract.
        let cats = unsafe { slice(categories, nCategories, "categories") }?;
        // SAFETY: each entry is a NUL-terminated string per the FMI contract.
        let names = cats.iter().map(|&p| unsafe { text(p, "a category") }).collect::<Result<Vec<_>, _>>()?;
        inst.log.configure(loggingOn == TRUE, &names)?;
        Ok(Status::Ok)
    })
}

/// fmi2Instantiate (2.1.5): a Co-Simulation or Model Exchange instance (`fmuType`) of the
/// model in `<fmuResourceLocation>/model.xml`, or NULL (with the reason logged, also when
/// the FMU was packed without that interface).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: FmiString,
    fmuType: c_int,
    fmuGUID: FmiString,
    fmuResourceLocation: FmiString,
    functions: *const CallbackFunctions,
    _visible: Boolean,
    loggingOn: Boolean,
) -> Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        if functions.is_null() {
            return std::ptr::null_mut();
        }
        // SAFETY: non-NULL and pointing to the host's callback struct per FMI.
        let Ok(callbacks) = (unsafe { get(functions, "functions") }) else {
            return std::ptr::null_mut();
        };
        // SAFETY: a NUL-terminated string or NULL per FMI.
        let name = unsafe { text(instanceName, "instanceName") };
        let sink = Sink::new(&callbacks, name.as_deref().unwrap_or("?"));
        // Parsing the model (recursive over its expressions) needs the engine's stack.
        let made = with_stack(|| {
            // SAFETY: NUL-terminated strings or NULL per FMI.
            let (model, guid, layout) =
                name.and_then(|name| unsafe { instantiate(&name, fmuType, fmuGUID, fmuResourceLocation) })?;
            let mut inst = Instance::new(model, guid, layout, Logger::new(loggingOn == TRUE), Standard::Fmi2);
            if fmuType == MODEL_EXCHANGE {
                inst.interface = Interface::ModelExchange;
            }
            Ok::<_, String>(inst)
        });
        match made {
            Ok(inst) => create(inst, sink),
            Err(msg) => {
                sink.emit(Status::Error, &format!("fmi2Instantiate: {msg}"));
                std::ptr::null_mut()
            }
        }
    }));
    made.unwrap_or(std::ptr::null_mut())
}

/// Check the arguments and read the model (with its packed start values applied, see
/// [`super::resources::read_start_values`]) and its linearization states.
///
/// # Safety
/// `guid_p` and `res_p` are NULL or NUL-terminated.
unsafe fn instantiate(
    name: &str,
    fmu_type: c_int,
    guid_p: FmiString,
    res_p: FmiString,
) -> Result<(crate::model::Model, String, crate::linearize::StateLayout), String> {
    let fail = |m: String| format!("instance '{name}': {m}");
    if fmu_type != CO_SIMULATION && fmu_type != MODEL_EXCHANGE {
        return Err(fail(format!("unknown fmuType {fmu_type}")));
    }
    // SAFETY: per this function's contract.
    let given = unsafe { text(guid_p, "fmuGUID") }.map_err(fail)?;
    // SAFETY: per this function's contract.
    let res = unsafe { text(res_p, "fmuResourceLocation") }.map_err(fail)?;
    let dir = file_uri_to_path(&res).map_err(fail)?;
    let interface = if fmu_type == MODEL_EXCHANGE { Interface::ModelExchange } else { Interface::CoSimulation };
    super::resources::load_for(&dir, interface, "fmuGUID", &given).map_err(fail)
}

/// fmi2FreeInstance (2.1.5): release the instance and the FMU states it still holds
/// (NULL, or not a live instance: nothing; busy with another call: refused and logged).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: Component) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        if let Err(refused) = with_stack(|| destroy(c)) {
            refused.report(Func::FreeInstance.name());
        }
    }));
}

/// fmi2SetupExperiment (2.1.6): tolerance, start and stop time.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: Component,
    toleranceDefined: Boolean,
    tolerance: Real,
    startTime: Real,
    stopTimeDefined: Boolean,
    stopTime: Real,
) -> Status {
    guarded(c, Func::SetupExperiment, |inst| {
        let tol = (toleranceDefined == TRUE).then_some(tolerance);
        inst.setup(tol, startTime, (stopTimeDefined == TRUE).then_some(stopTime))?;
        Ok(Status::Ok)
    })
}

/// fmi2EnterInitializationMode (2.1.6).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Component) -> Status {
    guarded(c, Func::EnterInitializationMode, |inst| {
        inst.state = State::InitializationMode;
        Ok(Status::Ok)
    })
}

/// fmi2ExitInitializationMode (2.1.6): the engine is built with the values set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Component) -> Status {
    guarded(c, Func::ExitInitializationMode, |inst| {
        inst.exit_initialization()?;
        Ok(Status::Ok)
    })
}

/// fmi2Terminate (2.1.6).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: Component) -> Status {
    guarded(c, Func::Terminate, |inst| {
        inst.state = State::Terminated;
        Ok(Status::Ok)
    })
}

/// fmi2Reset (2.1.6): back to the state after fmi2Instantiate.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: Component) -> Status {
    guarded(c, Func::Reset, |inst| {
        inst.reset();
        Ok(Status::Ok)
    })
}

/// fmi2GetReal (2.1.7 Getting and Setting Variable Values).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(c: Component, vr: *const ValueReference, nvr: size_t, value: *mut Real) -> Status {
    guarded(c, Func::GetReal, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, value) = unsafe { (slice(vr, nvr, "vr")?, slice_mut(value, nvr, "value")?) };
        inst.get_reals(vr, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2SetReal (2.1.7): parameters before initialization ends, inputs, never outputs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    value: *const Real,
) -> Status {
    guarded(c, Func::SetReal, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, value) = unsafe { (slice(vr, nvr, "vr")?, slice(value, nvr, "value")?) };
        inst.set_reals(vr, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetInteger (2.1.7): the Integer parameter `solver.maxSteps`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    value: *mut Integer,
) -> Status {
    guarded(c, Func::GetInteger, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, value) = unsafe { (slice(vr, nvr, "vr")?, slice_mut(value, nvr, "value")?) };
        inst.get_integers(vr, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2SetInteger (2.1.7): `solver.maxSteps` (tunable: also between steps), at least 1.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    value: *const Integer,
) -> Status {
    guarded(c, Func::SetInteger, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, value) = unsafe { (slice(vr, nvr, "vr")?, slice(value, nvr, "value")?) };
        inst.set_integers(vr, value)?;
        Ok(Status::Ok)
    })
}

/// The model has no Boolean or String variables: any value reference of those types is
/// unknown.
fn no_such(func: Func, vr: &[ValueReference]) -> Result<Status, String> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(v) => Err(format!(
            "unknown value reference {v} (the FMU has only Real variables and the Integer solver.maxSteps; {})",
            func.name()
        )),
    }
}

/// Generate the getters and setters of the types the FMU has no variables of.
macro_rules! no_variables {
    ($($(#[$doc:meta])* $name:ident, $func:expr, $ptr:ty;)*) => {$(
        $(#[$doc])*
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: Component, vr: *const ValueReference, nvr: size_t, value: $ptr) -> Status {
            guarded(c, $func, |_| {
                // SAFETY: nvr elements each, per FMI (only NULL-ness of `value` is used).
                let vr = unsafe { slice(vr, nvr, "vr")? };
                if nvr > 0 && value.is_null() {
                    return Err("value is NULL".into());
                }
                no_such($func, vr)
            })
        }
    )*};
}

no_variables! {
    /// fmi2GetBoolean (2.1.7): no Boolean variables.
    fmi2GetBoolean, Func::GetBoolean, *mut Boolean;
    /// fmi2GetString (2.1.7): no String variables.
    fmi2GetString, Func::GetString, *mut FmiString;
    /// fmi2SetBoolean (2.1.7): no Boolean variables.
    fmi2SetBoolean, Func::SetBoolean, *const Boolean;
    /// fmi2SetString (2.1.7): no String variables.
    fmi2SetString, Func::SetString, *const FmiString;
}
