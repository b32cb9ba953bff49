//! The eigenvalue routes: the second-order route (A = [0 I; X 0] → λ² = eig(X)) against
//! the closed form of a hanging chain of uniform rods and against the general route on
//! the example models; models with damping or gyroscopic terms take the general route.

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::{EigenRoute, eigen_table, eigen_table_structured};
use mbfmu::linearize::{Linearization, Selection, linearize, select_states};
use mbfmu::model::Model;
use mbfmu::model::parse::{load_file, load_str};
use nalgebra::DMatrix;

fn linearized(m: &Model, t: f64) -> (Linearization, Selection) {
    let mut sim = Simulator::new(m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    if t > 0.0 {
        sim.advance(t).unwrap();
    }
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    (lin, sel)
}

/// A planar chain of `n` uniform rods (mass m, length l) hanging straight down from
/// revolute joints about y.
fn hanging_rods(n: usize, m: f64, l: f64) -> String {
    let mut s = String::from(
        r#"<multibody name="rods" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
"#,
    );
    for i in 0..n {
        let z = -(l / 2.0 + i as f64 * l);
        s += &format!(
            r#"  <body name="b{i}" mass="{m}" inertia="{j} {j} 0.0001" position="0 0 {z}">
    <marker name="P" position="0 0 {h}" z_axis="0 1 0"/>
    <marker name="A" position="0 0 -{h}" z_axis="0 1 0"/>
  </body>
"#,
            j = m * l * l / 12.0,
            h = l / 2.0
        );
        let j = if i == 0 { "ground.O".to_string() } else { format!("b{}.A", i - 1) };
        s += &format!("  <joint name=\"h{i}\" type=\"revolute\" i=\"b{i}.P\" j=\"{j}\"/>\n");
    }
    s + "</multibody>\n"
}

/// The chain's small-oscillation frequencies from its Lagrangian in absolute rod angles:
/// M_jk = Σ_i m v_ij v_ik + δ_jk m l²/12 with v_ij = l (j < i), l/2 (j = i), 0 (j > i);
/// K = m g l diag(n − j − 1/2); ω² = eig(L⁻¹ K L⁻ᵀ), M = L Lᵀ (nalgebra).
fn rod_frequencies(n: usize, m: f64, l: f64, g: f64) -> Vec<f64> {
    let v = |i: usize, j: usize| {
        if j < i {
            l
        } else if j == i {
            l / 2.0
        } else {
            0.0
        }
    };
    let mass = DMatrix::from_fn(n, n, |j, k| {
        (0..n).map(|i| m * v(i, j) * v(i, k)).sum::<f64>() + if j == k { m * l * l / 12.0 } else { 0.0 }
    });
    let stiff = DMatrix::from_fn(n, n, |j, k| if j == k { m * g * l * ((n - j) as f64 - 0.5) } else { 0.0 });
    let chol = mass.cholesky().unwrap();
    let linv = chol.l().try_inverse().unwrap();
    let sym = &linv * stiff * linv.transpose();
    let mut w: Vec<f64> = sym.symmetric_eigen().eigenvalues.iter().map(|x| x.sqrt()).collect();
    w.sort_by(f64::total_cmp);
    w
}

#[test]
fn a_hanging_rod_chain_takes_the_second_order_route_with_the_closed_form_frequencies() {
    // 1e-9 relative: the exact linearization and both eigensolvers are round-off only
    // (the closed form is good to ~1e-15; the chain's stiffness ratio is below 1e3).
    for n in [1, 3, 8] {
        let (m, l, g) = (0.7, 0.4, 9.81);
        let model = load_str(&hanging_rods(n, m, l), "rods.xml").unwrap();
        let (lin, sel) = linearized(&model, 0.0);
        let (rows, route) = eigen_table_structured(&lin.a, sel.states.len(), sel.velocities.len()).unwrap();
        assert_eq!(route, EigenRoute::SecondOrder { s: n });
        let exact = rod_frequencies(n, m, l, g);
        assert_eq!(rows.len(), n);
        for (r, w) in rows.iter().zip(&exact) {
            assert!(r.re.abs() < 1e-9 * w, "n = {n}: re {}", r.re);
            assert!((r.im - w).abs() < 1e-9 * w, "n = {n}: {} vs {w}", r.im);
        }
    }
}

#[test]
fn both_routes_agree_on_the_example_models() {
    // Whichever route is taken, the eigenvalues equal the general route's to 1e-10 of the
    // largest |λ| (round-off of two dense eigensolvers). Undamped models at rest take the
    // second-order route; damping, gyroscopic terms, velocity-dependent forces, user
    // states and non-holonomic constraints (fewer velocity than position states) keep
    // the general one.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut second_order = 0;
    for (name, t) in [
        ("pendulum", 0.0),
        ("double_pendulum", 0.0),
        ("double_pendulum", 0.3),
        ("fourbar", 0.2),
        ("slider_crank", 0.1),
        ("spinning_top", 0.1),
        ("spring_mass_damper", 0.0),
        ("rolling_disc", 0.0),
        ("cart_pendulum_pid", 0.0),
        ("benchmark_bicycle", 0.0),
        ("torque_free_body", 0.1),
    ] {
        let model = load_file(&root.join(format!("models/{name}.xml"))).unwrap();
        let (lin, sel) = linearized(&model, t);
        let general = eigen_table(&lin.a).unwrap();
        let (rows, route) = eigen_table_structured(&lin.a, sel.states.len(), sel.velocities.len()).unwrap();
        if matches!(route, EigenRoute::SecondOrder { .. }) {
            second_order += 1;
        }
        let scale = general.iter().map(|r| r.frequency).fold(1.0, f64::max);
        assert_eq!(rows.len(), general.len(), "{name} at {t}: {route:?}");
        // Each row against the nearest of the other route (rows of equal frequency, as
        // a real pair ±σ, may come in either order).
        for a in &rows {
            let d = general.iter().map(|b| (a.re - b.re).hypot(a.im - b.im)).fold(f64::INFINITY, f64::min);
            assert!(d < 1e-10 * scale, "{name} at {t} ({route:?}): {a:?} not in {general:?}");
        }
    }
    assert!(second_order >= 2, "the undamped pendulums at rest take the second-order route");
}

#[test]
fn damping_keeps_the_general_route() {
    let xml = r#"<multibody name="p" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="b" mass="1.5" inertia="0.05 0.08 0.06" position="0 0 -0.6">
    <marker name="P" position="0 0 0.6" z_axis="0 1 0"/>
  </body>
  <joint name="j" type="revolute" i="b.P" j="ground.O"/>
  <spring_damper name="damper" type="rotational" i="b.P" j="ground.O" stiffness="0" damping="0.4"/>
</multibody>"#;
    let (lin, sel) = linearized(&load_str(xml, "p.xml").unwrap(), 0.0);
    let (_, route) = eigen_table_structured(&lin.a, sel.states.len(), sel.velocities.len()).unwrap();
    assert_eq!(route, EigenRoute::General { n: 2 });
}
