//! Element loads (`fx(name)` ...) and their exact derivatives: the rows of C and D of
//! outputs that read joint, motion, spring, sforce and gforce loads against central
//! differences of the engine's own state-space map; the gradients of
//! `mechanics::loads` against central differences of its values; and the physical values
//! of a pendulum's hinge force (static weight, centripetal and tangential parts).

use crate::common::state_space;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{linearize, select_states};
use mbfmu::mechanics::body::NQ;
use mbfmu::mechanics::loads::{NLOAD, load_gradient, load_value};
use mbfmu::model::expr::ElementRef;
use mbfmu::model::parse::load_str;

/// A spatial mechanism moving under gravity: a pendulum l1 (hinge j1 about ground y), a
/// link l2 hinged to it about x (j2, driven by the input torque T through the sforce
/// `mot`), a spherical pendulum l3 hanging from ground (j3, i marker on ground), pushed by
/// the gforce `push` (input F) and tied to l2 by the spring `spr`; a rotor l0 driven by
/// the motion `m0` and tied to l1 by the spring `spr2`. Five degrees of freedom.
const MECH: &str = r#"<multibody name="loads" version="1">
  <gravity value="0 0 -9.81"/>
  <ground>
    <marker name="O" position="0 0 0" z_axis="0 1 0"/>
    <marker name="B" position="0.6 0 0"/>
    <marker name="R" position="0 -0.8 0" z_axis="0 1 0"/>
  </ground>
  <body name="l1" mass="2" inertia="0.05 0.06 0.02" position="0 0 -0.3" angular_velocity="0 1.5 0" velocity="-0.45 0 0">
    <marker name="P" position="0 0 0.3" z_axis="0 1 0"/>
    <marker name="Q" position="0 0 -0.3" z_axis="1 0 0"/>
  </body>
  <body name="l2" mass="1.2" inertia="0.03 0.01 0.03" position="0 0.25 -0.6">
    <marker name="A" position="0 -0.25 0" z_axis="1 0 0"/>
    <marker name="tip" position="0 0.25 0"/>
  </body>
  <body name="l3" mass="0.8" inertia="0.02 0.02 0.005" position="0.6 0 -0.4" angular_velocity="1 0.5 0">
    <marker name="a" position="0 0 0.4"/>
    <marker name="tip" position="0 0 -0.4"/>
  </body>
  <body name="l0" mass="1" inertia="0.1 0.2 0.1" position="0 -0.8 0">
    <marker name="axis" position="0 0 0" z_axis="0 1 0"/>
    <marker name="arm" position="0.3 0 0"/>
  </body>
  <joint name="j1" type="revolute" i="l1.P" j="ground.O"/>
  <joint name="j2" type="revolute" i="l2.A" j="l1.Q"/>
  <joint name="j3" type="spherical" i="ground.B" j="l3.a"/>
  <joint name="j0" type="revolute" i="l0.axis" j="ground.R"/>
  <motion name="m0" joint="j0" dof="rotation" function="0.5*sin(2*time)"/>
  <input name="T" start="0.4"/>
  <input name="F" start="-0.7"/>
  <spring_damper name="spr" type="translational" i="l3.tip" j="l2.tip" stiffness="40" damping="0.3" length="0.5"/>
  <spring_damper name="spr2" type="translational" i="l0.arm" j="l1.Q" stiffness="30" damping="0.2" length="0.9"/>
  <sforce name="mot" type="rotational" i="l2.A" j="l1.Q" function="T - 0.2*wz(l2.A, l1.Q, l1.Q)"/>
  <gforce name="push" i="l3.tip" force="F, 0.3*F*dz(l3.tip), 0" torque="0 0 0"/>
  <output name="j1_fx" function="fx(j1)"/>
  <output name="j1_fy" function="fy(j1)"/>
  <output name="j1_fz" function="fz(j1)"/>
  <output name="j1_tz" function="tz(j1)"/>
  <output name="j2_tx" function="tx(j2)"/>
  <output name="j2_fz" function="fz(j2)"/>
  <output name="j3_mix" function="fx(j3) + 2*fy(j3) - fz(j3)"/>
  <output name="m0_ty" function="ty(m0)"/>
  <output name="spr_fx" function="fx(spr)"/>
  <output name="spr_mix" function="fz(spr)*dx(l3.tip)"/>
  <output name="mot_tx" function="tx(mot) + tz(mot)"/>
  <output name="push_fy" function="fy(push)"/>
  <output name="mixed" function="fx(j1)^2/10 + T*fy(j2) + accz(l2.cm)"/>
