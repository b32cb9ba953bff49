//! The scalar trait shared by `f64` and dual numbers.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real scalar: `f64`, or a dual number carrying exact derivatives.
pub trait Real:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + 'static
{
    /// A constant (all derivatives zero).
    fn cst(v: f64) -> Self;
    /// The value part (derivatives dropped).
    fn val(&self) -> f64;
    /// Multiply by a plain number.
    fn scale(self, s: f64) -> Self;
    /// `self += x·s` for a plain number `s`, in place (no temporaries: the modal sums
    /// of flexible bodies run over many wide dual numbers).
    fn add_scaled(&mut self, x: &Self, s: f64) {
        *self += x.scale(s);
    }
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn tan(self) -> Self;
    fn asin(self) -> Self;
    fn acos(self) -> Self;
    fn atan(self) -> Self;
    /// `atan2(self, x)`.
    fn atan2(self, x: Self) -> Self;
    fn sinh(self) -> Self;
    fn cosh(self) -> Self;
    fn tanh(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    fn sqrt(self) -> Self;
    /// `self^p` for a constant exponent.
    fn powf(self, p: f64) -> Self;
    /// Absolute value (derivative `sign(x)`, 0 at 0).
    fn abs(self) -> Self {
        if self.val() < 0.0 { -self } else { self }
    }
    /// `self^y` with both varying: `exp(y ln self)`, with integer-power special cases.
    fn pow(self, y: Self) -> Self;
    /// True when no derivative is carried at any nesting level.
    fn is_constant(&self) -> bool;
    /// The first derivative component's value (0 for a plain number).
    fn tangent(&self) -> f64 {
        0.0
    }
    /// Zero.
    fn zero() -> Self {
        Self::cst(0.0)
    }
    /// One.
    fn one() -> Self {
        Self::cst(1.0)
    }
}

impl Real for f64 {
    fn cst(v: f64) -> Self {
        v
    }
    fn val(&self) -> f64 {
        *self
    }
    fn scale(self, s: f64) -> Self {
        self * s
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn tan(self) -> Self {
        f64::tan(self)
    }
    fn asin(self) -> Self {
        f64::asin(self)
    }
    fn acos(self) -> Self {
        f64::acos(self)
    }
    fn atan(self) -> Self {
        f64::atan(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    fn sinh(self) -> Self {
        f64::sinh(self)
    }
    fn cosh(self) -> Self {
        f64::cosh(self)
    }
    fn tanh(self) -> Self {
        f64::tanh(self)
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn ln(self) -> Self {
        f64::ln(self)
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn powf(self, p: f64) -> Self {
        f64::powf(self, p)
    }
    fn pow(self, y: Self) -> Self {
        f64::powf(self, y)
    }
    fn is_constant(&self) -> bool {
        true
    }
}
