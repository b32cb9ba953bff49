//! A full FMU lifecycle through the exported FMI 2.0 C functions, as a host drives it:
//! the program tests/it/memory_valgrind.rs runs under valgrind memcheck (issue 12 item 6).
//! Every status is checked; any failure prints the instance's last messages and exits 1.
//!
//! Usage: cargo run --release --example fmu_lifecycle -- MODEL.xml [--fmi3] [--steps N]
//! [--thread-stack BYTES] [--leak BYTES]
//!
//! `--fmi3`: the same lifecycle through the FMI 3.0 exports (instantiation token, an
//! initialization mode carrying the experiment, fmi3DoStep with its out-arguments,
//! directional and adjoint derivatives, FMU states, reset, terminate, free).
//!
//! `--thread-stack`: run on a host thread with that stack instead of the main thread (the
//! exports then run the engine on a stack of their own); `--leak`: leak that many bytes
//! on purpose at the end (the control that the valgrind test sees a leak).
//!
//! Instantiate (a refused GUID first, then the model from a resources directory given by
//! a file:// URI), debug logging on, setup, parameters and inputs set, initialize, N
//! steps, every output and the Integer solver.maxSteps read, one directional derivative
//! per known (states and inputs) against every unknown (state derivatives and outputs) and
//! one for all knowns at once, FMU states (get, set, overwrite, size, serialize,
//! deserialize, free, a double free refused; two states left unfreed for fmi2FreeInstance
//! to free), reset and a second run (a state saved before the reset restored after it),
//! terminate, free. N (default 5) steps in the first run, 9 more in the rest.

use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::exports_state::*;
use mbfmu::fmi::guid::guid;
use mbfmu::fmi::types::{CO_SIMULATION, Component, FmuStatePtr, Status};
use mbfmu::fmi::variables::{Causality, Variable, variables};
use std::ffi::CString;
use std::path::Path;
use std::time::Instant;

#[path = "../tests/it/common/host.rs"]
mod host;
use host::resources;

/// Communication step size.
const H: f64 = 0.01;

/// Print what failed, with the last messages the instance gave its logger, and exit 1.
fn fail(c: Component, what: &str) -> ! {
    let msgs = host::messages(c);
    let last = &msgs[msgs.len().saturating_sub(64)..];
    eprintln!("fmu_lifecycle: FAILED: {what}; last messages: {last:?}");
    std::process::exit(1)
}

/// Require fmi2OK from the call named `what`.
fn ok(c: Component, status: Status, what: &str) {
    if status != Status::Ok {
        fail(c, &format!("{what} returned {status:?}"));
    }
}

fn instantiate(guid_s: &str, uri: &CString) -> Component {
    let g = CString::new(guid_s).expect("no NUL in a GUID");
    // SAFETY: valid NUL-terminated strings; the host's callbacks with a recording logger.
    unsafe { host::instantiate(c"lifecycle".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), 0, 1) }
}

fn get_reals(c: Component, vrs: &[u32], what: &str) -> Vec<f64> {
    let mut v = vec![f64::NAN; vrs.len()];
    // SAFETY: arrays of vrs.len() elements.
    ok(c, unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) }, what);
    if let Some(k) = v.iter().position(|x| !x.is_finite()) {
        fail(c, &format!("{what}: value reference {} is {}", vrs[k], v[k]));
    }
    v
}

/// Steps of H from `t`, n times; returns the time reached.
fn steps(c: Component, mut t: f64, n: usize) -> f64 {
    for _ in 0..n {
        // SAFETY: a live instance.
        ok(c, unsafe { fmi2DoStep(c, t, H, 1) }, &format!("fmi2DoStep at {t}"));
        t += H;
    }
    t
}

