//! Exact linearization (Eq. 34) against analytic results and against central differences
//! of the engine's own state-space equations (tests only).

use crate::common::state_space;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::eigen_table;
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::Model;
use mbfmu::model::parse::load_str;

/// Eigenvalue rows (frequency, damping, re, im) at time t.
fn eig_at(m: &Model, t: f64) -> (Vec<String>, Vec<(f64, f64)>) {
    let mut sim = Simulator::new(m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    sim.advance(t).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let rows = eigen_table(&lin.a).unwrap();
    (sel.states.iter().map(|s| s.name.clone()).collect(), rows.iter().map(|r| (r.re, r.im)).collect())
}

fn with_states(xml: &str, states: &str) -> Model {
    let start = xml.find("<linearization>").unwrap();
    let end = xml.find("</linearization>").unwrap() + "</linearization>".len();
    let text = format!("{}{}{}", &xml[..start], states, &xml[end..]);
    let m = load_str(&text, "dp.xml").unwrap();
    let mut p = m.param_values();
    for (k, par) in m.parameters.iter().enumerate() {
        if par.name == "th1" || par.name == "th2" {
            p[k] = 0.0;
        }
    }
    m.with_params(&p).unwrap()
}

#[test]
fn double_pendulum_at_rest_has_the_analytic_frequencies_whichever_states() {
    // Two uniform rods (m = L = 1) hanging at rest: det(K − ω²M) = 0 with
    // M = mL²[[4/3, 1/2], [1/2, 1/3]], K = mgL[[3/2, 0], [0, 1/2]] gives
    // ω² = (g/L)(3 ∓ 6/√7). At an equilibrium the eigenvalues do not depend on the
    // coordinates: joint angles, tip x coordinates, or the engine's own choice all agree
    // with the closed form to 1e-9 relative (exact linearization; round-off only).
    let xml =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/double_pendulum.xml"))
            .unwrap();
    let g = 9.80665f64;
    let w = [(g * (3.0 - 6.0 / 7f64.sqrt())).sqrt(), (g * (3.0 + 6.0 / 7f64.sqrt())).sqrt()];
    let choices = [
        r#"<linearization><state name="a1" function="az(rod1.P, ground.O)"/><state name="a2" function="az(rod2.P, ground.O)"/></linearization>"#,
        r#"<linearization><state name="x1" function="dx(rod1.A)"/><state name="x2" function="dx(rod2.tip)"/></linearization>"#,
        "",
    ];
    for states in choices {
        let (names, rows) = eig_at(&with_states(&xml, states), 0.0);
        assert_eq!(rows.len(), 2, "{names:?} {rows:?}");
        for (k, (re, im)) in rows.iter().enumerate() {
            assert!(re.abs() < 1e-9 * w[k], "{names:?}: re {re}");
            assert!((im - w[k]).abs() < 1e-9 * w[k], "{names:?}: {im} vs {}", w[k]);
        }
    }
}

#[test]
fn damped_pendulum_has_the_analytic_natural_frequency_and_damping_ratio() {
    // Compound pendulum (pivot 0.6 m from the CM) with a viscous joint damper c about its
    // lower equilibrium: J_p θ'' + c θ' + m g d θ = 0, J_p = J_cm + m d²:
    // ω_n = sqrt(m g d / J_p), ζ = c / (2 sqrt(J_p m g d)). 1e-9 relative.
    let (m, jc, d, c, g) = (1.5f64, 0.08f64, 0.6f64, 0.4f64, 9.81f64);
    let xml = format!(
        r#"<multibody name="p" version="1">
  <gravity value="0 0 -{g}"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="b" mass="{m}" inertia="0.05 {jc} 0.06" position="0 0 -{d}">
    <marker name="P" position="0 0 {d}" z_axis="0 1 0"/>
  </body>
  <joint name="j" type="revolute" i="b.P" j="ground.O"/>
  <spring_damper name="damper" type="rotational" i="b.P" j="ground.O" stiffness="0" damping="{c}"/>
  <linearization><state name="tilt" function="az(b.P, ground.O)"/></linearization>
</multibody>"#
    );
    let model = load_str(&xml, "p.xml").unwrap();
    let (_, rows) = eig_at(&model, 0.0);
    let jp = jc + m * d * d;
    let wn = (m * g * d / jp).sqrt();
    let zeta = c / (2.0 * (jp * m * g * d).sqrt());
    assert_eq!(rows.len(), 1);
    let (re, im) = rows[0];
    let f = re.hypot(im);
    assert!((f - wn).abs() < 1e-9 * wn, "{f} vs {wn}");
    assert!((-re / f - zeta).abs() < 1e-9, "{} vs {zeta}", -re / f);
}

#[test]
fn state_selection_completes_keeps_and_drops_user_states() {
    let xml =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/double_pendulum.xml"))
            .unwrap();
    let names = |states: &str| {
        let m = with_states(&xml, states);
        let sim = Simulator::new(&m, SimOptions::default(), 0.0).unwrap();
        let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
        (sel.states.iter().map(|s| s.name.clone()).collect::<Vec<_>>(), sel.dropped)
    };
    // None: the two hinge angles.
    let (s, d) = names("");
    assert_eq!(s, ["hinge1.angle", "hinge2.angle"]);
    assert!(d.is_empty());
    // Fewer than the dofs: the user's is kept, completed by the joint to ground (rod2's
    // absolute angle a2 and hinge1's angle are independent; hinge2's = a2 − hinge1's is
    // not, given both).
    let (s, d) = names(r#"<linearization><state name="a2" function="az(rod2.P, ground.O)"/></linearization>"#);
    assert_eq!(s, ["a2", "hinge1.angle"]);
    assert!(d.is_empty());
    // More than the dofs: one of three dropped and reported.
    let (s, d) = names(
        r#"<linearization><state name="a1" function="az(rod1.P, ground.O)"/><state name="a2" function="az(rod2.P, ground.O)"/><state name="x2" function="dx(rod2.tip)"/></linearization>"#,
    );
    assert_eq!(s.len(), 2, "{s:?}");
    assert_eq!(d.len(), 1, "{d:?}");
    // A state that cannot parameterize the motion (depends on time only) is dropped too.
    let (s, d) = names(r#"<linearization><state name="clock" function="0*dx(rod1.A) + time"/></linearization>"#);
    assert_eq!(d, ["clock"]);
    assert_eq!(s, ["hinge1.angle", "hinge2.angle"]);
}

#[test]
fn singular_partition_is_reported_not_returned_as_a_matrix() {
    // A free rotor (no gravity) turning at 1 rad/s about ground z, linearized in the y
    // coordinate of its CM, y = L sin θ: fine at θ = 0, singular at θ = π/2 (dy/dθ = 0),
    // reached at t = π/2 (uniform rotation, integrated to ~1e-10). There linearize must
    // refuse with a message, never return a matrix.
    let xml = r#"<multibody name="r" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="b" mass="1" inertia="0.1 0.1 0.1" position="0.5 0 0" angular_velocity="0 0 1" velocity="0 0.5 0">
    <marker name="P" position="-0.5 0 0"/>
  </body>
  <joint name="j" type="revolute" i="b.P" j="ground.O"/>
  <linearization><state name="yc" function="dy(b.cm)"/></linearization>
</multibody>"#;
    let m = load_str(xml, "r.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-12, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states[0].name, "yc");
    assert!(linearize(&mut sim, &sel, 1).is_ok());
    sim.advance(std::f64::consts::FRAC_PI_2).unwrap();
    let err = linearize(&mut sim, &sel, 1).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("no longer parameterize"), "{err}");
}

const ARM: &str = r#"<multibody name="arm" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 0 1"/></ground>
  <body name="l1" mass="2" inertia="0.02 0.02 0.01" position="0 0 0.25">
    <marker name="base" position="0 0 -0.25" z_axis="0 0 1"/>
    <marker name="top" position="0 0 0.25" z_axis="0 1 0"/>
  </body>
  <body name="l2" mass="1.5" inertia="0.04 0.01 0.04" position="0 0.2 0.5" euler313="0.1 0.2 0.3">
    <marker name="a" position="0 -0.2 0" z_axis="0 1 0"/>
    <marker name="b" position="0 0.2 0" z_axis="1 0 0"/>
  </body>
  <body name="l3" mass="1" inertia="0.02 0.01 0.02" position="0 0.55 0.5">
    <marker name="a" position="0 -0.15 0" z_axis="1 0 0"/>
    <marker name="tip" position="0 0.15 0"/>
  </body>
  <joint name="j1" type="revolute" i="l1.base" j="ground.O"/>
  <joint name="j2" type="revolute" i="l2.a" j="l1.top"/>
  <joint name="j3" type="revolute" i="l3.a" j="l2.b"/>
  <input name="T1" start="0.5"/>
  <input name="T2" start="-0.3"/>
  <input name="T3" start="0.2"/>
  <sforce name="m1" type="rotational" i="l1.base" j="ground.O" function="T1 - 0.1*wz(l1.base, ground.O, ground.O)"/>
  <sforce name="m2" type="rotational" i="l2.a" j="l1.top" function="T2"/>
  <sforce name="m3" type="rotational" i="l3.a" j="l2.b" function="T3 + 0.5*sin(az(l3.a, l2.b))"/>
  <output name="tip_x" function="dx(l3.tip)"/>
  <output name="tip_z" function="dz(l3.tip)"/>
  <output name="tip_acc" function="accy(l3.tip) + 0.1*T1"/>
</multibody>"#;

#[test]
fn spatial_arm_abcd_match_central_differences_of_the_state_space_equations() {
    // At a non-equilibrium point (after 0.3 s of motion, internal states chosen by Eq. 33),
    // A, B, C, D from Eq. 34 against central differences of the engine's own state-space
    // map (solve q, u from the states, u̇ from the equations of motion). h = 1e-6:
    // truncation ~1e-12·|f'''|, round-off ~1e-16/1e-6 · |f| ≈ 1e-9 relative, so 1e-6
    // (relative to max(1, |entry|)) is a safe bound that still catches any wrong term.
    let m = load_str(ARM, "arm.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states.len(), 3);
    sim.advance(0.3).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let (sys, q0, t, v0) = (sim.system().clone(), sim.q().to_vec(), sim.time(), sim.inputs());
    let x0 = lin.x.clone();
    let ns = x0.len();
    let h = 1e-6;
    let check = |name: &str, got: f64, want: f64| {
        assert!((got - want).abs() < 1e-6 * want.abs().max(1.0), "{name}: {got} vs {want}");
    };
    for j in 0..ns {
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[j] += h;
        xm[j] -= h;
        let (fp, yp) = state_space(&sys, &sel, &q0, t, &xp, &v0);
        let (fm, ym) = state_space(&sys, &sel, &q0, t, &xm, &v0);
        for i in 0..ns {
            check(&format!("A[{i},{j}]"), lin.a[(i, j)], (fp[i] - fm[i]) / (2.0 * h));
        }
        for o in 0..yp.len() {
            check(&format!("C[{o},{j}]"), lin.c[(o, j)], (yp[o] - ym[o]) / (2.0 * h));
        }
    }
    for k in 0..v0.len() {
        let (mut vp, mut vm) = (v0.clone(), v0.clone());
        vp[k] += h;
        vm[k] -= h;
        let (fp, yp) = state_space(&sys, &sel, &q0, t, &x0, &vp);
        let (fm, ym) = state_space(&sys, &sel, &q0, t, &x0, &vm);
        for i in 0..ns {
            check(&format!("B[{i},{k}]"), lin.b[(i, k)], (fp[i] - fm[i]) / (2.0 * h));
        }
        for o in 0..yp.len() {
            check(&format!("D[{o},{k}]"), lin.d[(o, k)], (yp[o] - ym[o]) / (2.0 * h));
        }
    }
    // The acceleration output feels the torques directly: D has nonzero entries.
    assert!(
        (0..3).any(|k| lin.d[(2, k)].abs() > 1e-3),
        "D row of tip_acc: {:?}",
        (0..3).map(|k| lin.d[(2, k)]).collect::<Vec<_>>()
    );
}

#[test]
fn static_analysis_finds_the_equilibrium_and_its_analytic_frequencies() {
    // <analysis static="true"/> on the double pendulum drawn at (1, 0.5) rad: Newton on
    // Q − Pᵀλ = 0, C = 0 finds the hanging equilibrium; there ω² = (g/L)(3 ∓ 6/√7) (1e-9),
    // and the pendulum stays at rest (|Δ angle| < 1e-9 after 1 s).
    let xml =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/double_pendulum.xml"))
            .unwrap()
            .replace("<linearization>", r#"<analysis static="true"/><linearization>"#);
    let m = load_str(&xml, "dp.xml").unwrap();
    assert!(m.static_analysis);
    let (_, rows) = eig_at(&m, 0.0);
    let g = 9.80665f64;
    let w = [(g * (3.0 - 6.0 / 7f64.sqrt())).sqrt(), (g * (3.0 + 6.0 / 7f64.sqrt())).sqrt()];
    for (k, (re, im)) in rows.iter().enumerate() {
        assert!(re.abs() < 1e-9 * w[k] && (im - w[k]).abs() < 1e-9 * w[k], "{rows:?}");
    }
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let a0 = sim.outputs().unwrap()[0];
    assert!(a0.abs() < 1e-9, "hanging: theta1 = {a0}");
    sim.advance(1.0).unwrap();
    assert!((sim.outputs().unwrap()[0] - a0).abs() < 1e-9);
}

/// A planar 5-link pendulum, released horizontal, a torque input on the first hinge;
/// its outputs each measure all five bodies (more than one element may touch).
fn five_link_chain() -> String {
    let (n, l) = (5, 0.5);
    let mut s = String::from(
        r#"<multibody name="chain5" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
"#,
    );
    for i in 0..n {
        let x = l / 2.0 + i as f64 * l;
        s += &format!(
            r#"  <body name="b{i}" mass="{m}" inertia="0.001 {j} {j}" position="{x} 0 0">
    <marker name="P" position="{h} 0 0" z_axis="0 1 0"/>
    <marker name="A" position="{k} 0 0" z_axis="0 1 0"/>
  </body>
"#,
            m = 1.0 + 0.1 * i as f64,
            j = l * l / 12.0,
            h = -l / 2.0,
            k = l / 2.0
        );
        let j = if i == 0 { "ground.O".to_string() } else { format!("b{}.A", i - 1) };
        s += &format!("  <joint name=\"h{i}\" type=\"revolute\" i=\"b{i}.P\" j=\"{j}\"/>\n");
    }
    let sum = |f: &dyn Fn(usize) -> String| (0..n).map(f).collect::<Vec<_>>().join(" + ");
    s += r#"  <input name="T" start="0.4"/>
  <sforce name="motor" type="rotational" i="b0.P" j="ground.O" function="T"/>
"#;
    s += &format!(
        "  <output name=\"energy\" function=\"{}\"/>\n",
        sum(&|i| format!("0.5*vm(b{i}.cm)^2 + 9.81*dz(b{i}.cm)"))
    );
    s += &format!("  <output name=\"acc\" function=\"{} + 0.1*T\"/>\n", sum(&|i| format!("accz(b{i}.cm)")));
    s + "</multibody>\n"
}

#[test]
fn outputs_that_measure_more_bodies_than_an_element_may_match_central_differences() {
    // An output is not an element: it may measure every body of the model. Its gradient is
    // seeded four bodies at a time; C and D against central differences of the state-space
    // map, h = 1e-6 and tolerance 1e-6 relative to max(1, |entry|) as for the spatial arm.
    let m = load_str(&five_link_chain(), "chain5.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states.len(), 5);
    sim.advance(0.2).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let (sys, q0, t, v0) = (sim.system().clone(), sim.q().to_vec(), sim.time(), sim.inputs());
    let (x0, h) = (lin.x.clone(), 1e-6);
    let check = |name: &str, got: f64, want: f64| {
        assert!((got - want).abs() < 1e-6 * want.abs().max(1.0), "{name}: {got} vs {want}");
    };
    for j in 0..x0.len() {
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[j] += h;
        xm[j] -= h;
        let (_, yp) = state_space(&sys, &sel, &q0, t, &xp, &v0);
        let (_, ym) = state_space(&sys, &sel, &q0, t, &xm, &v0);
        for o in 0..2 {
            check(&format!("C[{o},{j}]"), lin.c[(o, j)], (yp[o] - ym[o]) / (2.0 * h));
        }
    }
    let (mut vp, mut vm) = (v0.clone(), v0.clone());
    vp[0] += h;
    vm[0] -= h;
    let ((_, yp), (_, ym)) = (state_space(&sys, &sel, &q0, t, &x0, &vp), state_space(&sys, &sel, &q0, t, &x0, &vm));
    for o in 0..2 {
        check(&format!("D[{o},0]"), lin.d[(o, 0)], (yp[o] - ym[o]) / (2.0 * h));
    }
    // Every body counts: the energy's row is not zero in any velocity state.
    assert!((5..10).all(|j| lin.c[(0, j)].abs() > 1e-3), "C row of energy: {:?}", lin.c.row(0));
    assert!(lin.d[(1, 0)].abs() > 0.1, "D of acc: {}", lin.d[(1, 0)]);
}
