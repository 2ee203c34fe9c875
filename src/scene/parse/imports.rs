//! `[[import]]`: blocks read from Gmsh and DXF files by [`crate::scene::import`].

use super::blocks::{parse_kind, room_for};
use super::materials::material_index;
use super::{check_value, err_at, RawImport, Src};
use crate::error::Result;
use crate::scene::import;
use crate::scene::{Block, Material, Support};
use std::path::Path;
use toml::Spanned;

/// The blocks of the `[[import]]` entries, appended to `blocks`; `file` is the scene's,
/// the directory of relative names.
pub(super) fn parse_imports(
    src: &Src,
    raw: &[Spanned<RawImport>],
    file: Option<&Path>,
    materials: &[Material],
    blocks: &mut Vec<Block>,
) -> Result<()> {
    for (i, im) in raw.iter().enumerate() {
        let at = im.span().start;
        let made = import_blocks(src, at, i, im.get_ref(), file, materials)?;
        room_for(
            blocks.len(),
            made.len(),
            src.line(at),
            &format!("[[import]] #{}", i + 1),
            "split the model",
        )?;
        blocks.extend(made);
    }
    Ok(())
}

/// The blocks of one `[[import]]` entry: read the file, give each block the material and
/// support of its group (`materials`, `fixed`), its kind and mesh size.
fn import_blocks(
    src: &Src,
    at: usize,
    i: usize,
    im: &RawImport,
    scene_file: Option<&Path>,
    materials: &[Material],
) -> Result<Vec<Block>> {
    let line = src.line(at);
    let entry = format!("[[import]] #{}", i + 1);
    let fline = src.key_line(at, "file");
    let name = im.file.as_deref().ok_or_else(|| {
        err_at(
            line,
            entry.clone(),
            "key 'file' is missing",
            "add file = \"blocks.msh\" (a Gmsh mesh) or \"blocks.dxf\" (a DXF drawing)",
        )
    })?;
    // relative names are taken from the scene's directory (as ground-motion records)
    let path = match scene_file.filter(|f| f.exists()).and_then(|f| f.parent()) {
        Some(dir) if Path::new(name).is_relative() => dir.join(name),
        _ => Path::new(name).to_path_buf(),
    };
    let format =
        import::format_of(&path, im.format.as_deref()).ok_or_else(|| match &im.format {
            Some(f) => err_at(
                src.key_line(at, "format"),
                format!("{entry} key 'format'"),
                format!("unknown format '{f}'"),
                format!("use one of: {}", import::FORMATS.join(", ")),
            ),
            None => err_at(
                fline,
                format!("{entry} key 'file'"),
                format!("cannot tell the format of '{name}' from its extension"),
                "name a .msh or .dxf file, or add format = \"gmsh\" or \"dxf\"",
            ),
        })?;
    let read = import::read(&path, format).map_err(|e| {
        let place = match e.line {
            Some(l) => format!("{entry}: {}:{l}", path.display()),
            None => format!("{entry}: {}", path.display()),
        };
        err_at(fline, place, e.what, e.fix)
    })?;
    let groups: Vec<&str> = {
        let mut g: Vec<&str> = read.iter().map(|b| b.group.as_str()).collect();
        g.sort_unstable();
        g.dedup();
        g
    };
    let unknown_group = |key: &str, g: &str| {
        err_at(
            src.key_line(at, key),
            format!("{entry} key '{key}'"),
            format!("'{}' has no group '{g}'", path.display()),
            format!("use the groups of the file: {}", groups.join(", ")),
        )
    };
    let default = match &im.material {
        Some(m) => Some(material_index(
            materials,
            m,
            src.key_line(at, "material"),
            &entry,
        )?),
        None => None,
    };
    let mut by_group = std::collections::HashMap::new();
    for (g, m) in im.materials.iter().flatten() {
        if !groups.contains(&g.as_str()) {
            return Err(unknown_group("materials", g));
        }
        by_group.insert(
            g.as_str(),
            material_index(materials, m, src.key_line(at, "materials"), &entry)?,
        );
    }
    let fixed = im.fixed.clone().unwrap_or_default();
    if let Some(g) = fixed.iter().find(|g| !groups.contains(&g.as_str())) {
        return Err(unknown_group("fixed", g));
    }
    let kind = parse_kind(im.kind.as_deref())
        .map_err(|e| err_at(src.key_line(at, "kind"), entry.clone(), e.0, e.1))?;
    let mesh_size = match im.mesh_size {
        None => None,
        Some(h) => Some(check_value(src, at, &entry, "mesh_size", h, true, "m")?),
    };
    read.into_iter()
        .map(|b| {
            let material = match by_group.get(b.group.as_str()).copied().or(default) {
                Some(m) => m,
                None => {
                    return Err(err_at(
                        line,
                        entry.clone(),
                        format!("the blocks of group '{}' have no material", b.group),
                        format!(
                            "add material = \"<name>\" (every group) or materials = {{ {} = \"<name>\" }}",
                            b.group
                        ),
                    ))
                }
            };
            Ok(Block {
                name: match &im.name {
                    Some(p) => format!("{p}_{}", b.name),
                    None => b.name,
                },
                material,
                support: if fixed.contains(&b.group) {
                    Support::Fixed
                } else {
                    Support::Free
                },
                vertices: b.vertices,
                kind,
                mesh_size,
                prescribed: None,
                line: Some(line),
                unit: None,
            })
        })
        .collect()
}
