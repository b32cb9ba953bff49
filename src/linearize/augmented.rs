//! The augmented sensitivity system (seed Eq. 34a–34k, Table 1): unknowns
//! (u̇, q̇, Ẇ, Ṡ, λ, u, q, W, S) differentiated with respect to the virtual states (S̄, W̄)
//! and the inputs v. One sparse matrix, one sparse LU, the right-hand sides in blocks
//! (split over threads), keeping only the rows A, B, C, D need. Nothing is reduced to
//! the state-space ODE (Eq. 6).

use super::jets::{PositionFn, jets};
use super::outputs::{OutputGradient, output_gradient};
use super::select::Selection;
use super::states::VelState;
use crate::dae::equations::{Layout, jacobian};
use crate::dae::rank::full_pivot;
use crate::dae::sparse::{SparseLu, Triplets};
use crate::dae::{EngineError, Simulator};
use crate::mechanics::body::NQ;
use crate::mechanics::kernels::{force_ext_jacobian, user_jacobian};
use crate::mechanics::loads::{LoadGradient, LoadTerm, NLOAD, load_gradient};
use faer::Mat;

/// A, B, C, D at one operating point, with the names of states, inputs and outputs.
#[derive(Clone, Debug)]
pub struct Linearization {
    pub time: f64,
    /// State names: S, then W (`der(S)`), then the differential states X.
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// A (ns × ns), B (ns × ni), C (no × ns), D (no × ni), ns = 2s + nx.
    pub a: Mat<f64>,
    pub b: Mat<f64>,
    pub c: Mat<f64>,
    pub d: Mat<f64>,
    /// Values of the states (S, W, X) at the operating point.
    pub x: Vec<f64>,
}

