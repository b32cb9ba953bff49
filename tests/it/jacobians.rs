//! The engine's exact derivatives against central finite differences (tests only; the
//! engine itself never differentiates numerically). The model deliberately mixes every
//! joint type, motions, a user constraint and every force element on three bodies in
//! general orientations; it need not be assemblable, since derivatives are checked at
//! arbitrary states. A second model puts a flexible body with 50 modes among them, its
//! node markers on joints, forces and non-holonomic constraints: its elements have up to
//! 68 local coordinates, so every derivative kernel seeds its dual numbers a chunk at a
//! time, and those chunked derivatives are checked the same way.

use mbfmu::dae::equations::{JacScratch, Layout, jacobian, jacobian_with, rhs};
use mbfmu::dae::residual::RhsScratch;
use mbfmu::dae::sparse::Triplets;
use mbfmu::mechanics::System;
use mbfmu::mechanics::body::NQ;
use mbfmu::mechanics::constraint_jacobian::{acceleration_rhs, p_row};
use mbfmu::mechanics::coords::{gather, nql, rates};
use mbfmu::mechanics::kernels::constraint_first;
use mbfmu::model::parse::load_str;

const KITCHEN_SINK: &str = r#"<multibody name="sink" version="1">
  <parameter name="k" value="30"/>
  <gravity value="0.3 -0.2 -9.81"/>
  <ground><marker name="O" position="0.1 0.2 0.3" euler313="0.2 0.7 -0.4"/></ground>
  <body name="a" mass="1.3" inertia="0.2 0.3 0.4 0.01 -0.02 0.03" position="0.4 -0.1 0.2" euler313="0.3 1.1 0.5">
    <marker name="m1" position="0.1 0.2 -0.1" euler313="-0.3 0.4 0.9"/>
    <marker name="m2" position="-0.2 0.1 0.05" z_axis="0.2 1 0.3"/>
  </body>
  <body name="b" mass="0.7" inertia="0.1 0.15 0.12" position="-0.3 0.5 0.1" euler313="1.2 2.0 -0.7"
        velocity="0.1 0.2 -0.3" angular_velocity="0.5 -0.4 1.1">
    <marker name="m1" position="0.05 -0.1 0.2" euler313="0.5 0.3 0.2"/>
    <marker name="m2" position="0.3 0.0 -0.1" euler313="-1.0 1.3 0.1"/>
  </body>
  <body name="c" mass="2.1" inertia="0.5 0.4 0.3" position="0.2 0.3 -0.6" euler313="-0.6 0.9 2.4">
    <marker name="m1" position="-0.1 0.1 0.1" euler313="0.1 0.2 0.3"/>
  </body>
  <joint name="jfix" type="fixed" i="a.m1" j="b.m1"/>
  <joint name="jrev" type="revolute" i="b.m2" j="c.m1"/>
  <joint name="jtra" type="translational" i="c.m1" j="ground.O"/>
  <joint name="jcyl" type="cylindrical" i="a.m2" j="c.cm"/>
  <joint name="juni" type="universal" i="a.cm" j="ground.O"/>
  <joint name="jsph" type="spherical" i="b.cm" j="c.m1"/>
  <joint name="jpla" type="planar" i="c.cm" j="b.m2"/>
  <motion name="mrot" joint="jrev" dof="rotation" function="0.3*sin(2*time) + 0.1*time^2"/>
  <motion name="mtra" joint="jtra" dof="translation" function="0.2*cos(3*time)"/>
  <constraint name="uc" function="dx(a.m1, b.m2, c.m1)*cos(time) + az(b.m2, a.m2) - 0.1"/>
  <spring_damper name="st" type="translational" i="a.m1" j="c.m1" stiffness="k" damping="0.7" length="0.3" preload="2"/>
  <spring_damper name="sr" type="rotational" i="b.m2" j="a.m2" stiffness="5" damping="0.2" angle="0.1" preload="0.3"/>
  <sforce name="ft" type="translational" i="b.m1" j="ground.O" function="-3*dm(b.m1, ground.O) - 0.5*vr(b.m1, ground.O) + sin(time)"/>
  <sforce name="fr" type="rotational" i="c.cm" j="a.m1" function="-2*az(c.cm, a.m1) - 0.4*wz(c.cm, a.m1, a.m1)"/>
  <gforce name="g1" i="a.m2" j="b.m1" frame="c.m1" force="vx(a.m2, b.m1)*2, -dy(a.m2), 1+time" torque="wz(a.m2)*0.5, 0.2, -dz(b.cm, a.cm, c.m1)"/>
  <gforce name="g2" i="c.m1" force="0 0 3" torque="0.1*wx(c.cm) 0 0"/>
  <bushing name="bu" i="a.m2" j="b.m1" stiffness="10 20 30 4 5 6" damping="0.1 0.2 0.3 0.04 0.05 0.06"/>
  <rolling_wheel name="wheel" marker="a.m2" radius="0.35"/>
  <rolling_wheel name="wheel2" marker="b.m2" radius="0.2" plane="c.m1"/>
  <knife_edge name="knife" marker="b.m1"/>
  <velocity_constraint name="vc" function="vx(c.cm)*dy(a.cm) + 0.3*wz(c.cm, b.cm, a.m1) - 0.2*sin(time)"/>
  <input name="v"/>
  <variable name="loop1" function="0.3*loop2 + dx(a.m1, b.cm) + v*xi"/>
  <variable name="loop2" function="-0.2*loop1^2 + sin(xi) + wz(c.cm)"/>
  <differential name="xi" start="0.2" function="loop1 - 0.5*xi + vx(b.cm)"/>
  <differential name="filt" start="-0.1" implicit="true" function="0.3*dif1(filt) + filt^3 - loop2*dif1(xi)"/>
  <variable name="fric" function="0.2*sqrt(fz(jrev)^2 + 0.01) + 0.1*fx(st) - 0.05*ty(jsph)"/>
  <sforce name="fu" type="translational" i="a.cm" j="c.cm" function="2*loop1 + filt*v - xi + fric"/>
  <gforce name="g4" i="c.cm" force="0.3*fy(jrev) 0 tz(mrot)" torque="0 0 0.1*fx(g2)"/>
  <sforce name="added_mass" type="translational" i="b.cm" j="ground.O" function="-0.4*accx(b.cm, ground.O, b.m1) + 0.1*wdtz(a.m2)"/>
  <variable name="acc_var" function="0.2*accz(c.cm) + 0.1*loop1"/>
  <gforce name="g5" i="a.cm" force="acc_var 0 0"/>
  <gforce name="g3" i="b.cm" force="loop2 dif1(filt) 0" torque="0 0 xi*wz(b.cm)"/>
