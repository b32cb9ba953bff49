//! The wrapper every export runs in: NULL-instance check, the state-machine guard, panic
//! containment (a Rust panic must never unwind into the host), and the logging of errors.
//! Also the checked conversions of the host's array and string arguments.

use super::instance::Instance;
use super::state_machine::{Func, State, check};
use super::types::{Component, Status};
use std::ffi::{CStr, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Run `body` on the instance `c` if `func` is legal in its state. `Err(msg)` becomes
/// fmi2Error with "fmi2X: msg" logged (category logStatusError); a state change is logged
/// under logEvents; a panic becomes fmi2Error and state Error, or
/// fmi2Fatal and state Fatal when the function may have left the engine half-updated.
/// A NULL `c` gives fmi2Error (there is no logger to tell).
pub fn guarded(c: Component, func: Func, body: impl FnOnce(&mut Instance) -> Result<Status, String>) -> Status {
    if c.is_null() {
        return Status::Error;
    }
    let inst = c.cast::<Instance>();
    let run = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: `c` is non-NULL and, as FMI 2.0 requires of the host, a pointer that
        // fmi2Instantiate returned and fmi2FreeInstance has not freed; the host calls an
        // instance from one thread at a time, so this is the only reference.
        let inst = unsafe { &mut *inst };
        if let Err(msg) = check(inst.state, func) {
            inst.log(Status::Error, &msg);
            return Status::Error;
        }
        let before = inst.state;
        let status = body(inst).unwrap_or_else(|msg| {
            inst.log(Status::Error, &format!("{}: {msg}", func.name()));
            Status::Error
        });
        if inst.state != before {
            inst.log(Status::Ok, &format!("{}: state {before:?} -> {:?}", func.name(), inst.state));
        }
        status
    }));
    run.unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        let (status, state) =
            if func.rule().panic_is_fatal { (Status::Fatal, State::Fatal) } else { (Status::Error, State::Error) };
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: as above; the reference of the panicked closure is gone.
            let inst = unsafe { &mut *inst };
            inst.state = state;
            inst.log(status, &format!("{}: internal error (panic): {what}", func.name()));
        }));
        status
    })
}

/// The host's array `p` of `n` elements (empty when n = 0, whatever `p` is).
///
/// # Safety
/// When `n > 0` and `p` is not NULL, `p` must point to `n` readable elements.
pub unsafe fn slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], String> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: non-NULL, and the caller guarantees n elements.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// The host's writable array `p` of `n` elements.
///
/// # Safety
/// When `n > 0` and `p` is not NULL, `p` must point to `n` writable elements not aliased
/// by any other argument.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, what: &str) -> Result<&'a mut [T], String> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: non-NULL, and the caller guarantees n exclusive elements.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// The host's string `p` (UTF-8 expected).
///
/// # Safety
/// If not NULL, `p` must be a NUL-terminated string.
pub unsafe fn text(p: *const c_char, what: &str) -> Result<String, String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: non-NULL and NUL-terminated per the caller.
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str().map(str::to_string).map_err(|_| format!("{what} is not UTF-8"))
}

/// Write `v` through the host's out-pointer `p`.
///
/// # Safety
/// If not NULL, `p` must be valid for a write of `T`.
pub unsafe fn put<T>(p: *mut T, v: T, what: &str) -> Result<(), String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: non-NULL and writable per the caller.
    unsafe { p.write(v) };
    Ok(())
}
