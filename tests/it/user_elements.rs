//! User elements (seed Eq. 7): differential states, variables (with algebraic loops),
//! forces reading them, simulated and linearized in the same augmented system.

use crate::common::{lin_at_start, model, model_text};
use faer::Mat;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::eigen_table;
use mbfmu::model::parse::load_str;

/// Parameters of models/cart_pendulum_pid.xml.
struct Cart {
    big_m: f64,
    m: f64,
    a: f64,
    j: f64,
    g: f64,
    kp: f64,
    ki: f64,
    kd: f64,
}

const CART: Cart = Cart { big_m: 2.0, m: 0.5, a: 0.4, j: 0.5 * 0.64 / 12.0, g: 9.81, kp: 60.0, ki: 30.0, kd: 10.0 };

fn max_abs(m: &Mat<f64>) -> f64 {
    let mut w = 0.0f64;
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            w = w.max(m[(r, c)].abs());
        }
    }
    w
}

fn assert_close(name: &str, got: &Mat<f64>, want: &Mat<f64>, tol: f64) {
    assert_eq!((got.nrows(), got.ncols()), (want.nrows(), want.ncols()), "{name} shape");
    let scale = max_abs(want).max(1.0);
    for r in 0..want.nrows() {
        for c in 0..want.ncols() {
            let e = (got[(r, c)] - want[(r, c)]).abs() / scale;
            assert!(e < tol, "{name}[{r},{c}] = {} want {} (rel. error {e:e})", got[(r, c)], want[(r, c)]);
        }
    }
}

#[test]
fn pid_cart_pendulum_matches_the_hand_linearized_closed_loop() {
    // States (x, th, x', th', xi), input r, outputs (force, angle). From
    // [M+m, ma; ma, J+ma²][x''; th''] = [fc; m g a th], fc = kp (th − r) + ki xi + kd th',
    // xi' = th − r. Exact linearization: agreement to round-off; 1e-10 relative to the
    // largest entry leaves margin for the sparse LU's backward error (~1e-14·cond).
    let c = CART;
    let lin = lin_at_start(&model("cart_pendulum_pid.xml"));
    assert_eq!(lin.states, ["x", "th", "der(x)", "der(th)", "xi"]);
    let ma = c.m * c.a;
    let jp = c.j + c.m * c.a * c.a;
    let dm = (c.big_m + c.m) * jp - ma * ma;
    let mut a = Mat::<f64>::zeros(5, 5);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    a[(2, 1)] = (jp * c.kp - ma * c.m * c.g * c.a) / dm;
    a[(2, 3)] = jp * c.kd / dm;
    a[(2, 4)] = jp * c.ki / dm;
    a[(3, 1)] = ((c.big_m + c.m) * c.m * c.g * c.a - ma * c.kp) / dm;
    a[(3, 3)] = -ma * c.kd / dm;
    a[(3, 4)] = -ma * c.ki / dm;
    a[(4, 1)] = 1.0;
    let mut b = Mat::<f64>::zeros(5, 1);
    b[(2, 0)] = -jp * c.kp / dm;
    b[(3, 0)] = ma * c.kp / dm;
    b[(4, 0)] = -1.0;
    let mut cm = Mat::<f64>::zeros(2, 5);
    cm[(0, 1)] = c.kp;
    cm[(0, 3)] = c.kd;
    cm[(0, 4)] = c.ki;
    cm[(1, 1)] = 1.0;
    let mut d = Mat::<f64>::zeros(2, 1);
    d[(0, 0)] = -c.kp;
    assert_close("A", &lin.a, &a, 1e-10);
    assert_close("B", &lin.b, &b, 1e-10);
    assert_close("C", &lin.c, &cm, 1e-10);
    assert_close("D", &lin.d, &d, 1e-10);
}

