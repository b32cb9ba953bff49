//! Bounded fmi2DoStep (issue 12 item 2): the Integer parameter `solver.maxSteps` limits the
//! integrator step attempts of one step, and a step the engine cannot finish (the limit,
//! a step-size collapse at a lock-up) returns fmi2Discard with fmi2LastSuccessfulTime =
//! the time reached; restoring an FMU state lets the host retry or continue.

use crate::common::guid;
use crate::common::host::{self, free, get, messages, resources};
use crate::common::{attempts_between, engine_stats, model_text, root};
use mbfmu::dae::{DEFAULT_MAX_STEPS, SimOptions, Simulator};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::exports_state::*;
use mbfmu::fmi::state_machine::State;
use mbfmu::fmi::types::{CO_SIMULATION, Component, LAST_SUCCESSFUL_TIME, Status};
use mbfmu::fmi::variables::{MAX_STEPS_NAME, variables};
use mbfmu::linearize::StateLayout;
use mbfmu::model::parse::load_str;
use mbfmu::pack::fmi2_description::write;
use std::ffi::CString;

/// Step attempts the four-bar's discarded step may make before the step size collapses
/// at the toggle. Measured: 152 (2026-12-04, tolerance 1e-6, from t = 1.9). 1000 leaves
/// room for changes of the step control and Newton iteration, and is a tenth of the
/// default limit, so a collapse that went undetected until the limit fails it.
const TOGGLE_ATTEMPTS_BOUND: usize = 1000;

fn toggle_text() -> String {
    std::fs::read_to_string(root().join("tests/models/fourbar_toggle.xml")).unwrap()
}

/// Toggle geometry of tests/models/fourbar_toggle.xml: crank a, coupler b, rocker c,
/// ground d, crank speed w (phi = w t).
const A: f64 = 0.4;
const B: f64 = 0.5;
const C: f64 = 0.35;
const D: f64 = 0.6;
const W: f64 = 1.0;

/// The toggle time t*: |A − O2| = b + c, i.e. cos(w t*) = (a² + d² − (b + c)²) / (2 a d).
fn toggle_time() -> f64 {
    ((A * A + D * D - (B + C).powi(2)) / (2.0 * A * D)).acos() / W
}

/// The rocker angle at crank angle phi on the model's branch (B above the ground line at
/// the start): the direction θ of O2 → A plus the angle γ of the triangle O2 A B at O2,
/// both in the model's convention (a rotation by θ takes x to (cos θ, 0, −sin θ)).
fn rocker_angle(phi: f64) -> f64 {
    let (x, z) = (A * phi.cos() - D, -A * phi.sin());
    let l = x.hypot(z);
    let theta = (-z).atan2(x);
    let gamma = ((C * C + l * l - B * B) / (2.0 * C * l)).acos();
    theta + gamma
}

/// `a − b` reduced to (−π, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let d = (a - b).rem_euclid(tau);
    if d > std::f64::consts::PI { d - tau } else { d }
}

fn instantiate(text: &str) -> Component {
    let (g, uri) = (CString::new(guid(text)).unwrap(), resources(text, "bounded").1);
    // SAFETY: valid NUL-terminated strings; the host's callbacks with a recording logger;
    // logging on (every category).
    let c = unsafe { host::instantiate(c"bounded".as_ptr(), CO_SIMULATION, g.as_ptr(), uri.as_ptr(), 0, 1) };
    assert!(!c.is_null());
    c
}

/// Set up (tolerance `tol`, start 0) and initialize.
fn initialize(c: Component, tol: f64) {
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, tol, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok, "{:?}", messages(c));
    }
}

/// Value reference of variable `name` of the model `text`.
fn vr(text: &str, name: &str) -> u32 {
    let model = load_str(text, "model.xml").unwrap();
    variables(&model, &StateLayout::at_start(&model), mbfmu::fmi::variables::Standard::Fmi2)
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

fn get_int(c: Component, vr: u32) -> i32 {
    let mut v = 0;
    // SAFETY: one-element arrays.
    assert_eq!(unsafe { fmi2GetInteger(c, &vr, 1, &mut v) }, Status::Ok, "{:?}", messages(c));
    v
}

fn set_int(c: Component, vr: u32, v: i32) -> Status {
    // SAFETY: one-element arrays.
    unsafe { fmi2SetInteger(c, &vr, 1, &v) }
}

fn last_time(c: Component) -> f64 {
    let mut t = f64::NAN;
    // SAFETY: a live instance, a valid out-pointer.
    assert_eq!(unsafe { fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut t) }, Status::Ok);
    t
}

