//! `<bushing>`: six uncoupled spring-dampers when the bushing sits at the CM of a body
//! with principal inertia along its axes — each component is a 1-DOF oscillator.

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::eigen_table;
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_str;

#[test]
fn bushing_at_the_cm_gives_six_oscillators_and_the_static_sag() {
    // m = 2, I = diag(0.1, 0.2, 0.3), K = (100, 200, 300, 4, 5, 6), C = (1, 2, 3, 0.1, 0.2, 0.3):
    // ω_n = sqrt(k/m) or sqrt(k_r/I), ζ = c / (2 sqrt(k m)) or c_r / (2 sqrt(k_r I)); static
    // equilibrium sags by m g / k_z. Exact linearization (small-angle rotation vector):
    // 1e-9 relative.
    let xml = r#"<multibody name="bush" version="1">
      <gravity value="0 0 -9.81"/>
      <ground><marker name="O" position="0 0 1"/></ground>
      <body name="b" mass="2" inertia="0.1 0.2 0.3" position="0 0 1"/>
      <bushing name="mount" i="b.cm" j="ground.O" stiffness="100 200 300 4 5 6" damping="1 2 3 0.1 0.2 0.3"/>
      <output name="z" function="dz(b.cm)"/>
      <output name="force_z" function="fz(mount)"/>
      <analysis static="true"/>
    </multibody>"#;
    let m = load_str(xml, "bush.xml").unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let y = sim.outputs().unwrap();
    assert!((y[0] - (1.0 - 2.0 * 9.81 / 300.0)).abs() < 1e-9, "sag: z = {}", y[0]);
    assert!((y[1] - 2.0 * 9.81).abs() < 1e-9, "bushing force {}", y[1]);
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let mut got: Vec<(f64, f64)> = eigen_table(&lin.a).unwrap().iter().map(|r| (r.frequency, r.damping)).collect();
    let (k, c, inert): ([f64; 6], [f64; 6], [f64; 6]) =
        ([100.0, 200.0, 300.0, 4.0, 5.0, 6.0], [1.0, 2.0, 3.0, 0.1, 0.2, 0.3], [2.0, 2.0, 2.0, 0.1, 0.2, 0.3]);
    let mut want: Vec<(f64, f64)> =
        (0..6).map(|i| ((k[i] / inert[i]).sqrt(), c[i] / (2.0 * (k[i] * inert[i]).sqrt()))).collect();
    got.sort_by(|a, b| a.0.total_cmp(&b.0));
    want.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(got.len(), 6, "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!((g.0 - w.0).abs() < 1e-9 * w.0 && (g.1 - w.1).abs() < 1e-9, "{g:?} vs {w:?}");
    }
}
