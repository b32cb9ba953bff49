//! Dual numbers `v + Σ d_k ε_k` with `N` independent infinitesimal directions.

use super::Real;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A dual number over scalar `T` with `N` derivative directions.
/// Nesting (`Dual<Dual<f64, N>, N>`) gives second derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<T: Real, const N: usize> {
    /// Value.
    pub v: T,
    /// Derivatives along each of the `N` seeded directions.
    pub d: [T; N],
}

impl<T: Real, const N: usize> Dual<T, N> {
    /// The independent variable number `k` with value `v` (derivative 1 along `k`).
    pub fn var(v: T, k: usize) -> Self {
        let mut d = [T::zero(); N];
        d[k] = T::one();
        Dual { v, d }
    }
    /// Apply the chain rule: value `f`, derivative factor `df` (= f'(v)).
    #[inline]
    fn chain(&self, f: T, df: T) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= df;
        }
        Dual { v: f, d }
    }
}

impl<T: Real, const N: usize> Add for Dual<T, N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}
impl<T: Real, const N: usize> AddAssign for Dual<T, N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.v += o.v;
        for k in 0..N {
            self.d[k] += o.d[k];
        }
    }
}
impl<T: Real, const N: usize> Sub for Dual<T, N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self -= o;
        self
    }
}
impl<T: Real, const N: usize> SubAssign for Dual<T, N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        self.v -= o.v;
        for k in 0..N {
            self.d[k] -= o.d[k];
        }
    }
}
impl<T: Real, const N: usize> Mul for Dual<T, N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [T::zero(); N];
        for (k, x) in d.iter_mut().enumerate() {
            *x = self.d[k] * o.v + self.v * o.d[k];
        }
        Dual { v: self.v * o.v, d }
    }
}
impl<T: Real, const N: usize> MulAssign for Dual<T, N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl<T: Real, const N: usize> Div for Dual<T, N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = T::one() / o.v;
        let q = self.v * inv;
        let mut d = [T::zero(); N];
        for (k, x) in d.iter_mut().enumerate() {
            *x = (self.d[k] - q * o.d[k]) * inv;
        }
        Dual { v: q, d }
    }
}
impl<T: Real, const N: usize> Neg for Dual<T, N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = -*x;
        }
        Dual { v: -self.v, d }
    }
}

impl<T: Real, const N: usize> Real for Dual<T, N> {
    fn cst(v: f64) -> Self {
        Dual { v: T::cst(v), d: [T::zero(); N] }
    }
    fn val(&self) -> f64 {
        self.v.val()
    }
    fn tangent(&self) -> f64 {
        self.d.first().map_or(0.0, |x| x.val())
    }
    fn scale(self, s: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = x.scale(s);
        }
        Dual { v: self.v.scale(s), d }
    }
    #[inline]
    fn add_scaled(&mut self, x: &Self, s: f64) {
        self.v.add_scaled(&x.v, s);
        for (a, b) in self.d.iter_mut().zip(&x.d) {
            a.add_scaled(b, s);
        }
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    fn tan(self) -> Self {
        let t = self.v.tan();
        self.chain(t, T::one() + t * t)
    }
    fn asin(self) -> Self {
        self.chain(self.v.asin(), T::one() / (T::one() - self.v * self.v).sqrt())
    }
    fn acos(self) -> Self {
        self.chain(self.v.acos(), -T::one() / (T::one() - self.v * self.v).sqrt())
    }
    fn atan(self) -> Self {
        self.chain(self.v.atan(), T::one() / (T::one() + self.v * self.v))
    }
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
        let r2 = x.v * x.v + self.v * self.v;
        let mut d = [T::zero(); N];
        for (k, e) in d.iter_mut().enumerate() {
            *e = (x.v * self.d[k] - self.v * x.d[k]) / r2;
        }
        Dual { v: self.v.atan2(x.v), d }
    }
    fn sinh(self) -> Self {
        self.chain(self.v.sinh(), self.v.cosh())
    }
    fn cosh(self) -> Self {
        self.chain(self.v.cosh(), self.v.sinh())
    }
    fn tanh(self) -> Self {
        let t = self.v.tanh();
        self.chain(t, T::one() - t * t)
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), T::one() / self.v)
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        if s.val() == 0.0 {
            // √ is not differentiable at 0; along directions where the argument does not
            // change (e.g. |v|² at v = 0, so √ of it inside vm²) the derivative is 0.
            let d = self.d.map(|x| if x.val() == 0.0 { T::zero() } else { x / (s + s) });
            return Dual { v: s, d };
        }
        self.chain(s, T::one() / (s + s))
    }
    fn powf(self, p: f64) -> Self {
        if p == 0.0 {
            return Self::one();
        }
        self.chain(self.v.powf(p), self.v.powf(p - 1.0).scale(p))
    }
    fn pow(self, y: Self) -> Self {
        if y.is_constant() {
            return self.powf(y.val());
        }
        (y * self.ln()).exp()
    }
    fn is_constant(&self) -> bool {
        self.v.is_constant() && self.d.iter().all(|e| e.val() == 0.0 && e.is_constant())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_rule_and_nested_second_derivative() {
        // f(x, y) = x^2 y ; f_x = 2xy, f_xy = 2x, f_xx = 2y
        type D1 = Dual<f64, 2>;
        type D2 = Dual<D1, 2>;
        let x = D2 { v: D1::var(3.0, 0), d: [D1::one(), D1::zero()] };
        let y = D2 { v: D1::var(5.0, 1), d: [D1::zero(), D1::one()] };
        let f = x * x * y;
        assert_eq!(f.v.v, 45.0);
        assert_eq!(f.d[0].v, 30.0);
        assert_eq!(f.d[0].d[0], 10.0);
        assert_eq!(f.d[0].d[1], 6.0);
        assert_eq!(f.d[1].d[0], 6.0);
    }
}
