//! Face-to-face contact of two convex blocks in space (docs/theory.md, "Three-dimensional
//! blocks"): where a face of one block lies on a face of the other (normals opposite,
//! planes within a gap), the contact is the intersection of the two faces, clipped one by
//! the other (Sutherland–Hodgman, exact for convex polygons); its vertices are the
//! contact points, each with its tributary area, in a frame of the normal and two tangents.

use super::polyhedron::{add3, cross3, dot3, norm3, scale3, sub3, Polyhedron, Vec3};

/// The contact of two faces lying on each other.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceContact {
    /// The unit normal, outward from the first block's face.
    pub normal: Vec3,
    /// Two unit tangents, (t₁, t₂, n) right-handed.
    pub tangents: [Vec3; 2],
    /// The contact polygon's vertices (m) on the plane midway between the two faces,
    /// counter-clockwise about `normal`.
    pub points: Vec<Vec3>,
    /// Each point's tributary area (m²): its part of the polygon's median dual (the
    /// triangles from the polygon's centroid to the midpoints of its two edges); they sum
    /// to the polygon's area, and for a parallelogram each is a quarter of it.
    pub areas: Vec<f64>,
}

impl FaceContact {
    /// The area of the contact polygon (m²).
    pub fn area(&self) -> f64 {
        self.areas.iter().sum()
    }
}

/// Two unit tangents of the unit normal `n`, (t₁, t₂, n) right-handed: t₁ ⟂ n in the
/// plane of n and the coordinate axis least aligned with it, t₂ = n × t₁.
pub fn tangent_frame(n: Vec3) -> [Vec3; 2] {
    let k = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let t1 = cross3(e, n);
    let t1 = scale3(t1, 1.0 / norm3(t1));
    [t1, cross3(n, t1)]
}

/// The contact of face `fa` of block `a` with face `fb` of block `b`: `None` unless their
/// outward normals are opposite to within `angle` (rad), every vertex of `fb` is within
/// `gap` (m) of the plane of `fa` (either side: open or overlapping), and the faces
/// overlap in an area above 10⁻¹² of the square of the smaller face's size.
pub fn face_contact(
    a: &Polyhedron,
    fa: usize,
    b: &Polyhedron,
    fb: usize,
    gap: f64,
    angle: f64,
) -> Option<FaceContact> {
    let (na, ca) = a.plane(fa);
    let (nb, _) = b.plane(fb);
    if dot3(na, nb) > -angle.cos() {
        return None;
    }
    let pb = b.face_points(fb);
    let offsets: Vec<f64> = pb.iter().map(|&v| dot3(na, sub3(v, ca))).collect();
    if offsets.iter().any(|d| d.abs() > gap) {
        return None;
    }
    let tangents = tangent_frame(na);
    let local = |v: Vec3| {
        let d = sub3(v, ca);
        [dot3(tangents[0], d), dot3(tangents[1], d)]
    };
    // a's face is counter-clockwise about na; b's about nb ≈ −na, so reversed here
    let subject: Vec<[f64; 2]> = a.face_points(fa).into_iter().map(local).collect();
    let clip: Vec<[f64; 2]> = pb.iter().rev().map(|&v| local(v)).collect();
    let polygon = clip_convex(&subject, &clip);
    let size = face_size(&subject).min(face_size(&clip));
    let area = polygon_area(&polygon);
    if polygon.len() < 3 || area <= 1e-12 * size * size {
        return None;
    }
    let areas = median_dual_areas(&polygon);
    let mid = offsets.iter().sum::<f64>() / offsets.len() as f64 / 2.0;
    let origin = add3(ca, scale3(na, mid));
    let points = polygon
        .iter()
        .map(|p| {
            add3(
                origin,
                add3(scale3(tangents[0], p[0]), scale3(tangents[1], p[1])),
            )
        })
        .collect();
    Some(FaceContact {
        normal: na,
        tangents,
        points,
        areas,
    })
}

/// Every face-to-face contact between blocks `a` and `b` ([`face_contact`] over their
/// pairs of faces), with the faces' indices.
pub fn block_face_contacts(
    a: &Polyhedron,
    b: &Polyhedron,
    gap: f64,
    angle: f64,
) -> Vec<(usize, usize, FaceContact)> {
    let mut out = Vec::new();
    for fa in 0..a.faces.len() {
        for fb in 0..b.faces.len() {
            if let Some(c) = face_contact(a, fa, b, fb, gap, angle) {
                out.push((fa, fb, c));
            }
        }
    }
    out
}

/// A face-to-face contact between two blocks of a model: the blocks' indices (a < b),
/// their faces' and the contact.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockContact {
    pub blocks: (usize, usize),
    pub faces: (usize, usize),
    pub contact: FaceContact,
}

