//! The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab, Proc. R. Soc. A
//! 463, 2007): the full non-linear multibody model (4 bodies, 3 revolute joints, 2 rolling
//! wheels: 4 non-holonomic rows, s0 = 7, s1 = 3) linearized by Eq. 34 about upright straight
//! running, against the paper's published linearized equations
//! M q̈ + v C1 q̇ + (g K0 + v² K2) q = 0, q = (lean, steer) (benchmark values, 14 digits).

use faer::Mat;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_file;

/// The paper's eigenvalues at speed v (from its M, C1, K0, K2; g = 9.81).
fn reference(v: f64) -> Vec<(f64, f64)> {
    let m = [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]];
    let c1 = [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]];
    let k0 = [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]];
    let k2 = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let mi = [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]];
    let mut a = Mat::<f64>::zeros(4, 4);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    for r in 0..2 {
        for c in 0..2 {
            let k: f64 = (0..2).map(|j| mi[r][j] * (9.81 * k0[j][c] + v * v * k2[j][c])).sum();
            let d: f64 = (0..2).map(|j| mi[r][j] * v * c1[j][c]).sum();
            a[(2 + r, c)] = -k;
            a[(2 + r, 2 + c)] = -d;
        }
    }
    a.eigenvalues().unwrap().iter().map(|z| (z.re, z.im)).collect()
}

#[test]
fn benchmark_bicycle_eigenvalues_match_the_published_linearized_equations() {
    // At 2, 5 (self-stable) and 8 m/s: every eigenvalue of the paper's 4th-order lean/steer
    // system is an eigenvalue of the engine's 10 × 10 A to 1e-8·max(1, |λ|) (exact
    // linearization vs a 14-digit reference); the other six are zero (s0 − s1 = 4
    // integrating positions, the conserved rear-wheel rate and the heading).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/benchmark_bicycle.xml");
    let base = load_file(&path).unwrap();
    for v in [2.0, 5.0, 8.0] {
        let mut p = base.param_values();
        p[base.parameters.iter().position(|x| x.name == "v").unwrap()] = v;
        let m = base.with_params(&p).unwrap();
        let mut sim = Simulator::new(&m, SimOptions { tol: 1e-10, max_step: None, ..Default::default() }, 0.0).unwrap();
        let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
        assert_eq!((sel.states.len(), sel.velocities.len()), (7, 3));
        let lin = linearize(&mut sim, &sel, 2).unwrap();
        let got: Vec<(f64, f64)> = lin.a.eigenvalues().unwrap().iter().map(|z| (z.re, z.im)).collect();
        for (re, im) in reference(v) {
            let (best, _) = got
                .iter()
                .map(|g| (((g.0 - re).powi(2) + (g.1 - im).powi(2)).sqrt(), g))
                .fold((f64::INFINITY, (0.0, 0.0)), |a, (d, g)| if d < a.0 { (d, *g) } else { a });
            let mag = (re * re + im * im).sqrt();
            assert!(best < 1e-8 * mag.max(1.0), "v = {v}: reference {re} {im}i not found (error {best:e}) in {got:?}");
        }
        let zeros = got.iter().filter(|g| (g.0 * g.0 + g.1 * g.1).sqrt() < 1e-5).count();
        assert_eq!(zeros, 6, "v = {v}: {got:?}");
    }
}
