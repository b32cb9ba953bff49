//! SparseLu::solve_columns: right-hand sides given column by column, solved in blocks over
//! several threads, agree with one-column solves and satisfy A x = b (residual ≤ 1e-12
//! relative to |b| + |A||x|); a singular matrix gives None.

use mbfmu::dae::sparse::{SparseLu, Triplets};

/// A diagonally dominant n×n matrix with a few off-diagonal entries per row.
fn matrix(n: usize) -> Triplets {
    let mut t = Triplets::new();
    for i in 0..n {
        t.push(i, i, 4.0 + (i % 7) as f64);
        for k in [1, 5, 37] {
            t.push(i, (i + k) % n, 0.5 - 0.01 * (i % 11) as f64);
            t.push((i + k) % n, i, -0.25 + 0.02 * (i % 5) as f64);
        }
    }
    t
}

/// Column j: a unit vector for even j, a few entries for odd j.
fn rhs(j: usize, b: &mut [f64]) {
    let n = b.len();
    if j.is_multiple_of(2) {
        b[(7 * j) % n] = 1.0;
    } else {
        for k in 0..5 {
            b[(j * 13 + k * 31) % n] += 1.0 + k as f64;
        }
    }
}

#[test]
fn block_solves_over_threads_match_single_solves() {
    let n = 300;
    let t = matrix(n);
    let mut lu = SparseLu::new();
    lu.factor(n, &t).unwrap();
    let ncols = 53; // several blocks, a partial last one
    for threads in [1, 2, 3] {
        let sol = lu.solve_columns(ncols, threads, false, rhs, |j, x| (j, x.to_vec())).unwrap();
        assert_eq!(sol.len(), ncols);
        for (k, (j, x)) in sol.iter().enumerate() {
            assert_eq!(k, *j, "columns in order");
            let mut b = vec![0.0; n];
            rhs(*j, &mut b);
            let mut single = b.clone();
            assert!(lu.solve(&mut single));
            let mut ax = vec![0.0; n];
            t.mul_add(x, &mut ax);
            let mut abs_ax = vec![0.0; n];
            for (p, v) in t.idx.iter().zip(&t.vals) {
                abs_ax[p.row] += (v * x[p.col]).abs();
            }
            for i in 0..n {
                assert!((ax[i] - b[i]).abs() <= 1e-12 * (b[i].abs() + abs_ax[i]), "col {j} row {i}");
                assert!((x[i] - single[i]).abs() <= 1e-12 * single[i].abs().max(1e-3), "col {j} row {i}");
            }
        }
    }
}

#[test]
fn singular_matrix_gives_none() {
    // Two equal rows: faer's sparse LU factors it (a zero pivot), the solutions are not finite.
    let mut t = Triplets::new();
    for i in 0..4 {
        t.push(i, i, 1.0);
    }
    t.push(3, 2, 1.0);
    t.push(2, 3, 1.0);
    let mut lu = SparseLu::new();
    lu.factor(4, &t).unwrap();
    assert!(lu.solve_columns(3, 2, false, |j, b| b[j + 1] = 1.0, |_, x| x.to_vec()).is_none());
}
