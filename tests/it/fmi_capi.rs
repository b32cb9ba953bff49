//! The FMI 2.0 Co-Simulation C API, called as a host would: lifecycle, results equal to
//! the engine's own, FMU states, parameters, every refused call with its message, engine
//! failures as fmi2Discard, and many instances.

use crate::common::guid;
use crate::common::host::{self, CALLBACKS, free, get, last_message, messages, resources};
use crate::common::model_text;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::exports_me::fmi2SetTime;
use mbfmu::fmi::exports_state::*;
use mbfmu::fmi::resources::Interfaces;
use mbfmu::fmi::state_machine::State;
use mbfmu::fmi::types::{CO_SIMULATION, Component, LAST_SUCCESSFUL_TIME, MODEL_EXCHANGE, Status};
use std::ffi::CString;

const CO_SIMULATION_ONLY: Interfaces = Interfaces { model_exchange: false, co_simulation: true };
const ME_ONLY: Interfaces = Interfaces { model_exchange: true, co_simulation: false };

fn instantiate_with(text: &str, fmu_type: i32, guid_s: &str) -> Component {
    let (name, g, uri) = (c"inst", CString::new(guid_s).unwrap(), resources(text, "capi").1);
    // SAFETY: valid NUL-terminated strings; the host's callbacks with a recording logger.
    unsafe { host::instantiate(name.as_ptr(), fmu_type, g.as_ptr(), uri.as_ptr(), 0, 1) }
}

fn instantiate(text: &str) -> Component {
    let c = instantiate_with(text, CO_SIMULATION, &guid(text));
    assert!(!c.is_null());
    c
}

/// Instantiate, set up (tolerance `tol`, start 0), initialize with `params` (vr, value).
fn initialized(text: &str, tol: f64, params: &[(u32, f64)]) -> Component {
    let c = instantiate(text);
    // SAFETY: a live instance and valid arrays throughout.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, tol, 0.0, 0, 0.0), Status::Ok);
        for &(vr, v) in params {
            assert_eq!(fmi2SetReal(c, &vr, 1, &v), Status::Ok);
        }
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);
    }
    c
}

/// Steps of `h` from `t0`, n times; the time accumulates as a host's does.
fn step(c: Component, t0: f64, h: f64, n: usize) -> f64 {
    let mut t = t0;
    for _ in 0..n {
        // SAFETY: a live instance.
        assert_eq!(unsafe { fmi2DoStep(c, t, h, 1) }, Status::Ok, "{:?}", messages(c));
        t += h;
    }
    t
}

/// Pendulum value references: parameters m L Jc g th0 (0..5), outputs angle omega x z energy (5..10).
const PENDULUM_OUTPUTS: [u32; 5] = [5, 6, 7, 8, 9];
const L_VR: u32 = 1;

/// The engine run the FMU wraps, stepped like the host.
fn direct(text: &str, params: Option<&[f64]>, tol: f64, h: f64, n: usize) -> Vec<f64> {
    let m = mbfmu::model::parse::load_str(text, "model.xml").unwrap();
    let m = params.map_or(m.clone(), |p| m.with_params(p).unwrap());
    let mut s = Simulator::new(&m, SimOptions { tol, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mut t = 0.0;
    for _ in 0..n {
        t += h;
        s.advance(t).unwrap();
    }
    s.outputs().unwrap()
}

#[test]
fn a_full_lifecycle_gives_the_outputs_of_a_direct_engine_run_bit_for_bit() {
    let text = model_text("pendulum.xml");
    let c = initialized(&text, 1e-8, &[]);
    let t = step(c, 0.0, 0.05, 40);
    let fmu = get(c, &PENDULUM_OUTPUTS);
    assert_eq!(fmu, direct(&text, None, 1e-8, 0.05, 40));
    let mut last = 0.0;
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut last), Status::Ok);
        assert_eq!(last, t);
        assert_eq!(fmi2Terminate(c), Status::Ok);
    }
    assert_eq!(get(c, &PENDULUM_OUTPUTS), fmu, "outputs stay readable when terminated");
    free(c);
}

