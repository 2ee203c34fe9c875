//! Independent reference solutions for dfem's validation tests (BENCHMARKS V1, V2, V6,
//! V7). They use no dfem code; the arch limit analysis uses the `microlp` LP solver (a
//! dev-dependency). Include from a test file with
//! `#[path = "reference/mod.rs"] mod reference;`.
//!
//! * [`block`]: closed forms for one block on an incline or flat base (V1, V2).
//! * [`arch`]: rigid-block limit analysis by the static theorem, as an LP (V6).
//! * [`goodman_bray`]: limit equilibrium of block toppling (V7).

#![allow(dead_code)]

pub mod arch;
pub mod block;
pub mod goodman_bray;