/// Setup (tolerance 1e-6, start 0, no stop), `sets` written in initialization mode, then
/// initialized.
fn initialize(c: Component, sets: &[(u32, f64)]) {
    // SAFETY: a live instance, one-element arrays.
    unsafe {
        ok(c, fmi2SetupExperiment(c, 1, 1e-6, 0.0, 0, 0.0), "fmi2SetupExperiment");
        ok(c, fmi2EnterInitializationMode(c), "fmi2EnterInitializationMode");
        for (vr, v) in sets {
            ok(c, fmi2SetReal(c, vr, 1, v), &format!("fmi2SetReal vr {vr}"));
        }
        ok(c, fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode");
    }
}

/// One column of the linearization per known, then all knowns at once; returns how many
/// calls were made.
fn derivatives(c: Component, knowns: &[u32], unknowns: &[u32]) -> usize {
    let mut col = vec![f64::NAN; unknowns.len()];
    let ones = vec![1.0; knowns.len()];
    // SAFETY: a live instance and arrays of the stated lengths.
    unsafe {
        for k in knowns {
            let st = fmi2GetDirectionalDerivative(c, unknowns.as_ptr(), unknowns.len(), k, 1, &1.0, col.as_mut_ptr());
            ok(c, st, &format!("fmi2GetDirectionalDerivative for known vr {k}"));
        }
        let st = fmi2GetDirectionalDerivative(
            c,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            ones.as_ptr(),
            col.as_mut_ptr(),
        );
        ok(c, st, "fmi2GetDirectionalDerivative for all knowns");
    }
    if let Some(k) = col.iter().position(|x| !x.is_finite()) {
        fail(c, &format!("directional derivative of unknown vr {} is {}", unknowns[k], col[k]));
    }
    knowns.len() + 1
}

/// The FMU-state functions; leaves two states unfreed (returned) for fmi2FreeInstance.
/// `reals`: every Real variable, compared bit for bit after each restore.
fn fmu_states(c: Component, t: f64, reals: &[u32]) -> [FmuStatePtr; 2] {
    let mut s: FmuStatePtr = std::ptr::null_mut();
    // SAFETY: a live instance, valid out-pointers, states of this instance.
    unsafe {
        ok(c, fmi2GetFMUstate(c, &mut s), "fmi2GetFMUstate");
        let at_s = get_reals(c, reals, "fmi2GetReal at the state");
        let t2 = steps(c, t, 3);
        let later = get_reals(c, reals, "fmi2GetReal after steps");
        ok(c, fmi2SetFMUstate(c, s), "fmi2SetFMUstate");
        if get_reals(c, reals, "fmi2GetReal after fmi2SetFMUstate") != at_s {
            fail(c, "values after fmi2SetFMUstate differ from those when the state was taken");
        }
        if steps(c, t, 3) != t2 || get_reals(c, reals, "fmi2GetReal after steps again") != later {
            fail(c, "steps from a restored state differ from the first ones");
        }

        let mut size = 0usize;
        ok(c, fmi2SerializedFMUstateSize(c, s, &mut size), "fmi2SerializedFMUstateSize");
        let mut bytes = vec![0 as libc::c_char; size];
        ok(c, fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), size), "fmi2SerializeFMUstate");
        let mut d: FmuStatePtr = std::ptr::null_mut();
        ok(c, fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut d), "fmi2DeSerializeFMUstate");
        ok(c, fmi2SetFMUstate(c, d), "fmi2SetFMUstate (deserialized)");
        if get_reals(c, reals, "fmi2GetReal after the deserialized state") != at_s {
            fail(c, "values after the deserialized state differ from those when it was serialized");
        }
        ok(c, fmi2FreeFMUstate(c, &mut d), "fmi2FreeFMUstate (deserialized)");
        if !d.is_null() {
            fail(c, "fmi2FreeFMUstate left the pointer non-NULL");
        }
        // A state freed twice is refused, not freed again.
        let mut stale = s;
        ok(c, fmi2FreeFMUstate(c, &mut s), "fmi2FreeFMUstate");
        if fmi2FreeFMUstate(c, &mut stale) != Status::Error {
            fail(c, "a state freed twice was not refused");
        }

        // Overwriting a live state in place (a non-NULL *FMUstate), then two states the
        // host never frees: one taken, one deserialized.
        let mut kept: FmuStatePtr = std::ptr::null_mut();
        ok(c, fmi2GetFMUstate(c, &mut kept), "fmi2GetFMUstate (kept)");
        steps(c, t, 1);
        let before = kept;
        ok(c, fmi2GetFMUstate(c, &mut kept), "fmi2GetFMUstate (overwrite)");
        if kept != before {
            fail(c, "fmi2GetFMUstate into a live state returned another one");
        }
        let mut kept2: FmuStatePtr = std::ptr::null_mut();
        ok(c, fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut kept2), "fmi2DeSerializeFMUstate (kept)");
        ok(c, fmi2SetFMUstate(c, kept2), "fmi2SetFMUstate (kept)");
        [kept, kept2]
    }
}

