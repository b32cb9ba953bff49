//! Compound pendulum released at 170°: period against the exact elliptic-integral value.

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_str;

/// Complete elliptic integral of the first kind K(k) by the arithmetic-geometric mean.
fn ellip_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
    }
    std::f64::consts::PI / (2.0 * a)
}

fn pendulum(theta0: f64) -> String {
    let (s, c) = (theta0.sin(), theta0.cos());
    format!(
        r#"<multibody name="pendulum" version="1">
  <parameter name="L" value="1"/>
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="rod" mass="2" inertia="0.2 0.3 0.25" position="{x} 0 {z}">
    <marker name="P" position="{px} 0 {pz}" z_axis="0 1 0"/>
  </body>
  <joint name="pivot" type="revolute" i="rod.P" j="ground.O"/>
  <output name="omega" function="wy(rod.cm)"/>
</multibody>"#,
        x = s,
        z = -c,
        px = -s,
        pz = c
    )
}

#[test]
fn pendulum_at_170_deg_has_the_elliptic_period() {
    let theta0 = 170f64.to_radians();
    let model = load_str(&pendulum(theta0), "pendulum.xml").expect("model loads");
    let (m, g, l, jyy): (f64, f64, f64, f64) = (2.0, 9.81, 1.0, 0.3);
    let w0 = (m * g * l / (jyy + m * l * l)).sqrt();
    let period = 4.0 * ellip_k((theta0 / 2.0).sin()) / w0;
    let mut sim = Simulator::new(&model, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0)
        .expect("initializes");
    sim.advance(0.5 * period).expect("integrates");
    let w = sim.outputs().unwrap()[0];
    // Near the turning point ω(T/2 + δt) ≈ θ̈ δt with |θ̈| = ω0² sin θ0, so δt = ω/|θ̈|.
    let dt = w / (w0 * w0 * theta0.sin());
    eprintln!("period {period}, dt {dt:e}, stats {:?}, |C| {:e}", sim.stats(), sim.constraint_residual());
    assert!((dt / period).abs() < 1e-7, "relative period error {:e}", dt / period);
    assert!(sim.constraint_residual() < 1e-10);
}

/// The same swing co-simulated in 1 ms communication steps (steps held short of their
/// natural size by the grid, which keep their factorization and converge Newton below
/// their truncation error): the half period against the elliptic integral to the
/// requested tolerance (2.5e-8 relative measured), and the work counted.
#[test]
fn pendulum_in_1_ms_communication_steps_keeps_the_elliptic_period() {
    let theta0 = 170f64.to_radians();
    let model = load_str(&pendulum(theta0), "pendulum.xml").expect("model loads");
    let (m, g, l, jyy): (f64, f64, f64, f64) = (2.0, 9.81, 1.0, 0.3);
    let w0 = (m * g * l / (jyy + m * l * l)).sqrt();
    let period = 4.0 * ellip_k((theta0 / 2.0).sin()) / w0;
    let tol = 1e-6;
    let mut sim =
        Simulator::new(&model, SimOptions { tol, max_step: None, ..Default::default() }, 0.0).expect("initializes");
    let steps = (0.5 * period / 1e-3).floor() as usize;
    for k in 1..=steps {
        sim.advance(k as f64 * 1e-3).expect("integrates");
    }
    sim.advance(0.5 * period).expect("integrates");
    let w = sim.outputs().unwrap()[0];
    let dt = w / (w0 * w0 * theta0.sin());
    let st = sim.stats();
    eprintln!("period {period}, dt {dt:e}, stats {st:?}, |C| {:e}", sim.constraint_residual());
    // The phase error of the half period, relative, within the tolerance asked for.
    assert!((dt / period).abs() < tol, "relative period error {:e}", dt / period);
    assert!(sim.constraint_residual() < tol * 1e-3, "|C| {:e}", sim.constraint_residual());
    // Held steps keep J and its LU for many steps (35 Jacobians in 2626 steps; 67 with
    // the threshold of free-running steps); none is rejected (a slow Newton iteration
    // takes a fresh J within the step).
    assert!(st.jacobians * 50 < st.accepted, "{} Jacobians for {} steps", st.jacobians, st.accepted);
    assert!(st.rejected <= 2, "{} rejected steps", st.rejected);
}
