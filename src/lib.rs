//! dfem: the discrete finite element method (DFEM) for masonry and blocky rock.
//!
//! Data flows one way (docs/theory.md describes each stage):
//! scene → geometry → mesh → assembly → linear backend (`dfem_kernels`) → analysis → output.
// the `json!` of summary.json's statistics nests deeper than serde_json's default allows
#![recursion_limit = "256"]

pub mod analysis;
pub mod assembly;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod material;
pub mod mesh;
pub mod output;
pub mod resources;
pub mod scene;
pub mod solve;

pub use error::{Error, Result};
