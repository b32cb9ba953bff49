//! Engine state for the FMU: snapshots reproduce a run bit for bit, serialization round
//! trips, and inputs (held or linearly interpolated) drive the motion as analytic
//! solutions say.

use mbfmu::dae::{SimOptions, SimState, Simulator};
use mbfmu::model::parse::load_file;

fn model(name: &str) -> mbfmu::model::Model {
    load_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models").join(name)).unwrap()
}

#[test]
fn restoring_a_snapshot_reproduces_the_run_bit_for_bit() {
    let m = model("double_pendulum.xml");
    let opts = SimOptions { tol: 1e-8, max_step: None };
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
    let mut s = Simulator::new(&m, SimOptions { tol: 1e-8, max_step: None }, 0.0).unwrap();
    let j = 0.5;
    s.set_input(0, 2.0);
    s.advance(1.0).unwrap();
    assert!((s.outputs().unwrap()[0] - 2.0 / j).abs() < 1e-12);
    s.set_input_derivative(0, 3.0);
    s.advance(2.0).unwrap();
    assert!((s.outputs().unwrap()[0] - (2.0 / j + 3.5 / j)).abs() < 1e-12);
    assert!((s.inputs()[0] - 5.0).abs() < 1e-15);
}
