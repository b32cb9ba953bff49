//! Non-holonomic constraints (knife edge, rolling wheel): simulation and linearization with
//! separate position (s0) and velocity (s1 < s0) states, against closed forms.

use crate::common::lin_at_start;
use faer::Mat;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::Model;

fn model(name: &str, params: &[(&str, f64)]) -> Model {
    let m = crate::common::model(name);
    let mut p = m.param_values();
    for (k, v) in params {
        p[m.parameters.iter().position(|x| x.name == *k).unwrap()] = *v;
    }
    m.with_params(&p).unwrap()
}

#[test]
fn chaplygin_sleigh_matches_the_closed_form_linearization() {
    // v' = a w², (I + m a²) w' = −m a v w about (v0, 0), in S = (xP, yP, heading),
    // W = (v, heading rate): exact entries; 1e-8 relative (the issue's bound; round-off only).
    let (m, i, a, v0) = (3.0, 0.4, 0.5, 2.0);
    let lin = lin_at_start(&model("chaplygin_sleigh.xml", &[]));
    assert_eq!(lin.states, ["xp", "yp", "heading", "v", "der(heading)"]);
    let mut want = Mat::<f64>::zeros(5, 5);
    want[(0, 3)] = 1.0;
    want[(1, 2)] = v0;
    want[(2, 4)] = 1.0;
    want[(4, 4)] = -m * a * v0 / (i + m * a * a);
    for r in 0..5 {
        for c in 0..5 {
            assert!(
                (lin.a[(r, c)] - want[(r, c)]).abs() < 1e-8 * 2.0,
                "A[{r},{c}] = {} want {}",
                lin.a[(r, c)],
                want[(r, c)]
            );
        }
    }
    // Backwards (v0 < 0) the heading rate grows: the sleigh turns around.
    let back = lin_at_start(&model("chaplygin_sleigh.xml", &[("v0", -1.5)]));
    let w = back.states.iter().position(|s| s == "der(heading)").unwrap();
    assert!((back.a[(w, w)] - m * a * 1.5 / (i + m * a * a)).abs() < 1e-8);
}

/// Coefficients c_1..c_n of det(sI − A) = sⁿ + c_1 sⁿ⁻¹ + … (Faddeev–LeVerrier).
fn char_poly(a: &Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut mk = Mat::<f64>::identity(n, n);
    let mut c = Vec::with_capacity(n);
    for k in 1..=n {
        let am = a * &mk;
        let ck = -(0..n).map(|i| am[(i, i)]).sum::<f64>() / k as f64;
        c.push(ck);
        mk = &am + Mat::<f64>::identity(n, n) * faer::Scale(ck);
    }
    c
}

#[test]
fn rolling_disc_lean_eigenvalues_match_the_closed_form_at_three_spin_rates() {
    // Thin disc upright, rolling straight: lean'' + (4/5)(3Ω² − g/r) lean = 0 and six zero
    // eigenvalues, i.e. det(sI − A) = s⁶ (s² + ω²) with ω² = (4/5)(3Ω² − g/r). Checked on the
    // characteristic polynomial's coefficients (well conditioned even where the eigenvalues
    // are multiple, e.g. at the critical spin Ω² = g/(3r) where ω² = 0): c2 = ω² to 1e-8
    // relative to g/r, every other coefficient zero to 1e-8 relative to (g/r)^(k/2).
    let (g, r) = (9.81f64, 0.3f64);
    for omega in [10.0, (g / (3.0 * r)).sqrt(), 2.0] {
        let lin = lin_at_start(&model("rolling_disc.xml", &[("Omega", omega)]));
        assert_eq!(lin.a.nrows(), 8, "s0 = 5, s1 = 3");
        assert_eq!(&lin.states[..2], ["lean", "heading"]);
        let c = char_poly(&lin.a);
        let w2 = 0.8 * (3.0 * omega * omega - g / r);
        let scale = g / r;
        assert!((c[1] - w2).abs() < 1e-8 * scale, "Ω = {omega}: c2 = {} want {w2}", c[1]);
        for (k, ck) in c.iter().enumerate() {
            if k != 1 {
                let bound = 1e-8 * scale.powf((k + 1) as f64 / 2.0);
                assert!(ck.abs() < bound, "Ω = {omega}: c{} = {ck:e} (bound {bound:e})", k + 1);
            }
        }
    }
}