#[test]
fn solver_max_steps_is_the_last_variable_an_integer_tunable_parameter() {
    for text in [toggle_text(), model_text("cart_pendulum_pid.xml")] {
        let model = load_str(&text, "model.xml").unwrap();
        let vars = variables(&model, &StateLayout::at_start(&model), mbfmu::fmi::variables::Standard::Fmi2);
        let last = vars.last().unwrap();
        assert_eq!(last.name, MAX_STEPS_NAME);
        assert_eq!(last.value_reference as usize, vars.len() - 1, "value reference = index");
        assert!(last.target.is_integer() && vars[..vars.len() - 1].iter().all(|v| !v.target.is_integer()));
        let xml = write(&model, &text);
        let line = format!(
            "<ScalarVariable name=\"solver.maxSteps\" valueReference=\"{}\" causality=\"parameter\" \
             variability=\"tunable\" initial=\"exact\"",
            vars.len() - 1
        );
        let at = xml.find(&line).unwrap_or_else(|| panic!("{xml}"));
        let var = &xml[at..at + xml[at..].find("</ScalarVariable>").unwrap()];
        assert!(var.contains(&format!("<Integer start=\"{DEFAULT_MAX_STEPS}\"/>")), "{var}");
        assert!(var.contains("fmi2Discard"), "the description says what exceeding does: {var}");
        // It is the last ScalarVariable and no unknown depends on it.
        assert_eq!(xml.matches("<ScalarVariable").count(), vars.len());
        assert!(xml[at..].matches("<ScalarVariable").count() == 1);
        let index = vars.len().to_string();
        for l in xml.lines().filter(|l| l.contains("<Unknown")) {
            let deps = l.split("dependencies=\"").nth(1).unwrap().split('"').next().unwrap();
            assert!(!deps.split_whitespace().any(|d| d == index), "{l}");
        }
    }
}

#[test]
fn the_engine_stops_at_its_step_limit_at_the_time_reached_and_goes_on_from_there() {
    // The cart-pendulum's reference r ramps at 1 rad/s: the controller drives the cart ever
    // faster, and a step to t = 1e6 would need some 10⁸ integrator steps.
    let model = load_str(&model_text("cart_pendulum_pid.xml"), "m").unwrap();
    let opts = SimOptions { tol: 1e-6, max_steps: 50, ..Default::default() };
    let mut sim = Simulator::new(&model, opts, 0.0).unwrap();
    assert_eq!(sim.max_steps(), 50);
    assert_eq!(SimOptions::default().max_steps, DEFAULT_MAX_STEPS);
    sim.set_input_derivative(0, 1.0);
    let e = sim.advance(1e6).unwrap_err().to_string();
    let reached = sim.time();
    assert!(e.starts_with("step limit reached: 50 integrator steps (accepted and rejected) from t = 0 "), "{e}");
    assert!(e.contains(&format!("reached t = {reached}, not 1000000")) && e.contains("solver.maxSteps"), "{e}");
    assert_eq!(sim.stats().steps, 50, "attempts, accepted and rejected");
    assert!(reached > 0.0 && reached < 1e6, "{reached}");
    // The engine is at the last accepted step: constraints hold as at any step end (Newton
    // solves them to a fraction of the scaled tolerance; measured 1.9e-7 with the cart
    // metres away), and it continues from there.
    assert!(sim.constraint_residual() < 1e-6, "{}", sim.constraint_residual());
    sim.set_max_steps(DEFAULT_MAX_STEPS);
    sim.advance(reached + 0.1).unwrap();
    assert_eq!(sim.time(), reached + 0.1);
    // The limit is per call: 50 attempts again suffice for a short step.
    sim.set_max_steps(50);
    sim.advance(reached + 0.2).unwrap();
    sim.set_max_steps(0);
    assert_eq!(sim.max_steps(), 1, "at least one attempt");
}

