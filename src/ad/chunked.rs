//! Jacobians of functions of many variables with a small dual number: the variables are
//! seeded a chunk at a time, one evaluation per chunk, so the dual's width (and the stack
//! it takes) stays fixed however many variables there are.

use super::{Dual, Real};
use std::ops::Range;

/// Call `f::<K>(args…, chunk)` with `chunk = 0..n` and the smallest width K of the list
/// that holds `n` variables; when `n` exceeds the widest, call `f::<widest>` once per
/// chunk of that many consecutive variables (each call seeds its chunk, the rest held
/// constant, and writes its columns). Each derivative direction of a dual number is
/// computed independently of the others, so chunked and single-pass results are equal.
macro_rules! by_width {
    ($n:expr, $f:ident, [$($k:literal),+] ( $($a:expr),* )) => {{
        let n: usize = $n;
        $crate::ad::chunked::by_width!(@go n, $f, [$($k),+] ($($a),*))
    }};
    (@go $n:ident, $f:ident, [$k:literal] ( $($a:expr),* )) => {{
        for chunk in $crate::ad::chunked::chunks($n, $k) {
            $f::<$k>($($a,)* chunk);
        }
    }};
    (@go $n:ident, $f:ident, [$k:literal, $($rest:literal),+] ( $($a:expr),* )) => {
        if $n <= $k {
            $f::<$k>($($a,)* 0..$n)
        } else {
            $crate::ad::chunked::by_width!(@go $n, $f, [$($rest),+] ($($a),*))
        }
    };
}
pub(crate) use by_width;

/// `0..n` cut into consecutive ranges of at most `width` (one empty range when n = 0).
pub fn chunks(n: usize, width: usize) -> impl Iterator<Item = Range<usize>> {
    (0..n.max(1)).step_by(width).map(move |s| s..n.min(s + width))
}

/// `x` as dual numbers: `x[i]` is variable `first + i`; the variables in `chunk` are
/// seeded (direction = variable − `chunk.start`), the others constant.
pub fn seed<const K: usize>(x: &[f64], first: usize, chunk: &Range<usize>) -> Vec<Dual<f64, K>> {
    x.iter().enumerate().map(|(i, &v)| seed_one(v, first + i, chunk)).collect()
}

/// Variable number `var` with value `v`: seeded when it lies in `chunk`, else constant.
pub fn seed_one<const K: usize>(v: f64, var: usize, chunk: &Range<usize>) -> Dual<f64, K> {
    if chunk.contains(&var) { Dual::var(v, var - chunk.start) } else { Dual::cst(v) }
}

/// Width of the dual numbers [`jacobian`] evaluates `f` with.
pub const CHUNK: usize = 8;

/// The value f(x) and the exact Jacobian ∂f/∂x (row-major, f.len() × x.len()) of `f`,
/// evaluated ⌈x.len() / CHUNK⌉ times.
pub fn jacobian(x: &[f64], f: impl Fn(&[Dual<f64, CHUNK>]) -> Vec<Dual<f64, CHUNK>>) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let mut value = Vec::new();
    let mut jac = Vec::new();
    for chunk in chunks(n, CHUNK) {
        let out = f(&seed(x, 0, &chunk));
        if chunk.start == 0 {
            value = out.iter().map(|e| e.v).collect();
            jac = vec![0.0; out.len() * n];
        }
        for (r, e) in out.iter().enumerate() {
            for i in chunk.clone() {
                jac[r * n + i] = e.d[i - chunk.start];
            }
        }
    }
    (value, jac)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x) = (Σ x_i², x_0 x_19 + sin x_7): the Jacobian of 20 variables (three chunks)
    /// equals its closed form to rounding.
    #[test]
    fn chunks_cover_every_variable() {
        let x: Vec<f64> = (0..20).map(|i| 0.1 * f64::from(i) - 0.7).collect();
        let (v, j) = jacobian(&x, |x| {
            let mut s = Dual::zero();
            for &xi in x {
                s += xi * xi;
            }
            vec![s, x[0] * x[19] + x[7].sin()]
        });
        assert_eq!(v.len(), 2);
        for i in 0..20 {
            assert!((j[i] - 2.0 * x[i]).abs() < 1e-15);
            let d = match i {
                0 => x[19],
                19 => x[0],
                7 => x[7].cos(),
                _ => 0.0,
            };
            assert!((j[20 + i] - d).abs() < 1e-15, "{i}");
        }
    }
}
