//! Initialization (MODEL_FORMAT "Initial conditions"): assemble positions with the
//! smallest change (Gauss–Newton, minimum-norm corrections: [I C_qᵀ; C_q 0]), then
//! consistent velocities (closest to the given ones), then accelerations and Lagrange
//! multipliers from [M Pᵀ; P 0][u̇; λ] = [Q; −γ] (Eq. 1c–1d).

use super::equations::{acceleration_rhs, applied_forces, nonholonomic_b, nonholonomic_gamma, p_row};
use super::rank::full_pivot;
use super::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::constraints::ConstraintEl;
use crate::mechanics::kernels::{constraint_first, gather};
use crate::mechanics::local::LocalCtx;

/// Constraint values into `c` and Jacobian entries (row, global column, value) of a set
/// of elements, rows numbered by the elements' `row` fields.
fn eval_set(
    sys: &System,
    els: &[ConstraintEl],
    q: &[f64],
    t: f64,
    inputs: &[f64],
    c: &mut [f64],
) -> Vec<(usize, usize, f64)> {
    let mut cq = Vec::new();
    for el in els {
        let f = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            c[el.row + e] = f.c[e];
            for a in 0..nql {
                cq.push((el.row + e, NQ * el.bodies[a / NQ] + a % NQ, f.cq[e * nql + a]));
            }
        }
    }
    cq
}

/// An initialization failure, located at the constraint element to blame when there is one.
#[derive(Clone, Debug)]
pub struct InitError {
    /// The element and which of its equations (1-based).
    pub element: Option<Box<(ConstraintEl, usize)>>,
    pub msg: String,
}

/// An error blamed on the element holding constraint row `row`.
fn at_row(els: &[ConstraintEl], row: usize, msg: String) -> InitError {
    let element =
        els.iter().find(|e| row >= e.row && row < e.row + e.neq).map(|e| Box::new((e.clone(), row - e.row + 1)));
    InitError { element, msg }
}

/// Assemble positions: q closest to `q` (step by step) with C(q, t) = 0 and exact ICs.
pub fn assemble_positions(sys: &System, q: &mut [f64], t: f64, inputs: &[f64], tol: f64) -> Result<(), InitError> {
    let n = sys.n();
    let els: Vec<ConstraintEl> = sys.constraints.iter().chain(sys.ic_constraints.iter()).cloned().collect();
    let mr: usize = els.iter().map(|e| e.neq).sum();
    if mr == 0 {
        return Ok(());
    }
    let mut lu = SparseLu::new();
    let mut c = vec![0.0; mr];
    let scale = 1.0 + q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut last = f64::INFINITY;
    for _ in 0..100 {
        let mut kkt = Triplets::new();
        for i in 0..n {
            kkt.push(i, i, 1.0);
        }
        for (r, g, v) in eval_set(sys, &els, q, t, inputs, &mut c) {
            if r < sys.m && sys.redundant[r] {
                continue;
            }
            kkt.push(n + r, g, v);
            kkt.push(g, n + r, v);
        }
        for r in (0..sys.m).filter(|&r| sys.redundant[r]) {
            kkt.push(n + r, n + r, 1.0);
        }
        let worst =
            c.iter().enumerate().fold((0, 0.0f64), |(k, w), (i, v)| if v.abs() > w { (i, v.abs()) } else { (k, w) });
        if !worst.1.is_finite() {
            return Err(at_row(&els, worst.0, "cannot be assembled: its equations are not finite".into()));
        }
        if worst.1 <= tol * scale {
            return Ok(());
        }
        if lu.factor(n + mr, &kkt).is_err() {
            return Err(at_row(
                &els,
                worst.0,
                format!("{}; equations not met: {}", redundant(worst.1), unmet(sys, &els, &c, tol * scale, t, inputs)),
            ));
        }
        let mut rhs = vec![0.0; n + mr];
        for (i, v) in c.iter().enumerate() {
            rhs[n + i] = if i < sys.m && sys.redundant[i] { 0.0 } else { -v };
        }
        if !lu.solve(&mut rhs) {
            return Err(at_row(
                &els,
                worst.0,
                format!("{}; equations not met: {}", redundant(worst.1), unmet(sys, &els, &c, tol * scale, t, inputs)),
            ));
        }
        for i in 0..n {
            q[i] += rhs[i];
        }
        last = worst.1;
    }
    let _ = last;
    // Report the worst constraint after the iterations, and every element not met.
    eval_set(sys, &els, q, t, inputs, &mut c);
    let worst =
        c.iter().enumerate().fold((0, 0.0f64), |(k, w), (i, v)| if v.abs() > w { (i, v.abs()) } else { (k, w) });
    Err(at_row(
        &els,
        worst.0,
        format!(
            "cannot be assembled: worst constraint residual {:.3e} after 100 iterations; equations not met: {}",
            worst.1,
            unmet(sys, &els, &c, tol * scale, t, inputs)
        ),
    ))
}

