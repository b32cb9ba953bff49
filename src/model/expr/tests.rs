//! Parser and evaluator tests: syntax and error messages, hand-computed values of the
//! kinematic measures, and exact (dual-number) derivatives of every function checked
//! against central finite differences.

use super::*;
use crate::ad::{Dual, Real};
use crate::geom::{M3, V3, rot_x, rot_z, rot313};
use std::cell::RefCell;

// ---------------------------------------------------------------------------------------
// Mock scope
// ---------------------------------------------------------------------------------------

/// Names: params p0 p1, inputs u0 u1, variable v0, differentials x0 x1; markers a (bare
/// body), b.m, c.k, ground.O; elements j1 (joint), s0 (sforce), g2 (gforce); flexible body
/// flex (cm marker 5, three modes).
struct MockScope;

impl Scope for MockScope {
    fn name(&self, name: &str) -> Option<NameRef> {
        Some(match name {
            "p0" => NameRef::Param(0),
            "p1" => NameRef::Param(1),
            "u0" => NameRef::Input(0),
            "u1" => NameRef::Input(1),
            "v0" => NameRef::Variable(0),
            "x0" => NameRef::Diff(0),
            "x1" => NameRef::Diff(1),
            _ => return None,
        })
    }
    fn marker(&self, name: &str) -> Option<MarkerId> {
        Some(match name {
            "a" => 0,
            "b.m" => 1,
            "c.k" => 2,
            "ground.O" => 3,
            _ => return None,
        })
    }
    fn element(&self, name: &str) -> Option<ElementRef> {
        Some(match name {
            "j1" => ElementRef::Joint(1),
            "s0" => ElementRef::Sforce(0),
            "g2" => ElementRef::Gforce(2),
            _ => return None,
        })
    }
    fn flexible(&self, name: &str) -> Option<(MarkerId, usize)> {
        (name == "flex").then_some((5, 3))
    }
}

fn p(src: &str) -> Expr {
    match parse(src, &MockScope) {
        Ok(e) => e,
        Err(e) => panic!("parse of {src:?} failed at {}: {}", e.offset, e.msg),
    }
}

// ---------------------------------------------------------------------------------------
// Mock environment: everything a smooth function of a vector z
// ---------------------------------------------------------------------------------------

/// Layout of z: markers 0..3 take 18 entries each (position, 3-1-3 angles, velocity,
/// angular velocity, acceleration, angular acceleration); then time, inputs u0 u1,
/// params p0 p1, variable v0, differential x0 x1, and dif1(x0) dif1(x1).
const NZ: usize = 3 * 18 + 10;
const T_TIME: usize = 54;
const T_INPUT: usize = 55;
const T_PARAM: usize = 57;
const T_VAR: usize = 59;
const T_DIFF: usize = 60;
const T_DDOT: usize = 62;

struct ZEnv<T: Real> {
    z: Vec<T>,
    /// Angle slots seen by `unwrap_angle`.
    slots: RefCell<Vec<usize>>,
}

impl<T: Real> ZEnv<T> {
    fn new(z: Vec<T>) -> Self {
        ZEnv { z, slots: RefCell::new(Vec::new()) }
    }
    fn v3(&self, at: usize) -> V3<T> {
        V3([self.z[at], self.z[at + 1], self.z[at + 2]])
    }
}

/// The fixed ground marker `ground.O` (id 3): offset and rotated, at rest.
fn ground_o<T: Real>() -> Pose<T> {
    Pose { p: V3::cst([0.5, -0.2, 0.1]), r: rot313(T::cst(0.4), T::cst(0.9), T::cst(-1.2)) }
}

