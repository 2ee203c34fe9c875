//! TOML text → validated [`Scene`]. Everything is checked before any work: syntax, types,
//! unknown keys, moduli, names, polygons, overlaps. Every error names the file, the line,
//! the block or key, and the fix (docs/outputs.md, "Command line and exit status").

mod blocks;
mod contacts;
mod generators;
mod imports;
mod in_situ;
mod joints;
mod loads;
mod materials;
mod model;
mod output;

use super::*;
use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::hash_map::{self, HashMap};
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
    /// Read by [`check_dimension`] before the rest.
    #[allow(dead_code)]
    dimension: Option<toml::Value>,
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
    frame_interval: Option<f64>,
    checkpoint_every: Option<i64>,
}

/// Keys of `[analysis]`: those of every analysis type (a key that the scene's type does
/// not read is accepted and has no effect, docs/scene-reference.md, "`[analysis]`").
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
    "event_cuts",
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

/// The entries of one array of named tables (`[[material]]`, `[[joint]]`, `[[block]]`)
/// met so far: each entry needs a `name`, and no two entries may share one.
struct Named<'n> {
    /// The table, as the errors say it: "material".
    table: &'static str,
    /// Each name met, with the index of its entry.
    entries: HashMap<&'n str, usize>,
}

impl<'n> Named<'n> {
    fn new(table: &'static str) -> Self {
        Named {
            table,
            entries: HashMap::new(),
        }
    }

    /// The name of entry `i` (from 0), whose header starts at `at`; the error for an entry
    /// without one.
    fn name(&self, src: &Src, at: usize, i: usize, name: Option<&'n str>) -> Result<&'n str> {
        name.ok_or_else(|| {
            err_at(
                src.line(at),
                format!("[[{}]] #{}", self.table, i + 1),
                format!("the {} has no name", self.table),
                "add name = \"...\" to the table",
            )
        })
    }

    /// [`Named::name`], and the error for a name that an earlier entry has already.
    fn unique_name(
        &mut self,
        src: &Src,
        at: usize,
        i: usize,
        name: Option<&'n str>,
    ) -> Result<&'n str> {
        let name = self.name(src, at, i, name)?;
        if self.earlier(name, i).is_some() {
            return Err(err_at(
                src.key_line(at, "name"),
                format!("{} '{name}'", self.table),
                format!("a {} of that name is already defined", self.table),
                format!("give each {} a different name", self.table),
            ));
        }
        Ok(name)
    }

    /// Record `name` as that of entry `i`: the index of the earlier entry of that name,
    /// if there is one (which keeps it).
    fn earlier(&mut self, name: &'n str, i: usize) -> Option<usize> {
        match self.entries.entry(name) {
            hash_map::Entry::Occupied(e) => Some(*e.get()),
            hash_map::Entry::Vacant(e) => {
                e.insert(i);
                None
            }
        }
    }
}

/// The index of `name` among `names`, those of the `[[table]]` entries; the error, at
/// `line` in `place`, lists the names defined.
fn index_of<'a>(
    table: &str,
    names: impl Iterator<Item = &'a str> + Clone,
    name: &str,
    line: usize,
    place: &str,
) -> Result<usize> {
    names.clone().position(|n| n == name).ok_or_else(|| {
        let known: Vec<&str> = names.collect();
        err_at(
            line,
            place,
            format!("{table} '{name}' is not defined"),
            if known.is_empty() {
                format!("define it in a [[{table}]] table")
            } else {
                format!(
                    "define it in a [[{table}]] table or use one of: {}",
                    known.join(", ")
                )
            },
        )
    })
}

/// The value of `key` (in `unit`), which the table whose header starts at `at` (`place`
/// in errors) must give: the error when it is missing, else [`check_value`]'s.
fn required(
    src: &Src,
    at: usize,
    place: &str,
    key: &str,
    v: Option<f64>,
    positive: bool,
    unit: &str,
) -> Result<f64> {
    let v = v.ok_or_else(|| {
        err_at(
            src.line(at),
            place,
            format!("key '{key}' is missing"),
            format!("add {key} = <value in {unit}>"),
        )
    })?;
    check_value(src, at, place, key, v, positive, unit)
}

/// A warning about line `line` of the scene, after its file when it has one.
fn warning(file: Option<&Path>, line: usize, what: std::fmt::Arguments) -> String {
    format!(
        "{}line {line}: {what}",
        file.map(|f| format!("{}:", f.display()))
            .unwrap_or_default()
    )
}

/// `[model] dimension`, read before the rest of the scene, whose keys it changes: 2 (the
/// default) is read on; 3 is refused with its line, since this version analyses
/// two-dimensional scenes only (the blocks of a 3D scene would otherwise fail as 2D
/// blocks, with a message that does not say why).
fn check_dimension(src: &Src) -> Result<()> {
    #[derive(Deserialize)]
    struct Probe {
        model: Option<Spanned<ModelProbe>>,
    }
    #[derive(Deserialize)]
    struct ModelProbe {
        dimension: Option<toml::Value>,
    }
    // a scene that is not TOML is reported by the full parse
    let Ok(probe) = toml::from_str::<Probe>(src.text) else {
        return Ok(());
    };
    let Some(model) = probe.model else {
        return Ok(());
    };
    let line = src.key_line(model.span().start, "dimension");
    match model.get_ref().dimension.as_ref().map(|v| v.as_integer()) {
        None | Some(Some(2)) => Ok(()),
        Some(Some(3)) => Err(err_at(
            line,
            "[model] key 'dimension'",
            "three-dimensional scenes (dimension = 3) are not analysed by this version: it reads two-dimensional scenes",
            "give the model in two dimensions (docs/scene-reference.md), without the key 'dimension'",
        )),
        Some(_) => Err(err_at(
            line,
            "[model] key 'dimension'",
            "dimension must be the integer 2 or 3",
            "leave it out for a two-dimensional scene (dimension = 2)",
        )),
    }
}

fn parse_inner(text: &str, file: Option<&Path>) -> Result<Scene> {
    let src = Src { text };
    check_dimension(&src)?;
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

    let model = model::parse_model(&src, raw.model.as_ref())?;
    let materials = materials::parse_materials(&src, &raw.material)?;
    let mut joints = joints::parse_joints(&src, &raw.joint)?;
    let mut blocks = blocks::parse_blocks(&src, &raw.block, &materials)?;
    generators::parse_generate(&src, &raw.generate, &materials, &mut blocks)?;
    imports::parse_imports(&src, &raw.import, file, &materials, &mut blocks)?;
    blocks::check_count_and_names(&blocks)?;
    joints::resolve_blocks(&src, &raw.joint, &mut joints, &blocks)?;
    let contacts = contacts::parse_contacts(&src, raw.contacts.as_ref(), &joints, &blocks)?;
    blocks::check_geometry(&mut blocks, contacts.tolerance, file, &mut warnings)?;
    let loads = loads::parse_loads(&src, &raw.load, &blocks, contacts.tolerance)?;

    // [analysis]
    let analysis = parse_analysis(&src, raw.analysis.as_ref(), file, &blocks)?;

    let output = output::parse_output(&src, raw.output.as_ref(), &blocks)?;
    let in_situ = in_situ::parse_in_situ(
        &src,
        raw.in_situ.as_ref(),
        model.gravity,
        &materials,
        &blocks,
        file,
        &mut warnings,
    )?;

    Ok(Scene {
        title: raw.title.unwrap_or_default(),
        model,
        materials,
        joints,
        blocks,
        contacts,
        loads,
        analysis,
        output,
        in_situ,
        file: file.map(Path::to_path_buf),
        warnings,
    })
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
