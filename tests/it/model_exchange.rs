//! FMI 2.0 Model Exchange through the C API, called as an integrating host would (issue
//! 29): at the start ME answers what Co-Simulation does; at states the host sets, ẋ and
//! y equal the tests' own state-space map (tests/it/common, Newton on a dense system
//! written apart from the engine) and the directional derivatives equal central
//! differences of fmi2GetDerivatives; an RK4 host loop follows the Co-Simulation
//! trajectory; states that do not determine the mechanism (a four-bar's rocker angle past
//! or at its dead point) are fmi2Error naming the state, with the instance intact; bad
//! calls are refused; the FMU state carries the host's time and states.

use crate::common::host::{self, free, get, last_message, messages, resources_of};
use crate::common::{guid_of, model_dir, model_files, state_space};
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::exports_me::*;
use mbfmu::fmi::exports_state::*;
use mbfmu::fmi::types::{CO_SIMULATION, Component, EventInfo, FmuStatePtr, MODEL_EXCHANGE, Status};
use mbfmu::fmi::variables::{Causality, Standard, variables};
use mbfmu::linearize::{StateLayout, select_states};
use std::ffi::CString;
use std::path::{Path, PathBuf};

/// An initialized instance and the value references a host reads from its XML.
struct Fmu {
    c: Component,
    /// States, in `<Derivatives>` order (the order of fmi2GetContinuousStates).
    x: Vec<u32>,
    /// Their derivatives, same order.
    dx: Vec<u32>,
    /// Outputs.
    y: Vec<u32>,
    /// Inputs.
    u: Vec<u32>,
}

/// Model `path` (its text `text`, written to a resources directory of its own) as a host
/// instantiates it (`kind`: ME or CS) and initializes it at tolerance `tol`; an ME
/// instance is taken on to Continuous-Time Mode.
fn open(path: &Path, text: Option<&str>, kind: i32, tol: f64) -> Fmu {
    let (uri, guid, model) = match text {
        Some(t) => {
            let uri = host::resources(t, "me").1;
            (uri, crate::common::guid(t), mbfmu::model::parse::load_str(t, "model.xml").unwrap())
        }
        None => (resources_of(path, "me").1, guid_of(path), mbfmu::model::load_file(path).unwrap()),
    };
    let vars = variables(&model, &StateLayout::at_start(&model), Standard::Fmi2);
    let sorted = |key: &dyn Fn(&mbfmu::fmi::variables::Variable) -> Option<usize>| {
        let mut v: Vec<(usize, u32)> = vars.iter().filter_map(|v| key(v).map(|k| (k, v.value_reference))).collect();
        v.sort();
        v.into_iter().map(|(_, r)| r).collect::<Vec<u32>>()
    };
    let by = |c: Causality| vars.iter().filter(|v| v.causality == c).map(|v| v.value_reference).collect();
    let g = CString::new(guid).unwrap();
    // SAFETY: valid NUL-terminated strings; the host's callbacks.
    let (c, logged) = unsafe { host::instantiate_logged(c"me".as_ptr(), kind, g.as_ptr(), uri.as_ptr(), 0, 1) };
    assert!(!c.is_null(), "{}: not instantiated: {logged:?}", path.display());
    // SAFETY: a live instance; a writable event info.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 1, tol, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok, "{:?}", messages(c));
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok, "{:?}", messages(c));
        if kind == MODEL_EXCHANGE {
            let mut info = EventInfo::default();
            assert_eq!(fmi2NewDiscreteStates(c, &mut info), Status::Ok);
            assert_eq!(info.new_discrete_states_needed, 0, "no events");
            assert_eq!(fmi2EnterContinuousTimeMode(c), Status::Ok);
        }
    }
    Fmu { c, x: sorted(&|v| v.known), dx: sorted(&|v| v.unknown), y: by(Causality::Output), u: by(Causality::Input) }
}

