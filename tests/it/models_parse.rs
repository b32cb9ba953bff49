//! The model reader on valid models: every supported element and orientation form, with
//! the values it must produce.

use mbfmu::model::expr::Expr;
use mbfmu::model::{JointType, Model, MotionDof, Orientation, SpringType, load_str, rotation, try_rotation};

/// Every supported element once (expressions limited to arithmetic of parameters, time
/// and inputs so the test does not depend on the kinematic functions).
const FULL: &str = r#"<?xml version="1.0"?>
<multibody name="full" version="1">
  <!-- parameters in reverse dependency order -->
  <parameter name="c" value="b + 1" unit="m" description="last"/>
  <parameter name="b" value="2*a"/>
  <parameter name="a" value="1.5"/>
  <gravity value="0, 0, -9.81"/>
  <input name="u" start="a" unit="N"/>
  <ground>
    <marker name="O" position="0 0 0"/>
    <marker name="Z" position="0 0 0" z_axis="1 0 0"/>
  </ground>
  <body name="arm" mass="2*a" inertia="1 2 3" position="c, 0, 0"
        euler313="pi/2 0 0" velocity="0 1 0" angular_velocity="0 0 a">
    <marker name="tip" position="1 0 0" z_axis="0 0 2" x_axis="1 1 0"/>
    <marker name="side" position="0 1 0" euler313="0 pi/2 0"/>
  </body>
  <body name="slider" mass="1" inertia="1 1 1 0.1 0 0" position="0 0 1" z_axis="0 1 0">
    <marker name="m" position="0 0 0"/>
  </body>
  <joint name="hinge" type="revolute" i="arm.side" j="ground.O" ic_angle="0.1"/>
  <joint name="slide" type="cylindrical" i="slider" j="ground.Z" ic_speed="b"/>
  <motion name="drive" joint="slide" dof="translation" function="a*time"/>
  <constraint name="c1" function="time - 1"/>
  <spring_damper name="k1" type="translational" i="arm.tip" j="ground.O" stiffness="100" length="c"/>
  <spring_damper name="k2" type="rotational" i="slider.m" j="arm" stiffness="5" damping="0.5" angle="a" preload="1"/>
  <sforce name="f1" type="translational" i="arm.tip" j="slider.m" function="u*2"/>
  <gforce name="g1" i="arm.tip" frame="arm.cm" force="u 0 -1" torque="0, 0, time"/>
  <gforce name="g2" i="slider" j="arm.tip"/>
  <output name="y" function="u + a" unit="N"/>
  <linearization>
    <state name="s1" function="time"/>
    <velocity name="v1" function="2"/>
  </linearization>
  <experiment start="0" stop="10*a" step="0.01" tolerance="1e-8"/>
  <analysis static="true"/>
</multibody>
"#;

fn full() -> Model {
    match load_str(FULL, "full.xml") {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

fn close(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> bool {
    (0..3).all(|r| (0..3).all(|c| (a[r][c] - b[r][c]).abs() < 1e-12))
}

#[test]
fn parameters_are_evaluated_in_dependency_order() {
    let m = full();
    assert_eq!(m.param_values(), vec![4.0, 3.0, 1.5]);
    assert_eq!(m.parameters[0].unit.as_deref(), Some("m"));
    assert_eq!(m.parameters[0].description.as_deref(), Some("last"));
    assert_eq!(m.bodies[0].mass.value, 3.0);
    assert_eq!(m.inputs[0].start.value, 1.5);
    assert_eq!(m.experiment.stop, Some(15.0));
    assert_eq!(m.experiment.tolerance, Some(1e-8));
    assert!(m.static_analysis);
}

#[test]
fn vectors_split_on_commas_or_white_space() {
    let m = full();
    assert_eq!(m.gravity, [0.0, 0.0, -9.81]);
    assert_eq!(m.bodies[0].position.v3(), [4.0, 0.0, 0.0]);
    assert_eq!(m.bodies[0].angular_velocity.as_ref().map(|v| v.v3()), Some([0.0, 0.0, 1.5]));
    assert_eq!(m.bodies[1].inertia.values(), vec![1.0, 1.0, 1.0, 0.1, 0.0, 0.0]);
    assert_eq!(m.gforces[0].torque[2], Expr::Time);
}

#[test]
fn each_body_has_a_cm_marker_before_its_own_markers() {
    let m = full();
    let names: Vec<&str> = m.markers.iter().map(|k| k.name.as_str()).collect();
    assert_eq!(names, ["ground.O", "ground.Z", "arm.cm", "arm.tip", "arm.side", "slider.cm", "slider.m"]);
    assert_eq!(m.markers[2].body, Some(0));
    assert_eq!(m.markers[2].orientation, Orientation::Identity);
    assert_eq!(m.markers[0].body, None);
    assert_eq!(m.marker_index("arm"), Some(2));
    assert_eq!(m.marker_index("slider.m"), Some(6));
    assert_eq!(m.marker_index("nope"), None);
    // A bare body name in a reference means its cm marker.
    assert_eq!(m.joints[1].i, 5);
    assert_eq!(m.spring_dampers[1].j, 2);
}

#[test]
fn orientations_give_the_documented_rotations() {
    let m = full();
    // euler313 = (pi/2, 0, 0): Rz(pi/2).
    let rz = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    assert!(close(rotation(&m.bodies[0].orientation), rz));
    // euler313 = (0, pi/2, 0): Rx(pi/2).
    let rx = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]];
    assert!(close(rotation(&m.markers[4].orientation), rx));
    // z = (0,0,2) normalized, x = (1,1,0) normalized: columns x, y = z × x, z.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let r = [[s, -s, 0.0], [s, s, 0.0], [0.0, 0.0, 1.0]];
    assert!(close(rotation(&m.markers[3].orientation), r));
    // z = (0,1,0) alone: x = owner x (already orthogonal), y = z × x = (0,0,-1).
    let r = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];
    assert!(close(rotation(&m.bodies[1].orientation), r));
    // z = (1,0,0): |x_owner·z| > 0.9, so x comes from the owner's y axis.
    let r = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(close(rotation(&m.markers[1].orientation), r));
    let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert!(close(rotation(&Orientation::Identity), id));
    assert!(try_rotation(&m.markers[0].orientation).is_ok());
}

