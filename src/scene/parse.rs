//! TOML text → validated [`Scene`]. Everything is checked before any work: syntax, types,
//! unknown keys, moduli, names, polygons, overlaps. Every error names the file, the line,
//! the block or key, and the fix (docs/outputs.md, "Command line and exit status").

use super::generate::{self, GenError};
use super::import;
use super::*;
use crate::error::{Error, Result};
use crate::geometry::overlapping_pairs;
use crate::geometry::polygon::{self, PolygonDefect};
use serde::Deserialize;
use std::path::Path;
use toml::Spanned;

mod analysis_settings;
use analysis_settings::AnalysisTable;

/// More blocks than this are refused before any work (a typo in a generator, usually).
pub const MAX_BLOCKS: usize = 2_000_000;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    title: Option<String>,
    model: Option<Spanned<RawModel>>,
    #[serde(default)]
    material: Vec<Spanned<RawMaterial>>,
    #[serde(default)]
    joint: Vec<Spanned<RawJoint>>,
    #[serde(default)]
    block: Vec<Spanned<RawBlock>>,
    #[serde(default)]
    generate: Vec<Spanned<toml::Table>>,
    #[serde(default)]
    import: Vec<Spanned<RawImport>>,
    contacts: Option<Spanned<RawContacts>>,
    #[serde(default)]
    load: Vec<Spanned<RawLoad>>,
    analysis: Option<Spanned<toml::Table>>,
    output: Option<Spanned<RawOutput>>,
    in_situ: Option<Spanned<RawInSitu>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInSitu {
    stress: Option<[f64; 3]>,
    gradient: Option<[f64; 3]>,
    datum: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    plane: Option<String>,
    thickness: Option<f64>,
    gravity: Option<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: Option<String>,
    lame_lambda: Option<f64>,
    lame_mu: Option<f64>,
    unit_weight: Option<f64>,
    viscous_lambda: Option<f64>,
    viscous_mu: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: Option<String>,
    normal_modulus: Option<f64>,
    shear_modulus: Option<f64>,
    normal_viscosity: Option<f64>,
    shear_viscosity: Option<f64>,
    band: Option<f64>,
    friction_angle: Option<f64>,
    cohesion: Option<f64>,
    tensile_strength: Option<f64>,
    softening: Option<String>,
    fracture_energy_i: Option<f64>,
    fracture_energy_ii: Option<f64>,
    compressive_strength: Option<f64>,
    cap_shear_factor: Option<f64>,
    compressive_fracture_energy: Option<f64>,
    cap_peak_displacement: Option<f64>,
    dilatancy_angle: Option<f64>,
    dilatancy_stress: Option<f64>,
    within: Option<String>,
    blocks: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBlock {
    name: Option<String>,
    material: Option<String>,
    vertices: Option<Vec<[f64; 2]>>,
    support: Option<String>,
    kind: Option<String>,
    mesh_size: Option<f64>,
    prescribed: Option<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawImport {
    file: Option<String>,
    format: Option<String>,
    name: Option<String>,
    material: Option<String>,
    materials: Option<std::collections::BTreeMap<String, String>>,
    fixed: Option<Vec<String>>,
    kind: Option<String>,
    mesh_size: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContacts {
    joint: Option<String>,
    tolerance: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    block: Option<String>,
    force: Option<[f64; 2]>,
    along: Option<[[f64; 2]; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    track: Option<Vec<String>>,
    vtk: Option<bool>,
    every: Option<i64>,
    checkpoint_every: Option<i64>,
}

/// Keys of `[analysis]`: those of every analysis type (a key that the scene's type does
/// not read is accepted and has no effect, docs/scene-reference.md "[analysis]").
pub const ANALYSIS_KEYS: &[&str] = &[
    "type",
    "lateral",
    "load_steps",
    "direction",
    "dt",
    "duration",
    "ground_motion",
    "frame",
    "strategy",
    "tolerance",
    "max_iterations",
    "max_cuts",
    "initial_step",
    "bracket",
    "line_search",
    "fallout",
    "reuse_across_increments",
    "push_block",
    "push_displacement",
    "gravity_steps",
    "path",
    "arc_length",
    "accept_residual",
    "integrator",
    "alpha",
    "rho_inf",
    "rayleigh",
    "initial",
    "impact_reset",
    "inertia",
    "adaptive_tolerance",
];

/// Read and validate a scene file.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| {
        Error::new(format!("cannot read the scene: {e}"))
            .file(path)
            .fix("check the path (`dfem example --list` shows built-in scenes)")
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        Error::new(format!(
            "the scene is not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        ))
        .file(path)
        .fix("save the scene as UTF-8 TOML")
    })?;
    parse_str(&text, Some(path))
}

/// Text of the scene, for line look-ups.
struct Src<'a> {
    text: &'a str,
}

impl Src<'_> {
    /// 1-based line of a byte offset.
    fn line(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())]
            .bytes()
            .filter(|&b| b == b'\n')
            .count()
            + 1
    }
    /// Line of `key = ...` inside the table whose header starts at `start` (the header's
    /// line when the key is not written there).
    fn key_line(&self, start: usize, key: &str) -> usize {
        let header = self.line(start);
        for (k, l) in self.text[start.min(self.text.len())..].lines().enumerate() {
            let t = l.trim_start();
            if k > 0 && t.starts_with('[') {
                break;
            }
            if let Some(rest) = t.strip_prefix(key) {
                if rest.trim_start().starts_with('=') {
                    return header + k;
                }
            }
        }
        header
    }
}

