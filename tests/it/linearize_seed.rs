//! The seed paper's helicopter blade (Fig. 1, Eq. 16–23): the same mechanism linearized in
//! two different user states gives the two different, exactly known eigenvalue pairs.

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::eigen::eigen_table;
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_file;

fn blade_eigen(file: &str) -> (Vec<String>, f64, f64) {
    let m = load_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models").join(file)).unwrap();
    let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize(&mut sim, &sel, 2).unwrap();
    let rows = eigen_table(&lin.a).unwrap();
    assert_eq!(rows.len(), 1, "{rows:?}");
    (lin.states.clone(), rows[0].re, rows[0].im)
}

#[test]
fn blade_in_alpha_has_the_eigenvalues_of_eq_21() {
    // λ = ±i w sqrt(m e l / (I + m l²)) (Eq. 21); 1e-9 relative: the linearization is
    // exact, so only round-off in the sparse solve and the 2×2 eigenproblem remains.
    let (states, re, im) = blade_eigen("blade_alpha.xml");
    assert_eq!(states, ["alpha", "der(alpha)"]);
    let want = 10.0 * (3.0f64 * 2.0 * 10.0 / (10.0 + 3.0 * 100.0)).sqrt();
    assert!(re.abs() < 1e-9 * want, "re {re}");
    assert!((im - want).abs() < 1e-9 * want, "{im} vs {want}");
    assert!((im - 4.3994).abs() < 5e-5, "seed's printed value");
}

#[test]
fn blade_in_y_has_the_eigenvalues_of_eq_23() {
    let (states, re, im) = blade_eigen("blade_y.xml");
    assert_eq!(states, ["yb", "der(yb)"]);
    let want = 10.0 * (3.0f64 * 2.0 * 10.0 / (10.0 + 3.0 * 100.0) + 1.0).sqrt();
    assert!(re.abs() < 1e-9 * want, "re {re}");
    assert!((im - want).abs() < 1e-9 * want, "{im} vs {want}");
    assert!((im - 10.92496).abs() < 5e-6, "seed's printed value");
}
