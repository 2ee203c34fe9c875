//! `tunnel`: an opening in a jointed rock mass (docs/validation.md V9, P4).
//!
//! The domain [0, width] × [0, height] minus the opening is cut by the joint sets with
//! `geo::BooleanOps` (intersection of each piece with the strips between successive
//! joints of a set); pieces that still enclose the opening are split by a vertical line
//! through it, so every block is a simple polygon. Joint k of a set is the line
//! n·(p − c) = offset + k·spacing, with n = (−sin dip, cos dip) the set's normal and c the
//! opening centre (offset = 0: a joint through the centre). Vertices closer than
//! 2e-8 × the domain size are welded so that neighbours share them exactly. Four fixed
//! frame blocks of thickness `frame` surround the domain (no top one with
//! `free_surface = true`).

use std::f64::consts::PI;

use geo::{BooleanOps, Polygon};
use serde::Deserialize;

use super::common::*;
use super::{GenError, GeneratedBlock};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSet {
    /// Degrees from the horizontal, counter-clockwise.
    pub dip: f64,
    pub spacing: f64,
    #[serde(default)]
    pub offset: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Opening {
    pub shape: String,
    pub radius: f64,
    pub center: Option<[f64; 2]>,
    pub segments: usize,
    /// Horseshoe only: height of the vertical walls below the crown's centre (default radius).
    pub wall_height: Option<f64>,
}

impl Default for Opening {
    fn default() -> Self {
        Opening {
            shape: "circle".into(),
            radius: 3.0,
            center: None,
            segments: 32,
            wall_height: None,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    pub width: f64,
    pub height: f64,
    pub joint_sets: Vec<JointSet>,
    pub opening: Opening,
    pub frame: f64,
    pub free_surface: bool,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            width: 20.0,
            height: 20.0,
            joint_sets: vec![
                JointSet {
                    dip: 30.0,
                    spacing: 2.0,
                    offset: 0.0,
                },
                JointSet {
                    dip: 120.0,
                    spacing: 2.0,
                    offset: 0.0,
                },
            ],
            opening: Opening::default(),
            frame: 1.0,
            free_surface: false,
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    ("width", "the domain width in m, > 0"),
    ("height", "the domain height in m, > 0"),
    ("joint_sets", "an array of tables {dip (degrees), spacing (m, > 0), offset (m, default 0)}"),
    ("opening", "a table {shape = \"circle\" | \"horseshoe\", radius, center = [x, y], segments, wall_height}"),
    ("frame", "the thickness of the fixed frame blocks in m, > 0"),
    ("free_surface", "true or false (no top frame block)"),
];

/// The opening polygon (counter-clockwise).
pub fn opening_polygon(o: &Opening, c: P) -> Vec<P> {
    let r = o.radius;
    if o.shape == "circle" {
        (0..o.segments)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / o.segments as f64;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            })
            .collect()
    } else {
        let wh = o.wall_height.unwrap_or(r);
        let ns = (o.segments / 2).max(2);
        let mut v = vec![
            [c[0] - r, c[1] - wh],
            [c[0] + r, c[1] - wh],
            [c[0] + r, c[1]],
        ];
        for k in 1..ns {
            let a = PI * k as f64 / ns as f64;
            v.push([c[0] + r * a.cos(), c[1] + r * a.sin()]);
        }
        v.push([c[0] - r, c[1]]);
        v
    }
}

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("tunnel", params, KEYS)?;
    let w = positive("width", p.width, "m")?;
    let h = positive("height", p.height, "m")?;
    let f = positive("frame", p.frame, "m")?;
    if p.joint_sets.is_empty() {
        return Err(gen_err(Some("joint_sets"), "joint_sets is empty", "give at least one set, e.g. joint_sets = [{dip = 30, spacing = 2.0}, {dip = 120, spacing = 2.0}]"));
    }
    for (i, s) in p.joint_sets.iter().enumerate() {
        if !(s.dip.is_finite() && (-180.0..=180.0).contains(&s.dip)) {
            return Err(gen_err(
                Some("joint_sets"),
                format!(
                    "joint set {}: dip {} is not an angle in [-180, 180] degrees",
                    i + 1,
                    s.dip
                ),
                "give the dip in degrees from the horizontal",
            ));
        }
        if !(s.spacing.is_finite() && s.spacing > 0.0 && s.offset.is_finite()) {
            return Err(gen_err(
                Some("joint_sets"),
                format!(
                    "joint set {}: spacing must be a positive number and offset finite",
                    i + 1
                ),
                "give spacing > 0 (m)",
            ));
        }
    }
    let o = &p.opening;
    match o.shape.as_str() {
        "circle" | "horseshoe" => {}
        s => {
            return Err(gen_err(
                Some("opening"),
                format!("unknown opening shape '{s}'"),
                "give opening.shape = \"circle\" or \"horseshoe\"",
            ))
        }
    }
    let r = positive("opening", o.radius, "m").map_err(|mut e| {
        e.what = format!("opening radius must be a positive number, got {}", o.radius);
        e.fix = "give opening.radius > 0 (m)".into();
        e
    })?;
    if o.segments < 8 || o.segments > 100_000 {
        return Err(gen_err(
            Some("opening"),
            format!(
                "opening segments must be between 8 and 100000, got {}",
                o.segments
            ),
            "give opening.segments = 32 or so",
        ));
    }
    if o.shape == "circle" && o.wall_height.is_some() {
        return Err(gen_err(
            Some("opening"),
            "wall_height applies to horseshoe openings only",
            "remove opening.wall_height or set opening.shape = \"horseshoe\"",
        ));
    }
    if let Some(wh) = o.wall_height {
        if !(wh.is_finite() && wh > 0.0) {
            return Err(gen_err(
                Some("opening"),
                format!("opening wall_height must be positive, got {wh}"),
                "give opening.wall_height > 0 (m)",
            ));
        }
    }
    let c = o.center.unwrap_or([0.5 * w, 0.5 * h]);
    if !(c[0].is_finite() && c[1].is_finite()) {
        return Err(gen_err(
            Some("opening"),
            "opening center must be finite",
            "give opening.center = [x, y] inside the domain",
        ));
    }
    let _ = r;
    let hole = opening_polygon(o, c);
    let (mut bx0, mut by0, mut bx1, mut by1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for q in &hole {
        bx0 = bx0.min(q[0]);
        by0 = by0.min(q[1]);
        bx1 = bx1.max(q[0]);
        by1 = by1.max(q[1]);
    }
    if bx0 <= 0.0 || by0 <= 0.0 || bx1 >= w || by1 >= h {
        return Err(gen_err(Some("opening"), format!("the opening [{bx0:.3}, {bx1:.3}] x [{by0:.3}, {by1:.3}] is not inside the domain [0, {w}] x [0, {h}]"), "make the opening smaller or move its center"));
    }
    // Block count estimate: cells of the line arrangement inside the domain.
    let sets: Vec<(P, P, f64, f64)> = p
        .joint_sets
        .iter()
        .map(|s| {
            let a = s.dip.to_radians();
            ([-a.sin(), a.cos()], [a.cos(), a.sin()], s.spacing, s.offset)
        })
        .collect();
    let diag = w.hypot(h);
    let mut est = 1.0;
    for (i, si) in sets.iter().enumerate() {
        est += diag / si.2 + 1.0;
        for sj in &sets[i + 1..] {
            let sin = (si.0[0] * sj.0[1] - si.0[1] * sj.0[0]).abs();
            est += w * h * sin / (si.2 * sj.2);
        }
    }
    check_count("joint_sets", est)?;

    let domain = to_poly(&rect(0.0, 0.0, w, h));
    let mut polys: Vec<Polygon<f64>> = domain.difference(&to_poly(&hole)).0;
    for &(nrm, d, sp, off) in &sets {
        let mut next = Vec::new();
        for poly in polys {
            let ext = &poly.exterior().0;
            let proj = |q: &geo::Coord<f64>| nrm[0] * (q.x - c[0]) + nrm[1] * (q.y - c[1]);
            let (pmin, pmax) = ext.iter().fold((f64::MAX, f64::MIN), |(a, b), q| {
                (a.min(proj(q)), b.max(proj(q)))
            });
            let k0 = ((pmin - off) / sp).floor() as i64;
            let k1 = ((pmax - off) / sp).ceil() as i64;
            if k1 - k0 <= 1 {
                next.push(poly);
                continue;
            }
            // strips limited to the piece's neighbourhood (keeps the overlay grid fine)
            let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
            for q in ext {
                x0 = x0.min(q.x);
                y0 = y0.min(q.y);
                x1 = x1.max(q.x);
                y1 = y1.max(q.y);
            }
            let pc = [0.5 * (x0 + x1), 0.5 * (y0 + y1)];
            let rad = 0.51 * (x1 - x0).hypot(y1 - y0) + 1e-9 * diag;
            let tc = d[0] * (pc[0] - c[0]) + d[1] * (pc[1] - c[1]);
            for k in k0..k1 {
                let (s0, s1) = (off + k as f64 * sp, off + (k + 1) as f64 * sp);
                let pt = |s: f64, t: f64| -> P {
                    [c[0] + nrm[0] * s + d[0] * t, c[1] + nrm[1] * s + d[1] * t]
                };
                let strip = vec![
                    pt(s0, tc - rad),
                    pt(s0, tc + rad),
                    pt(s1, tc + rad),
                    pt(s1, tc - rad),
                ];
                let strip = if signed_area(&strip) < 0.0 {
                    strip.into_iter().rev().collect()
                } else {
                    strip
                };
                next.extend(poly.intersection(&to_poly(&strip)).0);
            }
        }
        polys = next;
    }
    let min_sp = sets.iter().map(|s| s.2).fold(f64::MAX, f64::min);
    let tol = 2e-8 * w.max(h);
    let mut rings: Vec<Vec<P>> = polys
        .into_iter()
        .flat_map(|p| pieces(geo::MultiPolygon(vec![p])))
        .collect();
    for ring in rings.iter_mut() {
        for q in ring.iter_mut() {
            q[0] = snap_to(q[0], &[0.0, w], tol);
            q[1] = snap_to(q[1], &[0.0, h], tol);
            if let Some(hv) = hole
                .iter()
                .find(|hv| (hv[0] - q[0]).hypot(hv[1] - q[1]) <= tol)
            {
                *q = *hv;
            }
        }
    }
    weld(&mut rings, tol);
    let mut cells: Vec<Vec<P>> = rings
        .into_iter()
        .filter_map(|r| clean(r, tol))
        .filter(|r| signed_area(r) > 1e-6 * min_sp * min_sp)
        .collect();
    // deterministic order: bottom to top, left to right (by lowest vertex)
    let key = |r: &Vec<P>| {
        r.iter().fold([f64::MAX, f64::MAX], |m, q| {
            if (q[1], q[0]) < (m[1], m[0]) {
                *q
            } else {
                m
            }
        })
    };
    cells.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        (ka[1], ka[0])
            .partial_cmp(&(kb[1], kb[0]))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut out = Vec::with_capacity(cells.len() + 4);
    let top = if p.free_surface { h } else { h + f };
    out.push(block("frame_left", rect(-f, -f, 0.0, top), true));
    out.push(block("frame_right", rect(w, -f, w + f, top), true));
    out.push(block("frame_bottom", rect(0.0, -f, w, 0.0), true));
    if !p.free_surface {
        out.push(block("frame_top", rect(0.0, h, w, h + f), true));
    }
    for (i, v) in cells.into_iter().enumerate() {
        out.push(block(format!("b{}", i + 1), v, false));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::common::signed_area;
    use super::super::testutil::*;

    fn check_tunnel(src: &str, frames: usize) {
        let b = run("tunnel", src);
        check_blocks(&b);
        assert_eq!(b.iter().filter(|x| x.fixed).count(), frames);
        let p = params(src);
        let get = |k: &str, d: f64| {
            p.get(k)
                .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
                .unwrap_or(d)
        };
        let (w, h) = (get("width", 20.0), get("height", 20.0));
        let par: super::Params = toml::Value::Table(p.clone()).try_into().unwrap();
        let c = par.opening.center.unwrap_or([0.5 * w, 0.5 * h]);
        let hole = super::opening_polygon(&par.opening, c);
        let rock: f64 = b
            .iter()
            .filter(|x| !x.fixed)
            .map(|x| signed_area(&x.vertices))
            .sum();
        let expect = w * h - signed_area(&hole);
        assert!(
            (rock - expect).abs() < 1e-6 * expect,
            "{src}: area {rock} vs {expect}"
        );
        // frame inner edges coincide with the domain boundary
        let fl = shared_length(
            &find(&b, "frame_left").vertices,
            &find(&b, "frame_bottom").vertices,
        );
        assert!((fl - 1.0).abs() < 1e-9, "{src}: frame corner {fl}");
        let along: f64 = b
            .iter()
            .filter(|x| !x.fixed)
            .map(|x| shared_length(&x.vertices, &find(&b, "frame_bottom").vertices))
            .sum();
        assert!((along - w).abs() < 1e-6, "{src}: bottom contact {along}");
        let left: f64 = b
            .iter()
            .filter(|x| !x.fixed)
            .map(|x| shared_length(&x.vertices, &find(&b, "frame_left").vertices))
            .sum();
        assert!((left - h).abs() < 1e-6, "{src}: left contact {left}");
        assert_connected(&b, 1e-6);
    }

    #[test]
    fn tunnels() {
        check_tunnel("", 4);
        check_tunnel("joint_sets = [{dip = 0, spacing = 2.5}, {dip = 90, spacing = 2.0, offset = 0.5}]\nopening = {shape = \"horseshoe\", radius = 3.0}", 4);
        check_tunnel("width = 30\nheight = 24\njoint_sets = [{dip = 20, spacing = 3.0}, {dip = 80, spacing = 4.0, offset = 1.0}, {dip = -45, spacing = 5.0}]\nopening = {radius = 4.0, segments = 48, center = [14.0, 10.0]}\nfree_surface = true", 3);
        check_tunnel("joint_sets = [{dip = 35, spacing = 3.3}, {dip = 100, spacing = 2.7}, {dip = 160, spacing = 4.1, offset = 0.3}]\nopening = {shape = \"horseshoe\", radius = 2.5, wall_height = 2.0, segments = 24}", 4);
        // one set with wide spacing: the opening falls inside one strip and is split
        check_tunnel("joint_sets = [{dip = 0, spacing = 8.0, offset = 4.0}]", 4);
        // joints at y = 6 and 14: three strips, the middle one split at the opening
        let b = run(
            "tunnel",
            "joint_sets = [{dip = 0, spacing = 8.0, offset = 4.0}]",
        );
        assert_eq!(b.len(), 4 + 4);
    }

    #[test]
    fn tunnel_bad_parameters() {
        assert_err_key("tunnel", "width = 0", "width");
        assert_err_key("tunnel", "height = -3", "height");
        assert_err_key("tunnel", "frame = 0", "frame");
        assert_err_key("tunnel", "joint_sets = []", "joint_sets");
        assert_err_key(
            "tunnel",
            "joint_sets = [{dip = 30, spacing = 0}]",
            "joint_sets",
        );
        assert_err_key("tunnel", "joint_sets = [{dip = 30}]", "joint_sets");
        assert_err_key(
            "tunnel",
            "joint_sets = [{dip = 30, spacing = 1, strike = 3}]",
            "joint_sets",
        );
        assert_err_key(
            "tunnel",
            "opening = {shape = \"square\", radius = 2}",
            "opening",
        );
        assert_err_key("tunnel", "opening = {radius = 12}", "opening");
        assert_err_key("tunnel", "opening = {radius = 0}", "opening");
        assert_err_key(
            "tunnel",
            "opening = {radius = 2, center = [1.0, 1.0]}",
            "opening",
        );
        assert_err_key(
            "tunnel",
            "opening = {radius = 2, wall_height = 1}",
            "opening",
        );
        assert_err_key(
            "tunnel",
            "joint_sets = [{dip = 0, spacing = 0.001}, {dip = 90, spacing = 0.001}]",
            "joint_sets",
        );
        assert_err_key("tunnel", "free = true", "free");
    }
}