#[test]
fn a_four_bar_driven_into_its_toggle_is_discarded_there_and_a_shorter_step_from_a_saved_state_succeeds() {
    let text = toggle_text();
    let outs = [vr(&text, "crank_angle"), vr(&text, "rocker_angle"), vr(&text, "closure"), vr(&text, "reach")];
    let t_star = toggle_time();
    assert!((t_star - 2.00630869785933).abs() < 1e-13, "{t_star}");
    let c = instantiate(&text);
    initialize(c, 1e-6);
    let mut s: *mut libc::c_void = std::ptr::null_mut();
    // SAFETY: a live instance, valid out-pointers, states of this FMU.
    unsafe {
        let mut t = 0.0;
        for k in 1..=19 {
            assert_eq!(fmi2DoStep(c, t, k as f64 * 0.1 - t, 1), Status::Ok, "{:?}", messages(c));
            t = k as f64 * 0.1;
        }
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        // Over the toggle: the engine cannot pass t*.
        let before = engine_stats(c);
        assert_eq!(fmi2DoStep(c, t, 0.2, 1), Status::Discard);
        let attempts = attempts_between(before, engine_stats(c));
        assert_eq!(host::state(c), Some(State::StepFailed));
        let m = messages(c);
        let discard = m.iter().find(|s| s.starts_with("fmi2DoStep: step from ")).unwrap();
        assert!(discard.contains(&format!("stopped at {}: step size collapsed", last_time(c))), "{discard}");
        assert!(discard.contains("toggle"), "{discard}");
        let reached = last_time(c);
        // The time reached is the toggle time: the integrator follows the rocker's
        // 1/sqrt(t* − t) speed until Newton no longer converges on any step (measured
        // t* − reached = 5.0e-10 s at tolerance 1e-6); 1e-7 s leaves room for changes of
        // the step control and is six orders below the communication step.
        assert!(reached > t && reached < t_star, "reached {reached}, toggle {t_star}");
        assert!(t_star - reached < 1e-7, "reached {reached}, toggle {t_star}: {:e}", t_star - reached);
        // The collapse is found in a few hundred attempts, not run into the step limit
        // (the default 10000).
        assert!(
            attempts <= TOGGLE_ATTEMPTS_BOUND,
            "{attempts} step attempts to find the collapse, bound {TOGGLE_ATTEMPTS_BOUND}"
        );
        // Outputs at the time reached: the crank follows its drive, the loop is closed, and
        // coupler and rocker are aligned up to reach ≈ (d|A − O2|/dt)(t* − t) =
        // 0.256 m/s · (t* − t) (measured 1.3e-10 m; the bound follows from the 1e-7 s above).
        let v = get(c, &outs);
        assert!((v[0] - W * reached).abs() < 1e-9, "crank angle {} at {reached}", v[0]);
        assert!(v[2].abs() < 1e-8, "closure {}", v[2]);
        assert!(v[3] >= 0.0 && v[3] < 0.26 * 1e-7, "reach {}", v[3]);
        assert_eq!(fmi2DoStep(c, reached, 0.01, 1), Status::Error, "no step after a discard");

        // Back before the toggle, a step that stays before it.
        assert_eq!(fmi2SetFMUstate(c, s), Status::Ok, "{:?}", messages(c));
        assert_eq!(host::state(c), Some(State::StepComplete));
        assert_eq!(last_time(c), t);
        assert_eq!(fmi2DoStep(c, t, 0.1, 1), Status::Ok, "{:?}", messages(c));
        assert_eq!(last_time(c), t + 0.1);
        // Constraints hold at t = 2.0, 6.3 ms before the toggle: the crank follows its
        // drive and the rocker sits where the loop closes (measured: crank exact, closure
        // 3.9e-11 m², rocker 8.9e-10 rad from the closed form; bounds 100 times larger).
        let v = get(c, &outs);
        assert!((v[0] - 2.0).abs() < 1e-9, "crank angle {}", v[0]);
        assert!(v[2].abs() < 4e-9, "closure {}", v[2]);
        assert!(angle_diff(v[1], rocker_angle(2.0)).abs() < 1e-7, "rocker {} vs {}", v[1], rocker_angle(2.0));
        assert!(v[3] > 1e-3, "reach {} before the toggle", v[3]);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
    }
    free(c);
}

