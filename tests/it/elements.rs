//! Each joint type and force element against an analytic motion or a second, independent
//! way of writing the same model.

use crate::common::out;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_str;

fn sim(xml: &str, tol: f64) -> Simulator {
    let m = load_str(xml, "t.xml").unwrap_or_else(|e| panic!("{e}"));
    Simulator::new(&m, SimOptions { tol, max_step: None, ..Default::default() }, 0.0).unwrap_or_else(|e| panic!("{e}"))
}

/// A body on a joint whose z axis is ground z, with gravity g_z, initial axial speed and spin.
fn on_axis(joint: &str, extra: &str) -> String {
    format!(
        r#"<multibody name="t" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="2" inertia="0.3 0.3 0.5" position="0 0 1" velocity="0 0 3" angular_velocity="0 0 4">
    <marker name="M" position="0 0 0"/>
  </body>
  <joint name="j" type="{joint}" i="b.M" j="ground.O"/>
  {extra}
  <output name="z" function="dz(b.cm)"/>
  <output name="spin" function="wz(b.cm)"/>
  <output name="x" function="dx(b.cm)"/>
</multibody>"#
    )
}

#[test]
fn cylindrical_joint_allows_free_fall_along_and_spin_about_its_axis() {
    // Along the axis: z = 1 + 3t − g t²/2; about it: ω_z = 4 (no torque). Tolerance 1e-8:
    // polynomial motion, integrated at tol 1e-10.
    let mut s = sim(&on_axis("cylindrical", ""), 1e-10);
    for k in 1..=10 {
        let t = 0.1 * k as f64;
        s.advance(t).unwrap();
        assert!((out(&mut s, "z") - (1.0 + 3.0 * t - 0.5 * 9.81 * t * t)).abs() < 1e-8);
        assert!((out(&mut s, "spin") - 4.0).abs() < 1e-8);
        assert!(out(&mut s, "x").abs() < 1e-10);
    }
}

#[test]
fn translational_joint_allows_axial_motion_but_stops_the_spin() {
    // Same free fall; the translational joint also locks rotation about the axis: the
    // initial spin is removed by velocity assembly (closest consistent velocity), ω_z = 0.
    let mut s = sim(&on_axis("translational", ""), 1e-10);
    s.advance(1.0).unwrap();
    assert!((out(&mut s, "z") - (1.0 + 3.0 - 0.5 * 9.81)).abs() < 1e-8);
    assert!(out(&mut s, "spin").abs() < 1e-10);
}

#[test]
fn planar_joint_allows_in_plane_motion_and_spin() {
    // Plane z = 0 of ground.O (normal z), gravity with an in-plane component: the body keeps
    // z = 0 and moves with x = g_x t²/2, spinning at ω_z = 4.
    let xml = r#"<multibody name="t" version="1">
  <gravity value="1.5 0 -9.81"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="2" inertia="0.3 0.3 0.5" position="0 0 0" angular_velocity="0 0 4"/>
  <joint name="j" type="planar" i="b.cm" j="ground.O"/>
  <output name="z" function="dz(b.cm)"/>
  <output name="x" function="dx(b.cm)"/>
  <output name="spin" function="wz(b.cm)"/>
  <output name="lift" function="fz(j)"/>
</multibody>"#;
    let mut s = sim(xml, 1e-10);
    s.advance(2.0).unwrap();
    assert!(out(&mut s, "z").abs() < 1e-10);
    assert!((out(&mut s, "x") - 0.5 * 1.5 * 4.0).abs() < 1e-8);
    assert!((out(&mut s, "spin") - 4.0).abs() < 1e-8);
    // The plane carries the weight: force on the body's marker = +m g.
    assert!((out(&mut s, "lift") - 2.0 * 9.81).abs() < 1e-8);
}

#[test]
fn fixed_joint_holds_the_body_and_carries_its_weight() {
    let xml = r#"<multibody name="t" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="3" inertia="0.3 0.4 0.5" position="1 0 0">
    <marker name="M" position="-1 0 0"/>
  </body>
  <joint name="weld" type="fixed" i="b.M" j="ground.O"/>
  <output name="z" function="dz(b.cm)"/>
  <output name="lift" function="fz(weld)"/>
  <output name="moment" function="ty(weld)"/>
</multibody>"#;
    let mut s = sim(xml, 1e-10);
    s.advance(1.0).unwrap();
    assert!(out(&mut s, "z").abs() < 1e-12);
    // Statics: the weld pushes up with m g; the weight acts at the CM, 1 m along +x from
    // the weld marker, with moment (1,0,0) × (0,0,−mg) = (0, mg, 0) about it, so the weld
    // applies −mg about y. Exact up to round-off.
    assert!((out(&mut s, "lift") - 3.0 * 9.81).abs() < 1e-9);
    assert!((out(&mut s, "moment") + 3.0 * 9.81).abs() < 1e-9);
}