#[test]
fn rewinding_through_fmu_states_and_serialized_bytes_reproduces_outputs_bit_for_bit() {
    let text = model_text("double_pendulum.xml");
    let c = initialized(&text, 1e-8, &[]);
    let m = mbfmu::model::parse::load_str(&text, "m").unwrap();
    let vars = mbfmu::fmi::variables::variables(
        &m,
        &mbfmu::linearize::StateLayout::at_start(&m),
        mbfmu::fmi::variables::Standard::Fmi2,
    );
    // Every Real variable (the last one, solver.maxSteps, is an Integer).
    let outs: Vec<u32> = vars.iter().filter(|v| !v.target.is_integer()).map(|v| v.value_reference).collect();
    let t1 = step(c, 0.0, 0.1, 5);
    let mut s: *mut libc::c_void = std::ptr::null_mut();
    // SAFETY: live instances, valid out-pointers, states of this FMU.
    unsafe {
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        let t2 = step(c, t1, 0.1, 5);
        let first = get(c, &outs);
        assert_eq!(fmi2SetFMUstate(c, s), Status::Ok);
        assert_eq!(step(c, t1, 0.1, 5), t2);
        assert_eq!(get(c, &outs), first, "same instance, rewound");

        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut size), Status::Ok);
        let mut bytes = vec![0 as libc::c_char; size];
        assert_eq!(fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), size), Status::Ok);
        assert_eq!(fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), size - 1), Status::Error);
        assert!(last_message(c).contains("fmi2SerializeFMUstate"));
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
        assert!(s.is_null());

        // A new instance, never initialized itself, continues from the bytes.
        let d = instantiate(&text);
        let mut s2: *mut libc::c_void = std::ptr::null_mut();
        assert_eq!(fmi2DeSerializeFMUstate(d, bytes.as_ptr(), size, &mut s2), Status::Ok);
        assert_eq!(fmi2SetFMUstate(d, s2), Status::Ok, "{:?}", messages(d));
        assert_eq!(host::state(d), Some(State::StepComplete));
        assert_eq!(step(d, t1, 0.1, 5), t2);
        assert_eq!(get(d, &outs), first, "new instance, deserialized");
        assert_eq!(fmi2FreeFMUstate(d, &mut s2), Status::Ok);

        // Bytes of another model are refused by name.
        assert_eq!(fmi2DeSerializeFMUstate(d, b"garbage".as_ptr().cast(), 7, &mut s2), Status::Error);
        assert!(last_message(d).contains("fmi2DeSerializeFMUstate"));
        let p = initialized(&model_text("pendulum.xml"), 1e-8, &[]);
        assert_eq!(fmi2DeSerializeFMUstate(p, bytes.as_ptr(), size, &mut s2), Status::Error);
        assert!(last_message(p).contains("belongs to"), "{:?}", messages(p));
        for x in [c, d, p] {
            free(x);
        }
    }
}

#[test]
fn a_pendulum_length_set_before_initialization_changes_the_motion_and_after_is_refused() {
    // x = dx(bob.cm) = -L sin(th0) at t = 0 (models/pendulum.xml).
    let text = model_text("pendulum.xml");
    let c = initialized(&text, 1e-8, &[(L_VR, 1.0)]);
    let x0 = get(c, &[7])[0];
    assert!((x0 + (170f64).to_radians().sin()).abs() < 1e-12, "x0 = {x0}");
    step(c, 0.0, 0.05, 20);
    let mut params = mbfmu::model::parse::load_str(&text, "m").unwrap().param_values();
    params[L_VR as usize] = 1.0;
    assert_eq!(get(c, &PENDULUM_OUTPUTS), direct(&text, Some(&params), 1e-8, 0.05, 20));
    assert_ne!(get(c, &PENDULUM_OUTPUTS), direct(&text, None, 1e-8, 0.05, 20));
    // SAFETY: a live instance, one-element arrays.
    assert_eq!(unsafe { fmi2SetReal(c, &L_VR, 1, &2.0) }, Status::Error);
    let m = last_message(c);
    assert!(m.contains("fmi2SetReal") && m.contains("'L'") && m.contains("after initialization"), "{m}");
    assert_eq!(get(c, &[L_VR]), [1.0], "refused value not applied");
    free(c);
}

