//! The engine's exact derivatives against central finite differences (tests only; the
//! engine itself never differentiates numerically). The model deliberately mixes every
//! joint type, motions, a user constraint and every force element on three bodies in
//! general orientations; it need not be assemblable, since derivatives are checked at
//! arbitrary states.

use mbfmu::dae::equations::{Layout, jacobian, rhs};
use mbfmu::dae::sparse::Triplets;
use mbfmu::mechanics::System;
use mbfmu::mechanics::body::{NQ, qdot};
use mbfmu::mechanics::constraint_jacobian::{acceleration_rhs, p_row};
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

fn setup() -> (System, Layout, Vec<f64>) {
    let model = load_str(KITCHEN_SINK, "sink.xml").unwrap_or_else(|e| panic!("{e}"));
    let sys = System::from_model(&model).unwrap();
    let lay = Layout::of(&sys);
    assert_eq!((lay.nx, lay.nv, lay.na), (2, 4, 18));
    assert_eq!(sys.load_refs.len(), 5);
    let mut seed = 7;
    let mut y = vec![0.0; lay.dim()];
    for i in 0..lay.n {
        y[i] = sys.q_init[i] + 0.1 * rng(&mut seed);
        y[lay.u() + i] = sys.u_init[i] + rng(&mut seed);
    }
    for i in 0..lay.nz() {
        y[lay.z() + i] = rng(&mut seed);
    }
    for i in 0..lay.m + lay.mn {
        y[lay.lam() + i] = 3.0 * rng(&mut seed); // λ then ν
    }
    (sys, lay, y)
}

#[test]
fn jacobian_of_the_equations_of_motion_matches_central_differences() {
    // J = ∂f/∂y is exact except the term ∂(C_qᵀμ)/∂q, which vanishes on the solution (μ = 0),
    // so μ = 0 here. Central differences with h = 1e-6 have truncation error ~h²·|f'''| ≈ 1e-12
    // and round-off ~ε|f|/h ≈ 1e-9 relative: agreement to 1e-6 (relative to max(1, |J|))
    // leaves margin while catching any wrong term (errors of O(1)).
    let (sys, lay, y) = setup();
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
        let (mut yp, mut ym) = (y.clone(), y.clone());
        yp[c] += h;
        ym[c] -= h;
        let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
        rhs(&sys, lay, t, &yp, &INPUTS, &mut fp);
        rhs(&sys, lay, t, &ym, &INPUTS, &mut fm);
        for r in 0..n {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let e = (fd - jd[r * n + c]).abs() / jd[r * n + c].abs().max(1.0);
            if e > worst.0 {
                worst = (e, r, c);
            }
        }
    }
    assert!(worst.0 < 1e-6, "worst relative error {:e} at row {} col {}", worst.0, worst.1, worst.2);
}

#[test]
fn acceleration_right_hand_side_is_the_second_time_derivative_of_the_constraints() {
    // C̈ = P u̇ + γ (Eq. 1c). Along the motion q' = H(q)u, u' = a (any a), t' = 1, the
    // central difference of Ċ(q, u, t) = P u + C_t over ±h must equal P a + γ. Tolerance as
    // above (second-order differences of smooth functions, h = 1e-5).
    let (sys, lay, y) = setup();
    let t = 0.21;
    let (q, u) = (&y[..lay.n], &y[lay.u()..lay.u() + lay.n]);
    let mut seed = 11;
    let a: Vec<f64> = (0..lay.n).map(|_| rng(&mut seed)).collect();
    let cdot = |q: &[f64], u: &[f64], t: f64| -> Vec<f64> {
        let mut out = vec![0.0; sys.m];
        for el in &sys.constraints {
            let f = constraint_first(&sys, el, q, t, &[]);
            let nql = NQ * el.bodies.len();
            for e in 0..el.neq {
                let p = p_row(&el.bodies, q, &f.cq[e * nql..(e + 1) * nql]);
                let ul: Vec<f64> = el.bodies.iter().flat_map(|&b| u[NQ * b..NQ * b + NQ].to_vec()).collect();
                out[el.row + e] = p.iter().zip(&ul).map(|(x, y)| x * y).sum::<f64>() + f.ct[e];
            }
        }
        out
    };
    let qd: Vec<f64> = (0..sys.nb()).flat_map(|b| qdot(&q[NQ * b..NQ * b + NQ], &u[NQ * b..NQ * b + NQ])).collect();
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
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            let r = el.row + e;
            let p = p_row(&el.bodies, q, &f.cq[e * nql..(e + 1) * nql]);
            let al: Vec<f64> = el.bodies.iter().flat_map(|&b| a[NQ * b..NQ * b + NQ].to_vec()).collect();
            let want = p.iter().zip(&al).map(|(x, y)| x * y).sum::<f64>() + gamma[r];
            let fd = (cp[r] - cm[r]) / (2.0 * h);
            assert!((fd - want).abs() < 1e-6 * want.abs().max(1.0), "{} eq {e}: fd {fd} vs {want}", el.name);
        }
    }
}

#[test]
fn nonholonomic_acceleration_right_hand_side_is_the_time_derivative_of_g() {
    // ġ = B u̇ + γ_nh along q' = H(q)u, u' = a, t' = 1: central differences of g over ±h
    // against B a + γ_nh (h = 1e-5, tolerance as above).
    use mbfmu::mechanics::nonholonomic_jacobian::{nonholonomic_b, nonholonomic_gamma};
    let (sys, lay, y) = setup();
    assert_eq!(sys.mn, 6);
    let t = 0.43;
    let (q, u) = (&y[..lay.n], &y[lay.u()..lay.u() + lay.n]);
    let ext = lay.ext(&sys, &INPUTS, &y, t);
    let mut seed = 5;
    let a: Vec<f64> = (0..lay.n).map(|_| rng(&mut seed)).collect();
    let qd: Vec<f64> = (0..sys.nb()).flat_map(|b| qdot(&q[NQ * b..NQ * b + NQ], &u[NQ * b..NQ * b + NQ])).collect();
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
