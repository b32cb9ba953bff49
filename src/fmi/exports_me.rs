//! FMI 2.0 Model Exchange functions (3.2): the host sets time and the continuous states
//! (the linearization states) and reads their derivatives; the model has no events, so
//! Event Mode only passes through. The work is the instance's ([`super::exchange`]).
//!
//! Safety of every export: as in `exports_common` (arrays of the length given, per FMI).
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::guard::{guarded, put, slice, slice_mut};
use super::state_machine::{Func, State};
use super::types::{Boolean, Component, EventInfo, FALSE, Real, Status};
use libc::size_t;

/// fmi2EnterEventMode (3.2.2).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterEventMode(c: Component) -> Status {
    guarded(c, Func::EnterEventMode, |inst| {
        inst.state = State::EventMode;
        Ok(Status::Ok)
    })
}

/// fmi2NewDiscreteStates (3.2.2): nothing is discrete; every flag false.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: Component, eventInfo: *mut EventInfo) -> Status {
    guarded(c, Func::NewDiscreteStates, |_| {
        // SAFETY: the host's fmi2EventInfo, per FMI.
        unsafe { put(eventInfo, EventInfo::default(), "fmi2EventInfo")? };
        Ok(Status::Ok)
    })
}

/// fmi2EnterContinuousTimeMode (3.2.2).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: Component) -> Status {
    guarded(c, Func::EnterContinuousTimeMode, |inst| {
        inst.enter_continuous_time_mode()?;
        Ok(Status::Ok)
    })
}

/// fmi2CompletedIntegratorStep (3.2.2): the accepted point is solved and kept as the one
/// later points continue from; no event, no termination.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: Component,
    _noSetFMUStatePriorToCurrentPoint: Boolean,
    enterEventMode: *mut Boolean,
    terminateSimulation: *mut Boolean,
) -> Status {
    guarded(c, Func::CompletedIntegratorStep, |inst| {
        // SAFETY: the host's out-arguments, per FMI.
        unsafe {
            put(enterEventMode, FALSE, "enterEventMode")?;
            put(terminateSimulation, FALSE, "terminateSimulation")?;
        }
        inst.completed_integrator_step()?;
        Ok(Status::Ok)
    })
}

/// fmi2SetTime (3.2.1).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetTime(c: Component, time: Real) -> Status {
    guarded(c, Func::SetTime, |inst| {
        inst.set_time(time)?;
        Ok(Status::Ok)
    })
}

/// fmi2SetContinuousStates (3.2.1).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(c: Component, x: *const Real, nx: size_t) -> Status {
    guarded(c, Func::SetContinuousStates, |inst| {
        // SAFETY: nx elements, per FMI.
        inst.set_continuous_states(unsafe { slice(x, nx, "x")? })?;
        Ok(Status::Ok)
    })
}

/// fmi2GetDerivatives (3.2.2).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(c: Component, derivatives: *mut Real, nx: size_t) -> Status {
    guarded(c, Func::GetDerivatives, |inst| {
        // SAFETY: nx writable elements, per FMI.
        inst.derivatives(unsafe { slice_mut(derivatives, nx, "derivatives")? })?;
        Ok(Status::Ok)
    })
}

/// fmi2GetEventIndicators (3.2.2): there are none.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(c: Component, _eventIndicators: *mut Real, ni: size_t) -> Status {
    guarded(c, Func::GetEventIndicators, |inst| {
        inst.event_indicators(ni)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetContinuousStates (3.2.2).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: Component, x: *mut Real, nx: size_t) -> Status {
    guarded(c, Func::GetContinuousStates, |inst| {
        // SAFETY: nx writable elements, per FMI.
        inst.continuous_states(unsafe { slice_mut(x, nx, "x")? })?;
        Ok(Status::Ok)
    })
}

/// fmi2GetNominalsOfContinuousStates (3.2.2).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(c: Component, x_nominal: *mut Real, nx: size_t) -> Status {
    guarded(c, Func::GetNominalsOfContinuousStates, |inst| {
        // SAFETY: nx writable elements, per FMI.
        inst.nominals(unsafe { slice_mut(x_nominal, nx, "x_nominal")? })?;
        Ok(Status::Ok)
    })
}
