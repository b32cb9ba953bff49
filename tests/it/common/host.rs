//! What a test host of the FMU's C API needs: callbacks without a logger, or instances
//! whose logger records their messages; what an instance tells its logger and which state
//! its answers show; and a resources directory for a model text. Everything goes through
//! the exported FMI functions, as a host's would. A module of the integration tests
//! (tests/it), also included with `#[path]` by tests/memory_alloc.rs and
//! examples/fmu_lifecycle.rs (`common/mod.rs` is the engine-side helpers).

#![allow(dead_code)]

use mbfmu::fmi::exports_common::{fmi2FreeInstance, fmi2GetReal, fmi2Instantiate, fmi2SetReal};
use mbfmu::fmi::exports_cs::{fmi2GetRealStatus, fmi2GetStatus};
use mbfmu::fmi::resources::Interfaces;
use mbfmu::fmi::state_machine::{Func, State};
use mbfmu::fmi::types::{
    CallbackFunctions, Component, ComponentEnvironment, DO_STEP_STATUS, FmiString, LAST_SUCCESSFUL_TIME, LoggerFn,
    Status,
};
use std::collections::BTreeMap;
use std::ffi::{CStr, CString, c_int};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

/// Callbacks without a logger (the instance then has no one to tell its messages).
pub const CALLBACKS: CallbackFunctions = CallbackFunctions {
    logger: None,
    allocate_memory: None,
    free_memory: None,
    step_finished: None,
    component_environment: std::ptr::null_mut(),
};

/// The messages one instance handed its logger, oldest first.
type Log = Mutex<Vec<String>>;

/// The log of every instance made by [`instantiate`], by component (an entry goes with
/// [`free`], or when a new instance gets the address of a freed one).
static LOGS: Mutex<BTreeMap<usize, Arc<Log>>> = Mutex::new(BTreeMap::new());

/// A lock that a panicking test elsewhere cannot poison (the data stay consistent: push,
/// insert, remove).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The logger [`instantiate`] installs: it appends the text to the instance's [`Log`],
/// the component environment. mbfmu calls the (variadic) fmi2CallbackLogger as
/// `logger(env, name, status, category, "%s", text)`; on the x86-64 and AArch64 Linux
/// ABIs the variadic pointer argument is passed like a sixth fixed one, so this
/// six-argument function receives the text unformatted (as tests/python/fmu_helpers.py
/// does; stable Rust cannot define a variadic function). The text is read only when the
/// format is `"%s"`; any other format is recorded as it is, so a test sees it.
unsafe extern "C" fn record(
    env: ComponentEnvironment,
    _name: FmiString,
    _status: c_int,
    _category: FmiString,
    format: FmiString,
    text: FmiString,
) {
    if env.is_null() || format.is_null() {
        return;
    }
    // SAFETY: `env` is the `Log` of an `Arc` that LOGS (or `instantiate`) holds while the
    // instance lives; the strings are NUL-terminated, and `text` is the argument of the
    // "%s" format (read only then).
    let (log, format) = unsafe { (&*env.cast_const().cast::<Log>(), CStr::from_ptr(format)) };
    let msg = if format == c"%s" && !text.is_null() {
        // SAFETY: as above.
        unsafe { CStr::from_ptr(text) }.to_string_lossy().into_owned()
    } else {
        format.to_string_lossy().into_owned()
    };
    lock(log).push(msg);
}

#[cfg(not(any(target_arch = "x86_64", all(target_arch = "aarch64", not(target_vendor = "apple")))))]
compile_error!("the test host's logger needs an ABI that passes a variadic pointer like a fixed argument");

/// fmi2Instantiate with callbacks whose logger records the instance's messages
/// ([`messages`]); free the instance with [`free`].
///
/// # Safety
/// The strings are NUL-terminated (or NULL, which the FMU refuses).
pub unsafe fn instantiate(
    name: FmiString,
    fmu_type: c_int,
    guid: FmiString,
    resources: FmiString,
    visible: c_int,
    logging_on: c_int,
) -> Component {
    // SAFETY: per this function's contract.
    unsafe { instantiate_logged(name, fmu_type, guid, resources, visible, logging_on) }.0
}