#[test]
fn outputs_read_in_initialization_mode_follow_the_parameters_set_there() {
    let text = model_text("pendulum.xml");
    let c = instantiate(&text);
    // SAFETY: a live instance, one-element arrays.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 1.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        let x_default = get(c, &[7])[0];
        assert_eq!(fmi2SetReal(c, &L_VR, 1, &2.0), Status::Ok);
        assert_eq!(get(c, &[7])[0], 4.0 * x_default);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);
        // stopTime 1 is enforced.
        assert_eq!(fmi2DoStep(c, 0.0, 1.5, 1), Status::Error);
        assert!(last_message(c).contains("stopTime"));
        assert_eq!(fmi2DoStep(c, 0.0, 1.0, 1), Status::Ok);
    }
    free(c);
}

/// Expect `status` and a last message naming `func` (and containing `what`), then a valid call.
fn refused(c: Component, got: Status, want: Status, func: &str, what: &str) {
    assert_eq!(got, want, "{func}");
    let m = last_message(c);
    assert!(m.starts_with(func) && m.contains(what), "{func}: message {m:?}");
    get(c, &[0]);
}

#[test]
fn every_refused_call_returns_its_status_names_the_function_and_leaves_the_instance_usable() {
    let text = model_text("pendulum.xml");
    let c = instantiate(&text);
    let nul: *const u32 = std::ptr::null();
    let (mut v, mut i, mut b) = ([0.0; 2], 0i32, 0i32);
    // SAFETY: a live instance; NULL pointers are what is tested, with n > 0 they are refused.
    unsafe {
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), Status::Error);
        assert_eq!(last_message(c), "fmi2DoStep: not allowed in state Instantiated");
        assert_eq!(fmi2SetupExperiment(c, 1, -1.0, 0.0, 0, 0.0), Status::Error);
        assert!(last_message(c).starts_with("fmi2SetupExperiment: tolerance -1"));
        assert_eq!(fmi2SetupExperiment(c, 1, 1e-8, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);

        refused(c, fmi2GetReal(c, &99, 1, v.as_mut_ptr()), Status::Error, "fmi2GetReal", "unknown value reference 99");
        refused(c, fmi2GetReal(c, nul, 1, v.as_mut_ptr()), Status::Error, "fmi2GetReal", "vr is NULL");
        refused(c, fmi2GetReal(c, &0, 1, std::ptr::null_mut()), Status::Error, "fmi2GetReal", "value is NULL");
        assert_eq!(fmi2GetReal(c, nul, 0, std::ptr::null_mut()), Status::Ok, "nothing asked, nothing read");
        refused(c, fmi2SetReal(c, &7, 1, &f64::NAN), Status::Error, "fmi2SetReal", "value NaN for 'x' (vr 7)");
        refused(c, fmi2SetReal(c, &7, 1, &1.0), Status::Error, "fmi2SetReal", "'x' (vr 7) is an output");
        refused(c, fmi2SetReal(c, &42, 1, &1.0), Status::Error, "fmi2SetReal", "unknown value reference 42");
        refused(c, fmi2GetInteger(c, &0, 1, &mut i), Status::Error, "fmi2GetInteger", "'m' (vr 0) is a Real");
        assert_eq!(fmi2GetInteger(c, nul, 0, &mut i), Status::Ok);
        refused(c, fmi2SetBoolean(c, &0, 1, &b), Status::Error, "fmi2SetBoolean", "unknown value reference 0");
        refused(c, fmi2GetString(c, &0, 1, std::ptr::null_mut()), Status::Error, "fmi2GetString", "value is NULL");
        refused(c, fmi2SetTime(c, 1.0), Status::Error, "fmi2SetTime", "not allowed in state StepComplete");
        refused(c, fmi2EnterInitializationMode(c), Status::Error, "fmi2EnterInitializationMode", "StepComplete");
        refused(c, fmi2DoStep(c, 0.5, 0.1, 1), Status::Error, "fmi2DoStep", "is not the current time 0");
        refused(c, fmi2DoStep(c, 0.0, -0.1, 1), Status::Error, "fmi2DoStep", "communicationStepSize -0.1");
        refused(c, fmi2DoStep(c, 0.0, f64::NAN, 1), Status::Error, "fmi2DoStep", "communicationStepSize NaN");
        refused(c, fmi2CancelStep(c), Status::Error, "fmi2CancelStep", "synchronously");
        let dd = fmi2GetDirectionalDerivative(c, &7, 1, &0, 1, &1.0, v.as_mut_ptr());
        refused(c, dd, Status::Error, "fmi2GetDirectionalDerivative", "is neither a state nor an input");
        let od = fmi2GetRealOutputDerivatives(c, &7, 1, &2, v.as_mut_ptr());
        refused(c, od, Status::Error, "fmi2GetRealOutputDerivatives", "only order 1 is supported");
        assert_eq!(fmi2GetRealOutputDerivatives(c, &7, 1, &1, v.as_mut_ptr()), Status::Ok);
        assert!(v[0].is_finite());
        let od2 = fmi2GetRealOutputDerivatives(c, &0, 1, &1, v.as_mut_ptr());
        refused(c, od2, Status::Error, "fmi2GetRealOutputDerivatives", "'m' (vr 0) is not an output");
        refused(c, fmi2GetRealStatus(c, 0, v.as_mut_ptr()), Status::Error, "fmi2GetRealStatus", "status kind 0");
        b = 1;
        assert_eq!(fmi2GetBooleanStatus(c, 3, &mut b), Status::Ok);
        assert_eq!(b, 0, "fmi2Terminated is false");
        let bad_cat = [c"logNonsense".as_ptr()];
        refused(c, fmi2SetDebugLogging(c, 1, 1, bad_cat.as_ptr()), Status::Error, "fmi2SetDebugLogging", "logNonsense");
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), Status::Ok, "still steps after all that");
        // A NULL instance: fmi2Error, nothing to log into.
        assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 0.1, 1), Status::Error);
        assert_eq!(fmi2GetReal(std::ptr::null_mut(), &0, 1, v.as_mut_ptr()), Status::Error);
        assert_eq!(fmi2Reset(c), Status::Ok);
        assert_eq!(host::state(c), Some(State::Instantiated));
    }
    free(c);
}

