//! Contact elements: where the blocks touch (docs/theory.md §3), found along the joints
//! of the scene when the mesh is built, and again in the current geometry while the
//! blocks move (docs/theory.md §5). One module for both, so that the elements found during a
//! run are of the same kind and follow the same rules as the initial ones.
//!
//! **Along the joints** (`joints`, `along_joints`, for [`super::build`]): the joint
//! segments where two blocks' edges overlap within the contact tolerance
//! ([`crate::geometry::find_joints`]), and one node-to-node contact per point along them.
//!
//! **In large motion** ([`search`], [`kept`], for the dynamic driver): "falling blocks
//! must find new contacts (broad phase + narrow phase detection) rather than pass through
//! each other" (docs/theory.md §5).
//!
//! Between time steps, in the current (updated Lagrangian) geometry:
//! * **broad phase**: the blocks' bounding boxes grown by the reach `r` (m) go into the
//!   R-tree of [`candidate_pairs`] (bulk loading O(n log n), each query O(log n + k)), so
//!   only blocks whose boxes come within `r` of each other are examined;
//! * **narrow phase**: every boundary node (vertex) of one block against every boundary
//!   segment of the other, both ways: a vertex whose signed distance `d` to a segment's
//!   line is within `[−r, r]`, whose projection falls on the segment, and which approaches
//!   (relative normal velocity < 0) or is already within the band, is a new
//!   vertex-to-edge contact ([`Contact::along`]) unless a contact between the same two
//!   blocks already sits within the band of it. A vertex on an end of a segment with no
//!   side of its own along the segment is a corner on a corner and not taken on that
//!   segment (where joints cross, the blocks diagonal to each other touch only there).
//!   A block landing flat on an edge gets contacts at the vertices of the common
//!   stretch, so the edge-to-edge case of
//!   [`crate::geometry::joints::touching`] is the union of vertex-to-edge cases.
//!
//! Tributary length (the contact area is length × thickness, docs/theory.md §3): half of each
//! boundary segment adjoining the vertex that lies along the edge (its far end no more
//! than `r` nearer to or farther from the edge's line than the vertex), clipped to the edge, as docs/theory.md §3 takes "half of each adjoining
//! segment"; a corner that meets an edge at an angle has no such segment and gets the
//! band thickness `h`, the width over which a corner indents a band of thickness h
//! (kₙ = Eₙ t, independent of h). See docs/theory.md, "New contacts".
//!
//! The reach is `r = h + 2 v_max Δt`: a vertex moving at the largest node speed v_max
//! is found at least one step before it reaches the edge. An open contact whose normal
//! gap exceeds `max(10 h, 2 r, 0.1 × the smaller block's size)` is dropped, and so is a
//! contact whose m node has slid past the end of its edge of block l.

use super::{BlockDofs, Mesh};
use crate::geometry::joints::candidate_pairs;
use crate::geometry::polygon::{bbox, contains, dot, norm, sub, Point};
use crate::geometry::{find_joints, JointSegment};
use crate::scene::Scene;
use std::collections::HashMap;

/// A node-to-node contact element (docs/theory.md §3).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Contact {
    /// Node `l` on block `block_l`, node `m` on block `block_m`, at the same position.
    pub node_l: u32,
    pub node_m: u32,
    pub block_l: u32,
    pub block_m: u32,
    /// Unit normal from block l into block m, from the edge geometry.
    pub normal: Point,
    /// The corner nodes of block l's edge that carries the contact (start, end, counter-
    /// clockwise): the normal follows them when the geometry is updated.
    pub edge_l: [u32; 2],
    /// Tributary length along the joint (m); the contact area is `length × thickness`.
    pub length: f64,
    /// Index of the joint segment it belongs to (`u32::MAX` for a contact found during a
    /// dynamic run).
    pub segment: u32,
    /// A vertex-to-edge contact found during a large motion (docs/theory.md §5): the l side is
    /// the point at this fraction (0 to 1) along `edge_l` (two consecutive boundary nodes
    /// of block l), not a node; `node_l` is then the nearer end of that edge.
    pub along: Option<f64>,
}

impl Contact {
    /// The nodes and weights whose combination is the contact's point on block l:
    /// `node_l` alone, or the two ends of `edge_l` for a vertex-to-edge contact.
    pub fn l_points(&self) -> [(u32, f64); 2] {
        match self.along {
            None => [(self.node_l, 1.0), (self.node_l, 0.0)],
            Some(w) => [(self.edge_l[0], 1.0 - w), (self.edge_l[1], w)],
        }
    }