</multibody>"#;

const ELEMENTS: [(&str, ElementRef); 9] = [
    ("j1", ElementRef::Joint(0)),
    ("j2", ElementRef::Joint(1)),
    ("j3", ElementRef::Joint(2)),
    ("j0", ElementRef::Joint(3)),
    ("m0", ElementRef::Motion(0)),
    ("spr", ElementRef::SpringDamper(0)),
    ("spr2", ElementRef::SpringDamper(1)),
    ("mot", ElementRef::Sforce(0)),
    ("push", ElementRef::Gforce(0)),
];

/// The mechanism after 0.3 s of motion (a moving, non-equilibrium point).
pub(crate) fn moving() -> Simulator {
    let m = load_str(MECH, "loads.xml").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    sim.advance(0.3).unwrap();
    sim
}

#[test]
fn load_outputs_c_and_d_match_central_differences_of_the_state_space_map() {
    // C and D from Eq. 34 (with the λ sensitivities of the loads) against central
    // differences of the engine's state-space map x, v ↦ y (q, u from the states, u̇ and
    // λ from the equations of motion, loads from mechanics::loads). h = 1e-6: truncation
    // ~1e-12·|y'''|, round-off ~1e-16/1e-6·|y| ≈ 1e-9 for loads of ~10 N, so 1e-6 relative
    // to max(1, |entry|) is safe and still catches any missing term.
    let m = load_str(MECH, "loads.xml").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states.len(), 5);
    sim.advance(0.3).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let (sys, q0, t, v0) = (sim.system().clone(), sim.q().to_vec(), sim.time(), sim.inputs());
    let x0 = lin.x.clone();
    // The map reproduces the engine's outputs at the operating point.
    let (_, y0) = state_space(&sys, &sel, &q0, t, &x0, &v0);
    for (o, (a, b)) in y0.iter().zip(sim.outputs().unwrap()).enumerate() {
        assert!((a - b).abs() < 1e-8 * b.abs().max(1.0), "output {o}: {a} vs {b}");
    }
    let h = 1e-6;
    let mut worst = 0.0f64;
    let mut check = |name: String, got: f64, want: f64| {
        let err = (got - want).abs() / want.abs().max(1.0);
        worst = worst.max(err);
        assert!(err < 1e-6, "{name}: {got} vs {want}");
    };
    let ns = x0.len();
    for j in 0..ns {
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[j] += h;
        xm[j] -= h;
        let (_, yp) = state_space(&sys, &sel, &q0, t, &xp, &v0);
        let (_, ym) = state_space(&sys, &sel, &q0, t, &xm, &v0);
        for o in 0..yp.len() {
            check(format!("C[{},{j}]", lin.outputs[o]), lin.c[(o, j)], (yp[o] - ym[o]) / (2.0 * h));
        }
    }
    for k in 0..v0.len() {
        let (mut vp, mut vm) = (v0.clone(), v0.clone());
        vp[k] += h;
        vm[k] -= h;
        let (_, yp) = state_space(&sys, &sel, &q0, t, &x0, &vp);
        let (_, ym) = state_space(&sys, &sel, &q0, t, &x0, &vm);
        for o in 0..yp.len() {
            check(format!("D[{},{k}]", lin.outputs[o]), lin.d[(o, k)], (yp[o] - ym[o]) / (2.0 * h));
        }
    }
    eprintln!("C, D of load outputs vs central differences: worst relative error {worst:.1e}");
    // The rows carry real sensitivities: every load output moves with some state, the
    // hinge j1 feels the torque T on l2 through λ, the hanging l3's joint feels the push F.
    for o in 0..lin.outputs.len() {
        assert!((0..ns).any(|j| lin.c[(o, j)].abs() > 1e-3), "C row of {} is ~0", lin.outputs[o]);
    }
    assert!(lin.d[(0, 0)].abs() > 1e-3 && lin.d[(2, 0)].abs() > 1e-3, "D of j1_fx, j1_fz: {:?}", lin.d);
    assert!(lin.d[(6, 1)].abs() > 1e-3, "D of j3_mix: {:?}", lin.d);
}

