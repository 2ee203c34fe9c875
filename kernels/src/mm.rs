//! Matrix Market input and output (<https://math.nist.gov/MatrixMarket/formats.html>).
//!
//! Values are written with Rust's shortest round-trip formatting, so a write followed by
//! a read gives back the same bits.

use crate::csr::{CsrMatrix, CsrPattern};
use std::fs::File;
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::path::Path;
use std::sync::Arc;

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg)
}

/// Writes `a` as "%%MatrixMarket matrix coordinate real symmetric": the lower triangle
/// (row ≥ column) of the stored entries, 1-based, row by row. The values are assumed
/// symmetric (the upper triangle is not written).
pub fn write_matrix_market(path: &Path, a: &CsrMatrix) -> io::Result<()> {
    let mut w = BufWriter::new(File::create(path)?);
    let p = &a.pattern;
    let n = p.n();
    let rp = p.row_ptr();
    let ci = p.col_idx();
    let nnz_lower = (0..n)
        .map(|i| {
            ci[rp[i]..rp[i + 1]]
                .iter()
                .filter(|&&j| j as usize <= i)
                .count()
        })
        .sum::<usize>();
    writeln!(w, "%%MatrixMarket matrix coordinate real symmetric")?;
    writeln!(w, "% written by dfem-kernels")?;
    writeln!(w, "{n} {n} {nnz_lower}")?;
    for i in 0..n {
        for (&j, v) in ci[rp[i]..rp[i + 1]].iter().zip(&a.values[rp[i]..rp[i + 1]]) {
            if j as usize <= i {
                writeln!(w, "{} {} {v:e}", i + 1, j + 1)?;
            }
        }
    }
    w.flush()
}

/// Writes a vector as "%%MatrixMarket matrix array real general" with one column.
pub fn write_vector_market(path: &Path, b: &[f64]) -> io::Result<()> {
    let mut w = BufWriter::new(File::create(path)?);
    writeln!(w, "%%MatrixMarket matrix array real general")?;
    writeln!(w, "{} 1", b.len())?;
    for v in b {
        writeln!(w, "{v:e}")?;
    }
    w.flush()
}

/// Non-comment lines of a Matrix Market file, after the banner.
fn data_lines(path: &Path) -> io::Result<(String, Vec<String>)> {
    let r = BufReader::new(File::open(path)?);
    let mut lines = r.lines();
    let banner = lines
        .next()
        .ok_or_else(|| invalid("empty Matrix Market file".into()))??;
    if !banner.to_ascii_lowercase().starts_with("%%matrixmarket") {
        return Err(invalid(format!("not a Matrix Market file: {banner}")));
    }
    let mut data = Vec::new();
    for l in lines {
        let l = l?;
        let t = l.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        data.push(t.to_string());
    }
    Ok((banner.to_ascii_lowercase(), data))
}

fn parse<T: std::str::FromStr>(s: Option<&str>, what: &str, line: &str) -> io::Result<T> {
    s.and_then(|s| s.parse().ok())
        .ok_or_else(|| invalid(format!("cannot read {what} in line '{line}'")))
}

/// Reads a square real "coordinate" matrix, "general" or "symmetric". The pattern of
/// the result is the full symmetric closure of the stored entries plus the diagonal
/// (entries added for the closure are zero); duplicate entries are summed.
pub fn read_matrix_market(path: &Path) -> io::Result<CsrMatrix> {
    let (banner, data) = data_lines(path)?;
    let words: Vec<&str> = banner.split_whitespace().collect();
    if words.len() < 5 || words[1] != "matrix" || words[2] != "coordinate" {
        return Err(invalid(format!(
            "only 'matrix coordinate' files are supported: {banner}"
        )));
    }
    if words[3] != "real" && words[3] != "integer" {
        return Err(invalid(format!(
            "only real or integer values are supported: {banner}"
        )));
    }
    let symmetric = match words[4] {
        "general" => false,
        "symmetric" => true,
        s => return Err(invalid(format!("unsupported symmetry '{s}'"))),
    };
    let mut it = data.iter();
    let size = it
        .next()
        .ok_or_else(|| invalid("missing size line".into()))?;
    let mut f = size.split_whitespace();
    let nr: usize = parse(f.next(), "rows", size)?;
    let nc: usize = parse(f.next(), "columns", size)?;
    let nnz: usize = parse(f.next(), "entries", size)?;
    if nr != nc {
        return Err(invalid(format!("matrix is not square: {nr} × {nc}")));
    }
    let mut trip = Vec::with_capacity(nnz);
    for line in it.by_ref().take(nnz) {
        let mut f = line.split_whitespace();
        let i: usize = parse(f.next(), "row", line)?;
        let j: usize = parse(f.next(), "column", line)?;
        let v: f64 = parse(f.next(), "value", line)?;
        if i == 0 || j == 0 || i > nr || j > nr {
            return Err(invalid(format!("index out of range in line '{line}'")));
        }
        trip.push((i - 1, j - 1, v));
    }
    if trip.len() != nnz {
        return Err(invalid(format!(
            "expected {nnz} entries, found {}",
            trip.len()
        )));
    }
    let pattern = Arc::new(CsrPattern::from_entries(
        nr,
        trip.iter().map(|&(i, j, _)| (i, j)),
    ));
    let mut a = CsrMatrix::zeros(pattern);
    for &(i, j, v) in &trip {
        a.add(i, j, v);
        if symmetric && i != j {
            a.add(j, i, v);
        }
    }
    Ok(a)
}

/// Reads a vector written by [`write_vector_market`] ("array" format, one column).
pub fn read_vector_market(path: &Path) -> io::Result<Vec<f64>> {
    let (banner, data) = data_lines(path)?;
    if !banner.contains("array") {
        return Err(invalid(format!("expected an 'array' file: {banner}")));
    }
    let mut it = data.iter();
    let size = it
        .next()
        .ok_or_else(|| invalid("missing size line".into()))?;
    let mut f = size.split_whitespace();
    let n: usize = parse(f.next(), "rows", size)?;
    let m: usize = parse(f.next(), "columns", size)?;
    if m != 1 {
        return Err(invalid(format!("expected one column, found {m}")));
    }
    let v = it
        .take(n)
        .map(|l| parse(Some(l.as_str()), "value", l))
        .collect::<io::Result<Vec<f64>>>()?;
    if v.len() != n {
        return Err(invalid(format!("expected {n} values, found {}", v.len())));
    }
    Ok(v)
}
