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
