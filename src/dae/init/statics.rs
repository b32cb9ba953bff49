//! Static equilibrium (`<analysis static="true"/>`): q, λ and the user unknowns with
//! u = 0 and Ẋ = 0, by Newton on the equations of motion at rest (Eq. 1a, 1d, 7).

use super::accelerations::accelerations;
use crate::dae::jacobian::jacobian;
use crate::dae::layout::Layout;
use crate::dae::residual::{RhsScratch, rhs};
use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::body::row_times_t;
use crate::mechanics::nonholonomic_jacobian::nonholonomic_b;

/// Newton iterations before the equilibrium counts as not found.
const MAX_ITERATIONS: usize = 100;

/// The equations and unknowns of the equilibrium, as indices of the DAE vector y (and of
/// its residual, which has the same layout).
struct Subsystem {
    /// Equations: force balance (u rows), algebraic user rows (Ẋ, V, a rows), C (λ rows).
    rows: Vec<usize>,
    /// Unknowns: q, X, V, a, λ, ν (u = 0 and Ẋ = 0 held).
    cols: Vec<usize>,
    /// Position in `rows` of each entry of y (usize::MAX: not an equation).
    row_of: Vec<usize>,
    /// Position in `cols` of each entry of y (usize::MAX: not an unknown).
    col_of: Vec<usize>,
}

impl Subsystem {
    fn of(lay: &Layout) -> Subsystem {
        let rows: Vec<usize> = lay.u_range().chain(lay.z_alg_range()).chain(lay.lam_range()).collect();
        let user_algebraic = lay.v_range().start..lay.acc_range().end;
        let cols: Vec<usize> =
            lay.q_range().chain(lay.x_range()).chain(user_algebraic).chain(lay.multipliers_range()).collect();
        let mut row_of = vec![usize::MAX; lay.dim()];
        let mut col_of = vec![usize::MAX; lay.dim()];
        rows.iter().enumerate().for_each(|(k, &r)| row_of[r] = k);
        cols.iter().enumerate().for_each(|(k, &c)| col_of[c] = k);
        Subsystem { rows, cols, row_of, col_of }
    }
}

/// The rows B T of the non-holonomic constraints at q (dense, one per equation): at rest
/// they hold trivially and their multipliers ν carry loads (e.g. a knife edge across a
/// slope); the positions they leave free to drift are held by B T (q − q0) = 0.
fn held_directions(sys: &System, q: &[f64], t: f64, ext: &[f64]) -> Vec<Vec<f64>> {
    let n = sys.n();
    let mut bt = vec![vec![0.0; n]; sys.mn];
    for (r, c, v) in nonholonomic_b(sys, q, &vec![0.0; n], t, ext).0 {
        bt[r][c] += v;
    }
    bt.iter_mut().for_each(|row| row_times_t(sys.nb(), q, row));
    bt
}

/// Static equilibrium: positions q, multipliers λ and user unknowns with u = 0 and Ẋ = 0:
/// Q(0, q, Z, t) − Pᵀλ = 0, C(q, t) = 0 and the user rows (Eq. 1a, 1d, 7 at rest), by
/// Newton from the assembled configuration with the exact Jacobian of the equations of
/// motion. `z` holds the user unknowns (X, Ẋ, V) in and out; returns λ.
pub fn static_equilibrium(
    sys: &System,
    q: &mut [f64],
    z: &mut [f64],
    t: f64,
    inputs: &[f64],
    tol: f64,
) -> Result<Vec<f64>, String> {
    let n = sys.n();
    let lay = Layout::of(sys);
    let mut y = vec![0.0; lay.dim()];
    y[lay.q_range()].copy_from_slice(q);
    y[lay.z_range()].copy_from_slice(z);
    y[lay.xdot_range()].iter_mut().for_each(|v| *v = 0.0);
    let mut lu = SparseLu::new();
    // Start from the multipliers at rest: the stiffness of a mechanism under gravity is in
    // the reactions' geometric term (Pᵀλ)_q, absent at λ = 0.
    let ext = lay.ext(sys, inputs, &y, t);
    let (_, lam0) = accelerations(sys, q, &vec![0.0; n], t, &ext, &mut lu)?;
    y[lay.lam_range()].copy_from_slice(&lam0[..sys.m]);
    let q0 = q.to_vec();
    let bt = held_directions(sys, q, t, &ext);
    let sub = Subsystem::of(&lay);
    let dim = sub.rows.len() + bt.len();
    let (mut f, mut ws) = (vec![0.0; lay.dim()], RhsScratch::default());
    let scale = 1.0 + sys.bodies.iter().map(|b| b.mass).sum::<f64>() * sys.gravity.iter().map(|g| g.abs()).sum::<f64>();
    for _ in 0..MAX_ITERATIONS {
        rhs(sys, lay, t, &y, inputs, &mut ws, &mut f);
        let mut r: Vec<f64> = sub.rows.iter().map(|&i| f[i]).collect();
        r.extend(bt.iter().map(|row| row.iter().zip(y.iter().zip(&q0)).map(|(b, (x, x0))| b * (x - x0)).sum::<f64>()));
        let worst = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !worst.is_finite() {
            return Err("static equilibrium: the equations are not finite".into());
        }
        if worst <= tol * scale {
            q.copy_from_slice(&y[lay.q_range()]);
            z.copy_from_slice(&y[lay.z_range()]);
            return Ok(y[lay.lam_range()].to_vec());
        }
        let mut jt = Triplets::new();
        jacobian(sys, lay, t, &y, inputs, &mut jt);
        let mut k = Triplets::new();
        for (p, &v) in jt.idx.iter().zip(&jt.vals) {
            let (rr, cc) = (sub.row_of[p.row], sub.col_of[p.col]);
            if rr != usize::MAX && cc != usize::MAX {
                k.push(rr, cc, v);
            }
        }
        for (i, row) in bt.iter().enumerate() {
            for (c, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                k.push(sub.rows.len() + i, c, v);
            }
        }
        lu.factor(dim, &k).map_err(|e| format!("static equilibrium: singular equations ({e})"))?;
        r.iter_mut().for_each(|v| *v = -*v);
        if !lu.solve(&mut r) {
            return Err("static equilibrium: singular equations (a free body or mechanism without stiffness?)".into());
        }
        for (k, &c) in sub.cols.iter().enumerate() {
            y[c] += r[k];
        }
    }
    Err(format!("static equilibrium: Newton did not converge in {MAX_ITERATIONS} iterations"))
}
