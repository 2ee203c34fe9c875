//! Reading back what dfem wrote: the ASCII `.vtu` files of `vtk.rs`, `summary.json` and
//! `curve.csv`, for `dfem plot DIR`. Only the subset of VTK XML that dfem writes is read:
//! `<DataArray ... Name="..." ...>values</DataArray>` with ASCII values.

use crate::analysis::dynamics::History;
use crate::{Error, Result};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The named data arrays of one `.vtu` file (values as f64; integers are exact up to 2⁵³).
#[derive(Debug, Clone, Default)]
pub struct Vtu {
    pub arrays: HashMap<String, Vec<f64>>,
}

fn damaged(path: &Path, what: impl std::fmt::Display) -> Error {
    Error::new(format!("cannot read the result file: {what}"))
        .file(path)
        .fix("this file was not written by dfem or is damaged; run the analysis again")
}

impl Vtu {
    /// Parse the text of a `.vtu` file written by dfem.
    pub fn parse(text: &str, path: &Path) -> Result<Vtu> {
        let mut arrays = HashMap::new();
        let mut rest = text;
        while let Some(start) = rest.find("<DataArray") {
            let after = &rest[start..];
            let head_end = after
                .find('>')
                .ok_or_else(|| damaged(path, "a <DataArray> tag is not closed"))?;
            let head = &after[..head_end];
            let name = attribute(head, "Name")
                .ok_or_else(|| damaged(path, "a <DataArray> has no Name"))?;
            let body_start = head_end + 1;
            let body_len = after[body_start..]
                .find("</DataArray>")
                .ok_or_else(|| damaged(path, format!("array '{name}' is not closed")))?;
            let body = &after[body_start..body_start + body_len];
            let values = body
                .split_ascii_whitespace()
                .map(|v| v.parse::<f64>())
                .collect::<std::result::Result<Vec<f64>, _>>()
                .map_err(|e| damaged(path, format!("array '{name}': {e}")))?;
            arrays.insert(name.to_string(), values);
            rest = &after[body_start + body_len..];
        }
        Ok(Vtu { arrays })
    }

    /// Read and parse a `.vtu` file.
    pub fn read(path: &Path) -> Result<Vtu> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::new(format!("cannot read the result file: {e}"))
                .file(path)
                .fix("check that the run finished and wrote its ParaView files")
        })?;
        Vtu::parse(&text, path)
    }

    /// The array `name`, which must exist.
    pub fn array(&self, name: &str, path: &Path) -> Result<&[f64]> {
        self.arrays
            .get(name)
            .map(|v| v.as_slice())
            .ok_or_else(|| damaged(path, format!("it has no data array '{name}'")))
    }

    /// Points (x, y) of the piece.
    pub fn points(&self, path: &Path) -> Result<Vec<[f64; 2]>> {
        Ok(self
            .array("Points", path)?
            .chunks_exact(3)
            .map(|p| [p[0], p[1]])
            .collect())
    }

    /// A 3-component point vector (x, y) such as `displacement_m`, one per point.
    pub fn vectors(&self, name: &str, n: usize, path: &Path) -> Result<Vec<[f64; 2]>> {
        let a = self.array(name, path)?;
        if a.len() != 3 * n {
            return Err(damaged(
                path,
                format!("'{name}' has {} values for {n} points", a.len()),
            ));
        }
        Ok(a.chunks_exact(3).map(|p| [p[0], p[1]]).collect())
    }

    /// Cells as lists of point indices, checked against the number of points.
    pub fn cells(&self, n_points: usize, path: &Path) -> Result<Vec<Vec<u32>>> {
        let conn = self.array("connectivity", path)?;
        let offsets = self.array("offsets", path)?;
        let mut cells = Vec::with_capacity(offsets.len());
        let mut start = 0usize;
        for &o in offsets {
            let end = o as usize;
            if o < 0.0 || end < start || end > conn.len() {
                return Err(damaged(path, "the cell offsets are out of range"));
            }
            let cell: Vec<u32> = conn[start..end].iter().map(|&v| v as u32).collect();
            if cell.iter().any(|&v| v as usize >= n_points) {
                return Err(damaged(
                    path,
                    "a cell refers to a point that does not exist",
                ));
            }
            cells.push(cell);
            start = end;
        }
        Ok(cells)
    }
}

