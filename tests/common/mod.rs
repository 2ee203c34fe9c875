//! Helpers shared by the integration tests.
#![allow(dead_code)]

use dfem::analysis::{self, Outcome};
use dfem::mesh::{self, Mesh};
use dfem::scene::{self, Scene};
use std::path::PathBuf;

pub fn scene(text: &str) -> Scene {
    scene::parse_str(text, None).unwrap_or_else(|e| panic!("scene does not parse: {e}"))
}

pub fn solve(sc: &Scene) -> (Mesh, Outcome) {
    let m = mesh::build(sc);
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).unwrap();
    let out = analysis::run(sc, &m, backend.as_mut()).unwrap();
    (m, out)
}

/// The `dfem` binary built by cargo for the integration tests.
pub fn dfem_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_dfem"))
}

/// A fresh empty directory under the target directory.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// TOML of a stone (λ = μ = 5 GPa, γ = 20 kN/m³) and a dry joint "dry" with normal and
/// shear moduli `en`, `gs` (Pa), band thickness `band` (m) and friction angle `phi`
/// (degrees), no cohesion: the material pair of the tilting, arch and stress tests.
pub fn stone_and_dry_joint(en: f64, gs: f64, band: f64, phi: f64) -> String {
    format!(
        r#"
[[material]]
name = "stone"
lame_lambda = 5e9
lame_mu = 5e9
unit_weight = 20e3
[[joint]]
name = "dry"
normal_modulus = {en:e}
shear_modulus = {gs:e}
band = {band:e}
friction_angle = {phi}
"#
    )
}
