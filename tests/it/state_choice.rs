//! Readable automatic states: without `<linearization>`, state selection (seed Eq. 33)
//! takes the joints' free coordinates before body coordinates. Only the candidate set and
//! the names change, so at an equilibrium the eigenvalues are those of the body-coordinate
//! choice (a change of state coordinates is a similarity transform of A there).

use crate::common::model_files;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::eigen_table;
use mbfmu::linearize::{Candidates, linearize, select_states, select_states_among};
use mbfmu::model::Model;
use mbfmu::model::parse::load_str;

/// Every example model, as written and (if it has one) without its `<linearization>`.
fn example_variants() -> Vec<(String, Model)> {
    let mut out = Vec::new();
    for path in model_files() {
        let file = path.file_name().unwrap().to_string_lossy().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        // Loaded under their own path: a flexible body's modal data file is found beside it.
        let label = path.display().to_string();
        out.push((file.clone(), load_str(&text, &label).unwrap_or_else(|e| panic!("{e}"))));
        if let (Some(a), Some(b)) = (text.find("<linearization>"), text.find("</linearization>")) {
            let bare = format!("{}{}", &text[..a], &text[b + "</linearization>".len()..]);
            out.push((
                format!("{file} (no <linearization>)"),
                load_str(&bare, &label).unwrap_or_else(|e| panic!("{e}")),
            ));
        }
    }
    out
}

fn names_without_linearization(file: &str) -> Vec<String> {
    let (_, model) = example_variants().into_iter().find(|(n, _)| n == file).unwrap();
    let t0 = model.experiment.start.unwrap_or(0.0);
    let sim = Simulator::new(&model, SimOptions::default(), t0).unwrap();
    let sel = select_states(sim.system(), sim.q(), t0, &sim.inputs()).unwrap();
    sel.states.iter().map(|s| s.name.clone()).collect()
}

#[test]
fn automatic_states_are_joint_coordinates_named_after_the_joint() {
    let expect: &[(&str, &[&str])] = &[
        ("pendulum.xml", &["hinge.angle"]),
        ("spring_mass_damper.xml", &["guide.displacement"]),
        ("cart_pendulum_pid.xml (no <linearization>)", &["rail.displacement", "hinge.angle"]),
        ("double_pendulum.xml (no <linearization>)", &["hinge1.angle", "hinge2.angle"]),
        // The rotor is driven by a motion: only the flap hinge is free.
        ("blade_alpha.xml (no <linearization>)", &["flap.angle"]),
        ("chaplygin_sleigh.xml (no <linearization>)", &["plane.dx", "plane.dy", "plane.angle"]),
        // A closed loop: one of the two ground pivots, not the spherical pin.
        ("fourbar.xml", &["crank_pivot.angle"]),
        ("spinning_top.xml", &["pivot.yaw", "pivot.pitch", "pivot.roll"]),
        // No joints: body coordinates.
        ("torque_free_body.xml", &["box.x", "box.y", "box.z", "box.psi", "box.theta", "box.phi"]),
    ];
    for (file, want) in expect {
        assert_eq!(names_without_linearization(file), *want, "{file}");
    }
}

#[test]
fn a_joint_angle_state_reads_the_angle_the_model_file_gives() {
    // pendulum.xml starts at th0 = 170° from the downward vertical, measured as
    // az(bob.P, ground.O) (its comment); the state hinge.angle must read exactly that.
    let (_, model) = example_variants().into_iter().find(|(n, _)| n == "pendulum.xml").unwrap();
    let mut sim = Simulator::new(&model, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize(&mut sim, &sel, 1).unwrap();
    assert_eq!(lin.states, ["hinge.angle", "der(hinge.angle)"]);
    // Assembly leaves an exactly consistent start untouched: round-off only.
    assert!((lin.x[0] - 170f64.to_radians()).abs() < 1e-12, "{}", lin.x[0]);
    assert!(lin.x[1].abs() < 1e-12);
}

/// State names and the eigenvalues (re, im) of A.
type Spectrum = (Vec<String>, Vec<(f64, f64)>);

/// Eigenvalues of A with the given candidates, at static equilibrium.
fn eigenvalues(model: &Model, which: Candidates) -> Option<Spectrum> {
    let t0 = model.experiment.start.unwrap_or(0.0);
    let mut m = model.clone();
    m.static_analysis = true;
    // At rest: no initial velocities (the spinning top, the four-bar's crank speed).
    for b in &mut m.bodies {
        (b.velocity, b.angular_velocity) = (None, None);
    }
    for j in &mut m.joints {
        (j.ic_speed, j.ic_angular_speed) = (None, None);
    }
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, t0).ok()?;
    let (udot, _) = sim.accelerations().ok()?;
    // An equilibrium: at rest and not accelerating (a driven model is neither).
    let moving = sim.u().iter().chain(&udot).fold(0.0f64, |a, v| a.max(v.abs()));
    if moving > 1e-8 {
        return None;
    }
    let sel = select_states_among(sim.system(), sim.q(), t0, &sim.inputs(), which).unwrap();
    let lin = linearize(&mut sim, &sel, 1).unwrap();
    let mut ev: Vec<(f64, f64)> = eigen_table(&lin.a)
        .unwrap()
        .iter()
        .flat_map(|r| if r.im == 0.0 { vec![(r.re, 0.0)] } else { vec![(r.re, r.im), (r.re, -r.im)] })
        .collect();
    ev.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    Some((lin.states, ev))
}