#[test]
fn a_runaway_step_returns_discard_at_solver_max_steps_and_the_host_continues_from_the_time_reached() {
    // The issue's call sequence: an input slope set before initialization, then one step
    // of 1e6 s. The ramped reference drives the cart ever faster (some 10⁸ steps in all).
    let text = model_text("cart_pendulum_pid.xml");
    let (r, max) = (vr(&text, "r"), vr(&text, MAX_STEPS_NAME));
    let c = instantiate(&text);
    // SAFETY: a live instance, valid arrays and out-pointers.
    unsafe {
        assert_eq!(fmi2SetRealInputDerivatives(c, &r, 1, &1, &1.0), Status::Ok);
        initialize(c, 1e-6);
        assert_eq!(get_int(c, max), DEFAULT_MAX_STEPS as i32);
        // Tunable: set after initialization, it holds from the next step.
        assert_eq!(set_int(c, max, 200), Status::Ok);
        assert_eq!(get_int(c, max), 200);
        let before = engine_stats(c);
        assert_eq!(fmi2DoStep(c, 0.0, 1e6, 1), Status::Discard);
        let after = engine_stats(c);
        let reached = last_time(c);
        assert!(reached > 0.0 && reached < 1e6, "{reached}");
        let m = messages(c);
        let discard = m.iter().find(|s| s.starts_with("fmi2DoStep: step from 0 to 1000000 stopped at ")).unwrap();
        assert!(discard.contains("step limit reached: 200 integrator steps"), "{discard}");
        assert!(discard.contains("raise the limit (FMU parameter solver.maxSteps"), "{discard}");
        // The engine stopped at exactly the limit: 200 attempts, each accepted or rejected
        // (measured: reaching t = 2.5).
        let stats = after.unwrap().0;
        assert_eq!(attempts_between(before, after), 200, "{stats:?}");
        assert_eq!(stats.accepted + stats.rejected, stats.steps, "{stats:?}");
        assert_eq!(fmi2SetInteger(c, &max, 1, &300), Status::Error, "not in StepFailed");

        // Continue from the time reached: a state taken after the discard is the engine at
        // fmi2LastSuccessfulTime, restored as a completed step.
        let mut s: *mut libc::c_void = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        assert_eq!(fmi2SetFMUstate(c, s), Status::Ok);
        assert_eq!(host::state(c), Some(State::StepComplete));
        assert_eq!(get_int(c, max), 200, "the state carries solver.maxSteps");
        assert_eq!(fmi2DoStep(c, reached, 0.01, 1), Status::Ok, "{:?}", messages(c));
        assert_eq!(last_time(c), reached + 0.01);
        assert!(get(c, &[vr(&text, "angle")])[0].is_finite());
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
    }
    free(c);
}

