//! Checks shared by the generators' tests (geometry measured with `geo`).

use std::collections::HashSet;

use geo::{Area, BooleanOps, Validation};

use super::common::{signed_area, to_poly, P};
use super::{generate, GenError, GeneratedBlock};

pub fn params(src: &str) -> toml::Table {
    src.parse::<toml::Table>().expect("test parameters parse")
}

pub fn run(kind: &str, src: &str) -> Vec<GeneratedBlock> {
    match generate(kind, &params(src)) {
        Ok(b) => b,
        Err(e) => panic!("{kind} {src}: {e:?}"),
    }
}

pub fn run_err(kind: &str, src: &str) -> GenError {
    match generate(kind, &params(src)) {
        Ok(b) => panic!("{kind} {src}: expected an error, got {} blocks", b.len()),
        Err(e) => e,
    }
}

/// The error names `key`.
pub fn assert_err_key(kind: &str, src: &str, key: &str) {
    let e = run_err(kind, src);
    assert_eq!(e.key.as_deref(), Some(key), "{kind} {src}: {e:?}");
    assert!(!e.what.is_empty() && !e.fix.is_empty());
}

fn bbox(p: &[P]) -> [f64; 4] {
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for q in p {
        b[0] = b[0].min(q[0]);
        b[1] = b[1].min(q[1]);
        b[2] = b[2].max(q[0]);
        b[3] = b[3].max(q[1]);
    }
    b
}

/// Every polygon CCW with positive area, simple, no repeated or collinear vertices;
/// names unique; no two blocks overlap.
pub fn check_blocks(blocks: &[GeneratedBlock]) {
    let mut names = HashSet::new();
    for b in blocks {
        assert!(names.insert(b.name.clone()), "duplicate name {}", b.name);
        let v = &b.vertices;
        assert!(v.len() >= 3, "{}: {} vertices", b.name, v.len());
        let a = signed_area(v);
        assert!(a > 0.0, "{}: signed area {a}", b.name);
        assert!(v.iter().all(|q| q[0].is_finite() && q[1].is_finite()));
        let poly = to_poly(v);
        assert!(poly.is_valid(), "{}: invalid polygon {:?}", b.name, v);
        let scale = (bbox(v)[2] - bbox(v)[0]).max(bbox(v)[3] - bbox(v)[1]);
        let n = v.len();
        for i in 0..n {
            let (p0, p1, p2) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
            assert!(
                (p1[0] - p0[0]).hypot(p1[1] - p0[1]) > 1e-9 * scale,
                "{}: repeated vertex",
                b.name
            );
            let cr = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
            let l = (p2[0] - p0[0]).hypot(p2[1] - p0[1]);
            assert!(
                cr.abs() / l.max(1e-300) > 1e-10 * scale,
                "{}: collinear vertex {i} {:?}",
                b.name,
                v
            );
        }
    }
    let boxes: Vec<[f64; 4]> = blocks.iter().map(|b| bbox(&b.vertices)).collect();
    let polys: Vec<_> = blocks.iter().map(|b| to_poly(&b.vertices)).collect();
    for i in 0..blocks.len() {
        for j in i + 1..blocks.len() {
            let (a, b) = (boxes[i], boxes[j]);
            if a[2] <= b[0] || b[2] <= a[0] || a[3] <= b[1] || b[3] <= a[1] {
                continue;
            }
            let inter = polys[i].intersection(&polys[j]).unsigned_area();
            let small = polys[i].unsigned_area().min(polys[j].unsigned_area());
            // geo's overlay works on an integer grid of 2^29 units over the pair's extent:
            // an edge shared by both blocks can show a spurious overlap of up to a grid
            // unit times its length, which is what the second term allows.
            let ext = (a[2].max(b[2]) - a[0].min(b[0])).max(a[3].max(b[3]) - a[1].min(b[1]));
            let grid = ext / (1u64 << 28) as f64;
            let per = perimeter(&blocks[i].vertices).min(perimeter(&blocks[j].vertices));
            assert!(
                inter < 1e-9 * small + grid * per,
                "{} and {} overlap by {inter}",
                blocks[i].name,
                blocks[j].name
            );
        }
    }
}

fn perimeter(p: &[P]) -> f64 {
    (0..p.len())
        .map(|i| (p[(i + 1) % p.len()][0] - p[i][0]).hypot(p[(i + 1) % p.len()][1] - p[i][1]))
        .sum()
}

/// Length along which the boundaries of two blocks coincide: the overlaps of edges that
/// lie on one line (within 1e-9 of the edge length, so that round-off in rotated
/// coordinates does not hide a contact).
pub fn shared_length(a: &[P], b: &[P]) -> f64 {
    let mut total = 0.0;
    for i in 0..a.len() {
        let (a0, a1) = (a[i], a[(i + 1) % a.len()]);
        let (dx, dy) = (a1[0] - a0[0], a1[1] - a0[1]);
        let l = dx.hypot(dy);
        let (tx, ty) = (dx / l, dy / l);
        for j in 0..b.len() {
            let (b0, b1) = (b[j], b[(j + 1) % b.len()]);
            let off = |q: P| ((q[0] - a0[0]) * ty - (q[1] - a0[1]) * tx).abs();
            if off(b0) > 1e-9 * l || off(b1) > 1e-9 * l {
                continue;
            }
            let s = |q: P| (q[0] - a0[0]) * tx + (q[1] - a0[1]) * ty;
            let (s0, s1) = (s(b0).min(s(b1)), s(b0).max(s(b1)));
            let ov = s1.min(l) - s0.max(0.0);
            if ov > 0.0 {
                total += ov;
            }
        }
    }
    total
}

pub fn find<'a>(blocks: &'a [GeneratedBlock], name: &str) -> &'a GeneratedBlock {
    blocks
        .iter()
        .find(|b| b.name == name)
        .unwrap_or_else(|| panic!("no block {name}"))
}

pub fn total_area(blocks: &[GeneratedBlock]) -> f64 {
    blocks.iter().map(|b| signed_area(&b.vertices)).sum()
}

/// Every block touches at least one other block along an edge of positive length.
pub fn assert_connected(blocks: &[GeneratedBlock], min_len: f64) {
    for (i, a) in blocks.iter().enumerate() {
        let touches = blocks
            .iter()
            .enumerate()
            .any(|(j, b)| i != j && shared_length(&a.vertices, &b.vertices) > min_len);
        assert!(touches, "{} touches nothing", a.name);
    }
}
