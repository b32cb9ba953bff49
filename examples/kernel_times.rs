//! Time the integrator's kernels on a model at its initial point (benchmark aid):
//! f(t, y), J = ∂f/∂y, and the sparse LU of a matrix with J's pattern.
//! Usage: cargo run --release --example kernel_times -- model.xml
use mbfmu::dae::equations::{Layout, RhsScratch, jacobian, rhs};
use mbfmu::dae::sparse::{SparseLu, Triplets};
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_file;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = load_file(std::path::Path::new(&args[1])).unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulator::new(&model, SimOptions::default(), 0.0).unwrap_or_else(|e| panic!("{e}"));
    let sys = sim.system();
    let lay = Layout::of(sys);
    let y = sim.snapshot().y;
    let inputs = sim.inputs();
    let (mut f, mut ws) = (vec![0.0; y.len()], RhsScratch::default());
    let time = |name: &str, reps: usize, mut work: Box<dyn FnMut() + '_>| {
        let t0 = Instant::now();
        for _ in 0..reps {
            work();
        }
        println!("{name}: {:.1} us", t0.elapsed().as_secs_f64() / reps as f64 * 1e6);
    };
    time("rhs", 2000, Box::new(|| rhs(sys, lay, 0.0, &y, &inputs, &mut ws, &mut f)));
    let mut j = Triplets::new();
    time(
        "jacobian",
        200,
        Box::new(|| {
            j.clear();
            jacobian(sys, lay, 0.0, &y, &inputs, &mut j)
        }),
    );
    let n = y.len();
    let mut e = Triplets::new();
    for (p, v) in j.idx.iter().zip(&j.vals) {
        e.push(p.row, p.col, -v);
    }
    for i in 0..n {
        e.push(i, i, 1e3);
    }
    let mut lu = SparseLu::new();
    lu.factor(n, &e).unwrap();
    time("factor n", 200, Box::new(|| lu.factor(n, &e).unwrap()));
    let mut b = vec![1.0; n];
    time(
        "solve n",
        2000,
        Box::new(|| {
            lu.solve(&mut b);
        }),
    );
    println!("dim {n}, nnz(J) {}", j.vals.len());
}
