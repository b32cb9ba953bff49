//! Jacobians of functions of many variables with a small dual number: the variables are
//! seeded a chunk at a time, one evaluation per chunk, so the dual's width (and the stack
//! it takes) stays fixed however many variables there are.

use super::{Dual, Real};

/// Width of the dual numbers [`jacobian`] evaluates `f` with.
pub const CHUNK: usize = 8;

/// The value f(x) and the exact Jacobian ∂f/∂x (row-major, f.len() × x.len()) of `f`,
/// evaluated ⌈x.len() / CHUNK⌉ times.
pub fn jacobian(x: &[f64], f: impl Fn(&[Dual<f64, CHUNK>]) -> Vec<Dual<f64, CHUNK>>) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let mut value = Vec::new();
    let mut jac = Vec::new();
    for start in (0..n.max(1)).step_by(CHUNK) {
        let seeded = start..n.min(start + CHUNK);
        let xd: Vec<Dual<f64, CHUNK>> = x
            .iter()
            .enumerate()
            .map(|(i, &v)| if seeded.contains(&i) { Dual::var(v, i - start) } else { Dual::cst(v) })
            .collect();
        let out = f(&xd);
        if start == 0 {
            value = out.iter().map(|e| e.v).collect();
            jac = vec![0.0; out.len() * n];
        }
        for (r, e) in out.iter().enumerate() {
            for i in seeded.clone() {
                jac[r * n + i] = e.d[i - start];
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
