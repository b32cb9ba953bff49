//! FMI 3.0 Co-Simulation functions (4.2 Co-Simulation): Step Mode, stepping and output
//! derivatives, over the same shell as the FMI 2 exports.
//!
//! Safety of every export: as in `exports3_common`.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::exports3_common::{Bool3, scalars};
use super::guard::{guarded, put, slice, slice_mut};
use super::instance::Step;
use super::state_machine::Func;
use super::types::{Component, Status, ValueReference};
use libc::size_t;

/// fmi3EnterStepMode: from Event Mode to Step Mode (Co-Simulation instances only).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(c: Component) -> Status {
    guarded(c, Func::EnterStepMode, |inst| {
        inst.enter_step_mode()?;
        Ok(Status::Ok)
    })
}

/// fmi3DoStep: integrate from `currentCommunicationPoint` (the current time) over
/// `communicationStepSize`. Never returns early and needs no event handling; an engine
/// failure or `solver.maxSteps` reached gives fmi3Discard with `lastSuccessfulTime` the
/// time reached (the FMU stays there: a host may continue from it, restore a saved
/// state, or terminate).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    c: Component,
    currentCommunicationPoint: f64,
    communicationStepSize: f64,
    _noSetFMUStatePriorToCurrentPoint: Bool3,
    eventHandlingNeeded: *mut Bool3,
    terminateSimulation: *mut Bool3,
    earlyReturn: *mut Bool3,
    lastSuccessfulTime: *mut f64,
) -> Status {
    guarded(c, Func::DoStep, |inst| {
        for (p, what) in [
            (eventHandlingNeeded, "eventHandlingNeeded"),
            (terminateSimulation, "terminateSimulation"),
            (earlyReturn, "earlyReturn"),
        ] {
            // SAFETY: a writable fmi3Boolean per FMI.
            unsafe { put(p, 0, what) }?;
        }
        let step = inst.do_step(currentCommunicationPoint, communicationStepSize)?;
        // SAFETY: a writable fmi3Float64 per FMI.
        unsafe { put(lastSuccessfulTime, inst.last_time, "lastSuccessfulTime") }?;
        match step {
            Step::Done => Ok(Status::Ok),
            Step::Failed(msg) => {
                inst.log(Status::Discard, &format!("fmi3DoStep: {msg}"));
                Ok(Status::Discard)
            }
        }
    })
}

/// fmi3GetOutputDerivatives: order 1, from the engine.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    orders: *const i32,
    values: *mut f64,
    nValues: size_t,
) -> Status {
    guarded(c, Func::GetRealOutputDerivatives, |inst| {
        scalars(nvr, nValues)?;
        // SAFETY: nvr elements each, per FMI.
        let (vr, orders, values) = unsafe {
            (slice(vr, nvr, "valueReferences")?, slice(orders, nvr, "orders")?, slice_mut(values, nvr, "values")?)
        };
        inst.output_derivatives(vr, orders, values)?;
        Ok(Status::Ok)
    })
}
