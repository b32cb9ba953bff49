//! Position assembly: q closest to the given q (step by step) with C(q, t) = 0 and the
//! exact position ICs, by Gauss–Newton with minimum-norm corrections:
//! [I C_qᵀ; C_q 0][Δq; κ] = [0; −C].

use crate::dae::sparse::{SparseLu, Triplets};
use crate::mechanics::System;
use crate::mechanics::constraint_jacobian::constraint_rows;
use crate::mechanics::constraints::ConstraintEl;
use crate::mechanics::local::LocalCtx;

/// Gauss–Newton iterations before assembly gives up.
const MAX_ITERATIONS: usize = 100;

/// An initialization failure, located at the constraint element to blame when there is one.
#[derive(Clone, Debug)]
pub struct InitError {
    /// The element and which of its equations (1-based).
    pub element: Option<Box<(ConstraintEl, usize)>>,
    /// What went wrong.
    pub msg: String,
}

/// An error blamed on the element holding constraint row `row`.
fn at_row(els: &[ConstraintEl], row: usize, msg: String) -> InitError {
    let element =
        els.iter().find(|e| row >= e.row && row < e.row + e.neq).map(|e| Box::new((e.clone(), row - e.row + 1)));
    InitError { element, msg }
}

/// The row of the largest |C_i| and its size.
fn worst(c: &[f64]) -> (usize, f64) {
    c.iter().enumerate().fold((0, 0.0f64), |(k, w), (i, v)| if v.abs() > w { (i, v.abs()) } else { (k, w) })
}

/// Assemble positions: q closest to `q` (step by step) with C(q, t) = 0 and exact ICs.
pub fn assemble_positions(sys: &System, q: &mut [f64], t: f64, inputs: &[f64], tol: f64) -> Result<(), InitError> {
    let n = sys.n();
    let els: Vec<ConstraintEl> = sys.constraints.iter().chain(sys.ic_constraints.iter()).cloned().collect();
    let mr: usize = els.iter().map(|e| e.neq).sum();
    if mr == 0 {
        return Ok(());
    }
    let redundant = |r: usize| r < sys.m && sys.redundant[r];
    let mut lu = SparseLu::new();
    let scale = 1.0 + q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for _ in 0..MAX_ITERATIONS {
        let rows = constraint_rows(sys, &els, q, t, inputs);
        let mut kkt = Triplets::new();
        for i in 0..n {
            kkt.push(i, i, 1.0);
        }
        for &(r, g, v) in rows.entries.iter().filter(|e| !redundant(e.0)) {
            kkt.push(n + r, g, v);
            kkt.push(g, n + r, v);
        }
        for r in (0..sys.m).filter(|&r| sys.redundant[r]) {
            kkt.push(n + r, n + r, 1.0);
        }
        let (at, size) = worst(&rows.c);
        if !size.is_finite() {
            return Err(at_row(&els, at, "cannot be assembled: its equations are not finite".into()));
        }
        if size <= tol * scale {
            return Ok(());
        }
        let singular = || {
            let unmet = unmet(sys, &els, &rows.c, tol * scale, t, inputs);
            at_row(&els, at, format!("{}; equations not met: {unmet}", singular_message(size)))
        };
        if lu.factor(n + mr, &kkt).is_err() {
            return Err(singular());
        }
        let mut rhs = vec![0.0; n + mr];
        for (i, v) in rows.c.iter().enumerate() {
            rhs[n + i] = if redundant(i) { 0.0 } else { -v };
        }
        if !lu.solve(&mut rhs) {
            return Err(singular());
        }
        for i in 0..n {
            q[i] += rhs[i];
        }
    }
    // Report the worst constraint after the iterations, and every element not met.
    let c = constraint_rows(sys, &els, q, t, inputs).c;
    let (at, size) = worst(&c);
    Err(at_row(
        &els,
        at,
        format!(
            "cannot be assembled: worst constraint residual {size:.3e} after {MAX_ITERATIONS} iterations; \
             equations not met: {}",
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
fn singular_message(residual: f64) -> String {
    format!(
        "cannot be assembled: the constraint Jacobian is singular (redundant or conflicting constraints); \
         worst residual {residual:.3e} is here"
    )
}