#[test]
fn instantiation_refuses_an_interface_the_fmu_lacks_a_wrong_guid_and_a_missing_model() {
    let text = model_text("pendulum.xml");
    let g = CString::new(guid(&text)).unwrap();
    for (kind, lacks, offered) in
        [(MODEL_EXCHANGE, "Model Exchange", CO_SIMULATION_ONLY), (CO_SIMULATION, "Co-Simulation", ME_ONLY)]
    {
        let uri = host::resources_offering(&text, "capi", Some(offered)).1;
        // SAFETY: valid NUL-terminated strings.
        let (c, logged) = unsafe { host::instantiate_logged(c"i".as_ptr(), kind, g.as_ptr(), uri.as_ptr(), 0, 1) };
        assert!(c.is_null(), "{lacks} instantiated");
        assert!(logged.iter().any(|m| m.contains(lacks)), "{lacks}: {logged:?}");
    }
    assert!(instantiate_with(&text, CO_SIMULATION, "{00000000-0000-0000-0000-000000000000}").is_null());
    let uri = c"file:///nonexistent/resources";
    let g = CString::new(guid(&text)).unwrap();
    // SAFETY: valid strings and callbacks; NULL callbacks struct is refused.
    unsafe {
        assert!(fmi2Instantiate(c"i".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), &CALLBACKS, 0, 0).is_null());
        assert!(
            fmi2Instantiate(c"i".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), std::ptr::null(), 0, 0).is_null()
        );
    }
}

