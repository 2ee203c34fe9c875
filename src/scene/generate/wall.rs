//! `wall`: a running-bond masonry wall on a fixed base (docs/validation.md P2, V8).
//!
//! Lourenço's simplified micro-model: each block is the brick plus half a joint on every
//! side, so a block is `brick_length + joint` long and `brick_height + joint` high and
//! the blocks touch along zero-thickness interfaces. Course k (0 from the bottom) has its
//! head joints at x = o_k + i L with o_k = 0 for even k and L/2 for odd k, so the odd
//! courses start and end with half bricks and the wall ends are straight. A wall length
//! of 4.5 bricks (`bricks_per_course = 4.5`) gives courses of 4 full + 1 half brick, as in
//! the Raijmakers–Vermeltfoort walls.
//!
//! With `split_bricks = true` every full brick is two blocks, its halves `…_a` and `…_b`
//! meeting at mid-length, one masonry unit: the potential crack through the brick of
//! Lourenço's micro-model, whose contacts take the `[[joint]]` with `within = "unit"`.
//!
//! Openings (windows, doors) remove the bricks inside them; bricks partly inside are cut
//! with `geo::BooleanOps`, and the cut coordinates are snapped back to the exact course
//! and opening lines so that neighbours share their edges.

use geo::{BooleanOps, MultiPolygon};
use serde::Deserialize;

use super::common::*;
use super::{GenError, GeneratedBlock};

/// An opening in wall coordinates (lower-left corner relative to the wall origin), m.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Opening {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub height: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    pub courses: usize,
    /// A multiple of 0.5.
    pub bricks_per_course: f64,
    pub brick_length: f64,
    pub brick_height: f64,
    pub joint: f64,
    pub origin: [f64; 2],
    pub base: bool,
    pub top_beam: bool,
    pub openings: Vec<Opening>,
    pub split_bricks: bool,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            courses: 10,
            bricks_per_course: 5.0,
            brick_length: 0.4,
            brick_height: 0.2,
            joint: 0.0,
            origin: [0.0, 0.0],
            base: true,
            top_beam: false,
            openings: Vec::new(),
            split_bricks: false,
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    ("courses", "the number of courses, an integer >= 1"),
    (
        "bricks_per_course",
        "the wall length in bricks, a multiple of 0.5, >= 1",
    ),
    ("brick_length", "the brick length in m, > 0"),
    ("brick_height", "the brick height in m, > 0"),
    ("joint", "the mortar joint thickness in m, >= 0"),
    ("origin", "[x, y], the lower-left corner of the wall in m"),
    ("base", "true or false (a fixed base under the wall)"),
    ("top_beam", "true or false (a free beam across the top)"),
    (
        "openings",
        "an array of tables {x, y, width, height} in m, relative to the origin",
    ),
    (
        "split_bricks",
        "true or false (every full brick in two halves, one masonry unit)",
    ),
];

/// A running-bond wall, in blocks (joint included). Shared with `tower`.
pub(crate) struct WallSpec {
    pub courses: usize,
    pub bricks_per_course: f64,
    /// Block length and height (brick plus joint), m.
    pub block_length: f64,
    pub block_height: f64,
    pub origin: [f64; 2],
    pub base: bool,
    pub top_beam: bool,
    pub openings: Vec<Opening>,
    /// Split every full brick at mid-length into two blocks of one unit.
    pub split_bricks: bool,
}

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("wall", params, KEYS)?;
    let joint = non_negative("joint", p.joint, "m")?;
    let bl = positive("brick_length", p.brick_length, "m")?;
    let bh = positive("brick_height", p.brick_height, "m")?;
    build(
        WallSpec {
            courses: p.courses,
            bricks_per_course: p.bricks_per_course,
            block_length: bl + joint,
            block_height: bh + joint,
            origin: p.origin,
            base: p.base,
            top_beam: p.top_beam,
            openings: p.openings,
            split_bricks: p.split_bricks,
        },
        ("courses", "bricks_per_course"),
    )
}

