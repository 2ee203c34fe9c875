//! Mesh: nodes, constant-strain triangles, rigid-block degrees of freedom and contact
//! elements (docs/theory.md §1–3).
//!
//! Every block's boundary holds its corners plus the *contact nodes*: the projections of
//! the neighbours' corners onto each shared edge (and, with a `mesh_size`, the points that
//! subdivide edges, placed on both sides of a joint so that contacts stay node to node).
//! A deformable block is triangulated (constrained Delaunay, `spade`); a rigid block gets
//! three degrees of freedom (u, v, θ) at its centroid and its nodes follow it rigidly; a
//! fixed block has no unknowns. The contact elements, found along the joints here and
//! again while the blocks move: [`contacts`].

pub mod contacts;
pub mod triangulate;

pub use contacts::Contact;

use crate::geometry::polygon::{centroid, dot, norm, signed_area, sub, Point};
use crate::geometry::JointSegment;
use crate::scene::{BlockKind, Scene, Support};
use dfem_kernels::CONSTRAINED;

/// How a block's nodes are tied to the unknowns.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum BlockDofs {
    /// No unknowns: the block does not move (or moves as prescribed).
    Fixed,
    /// Three unknowns (u, v, θ), starting at `first`, at `centroid`.
    Rigid { first: u32, centroid: Point },
    /// Two unknowns (u, v) per node.
    Deformable,
}

/// A block in the mesh.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct MeshBlock {
    /// Boundary nodes, counter-clockwise (corners and contact nodes).
    pub boundary: Vec<u32>,
    /// All nodes of the block (boundary first, then interior), as a range of node ids.
    pub nodes: std::ops::Range<u32>,
    /// Its triangles, as a range of triangle ids (empty for rigid and fixed blocks).
    pub triangles: std::ops::Range<u32>,
    pub dofs: BlockDofs,
    /// Area (m²) and centroid (m) of the block polygon.
    pub area: f64,
    pub centroid: Point,
}

/// The mesh of a scene.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Mesh {
    /// Node positions (m).
    pub nodes: Vec<Point>,
    /// Owning block of each node.
    pub node_block: Vec<u32>,
    /// Unknowns of each node for a deformable block; `[CONSTRAINED; 2]` otherwise.
    pub node_dofs: Vec<[u32; 2]>,
    /// Triangles (node ids, counter-clockwise).
    pub triangles: Vec<[u32; 3]>,
    pub tri_block: Vec<u32>,
    pub blocks: Vec<MeshBlock>,
    pub segments: Vec<JointSegment>,
    pub contacts: Vec<Contact>,
    pub n_dofs: usize,
}

/// The unknowns a node's displacement depends on: `u_node = G · u[dofs]` with
/// `G = [[1, 0, −(y − y_c)], [0, 1, x − x_c]]` for rigid blocks and the identity for
/// deformable ones. Slots that are not unknowns hold `CONSTRAINED`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeMap {
    pub dofs: [u32; 3],
    pub g: [[f64; 3]; 2],
}

/// The unknowns a contact point depends on: a node's [`NodeMap`] (3 slots), or the
/// combination (1 − w) G_a + w G_b of an edge's two ends (3 slots when both ends follow
/// the same rigid block, 6 otherwise). `u_point = g · u[dofs[..len]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMap {
    pub dofs: [u32; 6],
    pub g: [[f64; 6]; 2],
    pub len: usize,
}

impl PointMap {
    fn weighted(parts: &[(NodeMap, f64)]) -> PointMap {
        let mut m = PointMap {
            dofs: [CONSTRAINED; 6],
            g: [[0.0; 6]; 2],
            len: 0,
        };
        for (nm, w) in parts {
            // the same unknowns as the part before (a rigid block): add into its slots
            let base = if m.len >= 3 && m.dofs[m.len - 3..m.len] == nm.dofs {
                m.len - 3
            } else {
                m.len += 3;
                m.len - 3
            };
            for k in 0..3 {
                m.dofs[base + k] = nm.dofs[k];
                for i in 0..2 {
                    m.g[i][base + k] += w * nm.g[i][k];
                }
            }
        }
        m
    }
}