/// The options after the model path.
struct Options {
    steps: usize,
    thread_stack: Option<usize>,
    leak: usize,
}

fn usage() -> ! {
    eprintln!("usage: fmu_lifecycle MODEL.xml [--fmi3] [--steps N] [--thread-stack BYTES] [--leak BYTES]");
    std::process::exit(2)
}

fn parse_args(args: &[String]) -> Options {
    let mut o = Options { steps: 5, thread_stack: None, leak: 0 };
    for pair in args.chunks(2) {
        let [flag, value] = pair else { usage() };
        let value: usize = value.parse().unwrap_or_else(|_| usage());
        match flag.as_str() {
            "--steps" => o.steps = value,
            "--thread-stack" => o.thread_stack = Some(value),
            "--leak" => o.leak = value,
            _ => usage(),
        }
    }
    o
}

/// Allocate `n` bytes and drop the only pointer to them: the leak the valgrind test must
/// see (its control that a leak fails it).
#[inline(never)]
fn leak(n: usize) {
    if n > 0 {
        std::mem::forget(std::hint::black_box(vec![1u8; n]));
    }
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let fmi3 = args.iter().any(|a| a == "--fmi3");
    args.retain(|a| a != "--fmi3");
    let Some((model_path, rest)) = args.split_first() else { usage() };
    let o = parse_args(rest);
    let t0 = Instant::now();
    // Reading the model and naming its variables runs the engine: on the main thread,
    // with the host's own stack (only the exports promise to work on a small one).
    let plan = Plan::new(model_path, o.steps);
    let summary = match o.thread_stack {
        // A host thread with a small stack: the exports switch to a stack of their own.
        Some(bytes) => std::thread::Builder::new()
            .stack_size(bytes)
            .spawn(move || if fmi3 { lifecycle3(&plan) } else { lifecycle(&plan) })
            .expect("a host thread")
            .join()
            .unwrap_or_else(|_| fail(std::ptr::null_mut(), "the host thread panicked")),
        None if fmi3 => lifecycle3(&plan),
        None => lifecycle(&plan),
    };
    leak(o.leak);
    let on = o.thread_stack.map_or("the main thread".into(), |b| format!("a thread with a {b}-byte stack"));
    println!("fmu_lifecycle: {model_path}: ok on {on}: {summary}, {:.2} s", t0.elapsed().as_secs_f64());
}

/// What the lifecycle needs to know of the model: its text and value references.
struct Plan {
    text: String,
    /// The GUID of its FMU.
    guid: String,
    steps: usize,
    n_vars: usize,
    /// States and inputs.
    knowns: Vec<u32>,
    /// State derivatives and outputs.
    unknowns: Vec<u32>,
    outputs: Vec<u32>,
    /// Every Real variable.
    reals: Vec<u32>,
    /// solver.maxSteps.
    integers: Vec<u32>,
    /// Every Real parameter and input with its start value: written back, the setters run
    /// and the model stays the one of the file.
    sets: Vec<(u32, f64)>,
}

impl Plan {
    fn new(model_path: &str, steps: usize) -> Plan {
        let text =
            std::fs::read_to_string(model_path).unwrap_or_else(|e| panic!("{}: {e}", Path::new(model_path).display()));
        let model = mbfmu::model::parse::load_str(&text, model_path).unwrap_or_else(|e| panic!("{e}"));
        let vars =
            variables(&model, &mbfmu::linearize::StateLayout::at_start(&model), mbfmu::fmi::variables::Standard::Fmi2);
        let pick = |f: &dyn Fn(&Variable) -> bool| vars.iter().filter(|v| f(v)).map(|v| v.value_reference).collect();
        Plan {
            steps,
            n_vars: vars.len(),
            knowns: pick(&|v| v.known.is_some() || v.causality == Causality::Input),
            unknowns: pick(&|v| v.unknown.is_some() || v.causality == Causality::Output),
            outputs: pick(&|v| v.causality == Causality::Output),
            reals: pick(&|v| !v.target.is_integer()),
            integers: pick(&|v| v.target.is_integer()),
            sets: vars
                .iter()
                .filter(|v| matches!(v.causality, Causality::Parameter | Causality::Input) && !v.target.is_integer())
                .filter_map(|v| Some((v.value_reference, v.start?)))
                .collect(),
            guid: guid(&model, &text),
            text,
        }
    }
}