/// Every face-to-face contact of a set of blocks: the broad phase sweeps the blocks'
/// bounding boxes, grown by `gap` (m), along x (sorted by their lowest x, each compared
/// with the boxes that start before it ends) and keeps the pairs whose boxes overlap in
/// y and z too; the narrow phase is [`block_face_contacts`]. Sorted by block pair, then
/// faces: the same list whatever the input's memory layout.
pub fn find_face_contacts(blocks: &[Polyhedron], gap: f64, angle: f64) -> Vec<BlockContact> {
    let boxes: Vec<(Vec3, Vec3)> = blocks.iter().map(|b| b.bounding_box()).collect();
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by(|&i, &j| boxes[i].0[0].total_cmp(&boxes[j].0[0]).then(i.cmp(&j)));
    let mut out = Vec::new();
    for (n, &i) in order.iter().enumerate() {
        let (lo, hi) = boxes[i];
        for &j in &order[n + 1..] {
            let (lo2, hi2) = boxes[j];
            if lo2[0] > hi[0] + gap {
                break;
            }
            if (1..3).any(|k| lo2[k] > hi[k] + gap || lo[k] > hi2[k] + gap) {
                continue;
            }
            let (a, b) = (i.min(j), i.max(j));
            for (fa, fb, contact) in block_face_contacts(&blocks[a], &blocks[b], gap, angle) {
                out.push(BlockContact {
                    blocks: (a, b),
                    faces: (fa, fb),
                    contact,
                });
            }
        }
    }
    out.sort_by(|x, y| x.blocks.cmp(&y.blocks).then(x.faces.cmp(&y.faces)));
    out
}

fn cross2(o: [f64; 2], p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
}

/// The part of the polygon `subject` inside the convex counter-clockwise polygon `clip`
/// (Sutherland–Hodgman: clipped by each edge's half-plane in turn), with vertices closer
/// than 10⁻¹² of the polygons' size merged.
pub fn clip_convex(subject: &[[f64; 2]], clip: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = subject.to_vec();
    for (k, &p) in clip.iter().enumerate() {
        let q = clip[(k + 1) % clip.len()];
        let input = std::mem::take(&mut out);
        for (i, &s) in input.iter().enumerate() {
            let e = input[(i + 1) % input.len()];
            let (ds, de) = (cross2(p, q, s), cross2(p, q, e));
            if ds >= 0.0 {
                out.push(s);
            }
            if (ds >= 0.0) != (de >= 0.0) {
                let t = ds / (ds - de);
                out.push([s[0] + t * (e[0] - s[0]), s[1] + t * (e[1] - s[1])]);
            }
        }
        if out.is_empty() {
            break;
        }
    }
    let tiny = 1e-12 * face_size(subject).max(face_size(clip));
    let mut merged: Vec<[f64; 2]> = Vec::with_capacity(out.len());
    for p in out {
        let close = |a: &[f64; 2]| (a[0] - p[0]).hypot(a[1] - p[1]) <= tiny;
        if !merged.last().is_some_and(close) {
            merged.push(p);
        }
    }
    while merged.len() > 1 && {
        let (f, l) = (merged[0], merged[merged.len() - 1]);
        (f[0] - l[0]).hypot(f[1] - l[1]) <= tiny
    } {
        merged.pop();
    }
    merged
}

/// The signed area of a plane polygon (m², positive counter-clockwise).
pub fn polygon_area(p: &[[f64; 2]]) -> f64 {
    (0..p.len())
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % p.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

/// The largest distance between two vertices' coordinates, a polygon's size (m).
fn face_size(p: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in p {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

/// Each vertex's part of a convex counter-clockwise polygon's median dual (m²): the
/// triangles (g, mₖ₋₁, vₖ) and (g, vₖ, mₖ), g the polygon's centroid and mₖ the midpoint
/// of the edge from vₖ to vₖ₊₁.
fn median_dual_areas(p: &[[f64; 2]]) -> Vec<f64> {
    let n = p.len();
    let area = polygon_area(p);
    let mut g = [0.0; 2];
    for k in 0..n {
        let (a, b) = (p[k], p[(k + 1) % n]);
        let w = a[0] * b[1] - b[0] * a[1];
        g[0] += (a[0] + b[0]) * w;
        g[1] += (a[1] + b[1]) * w;
    }
    let g = [g[0] / (6.0 * area), g[1] / (6.0 * area)];
    let mid = |k: usize| {
        let (a, b) = (p[k % n], p[(k + 1) % n]);
        [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
    };
    (0..n)
        .map(|k| {
            let before = mid(k + n - 1);
            (cross2(g, before, p[k]) + cross2(g, p[k], mid(k))) / 2.0
        })
        .collect()
}
