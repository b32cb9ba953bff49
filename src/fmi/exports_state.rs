//! FMI 2.0 FMU state functions (2.1.8 Getting and Setting the Complete FMU State).
//! An fmi2FMUstate is a `Box<FmuState>` raw pointer.
//!
//! Safety of every export: as in `exports_common`; an fmi2FMUstate passed in must be one
//! this FMU returned and has not freed.
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::fmu_state::FmuState;
use super::guard::{guarded, put, slice, slice_mut};
use super::state_machine::Func;
use super::types::{Byte, Component, FmuStatePtr, Status};
use libc::size_t;

/// The state behind `p`.
///
/// # Safety
/// `p` is NULL or an fmi2FMUstate of this FMU not yet freed.
unsafe fn state_ref<'a>(p: FmuStatePtr) -> Result<&'a FmuState, String> {
    // SAFETY: per this function's contract.
    unsafe { p.cast::<FmuState>().as_ref() }.ok_or_else(|| "FMUstate is NULL".into())
}

/// Store `s` in `*out`: reuse the state there (FMI: a non-NULL `*FMUstate` is one
/// returned before), else allocate.
///
/// # Safety
/// `out` is NULL or writable; `*out` is NULL or an fmi2FMUstate of this FMU not yet freed.
unsafe fn store(out: *mut FmuStatePtr, s: FmuState) -> Result<(), String> {
    if out.is_null() {
        return Err("FMUstate is NULL".into());
    }
    // SAFETY: per this function's contract.
    unsafe {
        let old = (*out).cast::<FmuState>();
        if old.is_null() {
            *out = Box::into_raw(Box::new(s)).cast();
        } else {
            *old = s;
        }
    }
    Ok(())
}

/// fmi2GetFMUstate: a copy of the complete state.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, FMUstate: *mut FmuStatePtr) -> Status {
    guarded(c, Func::GetFmuState, |inst| {
        // SAFETY: per the module's contract.
        unsafe { store(FMUstate, FmuState::capture(inst)) }?;
        Ok(Status::Ok)
    })
}

/// fmi2SetFMUstate: continue from a saved state (also one of another instance of this FMU).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, FMUstate: FmuStatePtr) -> Status {
    guarded(c, Func::SetFmuState, |inst| {
        // SAFETY: per the module's contract.
        unsafe { state_ref(FMUstate) }?.restore(inst)?;
        Ok(Status::Ok)
    })
}

/// fmi2FreeFMUstate: release a state; `*FMUstate` becomes NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, FMUstate: *mut FmuStatePtr) -> Status {
    guarded(c, Func::FreeFmuState, |_| {
        if FMUstate.is_null() {
            return Err("FMUstate is NULL".into());
        }
        // SAFETY: per the module's contract; the Box came from `store` and is freed once.
        unsafe {
            let p = (*FMUstate).cast::<FmuState>();
            if !p.is_null() {
                drop(Box::from_raw(p));
            }
            *FMUstate = std::ptr::null_mut();
        }
        Ok(Status::Ok)
    })
}

/// fmi2SerializedFMUstateSize: bytes fmi2SerializeFMUstate writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(c: Component, FMUstate: FmuStatePtr, size: *mut size_t) -> Status {
    guarded(c, Func::SerializedFmuStateSize, |_| {
        // SAFETY: per the module's contract.
        let n = unsafe { state_ref(FMUstate) }?.to_bytes().len();
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
    guarded(c, Func::SerializeFmuState, |_| {
        // SAFETY: per the module's contract.
        let bytes = unsafe { state_ref(FMUstate) }?.to_bytes();
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
        unsafe { store(FMUstate, s) }?;
        Ok(Status::Ok)
    })
}
