//! Solid blocks from the plane generators (docs/theory.md §7): the blocks of a
//! two-dimensional generator (its (x, y) as (x, z), y up becoming z up) made prisms
//! through a depth, in rings, so that a one-leaf wall is the `wall` generator's bricks
//! through the wall's thickness and a barrel vault the `arch` generator's voussoirs in
//! rings along its axis.

use super::GeneratedBlock;
use crate::geometry::Polyhedron;

/// A solid block: its name (the plane block's, with its ring after a `/` when there are
/// several), its geometry, and whether it is fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct SolidBlock {
    pub name: String,
    pub block: Polyhedron,
    pub fixed: bool,
}

/// The plane `blocks` made prisms through `rings` equal rings between the depths y = 0 and
/// y = `depth` (m); a fixed block (a foundation) is one prism through the whole depth.
pub fn extrude(blocks: &[GeneratedBlock], depth: f64, rings: usize) -> Vec<SolidBlock> {
    let rings = rings.max(1);
    let ring = depth / rings as f64;
    let mut out = Vec::new();
    for b in blocks {
        if b.fixed || rings == 1 {
            out.push(SolidBlock {
                name: b.name.clone(),
                block: Polyhedron::prism(&b.vertices, 0.0, depth),
                fixed: b.fixed,
            });
            continue;
        }
        for r in 0..rings {
            let (y0, y1) = (
                r as f64 * ring,
                if r + 1 == rings {
                    depth
                } else {
                    (r + 1) as f64 * ring
                },
            );
            out.push(SolidBlock {
                name: format!("{}/{}", b.name, r + 1),
                block: Polyhedron::prism(&b.vertices, y0, y1),
                fixed: false,
            });
        }
    }
    out
}

#[cfg(test)]
#[path = "solid_tests.rs"]
mod tests;
