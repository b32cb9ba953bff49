//! The expression API as other layers use it: a scope and an environment implemented
//! outside the crate, parse, dependency analysis, and dual-number evaluation.

use mbfmu::ad::{Dual, Real};
use mbfmu::geom::{M3, V3, rot_z};
use mbfmu::model::expr::*;

struct OneBody;

impl Scope for OneBody {
    fn name(&self, name: &str) -> Option<NameRef> {
        (name == "k").then_some(NameRef::Param(0))
    }
    fn marker(&self, name: &str) -> Option<MarkerId> {
        match name {
            "arm" => Some(0),
            "ground.O" => Some(1),
            _ => None,
        }
    }
    fn element(&self, _: &str) -> Option<ElementRef> {
        None
    }
    fn flexible(&self, _: &str) -> Option<(MarkerId, usize)> {
        None
    }
}

/// A marker on a rotating arm: angle q = z0, radius r = z1, at time t; pin at the origin.
struct Arm<T: Real> {
    q: T,
    r: T,
    qd: T,
}

impl<T: Real> ExprEnv<T> for Arm<T> {
    fn time(&self) -> T {
        T::zero()
    }
    fn param(&self, _: usize) -> T {
        T::cst(2.0)
    }
    fn input(&self, _: usize) -> T {
        T::zero()
    }
    fn variable(&self, _: usize) -> T {
        T::zero()
    }
    fn diff(&self, _: usize) -> T {
        T::zero()
    }
    fn diff_dot(&self, _: usize) -> T {
        T::zero()
    }
    fn pose(&self, m: MarkerId) -> Pose<T> {
        if m == 1 {
            return Pose { p: V3::zero(), r: M3::identity() };
        }
        let r = rot_z(self.q);
        Pose { p: r.col(0).mul_s(self.r), r }
    }
    fn twist(&self, m: MarkerId) -> Twist<T> {
        if m == 1 {
            return Twist { v: V3::zero(), w: V3::zero() };
        }
        let w = V3::new(T::zero(), T::zero(), self.qd);
        Twist { v: w.cross(&self.pose(m).p), w }
    }
    fn accel(&self, _: MarkerId) -> Twist<T> {
        Twist { v: V3::zero(), w: V3::zero() }
    }
    fn load(&self, _: LoadFn, _: ElementRef) -> T {
        T::zero()
    }
}

#[test]
fn arm_angle_distance_and_tip_speed_with_exact_partials() {
    type D = Dual<f64, 3>;
    // Seeded on q, r, q̇.
    let env = Arm { q: D::var(0.3, 0), r: D::var(1.5, 1), qd: D::var(2.0, 2) };
    let e = parse("k * az(arm, ground.O) + dm(arm) + vm(arm)", &OneBody).unwrap();
    let d = deps(&e);
    assert_eq!((d.markers, d.level, d.params), (vec![0, 1], 1, vec![0]));
    // 2 q + r + r q̇ = 0.6 + 1.5 + 3
    let v = eval(&e, &env);
    assert!((v.v - 5.1).abs() < 1e-12);
    // ∂/∂q = 2, ∂/∂r = 1 + q̇ = 3, ∂/∂q̇ = r = 1.5
    for (got, want) in v.d.iter().zip([2.0, 3.0, 1.5]) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    assert!(!is_constant(&e));
    assert_eq!(const_value(&parse("k^2 + 1", &OneBody).unwrap(), &[3.0]), 10.0);
    assert_eq!(
        parse("az(arm, pin)", &OneBody).unwrap_err(),
        ExprError { offset: 8, msg: "unknown marker 'pin'".into() }
    );
}