    /// The contact's point on block l from per-node values (positions, displacements).
    pub fn at_l(&self, value: impl Fn(u32) -> Point) -> Point {
        let mut p = [0.0; 2];
        for (n, w) in self.l_points() {
            if w != 0.0 {
                let v = value(n);
                p[0] += w * v[0];
                p[1] += w * v[1];
            }
        }
        p
    }
}

/// Where the blocks `polys` touch (within `tol`): their joint segments, and along each
/// the points (m from its start) that get a contact: the corners of both blocks that lie
/// on it, plus subdivision points when either block asks for a mesh size. The mesh puts
/// boundary nodes of both blocks at these points ([`super::build`]).
pub(super) fn joints(
    scene: &Scene,
    polys: &[Vec<Point>],
    tol: f64,
) -> (Vec<JointSegment>, Vec<Vec<f64>>) {
    let segments = find_joints(polys, tol);
    let seg_points: Vec<Vec<f64>> = segments
        .iter()
        .map(|s| {
            let len = s.length();
            let t = [(s.p1[0] - s.p0[0]) / len, (s.p1[1] - s.p0[1]) / len];
            let mut pts = vec![0.0, len];
            for (blk, edge) in [(s.a, s.edge_a), (s.b, s.edge_b)] {
                let v = &polys[blk];
                for p in [v[edge], v[(edge + 1) % v.len()]] {
                    let x = dot(sub(p, s.p0), t);
                    if x > tol && x < len - tol {
                        pts.push(x);
                    }
                }
            }
            pts.sort_by(f64::total_cmp);
            pts.dedup_by(|a, b| (*a - *b).abs() <= tol);
            let h = mesh_size(scene, s.a, s.b);
            if let Some(h) = h {
                subdivide(&mut pts, h);
            }
            pts
        })
        .collect();
    (segments, seg_points)
}

/// The node-to-node contact elements of the joints (`joints`): one at each point of a
/// joint segment, between the boundary nodes of its two blocks there, with its tributary
/// length (half the distance to each neighbouring point). `keys`: per block, the edge
/// and the distance along it of each boundary node.
pub(super) fn along_joints(
    mesh: &Mesh,
    polys: &[Vec<Point>],
    keys: &[Vec<(usize, f64)>],
    segments: &[JointSegment],
    seg_points: &[Vec<f64>],
) -> Vec<Contact> {
    let mut contacts = Vec::new();
    for (si, (s, pts)) in segments.iter().zip(seg_points).enumerate() {
        let n = pts.len();
        for k in 0..n {
            let lo = if k == 0 {
                pts[0]
            } else {
                0.5 * (pts[k - 1] + pts[k])
            };
            let hi = if k + 1 == n {
                pts[n - 1]
            } else {
                0.5 * (pts[k] + pts[k + 1])
            };
            let p = seg_point(s, pts[k]);
            let node_l = find_boundary_node(mesh, polys, keys, s.a, s.edge_a, p);
            let node_m = find_boundary_node(mesh, polys, keys, s.b, s.edge_b, p);
            let corner = |v: usize| -> u32 {
                let k = keys[s.a]
                    .iter()
                    .position(|&(e, x)| e == v && x == 0.0)
                    .expect("corner node");
                mesh.blocks[s.a].boundary[k]
            };
            let edge_l = [corner(s.edge_a), corner((s.edge_a + 1) % polys[s.a].len())];
            contacts.push(Contact {
                node_l,
                node_m,
                block_l: s.a as u32,
                block_m: s.b as u32,
                normal: s.normal,
                edge_l,
                length: hi - lo,
                segment: si as u32,
                along: None,
            });
        }
    }
    contacts
}

/// The mesh size along a joint between blocks `a` and `b`: the smaller one asked for.
fn mesh_size(scene: &Scene, a: usize, b: usize) -> Option<f64> {
    match (scene.blocks[a].mesh_size, scene.blocks[b].mesh_size) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}

/// Insert equally spaced points so that no gap exceeds `h`.
fn subdivide(pts: &mut Vec<f64>, h: f64) {
    let mut out = vec![pts[0]];
    for w in pts.windows(2) {
        let n = ((w[1] - w[0]) / h).ceil().max(1.0) as usize;
        for k in 1..n {
            out.push(w[0] + (w[1] - w[0]) * k as f64 / n as f64);
        }
        out.push(w[1]);
    }
    *pts = out;
}

