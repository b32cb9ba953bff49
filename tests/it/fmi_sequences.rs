//! FMI call-sequence fuzzing (issue 12 item 5): random legal and illegal call orders over
//! every example model, with bad value references, NaN/Inf/huge values, zero, negative
//! and huge steps, stale and foreign FMU-state handles, corrupted serialized states, NULL
//! arrays, directional derivatives of random subsets, freed components; Model Exchange
//! instances with states set near, far, NaN and of the wrong count, derivatives read,
//! Euler steps completed, time going back. What must hold:
//! the process survives (a crash ends the test run), no call panics inside (the guard
//! would answer it, and logs "internal error (panic)"), every call returns, having made at
//! most `solver.maxSteps` integrator step attempts (counted, behind the C API: the bound
//! that makes a call of this FMU come back, whatever the machine's speed), and no call
//! answering fmi2OK hands out a value that is not finite.
//!
//! `MBFMU_FMI_SEQUENCES` (default 300, what CI runs) sets how many sequences;
//! `MBFMU_FMI_SEED` the base seed; `bench/fmi_sequences.sh` runs thousands.

use crate::common::host::{self, CALLBACKS, resources_of};
use crate::common::{attempts_between, engine_stats, guid_of, model_files};
use mbfmu::fmi::exports_common::*;
use mbfmu::fmi::exports_cs::*;
use mbfmu::fmi::exports_me::*;
use mbfmu::fmi::exports_state::*;
use mbfmu::fmi::types::{
    CO_SIMULATION, Component, DO_STEP_STATUS, EventInfo, FmuStatePtr, LAST_SUCCESSFUL_TIME, MODEL_EXCHANGE, Status,
    TERMINATED,
};
use mbfmu::fmi::variables::{Causality, variables};
use std::collections::BTreeMap;
use std::ffi::CString;
use std::time::Instant;

/// The largest `solver.maxSteps` the sequences set (or they leave the default). Whatever
/// the limit, no call may make more integrator step attempts than it: that is what bounds
/// a call (a doStep of 1e30 s, a runaway ramp), and the test counts it.
const MAX_STEPS: i32 = 3000;

/// splitmix64: a small, well-mixed generator, so a seed names a sequence exactly.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    pub(crate) fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    pub(crate) fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[self.below(v.len())]
    }
    /// A value: mostly ordinary, sometimes hostile.
    pub(crate) fn real(&mut self) -> f64 {
        match self.below(12) {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            3 => self.pick(&[1e308, -1e308, 1e-310, 1e30, -1e30]),
            4 => 0.0,
            _ => (self.next() >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0,
        }
    }
}

/// One model as the host sees it: its resource URI, GUID and value references.
struct Model {
    name: String,
    uri: CString,
    guid: CString,
    reals: Vec<u32>,
    parameters: Vec<u32>,
    inputs: Vec<u32>,
    outputs: Vec<u32>,
    knowns: Vec<u32>,
    unknowns: Vec<u32>,
    /// `solver.maxSteps`, the FMU's one Integer variable.
    max_steps: Option<u32>,
    /// Number of continuous states (Model Exchange).
    nx: usize,
}

fn models() -> Vec<Model> {
    model_files()
        .iter()
        .map(|path| {
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            let (_, uri) = resources_of(path, "sequences");
            let m = mbfmu::model::load_file(path).unwrap();
            let vars =
                variables(&m, &mbfmu::linearize::StateLayout::at_start(&m), mbfmu::fmi::variables::Standard::Fmi2);
            let vr = |f: &dyn Fn(&mbfmu::fmi::variables::Variable) -> bool| {
                vars.iter().filter(|v| f(v)).map(|v| v.value_reference).collect::<Vec<u32>>()
            };
            let max_steps = vars.iter().find(|v| v.target.is_integer()).map(|v| v.value_reference);
            Model {
                uri,
                guid: CString::new(guid_of(path)).unwrap(),
                reals: vr(&|v| Some(v.value_reference) != max_steps),
                parameters: vr(&|v| v.causality == Causality::Parameter && Some(v.value_reference) != max_steps),
                inputs: vr(&|v| v.causality == Causality::Input),
                outputs: vr(&|v| v.causality == Causality::Output),
                knowns: vr(&|v| v.known.is_some() || v.causality == Causality::Input),
                unknowns: vr(&|v| v.unknown.is_some() || v.causality == Causality::Output),
                max_steps,
                nx: vars.iter().filter(|v| v.known.is_some()).count(),
                name,
            }
        })
        .collect()
}