</multibody>"#;

/// The input value used at every evaluation.
const INPUTS: [f64; 1] = [0.7];

/// Pseudo-random numbers in [-1, 1] (LCG, reproducible).
fn rng(seed: &mut u64) -> f64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// The rigid kitchen sink at a pseudo-random state.
fn setup() -> (System, Layout, Vec<f64>) {
    let model = load_str(KITCHEN_SINK, "sink.xml").unwrap_or_else(|e| panic!("{e}"));
    let sys = System::from_model(&model).unwrap();
    let lay = Layout::of(&sys);
    assert_eq!((lay.nx, lay.nv, lay.na), (2, 4, 18));
    assert_eq!(sys.load_refs.len(), 5);
    let y = random_state(&sys, lay, 0.0);
    (sys, lay, y)
}

/// Modes of the flexible sink's body: more than any dual number the kernels use is wide.
const FLEX_MODES: usize = 50;

/// The flexible sink: body `b` is a free-free beam (12 elements, 1 m along x) with
/// [`FLEX_MODES`] modes, its markers on nodes, at a pseudo-random state. Modal
/// coordinates ± 1e-3 m·√kg (deflections of a few mm, node rotations up to ~0.1 rad in
/// the highest modes), rates ± 1e-2. Each test writes its data file in a directory of
/// its own (`test`): tests run in parallel.
fn setup_flexible(test: &str) -> (System, Layout, Vec<f64>) {
    use mbfmu::modal::{BeamSpec, Material, Reduction, Section, beam, write};
    let spec = BeamSpec {
        length: 1.0,
        elements: 12,
        section: Section { area: 1e-3, iy: 2e-9, iz: 1e-9, j: 3e-9 },
        material: Material { young: 7e9, shear: 2.7e9, density: 2700.0 },
        modes: FLEX_MODES,
        damping: Some(0.02),
        clamp: None,
        reduction: Reduction::FreeInterface,
        shear_coefficient: None,
    };
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("jacobians-flexible").join(test);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("beam.json"), write(&beam(&spec).unwrap())).unwrap();
    let path = dir.join("sink.xml").display().to_string();
    let model = load_str(FLEXIBLE_SINK, &path).unwrap_or_else(|e| panic!("{e}"));
    let sys = System::from_model(&model).unwrap();
    let lay = Layout::of(&sys);
    assert_eq!(lay.n, 3 * NQ + FLEX_MODES);
    assert!(sys.constraints.iter().any(|el| nql(&sys, &el.bodies) == 2 * NQ + FLEX_MODES));
    let y = random_state(&sys, lay, 1e-3);
    (sys, lay, y)
}

