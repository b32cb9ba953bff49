//! Eigenvalues of A and the table of the seed's Tables 2–4: undamped natural frequency
//! |λ|, damping ratio −Re λ/|λ|, real and imaginary parts, one row per conjugate pair.
//! When the states are s positions and their s rates and nothing feeds back the rates,
//! A = [0 I; X 0] and λ = ±√μ for the s eigenvalues μ of X: a dense eigenproblem of size
//! s instead of 2s (about 8× less work); otherwise the general one ([`EigenRoute`]).

use faer::{Mat, MatRef, c64};
use std::fmt::Write;

/// How the eigenvalues were computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EigenRoute {
    /// A = [0 I; X 0] (undamped, no gyroscopic or velocity terms): λ² = eig(X), X of size s.
    SecondOrder {
        /// Number of position states.
        s: usize,
    },
    /// The general dense eigenproblem of A (n × n).
    General {
        /// Number of states.
        n: usize,
    },
}

impl EigenRoute {
    /// One line for reports.
    pub fn describe(&self) -> String {
        match self {
            EigenRoute::SecondOrder { s } => {
                format!("second-order route: A = [0 I; X 0], lambda^2 = eig(X), X {s} x {s}")
            }
            EigenRoute::General { n } => format!("general route: eig(A), A {n} x {n}"),
        }
    }
}

/// X when A = [0 I; X Y] with Y = 0 for `s0` position states followed by as many rate
/// states and nothing else: the blocks 0 and I to round-off (1e-13 relative to A's largest
/// entry) and Y negligible (1e-13 relative to √max|X|, the scale of the rates' eigenvalues).
fn second_order_block(a: MatRef<'_, f64>, s0: usize, s1: usize) -> Option<MatRef<'_, f64>> {
    let n = a.nrows();
    if s0 == 0 || s1 != s0 || n != 2 * s0 {
        return None;
    }
    let amax = (0..n).flat_map(|j| (0..n).map(move |i| (i, j))).map(|(i, j)| a[(i, j)].abs()).fold(0.0, f64::max);
    let eps = 1e-13 * amax.max(1.0);
    for j in 0..n {
        for i in 0..s0 {
            let want = if j == s0 + i { 1.0 } else { 0.0 };
            if (a[(i, j)] - want).abs() > eps {
                return None;
            }
        }
    }
    let x = a.submatrix(s0, 0, s0, s0);
    let xmax = (0..s0).flat_map(|j| (0..s0).map(move |i| (i, j))).map(|(i, j)| x[(i, j)].abs()).fold(0.0, f64::max);
    let yeps = 1e-13 * xmax.sqrt().max(1.0);
    let y_zero = (0..s0).all(|j| (0..s0).all(|i| a[(s0 + i, s0 + j)].abs() <= yeps));
    y_zero.then_some(x)
}

/// The eigenvalues of A with the route taken: [`EigenRoute::SecondOrder`] when the first
/// `s0` states are positions whose rates are the next `s1` (= s0) states, the last, and A
/// has that structure; else [`EigenRoute::General`].
pub fn eigenvalues(a: &Mat<f64>, s0: usize, s1: usize) -> Result<(Vec<c64>, EigenRoute), String> {
    if let Some(x) = second_order_block(a.as_ref(), s0, s1) {
        let mu = x.to_owned().eigenvalues().map_err(|e| format!("eigenvalues: {e:?}"))?;
        // λ = ±√μ: the principal root (Re ≥ 0) and its negative.
        let mut ev = Vec::with_capacity(2 * mu.len());
        for m in mu {
            let r = c64::new(m.re, m.im).sqrt();
            ev.push(r);
            ev.push(-r);
        }
        return Ok((ev, EigenRoute::SecondOrder { s: s0 }));
    }
    Ok((general_eigenvalues(a)?, EigenRoute::General { n: a.nrows() }))
}

/// The eigenvalues of A by the general dense eigensolver (none for an empty A).
fn general_eigenvalues(a: &Mat<f64>) -> Result<Vec<c64>, String> {
    if a.nrows() == 0 {
        return Ok(vec![]);
    }
    a.eigenvalues().map_err(|e| format!("eigenvalues: {e:?}"))
}

/// [`eigen_table`] by the cheapest route that fits (see [`eigenvalues`]), and that route.
pub fn eigen_table_structured(a: &Mat<f64>, s0: usize, s1: usize) -> Result<(Vec<EigenRow>, EigenRoute), String> {
    let (ev, route) = eigenvalues(a, s0, s1)?;
    Ok((rows_of_eigenvalues(&ev), route))
}

/// One row of the eigenvalue table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EigenRow {
    /// Undamped natural frequency |λ| (rad/s).
    pub frequency: f64,
    /// Damping ratio −Re λ / |λ| (1 for a real negative root; NaN for λ = 0).
    pub damping: f64,
    /// Real part Re λ (1/s); negative for a decaying mode.
    pub re: f64,
    /// Imaginary part (≥ 0: one row per conjugate pair).
    pub im: f64,
}

/// Eigenvalues of `a` as table rows: real roots first, then complex pairs, each group by
/// increasing frequency (as the seed's Table 2).
pub fn eigen_table(a: &Mat<f64>) -> Result<Vec<EigenRow>, String> {
    Ok(rows_of_eigenvalues(&general_eigenvalues(a)?))
}

/// Table rows of eigenvalues `ev` (a set closed under conjugation).
pub fn rows_of_eigenvalues(ev: &[c64]) -> Vec<EigenRow> {
    let scale = ev.iter().map(|z| z.re.hypot(z.im)).fold(0.0, f64::max).max(1.0);
    let mut rows: Vec<EigenRow> = ev
        .iter()
        .filter(|z| z.im >= -1e-12 * scale)
        .map(|z| {
            let im = if z.im.abs() <= 1e-12 * scale { 0.0 } else { z.im };
            let f = z.re.hypot(im);
            // + 0.0 turns a −0 into +0 for printing.
            EigenRow { frequency: f, damping: if f > 0.0 { -z.re / f + 0.0 } else { f64::NAN }, re: z.re + 0.0, im }
        })
        .collect();
    rows.sort_by(|x, y| (x.im != 0.0).cmp(&(y.im != 0.0)).then(x.frequency.total_cmp(&y.frequency)));
    rows
}

/// The table as text, in the seed's format with the frequency also in Hz (|λ|/2π).
pub fn format_table(rows: &[EigenRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{:>14} {:>14} {:>14} {:>14} {:>14}", "Undmp. Freq.", "(Hz)", "Damping Ratio", "Real", "Imag");
    for r in rows {
        let hz = r.frequency / (2.0 * std::f64::consts::PI);
        let _ =
            writeln!(s, "{:>14.6e} {:>14.6e} {:>14.6e} {:>14.6e} {:>14.6e}", r.frequency, hz, r.damping, r.re, r.im);
    }
    s
}