/// What the run saw.
#[derive(Default)]
struct Tally {
    calls: usize,
    by_status: BTreeMap<String, usize>,
    /// Calls answered fmi2OK, by function.
    ok_by_function: BTreeMap<String, usize>,
    /// The most integrator step attempts one call made, with the call and the limit then.
    busiest: (usize, String, usize),
    /// Calls that made integrator step attempts, and the attempts at the step limit.
    stepping_calls: usize,
    at_limit: usize,
    failures: Vec<String>,
}

impl Tally {
    /// Make the call `what` on component `c` (`f`), count the integrator step attempts it
    /// made against the instance's step limit, and check its status and messages.
    fn call(&mut self, c: Component, what: &str, f: impl FnOnce() -> Status) -> Status {
        let before = engine_stats(c);
        let s = f();
        let after = engine_stats(c);
        let attempts = attempts_between(before, after);
        // The limit in force during the call: the one before it (a SetInteger or a
        // SetFMUstate changes it for later calls) or, for an engine the call built, the
        // one after; the larger of the two.
        let limit = [before, after].iter().flatten().map(|&(_, l)| l).max().unwrap_or(usize::MAX);
        self.calls += 1;
        *self.by_status.entry(format!("{s:?}")).or_default() += 1;
        if s == Status::Ok {
            *self.ok_by_function.entry(what.to_string()).or_default() += 1;
        }
        if attempts > 0 {
            self.stepping_calls += 1;
            self.at_limit += usize::from(attempts == limit);
        }
        if attempts > self.busiest.0 {
            self.busiest = (attempts, what.to_string(), limit);
        }
        if attempts > limit {
            self.failures.push(format!("{what} made {attempts} integrator step attempts, over the limit {limit}"));
        }
        // What the instance told its logger (every message that passed its log filter, as
        // a panic's fmi2Error or fmi2Fatal always does).
        if let Some(m) = host::messages(c).iter().find(|m| m.contains("internal error (panic)")) {
            self.failures.push(format!("{what}: {m}"));
        }
        s
    }

    /// Values a call answered fmi2OK with must be finite.
    fn finite(&mut self, what: &str, s: Status, v: &[f64]) {
        if s == Status::Ok && v.iter().any(|x| !x.is_finite()) {
            self.failures.push(format!("{what} returned fmi2OK with {v:?}"));
        }
    }
}

/// A random subset (with repeats and strangers) of `vrs`.
fn refs(r: &mut Rng, vrs: &[u32], all: &[u32]) -> Vec<u32> {
    let n = r.below(6);
    (0..n)
        .map(|_| match r.below(10) {
            0 => r.pick(&[u32::MAX, 100_000, all.len() as u32]),
            1 if !all.is_empty() => r.pick(all),
            _ if !vrs.is_empty() => r.pick(vrs),
            _ => r.next() as u32 % 64,
        })
        .collect()
}

/// The bytes of state `st` (`short`: into a buffer half the size it needs, which must be
/// refused).
fn serialize(tally: &mut Tally, c: Component, st: FmuStatePtr, short: bool) -> Vec<i8> {
    let mut n = 0usize;
    // SAFETY: a writable size; `c` live or refused.
    if tally.call(c, "fmi2SerializedFMUstateSize", || unsafe { fmi2SerializedFMUstateSize(c, st, &mut n) })
        != Status::Ok
    {
        return Vec::new();
    }
    let len = if short { n / 2 } else { n };
    let mut bytes = vec![0; len];
    // SAFETY: `len` writable bytes.
    let s = tally.call(c, "fmi2SerializeFMUstate", || unsafe { fmi2SerializeFMUstate(c, st, bytes.as_mut_ptr(), len) });
    if s == Status::Ok { bytes } else { Vec::new() }
}