/// A rotor whose drive torque sqrt(1 - time) stops existing at t = 1: the integrator
/// cannot pass it.
const DOOMED: &str = r#"<multibody name="doomed" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="1" inertia="0.2 0.3 0.5" position="0 0 0"/>
  <joint name="axle" type="revolute" i="r.cm" j="ground.O"/>
  <input name="T" start="0" unit="N.m"/>
  <gforce name="motor" i="r.cm" force="0 0 0" torque="0, 0, T + sqrt(1 - time)"/>
  <output name="w" function="wz(r.cm)"/>
</multibody>"#;

#[test]
fn a_step_the_engine_cannot_finish_is_discarded_at_the_time_it_reached() {
    let c = initialized(DOOMED, 1e-8, &[]);
    step(c, 0.0, 0.5, 1);
    let mut last = 0.0;
    // SAFETY: a live instance, valid out-pointers.
    unsafe {
        assert_eq!(fmi2DoStep(c, 0.5, 1.0, 1), Status::Discard);
        let m = messages(c);
        assert!(m.iter().any(|s| s.starts_with("fmi2DoStep: step from 0.5 to 1.5 stopped at")), "{m:?}");
        assert_eq!(m.last().unwrap(), "fmi2DoStep: state StepComplete -> StepFailed", "logEvents");
        assert_eq!(host::state(c), Some(State::StepFailed));
        assert_eq!(fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut last), Status::Ok);
        assert!(last > 0.5 && last <= 1.0, "reached {last}");
        let mut st = Status::Ok;
        assert_eq!(fmi2GetStatus(c, 0, &mut st), Status::Ok);
        assert_eq!(st, Status::Discard);
        assert!(get(c, &[1])[0].is_finite(), "outputs at the time reached");
        assert_eq!(fmi2DoStep(c, last, 0.1, 1), Status::Error);
        assert_eq!(fmi2Terminate(c), Status::Ok);
    }
    free(c);
}

const ROTOR: &str = r#"<multibody name="rotor" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="1" inertia="0.2 0.3 0.5" position="0 0 0"/>
  <joint name="axle" type="revolute" i="r.cm" j="ground.O"/>
  <input name="T" start="0" unit="N.m"/>
  <gforce name="motor" i="r.cm" force="0 0 0" torque="0 0 T"/>
  <output name="w" function="wz(r.cm)"/>
</multibody>"#;

#[test]
fn held_and_ramped_inputs_drive_a_rotor_as_the_closed_form_says() {
    // J ω' = T(t), J = 0.5: T = 2 held over [0, 1] gives ω = 4; then T = 2 + 3 (t − 1)
    // over [1, 2] adds (2 + 3/2) / J = 7. Polynomial motion: exact up to round-off.
    let c = initialized(ROTOR, 1e-8, &[(0, 2.0)]);
    // SAFETY: a live instance, one-element arrays.
    unsafe {
        step(c, 0.0, 1.0, 1);
        assert!((get(c, &[1])[0] - 4.0).abs() < 1e-12);
        assert_eq!(fmi2SetRealInputDerivatives(c, &0, 1, &2, &3.0), Status::Error);
        assert!(last_message(c).contains("order 2"));
        assert_eq!(fmi2SetRealInputDerivatives(c, &0, 1, &1, &3.0), Status::Ok);
        step(c, 1.0, 1.0, 1);
        assert!((get(c, &[1])[0] - 11.0).abs() < 1e-12);
        assert_eq!(get(c, &[0]), [5.0], "the input reads its ramped value");
    }
    free(c);
}

