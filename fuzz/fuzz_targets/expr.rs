//! Expressions: any bytes, read as (lossy) UTF-8 text, parsed against a fixed scope, then
//! analysed (`deps`, `is_constant`, `angle_count`) and evaluated with `f64`, with dual
//! numbers (first derivatives) and with nested dual numbers (second derivatives), at a
//! generic point and at a degenerate one (every marker at the origin, at rest).
//!
//! Properties (a violation panics, so libFuzzer reports the input):
//! - no panic, hang or stack overflow (the parser bounds nesting at `MAX_DEPTH`);
//! - a parse error carries a character offset inside the text (or just past its end)
//!   and a message;
//! - a derivative along a direction the expression does not depend on (by `deps`) is
//!   exactly 0 (or NaN, where 0·∞ arises): `deps` is what the engine's sparsity and the
//!   FMU's structural dependencies are built from;
//! - angle measures are unwrapped in slots 0, 1, …, `angle_count − 1`, in order;
//! - a constant expression folds (`const_value`) to its evaluated value.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mbfmu::ad::{Dual, Real};
use mbfmu::geom::{V3, rot313};
use mbfmu::model::expr::{
    Deps, ElementRef, Expr, ExprEnv, LoadFn, MarkerId, ModalFn, NameRef, Pose, Scope, Twist, angle_count, const_value,
    deps, eval, function_names, is_constant, parse,
};
use std::cell::RefCell;

/// Names resolve so that expressions taken from the example models parse too: p0 p1 (parameters),
/// u0 (input), v0 (variable), x0 (differential), markers a (id 0), b.m (1), ground.O (2,
/// fixed), elements j1 (joint), s0 (sforce); any other name resolves by its hash to one
/// of these, or to nothing (one name in eight is unknown, and function names are never
/// bare names, as in a model).
struct FuzzScope;

fn hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

impl Scope for FuzzScope {
    fn name(&self, name: &str) -> Option<NameRef> {
        Some(match name {
            "p0" => NameRef::Param(0),
            "p1" => NameRef::Param(1),
            "u0" => NameRef::Input(0),
            "v0" => NameRef::Variable(0),
            "x0" => NameRef::Diff(0),
            // As in a model, where no element may take a function's name.
            _ if function_names().contains(&name) => return None,
            _ => match hash(name) % 8 {
                0 | 1 => NameRef::Param(0),
                2 => NameRef::Param(1),
                3 => NameRef::Input(0),
                4 => NameRef::Variable(0),
                5 | 6 => NameRef::Diff(0),
                _ => return None,
            },
        })
    }
    fn marker(&self, name: &str) -> Option<MarkerId> {
        Some(match name {
            "a" => 0,
            "b.m" => 1,
            "ground.O" => 2,
            _ => match hash(name) % 8 {
                7 => return None,
                h => (h % 3) as MarkerId,
            },
        })
    }
    fn element(&self, name: &str) -> Option<ElementRef> {
        Some(match name {
            "j1" => ElementRef::Joint(1),
            "s0" => ElementRef::Sforce(0),
            _ => match hash(name) % 8 {
                7 => return None,
                h if h % 2 == 0 => ElementRef::Joint(1),
                _ => ElementRef::Sforce(0),
            },
        })
    }
    /// `f` (and some other names) is a flexible body with three modes, on marker a or b.
    fn flexible(&self, name: &str) -> Option<(MarkerId, usize)> {
        match name {
            "f" => Some((0, 3)),
            _ => match hash(name) % 8 {
                h @ (0 | 1) => Some((h as MarkerId, 3)),
                _ => None,
            },
        }
    }
}

/// Derivative directions, one per kind of thing an expression can read.
const D_TIME: usize = 0;
const D_P0: usize = 1;
const D_P1: usize = 2;
const D_U0: usize = 3;
const D_V0: usize = 4;
const D_X0: usize = 5;
const D_X0DOT: usize = 6;
const D_POS_A: usize = 7;
const D_POS_B: usize = 8;
const D_VEL: usize = 9;
const D_ACC: usize = 10;
const D_LOAD: usize = 11;
const N: usize = 12;