/// A compound pendulum swinging in the x-z plane about ground y, hinged by `joint`.
fn swing(joint: &str, i_axis: &str) -> String {
    format!(
        r#"<multibody name="t" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="b" mass="1.5" inertia="0.05 0.08 0.06" position="0.6 0 -0.3">
    <marker name="P" position="-0.6 0 0.3" z_axis="{i_axis}"/>
  </body>
  <joint name="j" type="{joint}" i="b.P" j="ground.O"/>
  <output name="x" function="dx(b.cm)"/>
  <output name="z" function="dz(b.cm)"/>
</multibody>"#
    )
}

#[test]
fn universal_joint_swinging_in_its_plane_is_a_revolute_pendulum() {
    // A universal joint whose cross axes are ground y (j) and the body's x (i) lets the
    // body swing about y exactly like a revolute about y when the motion starts in the
    // plane (the second freedom stays unexcited by symmetry). Both integrate at tol 1e-10,
    // so they agree to ~1e-9.
    let mut rev = sim(&swing("revolute", "0 1 0"), 1e-10);
    let mut uni = sim(&swing("universal", "1 0 0"), 1e-10);
    for k in 1..=20 {
        let t = 0.1 * k as f64;
        rev.advance(t).unwrap();
        uni.advance(t).unwrap();
        for o in ["x", "z"] {
            let (a, b) = (out(&mut rev, o), out(&mut uni, o));
            assert!((a - b).abs() < 1e-8, "{o} at {t}: {a} vs {b}");
        }
    }
}

#[test]
fn rotational_spring_damper_is_a_damped_torsional_oscillator() {
    // J θ'' + c θ' + k θ = 0 about a revolute (z): from θ0 at rest,
    // θ = e^{−ζω t}(θ0 cos ω_d t + ζω θ0/ω_d sin ω_d t). Tolerance 1e-8 rad at tol 1e-11.
    let (jz, k, c, th0): (f64, f64, f64, f64) = (0.5, 20.0, 0.6, 0.4);
    let xml = format!(
        r#"<multibody name="t" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="1" inertia="0.3 0.3 {jz}" position="0 0 0" euler313="{th0} 0 0"/>
  <joint name="j" type="revolute" i="b.cm" j="ground.O"/>
  <spring_damper name="s" type="rotational" i="b.cm" j="ground.O" stiffness="{k}" damping="{c}"/>
  <output name="a" function="az(b.cm, ground.O)"/>
</multibody>"#
    );
    let mut s = sim(&xml, 1e-11);
    let wn = (k / jz).sqrt();
    let zeta = c / (2.0 * (k * jz).sqrt());
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    for i in 1..=30 {
        let t = 0.1 * i as f64;
        s.advance(t).unwrap();
        let exact = (-zeta * wn * t).exp() * (th0 * (wd * t).cos() + zeta * wn * th0 / wd * (wd * t).sin());
        assert!((out(&mut s, "a") - exact).abs() < 1e-8, "t {t}");
    }
}

#[test]
fn rotational_spring_winds_past_pi_continuously() {
    // A free rotor spun at 10 rad/s against a soft torsional spring winds several turns:
    // the spring angle must be continuous (unwrapped), so energy ½Jω² + ½kθ² is conserved.
    let xml = r#"<multibody name="t" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="1" inertia="0.3 0.3 0.5" position="0 0 0" angular_velocity="0 0 10"/>
  <joint name="j" type="revolute" i="b.cm" j="ground.O"/>
  <spring_damper name="s" type="rotational" i="b.cm" j="ground.O" stiffness="0.2" damping="0"/>
</multibody>"#;
    let mut s = sim(xml, 1e-10);
    let e0 = s.mechanical_energy();
    for k in 1..=40 {
        s.advance(0.1 * k as f64).unwrap();
        assert!((s.mechanical_energy() - e0).abs() < 1e-7 * e0, "t {}", 0.1 * k as f64);
    }
}