#[test]
fn a_thousand_instantiate_free_cycles_and_parallel_instances_are_independent() {
    let text = model_text("pendulum.xml");
    for _ in 0..1000 {
        free(instantiate(&text));
    }
    let want = direct(&text, None, 1e-6, 0.1, 10);
    let runs: Vec<_> = (0..4)
        .map(|_| {
            let t = text.clone();
            std::thread::spawn(move || {
                let c = initialized(&t, 1e-6, &[]);
                step(c, 0.0, 0.1, 10);
                let v = get(c, &PENDULUM_OUTPUTS);
                free(c);
                v
            })
        })
        .collect();
    for r in runs {
        assert_eq!(r.join().unwrap(), want);
    }
}

#[test]
fn a_panic_inside_an_export_becomes_fatal_when_the_engine_may_be_corrupt_and_error_otherwise() {
    use mbfmu::fmi::guard::guarded;
    use mbfmu::fmi::state_machine::Func;
    let text = model_text("pendulum.xml");
    let c = initialized(&text, 1e-6, &[]);
    assert_eq!(guarded(c, Func::GetReal, |_| panic!("boom")), Status::Error);
    assert_eq!(last_message(c), "fmi2GetReal: internal error (panic): boom");
    assert_eq!(host::state(c), Some(State::Error));
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2DoStep(c, 0.0, 0.1, 1) }, Status::Error, "no stepping in state Error");
    let d = initialized(&text, 1e-6, &[]);
    assert_eq!(guarded(d, Func::DoStep, |_| panic!("boom {}", 2)), Status::Fatal);
    assert_eq!(last_message(d), "fmi2DoStep: internal error (panic): boom 2");
    assert_eq!(host::state(d), Some(State::Fatal));
    free(c);
    free(d);
}

/// Value references of the knowns (states, inputs) and unknowns (state derivatives,
/// outputs) of the linearization.
fn lin_refs(text: &str) -> (Vec<u32>, Vec<u32>) {
    use mbfmu::fmi::variables::{Causality, variables};
    let m = mbfmu::model::parse::load_str(text, "model.xml").unwrap();
    let vars = variables(&m, &mbfmu::linearize::StateLayout::at_start(&m), mbfmu::fmi::variables::Standard::Fmi2);
    let pick = |f: &dyn Fn(&mbfmu::fmi::variables::Variable) -> bool| {
        vars.iter().filter(|v| f(v)).map(|v| v.value_reference).collect::<Vec<u32>>()
    };
    (
        pick(&|v| v.known.is_some() || v.causality == Causality::Input),
        pick(&|v| v.unknown.is_some() || v.causality == Causality::Output),
    )
}

/// Instantiate, initialize, step, read every column of A/B/C/D, and round-trip an FMU
/// state: every export the engine runs in.
fn full_run(text: &str, knowns: &[u32], unknowns: &[u32]) -> Vec<f64> {
    let c = initialized(text, 1e-8, &[]);
    let t = step(c, 0.0, 0.01, 2);
    let mut out = Vec::new();
    // SAFETY: a live instance and arrays of the stated lengths throughout.
    unsafe {
        let mut s = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        step(c, t, 0.01, 1);
        assert_eq!(fmi2SetFMUstate(c, s), Status::Ok);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
        for &k in knowns {
            let mut col = vec![0.0; unknowns.len()];
            let st = fmi2GetDirectionalDerivative(c, unknowns.as_ptr(), unknowns.len(), &k, 1, &1.0, col.as_mut_ptr());
            assert_eq!(st, Status::Ok, "{:?}", messages(c));
            out.extend(col);
        }
    }
    free(c);
    out
}

