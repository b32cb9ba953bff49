//! Time the integrator's kernels on a model at its initial point (benchmark aid):
//! f(t, y), J = ∂f/∂y, and both LUs (block and general) of the real and the complex
//! iteration matrix of a 1 ms Radau step.
//! Usage: cargo run --release --example kernel_times -- model.xml [kernel ...]
//! Kernels: rhs, jacobian, block, general (all when none is named; name one to profile
//! it alone under `perf`); `exact`: the exact J instead of the integrator's iteration
//! approximation (`JacScratch::within_bodies`).
use faer::c64;
use faer::sparse::Pair;
use mbfmu::dae::block_lu::BlockLu;
use mbfmu::dae::equations::{Layout, RhsScratch, mass_matrix, rhs};
use mbfmu::dae::jacobian::{JacScratch, jacobian_with};
use mbfmu::dae::sparse::{SparseLu, Triplets};
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_file;
use std::time::Instant;

/// Radau IIA's γ, α, β (the eigenvalues of the inverse of its coefficient matrix).
const GAMMA: f64 = 3.637_834_252_744_496;
const ALPHA: f64 = 2.681_082_873_627_752;
const BETA: f64 = 3.050_430_199_247_41;

/// The fastest of 10 batches of `reps` calls, per call (the minimum filters a shared
/// machine's noise).
fn time(name: &str, reps: usize, mut work: impl FnMut()) {
    let best = (0..10)
        .map(|_| {
            let t0 = Instant::now();
            for _ in 0..reps {
                work();
            }
            t0.elapsed().as_secs_f64() / reps as f64
        })
        .fold(f64::INFINITY, f64::min);
    println!("{name}: {:.1} us", best * 1e6);
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let named: Vec<&String> = args.iter().skip(2).filter(|a| *a != "exact").collect();
    let want = |k: &str| named.is_empty() || named.iter().any(|a| *a == k);
    let exact = args.iter().skip(2).any(|a| a == "exact");
    let model = load_file(std::path::Path::new(&args[1])).unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulator::new(&model, SimOptions::default(), 0.0).unwrap_or_else(|e| panic!("{e}"));
    let sys = sim.system();
    let lay = Layout::of(sys);
    let y = sim.snapshot().y;
    let inputs = sim.inputs();
    let n = y.len();
    let (mut f, mut ws) = (vec![0.0; n], RhsScratch::default());
    if want("rhs") {
        time("rhs", 500, || rhs(sys, lay, 0.0, &y, &inputs, &mut ws, &mut f));
    }
    let (mut j, mut js) = (Triplets::new(), JacScratch::default());
    js.within_bodies = !exact;
    jacobian_with(sys, lay, 0.0, &y, &inputs, &mut js, &mut j);
    if want("jacobian") {
        time("jacobian", 50, || {
            j.clear();
            jacobian_with(sys, lay, 0.0, &y, &inputs, &mut js, &mut j)
        });
    }
    // The iteration matrices of a 1 ms step: γ/h M − J and (α − iβ)/h M − J.
    let h = 1e-3;
    let mut m = Triplets::new();
    mass_matrix(sys, lay, &mut m);
    let idx: Vec<Pair<usize, usize>> = j.idx.iter().chain(&m.idx).copied().collect();
    let e1: Vec<f64> = j.vals.iter().map(|v| -v).chain(m.vals.iter().map(|v| GAMMA / h * v)).collect();
    let e2: Vec<c64> = j
        .vals
        .iter()
        .map(|v| c64::new(-v, 0.0))
        .chain(m.vals.iter().map(|v| c64::new(ALPHA / h * v, -BETA / h * v)))
        .collect();
    let groups = lay.groups(sys);
    let (r1, r2) = (vec![1.0; n], vec![c64::new(1.0, 0.5); n]);
    let (mut b1, mut b2) = (r1.clone(), r2.clone());
    if want("block") {
        let (mut l1, mut l2) = (BlockLu::<f64>::default(), BlockLu::<c64>::default());
        l1.factor(n, &idx, &e1, &groups).unwrap();
        l2.factor(n, &idx, &e2, &groups).unwrap();
        time("block factor real", 50, || l1.factor(n, &idx, &e1, &groups).unwrap());
        time("block factor complex", 50, || l2.factor(n, &idx, &e2, &groups).unwrap());
        time("block solve real", 500, || {
            b1.copy_from_slice(&r1);
            assert!(l1.solve(&mut b1))
        });
        time("block solve complex", 500, || {
            b2.copy_from_slice(&r2);
            assert!(l2.solve(&mut b2))
        });
    }
    if want("general") {
        let (mut l1, mut l2) = (SparseLu::<f64>::default(), SparseLu::<c64>::default());
        l1.factor_values(n, &idx, &e1).unwrap();
        l2.factor_values(n, &idx, &e2).unwrap();
        time("general factor real", 50, || l1.factor_values(n, &idx, &e1).unwrap());
        time("general factor complex", 50, || l2.factor_values(n, &idx, &e2).unwrap());
        time("general solve real", 500, || {
            b1.copy_from_slice(&r1);
            assert!(l1.solve(&mut b1))
        });
        time("general solve complex", 500, || {
            b2.copy_from_slice(&r2);
            assert!(l2.solve(&mut b2))
        });
    }
    println!("dim {n}, nnz(J) {}", j.vals.len());
}