/// The lifecycle of the module's documentation, through the C API only; a summary.
fn lifecycle(p: &Plan) -> String {
    let (top, uri) = resources(&p.text, "lifecycle");
    // A refused instantiation (wrong GUID): NULL, with its message built and dropped.
    if !instantiate("{00000000-0000-0000-0000-000000000000}", &uri).is_null() {
        fail(std::ptr::null_mut(), "fmi2Instantiate accepted a wrong GUID");
    }
    let c = instantiate(&p.guid, &uri);
    if c.is_null() {
        fail(c, "fmi2Instantiate returned NULL");
    }
    let mut dd_calls = 0;
    // SAFETY: a live instance (until fmi2FreeInstance) and arrays of the stated lengths.
    unsafe {
        ok(c, fmi2SetDebugLogging(c, 1, 0, std::ptr::null()), "fmi2SetDebugLogging");
        initialize(c, &p.sets);
        let t = steps(c, 0.0, p.steps);
        get_reals(c, &p.outputs, "fmi2GetReal (outputs)");
        let mut ms = vec![0; p.integers.len()];
        ok(c, fmi2GetInteger(c, p.integers.as_ptr(), p.integers.len(), ms.as_mut_ptr()), "fmi2GetInteger");
        dd_calls += derivatives(c, &p.knowns, &p.unknowns);
        let kept = fmu_states(c, t, &p.reals);

        // Reset, run again, and continue from a state saved before the reset.
        ok(c, fmi2Reset(c), "fmi2Reset");
        initialize(c, &p.sets);
        steps(c, 0.0, 2);
        dd_calls += derivatives(c, &p.knowns, &p.unknowns);
        ok(c, fmi2SetFMUstate(c, kept[0]), "fmi2SetFMUstate after fmi2Reset");
        get_reals(c, &p.outputs, "fmi2GetReal after fmi2Reset and fmi2SetFMUstate");
        ok(c, fmi2Terminate(c), "fmi2Terminate");
        get_reals(c, &p.outputs, "fmi2GetReal when terminated");
        host::free(c);
    }
    std::fs::remove_dir_all(&top).unwrap_or_else(|e| panic!("{}: {e}", top.display()));
    format!(
        "{} variables, {} knowns x {} unknowns, {} steps, {dd_calls} directional derivative calls, 2 FMU states left \
         to fmi2FreeInstance",
        p.n_vars,
        p.knowns.len(),
        p.unknowns.len(),
        p.steps + 3 + 3 + 1 + 2,
    )
}

/// The FMI 3 host's log (its `instanceEnvironment` is not used).
static LOG3: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

unsafe extern "C" fn log3(
    _env: *mut std::ffi::c_void,
    _status: i32,
    _cat: *const std::ffi::c_char,
    msg: *const std::ffi::c_char,
) {
    // SAFETY: a NUL-terminated message, per FMI.
    let text = unsafe { std::ffi::CStr::from_ptr(msg) }.to_string_lossy().into_owned();
    LOG3.lock().unwrap_or_else(|e| e.into_inner()).push(text);
}

/// Require fmi3OK from the call named `what` (FMI 3 lifecycle).
fn ok3(status: Status, what: &str) {
    if status != Status::Ok {
        let log = LOG3.lock().unwrap_or_else(|e| e.into_inner());
        eprintln!(
            "fmu_lifecycle: FAILED: {what} returned {status:?}; last messages: {:?}",
            &log[log.len().saturating_sub(16)..]
        );
        std::process::exit(1)
    }
}

