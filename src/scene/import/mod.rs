//! `[[import]]`: block geometry read from the files engineers already draw in.
//!
//! [`gmsh`] reads a Gmsh mesh (`.msh`, ASCII format 4.1 or 2.2): every surface entity
//! becomes one block, its outline the boundary of its triangles and quadrangles
//! ([`outline`]); [`dxf`] reads a DXF drawing: every closed `LWPOLYLINE` or `POLYLINE`
//! becomes one block. Each block carries its group (the Gmsh physical group's name, or the
//! DXF layer), which the scene maps to a material and a support (`parse.rs`).
//!
//! Readers return an [`ImportError`] naming the line of the file (when there is one),
//! what is wrong and how to fix it; the scene parser adds the scene file and the
//! `[[import]]` entry.

pub mod dxf;
pub mod gmsh;
pub mod outline;

use std::path::Path;

/// A block read from a file: its group (physical group name or layer), a name unique
/// within the file, and its counter-clockwise outline (m).
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedBlock {
    /// `{group}_{n}`, n = 1, 2, ... in the order of the file within the group.
    pub name: String,
    /// The Gmsh physical group's name (`physical_TAG` when it has none, `surface` when the
    /// surface is in no physical group) or the DXF layer.
    pub group: String,
    /// Counter-clockwise vertices, m, without repeated or collinear vertices.
    pub vertices: Vec<[f64; 2]>,
}

/// An error in an imported file: the 1-based line (when known), what is wrong, the fix.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportError {
    pub line: Option<usize>,
    pub what: String,
    pub fix: String,
}

impl ImportError {
    pub fn new(line: Option<usize>, what: impl Into<String>, fix: impl Into<String>) -> Self {
        ImportError {
            line,
            what: what.into(),
            fix: fix.into(),
        }
    }
}

/// The formats `[[import]] format` accepts.
pub const FORMATS: &[&str] = &["gmsh", "dxf"];

/// The format named by `format`, or else by the file's extension (`.msh`, `.dxf`).
pub fn format_of(path: &Path, format: Option<&str>) -> Option<&'static str> {
    match format {
        Some(f) => FORMATS.iter().copied().find(|x| *x == f),
        None => match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("msh") => Some("gmsh"),
            Some("dxf") => Some("dxf"),
            _ => None,
        },
    }
}

/// Read the blocks of `path` in `format` (one of [`FORMATS`]).
pub fn read(path: &Path, format: &str) -> Result<Vec<ImportedBlock>, ImportError> {
    let bytes = std::fs::read(path).map_err(|e| {
        ImportError::new(
            None,
            format!("cannot read the file: {e}"),
            "check the path (relative paths are taken from the scene's directory)",
        )
    })?;
    match format {
        "gmsh" => {
            let text = String::from_utf8(bytes).map_err(|e| {
                let at = e.utf8_error().valid_up_to();
                let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
                ImportError::new(
                    Some(line),
                    "the file is not ASCII text (a binary .msh?)",
                    "save the mesh as ASCII: in Gmsh, File > Export with format 'Gmsh MSH' and 'Save all' off, Binary unchecked (or Mesh.Binary = 0)",
                )
            })?;
            gmsh::read(&text)
        }
        _ => dxf::read(&bytes),
    }
}

/// Name the blocks `{group}_{n}` (n from 1 within each group, in input order).
fn name_blocks(groups_and_outlines: Vec<(String, Vec<[f64; 2]>)>) -> Vec<ImportedBlock> {
    let mut count: std::collections::HashMap<String, usize> = Default::default();
    groups_and_outlines
        .into_iter()
        .map(|(group, vertices)| {
            let n = count.entry(group.clone()).or_insert(0);
            *n += 1;
            ImportedBlock {
                name: format!("{group}_{n}"),
                group,
                vertices,
            }
        })
        .collect()
}

/// Remove repeated and collinear vertices (within `rel_tol` of the outline's size) and
/// orient counter-clockwise; `None` when fewer than three vertices remain.
fn tidy(vertices: Vec<[f64; 2]>, rel_tol: f64) -> Option<Vec<[f64; 2]>> {
    let size = crate::geometry::polygon::size(&vertices);
    super::generate::common::clean(vertices, rel_tol * size)
}