#[test]
fn every_export_runs_on_a_host_thread_with_a_64_kib_stack() {
    // The engine needs more than such a thread has (the bicycle's initialization alone
    // overflowed 256 KiB before): the exports run it on a stack of their own. The result
    // is the one of the test thread's 2 MiB stack, bit for bit.
    for name in ["pendulum.xml", "benchmark_bicycle.xml", "cart_pendulum_pid.xml"] {
        let text = model_text(name);
        let (knowns, unknowns) = lin_refs(&text);
        let want = full_run(&text, &knowns, &unknowns);
        assert!(!want.is_empty());
        let got = std::thread::Builder::new()
            .stack_size(64 << 10)
            .spawn(move || full_run(&text, &knowns, &unknowns))
            .unwrap()
            .join()
            .unwrap();
        assert_eq!(got, want, "{name}");
    }
}

#[test]
fn a_call_while_another_runs_on_the_instance_is_refused_not_let_in() {
    // FMI allows one call at a time per instance. A call from a second thread, or from
    // inside a running call (as a logger callback would make), gets fmi2Error and the
    // instance stays intact, instead of a second &mut to it. The running call is held
    // open with the guard the exports use, so the overlap is certain.
    use mbfmu::fmi::guard::guarded;
    use mbfmu::fmi::state_machine::Func;
    use std::sync::mpsc::channel;
    let text = model_text("pendulum.xml");
    let c = initialized(&text, 1e-8, &[]);
    let addr = c as usize;
    let (inside, entered) = channel();
    let (tried, answer) = channel();
    let other = std::thread::spawn(move || {
        entered.recv().unwrap();
        let mut v = [0.0];
        // SAFETY: a live instance (busy: the call must be refused), a one-element array.
        let s = unsafe { fmi2GetReal(addr as Component, &0, 1, v.as_mut_ptr()) };
        tried.send(s).unwrap();
    });
    let mut nested = None;
    let held = guarded(c, Func::GetReal, |_| {
        inside.send(()).unwrap();
        let from_other_thread = answer.recv().unwrap();
        let mut v = [0.0];
        // SAFETY: as above, from the thread that holds the instance.
        nested = Some((from_other_thread, unsafe { fmi2GetReal(c, &0, 1, v.as_mut_ptr()) }));
        Ok(Status::Ok)
    });
    other.join().unwrap();
    assert_eq!(held, Status::Ok);
    assert_eq!(nested, Some((Status::Error, Status::Error)));
    assert_eq!(get(c, &PENDULUM_OUTPUTS).len(), 5, "the instance goes on");
    assert_eq!(step(c, 0.0, 0.1, 1), 0.1);
    free(c);
}

#[test]
fn a_serialized_state_with_any_byte_changed_or_cut_is_refused() {
    let text = model_text("pendulum.xml");
    let c = initialized(&text, 1e-8, &[]);
    step(c, 0.0, 0.1, 2);
    // SAFETY: a live instance and buffers of the stated sizes throughout.
    unsafe {
        let mut s = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        let mut n = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut n), Status::Ok);
        let mut bytes = vec![0i8; n];
        assert_eq!(fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), n), Status::Ok);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
        let mut back = std::ptr::null_mut();
        for i in 0..n {
            for bit in [0, 7] {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                assert_eq!(fmi2DeSerializeFMUstate(c, b.as_ptr(), n, &mut back), Status::Error, "byte {i} bit {bit}");
                assert!(back.is_null());
            }
        }
        assert!(last_message(c).contains("corrupted") || last_message(c).contains("not a serialized state"));
        for len in [0, 8, n / 2, n - 1] {
            assert_eq!(fmi2DeSerializeFMUstate(c, bytes.as_ptr(), len, &mut back), Status::Error, "length {len}");
        }
        assert_eq!(fmi2DeSerializeFMUstate(c, bytes.as_ptr(), n, &mut back), Status::Ok, "the bytes as written");
        assert_eq!(fmi2SetFMUstate(c, back), Status::Ok);
        assert_eq!(fmi2FreeFMUstate(c, &mut back), Status::Ok);
    }
    free(c);
}