/// An environment where every quantity is a smooth function of its own direction(s),
/// so that a derivative is nonzero only where the expression reads the quantity.
struct Env<T: Real> {
    /// Scale of positions and rates: 1 (generic) or 0 (degenerate: all markers at the
    /// origin with identity axes, at rest).
    s: f64,
    var: fn(f64, usize) -> T,
    slots: RefCell<Vec<usize>>,
}

impl<T: Real> Env<T> {
    fn new(s: f64, var: fn(f64, usize) -> T) -> Self {
        Env { s, var, slots: RefCell::new(Vec::new()) }
    }
    fn v(&self, x: f64, k: usize) -> T {
        (self.var)(x, k)
    }
    /// A 3-vector depending on direction `k` (and on nothing when `s` = 0 … but still
    /// seeded, so derivatives flow).
    fn v3(&self, base: [f64; 3], k: usize) -> V3<T> {
        let x = self.v(0.0, k);
        V3([
            x + T::cst(self.s * base[0]),
            x.scale(2.0) + T::cst(self.s * base[1]),
            x.scale(-0.5) + T::cst(self.s * base[2]),
        ])
    }
}

impl<T: Real> ExprEnv<T> for Env<T> {
    fn time(&self) -> T {
        self.v(1.25 * self.s, D_TIME)
    }
    fn param(&self, i: usize) -> T {
        [self.v(1.5, D_P0), self.v(0.75, D_P1)].get(i).copied().unwrap_or(T::cst(f64::NAN))
    }
    fn input(&self, i: usize) -> T {
        if i == 0 { self.v(-0.4 * self.s, D_U0) } else { T::cst(f64::NAN) }
    }
    fn variable(&self, i: usize) -> T {
        if i == 0 { self.v(0.3 * self.s, D_V0) } else { T::cst(f64::NAN) }
    }
    fn diff(&self, i: usize) -> T {
        if i == 0 { self.v(-1.1 * self.s, D_X0) } else { T::cst(f64::NAN) }
    }
    fn diff_dot(&self, i: usize) -> T {
        if i == 0 { self.v(0.9 * self.s, D_X0DOT) } else { T::cst(f64::NAN) }
    }
    fn pose(&self, m: MarkerId) -> Pose<T> {
        let k = match m {
            0 => D_POS_A,
            1 => D_POS_B,
            _ => {
                let r = rot313(T::cst(0.4 * self.s), T::cst(0.9 * self.s), T::cst(-1.2 * self.s));
                return Pose { p: V3::cst([0.5 * self.s, -0.2 * self.s, 0.1 * self.s]), r };
            }
        };
        let o = if m == 0 { [0.3, -0.7, 1.1] } else { [-0.6, 0.2, 0.4] };
        let x = self.v(0.0, k);
        let r = rot313(
            x + T::cst(0.7 * self.s * o[0]),
            x.scale(0.5) + T::cst(1.3 * self.s),
            x.scale(-1.5) + T::cst(o[2] * self.s),
        );
        Pose { p: self.v3(o, k), r }
    }
    fn twist(&self, m: MarkerId) -> Twist<T> {
        if m >= 2 {
            return Twist { v: V3::zero(), w: V3::zero() };
        }
        Twist { v: self.v3([0.8, -0.1, 0.5], D_VEL), w: self.v3([-0.3, 0.6, 1.4], D_VEL) }
    }
    fn accel(&self, m: MarkerId) -> Twist<T> {
        if m >= 2 {
            return Twist { v: V3::zero(), w: V3::zero() };
        }
        Twist { v: self.v3([0.2, 0.9, -0.8], D_ACC), w: self.v3([1.0, -0.5, 0.25], D_ACC) }
    }
    fn load(&self, f: LoadFn, e: ElementRef) -> T {
        let c = match e {
            ElementRef::Joint(_) => 1.0,
            _ => -2.0,
        };
        self.v(c * (1.0 + f as usize as f64) * self.s, D_LOAD)
    }
    fn modal(&self, f: ModalFn, m: MarkerId, k: usize) -> T {
        let x = 0.2 * (k as f64 + 1.0) * self.s;
        match (f, m) {
            (ModalFn::Rate, 0 | 1) => self.v(x, D_VEL),
            (ModalFn::Coordinate, 0) => self.v(x, D_POS_A),
            (ModalFn::Coordinate, 1) => self.v(x, D_POS_B),
            _ => T::cst(f64::NAN),
        }
    }
    fn unwrap_angle(&self, slot: usize, a: T) -> T {
        self.slots.borrow_mut().push(slot);
        a
    }
}