/// The flexible sink: the kitchen sink's elements with body `b` flexible (accelerations
/// of a flexible body may not be read by forces, so `added_mass` reads body a).
const FLEXIBLE_SINK: &str = r#"<multibody name="flexsink" version="1">
  <gravity value="0.3 -0.2 -9.81"/>
  <ground><marker name="O" position="0.1 0.2 0.3" euler313="0.2 0.7 -0.4"/></ground>
  <body name="a" mass="1.3" inertia="0.2 0.3 0.4 0.01 -0.02 0.03" position="0.4 -0.1 0.2" euler313="0.3 1.1 0.5">
    <marker name="m1" position="0.1 0.2 -0.1" euler313="-0.3 0.4 0.9"/>
    <marker name="m2" position="-0.2 0.1 0.05" z_axis="0.2 1 0.3"/>
  </body>
  <flexible_body name="b" modal="beam.json" position="-0.3 0.5 0.1" euler313="1.2 2.0 -0.7"
        velocity="0.1 0.2 -0.3" angular_velocity="0.5 -0.4 1.1">
    <marker name="m1" node="3" euler313="0.5 0.3 0.2"/>
    <marker name="m2" node="12" euler313="-1.0 1.3 0.1"/>
    <marker name="mid" node="6"/>
  </flexible_body>
  <body name="c" mass="2.1" inertia="0.5 0.4 0.3" position="0.2 0.3 -0.6" euler313="-0.6 0.9 2.4">
    <marker name="m1" position="-0.1 0.1 0.1" euler313="0.1 0.2 0.3"/>
  </body>
  <joint name="jfix" type="fixed" i="a.m1" j="b.m1"/>
  <joint name="jrev" type="revolute" i="b.m2" j="c.m1"/>
  <joint name="jsph" type="spherical" i="b.mid" j="c.m1"/>
  <joint name="jpla" type="planar" i="c.cm" j="b.m2"/>
  <joint name="juni" type="universal" i="a.cm" j="ground.O"/>
  <motion name="mrot" joint="jrev" dof="rotation" function="0.3*sin(2*time) + 0.1*time^2"/>
  <constraint name="uc" function="dx(a.m1, b.m2, c.m1)*cos(time) + az(b.m2, a.m2) + 0.2*modal(b, 40) - 0.1"/>
  <spring_damper name="st" type="translational" i="a.m1" j="b.mid" stiffness="30" damping="0.7" length="0.3" preload="2"/>
  <spring_damper name="sr" type="rotational" i="b.m2" j="a.m2" stiffness="5" damping="0.2" angle="0.1" preload="0.3"/>
  <sforce name="ft" type="translational" i="b.m1" j="ground.O" function="-3*dm(b.m1, ground.O) - 0.5*vr(b.m1, ground.O) + sin(time)"/>
  <gforce name="g1" i="a.m2" j="b.m1" frame="c.m1" force="vx(a.m2, b.m1)*2, -dy(a.m2), 1+time" torque="wz(b.mid)*0.5, 0.2, -dz(b.cm, a.cm, c.m1)"/>
  <bushing name="bu" i="a.m2" j="b.mid" stiffness="10 20 30 4 5 6" damping="0.1 0.2 0.3 0.04 0.05 0.06"/>
  <rolling_wheel name="wheel" marker="b.m2" radius="0.2" plane="c.m1"/>
  <knife_edge name="knife" marker="b.m1"/>
  <velocity_constraint name="vc" function="vx(c.cm)*dy(b.mid) + 0.3*wz(c.cm, b.m1, a.m1) - 0.2*sin(time) + modal_rate(b, 45)"/>
  <input name="v"/>
  <variable name="loop1" function="0.3*loop2 + dx(a.m1, b.cm) + v*xi + modal(b, 50)"/>
  <variable name="loop2" function="-0.2*loop1^2 + sin(xi) + wz(b.mid)"/>
  <differential name="xi" start="0.2" function="loop1 - 0.5*xi + vx(b.m2)"/>
  <variable name="fric" function="0.2*sqrt(fz(jrev)^2 + 0.01) + 0.1*fx(st) - 0.05*ty(jsph) + 0.1*tz(bu)"/>
  <sforce name="fu" type="translational" i="a.cm" j="b.m2" function="2*loop1 - xi + fric"/>
  <sforce name="added_mass" type="translational" i="a.cm" j="ground.O" function="-0.4*accx(a.cm, ground.O, a.m1)"/>
