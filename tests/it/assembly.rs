//! Initialization: assembly keeps exact joint ICs, velocities are made consistent, and a
//! model that cannot be assembled is reported at the constraint to blame, as bad input.

use mbfmu::dae::{EngineError, SimOptions, Simulator};
use mbfmu::model::parse::load_str;

const PENDULUM_WITH_ICS: &str = r#"<multibody name="p" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0" x_axis="0 0 -1"/></ground>
  <body name="bob" mass="1" inertia="0.01 0.01 0.01" position="0.29552 0 -0.95534" z_axis="0 1 0" x_axis="0 0 -1">
    <marker name="P" position="0 0 0" euler313="0 0 0"/>
  </body>
  <body name="slider" mass="1" inertia="0.1 0.1 0.1" position="0 0 0.7">
    <marker name="S" position="0 0 0" z_axis="0 1 0" x_axis="0 0 -1"/>
  </body>
  <joint name="pin" type="revolute" i="bob.P" j="ground.O" ic_angle="0.5" ic_angular_speed="-2"/>
  <joint name="rail" type="translational" i="slider.S" j="ground.O" ic_displacement="0.25" ic_speed="1.5"/>
</multibody>"#;

#[test]
fn joint_initial_conditions_are_exact_after_assembly() {
    // The bob is drawn off its pivot and at angle 0 about the joint axis; assembly moves it
    // onto the pivot and turns it to exactly ic_angle. The assembled angle, angular speed,
    // displacement and speed equal the ICs to round-off (1e-12).
    let m = load_str(PENDULUM_WITH_ICS, "p.xml").unwrap_or_else(|e| panic!("{e}"));
    let s = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let bob = s.body_state(0);
    // Angle of the bob's x axis about ground y from the ground marker's x axis (= −z).
    let x = [bob.rotation[0][0], bob.rotation[1][0], bob.rotation[2][0]];
    let angle = (-x[0]).atan2(-x[2]); // rotation about +y by a takes (0,0,−1) to (−sin a, 0, −cos a)
    assert!((angle - 0.5).abs() < 1e-12, "angle {angle}");
    assert!((bob.angular_velocity[1] + 2.0).abs() < 1e-12, "{:?}", bob.angular_velocity);
    let sl = s.body_state(1);
    // Translational joint along the ground marker's z (= ground y).
    assert!((sl.position[1] - 0.25).abs() < 1e-12, "{:?}", sl.position);
    assert!((sl.velocity[1] - 1.5).abs() < 1e-12, "{:?}", sl.velocity);
    assert!(s.constraint_residual() < 1e-12);
}

const UNREACHABLE: &str = r#"<multibody name="u" version="1">
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="arm" mass="1" inertia="0.1 0.1 0.1" position="0.5 0 0">
    <marker name="P" position="-0.5 0 0" z_axis="0 1 0"/>
    <marker name="tip" position="0.5 0 0"/>
  </body>
  <joint name="pin" type="revolute" i="arm.P" j="ground.O"/>
  <constraint name="reach" function="dm(arm.tip, ground.O) - 3"/>
</multibody>"#;

#[test]
fn unassemblable_model_names_the_worst_constraint_with_its_position() {
    let m = load_str(UNREACHABLE, "u.xml").unwrap_or_else(|e| panic!("{e}"));
    let err = Simulator::new(&m, SimOptions::default(), 0.0).err().expect("cannot be assembled");
    let msg = err.to_string();
    assert!(matches!(err, EngineError::Model(_)), "{msg}");
    assert!(msg.starts_with("u.xml:8:3: constraint 'reach': cannot be assembled"), "{msg}");
}

#[test]
fn cli_reports_an_unassemblable_model_as_bad_input() {
    let dir = std::env::temp_dir().join(format!("mbfmu-assembly-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("u.xml");
    std::fs::write(&path, UNREACHABLE).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mbfmu"))
        .args(["simulate", path.to_str().unwrap(), "--end", "0.1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(":8:3: constraint 'reach': cannot be assembled"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
