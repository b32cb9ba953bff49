//! The sparse complete-pivoting elimination (dae::rank) against faer's dense full-pivoting
//! LU: same rank, same pivot rows and columns in the same order, same pivot magnitudes
//! (1e-12 relative), on random sparse matrices of known rank and on the example models'
//! constraint Jacobians; and the example models keep the states chosen by Eq. 33.

use crate::common::model_dir;
use mbfmu::dae::rank::full_pivot;
use mbfmu::dae::{SimOptions, Simulator};
use mbfmu::linearize::select_states;
use mbfmu::mechanics::System;
use mbfmu::mechanics::body::NQ;
use mbfmu::mechanics::kernels::constraint_first;
use mbfmu::model::parse::{load_file, load_str};

/// Rank, pivot rows, pivot columns and |pivots| of the dense full-pivoting LU, the rank
/// decided as the engine did: pivots > tol·max(largest pivot, floor).
fn dense(
    nrows: usize,
    ncols: usize,
    t: &[(usize, usize, f64)],
    tol: f64,
    floor: f64,
) -> (usize, Vec<usize>, Vec<usize>, Vec<f64>) {
    let mut a = faer::Mat::<f64>::zeros(nrows, ncols);
    for &(r, c, v) in t {
        a[(r, c)] += v;
    }
    let lu = a.full_piv_lu();
    let u = lu.U();
    let k = nrows.min(ncols);
    let piv: Vec<f64> = (0..k).map(|i| u[(i, i)].abs()).collect();
    let big = piv.iter().copied().fold(0.0, f64::max).max(floor);
    let rank = piv.iter().take_while(|&&p| p > tol * big).count();
    let rows = lu.P().arrays().0[..rank].to_vec();
    let cols = lu.Q().arrays().0[..rank].to_vec();
    (rank, rows, cols, piv[..rank].to_vec())
}

/// Compare sparse and dense on one matrix; returns the rank.
fn agree(nrows: usize, ncols: usize, t: &[(usize, usize, f64)], tol: f64, floor: f64, what: &str) -> usize {
    let s = full_pivot(nrows, ncols, t.iter().copied(), tol, floor).unwrap();
    let (rank, rows, cols, mags) = dense(nrows, ncols, t, tol, floor);
    assert_eq!(s.rank, rank, "{what}: rank");
    assert_eq!(s.cols, cols, "{what}: pivot columns");
    assert_eq!(s.rows, rows, "{what}: pivot rows");
    for (k, (x, y)) in s.magnitudes.iter().zip(&mags).enumerate() {
        assert!((x - y).abs() <= 1e-12 * y, "{what}: pivot {k}: {x} vs {y}");
    }
    rank
}

/// xorshift64*: reproducible values without a dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    /// Uniform in [−2, −0.5] ∪ [0.5, 2].
    fn value(&mut self) -> f64 {
        let x = 0.5 + 1.5 * (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        if self.next() & 1 == 0 { x } else { -x }
    }
    fn perm(&mut self, n: usize) -> Vec<usize> {
        let mut p: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            p.swap(i, self.below(i + 1));
        }
        p
    }
}

/// A random sparse rows×cols factor of full rank min(rows, cols): a transversal of
/// non-zeros on a random permutation plus `extra` random entries per row.
fn factor(rng: &mut Rng, rows: usize, cols: usize, extra: usize) -> Vec<Vec<(usize, f64)>> {
    let mut a = vec![Vec::new(); rows];
    let (pr, pc) = (rng.perm(rows), rng.perm(cols));
    for k in 0..rows.min(cols) {
        a[pr[k]].push((pc[k], 2.0 * rng.value()));
    }
    for row in a.iter_mut() {
        for _ in 0..extra {
            row.push((rng.below(cols), rng.value()));
        }
    }
    a
}

#[test]
fn random_sparse_products_of_known_rank_match_dense_full_pivoting() {
    // B (m×r) C (r×n) with r = min(m, n) − d has rank r; the rounding left after r steps
    // is ~1e-15 relative, far below the rank tolerance 1e-9.
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut cases = 0;
    for &(m, n) in &[(8, 8), (20, 30), (45, 35), (60, 60), (120, 150), (200, 160)] {
        for d in 0..=3 {
            for _ in 0..3 {
                let r = m.min(n) - d;
                let b = factor(&mut rng, m, r, 1);
                let c = factor(&mut rng, r, n, 2);
                let mut t = Vec::new();
                for (i, row) in b.iter().enumerate() {
                    for &(k, bv) in row {
                        for &(j, cv) in &c[k] {
                            t.push((i, j, bv * cv));
                        }
                    }
                }
                let rank = agree(m, n, &t, 1e-9, 0.0, &format!("{m}x{n} rank {r}"));
                assert_eq!(rank, r, "{m}x{n}: known rank");
                cases += 1;
            }
        }
    }
    assert_eq!(cases, 72);
}