</multibody>"#;

/// A state near the initial one: body coordinates ± 0.1, velocities ± 1, modal
/// coordinates ± `eta` and their rates ± 10·`eta`, and λ, z at random.
fn random_state(sys: &System, lay: Layout, eta: f64) -> Vec<f64> {
    let mut seed = 7;
    let mut y = vec![0.0; lay.dim()];
    let modal = sys.modal_columns();
    for i in 0..lay.n {
        let (dq, du) = if modal.contains(&i) { (eta, 10.0 * eta) } else { (0.1, 1.0) };
        y[i] = sys.q_init[i] + dq * rng(&mut seed);
        y[lay.u() + i] = sys.u_init[i] + du * rng(&mut seed);
    }
    for i in 0..lay.nz() {
        y[lay.z() + i] = rng(&mut seed);
    }
    for i in 0..lay.m + lay.mn {
        y[lay.lam() + i] = 3.0 * rng(&mut seed); // λ then ν
    }
    y
}

#[test]
fn jacobian_of_the_equations_of_motion_matches_central_differences() {
    jacobian_matches_central_differences(setup());
}

/// The same with a 50-mode flexible body (chunked derivative kernels).
#[test]
fn jacobian_of_a_model_with_a_fifty_mode_body_matches_central_differences() {
    jacobian_matches_central_differences(setup_flexible("jacobian"));
}

fn jacobian_matches_central_differences((sys, lay, y): (System, Layout, Vec<f64>)) {
    // J = ∂f/∂y is exact except the term ∂(C_qᵀμ)/∂q, which vanishes on the solution (μ = 0),
    // so μ = 0 here. Fourth-order central differences, (8(f(h) − f(−h)) − (f(2h) − f(−2h)))
    // / 12h with h = 1e-6: truncation ~h⁴·|f⁽⁵⁾|/30, round-off ~1.5ε|f|/h (allowed for
    // explicitly: rows of large |f| with small derivatives lose digits to it). A
    // flexible body's highest modes turn its nodes by ρ ~ 300 rad per unit η, so its
    // derivatives grow as ρⁿ: second-order differences would err by h²ρ³/6 ≈ 5e-6 there,
    // fourth-order ones by h⁴ρ⁵/30 ≈ 1e-13. Agreement to 1e-6 (relative to max(1, |J|))
    // leaves margin while catching any wrong term (errors of O(1)).
    let t = 0.37;
    let n = lay.dim();
    let mut trip = Triplets::new();
    jacobian(&sys, lay, t, &y, &INPUTS, &mut trip);
    let mut jd = vec![0.0; n * n];
    for (p, v) in trip.idx.iter().zip(&trip.vals) {
        jd[p.row * n + p.col] += v;
    }
    let mut worst = (0.0f64, 0, 0);
    for c in 0..n {
        let h = 1e-6 * y[c].abs().max(1.0);
        let f_at = |s: f64| {
            let mut ys = y.clone();
            ys[c] += s;
            let mut f = vec![0.0; n];
            rhs(&sys, lay, t, &ys, &INPUTS, &mut RhsScratch::default(), &mut f);
            f
        };
        let (f1, fm1, f2, fm2) = (f_at(h), f_at(-h), f_at(2.0 * h), f_at(-2.0 * h));
        for r in 0..n {
            let fd = (8.0 * (f1[r] - fm1[r]) - (f2[r] - fm2[r])) / (12.0 * h);
            // Round-off of the difference quotient, (16 + 2)·ε|f|/12h, ten times over.
            let size = [f1[r], fm1[r], f2[r], fm2[r]].iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let roundoff = 15.0 * f64::EPSILON * size / h;
            let e = ((fd - jd[r * n + c]).abs() - roundoff).max(0.0) / jd[r * n + c].abs().max(1.0);
            if e > worst.0 {
                worst = (e, r, c);
            }
        }
    }
    assert!(worst.0 < 1e-6, "worst relative error {:e} at row {} col {}", worst.0, worst.1, worst.2);
}

