//! Engine state for the FMU: snapshots reproduce a run bit for bit, serialization round
//! trips, and inputs (held or linearly interpolated) drive the motion as analytic
//! solutions say.

use crate::common::model;
use mbfmu::dae::{SimOptions, SimState, Simulator};

#[test]
fn restoring_a_snapshot_reproduces_the_run_bit_for_bit() {
    let m = model("double_pendulum.xml");
    let opts = SimOptions { tol: 1e-8, max_step: None, ..Default::default() };
    let mut a = Simulator::new(&m, opts, 0.0).unwrap();
    a.advance(1.0).unwrap();
    let snap = a.snapshot();
    a.advance(2.0).unwrap();
    let first = a.outputs().unwrap();
    a.restore(&snap).unwrap();
    assert_eq!(a.time(), 1.0);
    a.advance(2.0).unwrap();
    assert_eq!(a.outputs().unwrap(), first, "same instance, restored");
    // Through bytes into a fresh instance of the same model.
    let bytes = snap.to_bytes();
    let back = SimState::from_bytes(&bytes).unwrap();
    assert_eq!(back, snap);
    let mut b = Simulator::new(&m, opts, 0.0).unwrap();
    b.restore(&back).unwrap();
    b.advance(2.0).unwrap();
    assert_eq!(b.outputs().unwrap(), first, "fresh instance, deserialized");
    // Garbage and truncated bytes are refused, not trusted.
    assert!(SimState::from_bytes(b"nonsense").is_err());
    assert!(SimState::from_bytes(&bytes[..bytes.len() - 3]).is_err());
    // A state of another model is refused.
    let mut other = Simulator::new(&model("pendulum.xml"), opts, 0.0).unwrap();
    assert!(other.restore(&snap).is_err());
}

/// At 1 ms communication steps the integrator keeps its Jacobian and factorization from
/// one step to the next; a snapshot taken between two such steps, restored in the same
/// instance or deserialized into a fresh one, continues bit for bit, and the reuse is
/// real: far fewer Jacobians than communication steps.
#[test]
fn jacobian_reuse_across_communication_steps_survives_snapshots_bit_for_bit() {
    let m = model("double_pendulum.xml");
    let opts = SimOptions { tol: 1e-4, ..Default::default() };
    let run = |sim: &mut Simulator, from: usize, to: usize| -> Vec<f64> {
        for k in from + 1..=to {
            sim.advance(k as f64 * 1e-3).unwrap();
        }
        sim.outputs().unwrap()
    };
    let mut a = Simulator::new(&m, opts, 0.0).unwrap();
    run(&mut a, 0, 150);
    let snap = a.snapshot();
    let first = run(&mut a, 150, 300);
    let stats = a.stats();
    // Measured (2026-12-04): 10 Jacobians and 12 factorizations in the 300 steps; a
    // restart at every communication step would make 300 of each.
    assert!(stats.jacobians * 10 <= 300, "{stats:?}");
    assert!(stats.factorizations * 10 <= 300, "{stats:?}");
    a.restore(&snap).unwrap();
    assert_eq!(run(&mut a, 150, 300), first, "same instance, restored");
    let mut b = Simulator::new(&m, opts, 0.0).unwrap();
    b.restore(&SimState::from_bytes(&snap.to_bytes()).unwrap()).unwrap();
    assert_eq!(run(&mut b, 150, 300), first, "fresh instance, deserialized");
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
fn held_and_interpolated_inputs_drive_a_rotor_exactly() {
    // J ω' = T(t). Held T = 2 over [0, 1]: ω(1) = 2/J. Then T(t) = 2 + 3 (t − 1) over
    // [1, 2] (fmi2SetRealInputDerivatives): ω(2) = ω(1) + (2 + 3/2)/J. Polynomial motion:
    // the order-5 integrator is exact up to round-off.
    let m = mbfmu::model::parse::load_str(ROTOR, "rotor.xml").unwrap();
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-8, max_step: None, ..Default::default() }, 0.0).unwrap();
    let j = 0.5;
    s.set_input(0, 2.0);
    s.advance(1.0).unwrap();
    assert!((s.outputs().unwrap()[0] - 2.0 / j).abs() < 1e-12);
    s.set_input_derivative(0, 3.0);
    s.advance(2.0).unwrap();
    assert!((s.outputs().unwrap()[0] - (2.0 / j + 3.5 / j)).abs() < 1e-12);
    assert!((s.inputs()[0] - 5.0).abs() < 1e-15);
}

#[test]
fn output_derivatives_match_differences_of_the_outputs() {
    // d/dt of each output at t = 1 against central differences of accurate runs (tol
    // 1e-12) around t = 1 (see the helper). Outputs of
    // positions/velocities are exact (dual numbers along the motion): 1e-6. Outputs of
    // accelerations use the collocation polynomial's jerk (accurate to O(h³) of the step):
    // 1e-3 relative.
    let xml = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/double_pendulum.xml"))
        .unwrap()
        .replace("</multibody>", r#"<output name="tip_acc" function="accx(rod2.tip)"/><output name="tip_vz" function="vz(rod2.tip)"/></multibody>"#);
    let m = mbfmu::model::parse::load_str(&xml, "dp.xml").unwrap();
    output_derivatives_match_differences(&m, &["tip_acc"]);
}

/// d/dt of each output of `m` at t = 1 against fourth-order central differences of the
/// outputs at 1 ± δ, 1 ± 2δ, δ = 1e-4: truncation δ⁴·|y⁽⁵⁾|/30, small even for a flexible
/// body's vibration at ω ~ 300 rad/s (second-order differences would err by δ²ω³|y|/6 ≈
/// 5e-6 there). Tolerances as above: 1e-6 relative to max(1, |y'|), 1e-3 for the outputs
/// named in `acceleration_outputs`.
pub fn output_derivatives_match_differences(m: &mbfmu::model::Model, acceleration_outputs: &[&str]) {
    let opts = SimOptions { tol: 1e-12, max_step: None, ..Default::default() };
    let at = |t: f64| {
        let mut s = Simulator::new(m, opts, 0.0).unwrap();
        s.advance(t).unwrap();
        s
    };
    let d = 1e-4;
    let y = |t: f64| at(t).outputs().unwrap();
    let (y1, ym1, y2, ym2) = (y(1.0 + d), y(1.0 - d), y(1.0 + 2.0 * d), y(1.0 - 2.0 * d));
    let mut s = at(1.0);
    let dy = s.output_derivatives().unwrap();
    let names = s.output_names();
    for (k, name) in names.iter().enumerate() {
        let fd = (8.0 * (y1[k] - ym1[k]) - (y2[k] - ym2[k])) / (12.0 * d);
        let rel = if acceleration_outputs.contains(&name.as_str()) { 1e-3 } else { 1e-6 };
        assert!((dy[k] - fd).abs() < rel * fd.abs().max(1.0), "{name}: {} vs {fd}", dy[k]);
    }
}