/// Column (unknown) and row (equation) offsets of Eq. 34, generalized to s0 position
/// states S, s1 ≤ s0 velocity states W, mn non-holonomic equations (multipliers ν) and
/// the user unknowns Z. Unknowns: (u̇, q̇, Ẇ, Ṡ, λ, ν, u, q, W, S, Z).
struct Blocks {
    n: usize,
    m: usize,
    /// Independent constraint rows (m minus the redundant ones): 34d–e have this many.
    mr: usize,
    mn: usize,
    s0: usize,
    s1: usize,
    /// Differential states X and user unknowns Z = (X, Ẋ, V).
    nx: usize,
    nz: usize,
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
        self.wd() + self.s1
    }
    fn lam(&self) -> usize {
        self.sd() + self.s0
    }
    fn nu(&self) -> usize {
        self.lam() + self.m
    }
    fn u(&self) -> usize {
        self.nu() + self.mn
    }
    fn q(&self) -> usize {
        self.u() + self.n
    }
    fn w(&self) -> usize {
        self.q() + self.n
    }
    fn sv(&self) -> usize {
        self.w() + self.s1
    }
    fn z(&self) -> usize {
        self.sv() + self.s0
    }
    fn dim(&self) -> usize {
        self.z() + self.nz
    }
    // Rows: 34a n, 34b n, 34c m + mn (redundant rows: λ = 0; then ġ = 0), 34d mr + mn
    // (Ċ = 0, g = 0), 34e mr, 34f s0 (S = s), 34g s0 (Ṡ = ṡ), 34h s1 (W = w), 34i s1
    // (Ẇ = ẇ), 34j s1 (W = W̄), 34k s0 (S = S̄), then the user rows r = 0 (nz − nx,
    // Eq. 7a–7b) and X = X̄ (nx).
    fn row(&self, eq: char) -> usize {
        let (n, m, mr, mn, s0, s1) = (self.n, self.m, self.mr, self.mn, self.s0, self.s1);
        let f = 2 * n + m + mn + 2 * mr + mn;
        match eq {
            'a' => 0,
            'b' => n,
            'c' => 2 * n,
            'd' => 2 * n + m + mn,
            'e' => 2 * n + m + mn + mr + mn,
            'f' => f,
            'g' => f + s0,
            'h' => f + 2 * s0,
            'i' => f + 2 * s0 + s1,
            'j' => f + 2 * s0 + 2 * s1,
            'k' => f + 2 * s0 + 3 * s1,
            'l' => f + 3 * s0 + 3 * s1,
            _ => f + 3 * s0 + 3 * s1 + self.nz - self.nx,
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
    let ext = sim.ext_with(&lam);
    let inputs = &ext[..];
    let (q, u) = (sim.q().to_vec(), sim.u().to_vec());
    let sys = sim.system();
    let (n, m, mn, s0, s1) = (sys.n(), sys.m, sys.mn, sel.states.len(), sel.velocities.len());
    // Compact index of each independent constraint row (rows of 34d–e).
    let mut cmap = vec![None; m];
    let mut mr = 0;
    for (r, slot) in cmap.iter_mut().enumerate() {
        if !sys.redundant[r] {
            *slot = Some(mr);
            mr += 1;
        }
    }
    if s0 + mr != n || s1 + mn != s0 {
        return Err(EngineError::Numeric(format!(
            "{s0} position and {s1} velocity states do not complete {mr} independent constraints and {mn} \
             non-holonomic ones to {n} coordinates"
        )));
    }
    check_partition(sys, sel, &q, t, inputs)?;
    let lay = Layout::of(sys);
    let (nx, nz, ni) = (lay.nx, lay.nz(), sys.ni());
    let bl = Blocks { n, m, mr, mn, s0, s1, nx, nz };
    let mut k = Triplets::new();
    // Eq. 34a, 34b, 34d, 34e and the user rows from the integrator's exact Jacobian of
    // f = [Hu; Q − Pᵀλ − Bᵀν; X' = Ẋ, r; C; g; Ċ] at μ = 0.
    let mut y = vec![0.0; lay.dim()];
    y[..n].copy_from_slice(&q);
    y[n..2 * n].copy_from_slice(&u);
    y[lay.z()..lay.z() + nz].copy_from_slice(&ext[ni..ni + nz]);
    y[lay.lam()..lay.lam() + m + mn].copy_from_slice(&lam);
    let mut jac = Triplets::new();
    jacobian(sys, lay, t, &y, &inputs[..ni], &mut jac);
    let (lz, ll, ln, lm) = (lay.z(), lay.lam(), lay.nu(), lay.mu());
    for (p, &v) in jac.idx.iter().zip(&jac.vals) {
        let (r, c) = (p.row, p.col);
        let col = if c < n {
            bl.q() + c
        } else if c < 2 * n {
            bl.u() + c - n
        } else if c < ll {
            bl.z() + c - lz
        } else if c < lm {
            bl.lam() + c - ll // λ then ν, contiguous in both
        } else {
            continue; // μ does not appear in Eq. 34
        };
        if r < n {
            k.push(bl.row('b') + r, col, -v); // 34b: q̇ − H(q)u
        } else if r < 2 * n {
            k.push(bl.row('a') + r - n, col, -v); // 34a: M u̇ − (Q − Pᵀλ − Bᵀν)
        } else if r < lz + nx {
            continue; // X' = Ẋ: the rate of X is the unknown Ẋ itself
        } else if r < ll {
            k.push(bl.row('l') + r - lz - nx, col, v); // Eq. 7a–7b: r(q, u, Z, v, t) = 0
        } else if r < ln {
            if let Some(cr) = cmap[r - ll] {
                k.push(bl.row('e') + cr, col, v); // 34e: C
            }
        } else if r < lm {
            k.push(bl.row('d') + mr + r - ln, col, v); // 34d: g = B u + b (non-holonomic)
        } else if let Some(cr) = cmap[r - lm] {
            k.push(bl.row('d') + cr, col, v); // 34d: Ċ
        }
    }
    for i in 0..nx {
        k.push(bl.row('x') + i, bl.z() + i, 1.0); // X = X̄
    }
    for i in 0..n {
        k.push(bl.row('b') + i, bl.qd() + i, 1.0);
    }
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = NQ * b;
        if sys.acc_bodies.contains(&b) {
            // u̇ = a (the force balance is an algebraic row among the user rows).
            for c in 0..NQ {
                k.push(bl.row('a') + o + c, bl.ud() + o + c, 1.0);
            }
            continue;
        }
        for c in 0..3 {
            k.push(bl.row('a') + o + c, bl.ud() + o + c, body.mass);
        }
        for r in 0..3 {
            for c in 0..3 {
                k.push(bl.row('a') + o + 3 + r, bl.ud() + o + 3 + c, body.inertia[r][c]);
            }
        }
    }
    // Rows of gradients over the local (q, u, u̇) of `bodies`.
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
    // Eq. 34c: C̈(u̇, u, q, t) = 0 and ġ(u̇, u, q, t) = 0, exact gradients from the time jets.
    for el in &sys.constraints {
        for (e, jet) in jets(sys, el, &q, &u, &udot, t, inputs).iter().enumerate() {
            if sys.redundant[el.row + e] {
                k.push(bl.row('c') + el.row + e, bl.lam() + el.row + e, 1.0); // its λ = 0
            } else {
                push_z(&mut k, bl.row('c') + el.row + e, el.bodies(), &jet.dg2, 1.0, true);
            }
        }
    }
    for el in &sys.nonholonomic {
        for (e, jet) in jets(sys, el, &q, &u, &udot, t, inputs).iter().enumerate() {
            push_z(&mut k, bl.row('c') + m + el.row + e, &el.bodies, &jet.dg1, 1.0, true);
        }
    }
    // Eq. 34f, 34g, 34k for each position state; 34h, 34i, 34j for each velocity state.
    let ns = s0 + s1 + nx;
    let mut x = vec![0.0; ns];
    x[s0 + s1..].copy_from_slice(&ext[ni..ni + nx]);
    for (i, st) in sel.states.iter().enumerate() {
        let jet = &jets(sys, st, &q, &u, &udot, t, inputs)[0];
        x[i] = jet.g;
        k.push(bl.row('f') + i, bl.sv() + i, 1.0);
        push_z(&mut k, bl.row('f') + i, st.bodies(), &jet.dg, -1.0, false);
        k.push(bl.row('g') + i, bl.sd() + i, 1.0);
        push_z(&mut k, bl.row('g') + i, st.bodies(), &jet.dg1, -1.0, false);
        k.push(bl.row('k') + i, bl.sv() + i, 1.0);
    }
    for (i, ws) in sel.velocities.iter().enumerate() {
        let jet = ws.jet(sys, &q, &u, &udot, t, inputs);
        x[s0 + i] = jet.w;
        k.push(bl.row('h') + i, bl.w() + i, 1.0);
        push_z(&mut k, bl.row('h') + i, ws.bodies(), &jet.dw, -1.0, false);
        k.push(bl.row('i') + i, bl.wd() + i, 1.0);
        push_z(&mut k, bl.row('i') + i, ws.bodies(), &jet.dwd, -1.0, true);
        k.push(bl.row('j') + i, bl.w() + i, 1.0);
    }
    // Right-hand sides: ∂/∂S̄ (34k), ∂/∂W̄ (34j), ∂/∂X̄, ∂/∂v (34a: +∂Q/∂v; user rows:
    // −∂r/∂v), the last sparse.
    let mut dq_dv: Vec<Vec<(usize, f64)>> = vec![Vec::new(); ni];
    for el in &sys.forces {
        for (v, col) in force_ext_jacobian(sys, el, &q, &u, t, inputs) {
            if v < ni {
                for (a, &val) in col.iter().enumerate() {
                    let b = el.bodies[a / NQ];
                    match sys.acc_bodies.iter().position(|&x| x == b) {
                        // The force balance of a body with acceleration unknowns is an
                        // algebraic row f = Q − … − M a among the user rows.
                        Some(kb) => dq_dv[v].push((bl.row('l') + nx + sys.nv + NQ * kb + a % NQ, -val)),
                        None => dq_dv[v].push((bl.row('a') + NQ * b + a % NQ, val)),
                    }
                }
            }
        }
    }
    for (r, ue) in sys.user.iter().enumerate() {
        for (v, val) in user_jacobian(sys, ue, &q, &u, t, inputs).dext {
            if v < ni {
                dq_dv[v].push((bl.row('l') + r, -val));
            }
        }
    }
    let fill = |col: usize, b: &mut [f64]| {
        if col < s0 {
            b[bl.row('k') + col] = 1.0;
        } else if col < s0 + s1 {
            b[bl.row('j') + col - s0] = 1.0;
        } else if col < ns {
            b[bl.row('x') + col - s0 - s1] = 1.0;
        } else {
            for &(r, v) in &dq_dv[col - ns] {
                b[r] += v;
            }
        }
    };
    let point = super::outputs::Point { q: &q, u: &u, udot: &udot, lam: &lam, t, inputs };
    let grads: Vec<OutputGradient> =
        sys.outputs.iter().zip(&sys.output_bases).map(|(e, &abase)| output_gradient(sys, e, abase, point)).collect();
    // Loads that forces and user rows read (external values): their exact gradients, for
    // outputs that depend on them indirectly (e.g. the load of a force that reads a load).
    let lgrads: Vec<Option<LoadGradient>> =
        sys.load_refs.iter().map(|&r| load_gradient(sys, r, (&q, &u, &lam[..m]), t, &ext[..ni + nz])).collect();
    // An output's sensitivity in solution column x (chain rule through the q, u, u̇, λ and
    // Z rows of Eq. 34). Positions and velocities do not depend on the inputs (Eq.
    // 34d–f, h, j–k hold no input terms), so input columns take no q and u terms: they are
    // zero and would carry only the LU's round-off.
    let sens = |g: &OutputGradient, x: &[f64], kinematic: bool| -> f64 {
        let nql = NQ * g.bodies.len();
        let mut v = 0.0;
        for a in 0..nql {
            let gi = NQ * g.bodies[a / NQ] + a % NQ;
            if kinematic {
                v += g.dz[a] * x[bl.q() + gi] + g.dz[nql + a] * x[bl.u() + gi];
            }
            v += g.dz[2 * nql + a] * x[bl.ud() + gi];
        }
        for &(row, w) in &g.dlam {
            v += w * x[bl.lam() + row];
        }
        for (zi, &dy) in g.dv[ni..ni + nz].iter().enumerate() {
            if dy != 0.0 {
                v += dy * x[bl.z() + zi];
            }
        }
        for (li, &dy) in g.dv[ni + nz..].iter().enumerate() {
            let Some(lg) = lgrads[li / NLOAD].as_ref().filter(|_| dy != 0.0) else { continue };
            lg.terms(li % NLOAD, |term, d| {
                v += dy
                    * d
                    * match term {
                        LoadTerm::Q(i) if kinematic => x[bl.q() + i],
                        LoadTerm::U(i) if kinematic => x[bl.u() + i],
                        LoadTerm::Lam(r) => x[bl.lam() + r],
                        LoadTerm::Ext(e) if e >= ni && e < ni + nz => x[bl.z() + e - ni],
                        _ => 0.0,
                    }
            });
        }
        v
    };
    // Kept of each solution: Ṡ, Ẇ, Ẋ (a column of A or B) and the outputs' sensitivities
    // (a column of C or D without the direct ∂y/∂v).
    let take = |col: usize, x: &[f64]| -> Vec<f64> {
        let mut keep = Vec::with_capacity(ns + grads.len());
        keep.extend_from_slice(&x[bl.sd()..bl.sd() + s0]);
        keep.extend_from_slice(&x[bl.wd()..bl.wd() + s1]);
        keep.extend_from_slice(&x[bl.z() + nx..bl.z() + 2 * nx]);
        keep.extend(grads.iter().map(|g| sens(g, x, col < ns)));
        keep
    };
    let mut lu = SparseLu::new();
    let singular = || {
        EngineError::Numeric(format!(
            "at t = {t}: the linearization states ({}) no longer parameterize the motion (singular partition); \
             choose user states (<linearization>) that stay independent",
            sel.states
                .iter()
                .map(|s| s.name.clone())
                .chain(sel.velocities.iter().map(|w| w.name()))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    };
    lu.factor(bl.dim(), &k).map_err(|_| singular())?;
    let sol = lu.solve_columns(ns + ni, threads, fill, take).ok_or_else(singular)?;
    let mut a = Mat::from_fn(ns, ns, |r, c| sol[c][r]);
    let mut b = Mat::from_fn(ns, ni, |r, v| sol[ns + v][r]);
    // Where W_j = Ṡ_r (always without non-holonomic constraints), the Ṡ rows of A and B are
    // exactly [0 I 0] and 0 (Eq. 34g–h), without the LU's round-off (the FMU's structural
    // zeros are zeros).
    for r in 0..s0 {
        let w =
            sel.velocities.iter().position(|w| matches!(w, VelState::Derivative(d) if d.name == sel.states[r].name));
        if let Some(j) = w {
            for col in 0..ns {
                a[(r, col)] = if col == s0 + j { 1.0 } else { 0.0 };
            }
            for v in 0..ni {
                b[(r, v)] = 0.0;
            }
        }
    }
    let no = grads.len();
    let c = Mat::from_fn(no, ns, |o, col| sol[col][ns + o]);
    let d = Mat::from_fn(no, ni, |o, v| sol[ns + v][ns + o] + grads[o].dv[v]);
    for o in 0..no {
        if (0..ns).any(|col| !c[(o, col)].is_finite()) || (0..ni).any(|v| !d[(o, v)].is_finite()) {
            return Err(EngineError::Numeric(format!(
                "output '{}' has no finite derivative here (e.g. |v| at v = 0, or the load of a user constraint)",
                sys.output_names[o]
            )));
        }
    }
    let mut states: Vec<String> = sel.states.iter().map(|s| s.name.clone()).collect();
    states.extend(sel.velocities.iter().map(|w| w.name()));
    states.extend(sys.user.iter().take(nx).map(|u| u.name.clone()));
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
