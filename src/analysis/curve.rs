//! The capacity curve: the load factor λ against the displacement of a control point, one
//! point per converged increment of the capacity search (written to `curve.csv` and drawn
//! as `figures/capacity_curve.*`); under displacement control, the pushed block's
//! displacement and the force that holds it.

use crate::mesh::{BlockDofs, Mesh};

/// One converged state of the capacity search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Load factor λ (lateral body force / weight).
    pub load_factor: f64,
    /// Displacement of the control block's centroid (m), total since the start.
    pub displacement: [f64; 2],
    /// Displacement control (`[analysis] push_block`): the horizontal and vertical
    /// forces (N) and the moment (N·m) that hold the pushed block on its path; `None` for
    /// a capacity curve.
    pub reaction: Option<[f64; 3]>,
    /// Displacement of the top block's centroid (m), total since the start
    /// ([`Curve::top_block`]; the control block's own in a capacity curve).
    pub top: [f64; 2],
}

/// The capacity curve of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The control block: the top-most free block (highest centroid; the first in scene
    /// order on ties).
    pub control_block: usize,
    /// The top-most free block ([`control_block`]): the control block of a capacity
    /// curve, whose displacement a push's curve also records.
    pub top_block: usize,
    /// From the state after gravity (λ = 0) to the last converged increment.
    pub points: Vec<CurvePoint>,
    /// Displacement control (`[analysis] push_block`): how far the push went and why it
    /// ended; `None` for a capacity curve.
    pub path: Option<PushPath>,
}

/// How a push (`[analysis] push_block`) was followed (summary.json, `curve.path`).
#[derive(Debug, Clone, PartialEq)]
pub struct PushPath {
    /// The displacement along the push at the end, as a fraction of `push_displacement`.
    pub reached: f64,
    /// The largest displacement along the push on the way (m): past a snap-back the
    /// path comes back from it.
    pub furthest: f64,
    /// The converged increments taken on the cylinder (docs/theory.md Eq. A1), on the
    /// dissipation (Eq. A2) and under displacement control of the block (Eq. A3, or
    /// `path = "displacement"`).
    pub increments: [usize; 3],
    /// The increments taken unconverged, within `accept_residual`
    /// ([`super::statics::arc_length::ArcLength::accept`]), and the largest relative
    /// out-of-balance force one of them was taken at (0 if none).
    pub accepted: usize,
    pub accepted_residual: f64,
    /// Why the push ended: "the end of the push" or why it stopped short.
    pub end: String,
}

/// The top-most free block (highest initial centroid; the first one on ties), if any.
pub fn control_block(mesh: &Mesh) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, b) in mesh.blocks.iter().enumerate() {
        if b.dofs == BlockDofs::Fixed {
            continue;
        }
        if best.is_none_or(|j| b.centroid[1] > mesh.blocks[j].centroid[1]) {
            best = Some(i);
        }
    }
    best
}

/// The control block's centroid displacement (m) in the configuration `cur` with total
/// unknowns `u`, measured from the initial mesh `mesh0`.
pub fn control_displacement(mesh0: &Mesh, cur: &Mesh, u: &[f64], block: usize) -> [f64; 2] {
    if let BlockDofs::Rigid { first, .. } = mesh0.blocks[block].dofs {
        let f = first as usize;
        return [u[f], u[f + 1]];
    }
    let b = &mesh0.blocks[block];
    let disp: Vec<[f64; 2]> = b
        .nodes
        .clone()
        .map(|n| {
            let (p, q) = (cur.nodes[n as usize], mesh0.nodes[n as usize]);
            [p[0] - q[0], p[1] - q[1]]
        })
        .collect();
    super::fit_motion(mesh0, block, &disp).0
}

/// The centroid displacement (m) of the free block `block` from the total unknowns `u`
/// alone, in the configuration `cur`: a rigid block's own unknowns, or the motion fitted
/// to a deformable block's nodes, whose unknowns are their total displacements
/// ([`super::fit_motion`]).
pub fn block_displacement(cur: &Mesh, u: &[f64], block: usize) -> [f64; 2] {
    match cur.blocks[block].dofs {
        BlockDofs::Rigid { first, .. } => [u[first as usize], u[first as usize + 1]],
        BlockDofs::Deformable => {
            let disp: Vec<[f64; 2]> = cur.blocks[block]
                .nodes
                .clone()
                .map(|n| {
                    let d = cur.node_dofs[n as usize];
                    [u[d[0] as usize], u[d[1] as usize]]
                })
                .collect();
            super::fit_motion(cur, block, &disp).0
        }
        BlockDofs::Fixed => [0.0, 0.0],
    }
}