/// Validate and build a wall; `keys` names the course and per-course count keys.
pub(crate) fn build(w: WallSpec, keys: (&str, &str)) -> Result<Vec<GeneratedBlock>, GenError> {
    let courses = count(keys.0, w.courses)?;
    let bpc = w.bricks_per_course;
    if !(bpc.is_finite() && bpc >= 1.0 && (2.0 * bpc - (2.0 * bpc).round()).abs() < 1e-9) {
        return Err(gen_err(
            Some(keys.1),
            format!("{} must be a whole or half number >= 1, got {bpc}", keys.1),
            format!("give {} = 1, 1.5, 2, ...", keys.1),
        ));
    }
    let halves = (2.0 * bpc).round() as usize;
    check_count(keys.0, courses as f64 * (halves as f64 / 2.0 + 2.0) + 2.0)?;
    let (l, h) = (w.block_length, w.block_height);
    let [ox, oy] = [
        finite("origin", w.origin[0])?,
        finite("origin", w.origin[1])?,
    ];
    let width = halves as f64 * 0.5 * l;
    let height = courses as f64 * h;
    for (i, o) in w.openings.iter().enumerate() {
        let bad = |what: String| {
            Err(gen_err(Some("openings"), format!("opening {}: {what}", i + 1), format!("keep every opening inside the wall: 0 <= x, x + width <= {width}, 0 <= y, y + height <= {height} (m)")))
        };
        if ![o.x, o.y, o.width, o.height].iter().all(|v| v.is_finite())
            || o.width <= 0.0
            || o.height <= 0.0
        {
            return bad("width and height must be positive numbers".into());
        }
        let eps = 1e-9 * (width + height);
        if o.x < -eps || o.y < -eps || o.x + o.width > width + eps || o.y + o.height > height + eps
        {
            return bad(format!("x = {}, y = {}, width = {}, height = {} reaches outside the wall {width} m x {height} m", o.x, o.y, o.width, o.height));
        }
    }
    // Every coordinate a block edge may take, computed once.
    let x_at = |k: usize| -> Vec<f64> {
        let off = if k % 2 == 1 { 0.5 } else { 0.0 };
        let mut xs = vec![ox];
        let mut i = 0usize;
        loop {
            let s = off + i as f64;
            if 2.0 * s >= halves as f64 - 1e-9 {
                break;
            }
            if s > 1e-9 {
                xs.push(ox + s * l);
            }
            i += 1;
        }
        xs.push(ox + width);
        xs
    };
    let ys: Vec<f64> = (0..=courses).map(|k| oy + k as f64 * h).collect();
    let mut known_x: Vec<f64> = x_at(0).into_iter().chain(x_at(1)).collect();
    let mut known_y = ys.clone();
    let holes: Vec<[f64; 4]> = w
        .openings
        .iter()
        .map(|o| [ox + o.x, oy + o.y, ox + o.x + o.width, oy + o.y + o.height])
        .collect();
    for r in &holes {
        known_x.extend([r[0], r[2], 0.5 * (r[0] + r[2])]);
        known_y.extend([r[1], r[3]]);
    }
    let cut = MultiPolygon(
        holes
            .iter()
            .map(|r| to_poly(&rect(r[0], r[1], r[2], r[3])))
            .collect(),
    );
    let tol = 1e-7 * (l + h);
    let mut out = Vec::new();
    let mut units = 0;
    if w.base {
        out.push(block(
            "base",
            rect(ox - l, oy - h, ox + width + l, oy),
            true,
        ));
    }
    for k in 0..courses {
        let xs = x_at(k);
        let (y0, y1) = (ys[k], ys[k + 1]);
        for i in 0..xs.len() - 1 {
            let (x0, x1) = (xs[i], xs[i + 1]);
            let name = format!("c{}_b{}", k + 1, i + 1);
            let brick = rect(x0, y0, x1, y1);
            let touching: Vec<&[f64; 4]> = holes
                .iter()
                .filter(|r| {
                    r[0] < x1 - tol && r[2] > x0 + tol && r[1] < y1 - tol && r[3] > y0 + tol
                })
                .collect();
            if touching.is_empty() {
                if w.split_bricks && x1 - x0 > 0.75 * l {
                    // a full brick: two halves of one unit
                    let xm = 0.5 * (x0 + x1);
                    for (suffix, r) in [("a", rect(x0, y0, xm, y1)), ("b", rect(xm, y0, x1, y1))] {
                        let mut b = block(format!("{name}_{suffix}"), r, false);
                        b.unit = Some(units);
                        out.push(b);
                    }
                    units += 1;
                } else {
                    out.push(block(name, brick, false));
                }
                continue;
            }
            if touching.iter().any(|r| {
                r[0] <= x0 + tol && r[2] >= x1 - tol && r[1] <= y0 + tol && r[3] >= y1 - tol
            }) {
                continue; // wholly inside an opening
            }
            let area = (x1 - x0) * (y1 - y0);
            let mut parts: Vec<Vec<P>> = Vec::new();
            for piece in pieces(to_poly(&brick).difference(&cut)) {
                let snapped: Vec<P> = piece
                    .iter()
                    .map(|q| [snap_to(q[0], &known_x, tol), snap_to(q[1], &known_y, tol)])
                    .collect();
                if let Some(c) = clean(snapped, tol) {
                    if signed_area(&c) > 1e-6 * area {
                        parts.push(c);
                    }
                }
            }
            // deterministic order: by lowest-left vertex
            parts.sort_by(|a, b| {
                let ka = a
                    .iter()
                    .fold([f64::MAX; 2], |m, q| [m[0].min(q[1]), m[1].min(q[0])]);
                let kb = b
                    .iter()
                    .fold([f64::MAX; 2], |m, q| [m[0].min(q[1]), m[1].min(q[0])]);
                ka.partial_cmp(&kb).unwrap_or(std::cmp::Ordering::Equal)
            });
            let n = parts.len();
            for (j, v) in parts.into_iter().enumerate() {
                let nm = if n == 1 {
                    name.clone()
                } else {
                    format!("{name}_{}", j + 1)
                };
                out.push(block(nm, v, false));
            }
        }
    }
    if w.top_beam {
        out.push(block(
            "top",
            rect(ox, ys[courses], ox + width, ys[courses] + h),
            false,
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::GeneratedBlock;

    /// Touching length between courses k and k+1 (1-based k), and between the base and course 1.
    fn course_contact(b: &[GeneratedBlock], k: usize) -> f64 {
        let lower: Vec<_> = if k == 0 {
            b.iter().filter(|x| x.name == "base").collect()
        } else {
            b.iter()
                .filter(|x| x.name.starts_with(&format!("c{k}_")))
                .collect()
        };
        let upper: Vec<_> = b
            .iter()
            .filter(|x| x.name.starts_with(&format!("c{}_", k + 1)))
            .collect();
        let mut s = 0.0;
        for a in &lower {
            for u in &upper {
                s += shared_length(&a.vertices, &u.vertices);
            }
        }
        s
    }

    #[test]
    fn plain_wall() {
        let b = run("wall", "courses = 6\nbricks_per_course = 4\nbrick_length = 0.21\nbrick_height = 0.05\njoint = 0.01\norigin = [1.0, 2.0]\ntop_beam = true");
        // 3 full courses of 4, 3 half courses of 5, base, top
        assert_eq!(b.len(), 3 * 4 + 3 * 5 + 2);
        check_blocks(&b);
        assert!(find(&b, "base").fixed);
        assert!(b.iter().filter(|x| x.fixed).count() == 1);
        let (wl, wh) = (4.0 * 0.22, 6.0 * 0.06);
        assert!((total_area(&b[1..b.len() - 1]) - wl * wh).abs() < 1e-9);
        for k in 0..6 {
            assert!((course_contact(&b, k) - wl).abs() < 1e-9, "course {k}");
        }
        assert!(
            (shared_length(&find(&b, "c6_b1").vertices, &find(&b, "top").vertices) - 0.11).abs()
                < 1e-9
        );
        // every brick touches its neighbours in the course
        for k in 1..=6 {
            let n = if k % 2 == 1 { 4 } else { 5 };
            for i in 1..n {
                let l = shared_length(
                    &find(&b, &format!("c{k}_b{i}")).vertices,
                    &find(&b, &format!("c{k}_b{}", i + 1)).vertices,
                );
                assert!((l - 0.06).abs() < 1e-12);
            }
        }
        assert!((find(&b, "c1_b1").vertices[0][0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn half_brick_length() {
        let b = run("wall", "courses = 18\nbricks_per_course = 4.5\nbrick_length = 0.21\nbrick_height = 0.052\njoint = 0.01\nbase = false");
        assert_eq!(b.len(), 18 * 5);
        check_blocks(&b);
        let w = 4.5 * 0.22;
        for k in 1..18 {
            assert!((course_contact(&b, k) - w).abs() < 1e-9);
        }
    }

    /// `split_bricks`: every full brick is two halves of one unit meeting at mid-length;
    /// the half bricks at the ends of the odd courses stay whole, without a unit.
    #[test]
    fn split_bricks_make_two_halves_of_one_unit() {
        let b = run("wall", "courses = 2\nbricks_per_course = 4.5\nbrick_length = 0.21\nbrick_height = 0.052\njoint = 0.01\nsplit_bricks = true");
        check_blocks(&b);
        // course 1: 4 full bricks + 1 half, course 2: half + 4 full; 8 full bricks split
        assert_eq!(b.len(), 1 + 8 * 2 + 2);
        let whole = run("wall", "courses = 2\nbricks_per_course = 4.5\nbrick_length = 0.21\nbrick_height = 0.052\njoint = 0.01");
        assert!((total_area(&b[1..]) - total_area(&whole[1..])).abs() < 1e-12);
        let (a, h) = (find(&b, "c1_b2_a"), find(&b, "c1_b2_b"));
        assert_eq!(a.unit, h.unit);
        assert!(a.unit.is_some());
        assert!((shared_length(&a.vertices, &h.vertices) - 0.062).abs() < 1e-12);
        assert_ne!(find(&b, "c1_b1_a").unit, a.unit);
        assert_eq!(find(&b, "c2_b1").unit, None);
        let units: std::collections::BTreeSet<_> = b.iter().filter_map(|x| x.unit).collect();
        assert_eq!(units.len(), 8);
    }

    #[test]
    fn wall_with_window_and_door() {
        // 10 bricks of 0.4 x 0.2 per course, 12 courses: 4.0 m x 2.4 m.
        // window 0.5..1.5 x 1.1..1.9 (cuts bricks), door 2.6..3.4 x 0..2.0
        let src = "courses = 12\nbricks_per_course = 10\nopenings = [{x = 0.5, y = 1.1, width = 1.0, height = 0.8}, {x = 2.6, y = 0.0, width = 0.8, height = 2.0}]";
        let b = run("wall", src);
        // 6 full courses of 10 + 6 half courses of 11 = 126 bricks; the door removes 1
        // brick from each of the 5 full and 2 from each of the 5 half courses it crosses,
        // the window 1 from c7 and c9 and 2 from c8 (the others are cut): 107, plus base.
        assert_eq!(b.len(), 108);
        check_blocks(&b);
        let holes = [[0.5, 1.1, 1.5, 1.9], [2.6, 0.0, 3.4, 2.0]];
        let open: f64 = holes.iter().map(|r| (r[2] - r[0]) * (r[3] - r[1])).sum();
        assert!((total_area(&b[1..]) - (4.0 * 2.4 - open)).abs() < 1e-9);
        for k in 0..12 {
            let y = 0.2 * k as f64;
            let lost: f64 = holes
                .iter()
                .filter(|r| r[1] <= y + 1e-9 && r[3] >= y - 1e-9)
                .map(|r| r[2] - r[0])
                .sum();
            let c = course_contact(&b, k);
            assert!(
                (c - (4.0 - lost)).abs() < 1e-9,
                "course {k}: {c} vs {}",
                4.0 - lost
            );
        }
        // no block inside an opening; every block touches another
        assert_connected(&b, 1e-6);
        // window cuts brick c6_b2 (0.4..0.8? no: course 6 is odd-indexed: half bricks) into one piece
        assert!(b.iter().all(|x| x
            .vertices
            .iter()
            .all(|q| !(q[0] > 2.6 + 1e-9 && q[0] < 3.4 - 1e-9 && q[1] < 2.0 - 1e-9))));
    }

    #[test]
    fn small_opening_inside_one_brick_is_split() {
        let b = run("wall", "courses = 3\nbricks_per_course = 3\nbrick_length = 1.0\nbrick_height = 0.5\nopenings = [{x = 0.4, y = 0.1, width = 0.2, height = 0.2}]");
        check_blocks(&b);
        assert!(b.iter().any(|x| x.name == "c1_b1_1") && b.iter().any(|x| x.name == "c1_b1_2"));
        assert!((total_area(&b[1..]) - (4.5 - 0.04)).abs() < 1e-9);
    }

    #[test]
    fn wall_bad_parameters() {
        assert_err_key("wall", "courses = 0", "courses");
        assert_err_key("wall", "bricks_per_course = 2.3", "bricks_per_course");
        assert_err_key("wall", "bricks_per_course = 0", "bricks_per_course");
        assert_err_key("wall", "brick_length = 0", "brick_length");
        assert_err_key("wall", "brick_height = -0.1", "brick_height");
        assert_err_key("wall", "joint = -0.01", "joint");
        assert_err_key(
            "wall",
            "openings = [{x = 1.9, y = 0.0, width = 0.5, height = 1.0}]",
            "openings",
        );
        assert_err_key(
            "wall",
            "openings = [{x = 0.1, y = 0.0, width = 0.5}]",
            "openings",
        );
        assert_err_key(
            "wall",
            "openings = [{x = 0.1, y = 0.0, width = 0.0, height = 0.2}]",
            "openings",
        );
        assert_err_key("wall", "coarses = 3", "coarses");
        assert_err_key("wall", "courses = 2.5", "courses");
        assert_err_key("wall", "base = 1", "base");
        let e = run_err("wall", "courses = 100000\nbricks_per_course = 100");
        assert_eq!(e.key.as_deref(), Some("courses"));
        assert!(
            e.what.contains("10150002") || e.what.contains("blocks"),
            "{e:?}"
        );
    }
}