#[test]
fn the_iteration_matrix_leaves_out_only_the_cross_body_constraint_force_derivatives() {
    iteration_matrix_differs_only_across_bodies(setup());
}

#[test]
fn the_iteration_matrix_of_a_fifty_mode_body_keeps_its_own_modal_coupling() {
    iteration_matrix_differs_only_across_bodies(setup_flexible("iteration-matrix"));
}

/// The integrator's iteration matrix (`JacScratch::within_bodies`) against the exact J,
/// entry by entry: they differ only in force-balance rows of one body (its u rows, or the
/// acceleration rows they move to) × q columns of another, the constraint forces' change
/// with the other body's pose, which the exact J has there (at random λ of O(1)); with
/// λ = 0 they agree everywhere. Entry sums are formed in the same order, so agreement is
/// to round-off of one sum (1e-13 relative to max(1, |J|)).
fn iteration_matrix_differs_only_across_bodies((sys, lay, mut y): (System, Layout, Vec<f64>)) {
    let t = 0.37;
    let n = lay.dim();
    let dense = |y: &[f64], within_bodies: bool| {
        let mut ws = JacScratch::default();
        ws.within_bodies = within_bodies;
        let mut trip = Triplets::new();
        jacobian_with(&sys, lay, t, y, &INPUTS, &mut ws, &mut trip);
        let mut jd = vec![0.0; n * n];
        for (p, v) in trip.idx.iter().zip(&trip.vals) {
            jd[p.row * n + p.col] += v;
        }
        jd
    };
    // The body of each force-balance row: u rows, and acceleration rows by their dof.
    let mut row_body = vec![None; n];
    for g in 0..lay.n {
        row_body[lay.u() + g] = Some(sys.body_of_coordinate(g));
        if let Some(r) = lay.acc_row(&sys.acc_bodies, g) {
            row_body[r] = Some(sys.body_of_coordinate(g));
        }
    }
    let (exact, approx) = (dense(&y, false), dense(&y, true));
    let mut dropped = 0.0f64;
    for r in 0..n {
        for c in 0..n {
            let d = (exact[r * n + c] - approx[r * n + c]).abs();
            let across = c < lay.n && row_body[r].is_some_and(|b| b != sys.body_of_coordinate(c));
            if across {
                dropped = dropped.max(d);
            } else {
                assert!(d <= 1e-13 * exact[r * n + c].abs().max(1.0), "row {r} col {c}: {d:e} apart");
            }
        }
    }
    assert!(dropped > 1e-2, "no cross-body entry left out (largest {dropped:e})");
    y[lay.lam_range()].fill(0.0);
    let (exact, approx) = (dense(&y, false), dense(&y, true));
    for (i, (e, a)) in exact.iter().zip(&approx).enumerate() {
        assert!((e - a).abs() <= 1e-13 * e.abs().max(1.0), "λ = 0, entry {i}: {e} vs {a}");
    }
}

#[test]
fn acceleration_right_hand_side_is_the_second_time_derivative_of_the_constraints() {
    gamma_is_the_second_time_derivative_of_the_constraints(setup());
}

/// The same with a 50-mode flexible body (chunked second derivatives).
#[test]
fn acceleration_right_hand_side_with_a_fifty_mode_body_is_the_second_time_derivative() {
    gamma_is_the_second_time_derivative_of_the_constraints(setup_flexible("gamma"));
}

