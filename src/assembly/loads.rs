//! Load vectors (N): gravity and lateral body forces (docs/theory.md §2: b = ρ g, lumped to the
//! nodes), and `[[load]]` forces, mapped to the unknowns through each node's map.

use crate::geometry::polygon::{dot, norm, sub, Point};
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::Scene;
use dfem_kernels::CONSTRAINED;

/// Add a force (N) at a node to `f`, through the node's map (a rigid block also gets the
/// moment about its centroid).
pub fn add_nodal_force(mesh: &Mesh, node: u32, force: Point, f: &mut [f64]) {
    let m = mesh.node_map(node);
    for k in 0..3 {
        if m.dofs[k] != CONSTRAINED {
            f[m.dofs[k] as usize] += m.g[0][k] * force[0] + m.g[1][k] * force[1];
        }
    }
}

/// Body force of acceleration `acc` (m/s²) on every free block: ρ · acc per unit volume,
/// lumped one third per triangle node (deformable) or at the centroid (rigid).
pub fn body_force(scene: &Scene, mesh: &Mesh, acc: Point) -> Vec<f64> {
    let mut f = vec![0.0; mesh.n_dofs];
    let t = scene.model.thickness;
    for (bi, b) in mesh.blocks.iter().enumerate() {
        let rho = scene.materials[scene.blocks[bi].material].density();
        match b.dofs {
            BlockDofs::Fixed => {}
            BlockDofs::Rigid { first, .. } => {
                let w = rho * b.area * t;
                f[first as usize] += w * acc[0];
                f[first as usize + 1] += w * acc[1];
            }
            BlockDofs::Deformable => {
                for ti in b.triangles.clone() {
                    let w = rho * mesh.triangle_area(ti as usize) * t / 3.0;
                    for &n in &mesh.triangles[ti as usize] {
                        add_nodal_force(mesh, n, [w * acc[0], w * acc[1]], &mut f);
                    }
                }
            }
        }
    }
    f
}

/// Gravity load (N): body force of `[model] gravity`.
pub fn gravity(scene: &Scene, mesh: &Mesh) -> Vec<f64> {
    body_force(scene, mesh, scene.model.gravity)
}

/// The `[[load]]` forces (N). A load with `along` is spread uniformly over the block's
/// boundary edges lying on that segment; otherwise like a body force (resultant at the
/// centroid).
pub fn applied(scene: &Scene, mesh: &Mesh) -> Vec<f64> {
    let mut f = vec![0.0; mesh.n_dofs];
    let tol = scene.contacts.tolerance;
    for load in &scene.loads {
        let b = &mesh.blocks[load.block];
        match load.along {
            None => match b.dofs {
                BlockDofs::Fixed => {}
                BlockDofs::Rigid { first, .. } => {
                    f[first as usize] += load.force[0];
                    f[first as usize + 1] += load.force[1];
                }
                BlockDofs::Deformable => {
                    for ti in b.triangles.clone() {
                        let w = mesh.triangle_area(ti as usize) / b.area / 3.0;
                        for &n in &mesh.triangles[ti as usize] {
                            add_nodal_force(
                                mesh,
                                n,
                                [w * load.force[0], w * load.force[1]],
                                &mut f,
                            );
                        }
                    }
                }
            },
            Some([s0, s1]) => {
                let edges = edges_on_segment(mesh, load.block, s0, s1, tol);
                let total: f64 = edges.iter().map(|e| e.2).sum();
                for (n0, n1, len) in edges {
                    let w = 0.5 * len / total;
                    add_nodal_force(mesh, n0, [w * load.force[0], w * load.force[1]], &mut f);
                    add_nodal_force(mesh, n1, [w * load.force[0], w * load.force[1]], &mut f);
                }
            }
        }
    }
    f
}

/// Boundary edges (node, node, length) of a block lying on the segment s0–s1.
pub fn edges_on_segment(
    mesh: &Mesh,
    block: usize,
    s0: Point,
    s1: Point,
    tol: f64,
) -> Vec<(u32, u32, f64)> {
    let b = &mesh.blocks[block];
    let d = sub(s1, s0);
    let l = norm(d);
    let t = [d[0] / l, d[1] / l];
    let on = |p: Point| {
        let r = sub(p, s0);
        let x = dot(r, t);
        (r[0] * t[1] - r[1] * t[0]).abs() <= tol && x >= -tol && x <= l + tol
    };
    let nb = b.boundary.len();
    let mut out = Vec::new();
    for k in 0..nb {
        let (n0, n1) = (b.boundary[k], b.boundary[(k + 1) % nb]);
        let (p0, p1) = (mesh.nodes[n0 as usize], mesh.nodes[n1 as usize]);
        if on(p0) && on(p1) {
            out.push((n0, n1, norm(sub(p1, p0))));
        }
    }
    out
}
