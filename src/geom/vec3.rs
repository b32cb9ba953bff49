//! 3-vector.

use crate::ad::Real;
use std::ops::{Add, Mul, Neg, Sub};

/// A 3-vector over a [`Real`] scalar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T: Real>(pub [T; 3]);

impl<T: Real> V3<T> {
    /// From components.
    pub fn new(x: T, y: T, z: T) -> Self {
        V3([x, y, z])
    }
    /// The zero vector.
    pub fn zero() -> Self {
        V3([T::zero(); 3])
    }
    /// Lift a constant `f64` vector.
    pub fn cst(v: [f64; 3]) -> Self {
        V3([T::cst(v[0]), T::cst(v[1]), T::cst(v[2])])
    }
    /// Values only.
    pub fn val(&self) -> [f64; 3] {
        [self.0[0].val(), self.0[1].val(), self.0[2].val()]
    }
    /// Dot product.
    pub fn dot(&self, o: &Self) -> T {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    /// Cross product.
    pub fn cross(&self, o: &Self) -> Self {
        let (a, b) = (&self.0, &o.0);
        V3([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
    }
    /// Euclidean norm.
    pub fn norm(&self) -> T {
        self.dot(self).sqrt()
    }
    /// Multiply by a scalar.
    pub fn mul_s(&self, s: T) -> Self {
        V3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
    /// Component `k`.
    pub fn at(&self, k: usize) -> T {
        self.0[k]
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        V3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}
impl<T: Real> Sub for V3<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        V3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl<T: Real> Neg for V3<T> {
    type Output = Self;
    fn neg(self) -> Self {
        V3([-self.0[0], -self.0[1], -self.0[2]])
    }
}
impl<T: Real> Mul<T> for V3<T> {
    type Output = Self;
    fn mul(self, s: T) -> Self {
        self.mul_s(s)
    }
}
