//! The augmented sensitivity system (seed Eq. 34a–34k, Table 1): unknowns
//! (u̇, q̇, Ẇ, Ṡ, λ, u, q, W, S) differentiated with respect to the virtual states (S̄, W̄)
//! and the inputs v. One sparse matrix, one sparse LU, the right-hand sides in blocks
//! (split over threads), keeping only the rows A, B, C, D need. Nothing is reduced to
//! the state-space ODE (Eq. 6).

use super::jets::{PositionFn, jets};
use super::outputs::{OutputGradient, output_gradient};
use super::select::Selection;
use crate::dae::equations::{Layout, jacobian};
use crate::dae::rank::full_pivot;
use crate::dae::sparse::{SparseLu, Triplets};
use crate::dae::{EngineError, Simulator};
use crate::mechanics::body::NQ;
use crate::mechanics::kernels::force_input_jacobian;
use faer::Mat;

/// A, B, C, D at one operating point, with the names of states, inputs and outputs.
#[derive(Clone, Debug)]
pub struct Linearization {
    pub time: f64,
    /// State names: S then W (`der(S)`).
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// Row-major matrices: A (2s × 2s), B (2s × ni), C (no × 2s), D (no × ni).
    pub a: Mat<f64>,
    pub b: Mat<f64>,
    pub c: Mat<f64>,
    pub d: Mat<f64>,
    /// Values of the states S and W at the operating point.
    pub x: Vec<f64>,
}

/// Column (unknown) and row (equation) offsets of Eq. 34.
struct Blocks {
    n: usize,
    m: usize,
    /// Independent constraint rows (m minus the redundant ones): 34d–e have this many.
    mr: usize,
    s: usize,
}

impl Blocks {
    fn ud(&self) -> usize {
        0
    }
    fn qd(&self) -> usize {
        self.n
    }
    fn wd(&self) -> usize {
        2 * self.n
    }
    fn sd(&self) -> usize {
        2 * self.n + self.s
    }
    fn lam(&self) -> usize {
        2 * self.n + 2 * self.s
    }
    fn u(&self) -> usize {
        2 * self.n + 2 * self.s + self.m
    }
    fn q(&self) -> usize {
        3 * self.n + 2 * self.s + self.m
    }
    fn w(&self) -> usize {
        4 * self.n + 2 * self.s + self.m
    }
    fn sv(&self) -> usize {
        4 * self.n + 3 * self.s + self.m
    }
    fn dim(&self) -> usize {
        4 * self.n + 4 * self.s + self.m
    }
    // Rows: 34a n, 34b n, 34c m (redundant rows: λ = 0), 34d mr, 34e mr, 34f..34k s each.
    fn row(&self, eq: char) -> usize {
        let (n, m, mr, s) = (self.n, self.m, self.mr, self.s);
        let f = 2 * n + m + 2 * mr;
        match eq {
            'a' => 0,
            'b' => n,
            'c' => 2 * n,
            'd' => 2 * n + m,
            'e' => 2 * n + m + mr,
            'f' => f,
            'g' => f + s,
            'h' => f + 2 * s,
            'i' => f + 3 * s,
            'j' => f + 4 * s,
            _ => f + 5 * s,
        }
    }
}

/// The smallest pivot of [C_q; s_q] relative to the largest, below which the states no
/// longer parameterize the positions (Eq. 34e–f not solvable for q).
const PARTITION_TOL: f64 = 1e-8;

/// Check that the states still parameterize the motion here (the determinant condition
/// after Eq. 36): sparse complete-pivoting elimination of the square [C_q; s_q].
pub fn check_partition(
    sys: &crate::mechanics::System,
    sel: &Selection,
    q: &[f64],
    t: f64,
    inputs: &[f64],
) -> Result<(), EngineError> {
    let n = sys.n();
    let zeros = vec![0.0; n];
    let mut j: Vec<(usize, usize, f64)> = Vec::new();
    let mut row = 0;
    for el in &sys.constraints {
        for (e, jet) in jets(sys, el, q, &zeros, &zeros, t, inputs).iter().enumerate() {
            if sys.redundant[el.row + e] {
                continue;
            }
            for (a, &b) in el.bodies.iter().enumerate() {
                for c in 0..NQ {
                    j.push((row, NQ * b + c, jet.dg[NQ * a + c]));
                }
            }
            row += 1;
        }
    }
    for st in &sel.states {
        let jet = &jets(sys, st, q, &zeros, &zeros, t, inputs)[0];
        if row >= n {
            break;
        }
        for (a, &b) in st.bodies().iter().enumerate() {
            for c in 0..NQ {
                j.push((row, NQ * b + c, jet.dg[NQ * a + c]));
            }
        }
        row += 1;
    }
    // Stops at the first pivot ≤ PARTITION_TOL·largest: then the next candidate is the ratio.
    let ratio = match full_pivot(n, n, j, PARTITION_TOL, 0.0) {
        Ok(p) if p.rank == n => {
            let small = p.magnitudes.iter().copied().fold(f64::INFINITY, f64::min);
            small / p.largest()
        }
        Ok(p) => p.remaining / p.largest().max(p.remaining),
        Err(_) => f64::NAN,
    };
    if ratio.is_nan() || ratio <= PARTITION_TOL {
        return Err(EngineError::Numeric(format!(
            "at t = {t}: the linearization states ({}) no longer parameterize the motion (singular partition, \
             pivot ratio {:.1e}); choose user states (<linearization>) that stay independent",
            sel.states.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", "),
            ratio
        )));
    }
    Ok(())
}

