//! Lumped mass (docs/theory.md Eq. B5: Mₑ lumped, ρ t A / 3 per node and direction) and the
//! influence vectors ι of a ground motion (docs/theory.md §5). Built only by the dynamic
//! driver: a static run does no mass work at all.

use crate::geometry::polygon::{sub, Point};
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::Scene;
use dfem_kernels::CONSTRAINED;

/// Diagonal of the lumped mass matrix, one entry per unknown: kg for translations,
/// kg·m² for the rotation of a rigid block.
///
/// * deformable block: a third of each triangle's mass ρ t A to each of its nodes, in
///   both directions;
/// * rigid block: m = ρ t A on u and v, and the polar moment I = ρ t ∫ r² dA about the
///   centroid on θ (docs/theory.md §1: the three unknowns sit at the centroid).
///
/// The mass is computed once from the initial geometry (it is conserved).
pub fn lumped(scene: &Scene, mesh: &Mesh) -> Vec<f64> {
    let mut m = vec![0.0; mesh.n_dofs];
    let t = scene.model.thickness;
    for (bi, b) in mesh.blocks.iter().enumerate() {
        let rho = scene.materials[scene.blocks[bi].material].density();
        match b.dofs {
            BlockDofs::Fixed => {}
            BlockDofs::Rigid { first, centroid } => {
                let poly: Vec<Point> = b
                    .boundary
                    .iter()
                    .map(|&n| sub(mesh.nodes[n as usize], centroid))
                    .collect();
                let f = first as usize;
                m[f] = rho * t * b.area;
                m[f + 1] = rho * t * b.area;
                m[f + 2] = rho * t * polar_moment(&poly);
            }
            BlockDofs::Deformable => {
                for ti in b.triangles.clone() {
                    let w = rho * t * mesh.triangle_area(ti as usize) / 3.0;
                    for &n in &mesh.triangles[ti as usize] {
                        for d in mesh.node_dofs[n as usize] {
                            if d != CONSTRAINED {
                                m[d as usize] += w;
                            }
                        }
                    }
                }
            }
        }
    }
    m
}

/// Polar second moment of area ∫ (x² + y²) dA (m⁴) of a counter-clockwise polygon about
/// the origin: Σ (xᵢyᵢ₊₁ − xᵢ₊₁yᵢ)(xᵢ² + xᵢxᵢ₊₁ + xᵢ₊₁² + yᵢ² + yᵢyᵢ₊₁ + yᵢ₊₁²) / 12.
pub fn polar_moment(poly: &[Point]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            let cross = p[0] * q[1] - q[0] * p[1];
            cross
                * (p[0] * p[0]
                    + p[0] * q[0]
                    + q[0] * q[0]
                    + p[1] * p[1]
                    + p[1] * q[1]
                    + q[1] * q[1])
        })
        .sum::<f64>()
        / 12.0
}

/// Influence vectors ι_x, ι_y: 1 on the unknowns that translate in x (resp. y) — a
/// deformable node's u (v), a rigid block's centroid u (v) — and 0 elsewhere, rotations
/// included. The ground-motion load is −M ι a_g (docs/theory.md §5).
pub fn influence(mesh: &Mesh) -> [Vec<f64>; 2] {
    let mut iota = [vec![0.0; mesh.n_dofs], vec![0.0; mesh.n_dofs]];
    for b in &mesh.blocks {
        match b.dofs {
            BlockDofs::Fixed => {}
            BlockDofs::Rigid { first, .. } => {
                iota[0][first as usize] = 1.0;
                iota[1][first as usize + 1] = 1.0;
            }
            BlockDofs::Deformable => {
                for n in b.nodes.clone() {
                    let d = mesh.node_dofs[n as usize];
                    iota[0][d[0] as usize] = 1.0;
                    iota[1][d[1] as usize] = 1.0;
                }
            }
        }
    }
    iota
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_polar_moment() {
        // b × d about its centre: b d (b² + d²) / 12
        let (b, d) = (2.0, 3.0);
        let p = [[-1.0, -1.5], [1.0, -1.5], [1.0, 1.5], [-1.0, 1.5]];
        let want = b * d * (b * b + d * d) / 12.0;
        assert!((polar_moment(&p) - want).abs() < 1e-12);
    }
}
