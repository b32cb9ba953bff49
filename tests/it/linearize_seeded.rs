//! Products with the linearization one seed at a time ([`Seeded`], what FMI directional
//! and adjoint derivatives return): [A B; C D]·e_c is column c and e_rᵀ[A B; C D] is row
//! r of the matrices the full linearization forms, on every example model in motion and
//! on a mechanism with inputs and load outputs; a random seed gives the matrix–vector
//! products; each call costs at most two solves. (The full linearization is checked
//! against independent references by the other linearization tests.)

use crate::common::moving_examples;
use faer::Mat;
use mbfmu::dae::Simulator;
use mbfmu::linearize::{Linearization, Seeded, linearize, select_states};

/// [A B; C D] as one dense matrix.
fn whole(l: &Linearization) -> Mat<f64> {
    let (ns, ni, no) = (l.a.nrows(), l.b.ncols(), l.c.nrows());
    Mat::from_fn(ns + no, ns + ni, |r, c| match (r < ns, c < ns) {
        (true, true) => l.a[(r, c)],
        (true, false) => l.b[(r, c - ns)],
        (false, true) => l.c[(r - ns, c)],
        (false, false) => l.d[(r - ns, c - ns)],
    })
}

/// A deterministic seed in [-1, 1].
fn seed(n: usize, k: u64) -> Vec<f64> {
    (0..n).map(|i| (((i as u64 + 1) * 2654435761 + k * 40503) % 2001) as f64 / 1000.0 - 1.0).collect()
}

/// Largest difference between the seeded products and the full matrix `j` at `sim`'s
/// point, relative to 1 + max |entry|; and the most solves one call took.
fn compare(sim: &mut Simulator) -> (f64, usize) {
    let sel = select_states(sim.system(), sim.q(), sim.time(), &sim.inputs()).unwrap();
    let j = whole(&linearize(sim, &sel, 2).unwrap());
    let mut s = Seeded::at(sim, &sel).unwrap();
    assert_eq!((s.unknowns(), s.knowns()), (j.nrows(), j.ncols()));
    let scale = 1.0
        + (0..j.nrows())
            .flat_map(|r| (0..j.ncols()).map(move |c| (r, c)))
            .fold(0.0f64, |m, (r, c)| m.max(j[(r, c)].abs()));
    let (mut worst, mut most) = (0.0f64, 0);
    let mut call = |s: &mut Seeded, adjoint: bool, v: &[f64]| -> Vec<f64> {
        let before = s.solves();
        let out = if adjoint { s.adjoint(v) } else { s.directional(v) }.unwrap();
        most = most.max(s.solves() - before);
        out
    };
    for c in 0..j.ncols() {
        let mut e = vec![0.0; j.ncols()];
        e[c] = 1.0;
        for (r, v) in call(&mut s, false, &e).iter().enumerate() {
            worst = worst.max((v - j[(r, c)]).abs() / scale);
        }
    }
    for r in 0..j.nrows() {
        let mut e = vec![0.0; j.nrows()];
        e[r] = 1.0;
        for (c, v) in call(&mut s, true, &e).iter().enumerate() {
            worst = worst.max((v - j[(r, c)]).abs() / scale);
        }
    }
    for k in 0..3 {
        let x = seed(j.ncols(), k);
        let jx: Vec<f64> = (0..j.nrows()).map(|r| (0..j.ncols()).map(|c| j[(r, c)] * x[c]).sum()).collect();
        for (a, b) in call(&mut s, false, &x).iter().zip(&jx) {
            worst = worst.max((a - b).abs() / scale);
        }
        let y = seed(j.nrows(), k + 7);
        let yj: Vec<f64> = (0..j.ncols()).map(|c| (0..j.nrows()).map(|r| y[r] * j[(r, c)]).sum()).collect();
        for (a, b) in call(&mut s, true, &y).iter().zip(&yj) {
            worst = worst.max((a - b).abs() / scale);
        }
    }
    (worst, most)
}

#[test]
fn seeded_products_equal_the_full_linearization() {
    // 1e-10 as between the column and row routes (linearize_routes.rs): the same LU,
    // other right-hand sides, round-off cond(K)·ε with cond(K) < 1e5 here.
    for (path, mut sim) in moving_examples() {
        let (d, most) = compare(&mut sim);
        assert!(d < 1e-10, "{}: seeded products differ by {d:e}", path.display());
        assert!(most <= 2, "{}: {most} solves in one call", path.display());
    }
    let mut sim = crate::linearize_loads::moving();
    let (d, most) = compare(&mut sim);
    assert!(d < 1e-10, "loads mechanism: seeded products differ by {d:e}");
    assert!(most <= 2, "loads mechanism: {most} solves in one call");
}
