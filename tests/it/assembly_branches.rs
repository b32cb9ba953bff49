//! Assembly meets exact joint conditions over the whole circle, on the mechanism's own
//! branch. References are computed here, independently of the engine: forward kinematics
//! of serial chains by multiplying rotation matrices out, and the closed-form rocker
//! angle of a four-bar.
//!
//! Tolerance 1e-12 (absolute, on angles in rad and on positions and rotation entries of
//! chains of size below 5 m): assembly runs at tolerance 1e-13 × the model's size and
//! polishes exact conditions down to round-off, and 7 joints accumulate a few 1e-15.

use crate::common;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_str;
use std::f64::consts::PI;

type M = [[f64; 3]; 3];
type V = [f64; 3];

/// A small deterministic generator (64-bit LCG, high bits), so that cases are fixed by seed.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in (a, b].
    fn range(&mut self, a: f64, b: f64) -> f64 {
        b - (b - a) * self.unit()
    }
    fn vec(&mut self, r: f64) -> V {
        [self.range(-r, r), self.range(-r, r), self.range(-r, r)]
    }
    fn euler(&mut self) -> V {
        [self.range(-PI, PI), self.range(0.0, PI), self.range(-PI, PI)]
    }
}

fn rz(a: f64) -> M {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn rx(a: f64) -> M {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn mm(a: &M, b: &M) -> M {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

fn mv(a: &M, v: &V) -> V {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn add(a: &V, b: &V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn transpose(a: &M) -> M {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

/// R = Rz(psi) Rx(theta) Rz(phi), the model format's `euler313`.
fn euler(e: &V) -> M {
    mm(&mm(&rz(e[0]), &rx(e[1])), &rz(e[2]))
}

fn fmt(v: &V) -> String {
    format!("{:.17e} {:.17e} {:.17e}", v[0], v[1], v[2])
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Revolute,
    Translational,
    Cylindrical,
}

/// One joint of a serial chain: its frame J on the parent (position, rotation; z is the
/// axis), and the child's body frame relative to the joint's moving frame (offset c,
/// rotation C). The moving frame is J turned by the angle about z and shifted by the
/// displacement along z.
struct Link {
    kind: Kind,
    p: V,
    r: M,
    r_euler: V,
    c: V,
    cr: M,
    cr_euler: V,
}

/// Ground-frame poses of the chain's bodies at joint values (angle, displacement).
fn forward(links: &[Link], values: &[(f64, f64)]) -> Vec<(V, M)> {
    let (mut r, mut a) = ([0.0; 3], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let mut out = Vec::new();
    for (l, &(th, d)) in links.iter().zip(values) {
        let joint = mm(&a, &l.r);
        let origin = add(&add(&r, &mv(&a, &l.p)), &mv(&joint, &[0.0, 0.0, d]));
        let moving = mm(&joint, &rz(th));
        r = add(&origin, &mv(&moving, &l.c));
        a = mm(&moving, &l.cr);
        out.push((r, a));
    }
    out
}

/// The model of the chain drawn at `drawn`, asking for `target` by ic_angle /
/// ic_displacement, with one output per joint coordinate.
fn chain_model(links: &[Link], drawn: &[(f64, f64)], target: &[(f64, f64)]) -> String {
    let poses = forward(links, drawn);
    let mut s = String::from("<multibody name=\"chain\" version=\"1\">\n<ground>\n");
    s += &format!(
        "<marker name=\"J0\" position=\"{}\" euler313=\"{}\"/>\n</ground>\n",
        fmt(&links[0].p),
        fmt(&links[0].r_euler)
    );
    for (k, (r, a)) in poses.iter().enumerate() {
        let col = |c: usize| [a[0][c], a[1][c], a[2][c]];
        s += &format!(
            "<body name=\"b{k}\" mass=\"1\" inertia=\"0.1 0.2 0.3\" position=\"{}\" z_axis=\"{}\" x_axis=\"{}\">\n",
            fmt(r),
            fmt(&col(2)),
            fmt(&col(0))
        );
        // Marker i: the joint's moving frame in this body's axes (C^T, −C^T c).
        let l = &links[k];
        let ct = transpose(&l.cr);
        let pos = mv(&ct, &l.c).map(|x| -x);
        let e = [-l.cr_euler[2], -l.cr_euler[1], -l.cr_euler[0]];
        s += &format!("<marker name=\"I\" position=\"{}\" euler313=\"{}\"/>\n", fmt(&pos), fmt(&e));
        if let Some(next) = links.get(k + 1) {
            s += &format!("<marker name=\"J\" position=\"{}\" euler313=\"{}\"/>\n", fmt(&next.p), fmt(&next.r_euler));
        }
        s += "</body>\n";
    }
    for (k, l) in links.iter().enumerate() {
        let j = if k == 0 { "ground.J0".to_string() } else { format!("b{}.J", k - 1) };
        let (th, d) = target[k];
        let (ty, ics) = match l.kind {
            Kind::Revolute => ("revolute", format!("ic_angle=\"{th:.17e}\"")),
            Kind::Translational => ("translational", format!("ic_displacement=\"{d:.17e}\"")),
            Kind::Cylindrical => ("cylindrical", format!("ic_angle=\"{th:.17e}\" ic_displacement=\"{d:.17e}\"")),
        };
        s += &format!("<joint name=\"q{k}\" type=\"{ty}\" i=\"b{k}.I\" j=\"{j}\" {ics}/>\n");
        s += &format!("<output name=\"angle{k}\" function=\"az(b{k}.I, {j})\"/>\n");
        s += &format!("<output name=\"disp{k}\" function=\"dz(b{k}.I, {j}, {j})\"/>\n");
    }
    s + "</multibody>\n"
}

/// A random chain of `n` joints of the kinds `kinds` chooses from.
fn random_chain(rng: &mut Lcg, n: usize, kinds: &[Kind]) -> Vec<Link> {
    (0..n)
        .map(|_| {
            let kind = kinds[(rng.unit() * kinds.len() as f64) as usize % kinds.len()];
            let (r_euler, cr_euler) = (rng.euler(), rng.euler());
            Link { kind, p: rng.vec(0.4), r: euler(&r_euler), r_euler, c: rng.vec(0.4), cr: euler(&cr_euler), cr_euler }
        })
        .collect()
}

/// Joint values: angles in (−π, π] (0 for translational joints), displacements in (−0.3, 0.3].
fn random_values(rng: &mut Lcg, links: &[Link]) -> Vec<(f64, f64)> {
    links
        .iter()
        .map(|l| {
            let th = if l.kind == Kind::Translational { 0.0 } else { rng.range(-PI, PI) };
            let d = if l.kind == Kind::Revolute { 0.0 } else { rng.range(-0.3, 0.3) };
            (th, d)
        })
        .collect()
}

/// Assemble `cases` random chains of each length in `lengths` and compare with forward
/// kinematics; returns the largest error seen.
fn check_chains(seed: u64, lengths: &[usize], kinds: &[Kind], cases: usize) -> f64 {
    let mut rng = Lcg(seed);
    let mut worst = 0.0f64;
    for &n in lengths {
        for case in 0..cases {
            let links = random_chain(&mut rng, n, kinds);
            let drawn = random_values(&mut rng, &links);
            let target = random_values(&mut rng, &links);
            let text = chain_model(&links, &drawn, &target);
            let m = load_str(&text, "chain.xml").unwrap_or_else(|e| panic!("{e}\n{text}"));
            let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
            let mut s = Simulator::new(&m, opts, 0.0)
                .unwrap_or_else(|e| panic!("n = {n}, case {case}: {e}\ndrawn {drawn:?}\ntarget {target:?}"));
            let expected = forward(&links, &target);
            let outputs = s.outputs().unwrap();
            for (k, (r, a)) in expected.iter().enumerate() {
                let b = s.body_state(k);
                let rows = b.rotation.iter().flatten().zip(a.iter().flatten());
                for (x, y) in b.position.iter().zip(r).chain(rows) {
                    worst = worst.max((x - y).abs());
                }
                let (th, d) = target[k];
                if links[k].kind != Kind::Translational {
                    worst = worst.max((outputs[2 * k] - th).abs());
                }
                worst = worst.max((outputs[2 * k + 1] - d).abs());
            }
            assert!(
                worst < 1e-12,
                "n = {n}, case {case}: error {worst:.3e}\ndrawn {drawn:?}\ntarget {target:?}\n{text}"
            );
        }
    }
    worst
}

#[test]
fn revolute_chains_reach_any_target_angles_exactly() {
    // 1, 2, 4 and 7 joints with random axes, drawn at random angles, asked for random
    // angles over (−π, π]: 100 cases each.
    let worst = check_chains(0x5eed_0001, &[1, 2, 4, 7], &[Kind::Revolute], 100);
    eprintln!("revolute chains: largest error {worst:.3e}");
}

#[test]
fn translational_and_cylindrical_chains_reach_their_targets_exactly() {
    let worst = check_chains(0x5eed_0002, &[1, 2, 4], &[Kind::Translational, Kind::Cylindrical], 40);
    let mixed = check_chains(0x5eed_0003, &[3, 6], &[Kind::Revolute, Kind::Translational, Kind::Cylindrical], 40);
    eprintln!("translational/cylindrical chains: {worst:.3e}, mixed: {mixed:.3e}");
}

/// A planar four-bar (all joint axes along ground z): ground pivots A = 0 and D = (d, 0),
/// crank AB = a, coupler BC = b, rocker DC = c, drawn with the crank at `theta` on the
/// assembly branch `sign`, coupler and rocker shifted off by `off` (m); the crank is asked
/// for `target` by ic_angle.
fn four_bar(dims: [f64; 4], theta: f64, sign: f64, off: f64, target: f64) -> String {
    let [a, b, c, d] = dims;
    let bp = [a * theta.cos(), a * theta.sin(), 0.0];
    let phi = rocker_angle(dims, theta, sign).expect("the drawing assembles");
    let cp = [d + c * phi.cos(), c * phi.sin(), 0.0];
    let beta = (cp[1] - bp[1]).atan2(cp[0] - bp[0]);
    let body = |name: &str, from: V, angle: f64, len: f64, m1: &str, m2: &str, shift: f64| {
        let (s, co) = angle.sin_cos();
        let cm = [from[0] + 0.5 * len * co + shift, from[1] + 0.5 * len * s - shift, 0.0];
        format!(
            "<body name=\"{name}\" mass=\"1\" inertia=\"0.01 0.01 0.02\" position=\"{}\" z_axis=\"0 0 1\" \
             x_axis=\"{co:.17e} {s:.17e} 0\">\n<marker name=\"{m1}\" position=\"{:.17e} 0 0\"/>\n\
             <marker name=\"{m2}\" position=\"{:.17e} 0 0\"/>\n</body>\n",
            fmt(&cm),
            -0.5 * len,
            0.5 * len
        )
    };
    let mut s = String::from("<multibody name=\"fourbar\" version=\"1\">\n<gravity value=\"0 -9.81 0\"/>\n<ground>\n");
    s += &format!(
        "<marker name=\"A\" position=\"0 0 0\"/>\n<marker name=\"D\" position=\"{d:.17e} 0 0\"/>\n</ground>\n"
    );
    s += &body("crank", [0.0; 3], theta, a, "A", "B", 0.0);
    s += &body("coupler", bp, beta, b, "B", "C", off);
    s += &body("rocker", [d, 0.0, 0.0], phi, c, "D", "C", -off);
    s += &format!(
        "<joint name=\"crank_pin\" type=\"revolute\" i=\"crank.A\" j=\"ground.A\" ic_angle=\"{target:.17e}\"/>\n"
    );
    s += "<joint name=\"b_pin\" type=\"revolute\" i=\"coupler.B\" j=\"crank.B\"/>\n";
    s += "<joint name=\"c_pin\" type=\"revolute\" i=\"coupler.C\" j=\"rocker.C\"/>\n";
    s += "<joint name=\"d_pin\" type=\"revolute\" i=\"rocker.D\" j=\"ground.D\"/>\n";
    s += "<output name=\"crank\" function=\"az(crank.A, ground.A)\"/>\n";
    s + "<output name=\"rocker\" function=\"az(rocker.D, ground.D)\"/>\n</multibody>\n"
}

/// The rocker angle of the four-bar at crank angle `theta` on branch `sign` (±1), in closed
/// form: with P = D − B, |P + c e(φ)| = b gives P·e(φ) = (b² − |P|² − c²)/(2c), so
/// φ = atan2(P_y, P_x) + sign·acos(K/|P|). None where the loop does not close.
fn rocker_angle([a, b, c, d]: [f64; 4], theta: f64, sign: f64) -> Option<f64> {
    let p = [d - a * theta.cos(), -a * theta.sin()];
    let r = p[0].hypot(p[1]);
    let k = (b * b - r * r - c * c) / (2.0 * c);
    (k.abs() <= r).then(|| p[1].atan2(p[0]) + sign * (k / r).acos())
}

/// `x − y` wrapped to (−π, π].
fn wrapped(x: f64, y: f64) -> f64 {
    let d = (x - y).rem_euclid(2.0 * PI);
    if d > PI { d - 2.0 * PI } else { d }
}

#[test]
fn four_bar_crank_over_the_full_circle_gives_the_closed_form_rocker_on_the_drawn_branch() {
    // A Grashof crank-rocker (a + b ≤ c + d, crank shortest): the crank turns fully and
    // the two assembly branches never meet. Drawn on either branch at 3 crank angles, the
    // coupler and rocker 5 mm off, the crank asked for 72 angles around the circle: the
    // rocker equals the closed form on the drawn branch to 1e-12 (the other branch is at
    // least 0.1 rad away for these dimensions).
    let dims = [0.2, 0.7, 0.5, 0.6];
    let mut worst = 0.0f64;
    for sign in [1.0, -1.0] {
        for theta in [0.3, 2.0, -2.6] {
            for k in 0..72 {
                let target = -PI + (k as f64 + 0.5) * 2.0 * PI / 72.0;
                let text = four_bar(dims, theta, sign, 0.005, target);
                let m = load_str(&text, "fourbar.xml").unwrap_or_else(|e| panic!("{e}"));
                let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
                let mut s = Simulator::new(&m, opts, 0.0).unwrap_or_else(|e| panic!("{theta} → {target}: {e}"));
                let (crank, rocker) = (common::out(&mut s, "crank"), common::out(&mut s, "rocker"));
                let expected = rocker_angle(dims, target, sign).expect("Grashof: closes everywhere");
                let other = rocker_angle(dims, target, -sign).unwrap();
                assert!(wrapped(other, expected).abs() > 0.1);
                let err = (crank - target).abs().max(wrapped(rocker, expected).abs());
                assert!(
                    err < 1e-12,
                    "branch {sign}, drawn {theta}, target {target}: crank {crank}, rocker {rocker} vs {expected}"
                );
                worst = worst.max(err);
            }
        }
    }
    eprintln!("four-bar: largest error {worst:.3e}");
}

#[test]
fn a_crank_angle_the_loop_cannot_reach_is_an_error_at_the_joint() {
    // Non-Grashof: crank 0.4, coupler 0.3, rocker 0.3, ground 0.6; the loop closes only for
    // |θ| ≤ acos(1/3) ≈ 1.23 rad. Asking for 2.5 must fail, at the crank joint's line.
    let dims = [0.4, 0.3, 0.3, 0.6];
    let text = four_bar(dims, 0.3, 1.0, 0.0, 2.5);
    let m = load_str(&text, "fourbar.xml").unwrap();
    let err = Simulator::new(&m, SimOptions::default(), 0.0).err().expect("2.5 rad is out of reach");
    let msg = err.to_string();
    let line = text.lines().position(|l| l.contains("crank_pin")).unwrap() + 1;
    assert!(
        msg.starts_with(&format!("fourbar.xml:{line}:1: joint 'crank_pin (ic_angle)': cannot be assembled")),
        "{msg}"
    );
    assert!(msg.contains("2.5"), "{msg}");
}

#[test]
fn a_revolute_joint_drawn_inside_out_is_an_error_naming_it() {
    // z_i = −z_j as drawn: the dot-product equations hold, the joint's definition does not.
    let text = r#"<multibody name="flip" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="arm" mass="1" inertia="0.1 0.1 0.1" position="0.5 0 0">
    <marker name="P" position="-0.5 0 0" z_axis="0 0 -1"/>
  </body>
  <joint name="pin" type="revolute" i="arm.P" j="ground.O"/>
</multibody>"#;
    let m = load_str(text, "flip.xml").unwrap();
    let msg = Simulator::new(&m, SimOptions::default(), 0.0).err().expect("inside out").to_string();
    assert!(msg.starts_with("flip.xml:6:3: joint 'pin': cannot be assembled as drawn"), "{msg}");
    assert!(msg.contains("inside out"), "{msg}");
}

#[test]
fn the_move_warning_names_what_the_drawing_lacks_and_is_silent_for_what_was_asked() {
    // An arm of 1 m drawn on its pivot at angle 0 and asked for 2.5 rad: its CM moves by
    // 2·0.5·sin(1.25) ≈ 0.95 m, exactly as asked: no warning. Drawn 0.3 m off the pivot:
    // the warning names the joint the drawing does not meet.
    let arm = |x0: f64| {
        format!(
            r#"<multibody name="arm" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="arm" mass="1" inertia="0.1 0.1 0.1" position="{x0} 0 0">
    <marker name="P" position="-0.5 0 0"/>
  </body>
  <joint name="pin" type="revolute" i="arm.P" j="ground.O" ic_angle="2.5"/>
</multibody>"#
        )
    };
    let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
    let asked = Simulator::new(&load_str(&arm(0.5), "arm.xml").unwrap(), opts, 0.0).unwrap();
    let cm = asked.body_state(0).position;
    assert!((cm[0] - 0.5 * 2.5f64.cos()).abs() < 1e-12 && (cm[1] - 0.5 * 2.5f64.sin()).abs() < 1e-12, "{cm:?}");
    assert!(asked.warnings().is_empty(), "{:?}", asked.warnings());
    let off = Simulator::new(&load_str(&arm(0.8), "arm.xml").unwrap(), opts, 0.0).unwrap();
    assert_eq!(off.warnings().len(), 1, "{:?}", off.warnings());
    let w = &off.warnings()[0];
    assert!(w.starts_with("assembly moved body 'arm' by 3.000e-1 m"), "{w}");
    assert!(w.contains("the drawing disagrees with joint 'pin'"), "{w}");
}

fn ry(a: f64) -> M {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

#[test]
fn spherical_and_planar_coordinates_set_as_start_values_are_met_exactly() {
    // A ball on a spherical joint at a tilted ground marker, and a puck on a planar joint:
    // start values on yaw, pitch, roll (R = Rz Ry Rx relative to the marker, MODEL_FORMAT)
    // and on dx, dy, angle, over random targets (pitch within ±60°, where the spherical
    // coordinates are defined), give the body poses multiplied out here, to 1e-12.
    let text = r#"<multibody name="sp" version="1">
  <ground><marker name="S" position="0.1 0.2 0.3" euler313="0.3 0.4 0.5"/><marker name="Q" position="0 0 1" euler313="-0.7 0.2 0"/></ground>
  <body name="ball" mass="1" inertia="0.1 0.2 0.3" position="0.1 0.2 0.3" euler313="0.3 0.4 0.5"/>
  <body name="puck" mass="1" inertia="0.1 0.2 0.3" position="0 0 1" euler313="-0.7 0.2 0"/>
  <joint name="ball_joint" type="spherical" i="ball.cm" j="ground.S"/>
  <joint name="slide" type="planar" i="puck.cm" j="ground.Q"/>
</multibody>"#;
    let base = load_str(text, "sp.xml").unwrap();
    let (rs, rq) = (euler(&[0.3, 0.4, 0.5]), euler(&[-0.7, 0.2, 0.0]));
    let mut rng = Lcg(0x5eed_0004);
    let mut worst = 0.0f64;
    for _ in 0..50 {
        let (yaw, pitch, roll) = (rng.range(-PI, PI), rng.range(-1.0, 1.0), rng.range(-PI, PI));
        let (dx, dy, angle) = (rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), rng.range(-PI, PI));
        let mut m = base.clone();
        m.state_starts = [
            ("ball_joint.yaw", yaw),
            ("ball_joint.pitch", pitch),
            ("ball_joint.roll", roll),
            ("slide.dx", dx),
            ("slide.dy", dy),
            ("slide.angle", angle),
        ]
        .iter()
        .map(|(n, v)| (n.to_string(), *v))
        .collect();
        let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
        let s = Simulator::new(&m, opts, 0.0).unwrap_or_else(|e| panic!("{yaw} {pitch} {roll}: {e}"));
        let ball = mm(&rs, &mm(&mm(&rz(yaw), &ry(pitch)), &rx(roll)));
        let puck = mm(&rq, &rz(angle));
        let puck_at = add(&[0.0, 0.0, 1.0], &mv(&rq, &[dx, dy, 0.0]));
        let (b, p) = (s.body_state(0), s.body_state(1));
        let pairs = b.rotation.iter().flatten().zip(ball.iter().flatten());
        let pairs = pairs.chain(p.rotation.iter().flatten().zip(puck.iter().flatten()));
        let pairs = pairs.chain(p.position.iter().zip(&puck_at)).chain(b.position.iter().zip(&[0.1, 0.2, 0.3]));
        for (x, y) in pairs {
            worst = worst.max((x - y).abs());
        }
        assert!(worst < 1e-12, "{yaw} {pitch} {roll} {dx} {dy} {angle}: error {worst:.3e}");
    }
    eprintln!("spherical and planar start values: largest error {worst:.3e}");
}