#[test]
fn solver_max_steps_refuses_values_below_one_and_travels_with_the_fmu_state() {
    let text = model_text("pendulum.xml");
    let max = vr(&text, MAX_STEPS_NAME);
    let c = instantiate(&text);
    // SAFETY: a live instance, valid arrays and out-pointers, states of this FMU.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, 1e-6, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(get_int(c, max), DEFAULT_MAX_STEPS as i32, "readable in initialization mode");
        for bad in [0, -3, i32::MIN] {
            assert_eq!(set_int(c, max, bad), Status::Error);
            let m = messages(c).pop().unwrap();
            assert!(m.starts_with(&format!("fmi2SetInteger: value {bad} for 'solver.maxSteps' (vr {max})")), "{m}");
            assert_eq!(get_int(c, max), DEFAULT_MAX_STEPS as i32, "refused value not applied");
        }
        // Both values are checked before either is applied.
        let (vrs, vals) = ([max, max], [500, 0]);
        assert_eq!(fmi2SetInteger(c, vrs.as_ptr(), 2, vals.as_ptr()), Status::Error);
        assert_eq!(get_int(c, max), DEFAULT_MAX_STEPS as i32);
        // It is an Integer; the model's variables are Real.
        let mut x = 0.0;
        assert_eq!(fmi2GetReal(c, &max, 1, &mut x), Status::Error);
        assert!(messages(c).pop().unwrap().contains("is an Integer variable"));
        assert_eq!(fmi2SetReal(c, &max, 1, &5.0), Status::Error);
        let mut i = 0;
        assert_eq!(fmi2GetInteger(c, &0, 1, &mut i), Status::Error);
        assert!(messages(c).pop().unwrap().contains("'m' (vr 0) is a Real variable"));
        assert_eq!(fmi2GetInteger(c, &(max + 1), 1, &mut i), Status::Error);
        assert!(messages(c).pop().unwrap().contains(&format!("unknown value reference {}", max + 1)));

        // Still usable: set in initialization mode, initialized, stepped.
        assert_eq!(set_int(c, max, 500), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);
        assert_eq!(get_int(c, max), 500);
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), Status::Ok);

        // The FMU state carries it, in memory and serialized (into another instance).
        let mut s: *mut libc::c_void = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), Status::Ok);
        assert_eq!(set_int(c, max, 700), Status::Ok);
        assert_eq!(fmi2SetFMUstate(c, s), Status::Ok);
        assert_eq!(get_int(c, max), 500);
        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut size), Status::Ok);
        let mut bytes = vec![0 as libc::c_char; size];
        assert_eq!(fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), size), Status::Ok);
        let d = instantiate(&text);
        let mut s2: *mut libc::c_void = std::ptr::null_mut();
        assert_eq!(fmi2DeSerializeFMUstate(d, bytes.as_ptr(), size, &mut s2), Status::Ok);
        assert_eq!(fmi2SetFMUstate(d, s2), Status::Ok, "{:?}", messages(d));
        assert_eq!(get_int(d, max), 500);
        // A limit of one attempt cannot cross 1 s (half a swing) of the pendulum: discard.
        assert_eq!(set_int(d, max, 1), Status::Ok);
        assert_eq!(fmi2DoStep(d, 0.1, 1.0, 1), Status::Discard);
        assert!(messages(d).iter().any(|m| m.contains("step limit reached: 1 integrator steps")), "{:?}", messages(d));
        assert_eq!(fmi2SetFMUstate(d, s2), Status::Ok);
        assert_eq!(get_int(d, max), 500);
        assert_eq!(fmi2DoStep(d, 0.1, 0.1, 1), Status::Ok, "{:?}", messages(d));
        // fmi2Reset restores the default.
        assert_eq!(fmi2Reset(d), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(d), Status::Ok);
        assert_eq!(get_int(d, max), DEFAULT_MAX_STEPS as i32);
        assert_eq!(fmi2FreeFMUstate(d, &mut s2), Status::Ok);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), Status::Ok);
        free(d);
    }
    free(c);
}

#[test]
fn the_cli_bounds_each_communication_step_with_max_steps() {
    let run = |args: &[&str]| {
        let out =
            std::process::Command::new(env!("CARGO_BIN_EXE_mbfmu")).args(args).current_dir(root()).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    // One attempt cannot cover a 1 s communication step of the pendulum.
    let (code, err) = run(&["simulate", "models/pendulum.xml", "--end", "1", "--step", "1", "--max-steps", "1"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("step limit reached: 1 integrator steps (accepted and rejected) from t = 0 "), "{err}");
    let (code, err) = run(&["simulate", "models/pendulum.xml", "--end", "1", "--step", "1", "--max-steps", "0"]);
    assert_eq!(code, Some(2), "a usage error: {err}");
    let (code, err) = run(&["linearize", "models/pendulum.xml", "--at", "1", "--max-steps", "1"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("step limit reached: 1 integrator steps"), "{err}");
    // The toggle: the step size collapses at t*.
    let (code, err) = run(&["simulate", "tests/models/fourbar_toggle.xml", "--end", "2.2", "--step", "0.1"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("step size collapsed at t = 2.0063086"), "{err}");
}
