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
    let pts: Vec<Point> = ring.iter().chain(&interior).copied().collect();
    repair_slivers(&pts, &mut tris);
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

/// Twice the signed area (m²) of triangle `t` of `pts`.
fn area2(pts: &[Point], t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|k| pts[k as usize]);
    cross(sub(b, a), sub(c, a))
}

/// Replace the triangles of zero area in the true coordinates. Three ring vertices that
/// are collinear only up to the round-off of the centring (a vertex lying on the line
/// through two others, e.g. (0, 0), (1.984375, 1.984375), (2.25, 2.25)) can make the
/// triangulator close a face that has no area in the input's coordinates: a CST with
/// no stiffness. Such a sliver (a, m, b), m between a and b, shares its long edge a–b with
/// a neighbour (b, a, x) inside the polygon (a–b is not a ring edge: m lies on it); the
/// pair is replaced by (a, m, x) and (m, b, x), which cover the same area and keep the
/// mesh conforming. (Found by the `mesher` fuzz target.)
fn repair_slivers(pts: &[Point], tris: &mut Vec<[u32; 3]>) {
    let b = crate::geometry::polygon::bbox(pts);
    let tiny = 1e-12 * ((b[2] - b[0]).powi(2) + (b[3] - b[1]).powi(2));
    // each repair removes one sliver and adds none with a positive-area neighbour
    for _ in 0..tris.len() {
        let Some(s) = tris.iter().position(|&t| area2(pts, t).abs() <= tiny) else {
            return;
        };
        let t = tris[s];
        // the long edge: the one opposite the middle vertex
        let len = |i: usize, j: usize| norm(sub(pts[t[i] as usize], pts[t[j] as usize]));
        let k = (0..3)
            .max_by(|&i, &j| {
                len((i + 1) % 3, (i + 2) % 3).total_cmp(&len((j + 1) % 3, (j + 2) % 3))
            })
            .expect("three edges");
        let (m, a, bb) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let neighbour = tris
            .iter()
            .enumerate()
            .position(|(q, u)| q != s && u.contains(&a) && u.contains(&bb));
        match neighbour {
            Some(q) => {
                let u = tris[q];
                let x = *u
                    .iter()
                    .find(|&&v| v != a && v != bb)
                    .expect("a third vertex");
                let orient = |t: [u32; 3]| {
                    if area2(pts, t) < 0.0 {
                        [t[0], t[2], t[1]]
                    } else {
                        t
                    }
                };
                let (first, second) = (orient([a, m, x]), orient([m, bb, x]));
                let (hi, lo) = (s.max(q), s.min(q));
                tris.swap_remove(hi);
                tris.swap_remove(lo);
                tris.push(first);
                tris.push(second);
            }
            None => {
                tris.swap_remove(s);
            }
        }
    }
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

    /// The polygon the `mesher` fuzz target found (input `KJCQBQAAAH9/DwsA`, oriented
    /// counter-clockwise): vertices 1, 2 and 4 lie on the line y = x, and the
    /// triangulation of the centred coordinates closed them into a face of zero area.
    #[test]
    fn collinear_ring_vertices_give_no_zero_area_triangle() {
        let mut v: Vec<Point> = [
            (0x90, 0x90),
            (0x05, 0x00),
            (0x00, 0x00),
            (0x7f, 0x7f),
            (0x0f, 0x0b),
        ]
        .iter()
        .map(|&(x, y)| [x as f64 / 64.0, y as f64 / 64.0])
        .collect();
        if crate::geometry::polygon::signed_area(&v) < 0.0 {
            v.reverse();
        }
        let area = crate::geometry::polygon::signed_area(&v);
        let (interior, tris) = triangulate(&v, None);
        let pts: Vec<Point> = v.iter().chain(&interior).copied().collect();
        let mut sum = 0.0;
        for t in &tris {
            let a = 0.5 * area2(&pts, *t);
            assert!(a > 0.0, "triangle {t:?} of area {a:e}");
            sum += a;
        }
        assert!((sum - area).abs() <= 1e-12 * area, "{sum} against {area}");
    }

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
