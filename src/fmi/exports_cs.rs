//! FMI 2.0 Co-Simulation functions (4.2 FMI Application Programming Interface): stepping,
//! input and output derivatives, status inquiry; and fmi2GetDirectionalDerivative.
//!
//! Safety of every export: as in `exports_common`.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::guard::{guarded, put, slice, slice_mut};
use super::instance::Step;
use super::state_machine::{Func, State};
use super::types::{
    Boolean, Component, DO_STEP_STATUS, FALSE, FmiString, Integer, LAST_SUCCESSFUL_TIME, Real, Status, TERMINATED,
    ValueReference,
};
use libc::{c_int, size_t};

/// fmi2DoStep (4.2.2 Computation): integrate from `currentCommunicationPoint` (which must
/// be the current time) over `communicationStepSize`. An engine failure gives fmi2Discard,
/// state StepFailed, and fmi2LastSuccessfulTime = the time reached.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: Component,
    currentCommunicationPoint: Real,
    communicationStepSize: Real,
    _noSetFMUStatePriorToCurrentPoint: Boolean,
) -> Status {
    guarded(c, Func::DoStep, |inst| match inst.do_step(currentCommunicationPoint, communicationStepSize)? {
        Step::Done => Ok(Status::Ok),
        Step::Failed(msg) => {
            inst.log(Status::Discard, &format!("fmi2DoStep: {msg}"));
            Ok(Status::Discard)
        }
    })
}

/// fmi2CancelStep (4.2.2): fmi2DoStep runs synchronously, so there is nothing to cancel.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: Component) -> Status {
    guarded(c, Func::CancelStep, |_| Err("not supported: fmi2DoStep runs synchronously (never fmi2Pending)".into()))
}

/// fmi2SetRealInputDerivatives (4.2.1 Transfer of Input / Output Values and Parameters):
/// order 1 only; the input then changes linearly until set again.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    order: *const Integer,
    value: *const Real,
) -> Status {
    guarded(c, Func::SetRealInputDerivatives, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, order, value) =
            unsafe { (slice(vr, nvr, "vr")?, slice(order, nvr, "order")?, slice(value, nvr, "value")?) };
        inst.set_input_derivatives(vr, order, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetRealOutputDerivatives (4.2.1): order 1, from the engine.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    order: *const Integer,
    value: *mut Real,
) -> Status {
    guarded(c, Func::GetRealOutputDerivatives, |inst| {
        // SAFETY: nvr elements each, per FMI.
        let (vr, order, value) =
            unsafe { (slice(vr, nvr, "vr")?, slice(order, nvr, "order")?, slice_mut(value, nvr, "value")?) };
        inst.output_derivatives(vr, order, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetDirectionalDerivative (2.1.9 Getting Partial Derivatives): rows and columns of
/// the exact linearization A, B, C, D (seed Eq. 34) at the current communication point.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: Component,
    vUnknown_ref: *const ValueReference,
    nUnknown: size_t,
    vKnown_ref: *const ValueReference,
    nKnown: size_t,
    dvKnown: *const Real,
    dvUnknown: *mut Real,
) -> Status {
    guarded(c, Func::GetDirectionalDerivative, |inst| {
        // SAFETY: nUnknown / nKnown elements each, per FMI.
        let (u, k, dv, out) = unsafe {
            (
                slice(vUnknown_ref, nUnknown, "vUnknown_ref")?,
                slice(vKnown_ref, nKnown, "vKnown_ref")?,
                slice(dvKnown, nKnown, "dvKnown")?,
                slice_mut(dvUnknown, nUnknown, "dvUnknown")?,
            )
        };
        inst.directional_derivative(u, k, dv, out)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetStatus (4.2.3 Retrieving Status Information from the Slave): fmi2DoStepStatus
/// only; steps never pend, so it reports how the last step ended.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(c: Component, s: c_int, value: *mut Status) -> Status {
    guarded(c, Func::GetStatus, |inst| {
        if s != DO_STEP_STATUS {
            return Err(format!("status kind {s} is not available (only fmi2DoStepStatus)"));
        }
        let v = if inst.state == State::StepFailed { Status::Discard } else { Status::Ok };
        // SAFETY: a writable fmi2Status per FMI.
        unsafe { put(value, v, "value") }?;
        Ok(Status::Ok)
    })
}

/// fmi2GetRealStatus (4.2.3): fmi2LastSuccessfulTime.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, s: c_int, value: *mut Real) -> Status {
    guarded(c, Func::GetRealStatus, |inst| {
        if s != LAST_SUCCESSFUL_TIME {
            return Err(format!("status kind {s} is not available (only fmi2LastSuccessfulTime)"));
        }
        // SAFETY: a writable fmi2Real per FMI.
        unsafe { put(value, inst.last_time, "value") }?;
        Ok(Status::Ok)
    })
}

/// fmi2GetIntegerStatus (4.2.3): no Integer status exists.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(c: Component, s: c_int, _value: *mut Integer) -> Status {
    guarded(c, Func::GetIntegerStatus, |_| Err(format!("status kind {s} has no Integer value")))
}

/// fmi2GetBooleanStatus (4.2.3): fmi2Terminated, always false (the slave never ends a
/// simulation by itself).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(c: Component, s: c_int, value: *mut Boolean) -> Status {
    guarded(c, Func::GetBooleanStatus, |_| {
        if s != TERMINATED {
            return Err(format!("status kind {s} is not available (only fmi2Terminated)"));
        }
        // SAFETY: a writable fmi2Boolean per FMI.
        unsafe { put(value, FALSE, "value") }?;
        Ok(Status::Ok)
    })
}

/// fmi2GetStringStatus (4.2.3): fmi2PendingStatus never applies (no asynchronous steps).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(c: Component, s: c_int, _value: *mut FmiString) -> Status {
    guarded(c, Func::GetStringStatus, |_| Err(format!("status kind {s} is not available (no asynchronous steps)")))
}
