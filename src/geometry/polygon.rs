//! Polygon predicates used to validate blocks: area, orientation, simplicity, containment.
//! Small, exact-enough formulas on `[f64; 2]` points; boolean operations use `geo`.

pub type Point = [f64; 2];

/// Signed area (m²): positive for counter-clockwise vertex order (shoelace formula).
pub fn signed_area(v: &[Point]) -> f64 {
    let n = v.len();
    let mut s = 0.0;
    for i in 0..n {
        let a = v[i];
        let b = v[(i + 1) % n];
        s += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * s
}

/// Area centroid (m) of a simple polygon with non-zero area.
pub fn centroid(v: &[Point]) -> Point {
    let n = v.len();
    // shift to the first vertex to limit cancellation for polygons far from the origin
    let o = v[0];
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let p = sub(v[i], o);
        let q = sub(v[(i + 1) % n], o);
        let c = p[0] * q[1] - q[0] * p[1];
        a += c;
        cx += (p[0] + q[0]) * c;
        cy += (p[1] + q[1]) * c;
    }
    [o[0] + cx / (3.0 * a), o[1] + cy / (3.0 * a)]
}

pub fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}

pub fn dot(a: Point, b: Point) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

pub fn cross(a: Point, b: Point) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

pub fn norm(a: Point) -> f64 {
    a[0].hypot(a[1])
}

/// Axis-aligned bounding box `[xmin, ymin, xmax, ymax]`.
pub fn bbox(v: &[Point]) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in v {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

/// Length scale of a polygon: the diagonal of its bounding box.
pub fn size(v: &[Point]) -> f64 {
    let b = bbox(v);
    (b[2] - b[0]).hypot(b[3] - b[1])
}

/// Whether segments `p1p2` and `q1q2` intersect, touching included (orientation tests).
pub fn segments_intersect(p1: Point, p2: Point, q1: Point, q2: Point) -> bool {
    let d1 = orient(q1, q2, p1);
    let d2 = orient(q1, q2, p2);
    let d3 = orient(p1, p2, q1);
    let d4 = orient(p1, p2, q2);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment(q1, q2, p1))
        || (d2 == 0.0 && on_segment(q1, q2, p2))
        || (d3 == 0.0 && on_segment(p1, p2, q1))
        || (d4 == 0.0 && on_segment(p1, p2, q2))
}

fn orient(a: Point, b: Point, c: Point) -> f64 {
    cross(sub(b, a), sub(c, a))
}

fn on_segment(a: Point, b: Point, p: Point) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// What makes a polygon unusable as a block.
#[derive(Debug, Clone, PartialEq)]
pub enum PolygonDefect {
    TooFewVertices(usize),
    NotFinite(usize),
    /// Two consecutive vertices (indices) closer than the tolerance.
    RepeatedVertex(usize, usize),
    /// Area (m²) below the tolerance.
    ZeroArea(f64),
    /// Two non-adjacent edges (starting at these vertex indices) cross or touch.
    SelfIntersecting(usize, usize),
}

/// Check a polygon for use as a block. `tol` is a length (m). Clockwise order is not a
/// defect (the caller reverses it).
pub fn check(v: &[Point], tol: f64) -> Result<(), PolygonDefect> {
    let n = v.len();
    if n < 3 {
        return Err(PolygonDefect::TooFewVertices(n));
    }
    if let Some(i) = v
        .iter()
        .position(|p| !p[0].is_finite() || !p[1].is_finite())
    {
        return Err(PolygonDefect::NotFinite(i));
    }
    for i in 0..n {
        let j = (i + 1) % n;
        if norm(sub(v[j], v[i])) <= tol {
            return Err(PolygonDefect::RepeatedVertex(i, j));
        }
    }
    // O(n²) edge test: blocks have few vertices; large polygons (cut tunnel blocks)
    // stay below a few hundred.
    for i in 0..n {
        let (a1, a2) = (v[i], v[(i + 1) % n]);
        for j in (i + 2)..n {
            if i == 0 && j == n - 1 {
                continue; // adjacent through the closing edge
            }
            let (b1, b2) = (v[j], v[(j + 1) % n]);
            if segments_intersect(a1, a2, b1, b2) {
                return Err(PolygonDefect::SelfIntersecting(i, j));
            }
        }
    }
    let a = signed_area(v).abs();
    let s = size(v);
    if a <= tol * s || a <= 1e-12 * s * s {
        return Err(PolygonDefect::ZeroArea(a));
    }
    Ok(())
}

/// Point-in-polygon by the winding/crossing rule (boundary points may go either way).
pub fn contains(v: &[Point], p: Point) -> bool {
    let n = v.len();
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (v[i], v[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Area (m²) of the intersection of two simple polygons, through `geo`'s boolean operations.
pub fn overlap_area(a: &[Point], b: &[Point]) -> f64 {
    use geo::{Area, BooleanOps};
    let pa = to_geo(a);
    let pb = to_geo(b);
    pa.intersection(&pb).unsigned_area()
}

/// A `geo` polygon from a vertex ring.
pub fn to_geo(v: &[Point]) -> geo::Polygon<f64> {
    geo::Polygon::new(
        geo::LineString::from(v.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>()),
        vec![],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_centroid_orientation() {
        let sq = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
        assert_eq!(signed_area(&sq), 2.0);
        assert_eq!(centroid(&sq), [1.0, 0.5]);
        let mut cw = sq;
        cw.reverse();
        assert_eq!(signed_area(&cw), -2.0);
        let l = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        let c = centroid(&l);
        assert!((c[0] - 5.0 / 6.0).abs() < 1e-14 && (c[1] - 5.0 / 6.0).abs() < 1e-14);
    }

    #[test]
    fn defects() {
        assert_eq!(
            check(&[[0.0, 0.0], [1.0, 0.0]], 1e-9),
            Err(PolygonDefect::TooFewVertices(2))
        );
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(
            check(&bow, 1e-9),
            Err(PolygonDefect::SelfIntersecting(..))
        ));
        let flat = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        assert!(matches!(
            check(&flat, 1e-9),
            Err(PolygonDefect::ZeroArea(_))
        ));
        let rep = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(
            check(&rep, 1e-9),
            Err(PolygonDefect::RepeatedVertex(1, 2))
        ));
        let l = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        assert_eq!(check(&l, 1e-9), Ok(()));
        assert!(contains(&l, [0.5, 1.5]) && !contains(&l, [1.5, 1.5]));
    }

    #[test]
    fn overlap() {
        let a = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let b = [[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]];
        assert!((overlap_area(&a, &b) - 1.0).abs() < 1e-12);
        let c = [[2.0, 0.0], [4.0, 0.0], [4.0, 2.0], [2.0, 2.0]];
        assert!(overlap_area(&a, &c) < 1e-12);
    }
}