/// The point at distance `x` (m) along joint segment `s`.
pub(super) fn seg_point(s: &JointSegment, x: f64) -> Point {
    let len = s.length();
    [
        s.p0[0] + (s.p1[0] - s.p0[0]) * x / len,
        s.p0[1] + (s.p1[1] - s.p0[1]) * x / len,
    ]
}

/// The boundary node of block `blk` nearest to `p` on edge `edge` (or at its ends).
fn find_boundary_node(
    mesh: &Mesh,
    polys: &[Vec<Point>],
    keys: &[Vec<(usize, f64)>],
    blk: usize,
    edge: usize,
    p: Point,
) -> u32 {
    let b = &mesh.blocks[blk];
    let nv = polys[blk].len();
    let next = (edge + 1) % nv;
    let mut best = (f64::INFINITY, b.boundary[0]);
    for (k, &(e, _)) in keys[blk].iter().enumerate() {
        // nodes on this edge, plus the corner that ends it (first node of the next edge)
        let on_edge = e == edge || (e == next && keys[blk][k].1 == 0.0);
        if !on_edge {
            continue;
        }
        let node = b.boundary[k];
        let d = norm(sub(mesh.nodes[node as usize], p));
        if d < best.0 {
            best = (d, node);
        }
    }
    best.1
}

/// A vertex-to-edge contact found, with its signed gap (m, > 0 open).
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    pub contact: Contact,
    pub gap: f64,
}

/// The boundary of every block in the current geometry (counter-clockwise).
pub fn boundaries(mesh: &Mesh) -> Vec<Vec<Point>> {
    mesh.blocks
        .iter()
        .map(|b| b.boundary.iter().map(|&n| mesh.nodes[n as usize]).collect())
        .collect()
}

/// Bounding-box diagonal (m) of each block.
fn sizes(polys: &[Vec<Point>]) -> Vec<f64> {
    polys
        .iter()
        .map(|p| {
            let b = bbox(p);
            (b[2] - b[0]).hypot(b[3] - b[1])
        })
        .collect()
}

/// Normal gap (m) of a contact in the current geometry: n · (x_m − x_l).
pub fn gap(mesh: &Mesh, c: &Contact) -> f64 {
    let xl = c.at_l(|n| mesh.nodes[n as usize]);
    dot(sub(mesh.nodes[c.node_m as usize], xl), c.normal)
}

/// Position of a contact's m node along its edge of block l: the fraction of the edge
/// (0 to 1 on it).
pub fn along_edge(mesh: &Mesh, c: &Contact) -> f64 {
    let (a, b) = (
        mesh.nodes[c.edge_l[0] as usize],
        mesh.nodes[c.edge_l[1] as usize],
    );
    let e = sub(b, a);
    dot(sub(mesh.nodes[c.node_m as usize], a), e) / dot(e, e)
}

/// Which contacts to keep: all but the open ones (`open[k]`: contact k is open)
/// separated far beyond the band, and those whose m node has slid off the end of its edge
/// of block l by more than the band (a node-to-node contact holds only while its node is
/// over the edge; past it the edge's line would hold the node up where there is no block:
/// the search finds the node again on the edge it meets next).
pub fn kept(mesh: &Mesh, open: &[bool], band: f64, reach: f64) -> Vec<bool> {
    let polys = boundaries(mesh);
    let size = sizes(&polys);
    mesh.contacts
        .iter()
        .zip(open)
        .map(|(c, &open)| {
            let small = size[c.block_l as usize].min(size[c.block_m as usize]);
            let far = (10.0 * band).max(2.0 * reach).max(0.1 * small);
            let (a, b) = (
                mesh.nodes[c.edge_l[0] as usize],
                mesh.nodes[c.edge_l[1] as usize],
            );
            let slack = band / norm(sub(b, a));
            let w = along_edge(mesh, c);
            (!open || gap(mesh, c) <= far) && w >= -slack && w <= 1.0 + slack
        })
        .collect()
}

/// Tributary length (m) of vertex `v` of polygon `p` on the edge from `a` along the unit
/// tangent `t` (length `len`, unit normal `n`): half of each adjoining segment lying
/// along the edge (parallel to it within `reach` over its length), clipped to the edge;
/// `band` for a lone corner.
pub fn tributary(
    p: &[Point],
    v: usize,
    edge: (Point, Point, Point, f64),
    reach: f64,
    band: f64,
) -> f64 {
    let l = along_length(p, v, edge, reach);
    if l > 0.0 {
        l
    } else {
        band
    }
}

