//! Triangulation of one block: constrained Delaunay (`spade`) of its boundary ring, with
//! optional interior points to a target size. Works for any simple polygon, convex or
//! not. The boundary nodes are kept exactly as given (contact nodes must pair with the
//! neighbour's), so the caller subdivides boundary edges and the interior is seeded with
//! a triangular lattice of spacing h kept clear of the boundary: spade's Delaunay
//! refinement either splits constraint edges (which would break the node pairing) or,
//! with the constraint edges kept, declines to refine.

use crate::geometry::polygon::{contains, Point};
use crate::geometry::polygon::{cross, dot, norm, sub};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// Triangulate the counter-clockwise `ring`. Returns the interior points added by the
/// refinement (numbered after the ring) and the triangles (indices into ring ++ interior),
/// counter-clockwise.
pub fn triangulate(ring: &[Point], h: Option<f64>) -> (Vec<Point>, Vec<[u32; 3]>) {
    let n = ring.len();
    if n == 3 && h.is_none() {
        return (Vec::new(), vec![[0, 1, 2]]);
    }
    // work in coordinates centred on the ring, for the predicates' sake
    let c = ring
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
    let c = [c[0] / n as f64, c[1] / n as f64];
    let mut local: Vec<Point> = ring.iter().map(|p| [p[0] - c[0], p[1] - c[1]]).collect();
    // Points inserted on a straight edge (contact nodes, subdivisions) are off the line by
    // round-off; a convex kink of 1e-16 makes the Delaunay triangulation close it with a
    // zero-area triangle. Nudge every near-collinear boundary point inward by 1e-9 of its
    // span in the triangulator's input only (the nodes keep their positions): any
    // degenerate face then lies outside and is dropped below.
    let orig = local.clone();
    for i in 0..n {
        let (a, b, d) = (orig[(i + n - 1) % n], orig[i], orig[(i + 1) % n]);
        let (u, w) = (sub(b, a), sub(d, b));
        let span = sub(d, a);
        if cross(u, w).abs() <= 1e-9 * norm(u) * norm(w) {
            let l = norm(span);
            let inward = [-span[1] / l, span[0] / l];
            local[i] = [b[0] + 1e-9 * l * inward[0], b[1] + 1e-9 * l * inward[1]];
        }
    }
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut handles = Vec::with_capacity(n);
    for p in &local {
        // distinct boundary points by construction; insertion cannot fail for finite input
        let hnd = cdt
            .insert(Point2::new(p[0], p[1]))
            .expect("finite boundary point");
        handles.push(hnd);
    }
    for i in 0..n {
        cdt.add_constraint(handles[i], handles[(i + 1) % n]);
    }
    if let Some(h) = h {
        for p in lattice(&local, h) {
            // a point coinciding with an existing vertex is skipped by construction
            let _ = cdt.insert(Point2::new(p[0], p[1]));
        }
    }
    // vertex handle index → local node index
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    for (k, hnd) in handles.iter().enumerate() {
        index[hnd.index()] = k as u32;
    }
    let mut interior = Vec::new();
    for v in cdt.vertices() {
        if index[v.fix().index()] == u32::MAX {
            index[v.fix().index()] = (n + interior.len()) as u32;
            let p = v.position();
            interior.push([p.x + c[0], p.y + c[1]]);
        }
    }
    let mut tris = Vec::new();
    let nn = n as u32;
    for f in cdt.inner_faces() {
        let vs = f.vertices();
        let p: Vec<Point2<f64>> = vs.iter().map(|v| v.position()).collect();
        let t = [
            index[vs[0].fix().index()],
            index[vs[1].fix().index()],
            index[vs[2].fix().index()],
        ];
        let a = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
        let t = if a > 0.0 { t } else { [t[0], t[2], t[1]] };
        // a face carrying a boundary edge in the ring's direction is inside, against it
        // outside; the others are decided by their centroid
        let mut side = None;
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            if i < nn && j < nn {
                if j == (i + 1) % nn {
                    side = Some(true);
                } else if i == (j + 1) % nn {
                    side = Some(false);
                }
            }
        }
        let inside = side.unwrap_or_else(|| {
            let g = [
                (p[0].x + p[1].x + p[2].x) / 3.0,
                (p[0].y + p[1].y + p[2].y) / 3.0,
            ];
            contains(&local, g)
        });
        if inside {
            tris.push(t);
        }
    }
    // drop interior points no triangle uses (refinement outside the polygon)
    let mut used = vec![false; n + interior.len()];
    for t in &tris {
        for &k in t {
            used[k as usize] = true;
        }
    }
    let mut renum: Vec<u32> = (0..(n + interior.len()) as u32).collect();
    let mut kept = Vec::new();
    for (k, p) in interior.iter().enumerate() {
        if used[n + k] {
            renum[n + k] = (n + kept.len()) as u32;
            kept.push(*p);
        }
    }
    for t in &mut tris {
        for k in t.iter_mut() {
            *k = renum[*k as usize];
        }
    }
    (kept, tris)
}

/// Points of an equilateral lattice of spacing `h` inside the polygon, at least 0.45 h
/// from its boundary.
fn lattice(ring: &[Point], h: f64) -> Vec<Point> {
    let b = crate::geometry::polygon::bbox(ring);
    let dy = h * 3f64.sqrt() / 2.0;
    let clear = 0.45 * h;
    let mut out = Vec::new();
    let rows = ((b[3] - b[1]) / dy).floor() as i64;
    for r in 1..=rows {
        let y = b[1] + r as f64 * dy;
        let x0 = b[0] + if r % 2 == 0 { h } else { 0.5 * h };
        let cols = ((b[2] - x0) / h).floor() as i64;
        for c in 0..=cols {
            let p = [x0 + c as f64 * h, y];
            if contains(ring, p) && distance_to_ring(ring, p) >= clear {
                out.push(p);
            }
        }
    }
    out
}

/// Distance (m) from a point to the polygon's boundary.
fn distance_to_ring(ring: &[Point], p: Point) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let d = sub(b, a);
            let t = (dot(sub(p, a), d) / dot(d, d)).clamp(0.0, 1.0);
            norm(sub(p, [a[0] + t * d[0], a[1] + t * d[1]]))
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::polygon::signed_area;

    fn total_area(ring: &[Point], interior: &[Point], tris: &[[u32; 3]]) -> f64 {
        let all: Vec<Point> = ring.iter().chain(interior).copied().collect();
        tris.iter()
            .map(|t| {
                let a = signed_area(&[all[t[0] as usize], all[t[1] as usize], all[t[2] as usize]]);
                assert!(a > 0.0);
                a
            })
            .sum()
    }

    #[test]
    fn non_convex_covered() {
        let l = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        let (i, t) = triangulate(&l, None);
        assert!(i.is_empty());
        assert_eq!(t.len(), 4);
        assert!((total_area(&l, &i, &t) - 3.0).abs() < 1e-12);
        let (i, t) = triangulate(&l, Some(0.2));
        assert!(!i.is_empty());
        assert!((total_area(&l, &i, &t) - 3.0).abs() < 1e-12);
    }
}