/// One sequence on model `m`: instantiate (sometimes wrongly), then random calls.
fn sequence(r: &mut Rng, m: &Model, other: &Model, tally: &mut Tally) {
    let name = c"seq";
    let bad_guid = CString::new("{00000000-0000-0000-0000-000000000000}").unwrap();
    let guid = if r.chance(0.03) { &bad_guid } else { &m.guid };
    let fmu_type = if r.chance(0.03) {
        r.pick(&[0, 7, -1])
    } else if r.chance(0.35) {
        MODEL_EXCHANGE
    } else {
        CO_SIMULATION
    };
    // SAFETY: valid strings, and the host's callbacks with a recording logger (the wrong
    // GUID and type are refused values).
    let c = unsafe { host::instantiate(name.as_ptr(), fmu_type, guid.as_ptr(), m.uri.as_ptr(), 0, 1) };
    if c.is_null() {
        return;
    }
    // A second instance, of another model: its states are foreign handles here.
    // SAFETY: as above.
    let d = unsafe {
        fmi2Instantiate(name.as_ptr(), CO_SIMULATION, other.guid.as_ptr(), other.uri.as_ptr(), &CALLBACKS, 0, 0)
    };
    let mut foreign: FmuStatePtr = std::ptr::null_mut();
    if !d.is_null() {
        // SAFETY: a live instance and a writable handle.
        unsafe { fmi2GetFMUstate(d, &mut foreign) };
    }
    let mut states: Vec<FmuStatePtr> = Vec::new();
    let mut freed: Vec<FmuStatePtr> = Vec::new();
    let mut bytes: Vec<i8> = Vec::new();
    let mut time = 0.0;
    let mut alive = true;
    if let Some(vr) = m.max_steps
        && r.chance(0.9)
    {
        let n = r.pick(&[1, 10, 200, MAX_STEPS]);
        // SAFETY: one element each.
        tally.call(c, "fmi2SetInteger", || unsafe { fmi2SetInteger(c, &vr, 1, &n) });
    }
    // Mostly the legal opening, so that the random part reaches the stepping states.
    if r.chance(0.85) {
        let stop = r.chance(0.2);
        // SAFETY: a live instance.
        tally.call(c, "fmi2SetupExperiment", || unsafe { fmi2SetupExperiment(c, 1, 1e-6, 0.0, stop as i32, 5.0) });
        // SAFETY: a live instance.
        tally.call(c, "fmi2EnterInitializationMode", || unsafe { fmi2EnterInitializationMode(c) });
        if r.chance(0.9) {
            // SAFETY: a live instance.
            tally.call(c, "fmi2ExitInitializationMode", || unsafe { fmi2ExitInitializationMode(c) });
            if fmu_type == MODEL_EXCHANGE && r.chance(0.8) {
                let mut info = EventInfo::default();
                // SAFETY: a live instance, a writable event info.
                tally.call(c, "fmi2NewDiscreteStates", || unsafe { fmi2NewDiscreteStates(c, &mut info) });
                // SAFETY: a live instance.
                tally.call(c, "fmi2EnterContinuousTimeMode", || unsafe { fmi2EnterContinuousTimeMode(c) });
            }
        }
    }
    // Model Exchange: the host's states and time, moved as an integrator would (mostly).
    let mut x = vec![0.0; m.nx];
    if fmu_type == MODEL_EXCHANGE {
        // SAFETY: nx writable elements.
        tally.call(c, "fmi2GetContinuousStates", || unsafe { fmi2GetContinuousStates(c, x.as_mut_ptr(), m.nx) });
    }
    let n_calls = 5 + r.below(40);
    for _ in 0..n_calls {
        // SAFETY (every call below): the arrays passed hold the counts passed, or are NULL
        // with a count the FMU must refuse; `c` is a live or freed instance (a freed one
        // must be refused, which is part of what is tested).
        unsafe {
            match r.below(if fmu_type == MODEL_EXCHANGE { 40 } else { 30 }) {
                0 => {
                    let tol = if r.chance(0.7) { 1e-6 } else { r.real() };
                    tally.call(c, "fmi2SetupExperiment", || fmi2SetupExperiment(c, 1, tol, r.real(), 0, 0.0));
                }
                1 => {
                    tally.call(c, "fmi2EnterInitializationMode", || fmi2EnterInitializationMode(c));
                }
                2 => {
                    tally.call(c, "fmi2ExitInitializationMode", || fmi2ExitInitializationMode(c));
                }
                3..=6 => {
                    let h = if r.chance(0.7) { r.pick(&[0.01, 0.1, 0.5, 1.0]) } else { r.real() };
                    let t = if r.chance(0.8) { time } else { r.real() };
                    let s = tally.call(c, "fmi2DoStep", || fmi2DoStep(c, t, h, 0));
                    let mut last = f64::NAN;
                    let q =
                        tally.call(c, "fmi2GetRealStatus", || fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut last));
                    tally.finite("fmi2GetRealStatus", q, &[last]);
                    if q == Status::Ok {
                        time = last;
                    }
                    if s == Status::Discard && r.chance(0.5) && !states.is_empty() {
                        let st = r.pick(&states);
                        tally.call(c, "fmi2SetFMUstate", || fmi2SetFMUstate(c, st));
                    }
                }
                7..=8 => {
                    let vrs = refs(r, &m.reals, &m.reals);
                    let mut v = vec![f64::NAN; vrs.len()];
                    let s = tally.call(c, "fmi2GetReal", || fmi2GetReal(c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()));
                    tally.finite("fmi2GetReal", s, &v);
                }
                9..=10 => {
                    let pool = if r.chance(0.5) { &m.inputs } else { &m.parameters };
                    let vrs = refs(r, pool, &m.reals);
                    let v: Vec<f64> = vrs.iter().map(|_| r.real()).collect();
                    tally.call(c, "fmi2SetReal", || fmi2SetReal(c, vrs.as_ptr(), vrs.len(), v.as_ptr()));
                }
                11 => {
                    let vrs = refs(r, &m.inputs, &m.reals);
                    let orders: Vec<i32> =
                        vrs.iter().map(|_| if r.chance(0.8) { 1 } else { r.pick(&[0, 2, -1]) }).collect();
                    let v: Vec<f64> = vrs.iter().map(|_| r.real() * r.pick(&[1.0, 1e6])).collect();
                    tally.call(c, "fmi2SetRealInputDerivatives", || {
                        fmi2SetRealInputDerivatives(c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), v.as_ptr())
                    });
                }
                12 => {
                    let vrs = refs(r, &m.outputs, &m.reals);
                    let orders = vec![1; vrs.len()];
                    let mut v = vec![f64::NAN; vrs.len()];
                    let s = tally.call(c, "fmi2GetRealOutputDerivatives", || {
                        fmi2GetRealOutputDerivatives(c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), v.as_mut_ptr())
                    });
                    tally.finite("fmi2GetRealOutputDerivatives", s, &v);
                }
                13..=15 => {
                    let u = refs(r, &m.unknowns, &m.reals);
                    let k = refs(r, &m.knowns, &m.reals);
                    let seed: Vec<f64> = k.iter().map(|_| if r.chance(0.9) { 1.0 } else { r.real() }).collect();
                    let mut v = vec![f64::NAN; u.len()];
                    let s = tally.call(c, "fmi2GetDirectionalDerivative", || {
                        fmi2GetDirectionalDerivative(
                            c,
                            u.as_ptr(),
                            u.len(),
                            k.as_ptr(),
                            k.len(),
                            seed.as_ptr(),
                            v.as_mut_ptr(),
                        )
                    });
                    tally.finite("fmi2GetDirectionalDerivative", s, &v);
                }
                16 => {
                    let mut s: FmuStatePtr = std::ptr::null_mut();
                    if tally.call(c, "fmi2GetFMUstate", || fmi2GetFMUstate(c, &mut s)) == Status::Ok {
                        states.push(s);
                    }
                }
                17 => {
                    // A live, freed, foreign or made-up handle.
                    let st = match r.below(4) {
                        0 if !freed.is_empty() => r.pick(&freed),
                        1 => foreign,
                        2 => 0x1000 as FmuStatePtr,
                        _ if !states.is_empty() => r.pick(&states),
                        _ => std::ptr::null_mut(),
                    };
                    tally.call(c, "fmi2SetFMUstate", || fmi2SetFMUstate(c, st));
                }
                18 => {
                    let mut st = match r.below(3) {
                        0 if !freed.is_empty() => r.pick(&freed),
                        1 => foreign,
                        _ if !states.is_empty() => states.swap_remove(r.below(states.len())),
                        _ => std::ptr::null_mut(),
                    };
                    let orig = st;
                    if tally.call(c, "fmi2FreeFMUstate", || fmi2FreeFMUstate(c, &mut st)) == Status::Ok
                        && !orig.is_null()
                    {
                        freed.push(orig);
                    }
                }
                19 => {
                    if let Some(&st) = states.last() {
                        bytes = serialize(tally, c, st, r.chance(0.2));
                    }
                }
                20 => {
                    // Deserialize as written, corrupted, truncated, or noise.
                    if bytes.is_empty()
                        && let Some(&st) = states.last()
                    {
                        bytes = serialize(tally, c, st, false);
                    }
                    let mut b = bytes.clone();
                    match r.below(6) {
                        0 if !b.is_empty() => {
                            for _ in 0..1 + r.below(4) {
                                let i = r.below(b.len());
                                b[i] ^= 1 << r.below(8);
                            }
                        }
                        1 => b.truncate(r.below(b.len() + 1)),
                        2 => b = (0..r.below(200)).map(|_| r.next() as i8).collect(),
                        _ => {}
                    }
                    let mut st: FmuStatePtr = std::ptr::null_mut();
                    if tally
                        .call(c, "fmi2DeSerializeFMUstate", || fmi2DeSerializeFMUstate(c, b.as_ptr(), b.len(), &mut st))
                        == Status::Ok
                    {
                        states.push(st);
                    }
                }
                21 => {
                    tally.call(c, "fmi2Reset", || fmi2Reset(c));
                    time = 0.0;
                }
                22 => {
                    tally.call(c, "fmi2Terminate", || fmi2Terminate(c));
                }
                23 => {
                    let cats = [c"logEvents".as_ptr(), c"nonsense".as_ptr(), c"logAll".as_ptr()];
                    let n = r.below(4);
                    tally.call(c, "fmi2SetDebugLogging", || fmi2SetDebugLogging(c, 1, n, cats.as_ptr()));
                }
                24 => {
                    let mut st = Status::Ok;
                    let mut b = 0;
                    let kind = r.pick(&[DO_STEP_STATUS, TERMINATED, 9]);
                    tally.call(c, "fmi2GetStatus", || fmi2GetStatus(c, kind, &mut st));
                    tally.call(c, "fmi2GetBooleanStatus", || fmi2GetBooleanStatus(c, kind, &mut b));
                    tally.call(c, "fmi2CancelStep", || fmi2CancelStep(c));
                }
                25 => {
                    // NULL arrays with non-zero counts.
                    let n = 1 + r.below(3);
                    tally.call(c, "fmi2GetReal", || fmi2GetReal(c, std::ptr::null(), n, std::ptr::null_mut()));
                    tally.call(c, "fmi2SetReal", || {
                        fmi2SetReal(c, m.reals.as_ptr(), n.min(m.reals.len()), std::ptr::null())
                    });
                    tally.call(c, "fmi2GetDirectionalDerivative", || {
                        fmi2GetDirectionalDerivative(
                            c,
                            std::ptr::null(),
                            n,
                            std::ptr::null(),
                            n,
                            std::ptr::null(),
                            std::ptr::null_mut(),
                        )
                    });
                }
                26 => {
                    if let Some(vr) = m.max_steps {
                        let n = if r.chance(0.7) { r.pick(&[1, 50, MAX_STEPS]) } else { r.pick(&[0, -5, i32::MIN]) };
                        tally.call(c, "fmi2SetInteger", || fmi2SetInteger(c, &vr, 1, &n));
                        let mut got = 0;
                        tally.call(c, "fmi2GetInteger", || fmi2GetInteger(c, &vr, 1, &mut got));
                    }
                }
                27 => {
                    tally.call(c, "fmi2SetTime", || fmi2SetTime(c, r.real()));
                }
                30..=32 => {
                    // A small move (an integrator's stage), a large one, hostile values,
                    // or a wrong count.
                    let mut v = x.clone();
                    match r.below(10) {
                        0..=5 => v.iter_mut().for_each(|a| *a += 0.01 * r.real().clamp(-2.0, 2.0)),
                        6 => v.iter_mut().for_each(|a| *a += r.real() * 10.0),
                        7 => v.iter_mut().for_each(|a| *a = r.real()),
                        _ => {}
                    }
                    let n = if r.chance(0.9) { m.nx } else { r.pick(&[0, m.nx + 1, 1]) };
                    v.resize(n, 0.0);
                    let p = if r.chance(0.05) { std::ptr::null() } else { v.as_ptr() };
                    if tally.call(c, "fmi2SetContinuousStates", || fmi2SetContinuousStates(c, p, n)) == Status::Ok
                        && n == m.nx
                    {
                        x = v;
                    }
                }
                33..=34 => {
                    let n = if r.chance(0.9) { m.nx } else { m.nx + 1 };
                    let mut d = vec![f64::NAN; n];
                    let s = tally.call(c, "fmi2GetDerivatives", || fmi2GetDerivatives(c, d.as_mut_ptr(), n));
                    tally.finite("fmi2GetDerivatives", s, &d);
                    if s == Status::Ok && r.chance(0.8) {
                        // An Euler step with the derivatives.
                        let h = r.pick(&[1e-3, 1e-2, 0.1]);
                        time += h;
                        tally.call(c, "fmi2SetTime", || fmi2SetTime(c, time));
                        let v: Vec<f64> = x.iter().zip(&d).map(|(a, b)| a + h * b).collect();
                        if tally.call(c, "fmi2SetContinuousStates", || fmi2SetContinuousStates(c, v.as_ptr(), m.nx))
                            == Status::Ok
                        {
                            x = v;
                        }
                        let (mut enter, mut stop) = (0, 0);
                        tally.call(c, "fmi2CompletedIntegratorStep", || {
                            fmi2CompletedIntegratorStep(c, 1, &mut enter, &mut stop)
                        });
                    }
                }
                35 => {
                    // Time forward, back (a rejected step), or hostile.
                    let t = match r.below(4) {
                        0 => time - 0.05,
                        1 => r.real(),
                        _ => time + 0.01,
                    };
                    if tally.call(c, "fmi2SetTime", || fmi2SetTime(c, t)) == Status::Ok {
                        time = t;
                    }
                }
                36 => {
                    let mut v = vec![f64::NAN; m.nx];
                    let s =
                        tally.call(c, "fmi2GetContinuousStates", || fmi2GetContinuousStates(c, v.as_mut_ptr(), m.nx));
                    tally.finite("fmi2GetContinuousStates", s, &v);
                    let s = tally.call(c, "fmi2GetNominalsOfContinuousStates", || {
                        fmi2GetNominalsOfContinuousStates(c, v.as_mut_ptr(), m.nx)
                    });
                    tally.finite("fmi2GetNominalsOfContinuousStates", s, &v);
                    let ni = r.pick(&[0, 1]);
                    tally.call(c, "fmi2GetEventIndicators", || fmi2GetEventIndicators(c, v.as_mut_ptr(), ni));
                }
                37 => {
                    let mut info = EventInfo::default();
                    match r.below(3) {
                        0 => tally.call(c, "fmi2EnterEventMode", || fmi2EnterEventMode(c)),
                        1 => tally.call(c, "fmi2NewDiscreteStates", || fmi2NewDiscreteStates(c, &mut info)),
                        _ => tally.call(c, "fmi2EnterContinuousTimeMode", || fmi2EnterContinuousTimeMode(c)),
                    };
                }
                28 if r.chance(0.3) => {
                    // Free mid-sequence: every later call must be refused, not crash.
                    host::free(c);
                    alive = false;
                }
                _ => {
                    let vrs = refs(r, &m.outputs, &m.reals);
                    let mut v = vec![f64::NAN; vrs.len()];
                    let s = tally.call(c, "fmi2GetReal", || fmi2GetReal(c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()));
                    tally.finite("fmi2GetReal", s, &v);
                }
            }
        }
        if !alive {
            // SAFETY: the freed component is refused by every export.
            let s = unsafe { fmi2Terminate(c) };
            if s != Status::Error {
                tally.failures.push(format!("{}: a freed instance answered {s:?}", m.name));
            }
            break;
        }
    }
    // SAFETY: live instances (or already freed: refused); `foreign` belongs to `d`.
    unsafe {
        if alive {
            host::free(c);
        }
        if !d.is_null() {
            fmi2FreeFMUstate(d, &mut foreign);
            fmi2FreeInstance(d);
        }
    }
}

