//! The fmi2Component the host holds: a handle that no misuse of the host can turn into
//! undefined behaviour. Every live handle is registered, so a NULL, foreign or freed
//! component is refused; a busy flag admits one call at a time, so a call from the host's
//! logger callback (re-entrant) or from a second thread is refused instead of aliasing
//! the instance; the host's logger runs only after the call's work, with no reference
//! into the instance alive.

use super::instance::Instance;
use super::logger::Sink;
use super::state_machine::Func;
use super::types::{Component, Status};
use std::cell::{Cell, UnsafeCell};
use std::collections::BTreeSet;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// An instance with its host-side logger and its call guard.
pub struct Handle {
    /// Set while a call runs on the instance (work and logging).
    busy: AtomicBool,
    sink: Sink,
    inst: UnsafeCell<Instance>,
}

/// Addresses of the live handles.
static LIVE: Mutex<BTreeSet<usize>> = Mutex::new(BTreeSet::new());

thread_local! {
    /// Set while this thread reports a refused re-entrant call, so a logger that calls
    /// back on every message cannot recurse without bound.
    static REPORTING: Cell<bool> = const { Cell::new(false) };
}

fn live() -> std::sync::MutexGuard<'static, BTreeSet<usize>> {
    // The set is consistent whatever panicked while holding it (insert/remove only).
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Why a call cannot enter an instance.
pub enum Refused {
    /// NULL, never returned by fmi2Instantiate, or already freed.
    Unknown,
    /// Another call on the instance is running (re-entrant or concurrent); its logger.
    Busy(Sink),
}

impl Refused {
    /// Tell the host why `func` (of the instance's FMI version; `name` if given) was
    /// refused.
    pub fn report_for(&self, func: Func, name: Option<&str>) {
        if let Refused::Busy(sink) = self {
            self.report(name.unwrap_or_else(|| func.name_in(sink.standard())));
        }
    }

    /// Tell the host (when there is a logger to tell) why `func` was refused.
    pub fn report(&self, func: &str) {
        let Refused::Busy(sink) = self else { return };
        if REPORTING.with(|r| r.replace(true)) {
            return;
        }
        sink.emit(
            Status::Error,
            &format!(
                "{func}: refused: another call on this instance is still running (a call from the logger \
                 callback, or from a second thread; FMI allows one call at a time)"
            ),
        );
        REPORTING.with(|r| r.set(false));
    }
}

/// Exclusive access to an instance for the length of one call.
pub struct Session<'a> {
    h: &'a Handle,
}

/// Register `inst` and return its component.
pub fn create(inst: Instance, sink: Sink) -> Component {
    let h = Box::new(Handle { busy: AtomicBool::new(false), sink, inst: UnsafeCell::new(inst) });
    let p = Box::into_raw(h);
    live().insert(p as usize);
    p.cast()
}

/// Mark the handle `c` busy; the caller holds the lock of the live set.
fn claim<'a>(set: &BTreeSet<usize>, c: Component) -> Result<&'a Handle, Refused> {
    if !set.contains(&(c as usize)) {
        return Err(Refused::Unknown);
    }
    // SAFETY: `c` is a registered handle, and a handle leaves the set (under the lock the
    // caller holds) only while it is busy for `destroy`, which then frees it; a handle
    // claimed here stays busy, hence alive, until its session ends.
    let h = unsafe { &*c.cast::<Handle>() };
    if h.busy.compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed).is_err() {
        return Err(Refused::Busy(h.sink.clone()));
    }
    Ok(h)
}

/// Enter the instance behind `c` for one call.
pub fn enter<'a>(c: Component) -> Result<Session<'a>, Refused> {
    claim(&live(), c).map(|h| Session { h })
}

/// Unregister and free the instance behind `c` (fmi2FreeInstance). A busy instance is
/// left alone.
pub fn destroy(c: Component) -> Result<(), Refused> {
    {
        let mut set = live();
        claim(&set, c)?;
        set.remove(&(c as usize));
    }
    // SAFETY: the handle came from Box::into_raw in `create`; it was claimed and left the
    // set under one lock, so no other reference to it exists or can be made.
    drop(unsafe { Box::from_raw(c.cast::<Handle>()) });
    Ok(())
}

impl Session<'_> {
    /// The instance, exclusively.
    pub fn instance(&mut self) -> &mut Instance {
        // SAFETY: `busy` is set for this session alone, so no other reference to the
        // instance exists; the borrow is tied to `&mut self`.
        unsafe { &mut *self.h.inst.get() }
    }

    /// End the call: hand the queued messages to the host's logger (with no reference
    /// into the instance alive; the instance stays busy, so a call from the logger is
    /// refused), then release the instance.
    pub fn finish(mut self) {
        let pending = self.instance().log.take_pending();
        for (status, msg) in pending {
            self.h.sink.emit(status, &msg);
        }
    }
}

impl Drop for Session<'_> {
    fn drop(&mut self) {
        self.h.busy.store(false, Ordering::Release);
    }
}
