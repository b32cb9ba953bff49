//! Eigenvalues of A and the table of the seed's Tables 2–4: undamped natural frequency
//! |λ|, damping ratio −Re λ/|λ|, real and imaginary parts, one row per conjugate pair.

use faer::Mat;
use std::fmt::Write;

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
    if a.nrows() == 0 {
        return Ok(vec![]);
    }
    let ev = a.eigenvalues().map_err(|e| format!("eigenvalues: {e:?}"))?;
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
    Ok(rows)
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