impl<T: Real> ExprEnv<T> for ZEnv<T> {
    fn time(&self) -> T {
        self.z[T_TIME]
    }
    fn param(&self, i: usize) -> T {
        self.z[T_PARAM + i]
    }
    fn input(&self, i: usize) -> T {
        self.z[T_INPUT + i]
    }
    fn variable(&self, i: usize) -> T {
        self.z[T_VAR + i]
    }
    fn diff(&self, i: usize) -> T {
        self.z[T_DIFF + i]
    }
    fn diff_dot(&self, i: usize) -> T {
        self.z[T_DDOT + i]
    }
    fn pose(&self, m: MarkerId) -> Pose<T> {
        if m == 3 {
            return ground_o();
        }
        let b = 18 * m;
        Pose { p: self.v3(b), r: rot313(self.z[b + 3], self.z[b + 4], self.z[b + 5]) }
    }
    fn twist(&self, m: MarkerId) -> Twist<T> {
        if m == 3 {
            return Twist { v: V3::zero(), w: V3::zero() };
        }
        let b = 18 * m;
        Twist { v: self.v3(b + 6), w: self.v3(b + 9) }
    }
    fn accel(&self, m: MarkerId) -> Twist<T> {
        if m == 3 {
            return Twist { v: V3::zero(), w: V3::zero() };
        }
        let b = 18 * m;
        Twist { v: self.v3(b + 12), w: self.v3(b + 15) }
    }
    fn load(&self, f: LoadFn, e: ElementRef) -> T {
        let (code, k) = match e {
            ElementRef::Joint(i) => (1, i),
            ElementRef::Sforce(i) => (2, i),
            ElementRef::Gforce(i) => (3, i),
            _ => (4, 0),
        };
        let c = code * 7 + k * 3 + f as usize * 5;
        // Reads positions, velocities, time and an input: like a real constraint force.
        self.z[c % 54] * self.z[(c + 11) % 54].cos() + self.z[T_TIME].scale(0.1 * code as f64) + self.z[T_INPUT]
    }
    fn unwrap_angle(&self, slot: usize, a: T) -> T {
        self.slots.borrow_mut().push(slot);
        a
    }
}

/// A tiny linear congruential generator (Knuth's MMIX constants), uniform in [lo, hi).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A random point: positions, rates and accelerations in [-2, 2], angles in [-π, π],
/// time in [0, 3], params in [0.5, 2] (they appear as bases of powers), rest in [-1, 1].
fn random_z(rng: &mut Lcg) -> Vec<f64> {
    let mut z = vec![0.0; NZ];
    for m in 0..3 {
        for c in 0..18 {
            let angle = (3..6).contains(&c);
            z[18 * m + c] = if angle { rng.uniform(-3.1, 3.1) } else { rng.uniform(-2.0, 2.0) };
        }
    }
    z[T_TIME] = rng.uniform(0.0, 3.0);
    for x in &mut z[T_INPUT..] {
        *x = rng.uniform(-1.0, 1.0);
    }
    z[T_PARAM] = rng.uniform(0.5, 2.0);
    z[T_PARAM + 1] = rng.uniform(0.5, 2.0);
    z
}

fn eval_f64(e: &Expr, z: &[f64]) -> f64 {
    eval(e, &ZEnv::new(z.to_vec()))
}

