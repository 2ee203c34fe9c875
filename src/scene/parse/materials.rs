//! `[[material]]`: the elastic (Kelvin–Voigt) materials of the blocks.

use super::{check_value, err_at, index_of, required, Named, RawMaterial, Src};
use crate::error::Result;
use crate::scene::Material;
use toml::Spanned;

/// The `[[material]]` tables, checked: named, unique, moduli and unit weight given.
pub(super) fn parse_materials(src: &Src, raw: &[Spanned<RawMaterial>]) -> Result<Vec<Material>> {
    let mut named = Named::new("material");
    let mut materials: Vec<Material> = Vec::new();
    for (i, m) in raw.iter().enumerate() {
        let at = m.span().start;
        let m = m.get_ref();
        let name = named
            .unique_name(src, at, i, m.name.as_deref())?
            .to_string();
        let place = format!("material '{name}'");
        let need = |key: &str, v: Option<f64>, positive: bool, unit: &str| {
            required(src, at, &place, key, v, positive, unit)
        };
        let lame_lambda = need("lame_lambda", m.lame_lambda, false, "Pa")?;
        let lame_mu = need("lame_mu", m.lame_mu, true, "Pa")?;
        let unit_weight = need("unit_weight", m.unit_weight, false, "N/m³")?;
        let opt = |key: &str, v: Option<f64>| -> Result<f64> {
            v.map_or(Ok(0.0), |v| {
                check_value(src, at, &place, key, v, false, "Pa·s")
            })
        };
        let viscous_lambda = opt("viscous_lambda", m.viscous_lambda)?;
        let viscous_mu = opt("viscous_mu", m.viscous_mu)?;
        materials.push(Material {
            name,
            lame_lambda,
            lame_mu,
            unit_weight,
            viscous_lambda,
            viscous_mu,
        });
    }
    Ok(materials)
}

/// The index of material `name`, written at `line` in `place`; the error lists the
/// materials defined.
pub(super) fn material_index(
    materials: &[Material],
    name: &str,
    line: usize,
    place: &str,
) -> Result<usize> {
    index_of(
        "material",
        materials.iter().map(|m| m.name.as_str()),
        name,
        line,
        place,
    )
}

/// The index of the material that key `material` of the table at `at` (`place` in
/// errors) names: `name`, which the table must give.
pub(super) fn material_key(
    src: &Src,
    at: usize,
    place: &str,
    materials: &[Material],
    name: Option<&str>,
) -> Result<usize> {
    let name = name.ok_or_else(|| {
        err_at(
            src.line(at),
            place,
            "key 'material' is missing",
            "add material = \"<name of a [[material]]>\"",
        )
    })?;
    material_index(materials, name, src.key_line(at, "material"), place)
}