/// The part of [`tributary`] that the sides adjoining vertex `v` give (m): half of each
/// that lies along the edge, clipped to it; zero for a lone corner.
fn along_length(p: &[Point], v: usize, edge: (Point, Point, Point, f64), reach: f64) -> f64 {
    let (a, t, n, len) = edge;
    let m = p.len();
    let x = p[v];
    let sx = dot(sub(x, a), t);
    let dx = dot(sub(x, a), n);
    let mut l = 0.0;
    for q in [p[(v + m - 1) % m], p[(v + 1) % m]] {
        if (dot(sub(q, a), n) - dx).abs() > reach {
            continue;
        }
        let sq = dot(sub(q, a), t);
        let (lo, hi) = (sx.min(sq).max(0.0), sx.max(sq).min(len));
        if hi > lo && (sq - sx).abs() > 0.0 {
            l += 0.5 * (hi - lo) * norm(sub(q, x)) / (sq - sx).abs();
        }
    }
    l
}

/// The new vertex-to-edge contacts of the current geometry (see the module
/// documentation). `vel`: every node's velocity (m/s); `band`: h (m); `reach`: r (m).
pub fn search(mesh: &Mesh, vel: &[Point], band: f64, reach: f64) -> Vec<Found> {
    let polys = boundaries(mesh);
    let fixed = |b: usize| mesh.blocks[b].dofs == BlockDofs::Fixed;
    let pairs = candidate_pairs(&polys, reach);
    // the contacts of each pair of blocks, in one pass (a scan of every contact for each
    // pair made the search quadratic: 30 % of a dynamic run of a 900-block wall)
    let mut of_pair: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (k, c) in mesh.contacts.iter().enumerate() {
        let key = (c.block_l.min(c.block_m), c.block_l.max(c.block_m));
        of_pair.entry(key).or_default().push(k);
    }
    let mut found: Vec<Found> = Vec::new();
    for (i, j) in pairs {
        if fixed(i) && fixed(j) {
            continue;
        }
        // points already in contact between these two blocks (m side's node positions)
        let key = (i.min(j) as u32, i.max(j) as u32);
        let mut taken: Vec<Point> = of_pair
            .get(&key)
            .into_iter()
            .flatten()
            .map(|&k| &mesh.contacts[k])
            .flat_map(|c| {
                [
                    mesh.nodes[c.node_m as usize],
                    c.at_l(|n| mesh.nodes[n as usize]),
                ]
            })
            .collect();
        for (bm, bl) in [(i, j), (j, i)] {
            let (pm, pl) = (&polys[bm], &polys[bl]);
            let nl = pl.len();
            for (v, &x) in pm.iter().enumerate() {
                if taken.iter().any(|&y| norm(sub(x, y)) <= band) {
                    continue;
                }
                // the nearest segment of block l in front of the vertex
                let mut best: Option<(f64, usize, f64)> = None;
                for e in 0..nl {
                    let (a, b) = (pl[e], pl[(e + 1) % nl]);
                    let len = norm(sub(b, a));
                    if len == 0.0 {
                        continue;
                    }
                    let t = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
                    let n = [t[1], -t[0]];
                    let d = dot(sub(x, a), n);
                    let s = dot(sub(x, a), t);
                    if d.abs() > reach || s < -band || s > len + band {
                        continue;
                    }
                    // a corner on an end of the edge with no side of its own along it
                    // is a corner on a corner: not a contact with this edge. Where joints
                    // cross, the blocks diagonal to each other touch at the crossing
                    // only, and their neighbours' contacts already hold them apart; a
                    // contact there would have no tributary length (its sides run off
                    // the edge's end) or a lone corner's h, and the normal of whichever
                    // edge came nearest (the `tunnel` example under El Centro: 184 such
                    // contacts at the first step, opening and closing as the rock
                    // shook). A corner landing square on a block of its width is found
                    // on the edge its side lies along, not on the block's side whose
                    // line it also touches
                    if (norm(sub(x, a)) <= band || norm(sub(x, b)) <= band)
                        && along_length(pm, v, (a, t, n, len), reach) < band
                    {
                        continue;
                    }
                    if best.is_none_or(|(bd, _, _)| d.abs() < bd.abs()) {
                        best = Some((d, e, (s / len).clamp(0.0, 1.0)));
                    }
                }
                let Some((d, e, w)) = best else { continue };
                // behind the edge's line by more than the band: a contact only where the
                // vertex is inside block l (an overlap to push out), not where it lies
                // beyond the block's far side (a large reach reaches through thin blocks)
                if d < -band && !contains(pl, x) {
                    continue;
                }
                let (na, nb) = (
                    mesh.blocks[bl].boundary[e],
                    mesh.blocks[bl].boundary[(e + 1) % nl],
                );
                let (a, b) = (pl[e], pl[(e + 1) % nl]);
                let len = norm(sub(b, a));
                let t = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
                let n = [t[1], -t[0]];
                let node_m = mesh.blocks[bm].boundary[v];
                let vl = [
                    (1.0 - w) * vel[na as usize][0] + w * vel[nb as usize][0],
                    (1.0 - w) * vel[na as usize][1] + w * vel[nb as usize][1],
                ];
                let approach = dot(sub(vel[node_m as usize], vl), n);
                if d > band && approach >= 0.0 {
                    continue;
                }
                let length = tributary(pm, v, (a, t, n, len), reach, band);
                found.push(Found {
                    contact: Contact {
                        node_l: if w < 0.5 { na } else { nb },
                        node_m,
                        block_l: bl as u32,
                        block_m: bm as u32,
                        normal: n,
                        edge_l: [na, nb],
                        length,
                        segment: u32::MAX,
                        along: Some(w),
                    },
                    gap: d,
                });
                taken.push(x);
            }
        }
    }
    found
}