impl Fmu {
    fn states(&self) -> Vec<f64> {
        let mut x = vec![0.0; self.x.len()];
        // SAFETY: nx writable elements.
        assert_eq!(unsafe { fmi2GetContinuousStates(self.c, x.as_mut_ptr(), x.len()) }, Status::Ok);
        x
    }
    fn set(&self, t: f64, x: &[f64]) {
        // SAFETY: nx elements.
        unsafe {
            assert_eq!(fmi2SetTime(self.c, t), Status::Ok, "{:?}", messages(self.c));
            assert_eq!(fmi2SetContinuousStates(self.c, x.as_ptr(), x.len()), Status::Ok, "{:?}", messages(self.c));
        }
    }
    /// ẋ, or the status and message of the refusal.
    fn try_derivatives(&self) -> Result<Vec<f64>, (Status, String)> {
        let mut d = vec![0.0; self.x.len()];
        // SAFETY: nx writable elements.
        match unsafe { fmi2GetDerivatives(self.c, d.as_mut_ptr(), d.len()) } {
            Status::Ok => Ok(d),
            s => Err((s, last_message(self.c))),
        }
    }
    fn derivatives(&self) -> Vec<f64> {
        self.try_derivatives().unwrap_or_else(|e| panic!("{e:?}"))
    }
    /// Column `known` of ∂(unknowns)/∂(known) by fmi2GetDirectionalDerivative.
    fn column(&self, unknowns: &[u32], known: u32) -> Vec<f64> {
        let mut v = vec![f64::NAN; unknowns.len()];
        // SAFETY: arrays of the sizes passed.
        let s = unsafe {
            fmi2GetDirectionalDerivative(self.c, unknowns.as_ptr(), unknowns.len(), &known, 1, &1.0, v.as_mut_ptr())
        };
        assert_eq!(s, Status::Ok, "{:?}", messages(self.c));
        v
    }
    /// [A B; C D] column by column (states, then inputs).
    fn jacobian(&self) -> Vec<Vec<f64>> {
        let rows: Vec<u32> = self.dx.iter().chain(&self.y).copied().collect();
        self.x.iter().chain(&self.u).map(|&k| self.column(&rows, k)).collect()
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * (1.0 + a.abs().max(b.abs()))
}

/// The example models that have continuous states (all of them today).
fn examples() -> Vec<PathBuf> {
    model_files()
        .into_iter()
        .filter(|p| StateLayout::at_start(&mbfmu::model::load_file(p).unwrap()).missing.is_none())
        .collect()
}

#[test]
fn at_the_start_model_exchange_answers_what_co_simulation_does_on_every_example() {
    // Same consistent point (initialization is shared): x, ẋ, y and the whole Jacobian
    // [A B; C D] agree to 1e-12 relative (round-off of two evaluations of one point).
    // Then x is moved by 1e-3 and set back: the placement from the moved point (Newton to
    // 1e-12) returns ẋ to 1e-9 of the start's (relative to its largest entry).
    let list = examples();
    assert!(list.len() >= 13, "{list:?}");
    for path in &list {
        let me = open(path, None, MODEL_EXCHANGE, 1e-8);
        let cs = open(path, None, CO_SIMULATION, 1e-8);
        let name = path.display();
        let x0 = me.states();
        let d0 = me.derivatives();
        for (what, a, b) in
            [("x", &x0, &get(cs.c, &cs.x)), ("ẋ", &d0, &get(cs.c, &cs.dx)), ("y", &get(me.c, &me.y), &get(cs.c, &cs.y))]
        {
            for (k, (p, q)) in a.iter().zip(b).enumerate() {
                assert!(close(*p, *q, 1e-12), "{name}: {what}[{k}] ME {p} vs CS {q}");
            }
        }
        let jac = me.jacobian();
        for (j, (a, b)) in jac.iter().zip(cs.jacobian()).enumerate() {
            for (i, (p, q)) in a.iter().zip(&b).enumerate() {
                assert!(close(*p, q.to_owned(), 1e-12), "{name}: J[{i},{j}] ME {p} vs CS {q}");
            }
        }
        let moved: Vec<f64> = x0.iter().map(|v| v + 1e-3).collect();
        me.set(0.0, &moved);
        let dm = me.derivatives();
        assert!(x0.is_empty() || dm.iter().zip(&d0).any(|(a, b)| a != b), "{name}: moving x changed nothing");
        me.set(0.0, &x0);
        // Tolerance of row k: 1e-9 (1 + max|ẋ|) plus what the placement's 1e-12 (1 +
        // max|q|) ≤ 1e-11 in the coordinates makes of it through the row of A (a stiff
        // elastic mode has entries of 1e9).
        let scale = d0.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        for (k, (p, q)) in me.derivatives().iter().zip(&d0).enumerate() {
            let stiff = jac.iter().take(x0.len()).fold(0.0f64, |m, col| m.max(col[k].abs()));
            assert!((p - q).abs() <= 1e-9 * scale + 1e-11 * stiff, "{name}: ẋ[{k}] back at x0 {p} vs {q}");
        }
        free(me.c);
        free(cs.c);
    }
}

/// Holonomic examples without user states or variables: those the tests' state-space
/// map covers.
const MAPPED: [&str; 6] = [
    "pendulum.xml",
    "double_pendulum.xml",
    "fourbar.xml",
    "slider_crank.xml",
    "spinning_top.xml",
    "torque_free_body.xml",
];

#[test]
fn at_states_the_host_sets_derivatives_and_outputs_equal_the_tests_state_space_map() {
    // x away from any point the engine integrated to (each state moved by 0.05..0.2):
    // the FMU's placement (sparse Newton from the last point) against the map's dense
    // Newton to 1e-15 from the start: 1e-9 relative (the FMU places to 1e-12).
    for file in MAPPED {
        let path = model_dir().join(file);
        let me = open(&path, None, MODEL_EXCHANGE, 1e-8);
        let model = mbfmu::model::load_file(&path).unwrap();
        let sim = Simulator::new(&model, SimOptions { tol: 1e-10, ..Default::default() }, 0.0).unwrap();
        let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
        let x: Vec<f64> =
            me.states().iter().enumerate().map(|(k, v)| v + 0.05 * (1 + k % 4) as f64 * [1.0, -1.0][k % 2]).collect();
        let t = 0.3;
        me.set(t, &x);
        // The map evaluates angles near the references of the start, not extrapolated
        // with their rates to t (the FMU, too, takes the branch from the states).
        let mut sys = sim.system().clone();
        sys.angle_time = t;
        let (f, y) = state_space(&sys, &sel, sim.q(), t, &x, &sim.inputs());
        for (k, (p, q)) in me.derivatives().iter().zip(&f).enumerate() {
            assert!(close(*p, *q, 1e-9), "{file}: ẋ[{k}] FMU {p} vs map {q}");
        }
        for (k, (p, q)) in get(me.c, &me.y).iter().zip(&y).enumerate() {
            assert!(close(*p, *q, 1e-9), "{file}: y[{k}] FMU {p} vs map {q}");
        }
        free(me.c);
    }
}

#[test]
fn directional_derivatives_at_a_set_state_equal_central_differences_of_get_derivatives() {
    // At a state the host set (not a communication point): A and C columns from Eq. 34
    // against fourth-order central differences of fmi2GetDerivatives / fmi2GetReal,
    // h = 1e-4 (truncation O(h⁴) = 1e-16). Tolerance of entry (i, j): 1e-7 of column j's
    // largest entry, plus the placement's round-off, 1e-12 (1 + max|x|) in the positions,
    // through row i's largest position entry and divided by h (1e-6 relative for a stiff
    // elastic mode's 1e9, 2e-6 absolute for a rigid model's entries of 100).
    for path in examples() {
        let name = path.display();
        let me = open(&path, None, MODEL_EXCHANGE, 1e-8);
        // Moved by 2 % of each state (at least 1e-3): an elastic mode moved by more than
        // its own size would be a state no motion reaches.
        let x: Vec<f64> =
            me.states().iter().enumerate().map(|(k, v)| v + 0.02 * v.abs().max(0.05) * [1.0, -1.0][k % 2]).collect();
        me.set(0.1, &x);
        let jac = me.jacobian();
        let rows: Vec<u32> = me.dx.iter().chain(&me.y).copied().collect();
        let row_scale: Vec<f64> =
            (0..rows.len()).map(|i| jac.iter().take(x.len()).fold(0.0f64, |m, col| m.max(col[i].abs()))).collect();
        let size = 1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let eval = |xs: &[f64]| {
            me.set(0.1, xs);
            let mut v = me.derivatives();
            v.extend(get(me.c, &me.y));
            v
        };
        for (j, col) in jac.iter().take(x.len()).enumerate() {
            let h = 1e-4 * x[j].abs().max(1.0);
            let at = |d: f64| {
                let mut xs = x.clone();
                xs[j] += d;
                eval(&xs)
            };
            let (p1, m1, p2, m2) = (at(h), at(-h), at(2.0 * h), at(-2.0 * h));
            let scale = col.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            for (i, c) in col.iter().enumerate() {
                let fd = (8.0 * (p1[i] - m1[i]) - (p2[i] - m2[i])) / (12.0 * h);
                let tol = 1e-7 * scale + 1e-12 * size * row_scale[i] / h;
                assert!((c - fd).abs() <= tol, "{name}: ∂{}/∂x{j}: {c} vs fd {fd} (tol {tol:.1e})", rows[i]);
            }
        }
        free(me.c);
    }
}

/// Classic RK4 over `n` steps of `h` through the ME interface, fmi2CompletedIntegratorStep
/// after each; the outputs at the end, or the refusal.
fn rk4(me: &Fmu, h: f64, n: usize) -> Result<Vec<f64>, (usize, String)> {
    let mut x = me.states();
    let mut t = 0.0;
    for step in 0..n {
        let stage = |tt: f64, xs: &[f64]| {
            me.set(tt, xs);
            me.try_derivatives().map_err(|(_, m)| (step, m))
        };
        let k1 = stage(t, &x)?;
        let x2: Vec<f64> = x.iter().zip(&k1).map(|(a, k)| a + 0.5 * h * k).collect();
        let k2 = stage(t + 0.5 * h, &x2)?;
        let x3: Vec<f64> = x.iter().zip(&k2).map(|(a, k)| a + 0.5 * h * k).collect();
        let k3 = stage(t + 0.5 * h, &x3)?;
        let x4: Vec<f64> = x.iter().zip(&k3).map(|(a, k)| a + h * k).collect();
        let k4 = stage(t + h, &x4)?;
        for i in 0..x.len() {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        t += h;
        me.set(t, &x);
        let (mut enter, mut terminate) = (1, 1);
        // SAFETY: writable flags.
        let s = unsafe { fmi2CompletedIntegratorStep(me.c, 1, &mut enter, &mut terminate) };
        if s != Status::Ok {
            return Err((step, last_message(me.c)));
        }
        assert_eq!((enter, terminate), (0, 0), "no events, no termination");
    }
    Ok(get(me.c, &me.y))
}

#[test]
fn an_rk4_host_loop_follows_the_co_simulation_trajectory() {
    // The double pendulum (chaotic, so a hard test of drift-free placement) and the
    // four-bar (a closed loop through a full crank turn, 0.5 s at 20 rad/s) for 0.5 s,
    // RK4 at h = 1 ms (error ~ h⁴ = 1e-12 per unit time, amplified by the motion) against
    // Co-Simulation at tolerance 1e-10: outputs to 1e-6.
    for (file, h) in [("double_pendulum.xml", 1e-3), ("fourbar.xml", 1e-3)] {
        let path = model_dir().join(file);
        let me = open(&path, None, MODEL_EXCHANGE, 1e-8);
        let y_me = rk4(&me, h, 500).unwrap_or_else(|e| panic!("{file}: {e:?}"));
        let cs = open(&path, None, CO_SIMULATION, 1e-10);
        // SAFETY: a live instance.
        assert_eq!(unsafe { fmi2DoStep(cs.c, 0.0, 0.5, 1) }, Status::Ok);
        for (k, (a, b)) in y_me.iter().zip(get(cs.c, &cs.y)).enumerate() {
            assert!(close(*a, b, 1e-6), "{file}: y[{k}] ME {a} vs CS {b}");
        }
        free(me.c);
        free(cs.c);
    }
}

/// The four-bar with its rocker angle ψ as the one state. ψ parameterizes the loop only
/// inside (-143.13°, -95.74°): at the ends the crank and coupler are aligned (dead
/// points of ψ, cos ψ = -0.1 and -0.8 from the link lengths), outside the loop does not close.
fn rocker_fourbar() -> String {
    let text = std::fs::read_to_string(model_dir().join("fourbar.xml")).unwrap();
    text.replace(
        "</multibody>",
        r#"<linearization><state name="rocker_psi" function="az(rocker.Q, ground.O2)"/></linearization></multibody>"#,
    )
}

#[test]
fn states_that_stop_parameterizing_the_mechanism_are_an_error_naming_them_and_the_instance_recovers() {
    let text = rocker_fourbar();
    let path = model_dir().join("fourbar.xml");
    let me = open(&path, Some(&text), MODEL_EXCHANGE, 1e-8);
    let x0 = me.states();
    assert_eq!(x0.len(), 2);
    assert!((x0[0] - (-98.950262f64).to_radians()).abs() < 1e-6, "psi0 = {}", x0[0]);
    // ẋ at x0 as placed from a nearby point (the engine then sits at x0's point).
    me.set(0.0, &[x0[0] + 1e-3, x0[1]]);
    me.set(0.0, &x0);
    let d0 = me.derivatives();
    let dead = -(0.1f64.acos());
    for (psi, what) in [(0.0, "outside the loop's range"), (dead, "at the dead point")] {
        me.set(0.0, &[psi, x0[1]]);
        let (s, m) = me.try_derivatives().expect_err(what);
        assert_eq!(s, Status::Error, "{what}");
        assert!(m.starts_with("fmi2GetDerivatives") && m.contains("rocker_psi"), "{what}: {m}");
        // Every read at that point says so; the state machine is untouched.
        let mut v = [0.0];
        // SAFETY: one-element arrays.
        assert_eq!(unsafe { fmi2GetReal(me.c, me.y.as_ptr(), 1, v.as_mut_ptr()) }, Status::Error, "{what}");
        // The engine stayed at the last good point: back there, the same answer to
        // round-off (one more Newton correction of 1e-16).
        me.set(0.0, &x0);
        for (a, b) in me.derivatives().iter().zip(&d0) {
            assert!(close(*a, *b, 1e-13), "{what}: back at the start {a} vs {b}");
        }
    }
    // Integrated by the host, the rocker reaches its dead point within the crank's first
    // turn: the FMU refuses there rather than integrating through it.
    let (step, m) = rk4(&me, 1e-3, 400).expect_err("the dead point is refused");
    assert!(step > 5 && m.contains("rocker_psi"), "step {step}: {m}");
    free(me.c);
}

/// fmi2CompletedIntegratorStep at (t, x); its status and, unless Ok, the message.
fn complete_step_at(me: &Fmu, t: f64, x: &[f64]) -> Result<(), String> {
    me.set(t, x);
    let (mut enter, mut terminate) = (1, 1);
    // SAFETY: writable flags.
    match unsafe { fmi2CompletedIntegratorStep(me.c, 1, &mut enter, &mut terminate) } {
        Status::Ok => Ok(()),
        _ => Err(last_message(me.c)),
    }
}

#[test]
fn a_host_step_through_a_fold_of_the_states_chart_is_an_error_naming_the_states() {
    // blade_y: the blade turns with the hub, α = w t (w = 10), its CM at (12 cos wt,
    // 12 sin wt), and its one state is y = 12 sin(wt), ẏ = 120 cos(wt) — a chart of the
    // blade's angle only on |α| < π/2. The host gives the exact states of that motion.
    // Before the fold (t = 0.15 → 0.155) the accepted steps are accepted; the step
    // 0.15 → 0.16 goes through y = 12 at t = π/20: the states at 0.16 (y = 11.9949 < 12,
    // ẏ < 0) have a configuration on the branch the engine is on (the blade swung back)
    // and one past the fold (the blade going on), and the step is refused, naming the state
    // and the step; the instance then still answers at the last accepted point.
    let path = model_dir().join("blade_y.xml");
    let me = open(&path, None, MODEL_EXCHANGE, 1e-8);
    let exact = |t: f64| [12.0 * (10.0 * t).sin(), 120.0 * (10.0 * t).cos()];
    assert!(me.states().iter().zip(exact(0.0)).all(|(a, b)| (a - b).abs() < 1e-9), "{:?}", me.states());
    for t in [0.05, 0.1, 0.15, 0.155] {
        complete_step_at(&me, t, &exact(t)).unwrap_or_else(|m| panic!("t = {t}: {m}"));
    }
    let before = me.derivatives();
    // The step from 0.155 over the fold: refused.
    let m = complete_step_at(&me, 0.16, &exact(0.16)).expect_err("the fold is refused");
    assert!(
        m.starts_with("fmi2CompletedIntegratorStep")
            && m.contains("between t = 0.155 and t = 0.16")
            && m.contains("yb = ")
            && m.contains("do not parameterize"),
        "{m}"
    );
    // The engine answers again at the states it last accepted.
    me.set(0.155, &exact(0.155));
    for (a, b) in me.derivatives().iter().zip(&before) {
        assert!(close(*a, *b, 1e-9), "back at t = 0.155: {a} vs {b}");
    }
    free(me.c);
}

/// A rotor about ground z (Izz = 0.5) driven by T = sqrt(1 - time): ω̇ = 2 sqrt(1 - t),
/// which stops existing at t = 1.
const DOOMED: &str = r#"<multibody name="doomed" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="1" inertia="0.2 0.3 0.5" position="0 0 0"/>
  <joint name="axle" type="revolute" i="r.cm" j="ground.O"/>
  <gforce name="motor" i="r.cm" force="0 0 0" torque="0, 0, sqrt(1 - time)"/>
  <output name="w" function="wz(r.cm)"/>
</multibody>"#;

#[test]
fn time_may_go_back_bad_states_and_calls_are_refused_and_the_instance_stays_usable() {
    let path = PathBuf::from("doomed.xml");
    let me = open(&path, Some(DOOMED), MODEL_EXCHANGE, 1e-8);
    let x = me.states();
    assert_eq!(x.len(), 2);
    // ω̇ = 2 sqrt(1 - t): at t = 0.19, 0.64 and back at 0.19 (a host retrying a step).
    for t in [0.19, 0.64, 0.19] {
        me.set(t, &x);
        let want = 2.0 * (1.0f64 - t).sqrt();
        let d = me.derivatives();
        assert!((d[1] - want).abs() < 1e-12, "t = {t}: {} vs {want}", d[1]);
        assert_eq!(d[0], x[1], "the angle's rate is the rate state");
    }
    let c = me.c;
    let bad = |s: Status, func: &str, what: &str| {
        assert_eq!(s, Status::Error, "{func} {what}");
        let m = last_message(c);
        assert!(m.starts_with(func) && m.contains(what), "{func}: {m}");
    };
    let mut out = [0.0; 3];
    // SAFETY: arrays of at least the sizes passed, or NULL with a count the FMU refuses.
    unsafe {
        // Past t = 1 the torque is not real: the derivatives are refused, not NaN.
        me.set(1.5, &x);
        let (s, m) = me.try_derivatives().unwrap_err();
        assert!(s == Status::Error && m.starts_with("fmi2GetDerivatives"), "{m}");
        me.set(0.19, &x);
        assert!((me.derivatives()[1] - 1.8).abs() < 1e-12);
        bad(fmi2SetContinuousStates(c, [f64::NAN, 0.0].as_ptr(), 2), "fmi2SetContinuousStates", "not a finite number");
        bad(fmi2SetContinuousStates(c, out.as_ptr(), 3), "fmi2SetContinuousStates", "nx = 3, but the model has 2");
        bad(fmi2SetContinuousStates(c, std::ptr::null(), 2), "fmi2SetContinuousStates", "NULL");
        bad(fmi2GetDerivatives(c, out.as_mut_ptr(), 1), "fmi2GetDerivatives", "nx = 1");
        bad(fmi2GetEventIndicators(c, out.as_mut_ptr(), 1), "fmi2GetEventIndicators", "no event indicators");
        bad(fmi2SetTime(c, f64::NAN), "fmi2SetTime", "not finite");
        bad(fmi2DoStep(c, 0.0, 0.1, 1), "fmi2DoStep", "not allowed in state ContinuousTimeMode");
        bad(fmi2EnterInitializationMode(c), "fmi2EnterInitializationMode", "not allowed");
        let mut nominal = [0.0; 2];
        assert_eq!(fmi2GetNominalsOfContinuousStates(c, nominal.as_mut_ptr(), 2), Status::Ok);
        assert_eq!(nominal, [1.0, 1.0]);
        // The rejected values changed nothing.
        assert_eq!(me.states(), x);
        assert!((me.derivatives()[1] - 1.8).abs() < 1e-12);
        // Event mode and back, then the end of the lifecycle and a new one.
        assert_eq!(fmi2EnterEventMode(c), Status::Ok);
        let (mut enter, mut stop) = (0, 0);
        let completed = fmi2CompletedIntegratorStep(c, 1, &mut enter, &mut stop);
        bad(completed, "fmi2CompletedIntegratorStep", "not allowed in state EventMode");
        assert_eq!(fmi2EnterContinuousTimeMode(c), Status::Ok);
        assert_eq!(fmi2Terminate(c), Status::Ok);
        assert_eq!(fmi2Reset(c), Status::Ok);
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(c), Status::Ok);
        assert_eq!(fmi2EnterContinuousTimeMode(c), Status::Ok);
        assert_eq!(me.states(), [0.0, 0.0], "the reset instance starts over");
        assert!((me.derivatives()[1] - 2.0).abs() < 1e-12);
    }
    free(c);
}

#[test]
fn the_fmu_state_carries_the_hosts_time_and_states() {
    let path = model_dir().join("double_pendulum.xml");
    let me = open(&path, None, MODEL_EXCHANGE, 1e-8);
    let x1: Vec<f64> = me.states().iter().map(|v| v + 0.1).collect();
    me.set(0.2, &x1);
    let d1 = me.derivatives();
    let mut st: FmuStatePtr = std::ptr::null_mut();
    // SAFETY: a live instance, writable handles and buffers of the sizes passed.
    unsafe {
        assert_eq!(fmi2GetFMUstate(me.c, &mut st), Status::Ok);
        let mut n = 0;
        assert_eq!(fmi2SerializedFMUstateSize(me.c, st, &mut n), Status::Ok);
        let mut bytes = vec![0i8; n];
        assert_eq!(fmi2SerializeFMUstate(me.c, st, bytes.as_mut_ptr(), n), Status::Ok);
        let x2: Vec<f64> = x1.iter().map(|v| v - 0.3).collect();
        me.set(0.4, &x2);
        assert_ne!(me.derivatives(), d1);
        assert_eq!(fmi2SetFMUstate(me.c, st), Status::Ok);
        assert_eq!(me.states(), x1);
        assert_eq!(me.derivatives(), d1);
        me.set(0.4, &x2);
        let mut back: FmuStatePtr = std::ptr::null_mut();
        assert_eq!(fmi2DeSerializeFMUstate(me.c, bytes.as_ptr(), n, &mut back), Status::Ok);
        assert_eq!(fmi2SetFMUstate(me.c, back), Status::Ok);
        assert_eq!(me.states(), x1);
        assert_eq!(me.derivatives(), d1);
        // A Model Exchange instance's state is not a Co-Simulation one, nor the reverse
        // (the bytes travel; the instance refuses them and stays as it was).
        let cs = open(&path, None, CO_SIMULATION, 1e-8);
        let mut into_cs: FmuStatePtr = std::ptr::null_mut();
        assert_eq!(fmi2DeSerializeFMUstate(cs.c, bytes.as_ptr(), n, &mut into_cs), Status::Ok);
        assert_eq!(fmi2SetFMUstate(cs.c, into_cs), Status::Error);
        let m = last_message(cs.c);
        assert!(m.contains("saved by a Model Exchange instance; this one is Co-Simulation"), "{m}");
        let mut cs_state: FmuStatePtr = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(cs.c, &mut cs_state), Status::Ok);
        let mut k = 0;
        assert_eq!(fmi2SerializedFMUstateSize(cs.c, cs_state, &mut k), Status::Ok);
        let mut cs_bytes = vec![0i8; k];
        assert_eq!(fmi2SerializeFMUstate(cs.c, cs_state, cs_bytes.as_mut_ptr(), k), Status::Ok);
        let mut into_me: FmuStatePtr = std::ptr::null_mut();
        assert_eq!(fmi2DeSerializeFMUstate(me.c, cs_bytes.as_ptr(), k, &mut into_me), Status::Ok);
        assert_eq!(fmi2SetFMUstate(me.c, into_me), Status::Error);
        assert_eq!(me.derivatives(), d1, "the refused state changed nothing");
        fmi2FreeFMUstate(cs.c, &mut cs_state);
        fmi2FreeFMUstate(cs.c, &mut into_cs);
        fmi2FreeFMUstate(me.c, &mut into_me);
        fmi2FreeFMUstate(me.c, &mut st);
        fmi2FreeFMUstate(me.c, &mut back);
        free(cs.c);
    }
    free(me.c);
}
