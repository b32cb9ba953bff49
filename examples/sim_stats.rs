//! Simulate a model file and print integrator statistics and wall time (benchmark aid).
//! Usage: cargo run --release --example sim_stats -- model.xml END [TOL] [MAX_STEPS]

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_file;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = load_file(std::path::Path::new(&args[1])).unwrap_or_else(|e| panic!("{e}"));
    let end: f64 = args.get(2).map_or(1.0, |s| s.parse().expect("END"));
    let tol: f64 = args.get(3).map_or(1e-6, |s| s.parse().expect("TOL"));
    let max_steps: usize = args.get(4).map_or(mbfmu::dae::DEFAULT_MAX_STEPS, |s| s.parse().expect("MAX_STEPS"));
    let t0 = Instant::now();
    let mut sim =
        Simulator::new(&model, SimOptions { tol, max_step: None, max_steps }, 0.0).unwrap_or_else(|e| panic!("{e}"));
    let t_init = t0.elapsed().as_secs_f64();
    sim.advance(end).unwrap_or_else(|e| panic!("{e}"));
    let wall = t0.elapsed().as_secs_f64();
    println!("init {t_init:.3} s, total {wall:.3} s, |C| {:.2e}, {:?}", sim.constraint_residual(), sim.stats());
}
