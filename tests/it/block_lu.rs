//! The block LU along the mechanism's graph (`dae::block_lu`) on the integrator's real
//! iteration matrices: for every example model in motion, γ/h M − J (h = 1 ms and
//! 100 ms) and the complex-pair matrix (α − iβ)/h M − J factor by blocks, and their
//! solutions have a backward error at round-off and agree with faer's general sparse LU
//! with row pivoting, an independent method (bounds at `compare`). The
//! integrator's statistics show that no factorization fell back to the general LU.

use crate::common::moving_examples;
use faer::c64;
use faer::sparse::Pair;
use mbfmu::dae::block_lu::BlockLu;
use mbfmu::dae::equations::{Layout, jacobian, mass_matrix};
use mbfmu::dae::sparse::{LuScalar, SparseLu, Triplets};

/// RADAU5's γ and α ± iβ: the real eigenvalue and the complex pair of the inverse of
/// the 3-stage Radau IIA matrix (Hairer & Wanner, IV.8).
const GAMMA: f64 = 3.637834252744496;
const ALPHA: f64 = 2.681082873627752;
const BETA: f64 = 3.050430199247411;

/// The normwise backward error ‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞).
fn backward_error<T: LuScalar>(n: usize, idx: &[Pair<usize, usize>], vals: &[T], x: &[T], b: &[T]) -> f64 {
    let mut r: Vec<T> = b.iter().map(|v| <T as LuScalar>::zero() - *v).collect();
    let mut rows = vec![0.0f64; n];
    for (p, v) in idx.iter().zip(vals) {
        r[p.row] += *v * x[p.col];
        rows[p.row] += v.magnitude();
    }
    let inf = |v: &[T]| v.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
    inf(&r) / (rows.iter().fold(0.0f64, |m, v| m.max(*v)) * inf(x) + inf(b))
}

/// Factor by blocks and by the general LU, solve three right-hand sides with each: the
/// block solution's backward error is at round-off (≤ 1e-14, normwise; the general LU's is shown
/// with it) and the two solutions agree to 1e-7 relative to |x|: round-off times the
/// condition number, which the suspension's 10⁹ N/m modal stiffness against its rigid
/// inertias makes large (measured: 5e-9 there, below 1e-12 on the rigid models).
fn compare<T: LuScalar>(name: &str, n: usize, idx: &[Pair<usize, usize>], vals: &[T], groups: &[usize]) {
    let mut blu = BlockLu::<T>::default();
    blu.factor(n, idx, vals, groups).unwrap_or_else(|e| panic!("{name}: the block LU refused: {e}"));
    let mut glu = SparseLu::<T>::default();
    glu.factor_values(n, idx, vals).unwrap_or_else(|e| panic!("{name}: {e}"));
    for k in 0..3 {
        let b: Vec<T> = (0..n).map(|i| vals[(i * 7 + k * 13) % vals.len()] + <T as LuScalar>::one()).collect();
        let (mut x, mut xg) = (b.clone(), b.clone());
        assert!(blu.solve(&mut x) && glu.solve(&mut xg), "{name}: not finite");
        let (eb, eg) = (backward_error(n, idx, vals, &x, &b), backward_error(n, idx, vals, &xg, &b));
        let size = xg.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
        let diff = x.iter().zip(&xg).fold(0.0f64, |m, (a, b)| m.max((*a - *b).magnitude()));
        eprintln!("{name}: backward error {eb:.1e} (general {eg:.1e}), difference {:.1e}", diff / size);
        assert!(eb <= 1e-14, "{name}: backward error {eb:e} (general LU: {eg:e})");
        assert!(diff <= 1e-7 * size, "{name}: block and general LU differ by {diff:e} (|x| {size:e})");
    }
}

#[test]
fn example_iteration_matrices_factor_by_blocks_as_the_general_lu_does() {
    for (path, sim) in moving_examples() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let sys = sim.system();
        let lay = Layout::of(sys);
        let y = sim.snapshot().y;
        let mut jac = Triplets::new();
        jacobian(sys, lay, sim.time(), &y, &sim.inputs(), &mut jac);
        let mut mass = Triplets::new();
        mass_matrix(sys, lay, &mut mass);
        let groups = lay.groups(sys);
        let n = lay.dim();
        let idx: Vec<Pair<usize, usize>> = jac.idx.iter().chain(&mass.idx).copied().collect();
        for h in [1e-3, 1e-1] {
            let real: Vec<f64> = jac.vals.iter().map(|v| -v).chain(mass.vals.iter().map(|v| GAMMA / h * v)).collect();
            compare(&format!("{name}, h = {h}, real"), n, &idx, &real, &groups);
            let complex: Vec<c64> = jac
                .vals
                .iter()
                .map(|v| c64::new(-v, 0.0))
                .chain(mass.vals.iter().map(|v| c64::new(ALPHA / h * v, -BETA / h * v)))
                .collect();
            compare(&format!("{name}, h = {h}, complex"), n, &idx, &complex, &groups);
        }
        assert_eq!(sim.stats().general_factorizations, 0, "{name}: {:?}", sim.stats());
        assert!(sim.stats().factorizations > 0, "{name}");
    }
}
