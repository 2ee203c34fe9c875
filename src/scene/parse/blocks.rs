//! `[[block]]`: blocks given by their polygons; and the checks of all the blocks of the
//! scene, given, generated and imported.

use super::materials::material_key;
use super::{check_value, err_at, warning, Named, RawBlock, Src, MAX_BLOCKS};
use crate::error::{Error, Result};
use crate::geometry::overlapping_pairs;
use crate::geometry::polygon::{self, PolygonDefect};
use crate::scene::{Block, BlockKind, Material, Support};
use std::path::Path;
use toml::Spanned;

/// The `[[block]]` tables, checked: named, with a defined material, vertices, support,
/// kind, mesh size and prescribed displacement (the polygons are checked by
/// [`check_geometry`], with the tolerance of `[contacts]`).
pub(super) fn parse_blocks(
    src: &Src,
    raw: &[Spanned<RawBlock>],
    materials: &[Material],
) -> Result<Vec<Block>> {
    let named = Named::new("block");
    let mut blocks: Vec<Block> = Vec::new();
    for (i, b) in raw.iter().enumerate() {
        let at = b.span().start;
        let b = b.get_ref();
        let line = src.line(at);
        let name = named.name(src, at, i, b.name.as_deref())?.to_string();
        let place = format!("block '{name}'");
        let material = material_key(src, at, &place, materials, b.material.as_deref())?;
        let vertices = b.vertices.clone().ok_or_else(|| {
            err_at(
                line,
                place.clone(),
                "key 'vertices' is missing",
                "add vertices = [[x1, y1], [x2, y2], [x3, y3], ...] in m, counter-clockwise",
            )
        })?;
        let support = match b.support.as_deref() {
            None | Some("free") => Support::Free,
            Some("fixed") => Support::Fixed,
            Some(s) => {
                return Err(err_at(
                    src.key_line(at, "support"),
                    place,
                    format!("unknown support '{s}'"),
                    "use \"free\" or \"fixed\"",
                ))
            }
        };
        let kind = parse_kind(b.kind.as_deref())
            .map_err(|e| err_at(src.key_line(at, "kind"), place.clone(), e.0, e.1))?;
        let mesh_size = match b.mesh_size {
            None => None,
            Some(h) => Some(check_value(src, at, &place, "mesh_size", h, true, "m")?),
        };
        if let Some(p) = b.prescribed {
            if support != Support::Fixed {
                return Err(err_at(
                    src.key_line(at, "prescribed"),
                    place,
                    "only a fixed block can have a prescribed displacement",
                    "add support = \"fixed\" or remove 'prescribed'",
                ));
            }
            if !p.iter().all(|x| x.is_finite()) {
                return Err(err_at(
                    src.key_line(at, "prescribed"),
                    place,
                    "the prescribed displacement must be finite",
                    "give prescribed = [dx, dy] in m",
                ));
            }
        }
        blocks.push(Block {
            name,
            material,
            vertices,
            support,
            kind,
            mesh_size,
            prescribed: b.prescribed,
            line: Some(src.key_line(at, "vertices")),
            unit: None,
        });
    }
    Ok(blocks)
}

/// The error when `made` more blocks after `blocks` would pass [`MAX_BLOCKS`]; `line`
/// and `place` are those of the entry that makes them, `fix` says how to make fewer.
pub(super) fn room_for(
    blocks: usize,
    made: usize,
    line: usize,
    place: &str,
    fix: &str,
) -> Result<()> {
    if blocks + made > MAX_BLOCKS {
        return Err(err_at(
            line,
            place,
            format!(
                "the scene would have {} blocks, more than the limit of {MAX_BLOCKS}",
                blocks + made
            ),
            fix,
        ));
    }
    Ok(())
}

