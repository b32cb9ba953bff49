//! Binary matrix files for `mbfmu linearize`: NumPy `.npz` (a zip of `.npy` arrays) and
//! MATLAB v4 `.mat`. Arrays are named A, B, C, D, `time` and the name lists `states`,
//! `inputs`, `outputs` (suffix `_k` for the k-th time when several were asked).

use super::CliError;
use crate::linearize::Linearization;
use faer::Mat;
use std::io::Write;

/// One array of a file: numbers, or a list of names.
enum Array {
    Numbers(Mat<f64>),
    Names(Vec<String>),
}

fn named(results: &[Linearization]) -> Vec<(String, Array)> {
    let mut v = Vec::new();
    for (k, l) in results.iter().enumerate() {
        let sfx = if results.len() > 1 { format!("_{k}") } else { String::new() };
        for (name, m) in [("A", &l.a), ("B", &l.b), ("C", &l.c), ("D", &l.d)] {
            v.push((format!("{name}{sfx}"), Array::Numbers(m.clone())));
        }
        v.push((format!("time{sfx}"), Array::Numbers(Mat::from_fn(1, 1, |_, _| l.time))));
        for (name, names) in [("states", &l.states), ("inputs", &l.inputs), ("outputs", &l.outputs)] {
            v.push((format!("{name}{sfx}"), Array::Names(names.clone())));
        }
    }
    v
}

/// The `.npy` header (format 1.0) for `descr` and `shape`, padded to 64 bytes.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - total % 64) % 64));
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(header.len() as u16).to_le_bytes());
    b.extend_from_slice(header.as_bytes());
    b
}

/// One `.npy` of names: little-endian UTF-32 strings of the longest name's length
/// (NumPy's `<U`), shape (k,).
fn npy_names(names: &[String]) -> Vec<u8> {
    let width = names.iter().map(|s| s.chars().count()).max().unwrap_or(0).max(1);
    let mut b = npy_header(&format!("<U{width}"), &format!("({},)", names.len()));
    for s in names {
        let mut n = 0;
        for c in s.chars() {
            b.extend_from_slice(&(c as u32).to_le_bytes());
            n += 1;
        }
        b.extend(std::iter::repeat_n(0u8, 4 * (width - n)));
    }
    b
}

/// One `.npy` (format 1.0, little-endian f64, C order).
fn npy(m: &Mat<f64>) -> Vec<u8> {
    let mut b = npy_header("<f8", &format!("({}, {})", m.nrows(), m.ncols()));
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
        for (name, a) in named(results) {
            let err = |e: std::io::Error| CliError::io(format!("writing {name}.npy"), e);
            zip.start_file(format!("{name}.npy"), opts).map_err(|e| err(std::io::Error::other(e)))?;
            let bytes = match &a {
                Array::Numbers(m) => npy(m),
                Array::Names(n) => npy_names(n),
            };
            zip.write_all(&bytes).map_err(err)?;
        }
        zip.finish().map_err(|e| CliError::io("writing npz", std::io::Error::other(e)))?;
    }
    Ok(buf.into_inner())
}

/// A MATLAB v4 `.mat` file (each matrix: header, name, column-major f64 data). Names are
/// text matrices (type 1): one name per row, padded with blanks, character codes as f64.
pub fn mat_v4(results: &[Linearization]) -> Result<Vec<u8>, CliError> {
    let mut b = Vec::new();
    for (name, a) in named(results) {
        let (kind, m) = match a {
            Array::Numbers(m) => (0i32, m),
            Array::Names(names) => {
                let rows: Vec<Vec<char>> = names.iter().map(|s| s.chars().collect()).collect();
                let width = rows.iter().map(Vec::len).max().unwrap_or(0);
                let m = Mat::from_fn(rows.len(), width, |i, j| rows[i].get(j).map_or(32.0, |&c| c as u32 as f64));
                (1, m)
            }
        };
        for v in [kind, m.nrows() as i32, m.ncols() as i32, 0, name.len() as i32 + 1] {
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