#[test]
fn load_gradients_match_central_differences_of_the_load_values() {
    // ∂load/∂(q, u, λ, v) from dual numbers against central differences of load_value
    // with h = 1e-6 on each local coordinate, velocity, multiplier of the element and
    // input: 1e-7 relative to max(1, |entry|) (round-off ~1e-16·|load|/h ≈ 1e-9).
    let mut sim = moving();
    let (_, lam) = sim.accelerations().unwrap();
    let (sys, q, u, t, v) = (sim.system().clone(), sim.q().to_vec(), sim.u().to_vec(), sim.time(), sim.inputs());
    let h = 1e-6;
    let mut worst = 0.0f64;
    for (name, e) in ELEMENTS {
        let g = load_gradient(&sys, e, (&q, &u, &lam), t, &v).unwrap_or_else(|| panic!("{name} has a load"));
        let value = load_value(&sys, e, (&q, &u, &lam), t, &v).unwrap();
        for c in 0..NLOAD {
            // One implementation: the dual-number value equals the f64 one (to round-off).
            assert!((g.value[c] - value[c]).abs() < 1e-14 * value[c].abs().max(1.0), "{name}: {g:?} vs {value:?}");
        }
        let nql = NQ * g.bodies.len();
        let mut cmp = |what: String, k: usize, got: &dyn Fn(usize) -> f64, f: &dyn Fn(f64) -> [f64; NLOAD]| {
            let (p, m) = (f(h), f(-h));
            for c in 0..NLOAD {
                let want = (p[c] - m[c]) / (2.0 * h);
                let err = (got(c) - want).abs() / want.abs().max(1.0);
                worst = worst.max(err);
                assert!(err < 1e-7, "{name} d(load {c})/d({what} {k}): {} vs {want}", got(c));
            }
        };
        for a in 0..nql {
            let gi = NQ * g.bodies[a / NQ] + a % NQ;
            let at_q = |d: f64| {
                let mut qq = q.clone();
                qq[gi] += d;
                load_value(&sys, e, (&qq, &u, &lam), t, &v).unwrap()
            };
            cmp("q".into(), gi, &|c| g.dz[c * 2 * nql + a], &at_q);
            let at_u = |d: f64| {
                let mut uu = u.clone();
                uu[gi] += d;
                load_value(&sys, e, (&q, &uu, &lam), t, &v).unwrap()
            };
            cmp("u".into(), gi, &|c| g.dz[c * 2 * nql + nql + a], &at_u);
        }
        let neq = g.neq();
        for k in 0..neq {
            let at_l = |d: f64| {
                let mut ll = lam.clone();
                ll[g.lam_row + k] += d;
                load_value(&sys, e, (&q, &u, &ll), t, &v).unwrap()
            };
            cmp("lambda".into(), g.lam_row + k, &|c| g.dlam[c * neq + k], &at_l);
        }
        for k in 0..v.len() {
            let at_v = |d: f64| {
                let mut vv = v.clone();
                vv[k] += d;
                load_value(&sys, e, (&q, &u, &lam), t, &vv).unwrap()
            };
            cmp("input".into(), k, &|c| g.dv[c * v.len() + k], &at_v);
        }
    }
    eprintln!("load gradients vs central differences: worst relative error {worst:.1e}");
}

