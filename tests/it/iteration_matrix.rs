//! The integrator's fallback from an approximate to the exact Jacobian
//! (`DaeProblem::set_exact_jacobian`): a problem whose approximation cannot converge
//! Newton's iteration is still solved, to its analytic solution, once the integrator asks
//! for the exact J; one whose approximation serves is never asked.

use mbfmu::dae::radau::{DaeProblem, Radau};
use mbfmu::dae::sparse::Triplets;

/// Stiffness of the test equation (1/s).
const K: f64 = 1e4;

/// y₁' = −K (y₁ − cos t) − sin t, y₂' = y₁ (solution y₁ = cos t, y₂ = sin t from
/// y = (1, 0)). Its "approximate" J leaves out −K, or (`good`) only the coupling ∂f₂/∂y₁.
struct Stiff {
    /// The approximation keeps −K (Newton converges with it).
    good: bool,
    /// What the integrator last asked for.
    exact: bool,
    /// Jacobians evaluated exact and approximate.
    calls: (usize, usize),
}

impl DaeProblem for Stiff {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], f: &mut [f64]) -> Result<(), String> {
        f[0] = -K * (y[0] - t.cos()) - t.sin();
        f[1] = y[0];
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut Triplets) -> Result<(), String> {
        if self.exact {
            self.calls.0 += 1;
            j.push(0, 0, -K);
            j.push(1, 0, 1.0);
        } else {
            self.calls.1 += 1;
            j.push(0, 0, if self.good { -K } else { 0.0 });
        }
        Ok(())
    }
    fn mass(&self, m: &mut Triplets) {
        m.push(0, 0, 1.0);
        m.push(1, 1, 1.0);
    }
    fn index(&self) -> Vec<u8> {
        vec![0, 0]
    }
    fn accepted(&mut self, _t: f64, _y: &mut [f64]) -> bool {
        false
    }
    fn set_exact_jacobian(&mut self, exact: bool) {
        self.exact = exact;
    }
}

/// Integrate to t = 2 at tolerance 1e-8; the worst error against (cos t, sin t) over
/// twenty output points.
fn run(p: &mut Stiff) -> f64 {
    let mut r = Radau::new(p, 0.0, vec![1.0, 0.0], 1e-8);
    let mut worst = 0.0f64;
    for k in 1..=20 {
        let t = 0.1 * k as f64;
        r.advance(p, t).unwrap();
        worst = worst.max((r.y[0] - t.cos()).abs()).max((r.y[1] - t.sin()).abs());
    }
    worst
}

/// With J₁₁ = 0, Newton's iteration is the fixed point y ← y₀ + h·f, which diverges once
/// hK > 1 (h > 0.1 ms; the error control alone asks for ~10 ms steps): the first failure
/// with a fresh J must turn the exact one on, for good. The error bound: the method's
/// at tolerance 1e-8 (relative and absolute, components of O(1)), 100× over for the
/// accumulation across some 100 steps.
#[test]
fn a_failing_approximate_jacobian_is_replaced_by_the_exact_one_for_the_rest_of_the_run() {
    let mut p = Stiff { good: false, exact: false, calls: (0, 0) };
    let err = run(&mut p);
    assert!(err < 1e-6, "error {err:e}");
    assert!(p.exact, "the integrator did not ask for the exact Jacobian");
    assert!(p.calls.0 >= 1, "no exact Jacobian evaluated: {:?}", p.calls);
}

/// An approximation that lets Newton converge is kept: no exact J is ever asked for, and
/// the solution is as accurate (J's coupling row only slows the iteration for y₂, which
/// depends linearly and explicitly on y₁).
#[test]
fn a_serving_approximate_jacobian_is_kept() {
    let mut p = Stiff { good: true, exact: false, calls: (0, 0) };
    let err = run(&mut p);
    assert!(err < 1e-6, "error {err:e}");
    assert_eq!(p.calls.0, 0, "exact Jacobians evaluated: {:?}", p.calls);
    assert!(p.calls.1 >= 1);
}