#[test]
fn elements_are_read_with_their_defaults() {
    let m = full();
    assert_eq!(m.name, "full");
    assert_eq!(m.file, "full.xml");
    assert_eq!(m.joints[0].kind, JointType::Revolute);
    assert_eq!(m.joints[0].ic_angle.as_ref().map(|n| n.value), Some(0.1));
    assert_eq!(m.joints[1].ic_speed.as_ref().map(|n| n.value), Some(3.0));
    assert_eq!(m.motions[0].joint, 1);
    assert_eq!(m.motions[0].dof, MotionDof::Translation);
    assert_eq!(m.constraints.len(), 1);
    let (k1, k2) = (&m.spring_dampers[0], &m.spring_dampers[1]);
    assert_eq!(k1.kind, SpringType::Translational);
    assert_eq!((k1.length.value, k1.damping.value, k1.preload.value), (4.0, 0.0, 0.0));
    assert_eq!(k2.kind, SpringType::Rotational);
    assert_eq!((k2.length.value, k2.damping.value, k2.preload.value), (1.5, 0.5, 1.0));
    assert_eq!(m.sforces[0].kind, SpringType::Translational);
    assert_eq!(m.gforces[0].frame, Some(2));
    assert_eq!(m.gforces[0].j, None);
    assert_eq!(m.gforces[1].j, Some(3));
    assert_eq!(m.gforces[1].force, [Expr::Num(0.0), Expr::Num(0.0), Expr::Num(0.0)]);
    assert_eq!(m.outputs[0].unit.as_deref(), Some("N"));
    assert_eq!(m.lin_states[0].name, "s1");
    assert_eq!(m.lin_velocities[0].name, "v1");
}

