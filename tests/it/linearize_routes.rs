//! The two ways the factored Eq. 34 yields A, B, C, D — one solve per column (state or
//! input) or one solve of the transposed system per row (Ẇ, Ẋ, an Ṡ without its W, an
//! output) — give the same matrices, on every example model in motion and on a mechanism
//! with inputs and load outputs; and the automatic choice takes the one with fewer
//! solves. (Each route is checked against independent references through the other
//! linearization tests: these run the automatic route.)

use crate::common::{model, moving_examples};
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::{Linearization, Route, linearize_with, select_states};
use mbfmu::model::parse::load_str;

/// Largest |x − y| over the four matrices, relative to 1 + the largest |entry|.
fn difference(a: &Linearization, b: &Linearization) -> f64 {
    let mut worst = 0.0f64;
    for (x, y) in [(&a.a, &b.a), (&a.b, &b.b), (&a.c, &b.c), (&a.d, &b.d)] {
        assert_eq!((x.nrows(), x.ncols()), (y.nrows(), y.ncols()));
        let scale = 1.0
            + (0..x.nrows())
                .flat_map(|i| (0..x.ncols()).map(move |j| (i, j)))
                .fold(0.0f64, |m, (i, j)| m.max(x[(i, j)].abs()));
        for i in 0..x.nrows() {
            for j in 0..x.ncols() {
                worst = worst.max((x[(i, j)] - y[(i, j)]).abs() / scale);
            }
        }
    }
    worst
}

/// Both routes at the simulator's point; their largest relative difference.
fn both(sim: &mut Simulator) -> f64 {
    let sel = select_states(sim.system(), sim.q(), sim.time(), &sim.inputs()).unwrap();
    let cols = linearize_with(sim, &sel, 2, Route::Columns).unwrap();
    let rows = linearize_with(sim, &sel, 2, Route::Rows).unwrap();
    difference(&cols, &rows)
}

#[test]
fn rows_and_columns_give_the_same_linearization() {
    // 1e-10: the two solve different triangular systems with one LU; their round-off
    // is cond(K)·ε, with K's condition numbers here below 1e5.
    for (path, mut sim) in moving_examples() {
        let d = both(&mut sim);
        assert!(d < 1e-10, "{}: routes differ by {d:e}", path.display());
    }
    // Inputs, and outputs that read element loads (their functional differs between
    // state and input columns).
    let mut sim = crate::linearize_loads::moving();
    let d = both(&mut sim);
    assert!(d < 1e-10, "loads mechanism: routes differ by {d:e}");
}

#[test]
fn the_hanging_chain_takes_one_solve_per_velocity_state() {
    // README, Benchmark: on the 1000-link chain Eq. 34 is solved by rows, 1000 solves (the
    // Ẇ rows; Ṡ = W is exact) instead of 2000 by columns. Counted, not timed; both routes
    // agree (above), so the automatic choice only changes the work.
    let chain = load_str(&crate::modes::hanging_spatial_chain(1000), "hang.xml").unwrap();
    let mut sim = Simulator::new(&chain, SimOptions { tol: 1e-8, max_step: None, ..Default::default() }, 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize_with(&mut sim, &sel, 2, Route::Auto).unwrap();
    assert_eq!((sel.states.len(), lin.solves), (1000, 1000));
    // A small model with outputs keeps the column route: the pendulum has 2 states and
    // no inputs, and more output rows than that.
    let pendulum = model("pendulum.xml");
    let mut sim = Simulator::new(&pendulum, SimOptions::default(), 0.0).unwrap();
    let sel = select_states(sim.system(), sim.q(), 0.0, &sim.inputs()).unwrap();
    let lin = linearize_with(&mut sim, &sel, 2, Route::Auto).unwrap();
    assert!(lin.outputs.len() >= 2, "{:?}", lin.outputs);
    assert_eq!(lin.solves, 2);
}