impl Mesh {
    /// The unknowns of block `b` (m, rad): a rigid block's three, a deformable block's
    /// nodes' two each (those not constrained), none for a fixed block.
    pub fn block_unknowns(&self, b: usize) -> Vec<usize> {
        let blk = &self.blocks[b];
        match blk.dofs {
            BlockDofs::Rigid { first, .. } => (first as usize..first as usize + 3).collect(),
            BlockDofs::Deformable => blk
                .nodes
                .clone()
                .flat_map(|n| self.node_dofs[n as usize])
                .filter(|&d| d != CONSTRAINED)
                .map(|d| d as usize)
                .collect(),
            BlockDofs::Fixed => Vec::new(),
        }
    }

    /// The maps of a contact's two points (l side, m side).
    pub fn contact_maps(&self, c: &Contact) -> (PointMap, PointMap) {
        let l = match c.along {
            None => PointMap::weighted(&[(self.node_map(c.node_l), 1.0)]),
            Some(_) => {
                let [(a, wa), (b, wb)] = c.l_points();
                PointMap::weighted(&[(self.node_map(a), wa), (self.node_map(b), wb)])
            }
        };
        (l, PointMap::weighted(&[(self.node_map(c.node_m), 1.0)]))
    }

    pub fn node_map(&self, node: u32) -> NodeMap {
        let b = &self.blocks[self.node_block[node as usize] as usize];
        match b.dofs {
            BlockDofs::Fixed => NodeMap {
                dofs: [CONSTRAINED; 3],
                g: [[0.0; 3]; 2],
            },
            BlockDofs::Deformable => {
                let d = self.node_dofs[node as usize];
                NodeMap {
                    dofs: [d[0], d[1], CONSTRAINED],
                    g: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                }
            }
            BlockDofs::Rigid { first, centroid } => {
                let p = self.nodes[node as usize];
                NodeMap {
                    dofs: [first, first + 1, first + 2],
                    g: [
                        [1.0, 0.0, -(p[1] - centroid[1])],
                        [0.0, 1.0, p[0] - centroid[0]],
                    ],
                }
            }
        }
    }

    /// Displacement (m) of a node for the unknowns `u`.
    pub fn node_displacement(&self, node: u32, u: &[f64]) -> Point {
        let m = self.node_map(node);
        let mut d = [0.0; 2];
        for (k, &dof) in m.dofs.iter().enumerate() {
            if dof != CONSTRAINED {
                d[0] += m.g[0][k] * u[dof as usize];
                d[1] += m.g[1][k] * u[dof as usize];
            }
        }
        d
    }

    /// Recompute every contact's normal from the current positions of its edge's corners
    /// (updated Lagrangian geometry, docs/theory.md §3: the angle of n comes from the edge).
    pub fn update_normals(&mut self) {
        for c in &mut self.contacts {
            let (a, b) = (
                self.nodes[c.edge_l[0] as usize],
                self.nodes[c.edge_l[1] as usize],
            );
            let d = sub(b, a);
            let l = norm(d);
            c.normal = [d[1] / l, -d[0] / l];
        }
    }

    /// Area (m²) of a triangle from the current node positions.
    pub fn triangle_area(&self, t: usize) -> f64 {
        let [i, j, k] = self.triangles[t];
        signed_area(&[
            self.nodes[i as usize],
            self.nodes[j as usize],
            self.nodes[k as usize],
        ])
    }
}