#[test]
fn pid_closed_loop_eigenvalues_are_the_roots_of_the_characteristic_polynomial() {
    // The (th, th', xi) loop: Dm s³ + m a kd s² + (m a kp − (M+m) m g a) s + m a ki = 0,
    // roots from its companion matrix (an independent path: no mechanics involved); the
    // cart adds a double zero. Tolerance 1e-8 relative to |root| (the issue's bound; the
    // simple roots are well conditioned).
    let c = CART;
    let ma = c.m * c.a;
    let dm = (c.big_m + c.m) * (c.j + c.m * c.a * c.a) - ma * ma;
    let p = [ma * c.kd / dm, (ma * c.kp - (c.big_m + c.m) * c.m * c.g * c.a) / dm, ma * c.ki / dm];
    let mut comp = Mat::<f64>::zeros(3, 3);
    comp[(0, 0)] = -p[0];
    comp[(0, 1)] = -p[1];
    comp[(0, 2)] = -p[2];
    comp[(1, 0)] = 1.0;
    comp[(2, 1)] = 1.0;
    let mut want: Vec<(f64, f64)> = comp.eigenvalues().unwrap().iter().map(|z| (z.re, z.im.abs())).collect();
    let lin = lin_at_start(&model("cart_pendulum_pid.xml"));
    let rows = eigen_table(&lin.a).unwrap();
    let got: Vec<(f64, f64)> = rows.iter().map(|r| (r.re, r.im.abs())).collect();
    let zeros = got.iter().filter(|(re, im)| re.abs() < 1e-7 && *im < 1e-7).count();
    assert_eq!(zeros, 2, "{got:?}");
    for w in want.iter_mut() {
        let best = got.iter().map(|g| ((g.0 - w.0).powi(2) + (g.1 - w.1).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
        let mag = (w.0 * w.0 + w.1 * w.1).sqrt();
        assert!(best < 1e-8 * mag, "root {w:?} not among {got:?} (error {best:e})");
    }
}

#[test]
fn implicit_and_explicit_differentials_linearize_alike() {
    // d(xi)/dt = e written implicitly (0.5·dif1(xi) − 0.5·e = 0) is the same equation.
    let text = model_text("cart_pendulum_pid.xml");
    let implicit = text.replace(
        r#"<differential name="xi" start="0" function="e"/>"#,
        r#"<differential name="xi" start="0" implicit="true" function="0.5*dif1(xi) - 0.5*e"/>"#,
    );
    assert_ne!(implicit, text);
    let a = lin_at_start(&model("cart_pendulum_pid.xml"));
    let b = lin_at_start(&load_str(&implicit, "implicit.xml").unwrap());
    assert_close("A", &a.a, &b.a, 1e-12);
    assert_close("B", &a.b, &b.b, 1e-12);
}

#[test]
fn pid_loop_simulates_back_to_upright_like_its_linearization() {
    // From th0 = 0.01 rad the controller brings the pendulum back. Against the linear model
    // ẋ = A x integrated by RK4 (h = 1e-4, error ~1e-13): the nonlinear motion differs by
    // O(th0³) terms ≈ 1e-6·|th|, so |th − th_lin| < 1e-5 over 3 s.
    let text = model_text("cart_pendulum_pid.xml");
    let m0 = load_str(&text, "c.xml").unwrap();
    let lin = lin_at_start(&m0);
    let th0 = 0.01;
    let text = text.replace(
        r#"position="0 0 a">"#,
        &format!(r#"position="a*sin({th0}) 0 a*cos({th0})" euler313="pi/2 {th0} -pi/2">"#),
    );
    let m = load_str(&text, "c.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let y0 = sim.outputs().unwrap();
    assert!((y0[1] - th0).abs() < 1e-12, "initial angle {}", y0[1]);
    let mut x = [0.0, th0, 0.0, 0.0, 0.0];
    let f = |x: &[f64; 5]| -> [f64; 5] { std::array::from_fn(|r| (0..5).map(|c| lin.a[(r, c)] * x[c]).sum()) };
    let h = 1e-4;
    let mut worst = 0.0f64;
    for k in 1..=30 {
        for _ in 0..1000 {
            let k1 = f(&x);
            let k2 = f(&std::array::from_fn(|i| x[i] + 0.5 * h * k1[i]));
            let k3 = f(&std::array::from_fn(|i| x[i] + 0.5 * h * k2[i]));
            let k4 = f(&std::array::from_fn(|i| x[i] + h * k3[i]));
            x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
        sim.advance(0.1 * k as f64).unwrap();
        let th = sim.outputs().unwrap()[1];
        worst = worst.max((th - x[1]).abs());
        assert!(sim.constraint_residual() < 1e-9);
    }
    assert!(worst < 1e-5, "nonlinear vs linear angle: {worst:e}");
    assert!(x[1].abs() < 0.2 * th0, "the loop is stable: th(3) = {}", x[1]);
}

const ADDED_MASS: &str = r#"<multibody name="added_mass" version="1">
  <parameter name="m" value="2"/>
  <parameter name="ma" value="0.5" description="added (fluid) mass"/>
  <parameter name="k" value="50"/>
  <ground><marker name="rail" position="0 0 0" z_axis="1 0 0" x_axis="0 1 0"/></ground>
  <body name="b" mass="m" inertia="1 1 1" position="0.1 0 0">
    <marker name="s" position="0 0 0" z_axis="1 0 0" x_axis="0 1 0"/>
  </body>
  <joint name="slide" type="translational" i="b.s" j="ground.rail"/>
  <spring_damper name="spring" type="translational" i="b.cm" j="ground.rail" stiffness="k" damping="0" length="0"/>
  <variable name="drag" function="-ma*accx(b.cm)"/>
  <gforce name="fluid" i="b.cm" force="drag 0 0"/>
  <output name="x" function="dx(b.cm)"/>
  <output name="drag_out" function="drag"/>
</multibody>"#;

#[test]
fn a_force_proportional_to_acceleration_acts_as_added_mass() {
    // F = −m_a ẍ (through a variable): (m + m_a) ẍ = −k x, ω = sqrt(k / (m + m_a)).
    // Linearization: eigenvalues ±iω to 1e-9 relative (exact). Simulation from x0 = 0.1 at
    // rest: x = x0 cos ωt to 1e-7 over 2 s (tol 1e-10; global error ≈ 100·tol), and the
    // drag output equals m_a ω² x (1e-6).
    added_mass_case(0.5);
    // An added mass larger than the body's (loop gain 2.5): the initial algebraic loop is
    // solved by Newton, not by fixed point.
    added_mass_case(5.0);
}

fn added_mass_case(ma: f64) {
    let m = load_str(
        &ADDED_MASS.replace(r#"value="0.5" description="added"#, &format!(r#"value="{ma}" description="added"#)),
        "added_mass.xml",
    )
    .unwrap();
    let w = (50.0f64 / (2.0 + ma)).sqrt();
    let lin = lin_at_start(&m);
    let rows = eigen_table(&lin.a).unwrap();
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert!((rows[0].im.abs() - w).abs() < 1e-9 * w && rows[0].re.abs() < 1e-9 * w, "{rows:?}");
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    for k in 1..=20 {
        let t = 0.1 * k as f64;
        sim.advance(t).unwrap();
        let y = sim.outputs().unwrap();
        let x = 0.1 * (w * t).cos();
        assert!((y[0] - x).abs() < 1e-7, "t = {t}: x = {} want {x}", y[0]);
        assert!((y[1] - ma * w * w * y[0]).abs() < 1e-6, "t = {t}: drag {} want {}", y[1], ma * w * w * y[0]);
    }
}

#[test]
fn static_equilibrium_solves_for_the_controller_state_too() {
    // A pendulum (m = 1, CM at L = 0.5 from the hinge) held by a PI torque
    // τ = −kp (θ − θr) − ki X with X' = θ − θr. Static equilibrium (<analysis static="true"/>)
    // solves q, λ and X with Ẋ = 0: θ = θr and −ki X = m g L sin θr, so X = −m g L sin θr / ki
    // (closed form; Newton converges to the assembly tolerance, 1e-9 asserted).
    let xml = r#"<multibody name="held" version="1">
      <parameter name="th_r" value="0.3"/>
      <parameter name="kp" value="20"/>
      <parameter name="ki" value="5"/>
      <gravity value="0 0 -9.81"/>
      <ground><marker name="O" position="0 0 0" z_axis="0 1 0" x_axis="0 0 -1"/></ground>
      <body name="bob" mass="1" inertia="0.05 0.1 0.1" position="0 0 -0.5" z_axis="0 1 0" x_axis="0 0 -1">
        <marker name="P" position="-0.5 0 0"/>
      </body>
      <joint name="hinge" type="revolute" i="bob.P" j="ground.O"/>
      <variable name="err" function="az(bob.P, ground.O) - th_r"/>
      <differential name="xi" start="0" function="err"/>
      <sforce name="motor" type="rotational" i="bob.P" j="ground.O" function="-kp*err - ki*xi"/>
      <output name="angle" function="az(bob.P, ground.O)"/>
      <output name="xi_out" function="xi"/>
      <analysis static="true"/>
    </multibody>"#;
    let m = load_str(xml, "held.xml").unwrap();
    let sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let mut sim = sim;
    let y = sim.outputs().unwrap();
    let want_x = -9.81 * 0.5 * 0.3f64.sin() / 5.0; // m = 1
    assert!((y[0] - 0.3).abs() < 1e-9, "angle {}", y[0]);
    assert!((y[1] - want_x).abs() < 1e-9, "xi {} want {want_x}", y[1]);
    // And it stays there.
    sim.advance(1.0).unwrap();
    let y = sim.outputs().unwrap();
    assert!((y[0] - 0.3).abs() < 1e-8 && (y[1] - want_x).abs() < 1e-8, "{y:?}");
}
