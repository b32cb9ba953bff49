//! A, B, C, D from the solutions of the augmented system (seed Eq. 36): column j of A
//! (of B) is (Ṡ, Ẇ, Ẋ) of the solution for state j (input j); C and D are the outputs'
//! sensitivities in the same solutions, D plus the direct ∂y/∂v.

use super::linearization::Linearization;
use super::operating_point::OperatingPoint;
use super::sensitivity::Sensitivities;
use crate::dae::EngineError;
use faer::Mat;

/// The linearization at `p` from the kept solutions `sol` (one per state, then per
/// input: Ṡ, Ẇ, Ẋ, then the outputs' sensitivities) and the values of S, W.
pub(super) fn extract(
    p: &OperatingPoint,
    sens: &Sensitivities,
    sol: &[Vec<f64>],
    values: Vec<f64>,
    solves: usize,
) -> Result<Linearization, EngineError> {
    let (sys, ns, ni, no) = (p.sys, p.eq.ns(), p.ni(), sens.outputs());
    let mut a = Mat::from_fn(ns, ns, |r, c| sol[c][r]);
    let mut b = Mat::from_fn(ns, ni, |r, v| sol[ns + v][r]);
    exact_kinematic_rows(p, &mut a, &mut b);
    let c = Mat::from_fn(no, ns, |o, col| sol[col][ns + o]);
    let d = Mat::from_fn(no, ni, |o, v| sol[ns + v][ns + o] + sens.direct(o, v));
    for o in 0..no {
        if (0..ns).any(|col| !c[(o, col)].is_finite()) || (0..ni).any(|v| !d[(o, v)].is_finite()) {
            return Err(no_finite_derivative(&sys.output_names[o]));
        }
    }
    let mut x = values;
    let xl = sys.ext_layout();
    x.extend((0..p.eq.nx).map(|i| p.ext[xl.diff(i)]));
    let mut states: Vec<String> = p.sel.states.iter().map(|s| s.name.clone()).collect();
    states.extend(p.sel.velocities.iter().map(|w| w.name()));
    states.extend(sys.user.iter().take(p.eq.nx).map(|u| u.name.clone()));
    let (inputs, outputs) = (sys.input_names.clone(), sys.output_names.clone());
    Ok(Linearization { time: p.t, states, inputs, outputs, a, b, c, d, x, solves })
}

/// The error of an output whose derivative is not finite at the operating point.
pub(super) fn no_finite_derivative(output: &str) -> EngineError {
    EngineError::Numeric(format!(
        "output '{output}' has no finite derivative here (e.g. |v| at v = 0, or the load of a user constraint)"
    ))
}

/// Where W_j = Ṡ_k (always without non-holonomic constraints), row k of A and B is
/// exactly [0 I 0] and 0 (Eq. 34g–h): set without the LU's round-off, so that the
/// FMU's structural zeros are zeros.
fn exact_kinematic_rows(p: &OperatingPoint, a: &mut Mat<f64>, b: &mut Mat<f64>) {
    let (s0, ns) = (p.eq.s0, p.eq.ns());
    for k in 0..s0 {
        let Some(j) = p.sel.velocity_of_state(k) else { continue };
        for col in 0..ns {
            a[(k, col)] = if col == s0 + j { 1.0 } else { 0.0 };
        }
        for v in 0..b.ncols() {
            b[(k, v)] = 0.0;
        }
    }
}
