//! Redundant constraints: the planar four-bar built from four revolute joints in 3-D has
//! 20 equations on 18 coordinates but one degree of freedom (3 equations are implied by
//! the others). The engine finds the redundant rows at initialization and leaves them
//! out (their multipliers 0), as production codes do, so the model simulates and
//! linearizes exactly like the same linkage built without redundancy.

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_str;

fn fourbars() -> (String, String) {
    let base = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/fourbar.xml"))
        .unwrap()
        .replace(
            "<experiment",
            r#"<linearization><state name="crank" function="az(crank.P, ground.O1)"/></linearization><experiment"#,
        );
    let revolutes = base
        .replace(r#"<joint name="crank_pin" type="spherical""#, r#"<joint name="crank_pin" type="revolute""#)
        .replace(r#"<joint name="rocker_pin" type="universal""#, r#"<joint name="rocker_pin" type="revolute""#)
        .replace(
            r#"<marker name="B" position="b/2, 0, 0" z_axis="0 1 0"/>"#,
            r#"<marker name="B" position="b/2, 0, 0"/>"#,
        );
    assert_ne!(base, revolutes);
    (base, revolutes)
}

#[test]
fn all_revolute_fourbar_moves_and_linearizes_like_the_non_redundant_one() {
    // Same motion to the integration tolerance (tol 1e-10 each: outputs agree to 1e-7 over
    // 1 s of this sensitive linkage) and the same A in the crank angle (1e-6 relative).
    let (base, revolutes) = fourbars();
    let opts = SimOptions { tol: 1e-10, max_step: None, ..Default::default() };
    let ma = load_str(&base, "a.xml").unwrap();
    let mb = load_str(&revolutes, "b.xml").unwrap();
    assert_eq!(mb.summary().constraints, 20);
    let mut a = Simulator::new(&ma, opts, 0.0).unwrap();
    let mut b = Simulator::new(&mb, opts, 0.0).unwrap();
    assert_eq!(b.system().redundant.iter().filter(|r| **r).count(), 3);
    let (sa, sb) = (
        select_states(a.system(), a.q(), 0.0, &a.inputs()).unwrap(),
        select_states(b.system(), b.q(), 0.0, &b.inputs()).unwrap(),
    );
    assert_eq!(sb.states.len(), 1);
    for k in 1..=10 {
        let t = 0.1 * k as f64;
        a.advance(t).unwrap();
        b.advance(t).unwrap();
        let (oa, ob) = (a.outputs().unwrap(), b.outputs().unwrap());
        for (x, y) in oa.iter().zip(&ob) {
            assert!((x - y).abs() < 1e-7 * x.abs().max(1.0), "t {t}: {x} vs {y}");
        }
        assert!(b.constraint_residual() < 1e-10);
    }
    let (la, lb) = (linearize(&mut a, &sa, 1).unwrap(), linearize(&mut b, &sb, 1).unwrap());
    for i in 0..2 {
        for j in 0..2 {
            let (x, y) = (la.a[(i, j)], lb.a[(i, j)]);
            assert!((x - y).abs() < 1e-6 * x.abs().max(1.0), "A[{i},{j}]: {x} vs {y}");
        }
    }
}

#[test]
fn redundancy_is_found_in_a_large_model() {
    // 150 copies of the all-revolute four-bar on the same ground pivots: n = 2700
    // coordinates, m = 3000 equations (n·m = 8.1e6, beyond the former dense limit of 4e6).
    // Each copy has 3 redundant equations, so 450 are found, 150 states are selected, and
    // the linearization exists.
    let (_, revolutes) = fourbars();
    let k = 150;
    let (b0, b1) = (revolutes.find("<body").unwrap(), revolutes.rfind("</body>").unwrap() + "</body>".len());
    let joints: Vec<&str> = revolutes.lines().filter(|l| l.trim_start().starts_with("<joint")).collect();
    let mut copies = String::new();
    for c in 0..k {
        let mut part = revolutes[b0..b1].to_string();
        part.extend(joints.iter().map(|l| format!("\n{l}")));
        for body in ["crank", "coupler", "rocker"] {
            part = part.replace(&format!("name=\"{body}\""), &format!("name=\"{body}{c}\""));
            part = part.replace(&format!("=\"{body}."), &format!("=\"{body}{c}."));
        }
        for joint in ["crank_pivot", "crank_pin", "rocker_pin", "rocker_pivot"] {
            part = part.replace(&format!("name=\"{joint}\""), &format!("name=\"{joint}{c}\""));
        }
        copies.push_str(&part);
        copies.push('\n');
    }
    let xml = format!("{}{}</multibody>\n", &revolutes[..b0], copies);
    let m = load_str(&xml, "many.xml").unwrap();
    assert_eq!(m.summary().constraints, 20 * k);
    let mut sim = Simulator::new(&m, SimOptions::default(), 0.0).unwrap();
    assert_eq!(sim.system().n() * sim.system().m, 2700 * 3000);
    assert_eq!(sim.system().redundant.iter().filter(|r| **r).count(), 3 * k);
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    assert_eq!(sel.states.len(), k);
    assert_eq!(sel.rank, 17 * k);
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    assert_eq!(lin.a.nrows(), 2 * k);
}