#[test]
fn rolling_disc_keeps_its_constraints_and_energy_over_ten_seconds() {
    // A wobbling disc (initial lean rate 0.3 rad/s at Ω = 10): no slip and no dissipation.
    // The integrator's tolerance is mixed (atol + rtol·|y| with atol = rtol = tol), so the
    // velocity residual |g| must stay below tol·(1 + |v|) (|v| = Ω r = 3 m/s) at every output
    // time, the contact height |C| below tol; energy to 1e-6 relative.
    let tol = 1e-8;
    let m = model("rolling_disc.xml", &[("lean_rate0", 0.3)]);
    let mut sim = Simulator::new(&m, SimOptions { tol, max_step: None, ..Default::default() }, 0.0).unwrap();
    let e0 = sim.mechanical_energy();
    let mut lean_max = 0.0f64;
    for k in 1..=200 {
        sim.advance(0.05 * k as f64).unwrap();
        let g = sim.nonholonomic_residual();
        assert!(g < tol * (1.0 + 3.0), "t = {}: |g| = {g:e}", sim.time());
        assert!(sim.constraint_residual() < tol, "t = {}: |C| = {:e}", sim.time(), sim.constraint_residual());
        let de = (sim.mechanical_energy() - e0).abs() / e0;
        assert!(de < 1e-6, "t = {}: energy drift {de:e}", sim.time());
        lean_max = lean_max.max(sim.outputs().unwrap()[0].abs());
    }
    // Small-amplitude lean: amplitude ≈ lean_rate0 / ω, ω = sqrt(0.8 (300 − g/r)) = 14.62.
    assert!((lean_max - 0.3 / 14.6233).abs() < 0.1 * 0.3 / 14.6233, "lean amplitude {lean_max}");
}

#[test]
fn static_equilibrium_with_a_knife_edge_across_a_slope() {
    // A sled on a 20° slope (planar joint) with its blade horizontal, across the fall line,
    // and its CM on the blade; springs (relaxed) hold it along the blade and in heading
    // (else the static problem is singular: neutral directions). The knife edge (multiplier
    // ν = m g sin α) holds it across: static equilibrium solves q, λ and ν, keeping the
    // sled where it was assembled; released, it stays (|Δr| < 1e-9 after 1 s). Without the
    // knife it slides down the fall line (checked against g sin α t²/2 along the slope).
    let with_knife = r#"<multibody name="sled" version="1">
      <parameter name="al" value="20*pi/180"/>
      <gravity value="0 0 -9.81"/>
      <ground>
        <marker name="slope" position="0 0 0" z_axis="0, -sin(al), cos(al)" x_axis="1 0 0"/>
        <marker name="anchor" position="-0.5 0 0"/>
      </ground>
      <body name="s" mass="3" inertia="0.2 0.3 0.4" position="0.5 0 0" z_axis="0, -sin(al), cos(al)" x_axis="1 0 0"/>
      <joint name="plane" type="planar" i="s.cm" j="ground.slope"/>
      <knife_edge name="blade" marker="s.cm"/>
      <spring_damper name="along" type="translational" i="s.cm" j="ground.anchor" stiffness="50" damping="1" length="1"/>
      <spring_damper name="turn" type="rotational" i="s.cm" j="ground.slope" stiffness="5" damping="0.1"/>
      <output name="x" function="dx(s.cm)"/>
      <output name="y" function="dy(s.cm)"/>
      <analysis static="true"/>
    </multibody>"#;
    let m = load_str_model(with_knife);
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let y0 = sim.outputs().unwrap();
    assert!((y0[0] - 0.5).abs() < 1e-9 && y0[1].abs() < 1e-9, "moved while solving: {y0:?}");
    sim.advance(1.0).unwrap();
    let y1 = sim.outputs().unwrap();
    assert!((y1[0] - y0[0]).abs() < 1e-9 && (y1[1] - y0[1]).abs() < 1e-9, "{y0:?} -> {y1:?}");
    // Without the blade (and springs) the sled slides down the fall line: after 1 s it has
    // moved g sin α / 2 along the slope, i.e. g sin α cos α / 2 in ground −y.
    let free = with_knife
        .replace(r#"<knife_edge name="blade" marker="s.cm"/>"#, "")
        .replace(r#"<analysis static="true"/>"#, "")
        .replace(r#"stiffness="50" damping="1""#, r#"stiffness="0" damping="0""#)
        .replace(r#"stiffness="5" damping="0.1""#, r#"stiffness="0" damping="0""#);
    let mut sim =
        Simulator::new(&load_str_model(&free), SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0)
            .unwrap();
    sim.advance(1.0).unwrap();
    let slid = -sim.outputs().unwrap()[1];
    let want = 0.5 * 9.81 * (20f64.to_radians()).sin() * (20f64.to_radians()).cos();
    assert!((slid - want).abs() < 1e-6, "slid {slid} want {want}");
}

fn load_str_model(xml: &str) -> Model {
    mbfmu::model::parse::load_str(xml, "sled.xml").unwrap()
}