/// [`instantiate`], also returning the messages logged during fmi2Instantiate (those of a
/// refused instantiation, which leaves no component to ask [`messages`] with).
///
/// # Safety
/// As [`instantiate`].
pub unsafe fn instantiate_logged(
    name: FmiString,
    fmu_type: c_int,
    guid: FmiString,
    resources: FmiString,
    visible: c_int,
    logging_on: c_int,
) -> (Component, Vec<String>) {
    let log: Arc<Log> = Arc::default();
    // SAFETY: the six-argument logger is called as the variadic type with exactly the
    // arguments it declares (see `record`); the pointer types have one size.
    let logger = unsafe {
        std::mem::transmute::<unsafe extern "C" fn(_, _, _, _, _, FmiString), LoggerFn>(
            record as unsafe extern "C" fn(_, _, _, _, _, _),
        )
    };
    let callbacks = CallbackFunctions {
        logger: Some(logger),
        component_environment: Arc::as_ptr(&log).cast_mut().cast(),
        ..CALLBACKS
    };
    // SAFETY: per this function's contract; the FMU copies the callbacks.
    let c = unsafe { fmi2Instantiate(name, fmu_type, guid, resources, &callbacks, visible, logging_on) };
    let logged = lock(&log).clone();
    if !c.is_null() {
        lock(&LOGS).insert(c as usize, log);
    }
    (c, logged)
}

/// fmi2FreeInstance, and the instance's log with it (out of LOGS first, while the
/// address is still the instance's, and dropped when the instance no longer logs). An
/// emptied LOGS lets go of its node too, so that a host that freed every instance holds
/// no memory (tests/it/memory_valgrind.rs bounds what stays reachable at exit).
pub fn free(c: Component) {
    let log = {
        let mut logs = lock(&LOGS);
        let log = logs.remove(&(c as usize));
        if logs.is_empty() {
            *logs = BTreeMap::new();
        }
        log
    };
    // SAFETY: a component from fmi2Instantiate (freed twice or foreign: refused).
    unsafe { fmi2FreeInstance(c) };
    drop(log);
}

/// The instance's log (None: not made by [`instantiate`]).
fn log_of(c: Component) -> Option<Arc<Log>> {
    lock(&LOGS).get(&(c as usize)).cloned()
}

/// Every message the instance made by [`instantiate`] handed its logger, oldest first
/// (those that passed its log filter, and the reports of refused overlapping calls).
pub fn messages(c: Component) -> Vec<String> {
    log_of(c).map(|log| lock(&log).clone()).unwrap_or_default()
}

/// The last message of [`messages`] ("" if none).
pub fn last_message(c: Component) -> String {
    messages(c).pop().unwrap_or_default()
}

/// fmi2GetReal of `vrs`, which must answer fmi2OK.
pub fn get(c: Component, vrs: &[u32]) -> Vec<f64> {
    let mut v = vec![0.0; vrs.len()];
    // SAFETY: arrays of vrs.len() elements.
    assert_eq!(unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) }, Status::Ok, "{:?}", messages(c));
    v
}

/// The state of an instance made by [`instantiate`], as its answers show it: calls that
/// change nothing (fmi2GetReal and fmi2SetReal of no variables, fmi2GetRealStatus,
/// fmi2GetStatus) are admitted or refused as the state machine's table says for that
/// state, and fmi2GetStatus reports fmi2Discard in StepFailed alone. A live instance
/// answers fmi2OK or logs why it refused; a component that is not one (freed, foreign)
/// refuses silently: None. None too when the answers fit more than one state
/// (StepCanceled and Terminated answer alike; this FMU never pends a step, so it is never
/// in StepCanceled). The messages of the probing calls are taken out of the log again.
pub fn state(c: Component) -> Option<State> {
    let log = log_of(c)?;
    let before = lock(&log).len();
    let (mut time, mut step) = (0.0, Status::Ok);
    // SAFETY: empty arrays (never read or written) and valid out-pointers; `c` is checked
    // by the FMU against its live instances.
    let (get, set, time_ok, status_ok) = unsafe {
        (
            fmi2GetReal(c, std::ptr::null(), 0, std::ptr::null_mut()) == Status::Ok,
            fmi2SetReal(c, std::ptr::null(), 0, std::ptr::null()) == Status::Ok,
            fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut time) == Status::Ok,
            fmi2GetStatus(c, DO_STEP_STATUS, &mut step) == Status::Ok,
        )
    };
    let logged = {
        let mut log = lock(&log);
        let logged = log.len() > before;
        log.truncate(before);
        logged
    };
    if !(get || set || time_ok || status_ok || logged) {
        return None;
    }
    let admits = |s: State, f: Func| f.rule().allowed2 & s.bit() != 0;
    // Event Mode is FMI 3's: an FMI 2 instance is never in it.
    let fits: Vec<State> = State::ALL
        .into_iter()
        .filter(|&s| s != State::EventMode)
        .filter(|&s| {
            admits(s, Func::GetReal) == get
                && admits(s, Func::SetReal) == set
                && admits(s, Func::GetRealStatus) == time_ok
                && admits(s, Func::GetStatus) == status_ok
                && (!status_ok || (step == Status::Discard) == (s == State::StepFailed))
        })
        .collect();
    match fits[..] {
        [s] => Some(s),
        _ => None,
    }
}