/// The lifecycle through the FMI 3.0 exports; a summary.
fn lifecycle3(p: &Plan) -> String {
    use mbfmu::fmi::exports3_common::*;
    use mbfmu::fmi::exports3_cs::*;
    let (top, _) = resources(&p.text, "lifecycle3");
    let res = CString::new(format!("{}/", top.join("resources").display())).expect("no NUL");
    let instantiate3 = |token: &str| {
        let t = CString::new(token).expect("no NUL");
        // SAFETY: valid strings; no intermediate variables.
        unsafe {
            fmi3InstantiateCoSimulation(
                c"lifecycle3".as_ptr(),
                t.as_ptr(),
                res.as_ptr(),
                0,
                1,
                0,
                0,
                std::ptr::null(),
                0,
                std::ptr::null_mut(),
                Some(log3),
                std::ptr::null(),
            )
        }
    };
    if !instantiate3("{00000000-0000-0000-0000-000000000000}").is_null() {
        fail(std::ptr::null_mut(), "fmi3InstantiateCoSimulation accepted a wrong token");
    }
    let c = instantiate3(&p.guid);
    if c.is_null() {
        ok3(Status::Error, "fmi3InstantiateCoSimulation");
    }
    let (mut b1, mut b2, mut b3, mut last) = (0u8, 0u8, 0u8, 0.0);
    let mut calls = 0;
    // SAFETY: a live instance (until fmi3FreeInstance) and arrays of the stated lengths.
    unsafe {
        let init = |c: Component| {
            ok3(fmi3EnterInitializationMode(c, 1, 1e-6, 0.0, 0, 0.0), "fmi3EnterInitializationMode");
            for (vr, v) in &p.sets {
                ok3(fmi3SetFloat64(c, vr, 1, v, 1), "fmi3SetFloat64");
            }
            ok3(fmi3ExitInitializationMode(c), "fmi3ExitInitializationMode");
        };
        ok3(fmi3SetDebugLogging(c, 1, 0, std::ptr::null()), "fmi3SetDebugLogging");
        init(c);
        let mut t = 0.0;
        for _ in 0..p.steps {
            ok3(fmi3DoStep(c, t, H, 1, &mut b1, &mut b2, &mut b3, &mut last), "fmi3DoStep");
            t = last;
        }
        let mut v = vec![0.0; p.reals.len()];
        ok3(fmi3GetFloat64(c, p.reals.as_ptr(), p.reals.len(), v.as_mut_ptr(), v.len()), "fmi3GetFloat64");
        let mut ms = vec![0; p.integers.len()];
        ok3(fmi3GetInt32(c, p.integers.as_ptr(), p.integers.len(), ms.as_mut_ptr(), ms.len()), "fmi3GetInt32");
        let (nk, nu) = (p.knowns.len(), p.unknowns.len());
        let mut col = vec![0.0; nu];
        for k in &p.knowns {
            let st = fmi3GetDirectionalDerivative(c, p.unknowns.as_ptr(), nu, k, 1, &1.0, 1, col.as_mut_ptr(), nu);
            ok3(st, "fmi3GetDirectionalDerivative");
            calls += 1;
        }
        let mut row = vec![0.0; nk];
        for u in &p.unknowns {
            let st = fmi3GetAdjointDerivative(c, u, 1, p.knowns.as_ptr(), nk, &1.0, 1, row.as_mut_ptr(), nk);
            ok3(st, "fmi3GetAdjointDerivative");
            calls += 1;
        }
        let mut s: FmuStatePtr = std::ptr::null_mut();
        ok3(fmi3GetFMUState(c, &mut s), "fmi3GetFMUState");
        let mut size = 0usize;
        ok3(fmi3SerializedFMUStateSize(c, s, &mut size), "fmi3SerializedFMUStateSize");
        let mut bytes = vec![0u8; size];
        ok3(fmi3SerializeFMUState(c, s, bytes.as_mut_ptr(), size), "fmi3SerializeFMUState");
        let mut back: FmuStatePtr = std::ptr::null_mut();
        ok3(fmi3DeserializeFMUState(c, bytes.as_ptr(), size, &mut back), "fmi3DeserializeFMUState");
        ok3(fmi3DoStep(c, t, H, 1, &mut b1, &mut b2, &mut b3, &mut last), "fmi3DoStep");
        ok3(fmi3SetFMUState(c, back), "fmi3SetFMUState");
        ok3(fmi3FreeFMUState(c, &mut back), "fmi3FreeFMUState");
        ok3(fmi3Reset(c), "fmi3Reset");
        init(c);
        ok3(fmi3DoStep(c, 0.0, H, 1, &mut b1, &mut b2, &mut b3, &mut last), "fmi3DoStep after fmi3Reset");
        ok3(fmi3Terminate(c), "fmi3Terminate");
        // `s` is left for fmi3FreeInstance to free.
        fmi3FreeInstance(c);
    }
    std::fs::remove_dir_all(&top).unwrap_or_else(|e| panic!("{}: {e}", top.display()));
    format!(
        "FMI 3: {} knowns x {} unknowns, {calls} derivative calls, 1 FMU state left to fmi3FreeInstance",
        p.knowns.len(),
        p.unknowns.len()
    )
}