/// Check every partial derivative of `src` (dual numbers seeded on all of z) against a
/// central finite difference of the `f64` evaluation, at `points` random points.
///
/// Tolerance: with h = 1e-6·max(1, |z_k|) the central difference has truncation error
/// |f'''|h²/6 ≈ 1e-12 (relative, for the O(1) third derivatives these test functions
/// have) and roundoff ≈ ε|f|/h ≈ 2e-16/1e-6 = 2e-10 (relative to |f|); 1e-6 of
/// max(1, |f|, |f'|) leaves four orders of margin while still catching any wrong term
/// (a missing chain-rule factor is an O(1) error).
fn check_derivatives(src: &str, seed: u64, points: usize) {
    type D = Dual<f64, NZ>;
    let e = p(src);
    let mut rng = Lcg(seed);
    for pt in 0..points {
        let z = random_z(&mut rng);
        let zd: Vec<D> = z.iter().enumerate().map(|(k, &v)| D::var(v, k)).collect();
        let dual = eval(&e, &ZEnv::new(zd));
        let f = eval_f64(&e, &z);
        assert!(f.is_finite(), "{src}: value {f} at point {pt}");
        assert!((dual.v - f).abs() <= 1e-14 * f.abs().max(1.0), "{src}: dual value {} vs {f}", dual.v);
        for k in 0..NZ {
            let h = 1e-6 * z[k].abs().max(1.0);
            let (mut zp, mut zm) = (z.clone(), z.clone());
            zp[k] += h;
            zm[k] -= h;
            let fd = (eval_f64(&e, &zp) - eval_f64(&e, &zm)) / (2.0 * h);
            let tol = 1e-6 * f.abs().max(dual.d[k].abs()).max(1.0);
            assert!(
                (dual.d[k] - fd).abs() <= tol,
                "{src}: d/dz[{k}] = {} but finite difference {fd} (point {pt}, z = {z:?})",
                dual.d[k]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Derivatives
// ---------------------------------------------------------------------------------------

const POINTS: usize = 6;

#[test]
fn math_functions_have_exact_derivatives() {
    // Each function applied to something that depends on several entries of z, with
    // arguments kept inside the function's domain.
    let cases = [
        "sin(dx(a) * u0 + time)",
        "cos(dy(b.m) - p0 * vz(c.k))",
        "tan(0.4 * sin(dz(a, b.m)))",
        "asin(0.8 * sin(dx(a, c.k)))",
        "acos(0.8 * cos(p1 * time + dy(a)))",
        "atan(dx(a) * p1 + wx(b.m))",
        "atan2(dy(a, b.m), dx(c.k) + 0.1 * u1)",
        "sinh(0.5 * vx(a))",
        "cosh(0.5 * vy(b.m, a))",
        "tanh(dz(c.k) * u0)",
        "exp(0.3 * dm(a, b.m))",
        "log(1 + dm(a, c.k)^2)",
        "sqrt(1 + vm(a)^2 + dif(x0)^2)",
        "abs(dx(a, b.m)) * p0",
        "sign(dx(a)) * wy(a) + sign(0) + sign(-dy(c.k))",
        "min(dx(a), dy(b.m) * u1)",
        "max(dx(a), dy(b.m) * u1)",
        "step(dx(a), -0.5, p0, 0.7, u1)",
        "step(time, p0 - 1, dy(a), p1 + 1, u0 * dz(b.m))",
        "step(time, 3.5, dy(a), 4, u0) + step(time, -2, dy(a), -1, u0 * wx(a))",
        "if(dx(a), vy(b.m), dif(x0))",
        "if(-dx(a), vy(b.m), dif1(x1))",
        "if(time - 1.5, 2 * time, time^2)",
    ];
    for (n, src) in cases.iter().enumerate() {
        check_derivatives(src, 1000 + n as u64, POINTS);
    }
}

#[test]
fn operators_and_leaves_have_exact_derivatives() {
    let cases = [
        "dx(a) + dy(b.m) - dz(c.k) * u0 / (2 + sin(time))",
        "-dx(a)^2 + +dy(a)",
        "dx(a)^3 - dy(b.m)^2 + (2 + dz(c.k)^2)^-1 + (-dz(a))^3",
        "p0^u0 + 2^time + p1^dx(a) + (1 + dm(a))^(0.5 * u1)",
        "dx(a)^0 + dx(a)^1",
        "pi * time + u0 * u1 + p0 / p1 + v0 + x0 + dif(x1) + dif1(x0) * dif1(x1)",
        "fx(j1) + fy(j1) * fz(s0) - tx(g2) + ty(s0) * time - tz(j1)",
    ];
    for (n, src) in cases.iter().enumerate() {
        check_derivatives(src, 2000 + n as u64, POINTS);
    }
}

#[test]
fn every_kinematic_measure_has_exact_derivatives_with_1_2_and_3_markers() {
    let markers = ["a", "b.m", "c.k"];
    let mut checked = 0;
    for (n, name) in function_names().iter().enumerate() {
        let Ok(Expr::Kin(f, ..)) =
            parse(&format!("{name}(a, b.m)"), &MockScope).or_else(|_| parse(&format!("{name}(a)"), &MockScope))
        else {
            continue;
        };
        let (lo, hi) = f.arity();
        for count in lo..=hi {
            let src = format!("{name}({})", markers[..count].join(", "));
            check_derivatives(&src, 3000 + 10 * n as u64 + count as u64, POINTS);
            // The same measure against the (constant) ground marker and in its frame.
            let mut with_ground = markers[..count].to_vec();
            with_ground[count - 1] = if count == 1 { "c.k" } else { "ground.O" };
            let src = format!("{name}({})", with_ground.join(", "));
            check_derivatives(&src, 5000 + 10 * n as u64 + count as u64, POINTS);
            checked += 1;
        }
    }
    // 28 measures: 15 with 1-3 markers, 12 with 1-2, vr with exactly 2.
    assert_eq!(checked, 15 * 3 + 12 * 2 + 1);
}

#[test]
fn second_derivatives_through_nested_duals() {
    // d²/dz0² of dx(a)^2 * u0 = 2 u0; d²/(dz0 du0) = 2 dx(a).
    type D1 = Dual<f64, 2>;
    type D2 = Dual<D1, 2>;
    let e = p("dx(a)^2 * u0");
    let z = random_z(&mut Lcg(7));
    let mut zd: Vec<D2> = z.iter().map(|&v| D2::cst(v)).collect();
    zd[0] = D2 { v: D1::var(z[0], 0), d: [D1::one(), D1::zero()] };
    zd[T_INPUT] = D2 { v: D1::var(z[T_INPUT], 1), d: [D1::zero(), D1::one()] };
    let r = eval(&e, &ZEnv::new(zd));
    assert!((r.d[0].d[0] - 2.0 * z[T_INPUT]).abs() < 1e-14);
    assert!((r.d[0].d[1] - 2.0 * z[0]).abs() < 1e-14);
}

// ---------------------------------------------------------------------------------------
// Values against hand-computed numbers
// ---------------------------------------------------------------------------------------

/// Explicit poses, twists and accelerations for markers a, b.m, c.k, ground.O.
struct FixedEnv {
    pose: Vec<Pose<f64>>,
    twist: Vec<Twist<f64>>,
    accel: Vec<Twist<f64>>,
    /// Added to each unwrapped angle: `offset · (slot + 1)`.
    unwrap_offset: f64,
}

impl FixedEnv {
    fn new() -> Self {
        let pose = Pose { p: V3::zero(), r: M3::identity() };
        let rest = Twist { v: V3::zero(), w: V3::zero() };
        FixedEnv { pose: vec![pose; 4], twist: vec![rest; 4], accel: vec![rest; 4], unwrap_offset: 0.0 }
    }
    fn val(&self, src: &str) -> f64 {
        eval(&p(src), self)
    }
}

impl ExprEnv<f64> for FixedEnv {
    fn time(&self) -> f64 {
        2.5
    }
    fn param(&self, i: usize) -> f64 {
        [3.0, -1.5][i]
    }
    fn input(&self, i: usize) -> f64 {
        [0.25, 4.0][i]
    }
    fn variable(&self, _: usize) -> f64 {
        7.0
    }
    fn diff(&self, i: usize) -> f64 {
        10.0 + i as f64
    }
    fn diff_dot(&self, i: usize) -> f64 {
        20.0 + i as f64
    }
    fn pose(&self, m: MarkerId) -> Pose<f64> {
        self.pose[m]
    }
    fn twist(&self, m: MarkerId) -> Twist<f64> {
        self.twist[m]
    }
    fn accel(&self, m: MarkerId) -> Twist<f64> {
        self.accel[m]
    }
    fn load(&self, f: LoadFn, e: ElementRef) -> f64 {
        let k = match e {
            ElementRef::Joint(i) => 100 + i,
            ElementRef::Sforce(i) => 200 + i,
            _ => 300,
        };
        k as f64 + f as usize as f64 / 10.0
    }
    fn unwrap_angle(&self, slot: usize, a: f64) -> f64 {
        a + self.unwrap_offset * (slot + 1) as f64
    }
}

fn rot_y(b: f64) -> M3<f64> {
    let (s, c) = b.sin_cos();
    M3([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn planar_angles_recover_single_axis_rotations() {
    let mut env = FixedEnv::new();
    env.pose[0].r = rot_z(0.3);
    assert!(close(env.val("az(a)"), 0.3));
    assert!(close(env.val("ax(a)"), 0.0) && close(env.val("ay(a)"), 0.0));
    env.pose[0].r = rot_x(0.4);
    assert!(close(env.val("ax(a)"), 0.4));
    env.pose[0].r = rot_y(-0.7);
    assert!(close(env.val("ay(a)"), -0.7));
    // Relative to a marker itself rotated about z: angles subtract.
    env.pose[0].r = rot_z(2.0);
    env.pose[1].r = rot_z(0.5);
    assert!(close(env.val("az(a, b.m)"), 1.5));
    assert!(close(env.val("az(b.m, a)"), -1.5));
}

#[test]
fn euler_and_yaw_pitch_roll_recover_the_angles_they_were_built_from() {
    let mut env = FixedEnv::new();
    env.pose[1].r = rot_z(0.5).mm(&rot_x(-0.2));
    env.pose[0].r = env.pose[1].r.mm(&rot313(0.3, 1.1, -2.0));
    assert!(close(env.val("psi(a, b.m)"), 0.3));
    assert!(close(env.val("theta(a, b.m)"), 1.1));
    assert!(close(env.val("phi(a, b.m)"), -2.0));
    env.pose[0].r = rot313(-1.0, 2.5, 3.0);
    assert!(close(env.val("psi(a)"), -1.0) && close(env.val("theta(a)"), 2.5) && close(env.val("phi(a)"), 3.0));
    // R = Rz(yaw) Ry(pitch) Rx(roll)
    env.pose[0].r = env.pose[1].r.mm(&rot_z(0.2).mm(&rot_y(-0.4)).mm(&rot_x(1.0)));
    assert!(close(env.val("yaw(a, b.m)"), 0.2));
    assert!(close(env.val("pitch(a, b.m)"), -0.4));
    assert!(close(env.val("roll(a, b.m)"), 1.0));
}

#[test]
fn displacements_and_distance_in_the_frame_of_k() {
    let mut env = FixedEnv::new();
    env.pose[0].p = V3([3.0, 4.0, 0.0]);
    env.pose[1].p = V3([3.0, 0.0, 0.0]);
    // k's x axis is ground y, its y axis is ground −x.
    env.pose[2].r = rot_z(std::f64::consts::FRAC_PI_2);
    assert!(close(env.val("dm(a)"), 5.0));
    assert!(close(env.val("dm(a, b.m)"), 4.0));
    assert!(close(env.val("dx(a)"), 3.0) && close(env.val("dy(a)"), 4.0) && close(env.val("dz(a)"), 0.0));
    assert!(close(env.val("dx(a, b.m, c.k)"), 4.0));
    assert!(close(env.val("dy(a, b.m, c.k)"), 0.0));
    assert!(close(env.val("dx(a, ground.O)"), 3.0));
}

#[test]
fn velocities_radial_velocity_and_angular_rates() {
    let mut env = FixedEnv::new();
    env.pose[0].p = V3([3.0, 4.0, 0.0]);
    env.twist[0] = Twist { v: V3([1.0, 0.0, 0.0]), w: V3([0.0, 0.0, 2.0]) };
    env.twist[1] = Twist { v: V3([0.0, -1.0, 0.0]), w: V3([0.0, 0.0, 0.5]) };
    // k = rot_x(π/2): x_k = X, y_k = Z, z_k = −Y.
    env.pose[2].r = rot_x(std::f64::consts::FRAC_PI_2);
    assert!(close(env.val("vm(a)"), 1.0));
    assert!(close(env.val("vr(a, ground.O)"), 0.6)); // (1,0,0)·(3,4,0)/5
    assert!(close(env.val("vr(a, b.m)"), (3.0 + 4.0) / 5.0)); // (1,1,0)·(3,4,0)/5
    assert!(close(env.val("vx(a, b.m)"), 1.0) && close(env.val("vy(a, b.m)"), 1.0));
    assert!(close(env.val("vz(a, b.m, c.k)"), -1.0));
    assert!(close(env.val("wz(a, b.m)"), 1.5) && close(env.val("wm(a, b.m)"), 1.5));
    assert!(close(env.val("wy(a, b.m, c.k)"), 1.5) && close(env.val("wz(a, b.m, c.k)"), 0.0));
}

#[test]
fn accelerations_subtract_and_resolve_in_k() {
    let mut env = FixedEnv::new();
    env.accel[0] = Twist { v: V3([1.0, 2.0, 3.0]), w: V3([-1.0, 0.5, 4.0]) };
    env.accel[1] = Twist { v: V3([0.5, 0.5, 0.5]), w: V3([1.0, 1.0, 1.0]) };
    env.pose[2].r = rot_z(std::f64::consts::FRAC_PI_2);
    assert!(close(env.val("accx(a)"), 1.0) && close(env.val("accy(a)"), 2.0) && close(env.val("accz(a)"), 3.0));
    assert!(close(env.val("accx(a, b.m, c.k)"), 1.5) && close(env.val("accy(a, b.m, c.k)"), -0.5));
    assert!(close(env.val("wdtx(a, b.m)"), -2.0) && close(env.val("wdtz(a, b.m)"), 3.0));
    assert!(close(env.val("wdty(a, b.m, c.k)"), 2.0));
}

#[test]
fn math_values() {
    let env = FixedEnv::new();
    let cases: &[(&str, f64)] = &[
        ("sign(-3) + sign(0) + sign(2)", 0.0),
        ("abs(-2.5)", 2.5),
        ("min(2, -1) + max(2, -1)", 1.0),
        ("step(-1, 0, 1, 1, 3) + step(2, 0, 1, 1, 3)", 4.0),
        ("step(0.5, 0, 1, 1, 3)", 2.0),
        ("step(0.25, 0, 0, 1, 1)", 0.25 * 0.25 * 2.5),
        ("if(1, 2, 3) + if(0, 20, 30) + if(-1, 200, 300)", 332.0),
        ("log(exp(2))", 2.0),
        ("atan2(1, -1)", 0.75 * std::f64::consts::PI),
        ("(-2)^3 + (-2)^2", -4.0),
        ("sqrt(16) + 8^(1/3)", 6.0),
        ("time * p0 + p1 + u0 + u1 + v0 + x0 + dif(x1) + dif1(x0)", 7.5 - 1.5 + 4.25 + 7.0 + 21.0 + 20.0),
        ("fx(j1) + tz(s0)", 101.0 + 200.5),
    ];
    for &(src, v) in cases {
        assert!(close(env.val(src), v), "{src} = {} expected {v}", env.val(src));
    }
    assert_eq!(env.val("1/0"), f64::INFINITY);
    assert!(env.val("sqrt(-1)").is_nan() && env.val("log(-1)").is_nan());
}

#[test]
fn angle_slots_number_angle_measures_in_order_regardless_of_branch() {
    let mut env = FixedEnv::new();
    env.pose[0].r = rot_z(0.3);
    env.unwrap_offset = 10.0;
    // Slots 0, 1, 2, 3 get +10, +20, +30, +40; the branch `if` skips still takes slot 1.
    let e = p("az(a) + if(-1, ax(a), 100 * ay(b.m)) * 0 + dx(a) + theta(a)");
    assert_eq!(angle_count(&e), 4);
    assert!(close(eval(&e, &env), 0.3 + 10.0 + 0.0 + 40.0));
    let z = random_z(&mut Lcg(3));
    let zenv = ZEnv::new(z);
    let _ = eval(&p("yaw(a) + psi(b.m, c.k) - dm(a) + roll(c.k)"), &zenv);
    assert_eq!(*zenv.slots.borrow(), vec![0, 1, 2]);
}

// ---------------------------------------------------------------------------------------
// Parser
// ---------------------------------------------------------------------------------------

#[test]
fn precedence_and_associativity() {
    let env = FixedEnv::new();
    let cases: &[(&str, f64)] = &[
        ("2+3*4^2", 50.0),
        ("-2^2", -4.0),
        ("2^3^2", 512.0),
        ("2^-1", 0.5),
        ("(2+3)*4", 20.0),
        ("10-4-3", 3.0),
        ("12/3/2", 2.0),
        ("+-+2", -2.0),
        ("2*-3", -6.0),
        ("-(1+2)^2", -9.0),
        ("1e-3*1000 + .5*4 + 2.", 5.0),
        ("1.5E+2", 150.0),
        ("pi", std::f64::consts::PI),
        ("  sin ( pi / 2 )\t", 1.0),
    ];
    for &(src, v) in cases {
        assert!(close(env.val(src), v), "{src} = {} expected {v}", env.val(src));
    }
}

#[test]
fn names_resolve_to_the_right_nodes() {
    assert_eq!(p("x0"), Expr::Diff(0));
    assert_eq!(p("dif(x1)"), Expr::Diff(1));
    assert_eq!(p("dif1(x0)"), Expr::DiffDot(0));
    assert_eq!(p("p1"), Expr::Param(1));
    assert_eq!(p("u0"), Expr::Input(0));
    assert_eq!(p("v0"), Expr::Variable(0));
    assert_eq!(p("time"), Expr::Time);
    assert_eq!(p("-2"), Expr::Num(-2.0));
    assert_eq!(p("-u0"), Expr::Neg(Box::new(Expr::Input(0))));
    assert_eq!(p("dx(a)"), Expr::Kin(KinFn::Dx, 0, None, None));
    assert_eq!(p("wdtz(a, ground.O, c.k)"), Expr::Kin(KinFn::Wdtz, 0, Some(3), Some(2)));
    assert_eq!(p("vr(b.m, a)"), Expr::Kin(KinFn::Vr, 1, Some(0), None));
    assert_eq!(p("ty(s0)"), Expr::Load(LoadFn::Ty, ElementRef::Sforce(0)));
    assert_eq!(p("atan2(1, u1)"), Expr::Math(MathFn::Atan2, vec![Expr::Num(1.0), Expr::Input(1)]));
    let d = deps(&p("vx(a, b.m) * fx(j1) + time"));
    assert_eq!((d.markers, d.level, d.time), (vec![0, 1], 1, true));
}

#[test]
fn function_names_lists_every_function_and_each_parses() {
    let names = function_names();
    assert_eq!(names.len(), 19 + 28 + 6 + 2 + 2);
    for n in names {
        // Every listed name is recognised as a function (an arity error, not "unknown").
        let e = parse(&format!("{n}()"), &MockScope).unwrap_err();
        assert!(e.msg.starts_with(&format!("'{n}' takes ")), "{n}: {}", e.msg);
    }
    assert!(!names.contains(&"pi") && keywords().contains(&"time"));
}

fn parse_err(src: &str) -> (usize, String) {
    match parse(src, &MockScope) {
        Ok(e) => panic!("{src:?} parsed as {e:?}"),
        Err(e) => (e.offset, e.msg),
    }
}

#[test]
fn errors_name_the_problem_and_its_character_offset() {
    let cases: &[(&str, usize, &str)] = &[
        ("foo(1)", 0, "unknown function 'foo'"),
        ("1 + x", 4, "unknown name 'x'"),
        ("dx(a, b.z)", 6, "unknown marker 'b.z'"),
        ("fx(j9)", 3, "unknown element 'j9'"),
        ("atan2(1, 2, 3)", 0, "'atan2' takes 2 arguments, got 3"),
        ("2 * dx()", 4, "'dx' takes 1 to 3 arguments, got 0"),
        ("dx(a, a, a, a)", 0, "'dx' takes 1 to 3 arguments, got 4"),
        ("dm(a, b.m, c.k)", 0, "'dm' takes 1 to 2 arguments, got 3"),
        ("vr(a)", 0, "'vr' takes 2 arguments, got 1"),
        ("sin(1, 2)", 0, "'sin' takes 1 argument, got 2"),
        ("step(1, 2)", 0, "'step' takes 5 arguments, got 2"),
        ("dif(x0, x1)", 0, "'dif' takes 1 argument, got 2"),
        ("(1 + 2))", 7, "unexpected ')'"),
        ("sin(1, )", 7, "unexpected ')'"),
        ("1 +", 3, "unexpected end of expression"),
        ("", 0, "unexpected end of expression"),
        ("sin(2", 5, "unexpected end of expression"),
        ("3 * 1e", 4, "bad number '1e'"),
        ("1.2.3", 0, "bad number '1.2.3'"),
        ("2x", 0, "bad number '2x'"),
        ("dif(p0)", 4, "'p0' is not a differential"),
        ("dif1(q)", 5, "unknown name 'q'"),
        ("2 * sin", 4, "function 'sin' needs arguments"),
        ("1 # 2", 2, "unexpected character '#'"),
        ("é", 0, "unexpected character 'é'"),
        ("ü + q", 0, "unexpected character 'ü'"),
        ("ü + q(", 0, "unexpected character 'ü'"),
        ("ππ + x", 0, "unexpected character 'π'"),
        ("dx(1)", 3, "unexpected number, expected a name"),
        ("dx(a b.m)", 5, "unexpected 'b.m', expected ',' or ')'"),
        ("(1 2)", 3, "unexpected number, expected ')'"),
        ("1 2", 2, "unexpected number"),
        ("u0 u1", 3, "unexpected 'u1'"),
    ];
    for &(src, off, msg) in cases {
        assert_eq!(parse_err(src), (off, msg.to_string()), "{src:?}");
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let deep = format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000));
    assert_eq!(parse_err(&deep).1, "expression too deeply nested");
    assert_eq!(parse_err(&"-".repeat(100_000)).1, "expression too deeply nested");
    assert_eq!(parse_err(&"2^".repeat(100_000)).1, "expression too deeply nested");
    assert_eq!(parse_err(&vec!["1"; 100_000].join("+")).1, "expression too deeply nested");
    assert_eq!(
        parse_err(&format!("{}1{}", "sin(".repeat(10_000), ")".repeat(10_000))).1,
        "expression too deeply nested"
    );
    // Within the limit is fine.
    let ok = format!("{}1{}", "(".repeat(MAX_DEPTH / 2), ")".repeat(MAX_DEPTH / 2));
    assert_eq!(p(&ok), Expr::Num(1.0));
    assert!(close(FixedEnv::new().val(&vec!["1"; MAX_DEPTH].join("+")), MAX_DEPTH as f64));
}

#[test]
fn random_garbage_never_panics() {
    let pieces = [
        "sin", "(", ")", ",", "dx", "a", "b.m", "c.k", "ground.O", "1e", "1e5", ".5", ".", "^", "-", "+", "*", "/",
        " ", "é", "#", "x0", "dif", "dif1", "fx", "j1", "pi", "time", "9", "e", "\u{0}", "(((", "step", "if", "vr",
        "atan2", "p0", "_", "..", "1.2.3", "∞", "NaN", "inf", "\n",
    ];
    let mut rng = Lcg(42);
    let env = FixedEnv::new();
    let mut parsed = 0;
    for _ in 0..20_000 {
        let n = (rng.next() * 12.0) as usize;
        let src: String = (0..n).map(|_| pieces[(rng.next() * pieces.len() as f64) as usize]).collect();
        match parse(&src, &MockScope) {
            Ok(e) => {
                parsed += 1;
                let _ = eval(&e, &env);
                let _ = deps(&e);
            }
            Err(e) => assert!(e.offset <= src.chars().count(), "{src:?}: offset {}", e.offset),
        }
    }
    assert!(parsed > 100, "only {parsed} random strings parsed");
    // Random characters (not just tokens), including multi-byte ones.
    for _ in 0..20_000 {
        let n = (rng.next() * 16.0) as usize;
        let src: String = (0..n).map(|_| char::from_u32((rng.next() * 0x300 as f64) as u32).unwrap_or('?')).collect();
        if let Err(e) = parse(&src, &MockScope) {
            assert!(e.offset <= src.chars().count());
        }
    }
}

#[test]
fn modal_measures_parse_to_the_body_cm_marker_and_a_mode_index_from_zero() {
    assert_eq!(p("modal(flex, 2)"), Expr::Modal(ModalFn::Coordinate, 5, 1));
    assert_eq!(p("modal_rate( flex ,3 )"), Expr::Modal(ModalFn::Rate, 5, 2));
    let d = deps(&p("2*modal(flex, 1) + modal_rate(flex, 3)"));
    assert_eq!((d.markers, d.level), (vec![5], 1));
    assert_eq!(deps(&p("modal(flex, 1)")).level, 0);
    let cases = [
        ("modal(a, 1)", 6, "'a' is not a flexible body: 'modal' reads a <flexible_body>'s modes"),
        ("modal(zz, 1)", 6, "'zz' is unknown: 'modal' reads a <flexible_body>'s modes"),
        ("modal(flex, 4)", 12, "mode 4 of 'flex': it has modes 1 to 3"),
        ("modal(flex, 0)", 12, "mode 0 of 'flex': it has modes 1 to 3"),
        ("modal_rate(flex, 1.5)", 17, "mode 1.5 of 'flex': it has modes 1 to 3"),
        ("modal(flex)", 10, "'modal' takes a flexible body and a mode number: modal(body, k)"),
        ("modal(flex, x0)", 12, "'modal' takes a flexible body and a mode number: modal(body, k)"),
        ("modal(1, flex)", 6, "'modal' takes a flexible body and a mode number: modal(body, k)"),
        ("modal(flex, 1", 13, "unexpected end of expression"),
    ];
    for (src, off, msg) in cases {
        assert_eq!(parse_err(src), (off, msg.to_string()), "{src}");
    }
}
