//! FMI 2.0 Model Exchange functions (3.2): exported because every FMI 2.0 function must
//! be, but this FMU is Co-Simulation only; each returns fmi2Error and says so.
//!
//! Safety of every export: as in `exports_common` (no pointer argument is read).
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::handle::enter;
use super::types::{Boolean, Component, Real, Status};
use libc::{c_void, size_t};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Log that `name` is Model Exchange only; fmi2Error.
fn unsupported(c: Component, name: &str) -> Status {
    let _ = catch_unwind(AssertUnwindSafe(|| match enter(c) {
        Ok(mut s) => {
            s.instance().log(
                Status::Error,
                &format!("{name}: Model Exchange is not supported (this FMU is Co-Simulation only)"),
            );
            s.finish();
        }
        Err(refused) => refused.report(name),
    }));
    Status::Error
}

/// fmi2EnterEventMode (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterEventMode(c: Component) -> Status {
    unsupported(c, "fmi2EnterEventMode")
}

/// fmi2NewDiscreteStates (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: Component, _eventInfo: *mut c_void) -> Status {
    unsupported(c, "fmi2NewDiscreteStates")
}

/// fmi2EnterContinuousTimeMode (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: Component) -> Status {
    unsupported(c, "fmi2EnterContinuousTimeMode")
}

/// fmi2CompletedIntegratorStep (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: Component,
    _noSetFMUStatePriorToCurrentPoint: Boolean,
    _enterEventMode: *mut Boolean,
    _terminateSimulation: *mut Boolean,
) -> Status {
    unsupported(c, "fmi2CompletedIntegratorStep")
}

/// fmi2SetTime (3.2.1): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetTime(c: Component, _time: Real) -> Status {
    unsupported(c, "fmi2SetTime")
}

/// fmi2SetContinuousStates (3.2.1): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(c: Component, _x: *const Real, _nx: size_t) -> Status {
    unsupported(c, "fmi2SetContinuousStates")
}

/// fmi2GetDerivatives (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(c: Component, _derivatives: *mut Real, _nx: size_t) -> Status {
    unsupported(c, "fmi2GetDerivatives")
}

/// fmi2GetEventIndicators (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(c: Component, _eventIndicators: *mut Real, _ni: size_t) -> Status {
    unsupported(c, "fmi2GetEventIndicators")
}

/// fmi2GetContinuousStates (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: Component, _x: *mut Real, _nx: size_t) -> Status {
    unsupported(c, "fmi2GetContinuousStates")
}

/// fmi2GetNominalsOfContinuousStates (3.2.2): Model Exchange only.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(c: Component, _x_nominal: *mut Real, _nx: size_t) -> Status {
    unsupported(c, "fmi2GetNominalsOfContinuousStates")
}
