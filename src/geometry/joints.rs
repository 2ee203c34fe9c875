//! Touching edges between blocks (docs/theory.md §1: contacts are generated from the
//! geometry, never typed by hand). A broad phase on an R-tree of bounding boxes finds the
//! candidate pairs; the narrow phase finds antiparallel, collinear edge pairs within the
//! tolerance and their common stretch: a [`JointSegment`].

use super::polygon::{bbox, dot, norm, overlap_area, sub, Point};
use rayon::prelude::*;
use rstar::{RTree, RTreeObject, AABB};

/// A stretch of boundary shared by two blocks.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointSegment {
    /// Block indices, `a < b`.
    pub a: usize,
    pub b: usize,
    /// Edge indices (edge k joins vertex k to vertex k+1).
    pub edge_a: usize,
    pub edge_b: usize,
    /// Ends of the common stretch, in the direction of block a's edge (m).
    pub p0: Point,
    pub p1: Point,
    /// Unit normal pointing from block a into block b (a's outward normal).
    pub normal: Point,
}

impl JointSegment {
    pub fn length(&self) -> f64 {
        norm(sub(self.p1, self.p0))
    }
}

struct Boxed {
    index: usize,
    env: AABB<[f64; 2]>,
}

impl RTreeObject for Boxed {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        self.env
    }
}

/// Pairs `(i, j)`, `i < j`, whose bounding boxes, grown by `tol`, intersect. Sorted.
pub fn candidate_pairs(polys: &[Vec<Point>], tol: f64) -> Vec<(usize, usize)> {
    let boxes: Vec<Boxed> = polys
        .iter()
        .enumerate()
        .map(|(index, v)| {
            let b = bbox(v);
            Boxed {
                index,
                env: AABB::from_corners([b[0] - tol, b[1] - tol], [b[2] + tol, b[3] + tol]),
            }
        })
        .collect();
    let envs: Vec<AABB<[f64; 2]>> = boxes.iter().map(|b| b.env).collect();
    let tree = RTree::bulk_load(boxes);
    let mut pairs: Vec<(usize, usize)> = envs
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, env)| {
            tree.locate_in_envelope_intersecting(*env)
                .filter(move |o| o.index > i)
                .map(move |o| (i, o.index))
                .collect::<Vec<_>>()
        })
        .collect();
    pairs.sort_unstable();
    pairs
}

/// The common stretches of two blocks' boundaries (both counter-clockwise).
pub fn touching(a: usize, pa: &[Point], b: usize, pb: &[Point], tol: f64) -> Vec<JointSegment> {
    let mut out = Vec::new();
    let (na, nb) = (pa.len(), pb.len());
    for ea in 0..na {
        let (a0, a1) = (pa[ea], pa[(ea + 1) % na]);
        let da = sub(a1, a0);
        let la = norm(da);
        let ta = [da[0] / la, da[1] / la];
        let normal = [ta[1], -ta[0]]; // outward for a counter-clockwise polygon
        for eb in 0..nb {
            let (b0, b1) = (pb[eb], pb[(eb + 1) % nb]);
            let db = sub(b1, b0);
            if dot(da, db) >= 0.0 {
                continue; // touching edges of two CCW polygons run in opposite directions
            }
            // distance of b's ends from a's line
            let h0 = dot(sub(b0, a0), normal);
            let h1 = dot(sub(b1, a0), normal);
            if h0.abs() > tol || h1.abs() > tol {
                continue;
            }
            let s0 = dot(sub(b0, a0), ta);
            let s1 = dot(sub(b1, a0), ta);
            let lo = s0.min(s1).max(0.0);
            let hi = s0.max(s1).min(la);
            if hi - lo <= tol {
                continue;
            }
            out.push(JointSegment {
                a,
                b,
                edge_a: ea,
                edge_b: eb,
                p0: [a0[0] + lo * ta[0], a0[1] + lo * ta[1]],
                p1: [a0[0] + hi * ta[0], a0[1] + hi * ta[1]],
                normal,
            });
        }
    }
    out
}

/// All joint segments of a scene, in a deterministic order.
pub fn find_joints(polys: &[Vec<Point>], tol: f64) -> Vec<JointSegment> {
    let pairs = candidate_pairs(polys, tol);
    pairs
        .par_iter()
        .flat_map_iter(|&(i, j)| touching(i, &polys[i], j, &polys[j], tol))
        .collect()
}

/// Pairs of blocks whose interiors overlap by more than a sliver: `(i, j, area)`.
/// A sliver is below `tol` times the smaller block's bounding-box diagonal, or 10⁻⁹ of
/// its area, whichever is larger.
pub fn overlapping_pairs(polys: &[Vec<Point>], tol: f64) -> Vec<(usize, usize, f64)> {
    let pairs = candidate_pairs(polys, 0.0);
    pairs
        .par_iter()
        .filter_map(|&(i, j)| {
            let (bi, bj) = (bbox(&polys[i]), bbox(&polys[j]));
            let w = bi[2].min(bj[2]) - bi[0].max(bj[0]);
            let h = bi[3].min(bj[3]) - bi[1].max(bj[1]);
            if w <= tol || h <= tol {
                return None; // boxes meet only along a line: no area in common
            }
            let area = overlap_area(&polys[i], &polys[j]);
            let ai = super::polygon::signed_area(&polys[i]).abs();
            let aj = super::polygon::signed_area(&polys[j]).abs();
            let small = if ai < aj { &polys[i] } else { &polys[j] };
            let limit = (tol * super::polygon::size(small)).max(1e-9 * ai.min(aj));
            (area > limit).then_some((i, j, area))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f64, y0: f64, w: f64, h: f64) -> Vec<Point> {
        vec![[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]
    }

    #[test]
    fn stacked_and_offset() {
        let polys = vec![
            rect(0.0, 0.0, 2.0, 1.0),
            rect(1.0, 1.0, 2.0, 1.0),
            rect(5.0, 0.0, 1.0, 1.0),
        ];
        let j = find_joints(&polys, 1e-9);
        assert_eq!(j.len(), 1);
        assert_eq!((j[0].a, j[0].b), (0, 1));
        assert!((j[0].length() - 1.0).abs() < 1e-15);
        assert_eq!(j[0].normal, [0.0, 1.0]);
        assert!(overlapping_pairs(&polys, 1e-9).is_empty());
        let over = vec![rect(0.0, 0.0, 2.0, 1.0), rect(1.0, 0.5, 2.0, 1.0)];
        let o = overlapping_pairs(&over, 1e-9);
        assert_eq!(o.len(), 1);
        assert!((o[0].2 - 0.5).abs() < 1e-12);
    }
}