fn err_at(
    line: usize,
    place: impl Into<String>,
    what: impl Into<String>,
    fix: impl Into<String>,
) -> Error {
    Error::new(what).line(Some(line)).place(place).fix(fix)
}

/// Parse and validate scene text; `file` names it in errors.
pub fn parse_str(text: &str, file: Option<&Path>) -> Result<Scene> {
    let r = parse_inner(text, file);
    match (r, file) {
        (Err(e), Some(f)) => Err(e.in_file(f)),
        (r, _) => r,
    }
}

fn parse_inner(text: &str, file: Option<&Path>) -> Result<Scene> {
    let src = Src { text };
    let raw: RawScene = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| src.line(s.start));
        let msg = e.message().trim().to_string();
        let fix = if msg.starts_with("unknown field") {
            "remove or correct the key (keys are listed in docs/scene-reference.md)"
        } else if msg.starts_with("invalid type") {
            "give the value the type the key expects (numbers without quotes, names in quotes)"
        } else if msg.contains("duplicate key") {
            "write each key once per table"
        } else {
            "correct the TOML syntax at that line"
        };
        Error::new(msg).line(line).fix(fix)
    })?;
    let mut warnings = Vec::new();

    // [model]
    let model = match &raw.model {
        None => Model {
            plane: Plane::Strain,
            thickness: 1.0,
            gravity: [0.0, -STANDARD_GRAVITY],
        },
        Some(m) => {
            let at = m.span().start;
            let m = m.get_ref();
            let plane = match m.plane.as_deref() {
                None | Some("strain") => Plane::Strain,
                Some("stress") => Plane::Stress,
                Some(p) => {
                    return Err(err_at(
                        src.key_line(at, "plane"),
                        "[model] key 'plane'",
                        format!("unknown plane '{p}'"),
                        "use \"strain\" or \"stress\"",
                    ))
                }
            };
            let thickness = m.thickness.unwrap_or(1.0);
            if !(thickness.is_finite() && thickness > 0.0) {
                return Err(err_at(
                    src.key_line(at, "thickness"),
                    "[model] key 'thickness'",
                    format!("thickness must be a positive number of metres, not {thickness}"),
                    "give the out-of-plane thickness in m, for example thickness = 1.0",
                ));
            }
            let gravity = m.gravity.unwrap_or([0.0, -STANDARD_GRAVITY]);
            if !gravity.iter().all(|g| g.is_finite()) {
                return Err(err_at(
                    src.key_line(at, "gravity"),
                    "[model] key 'gravity'",
                    "gravity must be finite",
                    "give gravity in m/s², for example [0.0, -9.81]",
                ));
            }
            Model {
                plane,
                thickness,
                gravity,
            }
        }
    };

    // [[material]]
    let mut materials: Vec<Material> = Vec::new();
    for (i, m) in raw.material.iter().enumerate() {
        let at = m.span().start;
        let m = m.get_ref();
        let name = m.name.clone().ok_or_else(|| {
            err_at(
                src.line(at),
                format!("[[material]] #{}", i + 1),
                "the material has no name",
                "add name = \"...\" to the table",
            )
        })?;
        let place = format!("material '{name}'");
        if materials.iter().any(|x| x.name == name) {
            return Err(err_at(
                src.key_line(at, "name"),
                place,
                "a material of that name is already defined",
                "give each material a different name",
            ));
        }
        let need = |key: &str, v: Option<f64>, positive: bool, unit: &str| -> Result<f64> {
            let v = v.ok_or_else(|| {
                err_at(
                    src.line(at),
                    place.clone(),
                    format!("key '{key}' is missing"),
                    format!("add {key} = <value in {unit}>"),
                )
            })?;
            check_value(&src, at, &place, key, v, positive, unit)
        };
        let lame_lambda = need("lame_lambda", m.lame_lambda, false, "Pa")?;
        let lame_mu = need("lame_mu", m.lame_mu, true, "Pa")?;
        let unit_weight = need("unit_weight", m.unit_weight, false, "N/m³")?;
        let opt = |key: &str, v: Option<f64>| -> Result<f64> {
            v.map_or(Ok(0.0), |v| {
                check_value(&src, at, &place, key, v, false, "Pa·s")
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

    // [[joint]]
    let mut joints: Vec<Joint> = Vec::new();
    // per joint: where it stands and the names of its `blocks`, resolved after the blocks
    let mut joint_blocks: Vec<(usize, String, Vec<String>)> = Vec::new();
    for (i, j) in raw.joint.iter().enumerate() {
        let at = j.span().start;
        let j = j.get_ref();
        let name = j.name.clone().ok_or_else(|| {
            err_at(
                src.line(at),
                format!("[[joint]] #{}", i + 1),
                "the joint has no name",
                "add name = \"...\" to the table",
            )
        })?;
        let place = format!("joint '{name}'");
        if joints.iter().any(|x| x.name == name) {
            return Err(err_at(
                src.key_line(at, "name"),
                place,
                "a joint of that name is already defined",
                "give each joint a different name",
            ));
        }
        let need = |key: &str, v: Option<f64>, unit: &str| -> Result<f64> {
            let v = v.ok_or_else(|| {
                err_at(
                    src.line(at),
                    place.clone(),
                    format!("key '{key}' is missing"),
                    format!("add {key} = <value in {unit}>"),
                )
            })?;
            check_value(&src, at, &place, key, v, true, unit)
        };
        let normal_modulus = need("normal_modulus", j.normal_modulus, "Pa")?;
        let shear_modulus = need("shear_modulus", j.shear_modulus, "Pa")?;
        let band = need("band", j.band, "m")?;
        let opt = |key: &str, v: Option<f64>, unit: &str| -> Result<f64> {
            v.map_or(Ok(0.0), |v| {
                check_value(&src, at, &place, key, v, false, unit)
            })
        };
        let friction_angle = match j.friction_angle {
            None => {
                return Err(err_at(
                    src.line(at),
                    place,
                    "key 'friction_angle' is missing",
                    "add friction_angle = <degrees, 0 to 89.9>",
                ))
            }
            Some(f) if f.is_finite() && (0.0..90.0).contains(&f) => f,
            Some(f) => {
                return Err(err_at(
                    src.key_line(at, "friction_angle"),
                    format!("{place} key 'friction_angle'"),
                    format!("friction angle {f}° is outside [0°, 90°)"),
                    "give the friction angle in degrees, for example 30",
                ))
            }
        };
        let cohesion = opt("cohesion", j.cohesion, "Pa")?;
        let tensile_strength = opt("tensile_strength", j.tensile_strength, "Pa")?;
        let softening = match j.softening.as_deref() {
            None | Some("none") => JointSoftening::None,
            Some("exponential") => JointSoftening::Exponential,
            Some(other) => {
                return Err(err_at(
                    src.key_line(at, "softening"),
                    format!("{place} key 'softening'"),
                    format!("unknown softening \"{other}\""),
                    "use \"exponential\" (or \"none\", the default)",
                ))
            }
        };
        let (fracture_energy_i, fracture_energy_ii) = if softening == JointSoftening::None {
            if let Some(key) = [
                ("fracture_energy_i", j.fracture_energy_i),
                ("fracture_energy_ii", j.fracture_energy_ii),
            ]
            .iter()
            .find_map(|(k, v)| v.map(|_| *k))
            {
                return Err(err_at(
                    src.key_line(at, key),
                    format!("{place} key '{key}'"),
                    "a fracture energy is given but the joint does not soften",
                    "add softening = \"exponential\" to the joint, or remove the key",
                ));
            }
            (0.0, 0.0)
        } else {
            let gf1 = need("fracture_energy_i", j.fracture_energy_i, "N/m")?;
            let gf2 = need("fracture_energy_ii", j.fracture_energy_ii, "N/m")?;
            let tan_phi = friction_angle.to_radians().tan();
            if tensile_strength * tan_phi > cohesion * (1.0 + 1e-12) {
                return Err(err_at(
                    src.key_line(at, "tensile_strength"),
                    format!("{place} key 'tensile_strength'"),
                    format!(
                        "the tension cut-off fₜ = {tensile_strength} Pa lies beyond the apex of the Coulomb line (c / tan φ = {} Pa)",
                        cohesion / tan_phi
                    ),
                    "a softening joint needs tensile_strength ≤ cohesion / tan(friction_angle): lower the tensile strength or raise the cohesion",
                ));
            }
            (gf1, gf2)
        };
        let cap = joint_cap(&src, at, &place, j, softening)?;
        let (dilatancy_angle, dilatancy_stress) =
            joint_dilatancy(&src, at, &place, j, softening, friction_angle)?;
        let within_unit = match j.within.as_deref() {
            None => false,
            Some("unit") => true,
            Some(other) => {
                return Err(err_at(
                    src.key_line(at, "within"),
                    format!("{place} key 'within'"),
                    format!("unknown value \"{other}\""),
                    "use within = \"unit\" (the joint of the potential cracks inside split bricks), or remove the key",
                ))
            }
        };
        joints.push(Joint {
            name,
            normal_modulus,
            shear_modulus,
            normal_viscosity: opt("normal_viscosity", j.normal_viscosity, "Pa·s")?,
            shear_viscosity: opt("shear_viscosity", j.shear_viscosity, "Pa·s")?,
            band,
            friction_angle,
            cohesion,
            tensile_strength,
            softening,
            fracture_energy_i,
            fracture_energy_ii,
            cap,
            dilatancy_angle,
            dilatancy_stress,
            within_unit,
            blocks: Vec::new(),
        });
        joint_blocks.push((at, place.clone(), j.blocks.clone().unwrap_or_default()));
    }

    let material_index = |name: &str, line: usize, place: &str| -> Result<usize> {
        materials
            .iter()
            .position(|m| m.name == name)
            .ok_or_else(|| {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                err_at(
                    line,
                    place.to_string(),
                    format!("material '{name}' is not defined"),
                    if known.is_empty() {
                        "define it in a [[material]] table".to_string()
                    } else {
                        format!(
                            "define it in a [[material]] table or use one of: {}",
                            known.join(", ")
                        )
                    },
                )
            })
    };

    // [[block]]
    let mut blocks: Vec<Block> = Vec::new();
    for (i, b) in raw.block.iter().enumerate() {
        let at = b.span().start;
        let b = b.get_ref();
        let line = src.line(at);
        let name = b.name.clone().ok_or_else(|| {
            err_at(
                line,
                format!("[[block]] #{}", i + 1),
                "the block has no name",
                "add name = \"...\" to the table",
            )
        })?;
        let place = format!("block '{name}'");
        let mat = b.material.as_deref().ok_or_else(|| {
            err_at(
                line,
                place.clone(),
                "key 'material' is missing",
                "add material = \"<name of a [[material]]>\"",
            )
        })?;
        let material = material_index(mat, src.key_line(at, "material"), &place)?;
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
            Some(h) => Some(check_value(&src, at, &place, "mesh_size", h, true, "m")?),
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

    // [[generate]]
    let mut next_unit = 0;
    for (i, g) in raw.generate.iter().enumerate() {
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
        let mat = take_str(&mut params, "material")?.ok_or_else(|| {
            err_at(
                line,
                place.clone(),
                "key 'material' is missing",
                "add material = \"<name of a [[material]]>\"",
            )
        })?;
        let material = material_index(&mat, src.key_line(at, "material"), &place)?;
        let base_material = match take_str(&mut params, "base_material")? {
            None => material,
            Some(m) => material_index(&m, src.key_line(at, "base_material"), &place)?,
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
                Some(check_value(&src, at, &place, "mesh_size", h, true, "m")?)
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
        if blocks.len() + made.len() > MAX_BLOCKS {
            return Err(err_at(
                line,
                place,
                format!(
                    "the scene would have {} blocks, more than the limit of {MAX_BLOCKS}",
                    blocks.len() + made.len()
                ),
                "reduce the counts of the generator",
            ));
        }
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

    // [[import]]
    for (i, im) in raw.import.iter().enumerate() {
        let at = im.span().start;
        let made = import_blocks(&src, at, i, im.get_ref(), file, &material_index)?;
        if blocks.len() + made.len() > MAX_BLOCKS {
            return Err(err_at(
                src.line(at),
                format!("[[import]] #{}", i + 1),
                format!(
                    "the scene would have {} blocks, more than the limit of {MAX_BLOCKS}",
                    blocks.len() + made.len()
                ),
                "split the model",
            ));
        }
        blocks.extend(made);
    }

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
    // names unique
    {
        let mut seen = std::collections::HashMap::new();
        for (i, b) in blocks.iter().enumerate() {
            if let Some(j) = seen.insert(b.name.as_str(), i) {
                return Err(err_at(b.line.unwrap_or(1), format!("block '{}'", b.name),
                    format!("the name is already used by the block at line {}", blocks[j].line.unwrap_or(1)),
                    "give every block a different name (set `name` on [[generate]] entries to prefix them)"));
            }
        }
    }

    for (j, (at, place, names)) in joint_blocks.iter().enumerate() {
        for name in names {
            let b = blocks.iter().position(|b| &b.name == name).ok_or_else(|| {
                err_at(
                    src.key_line(*at, "blocks"),
                    format!("{place} key 'blocks'"),
                    format!("there is no block '{name}'"),
                    "name blocks of the scene (generated walls call their base \"base\" and their top beam \"top\")",
                )
            })?;
            joints[j].blocks.push(b);
        }
    }

    // [contacts]
    let (joint_name, tol_given, cline) = match &raw.contacts {
        None => (None, None, 1),
        Some(c) => (
            c.get_ref().joint.clone(),
            c.get_ref().tolerance,
            src.line(c.span().start),
        ),
    };
    let scene_size = {
        let all: Vec<[f64; 2]> = blocks
            .iter()
            .flat_map(|b| b.vertices.iter().copied())
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .collect();
        if all.is_empty() {
            1.0
        } else {
            polygon::size(&all)
        }
    };
    let tolerance = match tol_given {
        None => 1e-6 * scene_size.max(1e-3),
        Some(t) if t.is_finite() && t >= 0.0 => t,
        Some(t) => {
            return Err(err_at(
                cline,
                "[contacts] key 'tolerance'",
                format!("tolerance must be a non-negative length, not {t}"),
                "give it in m, for example tolerance = 1e-6",
            ))
        }
    };
    let joint = match joint_name {
        Some(n) => joints.iter().position(|j| j.name == n).ok_or_else(|| {
            let known: Vec<&str> = joints.iter().map(|j| j.name.as_str()).collect();
            err_at(
                cline,
                "[contacts] key 'joint'",
                format!("joint '{n}' is not defined"),
                if known.is_empty() {
                    "define it in a [[joint]] table".to_string()
                } else {
                    format!(
                        "define it in a [[joint]] table or use one of: {}",
                        known.join(", ")
                    )
                },
            )
        })?,
        None if joints.len() == 1 => 0,
        None if joints.is_empty() && blocks.len() > 1 => {
            return Err(Error::new(
                "no [[joint]] is defined, so touching blocks would have no contact properties",
            )
            .line(Some(1))
            .fix("add a [[joint]] table (normal_modulus, shear_modulus, band, friction_angle)"))
        }
        None if joints.is_empty() => usize::MAX,
        None => {
            return Err(err_at(
                cline,
                "[contacts]",
                "several joints are defined and none is chosen",
                "add [contacts] joint = \"<name>\"",
            ))
        }
    };

    // polygons: defects, orientation
    for b in &mut blocks {
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
            warnings.push(format!(
                "{}line {line}: block '{}': vertices were clockwise; reversed to counter-clockwise",
                file.map(|f| format!("{}:", f.display()))
                    .unwrap_or_default(),
                b.name
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

    // [[load]]
    let mut loads = Vec::new();
    for (i, l) in raw.load.iter().enumerate() {
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

    // [analysis]
    let analysis = parse_analysis(&src, raw.analysis.as_ref(), file, &blocks)?;

    // [output]
    let output = match &raw.output {
        None => Output {
            track: vec![],
            vtk: true,
            every: 1,
            checkpoint_every: None,
        },
        Some(o) => {
            let at = o.span().start;
            let o = o.get_ref();
            let track = o.track.clone().unwrap_or_default();
            for t in &track {
                if !blocks.iter().any(|b| &b.name == t) {
                    return Err(err_at(
                        src.key_line(at, "track"),
                        "[output] key 'track'",
                        format!("block '{t}' does not exist"),
                        "name blocks of the scene",
                    ));
                }
            }
            let every = o.every.unwrap_or(1);
            if every < 1 {
                return Err(err_at(
                    src.key_line(at, "every"),
                    "[output] key 'every'",
                    format!("every must be a whole number of steps ≥ 1, not {every}"),
                    "for example every = 10 (a ParaView frame every 10 time steps)",
                ));
            }
            let checkpoint_every = match o.checkpoint_every {
                Some(n) if n < 1 => {
                    return Err(err_at(
                        src.key_line(at, "checkpoint_every"),
                        "[output] key 'checkpoint_every'",
                        format!("checkpoint_every must be a whole number of steps ≥ 1, not {n}"),
                        "for example checkpoint_every = 100 (a checkpoint every 100 time steps), or leave it out for one every 30 s of wall time",
                    ));
                }
                n => n.map(|n| n as usize),
            };
            Output {
                track,
                vtk: o.vtk.unwrap_or(true),
                every: every as usize,
                checkpoint_every,
            }
        }
    };

    // [in_situ]
    let in_situ = match &raw.in_situ {
        None => None,
        Some(r) => {
            let at = r.span().start;
            let r = r.get_ref();
            let Some(stress) = r.stress else {
                return Err(err_at(
                    src.line(at),
                    "[in_situ]",
                    "the in-situ stress needs 'stress'",
                    "give stress = [σxx, σyy, σxy] in Pa at y = datum, tension positive, for example stress = [-1.0e6, -2.0e6, 0.0]",
                ));
            };
            let gradient = r.gradient.unwrap_or([0.0; 3]);
            let datum = r.datum.unwrap_or(0.0);
            for (key, ok) in [
                ("stress", stress.iter().all(|x| x.is_finite())),
                ("gradient", gradient.iter().all(|x| x.is_finite())),
                ("datum", datum.is_finite()),
            ] {
                if !ok {
                    return Err(err_at(
                        src.key_line(at, key),
                        format!("[in_situ] key '{key}'"),
                        format!("'{key}' must be finite"),
                        "give finite numbers: stress in Pa, gradient in Pa/m, datum in m",
                    ));
                }
            }
            // equilibrium with gravity: ∂σxy/∂y = −ρ g_x, ∂σyy/∂y = −ρ g_y in every free
            // block's material
            let g = model.gravity;
            let mut used: Vec<usize> = blocks
                .iter()
                .filter(|b| b.support == Support::Free)
                .map(|b| b.material)
                .collect();
            used.sort_unstable();
            used.dedup();
            for m in used {
                let mat = &materials[m];
                let rho = mat.density();
                // (0 − x rather than −x: no "-0" in the message)
                let want = [0.0 - rho * g[1], 0.0 - rho * g[0]];
                let have = [gradient[1], gradient[2]];
                let scale = want[0].hypot(want[1]).max(have[0].hypot(have[1]));
                let off = (have[0] - want[0]).hypot(have[1] - want[1]);
                if scale > 0.0 && off > 0.01 * scale {
                    warnings.push(format!(
                        "{}line {}: [in_situ]: gradient (dσyy/dy, dσxy/dy) = ({}, {}) Pa/m is not in equilibrium with gravity in material '{}' ({}, {} Pa/m): the difference is released over the whole rock mass with the excavation",
                        file.map(|f| format!("{}:", f.display()))
                            .unwrap_or_default(),
                        src.line(at),
                        have[0],
                        have[1],
                        mat.name,
                        want[0],
                        want[1]
                    ));
                }
            }
            Some(InSitu {
                stress,
                gradient,
                datum,
            })
        }
    };

    Ok(Scene {
        title: raw.title.unwrap_or_default(),
        model,
        materials,
        joints,
        blocks,
        contacts: Contacts { joint, tolerance },
        loads,
        analysis,
        output,
        in_situ,
        file: file.map(Path::to_path_buf),
        warnings,
    })
}

/// The blocks of one `[[import]]` entry: read the file, give each block the material and
/// support of its group (`materials`, `fixed`), its kind and mesh size.
fn import_blocks(
    src: &Src,
    at: usize,
    i: usize,
    im: &RawImport,
    scene_file: Option<&Path>,
    material_index: &dyn Fn(&str, usize, &str) -> Result<usize>,
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
        Some(m) => Some(material_index(m, src.key_line(at, "material"), &entry)?),
        None => None,
    };
    let mut by_group = std::collections::HashMap::new();
    for (g, m) in im.materials.iter().flatten() {
        if !groups.contains(&g.as_str()) {
            return Err(unknown_group("materials", g));
        }
        by_group.insert(
            g.as_str(),
            material_index(m, src.key_line(at, "materials"), &entry)?,
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

fn parse_kind(k: Option<&str>) -> std::result::Result<BlockKind, (String, String)> {
    match k {
        None | Some("deformable") => Ok(BlockKind::Deformable),
        Some("rigid") => Ok(BlockKind::Rigid),
        Some(s) => Err((
            format!("unknown kind '{s}'"),
            "use \"deformable\" or \"rigid\"".into(),
        )),
    }
}

/// The compression cap of a `[[joint]]` (`compressive_strength` and its companions),
/// checked: only on softening joints; G_fc and κₚ together.
fn joint_cap(
    src: &Src,
    at: usize,
    place: &str,
    j: &RawJoint,
    softening: JointSoftening,
) -> Result<Option<JointCap>> {
    let companions = [
        ("cap_shear_factor", j.cap_shear_factor),
        ("compressive_fracture_energy", j.compressive_fracture_energy),
        ("cap_peak_displacement", j.cap_peak_displacement),
    ];
    let Some(fc) = j.compressive_strength else {
        if let Some((key, _)) = companions.iter().find(|(_, v)| v.is_some()) {
            return Err(err_at(
                src.key_line(at, key),
                format!("{place} key '{key}'"),
                "a parameter of the compression cap is given without compressive_strength",
                "add compressive_strength = <Pa> (the cap's strength), or remove the key",
            ));
        }
        return Ok(None);
    };
    let fc = check_value(src, at, place, "compressive_strength", fc, true, "Pa")?;
    softening_only(
        src,
        at,
        place,
        softening,
        "compressive_strength",
        "the compression cap",
    )?;
    let shear_factor = match j.cap_shear_factor {
        None => 9.0,
        Some(v) => check_value(
            src,
            at,
            place,
            "cap_shear_factor",
            v,
            true,
            "(dimensionless)",
        )?,
    };
    let (fracture_energy, peak_displacement) =
        match (j.compressive_fracture_energy, j.cap_peak_displacement) {
            (None, None) => (None, 0.0),
            (Some(g), Some(k)) => (
                Some(check_value(
                    src,
                    at,
                    place,
                    "compressive_fracture_energy",
                    g,
                    true,
                    "N/m",
                )?),
                check_value(src, at, place, "cap_peak_displacement", k, true, "m")?,
            ),
            (Some(_), None) => {
                return Err(err_at(
                    src.key_line(at, "compressive_fracture_energy"),
                    format!("{place} key 'compressive_fracture_energy'"),
                    "the cap softens with compressive_fracture_energy but its peak is not given",
                    "add cap_peak_displacement = <m> (the plastic relative displacement at the peak), or remove compressive_fracture_energy for a perfectly plastic cap",
                ))
            }
            (None, Some(_)) => {
                return Err(err_at(
                    src.key_line(at, "cap_peak_displacement"),
                    format!("{place} key 'cap_peak_displacement'"),
                    "the cap's peak is given without compressive_fracture_energy",
                    "add compressive_fracture_energy = <N/m>, or remove cap_peak_displacement for a perfectly plastic cap",
                ))
            }
        };
    Ok(Some(JointCap {
        compressive_strength: fc,
        shear_factor,
        fracture_energy,
        peak_displacement,
    }))
}

/// The error for `key`, a parameter of `what` (a part of the softening joint law), given
/// on a joint without softening.
fn softening_only(
    src: &Src,
    at: usize,
    place: &str,
    softening: JointSoftening,
    key: &str,
    what: &str,
) -> Result<()> {
    if softening != JointSoftening::None {
        return Ok(());
    }
    Err(err_at(
        src.key_line(at, key),
        format!("{place} key '{key}'"),
        format!("{what} belongs to softening joints"),
        format!("add softening = \"exponential\" with the fracture energies, or remove {key}"),
    ))
}

/// `dilatancy_angle` (degrees, 0 ≤ ψ₀ ≤ φ) and `dilatancy_stress` (Pa, > 0, required
/// with ψ₀ > 0) of a softening joint: (ψ₀, σᵤ), (0, 0) without dilatancy.
fn joint_dilatancy(
    src: &Src,
    at: usize,
    place: &str,
    j: &RawJoint,
    softening: JointSoftening,
    friction_angle: f64,
) -> Result<(f64, f64)> {
    let Some(psi) = j.dilatancy_angle else {
        if j.dilatancy_stress.is_some() {
            return Err(err_at(
                src.key_line(at, "dilatancy_stress"),
                format!("{place} key 'dilatancy_stress'"),
                "dilatancy_stress is given without dilatancy_angle",
                "add dilatancy_angle = <degrees> (the dilatancy at zero normal stress), or remove dilatancy_stress",
            ));
        }
        return Ok((0.0, 0.0));
    };
    let psi = check_value(src, at, place, "dilatancy_angle", psi, false, "degrees")?;
    softening_only(
        src,
        at,
        place,
        softening,
        "dilatancy_angle",
        "the dilatancy",
    )?;
    if psi > friction_angle {
        return Err(err_at(
            src.key_line(at, "dilatancy_angle"),
            format!("{place} key 'dilatancy_angle'"),
            format!("the dilatancy angle {psi}° exceeds the friction angle {friction_angle}°"),
            "give a dilatancy angle between 0 and the friction angle (degrees)",
        ));
    }
    if psi == 0.0 {
        return Ok((0.0, 0.0));
    }
    let Some(su) = j.dilatancy_stress else {
        return Err(err_at(
            src.key_line(at, "dilatancy_angle"),
            format!("{place} key 'dilatancy_angle'"),
            "a dilatancy angle is given without dilatancy_stress",
            "add dilatancy_stress = <Pa> (the compression at which the joint stops dilating; without it a held joint's compression would grow without bound as it slips)",
        ));
    };
    let su = check_value(src, at, place, "dilatancy_stress", su, true, "Pa")?;
    Ok((psi, su))
}

fn check_value(
    src: &Src,
    at: usize,
    place: &str,
    key: &str,
    v: f64,
    positive: bool,
    unit: &str,
) -> Result<f64> {
    let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
    if ok {
        return Ok(v);
    }
    let what = if !v.is_finite() {
        format!("'{key}' is {v}, not a finite number")
    } else if positive {
        format!("'{key}' must be positive, not {v}")
    } else {
        format!("'{key}' must not be negative, not {v}")
    };
    Err(err_at(
        src.key_line(at, key),
        format!("{place} key '{key}'"),
        what,
        format!(
            "give {key} in {unit}, a finite {} number",
            if positive { "positive" } else { "non-negative" }
        ),
    ))
}

fn parse_analysis(
    src: &Src,
    a: Option<&Spanned<toml::Table>>,
    file: Option<&Path>,
    blocks: &[Block],
) -> Result<Analysis> {
    let Some(a) = a else {
        return Ok(Analysis {
            kind: AnalysisType::Static,
            lateral: 0.0,
            load_steps: 10,
            direction: 1.0,
            dt: None,
            duration: None,
            ground_motion: Vec::new(),
            frame: ground_motion::Frame::Relative,
            settings: AnalysisSettings::Static(StaticSettings::default()),
        });
    };
    let at = a.span().start;
    let t = a.get_ref();
    for k in t.keys() {
        if !ANALYSIS_KEYS.contains(&k.as_str()) {
            return Err(err_at(
                src.key_line(at, k),
                format!("[analysis] key '{k}'"),
                format!("unknown key '{k}'"),
                format!("use one of: {}", ANALYSIS_KEYS.join(", ")),
            ));
        }
    }
    let num = |key: &str| -> Result<Option<f64>> {
        match t.get(key) {
            None => Ok(None),
            Some(toml::Value::Float(x)) => Ok(Some(*x)),
            Some(toml::Value::Integer(x)) => Ok(Some(*x as f64)),
            Some(_) => Err(err_at(
                src.key_line(at, key),
                format!("[analysis] key '{key}'"),
                format!("'{key}' must be a number"),
                "write a number without quotes",
            )),
        }
    };
    let kind = match t.get("type") {
        None => AnalysisType::Static,
        Some(toml::Value::String(s)) => match s.as_str() {
            "static" => AnalysisType::Static,
            "capacity" => AnalysisType::Capacity,
            "dynamic" => AnalysisType::Dynamic,
            _ => {
                return Err(err_at(
                    src.key_line(at, "type"),
                    "[analysis] key 'type'",
                    format!("unknown analysis type '{s}'"),
                    "use \"static\", \"capacity\" or \"dynamic\"",
                ))
            }
        },
        Some(_) => {
            return Err(err_at(
                src.key_line(at, "type"),
                "[analysis] key 'type'",
                "'type' must be a string",
                "use \"static\", \"capacity\" or \"dynamic\"",
            ))
        }
    };
    let lateral = num("lateral")?.unwrap_or(0.0);
    if !lateral.is_finite() {
        return Err(err_at(
            src.key_line(at, "lateral"),
            "[analysis] key 'lateral'",
            "'lateral' must be finite",
            "give the horizontal coefficient, for example 0.3",
        ));
    }
    let steps = num("load_steps")?.unwrap_or(10.0);
    if !((1.0..=1e6).contains(&steps) && steps.fract() == 0.0) {
        return Err(err_at(
            src.key_line(at, "load_steps"),
            "[analysis] key 'load_steps'",
            format!("load_steps must be a whole number from 1 to 10⁶, not {steps}"),
            "for example load_steps = 10",
        ));
    }
    let direction = num("direction")?.unwrap_or(1.0);
    if direction != 1.0 && direction != -1.0 {
        return Err(err_at(
            src.key_line(at, "direction"),
            "[analysis] key 'direction'",
            format!("direction must be 1 or -1, not {direction}"),
            "use direction = 1 (+x) or -1 (-x)",
        ));
    }
    let dt = num("dt")?;
    let duration = num("duration")?;
    for (key, v) in [("dt", dt), ("duration", duration)] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(err_at(
                    src.key_line(at, key),
                    format!("[analysis] key '{key}'"),
                    format!("'{key}' must be a positive time in s, not {v}"),
                    format!("for example {key} = 0.01"),
                ));
            }
        }
    }
    if kind == AnalysisType::Dynamic {
        let (Some(dt), Some(duration)) = (dt, duration) else {
            return Err(err_at(
                src.line(at),
                "[analysis]",
                "a dynamic analysis needs 'dt' and 'duration'",
                "add dt = <s> and duration = <s>",
            ));
        };
        if dt > duration {
            return Err(err_at(
                src.key_line(at, "dt"),
                "[analysis] key 'dt'",
                format!("dt = {dt} s is longer than the duration {duration} s"),
                "make dt smaller than the duration",
            ));
        }
    }
    let ground_motion = match t.get("ground_motion") {
        None => Vec::new(),
        Some(v) => {
            // relative record names are taken from the scene's directory (not for
            // built-in scenes, named "example:NAME")
            let base = file
                .filter(|f| f.exists())
                .map(|f| f.parent().unwrap_or(Path::new("")).to_path_buf());
            let gm = ground_motion::components_from_toml(v, base.as_deref()).map_err(|e| {
                let place = match &e.at {
                    Some((f, Some(l))) => {
                        format!("[analysis] ground_motion: record {}:{l}", f.display())
                    }
                    Some((f, None)) => format!("[analysis] ground_motion: record {}", f.display()),
                    None => "[analysis] key 'ground_motion'".to_string(),
                };
                err_at(src.key_line(at, "ground_motion"), place, e.what, e.fix)
            })?;
            if kind != AnalysisType::Dynamic {
                return Err(err_at(
                    src.key_line(at, "ground_motion"),
                    "[analysis] key 'ground_motion'",
                    "a ground motion needs type = \"dynamic\"",
                    "set type = \"dynamic\" with dt and duration, or remove ground_motion",
                ));
            }
            gm
        }
    };
    let frame = match t.get("frame") {
        None => ground_motion::Frame::Relative,
        Some(v) => {
            let f = match v.as_str() {
                Some("relative") => ground_motion::Frame::Relative,
                Some("absolute") => ground_motion::Frame::Absolute,
                _ => {
                    return Err(err_at(
                        src.key_line(at, "frame"),
                        "[analysis] key 'frame'",
                        "unknown frame",
                        "write frame = \"relative\" (default: the ground motion as the load −M ι a_g on the free blocks) or \"absolute\" (the fixed blocks move with the ground)",
                    ))
                }
            };
            if kind != AnalysisType::Dynamic {
                return Err(err_at(
                    src.key_line(at, "frame"),
                    "[analysis] key 'frame'",
                    "a frame of the ground motion needs type = \"dynamic\"",
                    "set type = \"dynamic\", or remove frame",
                ));
            }
            if f == ground_motion::Frame::Absolute
                && t.get("inertia").and_then(|v| v.as_bool()) == Some(false)
            {
                return Err(err_at(
                    src.key_line(at, "frame"),
                    "[analysis] key 'frame'",
                    "frame = \"absolute\" needs the inertia: without it the ground's motion reaches the blocks only as the body force of the relative frame",
                    "remove frame (the relative frame), or set inertia = true",
                ));
            }
            f
        }
    };
    let keys = AnalysisTable { src, at, t };
    let settings = match kind {
        AnalysisType::Static | AnalysisType::Capacity => {
            AnalysisSettings::Static(keys.statics(kind, blocks)?)
        }
        AnalysisType::Dynamic => AnalysisSettings::Dynamic(keys.dynamics(
            dt.unwrap_or(0.01),
            duration.unwrap_or(0.0),
            frame,
        )?),
    };
    Ok(Analysis {
        kind,
        lateral,
        load_steps: steps as usize,
        direction,
        dt,
        duration,
        ground_motion,
        frame,
        settings,
    })
}
