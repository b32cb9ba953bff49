//! The wrapper every export runs in: the handle check (NULL, foreign, freed or busy
//! components are refused), the state-machine guard, panic containment (a Rust panic must
//! never unwind into the host), a stack of known size for the engine, and the logging of
//! errors. Also the checked conversions of the host's array and string arguments.

use super::handle::enter;
use super::instance::Instance;
use super::state_machine::{Func, State, check};
use super::types::{Component, Status};
use std::ffi::{CStr, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Stack the engine may use below the host's stack pointer. Measured on 2026-12-02: the
/// full lifecycle of every example model (instantiation, initialization, steps, every
/// directional derivative, FMU state round trip) run directly on a host thread needed a
/// thread stack of 384 KiB (benchmark bicycle, four-bar, slider crank, cart with PID; the
/// host's own frames included) and 192 KiB for the smallest. With less than this left
/// (small host threads: musl's 128 KiB default, worker pools) the work runs on a stack of
/// [`ENGINE_STACK`] instead.
pub const RED_ZONE: usize = 2 << 20;

/// Size of the stack the work runs on when the host's has less than [`RED_ZONE`] left.
/// Memory is committed only as the stack is touched.
pub const ENGINE_STACK: usize = 16 << 20;

/// Run `f` with at least [`RED_ZONE`] bytes of stack (on a stack of its own if the
/// caller's has less left).
pub fn with_stack<R>(f: impl FnOnce() -> R) -> R {
    stacker::maybe_grow(RED_ZONE, ENGINE_STACK, f)
}

/// The text of a panic payload.
pub fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Run `body` on the instance `c` if `func` is legal in its state. `Err(msg)` becomes
/// fmi2Error with "fmi2X: msg" logged (category logStatusError); a state change is logged
/// under logEvents; a panic becomes fmi2Error and state Error, or
/// fmi2Fatal and state Fatal when the function may have left the engine half-updated.
/// A component that is not a live instance gives fmi2Error (there is no logger to tell);
/// one busy with another call (the host's logger calling back, a second thread) gives
/// fmi2Error and a message. The messages reach the host's logger after `body` is done.
pub fn guarded(c: Component, func: Func, body: impl FnOnce(&mut Instance) -> Result<Status, String>) -> Status {
    guarded_as(c, func, None, body)
}

/// [`guarded`] for a function whose C name is `name` rather than the table's (the FMI 3
/// functions of what the FMU lacks share one row, [`Func::Unsupported`]).
pub fn guarded_as(
    c: Component,
    func: Func,
    name: Option<&'static str>,
    body: impl FnOnce(&mut Instance) -> Result<Status, String>,
) -> Status {
    let mut session = match enter(c) {
        Ok(s) => s,
        Err(refused) => {
            refused.report_for(func, name);
            return Status::Error;
        }
    };
    let inst = session.instance();
    let standard = inst.standard;
    let fname = name.unwrap_or_else(|| func.name_in(standard));
    let run = catch_unwind(AssertUnwindSafe(|| {
        if let Err(msg) = check(inst.state, func, standard, fname) {
            inst.log(Status::Error, &msg);
            return Status::Error;
        }
        let before = inst.state;
        let status = with_stack(|| body(inst)).unwrap_or_else(|msg| {
            inst.log(Status::Error, &format!("{fname}: {msg}"));
            Status::Error
        });
        if inst.state != before {
            inst.log(Status::Ok, &format!("{fname}: state {before:?} -> {:?}", inst.state));
        }
        status
    }));
    let status = run.unwrap_or_else(|payload| {
        let what = panic_text(payload.as_ref());
        let (status, state) =
            if func.rule().panic_is_fatal { (Status::Fatal, State::Fatal) } else { (Status::Error, State::Error) };
        let _ = catch_unwind(AssertUnwindSafe(|| {
            let inst = session.instance();
            inst.state = state;
            inst.log(status, &format!("{fname}: internal error (panic): {what}"));
        }));
        status
    });
    session.finish();
    status
}

/// The host's array `p` of `n` elements (empty when n = 0, whatever `p` is).
///
/// # Safety
/// When `n > 0` and `p` is not NULL, `p` must point to `n` readable elements.
pub unsafe fn slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], String> {
    if n == 0 {
        return Ok(&[]);
    }
    check_array(p, n, what)?;
    // SAFETY: non-NULL, aligned, of a valid size, and the caller guarantees n elements.
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
    check_array(p.cast_const(), n, what)?;
    // SAFETY: non-NULL, aligned, of a valid size, and the caller guarantees n exclusive
    // elements.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// What can be checked of an array argument of `n` > 0 elements: not NULL, aligned for
/// `T`, and no larger than a Rust slice may be.
fn check_array<T>(p: *const T, n: usize, what: &str) -> Result<(), String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    if !p.is_aligned() {
        return Err(format!("{what} ({p:p}) is not aligned for its element type"));
    }
    if n.checked_mul(size_of::<T>().max(1)).is_none_or(|b| b > isize::MAX as usize) {
        return Err(format!("{what}: {n} elements is more than an array can hold"));
    }
    Ok(())
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

/// Read the value behind the host's pointer `p`.
///
/// # Safety
/// If not NULL, `p` must be valid for a read of `T`.
pub unsafe fn get<T: Copy>(p: *const T, what: &str) -> Result<T, String> {
    check_array(p, 1, what)?;
    // SAFETY: non-NULL, aligned and readable per the caller.
    Ok(unsafe { p.read() })
}

/// Write `v` through the host's out-pointer `p`.
///
/// # Safety
/// If not NULL, `p` must be valid for a write of `T`.
pub unsafe fn put<T>(p: *mut T, v: T, what: &str) -> Result<(), String> {
    check_array(p.cast_const(), 1, what)?;
    // SAFETY: non-NULL, aligned and writable per the caller.
    unsafe { p.write(v) };
    Ok(())
}
