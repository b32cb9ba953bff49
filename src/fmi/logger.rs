//! Logging through the host's fmi2CallbackLogger (2.1.5), filtered by the categories of
//! fmi2SetDebugLogging. An instance only queues its messages ([`Logger`]); the handle
//! hands them to the host ([`Sink`]) after the call's work is done, when no reference
//! into the instance is alive, so a logger that calls back into the FMU cannot alias it.
//! The text is always passed as the argument of a `"%s"` format, so a `%` in a message
//! (a path, a user name) is never read as a conversion.

use super::types::{CallbackFunctions, ComponentEnvironment, LogMessageFn, LoggerFn, Status};
use super::variables::Standard;
use std::collections::VecDeque;
use std::ffi::{CStr, CString};

/// The log categories (modelDescription.xml `LogCategories`) and what each carries.
pub const CATEGORIES: [(&CStr, &str); 6] = [
    (c"logEvents", "Calls and state changes"),
    (c"logStatusWarning", "Messages of calls returning Warning"),
    (c"logStatusDiscard", "Messages of calls returning Discard"),
    (c"logStatusError", "Messages of calls returning Error"),
    (c"logStatusFatal", "Messages of calls returning Fatal"),
    (c"logAll", "Every message"),
];

/// How many recent messages an instance keeps for inspection (tests, diagnostics).
const RECENT: usize = 64;

/// The category of a message with this status.
fn category(status: Status) -> &'static CStr {
    match status {
        Status::Ok | Status::Pending => CATEGORIES[0].0,
        Status::Warning => CATEGORIES[1].0,
        Status::Discard => CATEGORIES[2].0,
        Status::Error => CATEGORIES[3].0,
        Status::Fatal => CATEGORIES[4].0,
    }
}

/// One instance's log filter and the messages waiting for the host.
#[derive(Default)]
pub struct Logger {
    /// loggingOn of fmi2Instantiate / fmi2SetDebugLogging.
    on: bool,
    /// Enabled categories (None: all).
    enabled: Option<Vec<&'static CStr>>,
    recent: VecDeque<String>,
    pending: Vec<(Status, String)>,
}

impl Logger {
    /// A logger with logging `on` (loggingOn of fmi2Instantiate) and every category.
    pub fn new(on: bool) -> Logger {
        Logger { on, ..Logger::default() }
    }

    /// fmi2SetDebugLogging: switch logging and choose categories (none listed: all).
    pub fn configure(&mut self, on: bool, categories: &[String]) -> Result<(), String> {
        let mut chosen = Vec::new();
        for c in categories {
            let known = CATEGORIES.iter().find(|(k, _)| k.to_bytes() == c.as_bytes());
            chosen.push(known.ok_or_else(|| format!("unknown log category '{c}'"))?.0);
        }
        self.on = on;
        self.enabled = if chosen.is_empty() { None } else { Some(chosen) };
        Ok(())
    }

    /// Whether a message with `status` reaches the host. With logging off only those of
    /// failed calls (fmi2Discard, fmi2Error, fmi2Fatal) do: the host must learn why a call
    /// or a step failed.
    fn passes(&self, status: Status) -> bool {
        if !self.on {
            return matches!(status, Status::Discard | Status::Error | Status::Fatal);
        }
        match &self.enabled {
            None => true,
            Some(cats) => cats.iter().any(|c| *c == category(status) || *c == CATEGORIES[5].0),
        }
    }

    /// Log `msg` with `status` (its category follows from the status): queued for the
    /// host if it passes the filter.
    pub fn log(&mut self, status: Status, msg: &str) {
        if !self.passes(status) {
            return;
        }
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(msg.to_string());
        self.pending.push((status, msg.to_string()));
    }

    /// The queued messages, oldest first (the queue is left empty).
    pub fn take_pending(&mut self) -> Vec<(Status, String)> {
        std::mem::take(&mut self.pending)
    }

    /// The most recent messages that passed the filter, oldest first.
    pub fn recent(&self) -> Vec<String> {
        self.recent.iter().cloned().collect()
    }
}

/// The host's logger callback of either FMI version.
#[derive(Clone, Copy)]
enum Callback {
    /// fmi2CallbackLogger (with the instance name and a printf format).
    Fmi2(LoggerFn),
    /// fmi3LogMessageCallback (the message as is).
    Fmi3(LogMessageFn),
}

/// The host's logger callback, its environment and the instance name.
#[derive(Clone)]
pub struct Sink {
    callback: Option<Callback>,
    env: ComponentEnvironment,
    name: CString,
    standard: Standard,
}

impl Sink {
    /// The sink of FMI 2 instance `name` with the host's callbacks.
    pub fn new(callbacks: &CallbackFunctions, name: &str) -> Sink {
        let (callback, env) = (callbacks.logger.map(Callback::Fmi2), callbacks.component_environment);
        Sink { callback, env, name: c_text(name), standard: Standard::Fmi2 }
    }

    /// The sink of FMI 3 instance `name` with the host's `logMessage` and
    /// `instanceEnvironment`.
    pub fn fmi3(log: Option<LogMessageFn>, env: ComponentEnvironment, name: &str) -> Sink {
        Sink { callback: log.map(Callback::Fmi3), env, name: c_text(name), standard: Standard::Fmi3 }
    }

    /// The FMI version of the instance (whose function names its messages use).
    pub fn standard(&self) -> Standard {
        self.standard
    }

    /// Hand `msg` to the host's logger (nothing when it gave none).
    pub fn emit(&self, status: Status, msg: &str) {
        let Some(callback) = self.callback else { return };
        let text = c_text(msg);
        match callback {
            // SAFETY: `cb` is the host's fmi2CallbackLogger; every pointer passed is a valid
            // NUL-terminated string living across the call, and the format "%s" consumes
            // exactly the one string argument given.
            Callback::Fmi2(cb) => unsafe {
                cb(
                    self.env,
                    self.name.as_ptr(),
                    status as libc::c_int,
                    category(status).as_ptr(),
                    c"%s".as_ptr(),
                    text.as_ptr(),
                )
            },
            // SAFETY: `cb` is the host's fmi3LogMessageCallback; the strings are valid and
            // NUL-terminated across the call.
            Callback::Fmi3(cb) => unsafe {
                cb(self.env, status as libc::c_int, category(status).as_ptr(), text.as_ptr())
            },
        }
    }
}

/// A C string of `s` (an interior NUL becomes a space).
fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("NULs replaced")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn categories_filter_what_reaches_the_host() {
        let mut l = Logger::new(false);
        l.log(Status::Ok, "event");
        l.log(Status::Warning, "warning");
        l.log(Status::Discard, "step stopped");
        l.log(Status::Error, "error");
        assert_eq!(l.recent(), ["step stopped", "error"], "logging off: failed calls only");
        l.configure(true, &["logStatusDiscard".into()]).unwrap();
        l.log(Status::Ok, "event");
        l.log(Status::Discard, "discard");
        assert_eq!(l.recent(), ["step stopped", "error", "discard"]);
        let pending = l.take_pending();
        assert_eq!(
            pending.iter().map(|(s, _)| *s).collect::<Vec<_>>(),
            [Status::Discard, Status::Error, Status::Discard]
        );
        assert!(l.take_pending().is_empty());
        assert!(l.configure(true, &["nonsense".into()]).is_err());
    }
}