type D1 = Dual<f64, N>;
type D2 = Dual<Dual<f64, 2>, 2>;

fn f64_var(x: f64, _: usize) -> f64 {
    x
}
fn d1_var(x: f64, k: usize) -> D1 {
    D1::var(x, k)
}
/// Second derivatives along time (0) and marker a's position (1).
fn d2_var(x: f64, k: usize) -> D2 {
    let inner = match k {
        D_TIME => Dual::var(x, 0),
        D_POS_A => Dual::var(x, 1),
        _ => Dual::cst(x),
    };
    let mut d = D2::cst(0.0);
    d.v = inner;
    match k {
        D_TIME => d.d[0] = Dual::one(),
        D_POS_A => d.d[1] = Dual::one(),
        _ => {}
    }
    d
}

/// Whether `deps` says the expression may read direction `k`.
fn may_read(d: &Deps, k: usize) -> bool {
    match k {
        D_TIME => d.time,
        D_P0 => d.params.contains(&0),
        D_P1 => d.params.contains(&1),
        D_U0 => d.inputs.contains(&0),
        D_V0 => d.variables.contains(&0),
        D_X0 => d.diffs.contains(&0),
        D_X0DOT => d.diff_dots.contains(&0),
        D_POS_A => d.markers.contains(&0),
        D_POS_B => d.markers.contains(&1),
        D_VEL => d.level >= 1,
        D_ACC => d.level >= 2,
        D_LOAD => !d.loads.is_empty(),
        _ => true,
    }
}

fn check_slots<T: Real>(src: &str, env: &Env<T>, n: usize) {
    let slots = env.slots.borrow();
    assert!(slots.iter().copied().eq(0..n), "{src:?}: angle slots {slots:?}, angle_count {n}");
}

fuzz_target!(|data: &[u8]| {
    let src = String::from_utf8_lossy(data);
    let e: Expr = match parse(&src, &FuzzScope) {
        Ok(e) => e,
        Err(err) => {
            let len = src.chars().count();
            assert!(err.offset <= len, "{src:?}: error offset {} past the end ({len}): {}", err.offset, err.msg);
            assert!(!err.msg.is_empty(), "{src:?}: empty error message at {}", err.offset);
            return;
        }
    };
    let d = deps(&e);
    let angles = angle_count(&e);
    for s in [1.0, 0.0] {
        let env = Env::new(s, f64_var);
        let f = eval(&e, &env);
        check_slots(&src, &env, angles);
        if is_constant(&e) {
            let c = const_value(&e, &[1.5, 0.75]);
            assert!(c.to_bits() == f.to_bits() || (c.is_nan() && f.is_nan()), "{src:?}: const_value {c} but eval {f}");
        }

        let env = Env::new(s, d1_var);
        let g = eval(&e, &env);
        check_slots(&src, &env, angles);
        for (k, dk) in g.d.iter().enumerate() {
            assert!(
                may_read(&d, k) || *dk == 0.0 || dk.is_nan(),
                "{src:?}: derivative {dk} along direction {k}, which deps {d:?} says it does not read"
            );
        }

        let env = Env::new(s, d2_var);
        let _ = eval(&e, &env);
        check_slots(&src, &env, angles);
    }
});