/// The elements whose equations are not met (some |C_i| above `limit`), worst first, with
/// their largest residual and, for two-marker elements, how far apart their markers are
/// in the model as written (its initial positions).
fn unmet(sys: &System, els: &[ConstraintEl], c: &[f64], limit: f64, t: f64, inputs: &[f64]) -> String {
    use crate::mechanics::constraints::ConstraintKind;
    use crate::model::expr::{Expr, KinFn};
    let mut bad: Vec<(f64, &ConstraintEl)> = els
        .iter()
        .map(|e| (c[e.row..e.row + e.neq].iter().fold(0.0f64, |a, v| a.max(v.abs())), e))
        .filter(|(r, _)| *r > limit)
        .collect();
    bad.sort_by(|a, b| b.0.total_cmp(&a.0));
    let ids: Vec<usize> = (0..sys.nb()).collect();
    let zeros = vec![0.0; sys.n()];
    let ctx = LocalCtx::new(sys, &ids, &sys.q_init, &zeros, &zeros, t, inputs);
    bad.iter()
        .map(|(r, e)| {
            let markers = match &e.kind {
                ConstraintKind::Joint { i, j, .. }
                | ConstraintKind::Rotation { i, j, .. }
                | ConstraintKind::Translation { i, j, .. } => Some((*i, *j)),
                _ => None,
            };
            let gap = markers
                .map(|(i, j)| ctx.eval_expr(&Expr::Kin(KinFn::Dm, i, Some(j), None), 0))
                .filter(|d: &f64| d.is_finite())
                .map_or(String::new(), |d| format!(", markers {d:.3e} m apart as written"));
            format!("{} '{}' (residual {r:.3e}{gap})", e.tag, e.name)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Message for a singular assembly step.
fn redundant(residual: f64) -> String {
    format!(
        "cannot be assembled: the constraint Jacobian is singular (redundant or conflicting constraints); \
         worst residual {residual:.3e} is here"
    )
}

/// Add the symmetric blocks P and Pᵀ (P = C_q H, Eq. 13a/13d) of a KKT matrix whose
/// constraint rows start at `n`; returns each constraint row with its C_t.
fn push_p_blocks(sys: &System, q: &[f64], t: f64, inputs: &[f64], n: usize, kkt: &mut Triplets) -> Vec<(usize, f64)> {
    let mut rows = Vec::with_capacity(sys.m);
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            let r = n + el.row + e;
            if sys.redundant[el.row + e] {
                // Its multiplier is 0 (rhs 0).
                kkt.push(r, r, 1.0);
                continue;
            }
            let p = p_row(&el.bodies, q, &f.cq[e * nql..(e + 1) * nql]);
            for (a, pa) in p.iter().enumerate() {
                let g = NQ * el.bodies[a / NQ] + a % NQ;
                kkt.push(r, g, *pa);
                kkt.push(g, r, *pa);
            }
            rows.push((r, f.ct[e]));
        }
    }
    rows
}

/// Relative pivot size below which a constraint row counts as redundant.
pub const REDUNDANCY_TOL: f64 = 1e-6;

/// Constraint rows that depend on others at (q, t): sparse complete-pivoting elimination
/// of C_qᵀ; the rows that get no pivot are redundant (e.g. a planar loop of revolutes
/// modelled in 3-D). A non-finite C_q counts as independent (assembly reports it).
pub fn redundant_rows(sys: &System, q: &[f64], t: f64, inputs: &[f64]) -> Vec<bool> {
    let (n, m) = (sys.n(), sys.m);
    if m == 0 {
        return Vec::new();
    }
    let mut ct = Vec::new();
    for el in &sys.constraints {
        let f = constraint_first(sys, el, q, t, inputs);
        let nql = NQ * el.bodies.len();
        for e in 0..el.neq {
            for a in 0..nql {
                ct.push((NQ * el.bodies[a / NQ] + a % NQ, el.row + e, f.cq[e * nql + a]));
            }
        }
    }
    match full_pivot(n, m, ct, REDUNDANCY_TOL, 0.0) {
        Ok(p) => p.pivoted_cols(m).iter().map(|&pivoted| !pivoted).collect(),
        Err(_) => vec![false; m],
    }
}

/// Consistent velocities: u closest to `u` with P u + C_t = 0 and exact velocity ICs.
pub fn assemble_velocities(sys: &System, q: &[f64], u: &mut [f64], t: f64, inputs: &[f64]) -> Result<(), String> {
    let n = sys.n();
    let m = sys.m;
    let nic = sys.ic_velocities.len();
    let mn = sys.mn;
    let mut kkt = Triplets::new();
    for i in 0..n {
        kkt.push(i, i, 1.0);
    }
    let mut rhs = vec![0.0; n + m + nic + mn];
    rhs[..n].copy_from_slice(u);
    for (row, ct) in push_p_blocks(sys, q, t, inputs, n, &mut kkt) {
        rhs[row] = -ct;
    }
    // Non-holonomic rows (after the ICs): B u = B u_given − g(u_given) = −b.
    let (b, g) = nonholonomic_b(sys, q, u, t, inputs);
    let r0 = n + m + nic;
    for (r, gv) in g.iter().enumerate() {
        rhs[r0 + r] = -gv;
    }
    for (r, c, v) in b {
        kkt.push(r0 + r, c, v);
        kkt.push(c, r0 + r, v);
        rhs[r0 + r] += v * u[c];
    }
    for (k, ic) in sys.ic_velocities.iter().enumerate() {
        // Linear in u: residual(u) = a·u − value; a from dual numbers seeded on u.
        use crate::ad::{Dual, Real};
        let ql: Vec<Dual<f64, 24>> = gather(&ic.bodies, q).iter().map(|&v| Dual::cst(v)).collect();
        let ul: Vec<Dual<f64, 24>> = gather(&ic.bodies, u).iter().enumerate().map(|(i, &v)| Dual::var(v, i)).collect();
        let ctx = LocalCtx::new(sys, &ic.bodies, &ql, &ul, &[], Dual::cst(t), inputs);
        let res = ic.eval(&ctx);
        let r = n + m + k;
        let mut au = 0.0;
        for a in 0..NQ * ic.bodies.len() {
            let g = NQ * ic.bodies[a / NQ] + a % NQ;
            kkt.push(r, g, res.d[a]);
            kkt.push(g, r, res.d[a]);
            au += res.d[a] * u[g];
        }
        rhs[r] = au - res.val();
    }
    let mut lu = SparseLu::new();
    lu.factor(n + m + nic + mn, &kkt).map_err(|e| format!("cannot make velocities consistent: {e}"))?;
    if !lu.solve(&mut rhs) {
        return Err("cannot make velocities consistent: singular velocity constraints".into());
    }
    u.copy_from_slice(&rhs[..n]);
    Ok(())
}

/// Accelerations u̇ and multipliers (λ; ν): [M Pᵀ Bᵀ; P 0 0; B 0 0][u̇; λ; ν] = [Q; −γ; −γ_nh].
pub fn accelerations(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    lu: &mut SparseLu,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let n = sys.n();
    let m = sys.m;
    let mut kkt = Triplets::new();
    for (b, body) in sys.bodies.iter().enumerate() {
        let o = NQ * b;
        for c in 0..3 {
            kkt.push(o + c, o + c, body.mass);
        }
        for r in 0..3 {
            for c in 0..3 {
                kkt.push(o + 3 + r, o + 3 + c, body.inertia[r][c]);
            }
        }
    }
    let mn = sys.mn;
    let mut rhs = vec![0.0; n + m + mn];
    applied_forces(sys, q, u, t, inputs, &mut rhs[..n]);
    let gamma = acceleration_rhs(sys, q, u, t, inputs);
    for (row, _) in push_p_blocks(sys, q, t, inputs, n, &mut kkt) {
        rhs[row] = -gamma[row - n];
    }
    // Non-holonomic rows: B u̇ = −γ_nh; Bᵀν in the equations of motion.
    let (b, _) = nonholonomic_b(sys, q, u, t, inputs);
    for (r, c, v) in b {
        kkt.push(n + m + r, c, v);
        kkt.push(c, n + m + r, v);
    }
    for (r, gm) in nonholonomic_gamma(sys, q, u, t, inputs).into_iter().enumerate() {
        rhs[n + m + r] = -gm;
    }
    lu.factor(n + m + mn, &kkt).map_err(|e| format!("cannot solve accelerations: {e}"))?;
    if !lu.solve(&mut rhs) {
        return Err("cannot solve accelerations: singular (redundant constraints?)".into());
    }
    Ok((rhs[..n].to_vec(), rhs[n..].to_vec()))
}

/// Static equilibrium (`<analysis static="true"/>`): positions q, multipliers λ and user
/// unknowns with u = 0 and Ẋ = 0: Q(0, q, Z, t) − Pᵀλ = 0, C(q, t) = 0 and the user rows
/// (Eq. 1a, 1d, 7 at rest), by Newton from the assembled configuration with the exact
/// Jacobian of the equations of motion. `z` holds the user unknowns (X, Ẋ, V) in and out.
pub fn static_equilibrium(
    sys: &System,
    q: &mut [f64],
    z: &mut [f64],
    t: f64,
    inputs: &[f64],
    tol: f64,
) -> Result<Vec<f64>, String> {
    use super::equations::{Layout, jacobian, rhs};
    let (n, m) = (sys.n(), sys.m);
    let lay = Layout::of(sys);
    let (nz, nl, nx) = (lay.z(), lay.lam(), lay.nx);
    let mut y = vec![0.0; lay.dim()];
    y[..n].copy_from_slice(q);
    y[nz..nz + lay.nz()].copy_from_slice(z);
    y[nz + nx..nz + 2 * nx].iter_mut().for_each(|v| *v = 0.0);
    let mut lu = SparseLu::new();
    // Start from the multipliers at rest: the stiffness of a mechanism under gravity is in
    // the reactions' geometric term (Pᵀλ)_q, absent at λ = 0.
    let ext = lay.ext(sys, inputs, &y, t);
    let (_, lam0) = accelerations(sys, q, &vec![0.0; n], t, &ext, &mut lu)?;
    y[nl..nl + m].copy_from_slice(&lam0[..m]);
    // Equations: u rows, user rows, C rows; unknowns: q, X, V, a, λ, ν (Ẋ = 0 held). At
    // rest the non-holonomic constraints hold trivially and their multipliers ν carry loads
    // (e.g. a knife edge across a slope); the positions they leave free to drift are held
    // by mn extra rows B T (q − q0) = 0 (no motion along the constrained directions).
    let mn = sys.mn;
    let q0 = q.to_vec();
    let mut bt = vec![vec![0.0; n]; mn];
    for (r, c, v) in nonholonomic_b(sys, q, &vec![0.0; n], t, &ext).0 {
        bt[r][c] += v;
    }
    bt.iter_mut().for_each(|row| crate::mechanics::body::row_times_t(q, row));
    let rows: Vec<usize> = (n..2 * n).chain(nz + nx..nz + lay.nz()).chain(nl..nl + m).collect();
    let cols: Vec<usize> = (0..n).chain(nz..nz + nx).chain(nz + 2 * nx..nz + lay.nz()).chain(nl..nl + m + mn).collect();
    let mut row_of = vec![usize::MAX; lay.dim()];
    let mut col_of = vec![usize::MAX; lay.dim()];
    rows.iter().enumerate().for_each(|(k, &r)| row_of[r] = k);
    cols.iter().enumerate().for_each(|(k, &c)| col_of[c] = k);
    let dim = rows.len() + mn;
    let mut f = vec![0.0; lay.dim()];
    let scale = 1.0 + sys.bodies.iter().map(|b| b.mass).sum::<f64>() * sys.gravity.iter().map(|g| g.abs()).sum::<f64>();
    for _ in 0..100 {
        rhs(sys, lay, t, &y, inputs, &mut f);
        let mut r: Vec<f64> = rows.iter().map(|&i| f[i]).collect();
        r.extend(bt.iter().map(|row| row.iter().zip(y.iter().zip(&q0)).map(|(b, (x, x0))| b * (x - x0)).sum::<f64>()));
        let worst = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !worst.is_finite() {
            return Err("static equilibrium: the equations are not finite".into());
        }
        if worst <= tol * scale {
            q.copy_from_slice(&y[..n]);
            z.copy_from_slice(&y[nz..nz + lay.nz()]);
            return Ok(y[nl..nl + m].to_vec());
        }
        let mut jt = Triplets::new();
        jacobian(sys, lay, t, &y, inputs, &mut jt);
        let mut k = Triplets::new();
        for (p, &v) in jt.idx.iter().zip(&jt.vals) {
            let (rr, cc) = (row_of[p.row], col_of[p.col]);
            if rr != usize::MAX && cc != usize::MAX {
                k.push(rr, cc, v);
            }
        }
        for (i, row) in bt.iter().enumerate() {
            for (c, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                k.push(rows.len() + i, c, v);
            }
        }
        lu.factor(dim, &k).map_err(|e| format!("static equilibrium: singular equations ({e})"))?;
        for v in r.iter_mut() {
            *v = -*v;
        }
        if !lu.solve(&mut r) {
            return Err("static equilibrium: singular equations (a free body or mechanism without stiffness?)".into());
        }
        for (k, &c) in cols.iter().enumerate() {
            y[c] += r[k];
        }
    }
    Err("static equilibrium: Newton did not converge in 100 iterations".into())
}

/// The algebraic user unknowns (Ẋ, V) from the user rows (Eq. 7a–7b) at given q, u, X
/// (and multipliers λ, for rows that read element loads): Newton with the exact Jacobian;
/// `z` = (X, Ẋ, V) in and out (X is kept).
#[allow(clippy::too_many_arguments)]
pub fn user_unknowns(
    sys: &System,
    q: &[f64],
    u: &[f64],
    lam: Option<&[f64]>,
    t: f64,
    inputs: &[f64],
    z: &mut [f64],
) -> Result<(), String> {
    use crate::mechanics::kernels::user_jacobian;
    let (nx, ni, k) = (sys.nx, sys.ni(), sys.user.len());
    if k == 0 {
        return Ok(());
    }
    for _ in 0..50 {
        let ext = sys.ext(inputs, z, lam.map(|l| (q, u, l)), t);
        let mut jac = faer::Mat::<f64>::zeros(k, k);
        let mut r = faer::Mat::<f64>::zeros(k, 1);
        for (row, ue) in sys.user.iter().enumerate() {
            let uj = user_jacobian(sys, ue, q, u, t, &ext);
            r[(row, 0)] = -uj.value;
            for (e, v) in uj.dext {
                if e >= ni + nx && e < ni + 2 * nx + sys.nv {
                    jac[(row, e - ni - nx)] += v;
                }
            }
        }
        let worst = (0..k).map(|i| r[(i, 0)].abs()).fold(0.0, f64::max);
        if !worst.is_finite() {
            return Err("user variables/differentials: not finite at the initial state".into());
        }
        if worst <= 1e-13 * (1.0 + z.iter().fold(0.0f64, |a, v| a.max(v.abs()))) {
            return Ok(());
        }
        let dx = faer::linalg::solvers::Solve::solve(&jac.full_piv_lu(), &r);
        for i in 0..k {
            z[nx + i] += dx[(i, 0)];
        }
    }
    Err("user variables/differentials: Newton did not converge at the initial state (algebraic loop?)".into())
}

/// User unknowns, accelerations and multipliers at the initial point. When forces or user
/// rows read element loads or accelerations (algebraic loops through the constraint
/// forces or the inertia), they are solved together by Newton with the exact Jacobian of
/// the equations of motion: unknowns (u̇, Ẋ, V, a, λ, ν), equations the force balance,
/// the user rows, and the acceleration constraints P u̇ + γ = 0, B u̇ + γ_nh = 0.
#[allow(clippy::too_many_arguments)]
pub fn consistent_accelerations(
    sys: &System,
    q: &[f64],
    u: &[f64],
    t: f64,
    inputs: &[f64],
    z: &mut [f64],
    lu: &mut SparseLu,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    use super::equations::{Layout, jacobian, mass_matrix, rhs};
    user_unknowns(sys, q, u, None, t, inputs, z)?;
    let ext0 = sys.ext(inputs, z, None, t);
    let (udot0, lam0) = accelerations(sys, q, u, t, &ext0, lu)?;
    if sys.load_refs.is_empty() && sys.acc_bodies.is_empty() {
        return Ok((udot0, lam0));
    }
    let lay = Layout::of(sys);
    let (n, m, mn) = (lay.n, lay.m, lay.mn);
    let (nz0, nalg) = (lay.z() + lay.nx, lay.nz() - lay.nx);
    let a0 = 2 * sys.nx + sys.nv;
    let mut y = vec![0.0; lay.dim()];
    y[..n].copy_from_slice(q);
    y[n..2 * n].copy_from_slice(u);
    for (k, &b) in sys.acc_bodies.iter().enumerate() {
        z[a0 + NQ * k..a0 + NQ * k + NQ].copy_from_slice(&udot0[NQ * b..NQ * b + NQ]);
    }
    y[lay.z()..lay.z() + lay.nz()].copy_from_slice(z);
    y[lay.lam()..lay.lam() + m + mn].copy_from_slice(&lam0);
    let mut udot = udot0;
    // Unknown columns: u̇ (n), Z_alg (nalg), λ and ν (m + mn); the same order for rows:
    // force balance (u rows of the DAE), algebraic Z rows, acceleration constraints.
    let dim = n + nalg + m + mn;
    let col_of = |c: usize| -> Option<usize> {
        if (nz0..nz0 + nalg).contains(&c) {
            Some(n + c - nz0)
        } else if (lay.lam()..lay.lam() + m + mn).contains(&c) {
            Some(n + nalg + c - lay.lam())
        } else {
            None
        }
    };
    let row_of = |r: usize| -> Option<usize> {
        if (n..2 * n).contains(&r) {
            Some(r - n)
        } else if (nz0..nz0 + nalg).contains(&r) {
            Some(n + r - nz0)
        } else {
            None
        }
    };
    let mut mass = Triplets::new();
    mass_matrix(sys, lay, &mut mass);
    let mut nlu = SparseLu::new();
    let mut f = vec![0.0; lay.dim()];
    let scale = 1.0 + udot.iter().chain(&y[lay.lam()..lay.lam() + m + mn]).fold(0.0f64, |a, v| a.max(v.abs()));
    for _ in 0..50 {
        rhs(sys, lay, t, &y, inputs, &mut f);
        let ext = lay.ext(sys, inputs, &y, t);
        let mut r = vec![0.0; dim];
        let mut k = Triplets::new();
        // Force balance: M_dae u̇ − f_u = 0.
        for i in 0..n {
            r[i] = -f[n + i];
        }
        for (p, &v) in mass.idx.iter().zip(&mass.vals) {
            if (n..2 * n).contains(&p.row) {
                r[p.row - n] += v * udot[p.col - n];
                k.push(p.row - n, p.col - n, v);
            }
        }
        r[n..n + nalg].copy_from_slice(&f[nz0..nz0 + nalg]);
        let mut jt = Triplets::new();
        jacobian(sys, lay, t, &y, inputs, &mut jt);
        for (p, &v) in jt.idx.iter().zip(&jt.vals) {
            if let (Some(rr), Some(cc)) = (row_of(p.row), col_of(p.col)) {
                k.push(rr, cc, if rr < n { -v } else { v });
            }
        }
        // Acceleration constraints (redundant rows: λ = 0).
        let gamma = acceleration_rhs(sys, q, u, t, &ext);
        let r0 = n + nalg;
        for el in &sys.constraints {
            let fc = constraint_first(sys, el, q, t, &ext);
            let nql = NQ * el.bodies.len();
            for e in 0..el.neq {
                let row = el.row + e;
                if sys.redundant[row] {
                    k.push(r0 + row, r0 + row, 1.0);
                    r[r0 + row] = y[lay.lam() + row];
                    continue;
                }
                let pr = p_row(&el.bodies, q, &fc.cq[e * nql..(e + 1) * nql]);
                let mut v = gamma[row];
                for (a, pa) in pr.iter().enumerate() {
                    let g = NQ * el.bodies[a / NQ] + a % NQ;
                    k.push(r0 + row, g, *pa);
                    v += pa * udot[g];
                }
                r[r0 + row] = v;
            }
        }
        let (b, _) = nonholonomic_b(sys, q, u, t, &ext);
        let gnh = nonholonomic_gamma(sys, q, u, t, &ext);
        for (row, gv) in gnh.iter().enumerate() {
            r[r0 + m + row] = *gv;
        }
        for (row, c, v) in b {
            k.push(r0 + m + row, c, v);
            r[r0 + m + row] += v * udot[c];
        }
        let worst = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !worst.is_finite() {
            return Err(
                "the algebraic loop through element loads or accelerations is not finite at the initial state".into()
            );
        }
        if worst <= 1e-12 * scale {
            z.copy_from_slice(&y[lay.z()..lay.z() + lay.nz()]);
            return Ok((udot, y[lay.lam()..lay.lam() + m + mn].to_vec()));
        }
        nlu.factor(dim, &k).map_err(|e| format!("the algebraic loop at the initial state is singular ({e})"))?;
        r.iter_mut().for_each(|v| *v = -*v);
        if !nlu.solve(&mut r) {
            return Err("the algebraic loop at the initial state is singular".into());
        }
        for i in 0..n {
            udot[i] += r[i];
        }
        for i in 0..nalg {
            y[nz0 + i] += r[n + i];
        }
        for i in 0..m + mn {
            y[lay.lam() + i] += r[n + nalg + i];
        }
    }
    Err("the algebraic loop through element loads or accelerations does not converge at the initial state".into())
}