fn attribute<'a>(head: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let i = head.find(&pat)? + pat.len();
    let len = head[i..].find('"')?;
    Some(&head[i..i + len])
}

/// The last step written in `dir`: the highest NNNN with both `blocks_NNNN.vtu` and
/// `contacts_NNNN.vtu` present.
pub fn last_step(dir: &Path) -> Result<(PathBuf, PathBuf)> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        Error::new(format!("cannot read the results directory: {e}"))
            .file(dir)
            .fix("give the directory that `dfem run --out DIR` wrote")
    })?;
    let mut best: Option<u64> = None;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some(k) = name
            .strip_prefix("blocks_")
            .and_then(|r| r.strip_suffix(".vtu"))
            .and_then(|k| k.parse::<u64>().ok())
        {
            if dir.join(format!("contacts_{k:04}.vtu")).is_file() && best.is_none_or(|b| k > b) {
                best = Some(k);
            }
        }
    }
    let k = best.ok_or_else(|| {
        Error::new("there are no ParaView results (blocks_NNNN.vtu and contacts_NNNN.vtu) to draw")
            .file(dir)
            .fix("run the analysis into this directory first (`dfem run SCENE --out DIR`), with [output] vtk = true")
    })?;
    Ok((
        dir.join(format!("blocks_{k:04}.vtu")),
        dir.join(format!("contacts_{k:04}.vtu")),
    ))
}

/// Read `DIR/summary.json`.
pub fn summary(dir: &Path) -> Result<serde_json::Value> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::new(format!("cannot read the run's summary: {e}"))
            .file(&path)
            .fix("give the directory that `dfem run --out DIR` wrote, after the run finished")
    })?;
    serde_json::from_str(&text).map_err(|e| damaged(&path, e))
}

/// Read the numeric CSV file `DIR/name` if it exists: its header's column names and its
/// rows, each with at least `min_cols` values (a damaged file is an error).
fn numeric_csv(dir: &Path, name: &str, min_cols: usize) -> Result<Option<History>> {
    let path = dir.join(name);
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).map_err(|e| damaged(&path, e))?;
    let header = text
        .lines()
        .next()
        .unwrap_or("")
        .split(',')
        .map(|c| c.trim().to_string())
        .collect();
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| damaged(&path, format!("line {}: {e}", i + 1)))?;
        if v.len() < min_cols {
            return Err(damaged(
                &path,
                format!("line {} has fewer than {min_cols} columns", i + 1),
            ));
        }
        rows.push(v);
    }
    Ok(Some(History {
        columns: header,
        rows,
        frames: vec![],
    }))
}

/// Read `DIR/curve.csv` (docs/outputs.md, "The capacity curve") if it exists: its
/// columns and rows.
pub fn curve(dir: &Path) -> Result<Option<History>> {
    numeric_csv(dir, "curve.csv", 3)
}

/// Read `DIR/history.csv` (a dynamic run's, docs/outputs.md) if it exists.
pub fn history(dir: &Path) -> Result<Option<History>> {
    numeric_csv(dir, "history.csv", 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_arrays_and_cells() {
        let text = "<Piece><Points>\n<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">0e0 0e0 0e0 1e0 0e0 0e0 0e0 1.5e0 0e0 </DataArray>\n</Points><Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 </DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3 </DataArray>\n</Cells>";
        let p = Path::new("x.vtu");
        let v = Vtu::parse(text, p).unwrap();
        let pts = v.points(p).unwrap();
        assert_eq!(pts, vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.5]]);
        assert_eq!(v.cells(3, p).unwrap(), vec![vec![0, 1, 2]]);
        // a cell that points past the points is an error, not a panic
        assert!(v.cells(2, p).is_err());
        assert!(v.array("displacement_m", p).is_err());
    }

    #[test]
    fn damaged_files_are_errors() {
        let p = Path::new("x.vtu");
        assert!(Vtu::parse("<DataArray Name=\"a\">1 2 x</DataArray>", p).is_err());
        assert!(Vtu::parse("<DataArray Name=\"a\">1 2", p).is_err());
        assert!(Vtu::parse("<DataArray type=\"x\">1</DataArray>", p).is_err());
    }
}