/// The current tributary length (m) of a vertex-to-edge contact (see [`tributary`]).
pub fn current_length(mesh: &Mesh, c: &Contact, band: f64, reach: f64) -> f64 {
    let bm = &mesh.blocks[c.block_m as usize];
    let p: Vec<Point> = bm
        .boundary
        .iter()
        .map(|&n| mesh.nodes[n as usize])
        .collect();
    let Some(v) = bm.boundary.iter().position(|&n| n == c.node_m) else {
        return c.length;
    };
    let (a, b) = (
        mesh.nodes[c.edge_l[0] as usize],
        mesh.nodes[c.edge_l[1] as usize],
    );
    let len = norm(sub(b, a));
    let t = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
    tributary(&p, v, (a, t, c.normal, len), reach, band)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tributary_of_a_flat_side_and_of_a_corner() {
        // a 2 m wide box 1 mm above a 10 m edge: each bottom corner takes half its side
        let p = [[0.0, 0.001], [2.0, 0.001], [2.0, 1.0], [0.0, 1.0]];
        let edge = ([-5.0, 0.0], [1.0, 0.0], [0.0, 1.0], 10.0);
        assert!((tributary(&p, 0, edge, 0.01, 0.005) - 1.0).abs() < 1e-12);
        assert!((tributary(&p, 1, edge, 0.01, 0.005) - 1.0).abs() < 1e-12);
        // the same box over an edge that ends under its middle: the corner over the
        // edge takes half of the part of its side over the edge
        let short = ([-5.0, 0.0], [1.0, 0.0], [0.0, 1.0], 6.0);
        assert!((tributary(&p, 0, short, 0.01, 0.005) - 0.5).abs() < 1e-12);
        // tilted by 0.1 rad about its corner: a lone corner, the band thickness
        let (s, c) = 0.1f64.sin_cos();
        let q: Vec<Point> = p
            .iter()
            .map(|x| [c * x[0] - s * x[1], s * x[0] + c * x[1]])
            .collect();
        assert_eq!(tributary(&q, 0, edge, 0.01, 0.005), 0.005);
    }

    /// The broad phase passes on only the blocks that come within the reach of each
    /// other: a row of 2000 blocks 0.5 m apart gives no pair for a 0.1 m reach, and the
    /// 1999 neighbour pairs for a 0.3 m reach (each box grown by it; none of the 2 million
    /// other pairs).
    #[test]
    fn broad_phase_pairs_only_neighbours() {
        let polys: Vec<Vec<Point>> = (0..2000)
            .map(|i| {
                let x = 1.5 * i as f64;
                vec![[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]]
            })
            .collect();
        assert!(candidate_pairs(&polys, 0.1).is_empty());
        let pairs = candidate_pairs(&polys, 0.3);
        assert_eq!(pairs.len(), 1999);
        assert!(pairs.iter().all(|&(i, j)| j == i + 1));
    }
}
