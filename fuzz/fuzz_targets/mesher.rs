//! Any polygon that passes the validator's check meshes into counter-clockwise
//! triangles of positive area whose areas add up to the polygon's. Vertices come from
//! the input bytes as small integers scaled to metres (so that the polygons are
//! reasonable shapes rather than 1e300-sized ones, which the validator refuses anyway).
#![no_main]
use dfem::geometry::polygon::{check, signed_area};
use dfem::mesh::triangulate::triangulate;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 7 {
        return;
    }
    let h = match data[0] % 4 {
        0 => None,
        k => Some(0.05 * k as f64),
    };
    let mut v: Vec<[f64; 2]> = data[1..]
        .chunks_exact(2)
        .take(40)
        .map(|c| [c[0] as f64 / 64.0, c[1] as f64 / 64.0])
        .collect();
    if check(&v, 1e-9).is_err() {
        return;
    }
    // the check accepts either orientation; the scene reader turns clockwise polygons
    // counter-clockwise before meshing (src/scene/parse.rs), as the mesher requires
    if signed_area(&v) < 0.0 {
        v.reverse();
    }
    let area = signed_area(&v);
    let (interior, tris) = triangulate(&v, h);
    let pts: Vec<[f64; 2]> = v.iter().chain(&interior).copied().collect();
    let mut sum = 0.0;
    for t in &tris {
        let a = signed_area(&t.map(|i| pts[i as usize]));
        assert!(a > 0.0, "triangle {t:?} of area {a:e}");
        sum += a;
    }
    assert!((sum - area).abs() <= 1e-9 * area, "cover {sum} of {area}");
});