#[test]
fn sforces_equal_the_spring_dampers_they_spell_out() {
    // The same translational and rotational spring-dampers written as sforce expressions:
    // two independent code paths (element formula vs expression + line-of-sight/axis
    // application) must give the same motion to integration tolerance.
    let body = r#"<gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0"/><marker name="A" position="0.2 0.1 0.5"/></ground>
  <body name="b" mass="1.2" inertia="0.1 0.2 0.15" position="0.4 -0.2 -0.6" euler313="0.3 0.8 0.2"
        velocity="0.5 0 0.2" angular_velocity="0.3 -1 2"/>"#;
    let elems = r#"<spring_damper name="s1" type="translational" i="b.cm" j="ground.A" stiffness="40" damping="0.8" length="0.7" preload="1"/>
  <spring_damper name="s2" type="rotational" i="b.cm" j="ground.O" stiffness="3" damping="0.1" angle="0.2"/>"#;
    let forces = r#"<sforce name="s1" type="translational" i="b.cm" j="ground.A" function="-40*(dm(b.cm, ground.A) - 0.7) - 0.8*vr(b.cm, ground.A) + 1"/>
  <sforce name="s2" type="rotational" i="b.cm" j="ground.O" function="-3*(az(b.cm, ground.O) - 0.2) - 0.1*wz(b.cm, ground.O, ground.O)"/>"#;
    let outs = r#"<output name="x" function="dx(b.cm)"/><output name="y" function="dy(b.cm)"/><output name="p" function="psi(b.cm)"/>"#;
    let m1 = format!(r#"<multibody name="t" version="1">{body}{elems}{outs}</multibody>"#);
    let m2 = format!(r#"<multibody name="t" version="1">{body}{forces}{outs}</multibody>"#);
    let (mut a, mut b) = (sim(&m1, 1e-10), sim(&m2, 1e-10));
    for k in 1..=20 {
        let t = 0.1 * k as f64;
        a.advance(t).unwrap();
        b.advance(t).unwrap();
        for o in ["x", "y", "p"] {
            let (u, v) = (out(&mut a, o), out(&mut b, o));
            assert!((u - v).abs() < 1e-7, "{o} at {t}: {u} vs {v}");
        }
    }
}

#[test]
fn gforce_in_a_body_frame_with_reaction() {
    // Two free bodies, no gravity. A gforce on body 1 pointing along body 1's x axis with
    // its reaction on body 2: the pair's total momentum stays zero while body 1 accelerates
    // along its (non-rotating) x axis: x1 = F t²/(2 m1), x2 = −F t²/(2 m2).
    let xml = r#"<multibody name="t" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="a" mass="2" inertia="0.1 0.1 0.1" position="0 0 0" euler313="0.7 0 0"/>
  <body name="b" mass="4" inertia="0.1 0.1 0.1" position="0 0 0"/>
  <gforce name="push" i="a.cm" j="b.cm" frame="a.cm" force="3 0 0" torque="0 0 0"/>
  <output name="xa" function="dx(a.cm, ground.O, a.cm)"/>
  <output name="xb" function="dx(b.cm, ground.O, a.cm)"/>
  <output name="spin" function="wz(a.cm)"/>
</multibody>"#;
    let mut s = sim(xml, 1e-11);
    s.advance(1.5).unwrap();
    let t = 1.5f64;
    assert!((out(&mut s, "xa") - 3.0 * t * t / 4.0).abs() < 1e-9);
    assert!((out(&mut s, "xb") + 3.0 * t * t / 8.0).abs() < 1e-9);
    assert!(out(&mut s, "spin").abs() < 1e-12);
}

#[test]
fn constant_torque_spins_up_a_free_rotor_linearly() {
    // ω(t) = T t / J about a principal axis (no gyroscopic coupling): exact for any step.
    let xml = r#"<multibody name="t" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="1" inertia="0.2 0.3 0.5" position="0 0 0"/>
  <gforce name="motor" i="r.cm" force="0 0 0" torque="0 0 2"/>
  <output name="w" function="wz(r.cm)"/>
</multibody>"#;
    let mut s = sim(xml, 1e-8);
    s.advance(3.0).unwrap();
    assert!((out(&mut s, "w") - 2.0 * 3.0 / 0.5).abs() < 1e-10);
}
