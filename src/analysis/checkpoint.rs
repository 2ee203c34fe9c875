//! Checkpoints of a dynamic run (docs/outputs.md, "Interrupted runs and --resume"): the
//! whole state of the time integration (docs/theory.md §5) between two steps, so that
//! `dfem run --resume DIR` continues an interrupted run and reproduces the uninterrupted
//! one to the bit.
//!
//! The state is what [`crate::analysis::dynamics::Dynamics`] carries from one step to the
//! next: the current (updated Lagrangian) configuration with its contact set, the
//! committed stresses, contact forces, states and history variables, the total unknowns u, the velocity v
//! and acceleration a, the internal and damping forces of the committed state, the energy
//! sums, the time and the counters. Everything else (masses, loads, matrices and their
//! pattern) is rebuilt from the scene and that configuration.
//!
//! File format (`checkpoint.bin`), version [`VERSION`]: the 8 bytes `DFEMCKPT`, the format
//! version as a little-endian u32, then a [`Saved`] in the `postcard` encoding (f64 as
//! their 8 IEEE bytes, so that every number comes back exactly).

use super::config::Committed;
use super::dynamics::Energy;
use super::Stats;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Name of the checkpoint file in the output directory.
pub const FILE: &str = "checkpoint.bin";
const MAGIC: &[u8; 8] = b"DFEMCKPT";
/// Version of the format; a file of another version is refused. (4: the counters gained
/// `tangent_fallbacks`; 5: each contact's history is two variables, ξ and the cap's κ₃;
/// 6: the counters gained `event_cuts`, `step_error_max` and `step_error_sum`.)
pub const VERSION: u32 = 6;

/// The state of a dynamic run after `step` completed time steps.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Completed time steps (history.csv holds rows 0 to `step`).
    pub step: usize,
    /// Time reached (s).
    pub time: f64,
    /// Current configuration: node positions, rigid blocks' centroids, contacts (m).
    pub mesh: Mesh,
    pub committed: Committed,
    /// Velocity (m/s, rad/s) and acceleration (m/s², rad/s²) of the unknowns.
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    /// Internal and damping forces (N) of the committed state.
    pub f_int: Vec<f64>,
    pub f_visc: Vec<f64>,
    pub energy: Energy,
    /// Counters so far (factorizations and wall time included).
    pub stats: Stats,
    /// The ground's displacement (m) and velocity (m/s) in the absolute frame (zero in
    /// the relative frame).
    pub ground: [[f64; 2]; 2],
}

/// A checkpoint with the identity of the scene it belongs to.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Saved {
    /// Where the scene came from: its file (absolute path) or `example:NAME`.
    pub source: String,
    /// [`fingerprint`] of the scene.
    pub fingerprint: u64,
    pub state: Checkpoint,
}

/// A 64-bit FNV-1a hash of everything the scene defines (its parsed form, ground-motion
/// records included; not where it was read from): two scenes with the same fingerprint
/// run the same analysis.
pub fn fingerprint(scene: &Scene) -> u64 {
    let mut s = scene.clone();
    s.file = None;
    s.warnings.clear();
    // a record's path depends on how the scene's path was given (relative or not); its
    // samples are in the scene
    for g in &mut s.analysis.ground_motion {
        g.file = None;
    }
    let text = format!("{s:?}");
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// [`Saved`] by reference (the same encoding).
#[derive(Serialize)]
struct SavedRef<'a> {
    source: &'a str,
    fingerprint: u64,
    state: &'a Checkpoint,
}

/// The bytes of the checkpoint file of `state`, for the scene from `source` with
/// [`fingerprint`] `fingerprint`.
pub fn encode(source: &str, fingerprint: u64, state: &Checkpoint) -> Vec<u8> {
    let mut bytes = MAGIC.to_vec();
    bytes.extend(VERSION.to_le_bytes());
    let saved = SavedRef {
        source,
        fingerprint,
        state,
    };
    bytes.extend(postcard::to_allocvec(&saved).expect("plain data encodes"));
    bytes
}

/// Read a checkpoint file back; `path` names it in the errors.
pub fn decode(bytes: &[u8], path: &Path) -> Result<Saved> {
    let bad = |what: String| {
        Error::new(what)
            .file(path)
            .fix("run the analysis again without --resume (the checkpoint cannot be used)")
    };
    if bytes.len() < 12 || &bytes[..8] != MAGIC {
        return Err(bad("not a dfem checkpoint".into()));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(bad(format!(
            "checkpoint format version {version}; this dfem reads version {VERSION}"
        )));
    }
    postcard::from_bytes(&bytes[12..]).map_err(|e| bad(format!("the checkpoint is damaged ({e})")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_other_files_and_versions() {
        let p = Path::new("x/checkpoint.bin");
        assert!(decode(b"hello", p).is_err());
        let mut b = MAGIC.to_vec();
        b.extend(99u32.to_le_bytes());
        let e = decode(&b, p).unwrap_err().to_string();
        assert!(e.contains("version 99"), "{e}");
        let mut b = MAGIC.to_vec();
        b.extend(VERSION.to_le_bytes());
        b.extend([1, 2, 3]);
        let e = decode(&b, p).unwrap_err().to_string();
        assert!(e.contains("damaged"), "{e}");
    }
}