#[test]
fn with_params_re_evaluates_every_attribute() {
    let m = full();
    let m2 = match m.with_params(&[10.0, 4.0, 2.0]) {
        Ok(m2) => m2,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(m2.param_values(), vec![10.0, 4.0, 2.0]);
    assert_eq!(m2.bodies[0].mass.value, 4.0);
    assert_eq!(m2.bodies[0].position.v3(), [10.0, 0.0, 0.0]);
    assert_eq!(m2.spring_dampers[0].length.value, 10.0);
    assert_eq!(m2.spring_dampers[1].length.value, 2.0);
    assert_eq!(m2.joints[1].ic_speed.as_ref().map(|n| n.value), Some(4.0));
    assert_eq!(m2.inputs[0].start.value, 2.0);
    // The original is unchanged; invalid values are refused.
    assert_eq!(m.bodies[0].mass.value, 3.0);
    assert!(m.with_params(&[1.0]).is_err());
    let e = m.with_params(&[1.0, 1.0, -1.0]).err();
    assert_eq!(e.as_deref(), Some("body 'arm': mass must be positive (got -2)"));
}

#[test]
fn summary_counts_coordinates_and_constraints() {
    let s = full().summary();
    // 2 bodies; revolute 5 + cylindrical 4 + 1 motion + 1 constraint.
    assert_eq!((s.bodies, s.coordinates, s.constraints, s.dof), (2, 12, 11, 1));
    assert_eq!(s.to_string(), "2 bodies, 12 coordinates, 11 constraint equations, 1 degrees of freedom");
}

#[test]
fn minimal_model_has_defaults() {
    let m = load_str(r#"<multibody name="m" version="1"/>"#, "m.xml");
    let m = m.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.gravity, [0.0; 3]);
    assert!(m.bodies.is_empty() && !m.static_analysis);
    assert_eq!(m.experiment.stop, None);
}

#[test]

fn kinematic_functions_are_accepted_where_allowed() {
    let text = r#"<multibody name="k" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="1" inertia="1 1 1" position="1 0 0"/>
  <joint name="j" type="spherical" i="b" j="ground.O"/>
  <constraint name="c" function="dx(b, ground.O) - 1"/>
  <sforce name="s" type="translational" i="b" j="ground.O" function="-10*vr(b, ground.O)"/>
  <output name="y" function="accx(b) + fx(j)"/>
  <linearization>
    <state name="alpha" function="az(b.cm, ground.O)"/>
    <velocity name="v" function="vx(b)"/>
  </linearization>
</multibody>"#;
    let m = load_str(text, "k.xml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.outputs.len(), 1);
}

#[test]
fn load_file_labels_messages_with_the_path() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/21_zero_mass.xml");
    let e = mbfmu::model::load_file(&path).err().map(|e| e.to_string()).unwrap_or_default();
    assert_eq!(e, format!("{}:2:18: body 'b': mass must be positive (got 0)", path.display()));
    let missing = std::path::Path::new("/nonexistent/model.xml");
    let e = mbfmu::model::load_file(missing).err().map(|e| e.msg).unwrap_or_default();
    assert!(e.starts_with("cannot read"), "{e}");
}

#[test]
fn no_input_makes_the_reader_panic() {
    // Truncations of a valid model: every prefix must give Ok or Err, never a panic.
    for cut in (0..FULL.len()).filter(|&i| FULL.is_char_boundary(i)) {
        let _ = load_str(&FULL[..cut], "cut.xml");
    }
    // Each single character deleted, or replaced by a troublesome one.
    for (i, c) in FULL.char_indices() {
        let rest = &FULL[i + c.len_utf8()..];
        for rep in ["", "\"", "<", ",", "0", "é"] {
            let _ = load_str(&format!("{}{rep}{rest}", &FULL[..i]), "mut.xml");
        }
    }
    let deep = "<multibody name=\"m\" version=\"1\">".to_string() + &"<ground>".repeat(100_000);
    assert!(load_str(&deep, "deep.xml").is_err());
}

/// A model whose every kind of numeric attribute uses parameter `p`; its value is the
/// placeholder P.
const EVERY_ATTRIBUTE: &str = r#"<multibody name="every" version="1">
  <parameter name="p" value="P" unit="m"/>
  <gravity value="0, 0, -9*p"/>
  <input name="u" start="p"/>
  <ground><marker name="O" position="p 0 0" euler313="p 0 0"/></ground>
  <body name="a" mass="2*p" inertia="p, 2*p, 3*p" position="0 0 p" euler313="0 p 0"
        velocity="p 0 0" angular_velocity="0 0 p">
    <marker name="m" position="0 p 0" z_axis="p 0 1" x_axis="0 1 0"/>
    <marker name="w" position="0 0 -p"/>
  </body>
  <body name="b" mass="1" inertia="1 1 1" position="1 0 0">
    <marker name="m" position="0 0 0"/>
  </body>
  <joint name="j" type="cylindrical" i="a.m" j="ground.O" ic_angle="p/10" ic_angular_speed="p"
         ic_displacement="p/5" ic_speed="2*p"/>
  <spring_damper name="k" type="translational" i="a.m" j="b.m" stiffness="10*p" damping="p"
                 length="p" preload="3*p"/>
  <bushing name="bu" i="b.m" j="ground.O" stiffness="p, 2*p, 3*p, 4*p, 5*p, 6*p"
           damping="p, p, p, 2*p, 2*p, 2*p"/>
  <rolling_wheel name="rw" marker="a.w" radius="p/2"/>
  <differential name="x" start="4*p" function="-x"/>
</multibody>"#;

#[test]
fn with_params_equals_loading_the_model_with_those_values() {
    // The independent reference for re-evaluation: the same text loaded with the new value
    // written in. Every attribute must agree exactly (both evaluate the same expressions
    // with the same numbers); only the parameter's own expression differs.
    let load = |p: f64| load_str(&EVERY_ATTRIBUTE.replace("\"P\"", &format!("\"{p:?}\"")), "every.xml").unwrap();
    let (m, direct) = (load(1.25), load(1.75));
    let mut changed = m.with_params(&[1.75]).unwrap_or_else(|e| panic!("{e}"));
    assert_ne!(m, direct);
    changed.parameters = direct.parameters.clone();
    assert_eq!(changed, direct);
}

#[test]
fn with_params_refuses_a_wheel_radius_that_becomes_non_positive() {
    let m = load_str(&EVERY_ATTRIBUTE.replace("\"P\"", "\"1\""), "every.xml").unwrap();
    let e = m.with_params(&[-1.0]).err();
    // The body mass 2p is checked first.
    assert_eq!(e.as_deref(), Some("body 'a': mass must be positive (got -2)"));
    let text = EVERY_ATTRIBUTE.replace("\"P\"", "\"1\"").replace("mass=\"2*p\"", "mass=\"2\"");
    let text = text.replace("inertia=\"p, 2*p, 3*p\"", "inertia=\"1 2 3\"");
    let m = load_str(&text, "every.xml").unwrap();
    let e = m.with_params(&[-1.0]).err();
    assert_eq!(e.as_deref(), Some("rolling_wheel 'rw': radius must be positive (got -0.5)"));
}
