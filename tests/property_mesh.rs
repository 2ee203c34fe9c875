//! Property tests (proptest) of the geometry: any valid polygon meshes into
//! counter-clockwise triangles of positive area that cover it exactly.
//!
//! "Exactly" is checked three ways: the triangles' areas add up to the polygon's area
//! (relative 1e-9: a sum of a few hundred areas each exact to round-off), every triangle's
//! centroid lies inside the polygon, and the triangles form a proper surface: each boundary
//! edge of the ring belongs to exactly one triangle and every other edge to exactly two,
//! traversed in opposite directions (no overlap, no gap, no hanging node).

use dfem::geometry::polygon::{check, contains, signed_area, Point};
use dfem::mesh::triangulate::triangulate;
use proptest::prelude::*;
use std::collections::HashMap;

/// A star-shaped polygon about the origin: `n` vertices at increasing angles (each step a
/// random share of the turn) and random radii; always simple. Scaled by `scale` (m).
fn star(steps: &[f64], radii: &[f64], scale: f64) -> Vec<Point> {
    let total: f64 = steps.iter().sum();
    let mut a = 0.0;
    steps
        .iter()
        .zip(radii)
        .map(|(s, r)| {
            a += s / total * std::f64::consts::TAU;
            [scale * r * a.cos(), scale * r * a.sin()]
        })
        .collect()
}

fn polygon() -> impl Strategy<Value = (Vec<Point>, f64)> {
    (3usize..24).prop_flat_map(|n| {
        (
            prop::collection::vec(0.3f64..1.0, n),
            prop::collection::vec(0.35f64..1.0, n),
            prop::sample::select(vec![1e-3, 1.0, 1e3]),
        )
            .prop_map(|(steps, radii, scale)| (star(&steps, &radii, scale), scale))
    })
}

/// Checks the triangles of `ring` ++ `interior` cover `ring` exactly.
fn assert_exact_cover(ring: &[Point], interior: &[Point], tris: &[[u32; 3]]) {
    let pts: Vec<Point> = ring.iter().chain(interior).copied().collect();
    let area = signed_area(ring);
    let mut sum = 0.0;
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for t in tris {
        let p = t.map(|i| pts[i as usize]);
        let a = signed_area(&p);
        assert!(
            a > 1e-12 * area,
            "triangle {t:?} has area {a:e} (polygon {area:e})"
        );
        sum += a;
        let c = [
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ];
        assert!(contains(ring, c), "triangle {t:?} lies outside the polygon");
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    assert!(
        (sum - area).abs() <= 1e-9 * area,
        "triangles cover {sum:e} of {area:e}"
    );
    let n = ring.len() as u32;
    for (&(i, j), &count) in &edges {
        assert_eq!(count, 1, "edge ({i}, {j}) used twice in the same direction");
        let boundary = i < n && j < n && (j == (i + 1) % n);
        let reverse = edges.contains_key(&(j, i));
        assert!(
            boundary ^ reverse,
            "edge ({i}, {j}): boundary {boundary}, has a twin {reverse}"
        );
    }
    for i in 0..n {
        assert!(
            edges.contains_key(&(i, (i + 1) % n)),
            "boundary edge ({i}, {}) is not a triangle edge",
            (i + 1) % n
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn any_valid_polygon_meshes_into_an_exact_cover((ring, scale) in polygon()) {
        prop_assume!(check(&ring, 1e-9 * scale).is_ok());
        let (interior, tris) = triangulate(&ring, None);
        prop_assert!(interior.is_empty());
        assert_exact_cover(&ring, &interior, &tris);
    }

    #[test]
    fn refined_meshes_also_cover_exactly((ring, scale) in polygon(), h in 0.08f64..0.5) {
        prop_assume!(check(&ring, 1e-9 * scale).is_ok());
        let (interior, tris) = triangulate(&ring, Some(h * scale));
        for p in &interior {
            prop_assert!(contains(&ring, *p), "interior point {p:?} outside");
        }
        assert_exact_cover(&ring, &interior, &tris);
    }
}
