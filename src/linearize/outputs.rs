//! Exact gradients of the `<output>` expressions with respect to q, u, u̇ of the bodies they
//! read, to the multipliers λ and to the inputs (rows of C and D).
//!
//! An output that reads element loads (`fx(name)` ...) is differentiated in two steps: the
//! loads are independent seeded variables of the expression (∂y/∂load), chained with each
//! load's own gradient over q, u, λ and v from [`crate::mechanics::loads`].

use crate::ad::{Dual, Real};
use crate::mechanics::System;
use crate::mechanics::coords::{gather, local_columns, nql};
use crate::mechanics::loads::{LoadTerm, NLOAD, load_gradient, load_index, load_value};
use crate::mechanics::local::LocalCtx;
use crate::model::expr::{ElementRef, Expr, LoadFn, deps};
use std::ops::Range;

/// Gradient of one output: its bodies, ∂y/∂(q, u, u̇) local (18·nb: q of every body,
/// then u, then u̇), ∂y/∂λ as (global row, value) pairs, and ∂y/∂ext per external value.
pub struct OutputGradient {
    /// Bodies of the output and of every load it reads (global indices, ascending): the
    /// local order of `dz`.
    pub bodies: Vec<usize>,
    /// Global column of each local coordinate (see [`crate::mechanics::coords`]).
    pub cols: Vec<usize>,
    /// ∂y/∂(local q, u, u̇), loads chained in: q of each body of `bodies` (6 each), then u,
    /// then u̇; all NaN when it reads a load that has no value.
    pub dz: Vec<f64>,
    /// ∂y/∂λ through the loads it reads, as (global multiplier row, value); a row may
    /// appear more than once (the values add up).
    pub dlam: Vec<(usize, f64)>,
    /// ∂y/∂ext, one entry per external value of [`Point::inputs`] (inputs v, then Z, then
    /// loads L).
    pub dv: Vec<f64>,
}

/// The operating point: global q, u, u̇, λ, time and external values.
#[derive(Clone, Copy)]
pub struct Point<'a> {
    /// Coordinates q, 6 per body: [r; ψ θ φ].
    pub q: &'a [f64],
    /// Velocities u, 6 per body: [v; ω'], ω' in body axes.
    pub u: &'a [f64],
    /// Accelerations u̇, 6 per body.
    pub udot: &'a [f64],
    /// Multipliers: λ of the holonomic rows, then ν of the non-holonomic ones.
    pub lam: &'a [f64],
    /// Time (s).
    pub t: f64,
    /// Not only the inputs: every external value ext = [inputs v; Z; L], laid out by
    /// [`ExtLayout`](crate::mechanics::external::ExtLayout).
    pub inputs: &'a [f64],
}

/// Local coordinates seeded at once by [`own_gradient`]: those of four rigid bodies.
const SEEDED: usize = 24;

/// The gradient of output expression `e` (angle slots from `abase`) at `p`.
pub fn output_gradient(sys: &System, e: &Expr, abase: usize, p: Point) -> OutputGradient {
    let d = deps(e);
    let mut own: Vec<usize> = d.markers.iter().filter_map(|&m| sys.markers[m].body).collect();
    own.sort_unstable();
    own.dedup();
    // Loads read by the expression: values (constants of the passes below) and gradients.
    let loads: Vec<(ElementRef, [f64; NLOAD])> = d
        .loads
        .iter()
        .map(|&r| (r, load_value(sys, r, (p.q, p.u, p.lam), p.t, p.inputs).unwrap_or([f64::NAN; NLOAD])))
        .collect();
    let value_of = |f: LoadFn, r: ElementRef| -> f64 {
        loads.iter().find(|(x, _)| *x == r).map_or(f64::NAN, |(_, v)| v[load_index(f)])
    };
    let dz_own = own_gradient(sys, e, abase, &own, p, &value_of);
    let lift = |x: Vec<f64>| -> Vec<Dual<f64, 1>> { x.into_iter().map(Dual::cst).collect() };
    let mut dv: Vec<f64> = (0..p.inputs.len())
        .map(|k| {
            let (ql, ul, al) =
                (lift(gather(sys, &own, p.q)), lift(gather(sys, &own, p.u)), lift(gather(sys, &own, p.udot)));
            let loads = |f: LoadFn, r: ElementRef| Dual::cst(value_of(f, r));
            let mut ctx = LocalCtx::new(sys, &own, &ql, &ul, &al, Dual::cst(p.t), p.inputs);
            let seeded = p.inputs.iter().enumerate().map(|(i, &v)| if i == k { Dual::var(v, 0) } else { Dual::cst(v) });
            ctx.input_values = Some(seeded.collect());
            ctx.loads = Some(&loads);
            ctx.eval_expr(e, abase).d[0]
        })
        .collect();
    // Bodies of the output and of every load it reads; the output's own gradient first.
    let mut bodies = own.clone();
    let grads: Vec<_> = d.loads.iter().map(|&r| (r, load_gradient(sys, r, (p.q, p.u, p.lam), p.t, p.inputs))).collect();
    for (_, g) in &grads {
        bodies.extend(g.iter().flat_map(|g| g.bodies.iter().copied()));
    }
    bodies.sort_unstable();
    bodies.dedup();
    let cols = local_columns(sys, &bodies);
    let nql = cols.len();
    let position: std::collections::HashMap<usize, usize> = cols.iter().enumerate().map(|(i, &g)| (g, i)).collect();
    let local = |g: usize| position[&g];
    let mut dz = vec![0.0; 3 * nql];
    let own_cols = local_columns(sys, &own);
    let n_own = own_cols.len();
    for lvl in 0..3 {
        for (k, &g) in own_cols.iter().enumerate() {
            dz[lvl * nql + local(g)] += dz_own[lvl * n_own + k];
        }
    }
    let mut dlam = Vec::new();
    for (r, g) in grads {
        // A load without a value (a user constraint's): no derivative either.
        let Some(g) = g else {
            dz.fill(f64::NAN);
            continue;
        };
        let dy = load_sensitivity(sys, e, abase, &own, p, &value_of, r);
        for (c, &w) in dy.iter().enumerate().filter(|(_, w)| **w != 0.0) {
            // Chain rule: dy = Σ_c ∂y/∂load_c (∂load_c/∂q dq + ∂load_c/∂u du + ∂load_c/∂λ dλ + ∂load_c/∂v dv).
            g.terms(c, |term, d| match term {
                LoadTerm::Q(i) => dz[local(i)] += w * d,
                LoadTerm::U(i) => dz[nql + local(i)] += w * d,
                LoadTerm::Lam(r) => dlam.push((r, w * d)),
                LoadTerm::Ext(k) => dv[k] += w * d,
            });
        }
    }
    OutputGradient { bodies, cols, dz, dlam, dv }
}

