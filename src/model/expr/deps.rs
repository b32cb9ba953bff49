//! What an expression depends on, and constant folding.

use super::ast::{ElementRef, Expr, MarkerId};
use super::env::{ExprEnv, Pose, Twist};
use super::eval::eval;
use crate::geom::{M3, V3};

/// Everything an expression reads. Every list is sorted and free of duplicates.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Deps {
    /// Markers named in kinematic measures (i, j and k), and the `cm` markers of the
    /// flexible bodies whose modal coordinates it reads.
    pub markers: Vec<MarkerId>,
    /// Highest [`super::KinFn::level`] (or [`super::ModalFn::level`]) of its kinematic
    /// and modal measures; 0 if none.
    pub level: u8,
    /// Reads `time`.
    pub time: bool,
    /// Parameter indices.
    pub params: Vec<usize>,
    /// Input indices.
    pub inputs: Vec<usize>,
    /// User variable indices.
    pub variables: Vec<usize>,
    /// Differential states (`dif(x)` or bare `x`).
    pub diffs: Vec<usize>,
    /// Differential state derivatives (`dif1(x)`).
    pub diff_dots: Vec<usize>,
    /// Elements whose loads it reads, ordered by kind (joint, motion, constraint,
    /// spring-damper, sforce, gforce) then index.
    pub loads: Vec<ElementRef>,
}

/// The dependencies of `e`.
pub fn deps(e: &Expr) -> Deps {
    let mut d = Deps::default();
    collect(e, &mut d);
    for v in [&mut d.markers, &mut d.params, &mut d.inputs, &mut d.variables, &mut d.diffs, &mut d.diff_dots] {
        v.sort_unstable();
        v.dedup();
    }
    d.loads.sort_unstable_by_key(|r| element_key(*r));
    d.loads.dedup();
    d
}

fn element_key(r: ElementRef) -> (u8, usize) {
    match r {
        ElementRef::Joint(i) => (0, i),
        ElementRef::Motion(i) => (1, i),
        ElementRef::Constraint(i) => (2, i),
        ElementRef::SpringDamper(i) => (3, i),
        ElementRef::Sforce(i) => (4, i),
        ElementRef::Gforce(i) => (5, i),
        ElementRef::Bushing(i) => (6, i),
    }
}

fn collect(e: &Expr, d: &mut Deps) {
    match e {
        Expr::Num(_) => {}
        Expr::Time => d.time = true,
        Expr::Param(i) => d.params.push(*i),
        Expr::Input(i) => d.inputs.push(*i),
        Expr::Variable(i) => d.variables.push(*i),
        Expr::Diff(i) => d.diffs.push(*i),
        Expr::DiffDot(i) => d.diff_dots.push(*i),
        Expr::Neg(a) => collect(a, d),
        Expr::Bin(_, a, b) => {
            collect(a, d);
            collect(b, d);
        }
        Expr::Math(_, args) => args.iter().for_each(|a| collect(a, d)),
        Expr::Kin(f, i, j, k) => {
            d.markers.push(*i);
            d.markers.extend(j);
            d.markers.extend(k);
            d.level = d.level.max(f.level());
        }
        Expr::Load(_, r) => d.loads.push(*r),
        Expr::Modal(f, m, _) => {
            d.markers.push(*m);
            d.level = d.level.max(f.level());
        }
    }
}

/// True when `e` is built from numbers, `pi` and parameters only.
pub fn is_constant(e: &Expr) -> bool {
    match e {
        Expr::Num(_) | Expr::Param(_) => true,
        Expr::Neg(a) => is_constant(a),
        Expr::Bin(_, a, b) => is_constant(a) && is_constant(b),
        Expr::Math(_, args) => args.iter().all(is_constant),
        _ => false,
    }
}

/// Value of a constant expression (see [`is_constant`]) with parameter values `params`.
/// Anything else (a parameter index out of range, time, a marker ...) evaluates to NaN.
pub fn const_value(e: &Expr, params: &[f64]) -> f64 {
    eval(e, &ConstEnv(params))
}

/// An environment holding only parameter values.
struct ConstEnv<'a>(&'a [f64]);