#[test]
fn eigenvalues_at_equilibrium_do_not_depend_on_the_state_candidates() {
    let mut compared = Vec::new();
    for (name, model) in example_variants() {
        let (Some((joints, a)), Some((bodies, b))) =
            (eigenvalues(&model, Candidates::Joints), eigenvalues(&model, Candidates::BodiesOnly))
        else {
            continue;
        };
        assert_eq!(a.len(), b.len(), "{name}");
        let scale = a.iter().map(|z| z.0.hypot(z.1)).fold(1.0, f64::max);
        // Each eigenvalue of one set has a partner in the other. Tolerance: the two A are
        // exact to ~1e-13; repeated zero eigenvalues (integrators of cyclic coordinates,
        // 2×2 Jordan blocks) move by the square root of that, so 1e-6 relative.
        let mut unused = b.clone();
        for z in &a {
            let (k, d) = unused
                .iter()
                .enumerate()
                .map(|(k, w)| (k, (z.0 - w.0).hypot(z.1 - w.1)))
                .min_by(|x, y| x.1.total_cmp(&y.1))
                .unwrap();
            assert!(d <= 1e-6 * scale, "{name}: {z:?} has no partner (nearest {d:e}); {joints:?} vs {bodies:?}");
            unused.swap_remove(k);
        }
        compared.push((name, joints, bodies));
    }
    for c in &compared {
        eprintln!("{} : {:?} vs {:?}", c.0, c.1, c.2);
    }
    // Every example model with a static equilibrium takes part: all but the driven blades
    // and slider crank and the spinning top (its spin about the symmetry axis has no
    // stiffness, so its static problem is singular). The joint choice differs from the
    // body one in most of them.
    assert!(compared.len() >= 14, "{} variants compared", compared.len());
    assert!(compared.iter().filter(|c| c.1 != c.2).count() >= 6);
}

/// A body on a cylindrical joint to ground (axis: ground z), spring k along the axis; the
/// rotation is driven by a motion when `driven`, and spins freely at 10 rad/s otherwise.
fn cylinder(driven: bool) -> Model {
    let motion = if driven { r#"<motion name="spin" joint="cyl" dof="rotation" function="10*time"/>"# } else { "" };
    let xml = format!(
        r#"<multibody name="cyl" version="1">
  <parameter name="k" value="400"/>
  <ground><marker name="O" position="0 0 0"/><marker name="A" position="0 0 -1"/></ground>
  <body name="rotor" mass="4" inertia="0.1 0.1 0.2" position="0 0 0" angular_velocity="0 0 10">
    <marker name="c" position="0 0 0"/>
  </body>
  <joint name="cyl" type="cylindrical" i="rotor.c" j="ground.O"/>
  {motion}
  <spring_damper name="s" type="translational" i="rotor.c" j="ground.A" stiffness="k" damping="0" length="1"/>
</multibody>"#
    );
    load_str(&xml, "cyl.xml").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_motion_leaves_its_joints_other_coordinate_as_the_state() {
    // The driven rotation is no degree of freedom: the cylindrical joint's displacement is
    // the only state, and the axial spring gives λ = ±i·sqrt(k/m) = ±10i (exact: the
    // translation does not couple with the rotation about the same axis).
    let mut sim =
        Simulator::new(&cylinder(true), SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize(&mut sim, &sel, 1).unwrap();
    assert_eq!(lin.states, ["cyl.displacement", "der(cyl.displacement)"]);
    let rows = eigen_table(&lin.a).unwrap();
    assert_eq!(rows.len(), 1);
    assert!(rows[0].re.abs() < 1e-10 && (rows[0].im - 10.0).abs() < 1e-10, "{rows:?}");
}

#[test]
fn a_joint_angle_state_is_continuous_through_pi() {
    // Free spin at 10 rad/s: after 1 s the angle state reads 10 rad (not 10 − 4π), and its
    // rate 10 rad/s; the integrator's tolerance 1e-10 bounds the error.
    let mut sim =
        Simulator::new(&cylinder(false), SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let names: Vec<&str> = sel.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["cyl.angle", "cyl.displacement"]);
    sim.advance(1.0).unwrap();
    let v = mbfmu::linearize::state_values(&mut sim, &sel).unwrap();
    assert!((v.s[0] - 10.0).abs() < 1e-7, "{:?}", v.s);
    assert!((v.sd[0] - 10.0).abs() < 1e-7, "{:?}", v.sd);
}

#[test]
fn a_spherical_joint_near_its_angle_singularity_falls_back_to_body_coordinates() {
    // The pendulum's ball joint markers are turned so that the z-y-x pitch of i relative to
    // j is 80° (> 60°): the joint's yaw, pitch, roll are no candidates; body angles are.
    let xml = |pitch_deg: f64| {
        format!(
            r#"<multibody name="sph" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="bob" mass="1" inertia="0.01 0.01 0.01" position="0 0 -1">
    <marker name="top" position="0 0 1" euler313="{a}, {b}, {c}"/>
  </body>
  <joint name="ball" type="spherical" i="bob.top" j="ground.O"/>
</multibody>"#,
            // Ry(p) = Rz(π/2)·Rx(p)·Rz(−π/2) as 3-1-3 angles (ψ, θ, φ).
            a = std::f64::consts::FRAC_PI_2,
            b = pitch_deg.to_radians(),
            c = -std::f64::consts::FRAC_PI_2
        )
    };
    let names = |p: f64| {
        let m = load_str(&xml(p), "sph.xml").unwrap_or_else(|e| panic!("{e}"));
        let sim = Simulator::new(&m, SimOptions::default(), 0.0).unwrap();
        let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
        sel.states.iter().map(|s| s.name.clone()).collect::<Vec<_>>()
    };
    assert_eq!(names(30.0), ["ball.yaw", "ball.pitch", "ball.roll"]);
    assert_eq!(names(80.0), ["bob.psi", "bob.theta", "bob.phi"]);
}