/// All the blocks of the scene, given, generated and imported: some, not too many, and
/// no two of the same name.
pub(super) fn check_count_and_names(blocks: &[Block]) -> Result<()> {
    if blocks.is_empty() {
        return Err(Error::new("the scene has no blocks")
            .line(Some(1))
            .fix("add [[block]] tables or a [[generate]] entry (see `dfem example --list`)"));
    }
    if blocks.len() > MAX_BLOCKS {
        return Err(Error::new(format!(
            "the scene has {} blocks, more than the limit of {MAX_BLOCKS}",
            blocks.len()
        ))
        .fix("split the model"));
    }
    let mut named = Named::new("block");
    for (i, b) in blocks.iter().enumerate() {
        if let Some(j) = named.earlier(&b.name, i) {
            return Err(err_at(
                b.line.unwrap_or(1),
                format!("block '{}'", b.name),
                format!(
                    "the name is already used by the block at line {}",
                    blocks[j].line.unwrap_or(1)
                ),
                "give every block a different name (set `name` on [[generate]] entries to prefix them)",
            ));
        }
    }
    Ok(())
}

/// The blocks' polygons against the contact tolerance `tolerance` (m): no defects, no
/// overlaps, not every block fixed. Clockwise polygons are reversed, with a warning in
/// `warnings` (`file` names the scene in it).
pub(super) fn check_geometry(
    blocks: &mut [Block],
    tolerance: f64,
    file: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<()> {
    // polygons: defects, orientation
    for b in blocks.iter_mut() {
        let line = b.line.unwrap_or(1);
        let place = format!("block '{}'", b.name);
        if let Err(d) = polygon::check(&b.vertices, tolerance) {
            let (what, fix) = match d {
                PolygonDefect::TooFewVertices(n) => (
                    format!("the polygon has {n} vertices"),
                    "give at least three vertices".to_string(),
                ),
                PolygonDefect::NotFinite(k) => (
                    format!("vertex {} is not a finite number", k + 1),
                    "give finite coordinates in m".to_string(),
                ),
                PolygonDefect::RepeatedVertex(a, c) => (
                    format!("vertices {} and {} coincide", a + 1, c + 1),
                    "remove the repeated vertex".to_string(),
                ),
                PolygonDefect::ZeroArea(a) => (
                    format!("the polygon is degenerate (area {a:.3e} m²)"),
                    "give a polygon with a non-zero area".to_string(),
                ),
                PolygonDefect::SelfIntersecting(a, c) => (
                    format!(
                        "the polygon intersects itself (edges {} and {} cross)",
                        a + 1,
                        c + 1
                    ),
                    "list the vertices in order around the block, without crossing".to_string(),
                ),
            };
            return Err(err_at(line, place, what, fix));
        }
        if polygon::signed_area(&b.vertices) < 0.0 {
            b.vertices.reverse();
            warnings.push(warning(
                file,
                line,
                format_args!(
                    "block '{}': vertices were clockwise; reversed to counter-clockwise",
                    b.name
                ),
            ));
        }
    }
    // overlaps
    let polys: Vec<Vec<[f64; 2]>> = blocks.iter().map(|b| b.vertices.clone()).collect();
    if let Some(&(i, j, area)) = overlapping_pairs(&polys, tolerance).first() {
        return Err(err_at(
            blocks[j].line.unwrap_or(1),
            format!("block '{}'", blocks[j].name),
            format!(
                "overlaps block '{}' (line {}) over {area:.3e} m²",
                blocks[i].name,
                blocks[i].line.unwrap_or(1)
            ),
            "move the blocks so that they touch along edges without overlapping",
        ));
    }
    if !blocks.iter().any(|b| b.support == Support::Free) {
        return Err(
            Error::new("every block is fixed: there is nothing to analyse")
                .line(blocks[0].line)
                .fix("make at least one block free (support = \"free\" is the default)"),
        );
    }
    Ok(())
}

/// A block's `kind`: deformable (the default) or rigid; the error as (what, fix).
pub(super) fn parse_kind(k: Option<&str>) -> std::result::Result<BlockKind, (String, String)> {
    match k {
        None | Some("deformable") => Ok(BlockKind::Deformable),
        Some("rigid") => Ok(BlockKind::Rigid),
        Some(s) => Err((
            format!("unknown kind '{s}'"),
            "use \"deformable\" or \"rigid\"".into(),
        )),
    }
}