/// Linearize the simulation at its current point in the states of `sel` (Eq. 34, 36).
pub fn linearize(sim: &mut Simulator, sel: &Selection, threads: usize) -> Result<Linearization, EngineError> {
    let (udot, lam) = sim.accelerations()?;
    let t = sim.time();
    let inputs = sim.inputs();
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let sys = sim.system();
    let (n, m, s) = (sys.n(), sys.m, sel.states.len());
    // Compact index of each independent constraint row (rows of 34d–e).
    let mut cmap = vec![None; m];
    let mut mr = 0;
    for (r, slot) in cmap.iter_mut().enumerate() {
        if !sys.redundant[r] {
            *slot = Some(mr);
            mr += 1;
        }
    }
    if s + mr != n {
        return Err(EngineError::Numeric(format!(
            "{s} linearization states do not complete {mr} independent constraints to {n} coordinates"
        )));
    }
    check_partition(sys, sel, &q, t, &inputs)?;
    let bl = Blocks { n, m, mr, s };
    let mut k = Triplets::new();
    // Eq. 34a, 34b, 34d, 34e from the integrator's exact Jacobian of
    // f = [Hu; Q − Pᵀλ; C; Ċ] at μ = 0.
    let lay = Layout { n, m };
    let mut y = vec![0.0; lay.dim()];
    y[..n].copy_from_slice(&q);
    y[n..2 * n].copy_from_slice(&u);
    y[2 * n..2 * n + m].copy_from_slice(&lam);
    let mut jac = Triplets::new();
    jacobian(sys, lay, t, &y, &inputs, &mut jac);
    for (p, &v) in jac.idx.iter().zip(&jac.vals) {
        let (r, c) = (p.row, p.col);
        let col = if c < n {
            bl.q() + c
        } else if c < 2 * n {
            bl.u() + c - n
        } else if c < 2 * n + m {
            bl.lam() + c - 2 * n
        } else {
            continue; // μ does not appear in Eq. 34
        };
        if r < n {
            k.push(bl.row('b') + r, col, -v); // 34b: q̇ − H(q)u
        } else if r < 2 * n {
            k.push(bl.row('a') + r - n, col, -v); // 34a: M u̇ − (Q − Pᵀλ)
        } else if r < 2 * n + m {
            if let Some(cr) = cmap[r - 2 * n] {
                k.push(bl.row('e') + cr, col, v); // 34e: C
            }
        } else if let Some(cr) = cmap[r - 2 * n - m] {
            k.push(bl.row('d') + cr, col, v); // 34d: Ċ
        }
    }
    for i in 0..n {
        k.push(bl.row('b') + i, bl.qd() + i, 1.0);
    }
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = NQ * b;
        for c in 0..3 {
            k.push(bl.row('a') + o + c, bl.ud() + o + c, body.mass);
        }
        for r in 0..3 {
            for c in 0..3 {
                k.push(bl.row('a') + o + 3 + r, bl.ud() + o + 3 + c, body.inertia[r][c]);
            }
        }
    }
    // Eq. 34c: C̈(u̇, u, q, t) = 0, exact gradients from the time jets.
    let push_z = |k: &mut Triplets, row: usize, bodies: &[usize], dz: &[f64], sign: f64, with_acc: bool| {
        let nql = NQ * bodies.len();
        for a in 0..nql {
            let g = NQ * bodies[a / NQ] + a % NQ;
            k.push(row, bl.q() + g, sign * dz[a]);
            k.push(row, bl.u() + g, sign * dz[nql + a]);
            if with_acc {
                k.push(row, bl.ud() + g, sign * dz[2 * nql + a]);
            }
        }
    };
    for el in &sys.constraints {
        for (e, jet) in jets(sys, el, &q, &u, &udot, t, &inputs).iter().enumerate() {
            if sys.redundant[el.row + e] {
                k.push(bl.row('c') + el.row + e, bl.lam() + el.row + e, 1.0); // its λ = 0
            } else {
                push_z(&mut k, bl.row('c') + el.row + e, el.bodies(), &jet.dg2, 1.0, true);
            }
        }
    }
    // Eq. 34f–34k for each selected state.
    let mut x = vec![0.0; 2 * s];
    for (i, st) in sel.states.iter().enumerate() {
        let jet = &jets(sys, st, &q, &u, &udot, t, &inputs)[0];
        x[i] = jet.g;
        x[s + i] = jet.g1;
        k.push(bl.row('f') + i, bl.sv() + i, 1.0);
        push_z(&mut k, bl.row('f') + i, st.bodies(), &jet.dg, -1.0, false);
        k.push(bl.row('g') + i, bl.sd() + i, 1.0);
        k.push(bl.row('g') + i, bl.w() + i, -1.0);
        k.push(bl.row('h') + i, bl.w() + i, 1.0);
        push_z(&mut k, bl.row('h') + i, st.bodies(), &jet.dg1, -1.0, false);
        k.push(bl.row('i') + i, bl.wd() + i, 1.0);
        push_z(&mut k, bl.row('i') + i, st.bodies(), &jet.dg2, -1.0, true);
        k.push(bl.row('j') + i, bl.w() + i, 1.0);
        k.push(bl.row('k') + i, bl.sv() + i, 1.0);
    }
    // Right-hand sides: ∂/∂S̄ (34k), ∂/∂W̄ (34j), ∂/∂v (34a: +∂Q/∂v), the last sparse.
    let ni = inputs.len();
    let mut dq_dv: Vec<Vec<(usize, f64)>> = vec![Vec::new(); ni];
    for el in &sys.forces {
        for (v, col) in force_input_jacobian(sys, el, &q, &u, t, &inputs).iter().enumerate() {
            for (a, &val) in col.iter().enumerate() {
                dq_dv[v].push((bl.row('a') + NQ * el.bodies[a / NQ] + a % NQ, val));
            }
        }
    }
    let fill = |col: usize, b: &mut [f64]| {
        if col < s {
            b[bl.row('k') + col] = 1.0;
        } else if col < 2 * s {
            b[bl.row('j') + col - s] = 1.0;
        } else {
            for &(r, v) in &dq_dv[col - 2 * s] {
                b[r] += v;
            }
        }
    };
    // Kept of each solution: Ṡ, Ẇ (a column of A or B) and the outputs' sensitivities
    // through q, u, u̇ (chain rule; a column of C or D without ∂y/∂v).
    let grads: Vec<OutputGradient> = sys
        .outputs
        .iter()
        .zip(&sys.output_bases)
        .map(|(e, &abase)| output_gradient(sys, e, abase, &q, &u, &udot, t, &inputs))
        .collect();
    let take = |_: usize, x: &[f64]| -> Vec<f64> {
        let mut keep = Vec::with_capacity(2 * s + grads.len());
        keep.extend_from_slice(&x[bl.sd()..bl.sd() + s]);
        keep.extend_from_slice(&x[bl.wd()..bl.wd() + s]);
        for g in &grads {
            let nql = NQ * g.bodies.len();
            let mut v = 0.0;
            for a in 0..nql {
                let gi = NQ * g.bodies[a / NQ] + a % NQ;
                v += g.dz[a] * x[bl.q() + gi] + g.dz[nql + a] * x[bl.u() + gi] + g.dz[2 * nql + a] * x[bl.ud() + gi];
            }
            keep.push(v);
        }
        keep
    };
    let mut lu = SparseLu::new();
    let singular = || {
        EngineError::Numeric(format!(
            "at t = {t}: the linearization states ({}) no longer parameterize the motion (singular partition); \
             choose user states (<linearization>) that stay independent",
            sel.states.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", ")
        ))
    };
    lu.factor(bl.dim(), &k).map_err(|_| singular())?;
    let sol = lu.solve_columns(2 * s + ni, threads, fill, take).ok_or_else(singular)?;
    let a = Mat::from_fn(2 * s, 2 * s, |r, c| sol[c][r]);
    let b = Mat::from_fn(2 * s, ni, |r, v| sol[2 * s + v][r]);
    let no = grads.len();
    let c = Mat::from_fn(no, 2 * s, |o, col| sol[col][2 * s + o]);
    let d = Mat::from_fn(no, ni, |o, v| sol[2 * s + v][2 * s + o] + grads[o].dv[v]);
    for o in 0..no {
        if (0..2 * s).any(|col| !c[(o, col)].is_finite()) || (0..ni).any(|v| !d[(o, v)].is_finite()) {
            return Err(EngineError::Numeric(format!(
                "output '{}' has no finite derivative here (e.g. |v| at v = 0, or element loads, which are not differentiated yet)",
                sys.output_names[o]
            )));
        }
    }
    let mut states: Vec<String> = sel.states.iter().map(|s| s.name.clone()).collect();
    states.extend(sel.states.iter().map(|s| format!("der({})", s.name)));
    Ok(Linearization {
        time: t,
        states,
        inputs: sys.input_names.clone(),
        outputs: sys.output_names.clone(),
        a,
        b,
        c,
        d,
        x,
    })
}