impl ExprEnv<f64> for ConstEnv<'_> {
    fn time(&self) -> f64 {
        f64::NAN
    }
    fn param(&self, i: usize) -> f64 {
        self.0.get(i).copied().unwrap_or(f64::NAN)
    }
    fn input(&self, _: usize) -> f64 {
        f64::NAN
    }
    fn variable(&self, _: usize) -> f64 {
        f64::NAN
    }
    fn diff(&self, _: usize) -> f64 {
        f64::NAN
    }
    fn diff_dot(&self, _: usize) -> f64 {
        f64::NAN
    }
    fn pose(&self, _: MarkerId) -> Pose<f64> {
        Pose { p: V3::cst([f64::NAN; 3]), r: M3::cst(&[[f64::NAN; 3]; 3]) }
    }
    fn twist(&self, _: MarkerId) -> Twist<f64> {
        Twist { v: V3::cst([f64::NAN; 3]), w: V3::cst([f64::NAN; 3]) }
    }
    fn accel(&self, m: MarkerId) -> Twist<f64> {
        self.twist(m)
    }
    fn load(&self, _: super::ast::LoadFn, _: ElementRef) -> f64 {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::expr::{BinOp, KinFn, LoadFn, MathFn};

    #[test]
    fn deps_are_sorted_unique_and_level_is_the_maximum() {
        let b = |x: Expr| Box::new(x);
        let e = Expr::Bin(
            BinOp::Add,
            b(Expr::Math(
                MathFn::Max,
                vec![Expr::Kin(KinFn::Vx, 4, Some(1), Some(4)), Expr::Kin(KinFn::Dx, 2, None, None)],
            )),
            b(Expr::Bin(
                BinOp::Mul,
                b(Expr::Math(
                    MathFn::Step,
                    vec![
                        Expr::Time,
                        Expr::Param(3),
                        Expr::Param(1),
                        Expr::Input(2),
                        Expr::Load(LoadFn::Fx, ElementRef::Sforce(0)),
                    ],
                )),
                b(Expr::Math(
                    MathFn::If,
                    vec![
                        Expr::Param(3),
                        Expr::Diff(1),
                        Expr::Neg(b(Expr::Bin(
                            BinOp::Sub,
                            b(Expr::DiffDot(0)),
                            b(Expr::Load(LoadFn::Tz, ElementRef::Joint(5))),
                        ))),
                    ],
                )),
            )),
        );
        let d = deps(&e);
        assert_eq!(d.markers, vec![1, 2, 4]);
        assert_eq!(d.level, 1);
        assert!(d.time);
        assert_eq!(d.params, vec![1, 3]);
        assert_eq!(d.inputs, vec![2]);
        assert!(d.variables.is_empty());
        assert_eq!(d.diffs, vec![1]);
        assert_eq!(d.diff_dots, vec![0]);
        assert_eq!(d.loads, vec![ElementRef::Joint(5), ElementRef::Sforce(0)]);
        assert!(!is_constant(&e));

        let acc =
            Expr::Bin(BinOp::Add, b(Expr::Kin(KinFn::Accz, 0, None, None)), b(Expr::Kin(KinFn::Dm, 0, None, None)));
        assert_eq!(deps(&acc).level, 2);
        assert_eq!(deps(&Expr::Num(1.0)), Deps::default());
    }

    #[test]
    fn constants_fold_with_parameter_values() {
        let b = |x: Expr| Box::new(x);
        // 2 * p1 ^ 2 - sqrt(p0), p = [4, 3]: 18 - 2 = 16
        let e = Expr::Bin(
            BinOp::Sub,
            b(Expr::Bin(BinOp::Mul, b(Expr::Num(2.0)), b(Expr::Bin(BinOp::Pow, b(Expr::Param(1)), b(Expr::Num(2.0)))))),
            b(Expr::Math(MathFn::Sqrt, vec![Expr::Param(0)])),
        );
        assert!(is_constant(&e));
        assert_eq!(const_value(&e, &[4.0, 3.0]), 16.0);
        assert!(const_value(&e, &[4.0]).is_nan());
        assert!(!is_constant(&Expr::Time));
        assert!(!is_constant(&Expr::Math(MathFn::Sin, vec![Expr::Input(0)])));
    }
}