/// ∂y/∂(the six components of element `r`'s load), the loads seeded as dual variables.
fn load_sensitivity(
    sys: &System,
    e: &Expr,
    abase: usize,
    own: &[usize],
    p: Point,
    value_of: &dyn Fn(LoadFn, ElementRef) -> f64,
    r: ElementRef,
) -> [f64; NLOAD] {
    type D = Dual<f64, NLOAD>;
    let lift = |x: Vec<f64>| -> Vec<D> { x.into_iter().map(D::cst).collect() };
    let (ql, ul, al) = (lift(gather(sys, own, p.q)), lift(gather(sys, own, p.u)), lift(gather(sys, own, p.udot)));
    let loads = |f: LoadFn, x: ElementRef| {
        let v = value_of(f, x);
        if x == r { D::var(v, load_index(f)) } else { D::cst(v) }
    };
    let mut ctx = LocalCtx::new(sys, own, &ql, &ul, &al, D::cst(p.t), p.inputs);
    ctx.loads = Some(&loads);
    ctx.eval_expr(e, abase).d
}

/// ∂y/∂(local q, u, u̇) of the output's own kinematic measures (the local coordinates of
/// `own`, then their velocities, then their accelerations), loads held constant. An output
/// may measure any number of bodies: their local coordinates are seeded
/// [`SEEDED`] at a time (the widest dual number holds their q, u and u̇), the others held
/// constant.
fn own_gradient(
    sys: &System,
    e: &Expr,
    abase: usize,
    own: &[usize],
    p: Point,
    value_of: &dyn Fn(LoadFn, ElementRef) -> f64,
) -> Vec<f64> {
    let n_own = nql(sys, own);
    let mut dz = vec![0.0; 3 * n_own];
    for start in (0..n_own).step_by(SEEDED) {
        let seeded = start..n_own.min(start + SEEDED);
        let g = match seeded.len() {
            1..=6 => grad_k::<18>(sys, e, abase, own, seeded.clone(), p, value_of),
            7..=12 => grad_k::<36>(sys, e, abase, own, seeded.clone(), p, value_of),
            13..=18 => grad_k::<54>(sys, e, abase, own, seeded.clone(), p, value_of),
            _ => grad_k::<72>(sys, e, abase, own, seeded.clone(), p, value_of),
        };
        let nc = seeded.len();
        for lvl in 0..3 {
            let (to, from) = (lvl * n_own + seeded.start, lvl * nc);
            dz[to..to + nc].copy_from_slice(&g[from..from + nc]);
        }
    }
    dz
}

/// ∂y/∂(q, u, u̇ of the local coordinates `seeded` of `own`), the others held constant:
/// q of the seeded coordinates, then u, then u̇ (K ≥ 3 per seeded coordinate).
fn grad_k<const K: usize>(
    sys: &System,
    e: &Expr,
    abase: usize,
    own: &[usize],
    seeded: Range<usize>,
    p: Point,
    value_of: &dyn Fn(LoadFn, ElementRef) -> f64,
) -> Vec<f64> {
    let nc = seeded.len();
    let first = seeded;
    let seed = |x: Vec<f64>, off: usize| -> Vec<Dual<f64, K>> {
        let var =
            |i: usize, v: f64| if first.contains(&i) { Dual::var(v, off + i - first.start) } else { Dual::cst(v) };
        x.iter().enumerate().map(|(i, &v)| var(i, v)).collect()
    };
    let (ql, ul, al) =
        (seed(gather(sys, own, p.q), 0), seed(gather(sys, own, p.u), nc), seed(gather(sys, own, p.udot), 2 * nc));
    let loads = |f: LoadFn, r: ElementRef| Dual::cst(value_of(f, r));
    let mut ctx = LocalCtx::new(sys, own, &ql, &ul, &al, Dual::cst(p.t), p.inputs);
    ctx.loads = Some(&loads);
    ctx.eval_expr(e, abase).d[..3 * nc].to_vec()
}
