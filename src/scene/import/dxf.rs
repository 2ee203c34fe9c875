//! DXF drawings: every closed `LWPOLYLINE` or `POLYLINE` becomes one block; its group is
//! its layer. The file (ASCII or binary DXF) is read with the `dxf` crate
//! (ixmilia/dxf-rs, MIT); this module only picks the polylines.
//!
//! A polyline is closed when its closed flag (group code 70, bit 1) is set or when its last
//! vertex lies on its first (within `CLOSE` of its size; the repeated vertex is dropped).
//! Arc segments (a non-zero bulge, group code 42) are refused: a block's edges are
//! straight. Polygon meshes and polyface meshes (POLYLINE flags 16 and 64) are skipped,
//! as are open polylines and every other entity.

use super::{name_blocks, tidy, ImportError, ImportedBlock};
use dxf::entities::EntityType;

/// Relative tolerance (of a polyline's size) under which its last vertex closes it on the
/// first, and under which vertices are merged or dropped as collinear: DXF writers print
/// coordinates to 15–16 digits, so 1e-9 is far above their rounding and far below any
/// drawn feature.
const CLOSE: f64 = 1e-9;

/// Read the blocks of a DXF drawing (the file's bytes).
pub fn read(bytes: &[u8]) -> Result<Vec<ImportedBlock>, ImportError> {
    let mut cursor = std::io::Cursor::new(bytes);
    let drawing = dxf::Drawing::load(&mut cursor).map_err(explain)?;
    let mut out = Vec::new();
    for e in drawing.entities() {
        let (pts, closed): (Vec<([f64; 2], f64)>, bool) = match &e.specific {
            EntityType::LwPolyline(p) => (
                p.vertices.iter().map(|v| ([v.x, v.y], v.bulge)).collect(),
                p.is_closed(),
            ),
            EntityType::Polyline(p) if !p.is_3d_polygon_mesh() && !p.is_polyface_mesh() => (
                p.vertices()
                    .map(|v| ([v.location.x, v.location.y], v.bulge))
                    .collect(),
                p.is_closed(),
            ),
            _ => continue,
        };
        let at = || {
            format!(
                "the polyline with handle {:X} on layer '{}'",
                e.common.handle.0, e.common.layer
            )
        };
        let xy: Vec<[f64; 2]> = pts.iter().map(|p| p.0).collect();
        if xy.len() < 3 {
            continue;
        }
        if !xy.iter().flatten().all(|c| c.is_finite()) {
            return Err(ImportError::new(
                None,
                format!("{} has a coordinate that is not finite", at()),
                "give finite coordinates",
            ));
        }
        let size = crate::geometry::polygon::size(&xy);
        let (first, last) = (xy[0], xy[xy.len() - 1]);
        let ends_meet = (first[0] - last[0]).hypot(first[1] - last[1]) <= CLOSE * size;
        if !closed && !ends_meet {
            continue;
        }
        // the segments: from each vertex to the next, and the closing one unless the
        // last vertex repeats the first
        let n = if ends_meet { xy.len() - 1 } else { xy.len() };
        if pts[..n].iter().any(|p| p.1 != 0.0) {
            return Err(ImportError::new(
                None,
                format!("{} has arc segments (bulge)", at()),
                "explode or flatten the arcs into straight segments (a block's edges are straight)",
            ));
        }
        let ring = tidy(xy[..n].to_vec(), CLOSE).ok_or_else(|| {
            ImportError::new(
                None,
                format!("{} encloses no area", at()),
                "delete it or draw the block's outline",
            )
        })?;
        out.push((e.common.layer.clone(), ring));
    }
    if out.is_empty() {
        return Err(ImportError::new(
            None,
            "the drawing has no closed LWPOLYLINE or POLYLINE",
            "draw each block as a closed polyline (AutoCAD: PLINE, then C to close; or PEDIT > Close)",
        ));
    }
    Ok(name_blocks(out))
}

/// The `dxf` crate's error as an [`ImportError`], with its line when it gives one.
fn explain(e: dxf::DxfError) -> ImportError {
    use dxf::DxfError as D;
    let line = match &e {
        D::ParseFloatError(_, o)
        | D::ParseIntError(_, o)
        | D::ParseError(o)
        | D::UnexpectedCode(_, o)
        | D::UnexpectedByte(_, o)
        | D::UnexpectedEnumValue(o)
        | D::ExpectedTableType(o)
        | D::WrongValueType(o) => Some(*o),
        D::UnexpectedCodePair(p, _) => Some(p.offset),
        _ => None,
    };
    let what = match &e {
        D::ParseFloatError(..) => "a number cannot be read".to_string(),
        D::ParseIntError(..) => "a group code or integer cannot be read".to_string(),
        D::UnexpectedEndOfInput => "the file ends before the drawing does".to_string(),
        D::IoError(io) => format!("cannot read the drawing: {io}"),
        D::UnexpectedCodePair(p, expected) => format!(
            "group code {} is not expected here ({})",
            p.code,
            expected.trim()
        ),
        other => {
            // the crate's message ends with "at line/offset N": the line is given apart
            let m = other.to_string();
            m.split(" at line/offset").next().unwrap_or(&m).to_string()
        }
    };
    ImportError::new(
        line,
        format!("not a valid DXF drawing: {what}"),
        "save the drawing again as DXF (ASCII) from the CAD program",
    )
}
