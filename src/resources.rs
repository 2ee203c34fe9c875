//! Memory: the peak resident memory of the process, the memory this machine has, and an
//! estimate of what an analysis of a mesh will need, made before anything large is
//! allocated so that a scene too big for the machine is refused up front (with the
//! estimate) instead of being killed by the system halfway through.
//!
//! The estimate adds the pieces an analysis holds at its peak (the numeric
//! factorization): the element matrices with their scatter maps and the mesh, the
//! factor, the per-unknown work vectors. Every piece is counted from the mesh except the
//! factor, whose size is only known after the symbolic analysis: it is estimated as
//! `FILL · n · log₂ n` entries for n unknowns, the growth of a nested-dissection factor
//! of a planar mesh (Lipton, Rose and Tarjan 1979), with `FILL` and the per-item costs
//! fitted to runs measured here (docs/performance.md, "Memory"). The `memory_*` tests
//! check the estimate against the measured peak of the process.

use crate::mesh::{BlockDofs, Mesh};

/// Fill constant of the factor size estimate `FILL · n · log₂ n` (stored entries).
/// Measured here with faer's AMD-ordered supernodal Cholesky (`factor_nnz` in
/// summary.json): 4.1 and 6.4 on rigid running-bond walls of 2,745 and 10,890 unknowns
/// (it grows with n: AMD is not nested dissection), 3.3 on a meshed deformable wall of
/// 15,404 unknowns. 8 covers them all, erring on the safe side.
pub const FILL: f64 = 8.0;

/// Bytes per stored factor entry: the value, faer's supernodal row indices and its
/// numeric workspace (fitted with [`PER_CONTACT_ENTRY`] on the rigid walls above).
pub const PER_FACTOR_ENTRY: f64 = 24.0;

/// Bytes per entry of a contact element matrix (its scatter map, its values kept for
/// the deterministic sum, the pattern's building pairs, the CSR entry and its copies):
/// 1.3–1.7 kB per rigid–rigid contact (36 entries) measured on the rigid walls.
pub const PER_CONTACT_ENTRY: f64 = 45.0;

/// Bytes per triangle of the mesh (element matrix and scatter, co-rotational frame,
/// stresses and their trial copies, the mesh and its updated copy): fitted as the rest
/// of the peak on the meshed deformable wall (4.2 kB).
pub const PER_TRIANGLE: f64 = 4500.0;

/// Bytes per unknown (about 40 work vectors of f64).
pub const PER_DOF: f64 = 320.0;

/// Resident memory of the process before the analysis where the system does not tell
/// (code, threads, allocator): 7.4 MB measured on the smallest example of the default
/// build. Where it does, the process's current resident memory is taken instead: the
/// builds with the PETSc/MPI backends load about 50 MB of shared libraries.
pub const BASE: f64 = 8e6;

/// Peak resident memory of this process so far (bytes), from `VmHWM` in
/// `/proc/self/status`; `None` on systems without it.
pub fn peak_resident_bytes() -> Option<u64> {
    proc_kib("/proc/self/status", "VmHWM:").map(|k| k * 1024)
}

/// Current resident memory of this process (bytes), from `VmRSS` in `/proc/self/status`;
/// `None` on systems without it.
pub fn resident_bytes() -> Option<u64> {
    proc_kib("/proc/self/status", "VmRSS:").map(|k| k * 1024)
}

/// Memory the machine can give a new allocation without swapping (bytes), from
/// `MemAvailable` in `/proc/meminfo`; `None` on systems without it.
pub fn available_bytes() -> Option<u64> {
    proc_kib("/proc/meminfo", "MemAvailable:").map(|k| k * 1024)
}

/// The value in kB of the line `key` of a `/proc` file such as `VmHWM:   1234 kB`.
fn proc_kib(file: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// An estimate of the memory an analysis will need, in bytes, by part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The process before the analysis: its resident memory now, or [`BASE`].
    pub base: f64,
    /// Element matrices and scatter maps, the mesh and the per-element state.
    pub elements: f64,
    /// The sparse factor.
    pub factor: f64,
    /// Work vectors of the unknowns.
    pub vectors: f64,
}

impl Estimate {
    /// Total, bytes.
    pub fn total(&self) -> f64 {
        self.base + self.elements + self.factor + self.vectors
    }
}

/// The memory an analysis of `mesh` will need (bytes), counted from the mesh before any
/// matrix is built, with the per-item costs above. A contact element's matrix has the
/// square of the unknowns of its two sides (3 for a rigid block, 4 for the two nodes of a
/// deformable one). The `memory_*` tests check the estimate against the measured peak.
pub fn estimate(mesh: &Mesh) -> Estimate {
    let n = mesh.n_dofs as f64;
    let side = |b: u32| -> f64 {
        match mesh.blocks[b as usize].dofs {
            BlockDofs::Rigid { .. } => 3.0,
            BlockDofs::Fixed => 0.0,
            BlockDofs::Deformable => 4.0,
        }
    };
    let contact_entries: f64 = mesh
        .contacts
        .iter()
        .map(|c| (side(c.block_l) + side(c.block_m)).powi(2))
        .sum();
    Estimate {
        base: resident_bytes().map_or(BASE, |b| b as f64),
        elements: PER_CONTACT_ENTRY * contact_entries + PER_TRIANGLE * mesh.triangles.len() as f64,
        factor: PER_FACTOR_ENTRY * FILL * n * n.max(2.0).log2(),
        vectors: PER_DOF * n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_reports_its_memory() {
        // Linux: both files exist and the numbers are plausible for a test process
        if let (Some(peak), Some(avail)) = (peak_resident_bytes(), available_bytes()) {
            assert!(peak > 1_000_000 && peak < 1 << 40, "{peak}");
            assert!(avail > 1_000_000, "{avail}");
        }
    }

    #[test]
    fn a_larger_mesh_needs_more_memory() {
        let small =
            crate::scene::parse_str(crate::scene::examples::get("wall").unwrap(), None).unwrap();
        let m = crate::mesh::build(&small);
        let e = estimate(&m);
        assert!(e.total() > e.base && e.factor > 0.0 && e.elements > 0.0);
        let bigger = crate::scene::parse_str(
            &crate::scene::examples::get("wall")
                .unwrap()
                .replace("courses = 10", "courses = 40"),
            None,
        )
        .unwrap();
        let e4 = estimate(&crate::mesh::build(&bigger));
        // four times the blocks: about four times the elements, more for the factor
        assert!(e4.elements > 3.5 * e.elements, "{e4:?} {e:?}");
        assert!(e4.factor > 4.0 * e.factor, "{e4:?} {e:?}");
    }
}