fn gamma_is_the_second_time_derivative_of_the_constraints((sys, lay, y): (System, Layout, Vec<f64>)) {
    // C̈ = P u̇ + γ (Eq. 1c). Along the motion q' = H(q)u, u' = a (any a), t' = 1, the
    // central difference of Ċ(q, u, t) = P u + C_t over ±h must equal P a + γ. Tolerance as
    // above (second-order differences of smooth functions, h = 1e-5).
    let t = 0.21;
    let (q, u) = (&y[..lay.n], &y[lay.u()..lay.u() + lay.n]);
    let mut seed = 11;
    let a: Vec<f64> = (0..lay.n).map(|_| rng(&mut seed)).collect();
    let cdot = |q: &[f64], u: &[f64], t: f64| -> Vec<f64> {
        let mut out = vec![0.0; sys.m];
        for el in &sys.constraints {
            let f = constraint_first(&sys, el, q, t, &[]);
            let nql = nql(&sys, &el.bodies);
            for e in 0..el.neq {
                let p = p_row(&el.bodies, q, &f.cq[e * nql..(e + 1) * nql]);
                let ul = gather(&sys, &el.bodies, u);
                out[el.row + e] = p.iter().zip(&ul).map(|(x, y)| x * y).sum::<f64>() + f.ct[e];
            }
        }
        out
    };
    let qd = rates(sys.nb(), q, u);
    let h = 1e-5;
    let shift = |s: f64| -> (Vec<f64>, Vec<f64>) {
        // Second-order accurate point on the trajectory: q(t+s) ≈ q + s q' + s²/2 q''; the
        // s² term cancels in the central difference of Ċ's first derivative, so q + s q' and
        // u + s a suffice.
        ((0..lay.n).map(|i| q[i] + s * qd[i]).collect(), (0..lay.n).map(|i| u[i] + s * a[i]).collect())
    };
    let (qp, up) = shift(h);
    let (qm, um) = shift(-h);
    let (cp, cm) = (cdot(&qp, &up, t + h), cdot(&qm, &um, t - h));
    let gamma = acceleration_rhs(&sys, q, u, t, &[]);
    for el in &sys.constraints {
        let f = constraint_first(&sys, el, q, t, &[]);
        let nql = nql(&sys, &el.bodies);
        for e in 0..el.neq {
            let r = el.row + e;
            let p = p_row(&el.bodies, q, &f.cq[e * nql..(e + 1) * nql]);
            let al = gather(&sys, &el.bodies, &a);
            let want = p.iter().zip(&al).map(|(x, y)| x * y).sum::<f64>() + gamma[r];
            let fd = (cp[r] - cm[r]) / (2.0 * h);
            assert!((fd - want).abs() < 1e-6 * want.abs().max(1.0), "{} eq {e}: fd {fd} vs {want}", el.name);
        }
    }
}

#[test]
fn nonholonomic_acceleration_right_hand_side_is_the_time_derivative_of_g() {
    nonholonomic_gamma_is_the_time_derivative_of_g(setup(), 6);
}

/// The same with a 50-mode flexible body (chunked mixed second derivatives).
#[test]
fn nonholonomic_right_hand_side_with_a_fifty_mode_body_is_the_time_derivative_of_g() {
    nonholonomic_gamma_is_the_time_derivative_of_g(setup_flexible("nonholonomic"), 4);
}

fn nonholonomic_gamma_is_the_time_derivative_of_g((sys, lay, y): (System, Layout, Vec<f64>), mn: usize) {
    // ġ = B u̇ + γ_nh along q' = H(q)u, u' = a, t' = 1: central differences of g over ±h
    // against B a + γ_nh (h = 1e-5, tolerance as above).
    use mbfmu::mechanics::nonholonomic_jacobian::{nonholonomic_b, nonholonomic_gamma};
    assert_eq!(sys.mn, mn);
    let t = 0.43;
    let (q, u) = (&y[..lay.n], &y[lay.u()..lay.u() + lay.n]);
    let ext = lay.ext(&sys, &INPUTS, &y, t);
    let mut seed = 5;
    let a: Vec<f64> = (0..lay.n).map(|_| rng(&mut seed)).collect();
    let qd = rates(sys.nb(), q, u);
    let h = 1e-5;
    let at = |s: f64| -> Vec<f64> {
        let qs: Vec<f64> = (0..lay.n).map(|i| q[i] + s * qd[i]).collect();
        let us: Vec<f64> = (0..lay.n).map(|i| u[i] + s * a[i]).collect();
        nonholonomic_b(&sys, &qs, &us, t + s, &ext).1
    };
    let (gp, gm) = (at(h), at(-h));
    let (b, _) = nonholonomic_b(&sys, q, u, t, &ext);
    let mut want = nonholonomic_gamma(&sys, q, u, t, &ext);
    for (r, c, v) in b {
        want[r] += v * a[c];
    }
    for r in 0..sys.mn {
        let fd = (gp[r] - gm[r]) / (2.0 * h);
        assert!((fd - want[r]).abs() < 1e-6 * want[r].abs().max(1.0), "row {r}: fd {fd} vs {}", want[r]);
    }
}
