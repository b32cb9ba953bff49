//! Logging through the host's fmi2CallbackLogger (2.1.5), filtered by the categories of
//! fmi2SetDebugLogging. The text is always passed as the argument of a `"%s"` format, so
//! a `%` in a message (a path, a user name) is never read as a conversion.

use super::types::{CallbackFunctions, ComponentEnvironment, LoggerFn, Status};
use std::collections::VecDeque;
use std::ffi::{CStr, CString};

/// The log categories (modelDescription.xml `LogCategories`) and what each carries.
pub const CATEGORIES: [(&CStr, &str); 6] = [
    (c"logEvents", "Calls and state changes"),
    (c"logStatusWarning", "Messages of calls returning fmi2Warning"),
    (c"logStatusDiscard", "Messages of calls returning fmi2Discard"),
    (c"logStatusError", "Messages of calls returning fmi2Error"),
    (c"logStatusFatal", "Messages of calls returning fmi2Fatal"),
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

/// One instance's logger.
pub struct Logger {
    callback: Option<LoggerFn>,
    env: ComponentEnvironment,
    name: CString,
    /// loggingOn of fmi2Instantiate / fmi2SetDebugLogging.
    on: bool,
    /// Enabled categories (None: all).
    enabled: Option<Vec<&'static CStr>>,
    recent: VecDeque<String>,
}

impl Logger {
    /// A logger for instance `name` with the host's callbacks.
    pub fn new(callbacks: &CallbackFunctions, name: &str, on: bool) -> Logger {
        Logger {
            callback: callbacks.logger,
            env: callbacks.component_environment,
            name: c_text(name),
            on,
            enabled: None,
            recent: VecDeque::new(),
        }
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

    /// Whether a message with `status` reaches the host. With logging off only errors
    /// (fmi2Error, fmi2Fatal) do: the host must learn why a call failed.
    fn passes(&self, status: Status) -> bool {
        if !self.on {
            return status >= Status::Error;
        }
        match &self.enabled {
            None => true,
            Some(cats) => cats.iter().any(|c| *c == category(status) || *c == CATEGORIES[5].0),
        }
    }

    /// Log `msg` with `status` (its category follows from the status).
    pub fn log(&mut self, status: Status, msg: &str) {
        if !self.passes(status) {
            return;
        }
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(msg.to_string());
        if let Some(cb) = self.callback {
            let text = c_text(msg);
            // SAFETY: `cb` is the host's fmi2CallbackLogger; every pointer passed is a valid
            // NUL-terminated string living across the call, and the format "%s" consumes
            // exactly the one string argument given.
            unsafe {
                cb(
                    self.env,
                    self.name.as_ptr(),
                    status as libc::c_int,
                    category(status).as_ptr(),
                    c"%s".as_ptr(),
                    text.as_ptr(),
                )
            };
        }
    }

    /// The most recent messages that passed the filter, oldest first.
    pub fn recent(&self) -> Vec<String> {
        self.recent.iter().cloned().collect()
    }
}

/// A C string of `s` (an interior NUL becomes a space).
fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("NULs replaced")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn logger(on: bool) -> Logger {
        let cb = CallbackFunctions {
            logger: None,
            allocate_memory: None,
            free_memory: None,
            step_finished: None,
            component_environment: std::ptr::null_mut(),
        };
        Logger::new(&cb, "inst", on)
    }

    #[test]
    fn categories_filter_what_reaches_the_host() {
        let mut l = logger(false);
        l.log(Status::Ok, "event");
        l.log(Status::Error, "error");
        assert_eq!(l.recent(), ["error"]);
        l.configure(true, &["logStatusDiscard".into()]).unwrap();
        l.log(Status::Ok, "event");
        l.log(Status::Discard, "discard");
        assert_eq!(l.recent(), ["error", "discard"]);
        assert!(l.configure(true, &["nonsense".into()]).is_err());
    }
}
