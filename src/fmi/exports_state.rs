//! FMI 2.0 FMU state functions (2.1.8 Getting and Setting the Complete FMU State).
//! An fmi2FMUstate is a handle of the instance's [`StateHandles`]: one it did not hand
//! out, or one already freed, is refused with fmi2Error.
//!
//! Safety of every export: as in `exports_common`.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::fmu_state::FmuState;
use super::guard::{get, guarded, put, slice, slice_mut};
use super::state_handles::StateHandles;
use super::state_machine::Func;
use super::types::{Byte, Component, FmuStatePtr, Status};
use libc::size_t;

/// Store `s` through the host's `out` (`*out` NULL: a new state; else the live state
/// there is overwritten, as FMI specifies).
///
/// # Safety
/// `out` is NULL or valid for reads and writes of one fmi2FMUstate.
unsafe fn store(handles: &mut StateHandles, out: *mut FmuStatePtr, s: FmuState) -> Result<(), String> {
    // SAFETY: per this function's contract.
    let old = unsafe { get(out, "FMUstate") }?;
    let p = handles.store(old, s)?;
    // SAFETY: per this function's contract.
    unsafe { put(out, p, "FMUstate") }
}

/// fmi2GetFMUstate: a copy of the complete state.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, FMUstate: *mut FmuStatePtr) -> Status {
    guarded(c, Func::GetFmuState, |inst| {
        // SAFETY: per the module's contract.
        let s = inst.save_state();
        // SAFETY: per the module's contract.
        unsafe { store(&mut inst.states, FMUstate, s) }?;
        Ok(Status::Ok)
    })
}

/// fmi2SetFMUstate: continue from a state this instance saved (another instance's state
/// arrives through fmi2SerializeFMUstate / fmi2DeSerializeFMUstate).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, FMUstate: FmuStatePtr) -> Status {
    guarded(c, Func::SetFmuState, |inst| {
        let s = inst.states.get(FMUstate)?.clone();
        inst.restore_state(&s)?;
        Ok(Status::Ok)
    })
}

/// fmi2FreeFMUstate: release a state; `*FMUstate` becomes NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, FMUstate: *mut FmuStatePtr) -> Status {
    guarded(c, Func::FreeFmuState, |inst| {
        // SAFETY: per the module's contract.
        inst.states.free(unsafe { get(FMUstate, "FMUstate") }?)?;
        // SAFETY: per the module's contract.
        unsafe { put(FMUstate, std::ptr::null_mut(), "FMUstate") }?;
        Ok(Status::Ok)
    })
}

/// fmi2SerializedFMUstateSize: bytes fmi2SerializeFMUstate writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(c: Component, FMUstate: FmuStatePtr, size: *mut size_t) -> Status {
    guarded(c, Func::SerializedFmuStateSize, |inst| {
        let n = inst.states.get(FMUstate)?.to_bytes().len();
        // SAFETY: a writable size_t per FMI.
        unsafe { put(size, n, "size") }?;
        Ok(Status::Ok)
    })
}

/// fmi2SerializeFMUstate: the state as bytes (`size` from fmi2SerializedFMUstateSize).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Component,
    FMUstate: FmuStatePtr,
    serializedState: *mut Byte,
    size: size_t,
) -> Status {
    guarded(c, Func::SerializeFmuState, |inst| {
        let bytes = inst.states.get(FMUstate)?.to_bytes();
        if size < bytes.len() {
            return Err(format!("size {size} is less than the {} bytes of the state", bytes.len()));
        }
        // SAFETY: `size` writable bytes per FMI.
        let out = unsafe { slice_mut(serializedState.cast::<u8>(), size, "serializedState") }?;
        out[..bytes.len()].copy_from_slice(&bytes);
        Ok(Status::Ok)
    })
}

/// fmi2DeSerializeFMUstate: a state from bytes fmi2SerializeFMUstate wrote.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Component,
    serializedState: *const Byte,
    size: size_t,
    FMUstate: *mut FmuStatePtr,
) -> Status {
    guarded(c, Func::DeSerializeFmuState, |inst| {
        // SAFETY: `size` readable bytes per FMI.
        let bytes = unsafe { slice(serializedState.cast::<u8>(), size, "serializedState") }?;
        let s = FmuState::from_bytes(bytes)?;
        if s.guid != inst.guid {
            return Err(format!("the state belongs to FMU {}, not to this FMU {}", s.guid, inst.guid));
        }
        // SAFETY: per the module's contract.
        unsafe { store(&mut inst.states, FMUstate, s) }?;
        Ok(Status::Ok)
    })
}