/// [`resources`] for the model file `path`, with its flexible bodies' modal data files
/// copied into the resources under the paths the model gives (as `mbfmu pack` does).
pub fn resources_of(path: &std::path::Path, tag: &str) -> (PathBuf, CString) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let model = mbfmu::model::load_file(path).unwrap_or_else(|e| panic!("{e}"));
    // A model with modal data files has no layout from its text alone: the one of the
    // file, and the interfaces `mbfmu pack` would offer with it.
    let layout = mbfmu::linearize::StateLayout::at_start(&model);
    let interfaces = Interfaces { model_exchange: layout.missing.is_none(), co_simulation: true };
    let (top, uri) = resources_offering(&text, tag, Some(interfaces));
    let file = top.join("resources").join(mbfmu::fmi::resources::LAYOUT_FILE);
    if !file.exists() {
        let tmp = file.with_extension(format!("{:?}.tmp", std::thread::current().id()));
        let guid = mbfmu::fmi::guid::guid(&model, &text);
        std::fs::write(&tmp, layout.to_text(&guid)).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
        std::fs::rename(&tmp, &file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    }
    for flex in model.bodies.iter().filter_map(|b| b.flex.as_ref()) {
        let to = top.join("resources").join(&flex.file);
        if !to.exists() {
            let dir = to.parent().expect("a file in resources/");
            std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
            let tmp = dir.join(format!("data.{:?}.tmp", std::thread::current().id()));
            std::fs::copy(&flex.path, &tmp).unwrap_or_else(|e| panic!("{}: {e}", flex.path));
            std::fs::rename(&tmp, &to).unwrap_or_else(|e| panic!("{}: {e}", to.display()));
        }
    }
    (top, uri)
}

/// `<tmp>/mbfmu <tag> 100% <pid> <hash of text>/resources/model.xml` holding `text`, with the state
/// layout `mbfmu pack` writes beside it (when the text is a model): the directory (remove
/// it when done, if wanted) and the resource location's `file://` URI, with the space and
/// the `%` of the path escaped as a host must.
pub fn resources(text: &str, tag: &str) -> (PathBuf, CString) {
    resources_offering(text, tag, None)
}

/// [`resources`] for an FMU offering `interfaces` (`None`: what `mbfmu pack` offers by
/// default, Model Exchange and Co-Simulation when the model has states, else
/// Co-Simulation only).
pub fn resources_offering(text: &str, tag: &str, interfaces: Option<Interfaces>) -> (PathBuf, CString) {
    // The layout carries the GUID, which names this build of the engine: hashing it with the
    // text keeps a directory left by another build under a reused process id from being read.
    let made = mbfmu::pack::layout_file(text, "model.xml").ok();
    let interfaces = interfaces.unwrap_or(Interfaces {
        model_exchange: made.as_ref().is_some_and(|(_, missing)| missing.is_none()),
        co_simulation: true,
    });
    let layout = made.map(|(l, _)| l);
    let tag = format!(
        "{tag}{}{}",
        if interfaces.model_exchange { " me" } else { "" },
        if interfaces.co_simulation { " cs" } else { "" }
    );
    let id = {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        text.hash(&mut h);
        layout.hash(&mut h);
        format!("{:016x}", h.finish())
    };
    let top = std::env::temp_dir().join(format!("mbfmu {tag} 100% {} {id}", std::process::id()));
    let dir = top.join("resources");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let file = dir.join("model.xml");
    if !file.exists() {
        // Write then rename: tests running in parallel never read a half-written file.
        let tmp = dir.join(format!("model.{:?}.tmp", std::thread::current().id()));
        // The layout and the interfaces first: model.xml present means all are.
        std::fs::write(&tmp, interfaces.to_text()).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
        let to = dir.join(mbfmu::fmi::resources::INTERFACES_FILE);
        std::fs::rename(&tmp, &to).unwrap_or_else(|e| panic!("{}: {e}", to.display()));
        if let Some(layout) = layout {
            std::fs::write(&tmp, layout).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
            let to = dir.join(mbfmu::fmi::resources::LAYOUT_FILE);
            std::fs::rename(&tmp, &to).unwrap_or_else(|e| panic!("{}: {e}", to.display()));
        }
        std::fs::write(&tmp, text).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
        std::fs::rename(&tmp, &file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    }
    let path = dir.to_str().expect("UTF-8 temporary directory").replace('%', "%25").replace(' ', "%20");
    (top, CString::new(format!("file://{path}")).expect("no NUL in the path"))
}
