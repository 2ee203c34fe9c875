//! `[[generate]]`: structures built from a few parameters (docs/scene-reference.md, "[[generate]]").
//!
//! Every generator takes its own parameters (a TOML table without the common keys
//! `type`, `name`, `material`, `base_material`, `kind`, `mesh_size`) and returns blocks.
//!
//! One module per generator: [`incline`], [`wall`] (also used by [`tower`]), [`arch`],
//! [`slope`], [`tunnel`]; `common` holds the parameter parsing and the polygon helpers
//! (all polygon cutting goes through `geo::BooleanOps`).

pub mod arch;
pub(crate) mod common;
pub mod incline;
pub mod slope;
pub mod solid;
#[cfg(test)]
pub(crate) mod testutil;
pub mod tower;
pub mod tunnel;
pub mod wall;

/// A block made by a generator; the caller gives it a material and a kind.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratedBlock {
    /// Unique within the generator's output (the caller prefixes it with the entry's `name`).
    pub name: String,
    /// Counter-clockwise vertices, m.
    pub vertices: Vec<[f64; 2]>,
    /// Foundation / frame blocks are fixed.
    pub fixed: bool,
    /// The masonry unit the block is part of, numbered from 0 within the generator's
    /// output: the two halves of a brick split by a potential crack share one.
    pub unit: Option<usize>,
}

/// A generator error: the key at fault (if any), what is wrong and how to fix it.
#[derive(Debug, Clone, PartialEq)]
pub struct GenError {
    pub key: Option<String>,
    pub what: String,
    pub fix: String,
}

/// The generator types, for error messages.
pub const TYPES: &[&str] = &["incline", "wall", "arch", "tower", "slope", "tunnel"];

/// Run the generator `kind` with its parameters.
pub fn generate(kind: &str, params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    match kind {
        "incline" => incline::generate(params),
        "wall" => wall::generate(params),
        "arch" => arch::generate(params),
        "tower" => tower::generate(params),
        "slope" => slope::generate(params),
        "tunnel" => tunnel::generate(params),
        _ => Err(GenError {
            key: Some("type".into()),
            what: format!("unknown generator type '{kind}'"),
            fix: format!("use one of {}", TYPES.join(", ")),
        }),
    }
}