/// Build the mesh of a validated scene.
pub fn build(scene: &Scene) -> Mesh {
    let tol = scene.contacts.tolerance;
    let polys: Vec<Vec<Point>> = scene.blocks.iter().map(|b| b.vertices.clone()).collect();
    // 1. Where the blocks touch: the joint segments and the points along them
    let (segments, seg_points) = contacts::joints(scene, &polys, tol);

    // 2. Boundary points of each block, edge by edge: corners, joint points, and
    //    subdivision of the free stretches.
    let mut edge_points: Vec<Vec<Vec<f64>>> =
        polys.iter().map(|v| vec![Vec::new(); v.len()]).collect();
    let mut edge_cover: Vec<Vec<Vec<(f64, f64)>>> =
        polys.iter().map(|v| vec![Vec::new(); v.len()]).collect();
    for (s, pts) in segments.iter().zip(&seg_points) {
        for (blk, edge) in [(s.a, s.edge_a), (s.b, s.edge_b)] {
            let v = &polys[blk];
            let e0 = v[edge];
            let e1 = v[(edge + 1) % v.len()];
            let le = norm(sub(e1, e0));
            let te = [(e1[0] - e0[0]) / le, (e1[1] - e0[1]) / le];
            let along = |x: f64| -> f64 {
                let p = contacts::seg_point(s, x);
                dot(sub(p, e0), te)
            };
            let (c0, c1) = (along(0.0), along(s.length()));
            edge_cover[blk][edge].push((c0.min(c1), c0.max(c1)));
            for &x in pts {
                edge_points[blk][edge].push(along(x));
            }
        }
    }

    let mut mesh = Mesh {
        nodes: Vec::new(),
        node_block: Vec::new(),
        node_dofs: Vec::new(),
        triangles: Vec::new(),
        tri_block: Vec::new(),
        blocks: Vec::with_capacity(polys.len()),
        segments: Vec::new(),
        contacts: Vec::new(),
        n_dofs: 0,
    };
    // boundary positions (edge, distance along the edge) → node id, per block
    let mut boundary_keys: Vec<Vec<(usize, f64)>> = Vec::with_capacity(polys.len());
    for (bi, v) in polys.iter().enumerate() {
        let blk = &scene.blocks[bi];
        let h = blk.mesh_size;
        let mut ring: Vec<Point> = Vec::new();
        let mut keys: Vec<(usize, f64)> = Vec::new();
        for e in 0..v.len() {
            let e0 = v[e];
            let e1 = v[(e + 1) % v.len()];
            let le = norm(sub(e1, e0));
            let mut pts: Vec<f64> = vec![0.0, le];
            pts.extend(
                edge_points[bi][e]
                    .iter()
                    .copied()
                    .filter(|&x| x > tol && x < le - tol),
            );
            pts.sort_by(f64::total_cmp);
            pts.dedup_by(|a, b| (*a - *b).abs() <= tol);
            if let Some(h) = h {
                // subdivide only the stretches not covered by a joint
                let cover = &edge_cover[bi][e];
                let mut out = vec![pts[0]];
                for w in pts.windows(2) {
                    let mid = 0.5 * (w[0] + w[1]);
                    let covered = cover.iter().any(|&(lo, hi)| mid > lo && mid < hi);
                    if !covered {
                        let n = ((w[1] - w[0]) / h).ceil().max(1.0) as usize;
                        for k in 1..n {
                            out.push(w[0] + (w[1] - w[0]) * k as f64 / n as f64);
                        }
                    }
                    out.push(w[1]);
                }
                pts = out;
            }
            for &x in &pts[..pts.len() - 1] {
                let p = if x == 0.0 {
                    e0
                } else {
                    [
                        e0[0] + (e1[0] - e0[0]) * x / le,
                        e0[1] + (e1[1] - e0[1]) * x / le,
                    ]
                };
                ring.push(p);
                keys.push((e, x));
            }
        }
        let first_node = mesh.nodes.len() as u32;
        let boundary: Vec<u32> = (0..ring.len() as u32).map(|k| first_node + k).collect();
        mesh.nodes.extend_from_slice(&ring);
        let area = signed_area(v);
        let c = centroid(v);
        let first_tri = mesh.triangles.len() as u32;
        let dofs = match (blk.support, blk.kind) {
            (Support::Fixed, _) => BlockDofs::Fixed,
            (Support::Free, BlockKind::Rigid) => {
                let first = mesh.n_dofs as u32;
                mesh.n_dofs += 3;
                BlockDofs::Rigid { first, centroid: c }
            }
            (Support::Free, BlockKind::Deformable) => {
                let (interior, tris) = triangulate::triangulate(&ring, h);
                mesh.nodes.extend_from_slice(&interior);
                for t in tris {
                    mesh.triangles
                        .push([t[0] + first_node, t[1] + first_node, t[2] + first_node]);
                }
                BlockDofs::Deformable
            }
        };
        let last_node = mesh.nodes.len() as u32;
        for _ in first_node..last_node {
            mesh.node_block.push(bi as u32);
            if dofs == BlockDofs::Deformable {
                let d = mesh.n_dofs as u32;
                mesh.node_dofs.push([d, d + 1]);
                mesh.n_dofs += 2;
            } else {
                mesh.node_dofs.push([CONSTRAINED; 2]);
            }
        }
        let last_tri = mesh.triangles.len() as u32;
        mesh.tri_block.resize(last_tri as usize, bi as u32);
        mesh.blocks.push(MeshBlock {
            boundary,
            nodes: first_node..last_node,
            triangles: first_tri..last_tri,
            dofs,
            area,
            centroid: c,
        });
        boundary_keys.push(keys);
    }

    // 3. Contact elements: one per point of each joint segment
    mesh.contacts = contacts::along_joints(&mesh, &polys, &boundary_keys, &segments, &seg_points);
    mesh.segments = segments;
    mesh
}
