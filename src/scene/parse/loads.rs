//! `[[load]]`: forces on blocks.

use super::{err_at, RawLoad, Src};
use crate::error::Result;
use crate::geometry::polygon;
use crate::scene::{Block, Load};
use toml::Spanned;

/// The `[[load]]` tables, checked: on a block of the scene, a finite force, `along` two
/// points farther apart than the contact tolerance `tolerance` (m).
pub(super) fn parse_loads(
    src: &Src,
    raw: &[Spanned<RawLoad>],
    blocks: &[Block],
    tolerance: f64,
) -> Result<Vec<Load>> {
    let mut loads = Vec::new();
    for (i, l) in raw.iter().enumerate() {
        let at = l.span().start;
        let line = src.line(at);
        let l = l.get_ref();
        let place = format!("[[load]] #{}", i + 1);
        let bname = l.block.as_deref().ok_or_else(|| {
            err_at(
                line,
                place.clone(),
                "key 'block' is missing",
                "add block = \"<block name>\"",
            )
        })?;
        let block = blocks.iter().position(|b| b.name == bname).ok_or_else(|| {
            err_at(
                src.key_line(at, "block"),
                place.clone(),
                format!("block '{bname}' does not exist"),
                "name a block of the scene (`dfem check` lists the generated names)",
            )
        })?;
        let force = l.force.ok_or_else(|| {
            err_at(
                line,
                place.clone(),
                "key 'force' is missing",
                "add force = [Fx, Fy] in N",
            )
        })?;
        if !force.iter().all(|f| f.is_finite()) {
            return Err(err_at(
                src.key_line(at, "force"),
                place,
                "the force must be finite",
                "give force = [Fx, Fy] in N",
            ));
        }
        if let Some(s) = l.along {
            if !s.iter().flatten().all(|x| x.is_finite())
                || polygon::norm(polygon::sub(s[1], s[0])) <= tolerance
            {
                return Err(err_at(
                    src.key_line(at, "along"),
                    place,
                    "'along' must be two distinct finite points",
                    "give along = [[x1, y1], [x2, y2]] on the block's boundary",
                ));
            }
        }
        loads.push(Load {
            block,
            force,
            along: l.along,
            line: Some(line),
        });
    }
    Ok(loads)
}
