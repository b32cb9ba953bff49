//! FMI 3.0 Model Exchange functions (3.2 Model Exchange): the host sets time and the
//! continuous states (the linearization states) and reads their derivatives; the model
//! has no events and no event indicators, so Event Mode only passes through. Each is a
//! thin entry over the instance's Model Exchange ([`super::exchange`]), the one the FMI 2
//! exports use.
//!
//! Safety of every export: as in `exports3_common`.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::exports3_common::Bool3;
use super::guard::{guarded, put, slice, slice_mut};
use super::state_machine::Func;
use super::types::{Component, Status};
use libc::size_t;

/// fmi3EnterContinuousTimeMode: from Event Mode (Model Exchange instances only).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: Component) -> Status {
    guarded(c, Func::EnterContinuousTimeMode, |inst| {
        inst.enter_continuous_time_mode()?;
        Ok(Status::Ok)
    })
}

/// fmi3CompletedIntegratorStep: the accepted point is solved and kept as the one later
/// points continue from (a step through a fold of the states' chart is fmi3Error); no
/// event, no termination.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    c: Component,
    _noSetFMUStatePriorToCurrentPoint: Bool3,
    enterEventMode: *mut Bool3,
    terminateSimulation: *mut Bool3,
) -> Status {
    guarded(c, Func::CompletedIntegratorStep, |inst| {
        // SAFETY: the host's out-arguments, per FMI.
        unsafe {
            put(enterEventMode, 0, "enterEventMode")?;
            put(terminateSimulation, 0, "terminateSimulation")?;
        }
        inst.completed_integrator_step()?;
        Ok(Status::Ok)
    })
}

/// fmi3SetTime.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetTime(c: Component, time: f64) -> Status {
    guarded(c, Func::SetTime, |inst| {
        inst.set_time(time)?;
        Ok(Status::Ok)
    })
}

/// fmi3SetContinuousStates: x in the order of the `<ContinuousStateDerivative>` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    c: Component,
    continuousStates: *const f64,
    nContinuousStates: size_t,
) -> Status {
    guarded(c, Func::SetContinuousStates, |inst| {
        // SAFETY: nContinuousStates elements, per FMI.
        inst.set_continuous_states(unsafe { slice(continuousStates, nContinuousStates, "continuousStates")? })?;
        Ok(Status::Ok)
    })
}

/// fmi3GetContinuousStateDerivatives: ẋ at (time, x).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    c: Component,
    derivatives: *mut f64,
    nContinuousStates: size_t,
) -> Status {
    guarded(c, Func::GetDerivatives, |inst| {
        // SAFETY: nContinuousStates writable elements, per FMI.
        inst.derivatives(unsafe { slice_mut(derivatives, nContinuousStates, "derivatives")? })?;
        Ok(Status::Ok)
    })
}

/// fmi3GetEventIndicators: there are none.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    c: Component,
    _eventIndicators: *mut f64,
    nEventIndicators: size_t,
) -> Status {
    guarded(c, Func::GetEventIndicators, |inst| {
        inst.event_indicators(nEventIndicators)?;
        Ok(Status::Ok)
    })
}

/// fmi3GetContinuousStates.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    c: Component,
    continuousStates: *mut f64,
    nContinuousStates: size_t,
) -> Status {
    guarded(c, Func::GetContinuousStates, |inst| {
        // SAFETY: nContinuousStates writable elements, per FMI.
        inst.continuous_states(unsafe { slice_mut(continuousStates, nContinuousStates, "continuousStates")? })?;
        Ok(Status::Ok)
    })
}

/// fmi3GetNominalsOfContinuousStates.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    c: Component,
    nominals: *mut f64,
    nContinuousStates: size_t,
) -> Status {
    guarded(c, Func::GetNominalsOfContinuousStates, |inst| {
        // SAFETY: nContinuousStates writable elements, per FMI.
        inst.nominals(unsafe { slice_mut(nominals, nContinuousStates, "nominals")? })?;
        Ok(Status::Ok)
    })
}

/// fmi3GetNumberOfEventIndicators: 0.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(c: Component, nEventIndicators: *mut size_t) -> Status {
    guarded(c, Func::GetNumberOfEventIndicators, |inst| {
        inst.event_indicators(0)?;
        // SAFETY: a writable size_t, per FMI.
        unsafe { put(nEventIndicators, 0, "nEventIndicators")? };
        Ok(Status::Ok)
    })
}

/// fmi3GetNumberOfContinuousStates: the number of linearization states.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: Component, nContinuousStates: *mut size_t) -> Status {
    guarded(c, Func::GetNumberOfContinuousStates, |inst| {
        let n = inst.continuous_state_count()?;
        // SAFETY: a writable size_t, per FMI.
        unsafe { put(nContinuousStates, n, "nContinuousStates")? };
        Ok(Status::Ok)
    })
}
