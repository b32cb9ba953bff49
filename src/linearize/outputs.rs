//! Exact gradients of the `<output>` expressions with respect to q, u, u̇ of the bodies they
//! read and to the inputs (rows of C and D).

use crate::ad::{Dual, Real};
use crate::mechanics::System;
use crate::mechanics::body::NQ;
use crate::mechanics::kernels::gather;
use crate::mechanics::local::LocalCtx;
use crate::model::expr::{Expr, deps};

/// Gradient of one output: its bodies, ∂y/∂(q, u, u̇) local (18·nb), and ∂y/∂v per input.
pub struct OutputGradient {
    pub bodies: Vec<usize>,
    pub dz: Vec<f64>,
    pub dv: Vec<f64>,
}

/// The gradient of output expression `e` (angle slots from `abase`) at (q, u, u̇, t, v).
#[allow(clippy::too_many_arguments)]
pub fn output_gradient(
    sys: &System,
    e: &Expr,
    abase: usize,
    q: &[f64],
    u: &[f64],
    udot: &[f64],
    t: f64,
    inputs: &[f64],
) -> OutputGradient {
    let mut bodies: Vec<usize> = deps(e).markers.iter().filter_map(|&m| sys.markers[m].body).collect();
    bodies.sort_unstable();
    bodies.dedup();
    let dz = match bodies.len() {
        0 => grad_k::<1>(sys, e, abase, &bodies, q, u, udot, t, inputs),
        1 => grad_k::<18>(sys, e, abase, &bodies, q, u, udot, t, inputs),
        2 => grad_k::<36>(sys, e, abase, &bodies, q, u, udot, t, inputs),
        3 => grad_k::<54>(sys, e, abase, &bodies, q, u, udot, t, inputs),
        _ => grad_k::<72>(sys, e, abase, &bodies, q, u, udot, t, inputs),
    };
    let dv = (0..inputs.len())
        .map(|k| {
            let lift = |x: Vec<f64>| -> Vec<Dual<f64, 1>> { x.into_iter().map(Dual::cst).collect() };
            let (ql, ul, al) = (lift(gather(&bodies, q)), lift(gather(&bodies, u)), lift(gather(&bodies, udot)));
            let mut ctx = LocalCtx::new(sys, &bodies, &ql, &ul, &al, Dual::cst(t), inputs);
            ctx.input_values = Some(
                inputs.iter().enumerate().map(|(i, &v)| if i == k { Dual::var(v, 0) } else { Dual::cst(v) }).collect(),
            );
            ctx.eval_expr(e, abase).d[0]
        })
        .collect();
    OutputGradient { bodies, dz, dv }
}

#[allow(clippy::too_many_arguments)]
fn grad_k<const K: usize>(
    sys: &System,
    e: &Expr,
    abase: usize,
    bodies: &[usize],
    q: &[f64],
    u: &[f64],
    udot: &[f64],
    t: f64,
    inputs: &[f64],
) -> Vec<f64> {
    let nq = NQ * bodies.len();
    let seed = |x: Vec<f64>, off: usize| -> Vec<Dual<f64, K>> {
        x.iter().enumerate().map(|(i, &v)| Dual::var(v, off + i)).collect()
    };
    let (ql, ul, al) = (seed(gather(bodies, q), 0), seed(gather(bodies, u), nq), seed(gather(bodies, udot), 2 * nq));
    let ctx = LocalCtx::new(sys, bodies, &ql, &ul, &al, Dual::cst(t), inputs);
    ctx.eval_expr(e, abase).d[..3 * nq].to_vec()
}