#[test]
fn random_fmi_call_sequences_never_crash_hang_panic_or_return_nan_with_ok() {
    let count: usize = std::env::var("MBFMU_FMI_SEQUENCES").ok().and_then(|v| v.parse().ok()).unwrap_or(300);
    let seed: u64 = std::env::var("MBFMU_FMI_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(12);
    let ms = models();
    let mut tally = Tally::default();
    let t0 = Instant::now();
    for k in 0..count {
        let mut r = Rng(seed.wrapping_mul(1_000_003).wrapping_add(k as u64));
        let (a, b) = (r.below(ms.len()), r.below(ms.len()));
        let before = tally.failures.len();
        sequence(&mut r, &ms[a], &ms[b], &mut tally);
        for f in &mut tally.failures[before..] {
            *f = format!("sequence {k} (seed {seed}, model {}): {f}", ms[a].name);
        }
    }
    println!(
        "{count} sequences, {} calls in {:.1} s; statuses {:?}; {} calls made integrator steps, {} of them up to \
         the limit; the most attempts in one call {} ({}, limit {})\nfmi2OK by function: {:?}",
        tally.calls,
        t0.elapsed().as_secs_f64(),
        tally.by_status,
        tally.stepping_calls,
        tally.at_limit,
        tally.busiest.0,
        tally.busiest.1,
        tally.busiest.2,
        tally.ok_by_function
    );
    assert!(tally.failures.is_empty(), "{} failures:\n{}", tally.failures.len(), tally.failures.join("\n"));
    // The sequences reach the interesting states: steps, derivatives and states succeed.
    for f in ["fmi2DoStep", "fmi2GetDirectionalDerivative", "fmi2SetFMUstate", "fmi2DeSerializeFMUstate"] {
        assert!(tally.ok_by_function.get(f).copied().unwrap_or(0) >= count / 20, "{f}: {:?}", tally.ok_by_function);
    }
    // Model Exchange too: states set, derivatives read, integrator steps completed.
    for f in ["fmi2SetContinuousStates", "fmi2GetDerivatives", "fmi2CompletedIntegratorStep"] {
        assert!(tally.ok_by_function.get(f).copied().unwrap_or(0) >= count / 20, "{f}: {:?}", tally.ok_by_function);
    }
    assert!(tally.by_status.get("Error").copied().unwrap_or(0) > count / 10, "{:?}", tally.by_status);
    // The count sees the integrator: calls step, and some run into their limit (so the
    // bound above is met by calls it constrains, not only by idle ones).
    assert!(
        tally.stepping_calls >= count / 20 && tally.at_limit >= 1,
        "{} stepping, {} at the limit",
        tally.stepping_calls,
        tally.at_limit
    );
}