/// A rod (mass m, isotropic inertia J about its CM) hinged about ground y at the origin,
/// its CM at distance l, drawn to angle th from the downward vertical (towards +x) and
/// turning at w about +y.
fn pendulum(th: f64, w: f64) -> String {
    let (s, c) = (th.sin(), th.cos());
    let (l, m, j) = (0.8, 1.5, 0.05);
    format!(
        r#"<multibody name="p" version="1">
  <gravity value="0 0 -9.81"/>
  <ground><marker name="O" position="0 0 0" z_axis="0 1 0"/></ground>
  <body name="bob" mass="{m}" inertia="{j} {j} {j}" position="{x}, 0, {z}" velocity="{vx}, 0, {vz}" angular_velocity="0 {w} 0">
    <marker name="P" position="{px}, 0, {pz}" z_axis="0 1 0"/>
  </body>
  <joint name="hinge" type="revolute" i="bob.P" j="ground.O"/>
  <output name="h_fx" function="fx(hinge)"/>
  <output name="h_fy" function="fy(hinge)"/>
  <output name="h_fz" function="fz(hinge)"/>
  <output name="h_tx" function="tx(hinge)"/>
  <output name="h_ty" function="ty(hinge)"/>
  <output name="h_tz" function="tz(hinge)"/>
</multibody>"#,
        x = l * s,
        z = -l * c,
        vx = -w * l * c,
        vz = -w * l * s,
        px = -l * s,
        pz = l * c,
    )
}

#[test]
fn a_pendulum_hinge_carries_its_weight_at_rest_and_the_centripetal_and_tangential_forces_in_motion() {
    let (l, m, j, g) = (0.8, 1.5, 0.05, 9.81);
    // Hanging at rest: the hinge holds the weight, fz = m g, nothing else (1e-12 relative).
    let model = load_str(&pendulum(0.0, 0.0), "p.xml").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulator::new(&model, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let y = sim.outputs().unwrap();
    assert!((y[2] - m * g).abs() < 1e-12 * m * g, "fz at rest = {} vs m g = {}", y[2], m * g);
    for (k, v) in y.iter().enumerate().filter(|(k, _)| *k != 2) {
        assert!(v.abs() < 1e-12 * m * g, "component {k} at rest = {v}");
    }
    // Moving at angle th, rate w: with r = l (sin th, 0, −cos th), the hinge equation
    // (J + m l²) ẇ = m g l sin th about +y and a_cm = ẇ ŷ × r − w² r, the hinge force on
    // the rod is F = m a_cm − m g⃗ (1e-9 relative: assembly and Newton tolerances); it
    // has a centripetal part m w² l along −r̂ and no torque about the hinge (ty = 0, and
    // the rod's principal axes keep tx = tz = 0).
    let (th, w) = (0.4f64, 2.0f64);
    let model = load_str(&pendulum(th, w), "p.xml").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulator::new(&model, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let y = sim.outputs().unwrap();
    let r = [l * th.sin(), 0.0, -l * th.cos()];
    let wd = m * g * l * th.sin() / (j + m * l * l);
    // ŷ × r = (r_z, 0, −r_x).
    let a = [wd * r[2] - w * w * r[0], 0.0, -wd * r[0] - w * w * r[2]];
    let f = [m * a[0], 0.0, m * a[2] + m * g];
    for k in 0..3 {
        assert!((y[k] - f[k]).abs() < 1e-9 * m * g, "f{k} = {} vs {}", y[k], f[k]);
        assert!(y[3 + k].abs() < 1e-9 * m * g * l, "t{k} = {}", y[3 + k]);
    }
    // Along the rod (towards the hinge, −r̂) the force is m w² l + m g cos th.
    let along = -(y[0] * r[0] + y[2] * r[2]) / l;
    let want = m * w * w * l + m * g * th.cos();
    assert!((along - want).abs() < 1e-9 * want, "radial hinge force {along} vs {want}");
    eprintln!("moving pendulum hinge force: ({:.12}, {:.12}) vs ({:.12}, {:.12})", y[0], y[2], f[0], f[2]);
}
