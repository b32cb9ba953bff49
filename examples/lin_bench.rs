//! Linearization benchmark: for a model file, time the state selection (Eq. 33), the
//! partition check (after Eq. 36) and one linearization (Eq. 34) with 1 and 2 threads,
//! and one integrator Newton iteration for comparison. Linearizes after 0.01 s of motion.
//! Usage: cargo run --release --example lin_bench -- model.xml
//! (bench/lin_chain.sh runs it on the N-link chains of bench/chain.sh.)

use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::partition::check_partition;
use mbfmu::linearize::{linearize, select_states};
use mbfmu::model::parse::load_file;
use std::time::Instant;

fn main() {
    let Some(path) = std::env::args().nth(1).filter(|a| !a.starts_with('-')) else {
        eprintln!("usage: lin_bench model.xml   (times selection, partition check, linearization)");
        std::process::exit(2);
    };
    let model = load_file(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{e}"));
    let t = Instant::now();
    let mut sim = Simulator::new(&model, SimOptions { tol: 1e-6, max_step: None, ..Default::default() }, 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let t_init = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let t_select = t.elapsed().as_secs_f64();
    let t0 = Instant::now();
    sim.advance(0.01).unwrap();
    let st = sim.stats();
    let per_newton = t0.elapsed().as_secs_f64() / st.newton_iterations.max(1) as f64;
    let t = Instant::now();
    check_partition(sim.system(), &sel, sim.q(), sim.time(), &sim.inputs()).unwrap();
    let t_check = t.elapsed().as_secs_f64();
    let mut times = Vec::new();
    for threads in [1, 2] {
        let t = Instant::now();
        let lin = linearize(&mut sim, &sel, threads).unwrap();
        times.push(t.elapsed().as_secs_f64());
        assert!(lin.a.nrows() == 2 * sel.states.len());
    }
    let sys = sim.system();
    println!(
        "{path}: n = {}, m = {}, {} states; initialization {:.3} s; selection {:.3} s; partition check {:.3} s; \
         linearize (check included) {:.3} s (1 thread), {:.3} s (2 threads); \
         one integration step's Newton iteration {:.2e} s (ratio {:.1})",
        sys.n(),
        sys.m,
        sel.states.len(),
        t_init,
        t_select,
        t_check,
        times[0],
        times[1],
        per_newton,
        times[0] / per_newton
    );
}