/// C_q of a system as triplets (constraint row, coordinate, value).
fn cq(sys: &System, q: &[f64], inputs: &[f64]) -> Vec<(usize, usize, f64)> {
    let mut t = Vec::new();
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, 0.0, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            for a in 0..nql {
                t.push((el.row + e, NQ * el.bodies[a / NQ] + a % NQ, f.cq[e * nql + a]));
            }
        }
    }
    t
}

#[test]
fn example_models_constraint_jacobians_match_dense_full_pivoting() {
    // Mechanism Jacobians have exact ties (entries ±1, repeated lever arms) which the two
    // break differently: on C_q itself only the rank must agree; with the rows and columns
    // scaled by distinct factors 1 + 0.01·random (ties broken, same structure and rank)
    // the whole pivot sequence must.
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut checked = 0;
    for path in crate::common::model_files() {
        let model = load_file(&path).unwrap();
        let sim = Simulator::new(&model, SimOptions::default(), 0.0).unwrap();
        let sys = sim.system();
        let (m, n) = (sys.m, sys.n());
        let t = cq(sys, sim.q(), &sim.inputs());
        let what = path.display().to_string();
        let tr = |t: &[(usize, usize, f64)]| t.iter().map(|&(r, c, v)| (c, r, v)).collect::<Vec<_>>();
        // As for state selection (rows = constraints) and for redundancy (C_qᵀ).
        let rank = full_pivot(m, n, t.iter().copied(), 1e-9, 1.0).unwrap().rank;
        assert_eq!(rank, dense(m, n, &t, 1e-9, 1.0).0, "{what}: rank");
        let rank_t = full_pivot(n, m, tr(&t), 1e-6, 0.0).unwrap().rank;
        assert_eq!(rank_t, dense(n, m, &tr(&t), 1e-6, 0.0).0, "{what}: rank of C_qᵀ");
        let rs: Vec<f64> = (0..m).map(|_| 1.0 + 0.01 * rng.value()).collect();
        let cs: Vec<f64> = (0..n).map(|_| 1.0 + 0.01 * rng.value()).collect();
        let scaled: Vec<_> = t.iter().map(|&(r, c, v)| (r, c, v * rs[r] * cs[c])).collect();
        assert_eq!(agree(m, n, &scaled, 1e-9, 1.0, &format!("{what} scaled")), rank);
        assert_eq!(agree(n, m, &tr(&scaled), 1e-6, 0.0, &format!("{what} scaled, transposed")), rank_t);
        checked += 1;
    }
    assert!(checked >= 8, "{checked} models");
}

#[test]
fn example_models_keep_their_states() {
    // The states chosen by Eq. 33 (user states, then joint coordinates, then body
    // coordinates), as written and without <linearization>.
    let expect: &[(&str, &[&str])] = &[
        ("blade_alpha.xml", &["alpha"]),
        ("blade_y.xml", &["yb"]),
        ("double_pendulum.xml", &["alpha1", "alpha2"]),
        ("fourbar.xml", &["crank_pivot.angle"]),
        ("pendulum.xml", &["hinge.angle"]),
        ("slider_crank.xml", &[]),
        ("spinning_top.xml", &["pivot.yaw", "pivot.pitch", "pivot.roll"]),
        ("spring_mass_damper.xml", &["guide.displacement"]),
        ("torque_free_body.xml", &["box.x", "box.y", "box.z", "box.psi", "box.theta", "box.phi"]),
    ];
    for (file, states) in expect {
        let text = std::fs::read_to_string(model_dir().join(file)).unwrap();
        let mut variants = vec![text.clone()];
        if let (Some(a), Some(b)) = (text.find("<linearization>"), text.find("</linearization>")) {
            variants.push(format!("{}{}", &text[..a], &text[b + "</linearization>".len()..]));
        }
        for (k, xml) in variants.iter().enumerate() {
            let model = load_str(xml, file).unwrap();
            let t0 = model.experiment.start.unwrap_or(0.0);
            let sim = Simulator::new(&model, SimOptions::default(), t0).unwrap();
            let sel = select_states(sim.system(), sim.q(), t0, &sim.inputs()).unwrap();
            let names: Vec<&str> = sel.states.iter().map(|s| s.name.as_str()).collect();
            let want: &[&str] = match (k, *file) {
                (0, _) => states,
                (_, "double_pendulum.xml") => &["hinge1.angle", "hinge2.angle"],
                _ => &["flap.angle"],
            };
            assert_eq!(names, want, "{file} variant {k}");
        }
    }
}
