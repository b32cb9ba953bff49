//! Simulate a model in communication steps and print integrator statistics and wall
//! time (benchmark aid). Usage: cargo run --release --example step_stats -- model.xml
//! END STEP [TOL] [NAME=VALUE ...]
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::model::parse::load_file;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut model = load_file(std::path::Path::new(&args[1])).unwrap_or_else(|e| panic!("{e}"));
    let end: f64 = args[2].parse().expect("END");
    let step: f64 = args[3].parse().expect("STEP");
    let tol: f64 = args.get(4).map_or(1e-6, |s| s.parse().expect("TOL"));
    for a in args.iter().skip(5) {
        let (k, v) = a.split_once('=').expect("NAME=VALUE");
        model.state_starts.push((k.to_string(), v.parse().expect("VALUE")));
    }
    let t0 = Instant::now();
    let mut sim =
        Simulator::new(&model, SimOptions { tol, ..Default::default() }, 0.0).unwrap_or_else(|e| panic!("{e}"));
    let t_init = t0.elapsed().as_secs_f64();
    let n = (end / step).round() as usize;
    for k in 1..=n {
        sim.advance(k as f64 * step).unwrap_or_else(|e| panic!("{e}"));
    }
    let wall = t0.elapsed().as_secs_f64() - t_init;
    println!(
        "init {t_init:.3} s, steps {wall:.3} s ({:.1} us/comm step), q[last] {:?}",
        wall / n as f64 * 1e6,
        sim.q().last()
    );
    println!("{:?}", sim.stats());
}
