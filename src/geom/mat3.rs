//! 3x3 matrix (rotation matrices, inertia).

use super::V3;
use crate::ad::Real;
use std::ops::Mul;

/// A 3x3 matrix over a [`Real`] scalar, row-major: `self.0[row][col]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct M3<T: Real>(pub [[T; 3]; 3]);

impl<T: Real> M3<T> {
    /// The identity.
    pub fn identity() -> Self {
        let (o, z) = (T::one(), T::zero());
        M3([[o, z, z], [z, o, z], [z, z, o]])
    }
    /// Lift a constant `f64` matrix.
    pub fn cst(m: &[[f64; 3]; 3]) -> Self {
        M3(m.map(|r| r.map(T::cst)))
    }
    /// Values only.
    pub fn val(&self) -> [[f64; 3]; 3] {
        self.0.map(|r| r.map(|x| x.val()))
    }
    /// Column `k` (for a rotation: the k-th axis of the rotated frame).
    pub fn col(&self, k: usize) -> V3<T> {
        V3([self.0[0][k], self.0[1][k], self.0[2][k]])
    }
    /// Transpose.
    pub fn t(&self) -> Self {
        let a = &self.0;
        M3([[a[0][0], a[1][0], a[2][0]], [a[0][1], a[1][1], a[2][1]], [a[0][2], a[1][2], a[2][2]]])
    }
    /// Matrix-vector product.
    pub fn mv(&self, v: &V3<T>) -> V3<T> {
        let a = &self.0;
        let x = &v.0;
        V3([
            a[0][0] * x[0] + a[0][1] * x[1] + a[0][2] * x[2],
            a[1][0] * x[0] + a[1][1] * x[1] + a[1][2] * x[2],
            a[2][0] * x[0] + a[2][1] * x[1] + a[2][2] * x[2],
        ])
    }
    /// Transpose-vector product `selfᵀ v`.
    pub fn tv(&self, v: &V3<T>) -> V3<T> {
        let a = &self.0;
        let x = &v.0;
        V3([
            a[0][0] * x[0] + a[1][0] * x[1] + a[2][0] * x[2],
            a[0][1] * x[0] + a[1][1] * x[1] + a[2][1] * x[2],
            a[0][2] * x[0] + a[1][2] * x[1] + a[2][2] * x[2],
        ])
    }
    /// Matrix product.
    pub fn mm(&self, o: &Self) -> Self {
        let mut r = [[T::zero(); 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, e) in row.iter_mut().enumerate() {
                *e = self.0[i][0] * o.0[0][j] + self.0[i][1] * o.0[1][j] + self.0[i][2] * o.0[2][j];
            }
        }
        M3(r)
    }
}

impl<T: Real> Mul for M3<T> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        self.mm(&o)
    }
}
