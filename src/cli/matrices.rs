//! Binary matrix files for `mbfmu linearize`: NumPy `.npz` (a zip of `.npy` arrays) and
//! MATLAB v4 `.mat`. Arrays are named A, B, C, D (suffix `_k` for the k-th time when
//! several were asked) plus `time`.

use super::CliError;
use crate::linearize::Linearization;
use faer::Mat;
use std::io::Write;

fn named(results: &[Linearization]) -> Vec<(String, Mat<f64>)> {
    let mut v = Vec::new();
    for (k, l) in results.iter().enumerate() {
        let sfx = if results.len() > 1 { format!("_{k}") } else { String::new() };
        for (name, m) in [("A", &l.a), ("B", &l.b), ("C", &l.c), ("D", &l.d)] {
            v.push((format!("{name}{sfx}"), m.clone()));
        }
        v.push((format!("time{sfx}"), Mat::from_fn(1, 1, |_, _| l.time)));
    }
    v
}

/// One `.npy` (format 1.0, little-endian f64, C order).
fn npy(m: &Mat<f64>) -> Vec<u8> {
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {}), }}", m.nrows(), m.ncols());
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - total % 64) % 64));
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(header.len() as u16).to_le_bytes());
    b.extend_from_slice(header.as_bytes());
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            b.extend_from_slice(&m[(i, j)].to_le_bytes());
        }
    }
    b
}

/// A NumPy `.npz` archive of the matrices.
pub fn npz(results: &[Linearization]) -> Result<Vec<u8>, CliError> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut zip = zip::ZipWriter::new(&mut buf);
        let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
        for (name, m) in named(results) {
            let err = |e: std::io::Error| CliError::io(format!("writing {name}.npy"), e);
            zip.start_file(format!("{name}.npy"), opts).map_err(|e| err(std::io::Error::other(e)))?;
            zip.write_all(&npy(&m)).map_err(err)?;
        }
        zip.finish().map_err(|e| CliError::io("writing npz", std::io::Error::other(e)))?;
    }
    Ok(buf.into_inner())
}

/// A MATLAB v4 `.mat` file (each matrix: header, name, column-major f64 data).
pub fn mat_v4(results: &[Linearization]) -> Result<Vec<u8>, CliError> {
    let mut b = Vec::new();
    for (name, m) in named(results) {
        for v in [0i32, m.nrows() as i32, m.ncols() as i32, 0, name.len() as i32 + 1] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(name.as_bytes());
        b.push(0);
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                b.extend_from_slice(&m[(i, j)].to_le_bytes());
            }
        }
    }
    Ok(b)
}
