//! `[[generate]]`: blocks made by the generators of [`crate::scene::generate`].

use super::blocks::{parse_kind, room_for};
use super::materials::{material_index, material_key};
use super::{check_value, err_at, Src};
use crate::error::Result;
use crate::scene::generate::{self, GenError};
use crate::scene::{Block, Material, Support};
use toml::Spanned;

/// The blocks of the `[[generate]]` entries, appended to `blocks` (the masonry units
/// numbered on from entry to entry).
pub(super) fn parse_generate(
    src: &Src,
    raw: &[Spanned<toml::Table>],
    materials: &[Material],
    blocks: &mut Vec<Block>,
) -> Result<()> {
    let mut next_unit = 0;
    for (i, g) in raw.iter().enumerate() {
        let at = g.span().start;
        let line = src.line(at);
        let mut params = g.get_ref().clone();
        let kind = match params.remove("type") {
            Some(toml::Value::String(s)) => s,
            Some(_) => {
                return Err(err_at(
                    src.key_line(at, "type"),
                    format!("[[generate]] #{}", i + 1),
                    "key 'type' must be a string",
                    format!("use one of {}", generate::TYPES.join(", ")),
                ))
            }
            None => {
                return Err(err_at(
                    line,
                    format!("[[generate]] #{}", i + 1),
                    "key 'type' is missing",
                    format!("add type = \"...\", one of {}", generate::TYPES.join(", ")),
                ))
            }
        };
        let place = format!("[[generate]] #{} ({kind})", i + 1);
        let take_str = |params: &mut toml::Table, key: &str| -> Result<Option<String>> {
            match params.remove(key) {
                None => Ok(None),
                Some(toml::Value::String(s)) => Ok(Some(s)),
                Some(_) => Err(err_at(
                    src.key_line(at, key),
                    place.clone(),
                    format!("key '{key}' must be a string"),
                    "put the value in quotes",
                )),
            }
        };
        let prefix = take_str(&mut params, "name")?;
        let mat = take_str(&mut params, "material")?;
        let material = material_key(src, at, &place, materials, mat.as_deref())?;
        let base_material = match take_str(&mut params, "base_material")? {
            None => material,
            Some(m) => material_index(materials, &m, src.key_line(at, "base_material"), &place)?,
        };
        let kind_s = take_str(&mut params, "kind")?;
        let bkind = parse_kind(kind_s.as_deref())
            .map_err(|e| err_at(src.key_line(at, "kind"), place.clone(), e.0, e.1))?;
        let mesh_size = match params.remove("mesh_size") {
            None => None,
            Some(v) => {
                let h = v
                    .as_float()
                    .or_else(|| v.as_integer().map(|x| x as f64))
                    .unwrap_or(f64::NAN);
                Some(check_value(src, at, &place, "mesh_size", h, true, "m")?)
            }
        };
        let made = generate::generate(&kind, &params).map_err(|e: GenError| {
            let l = e.key.as_deref().map_or(line, |k| src.key_line(at, k));
            let p = match &e.key {
                Some(k) => format!("{place} key '{k}'"),
                None => place.clone(),
            };
            err_at(l, p, e.what, e.fix)
        })?;
        room_for(
            blocks.len(),
            made.len(),
            line,
            &place,
            "reduce the counts of the generator",
        )?;
        // the generator's masonry units, numbered after those of earlier entries
        let units = next_unit;
        next_unit += made
            .iter()
            .filter_map(|b| b.unit)
            .max()
            .map_or(0, |u| u + 1);
        for gb in made {
            blocks.push(Block {
                name: match &prefix {
                    Some(p) => format!("{p}_{}", gb.name),
                    None => gb.name,
                },
                material: if gb.fixed { base_material } else { material },
                vertices: gb.vertices,
                support: if gb.fixed {
                    Support::Fixed
                } else {
                    Support::Free
                },
                kind: bkind,
                mesh_size,
                prescribed: None,
                line: Some(line),
                unit: gb.unit.map(|u| units + u),
            });
        }
    }
    Ok(())
}
