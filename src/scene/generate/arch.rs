//! `arch`: a voussoir arch on two piers (seed section 4.3; docs/validation.md V5, V6).
//!
//! Coordinates: the arch is symmetric about x = 0, the intrados springings are at
//! (∓span/2, pier_height); the piers stand on y = 0 with their inner faces flush with the
//! intrados springings; the fixed base is below y = 0.
//!
//! Each face (intrados, extrados) is made of circular arcs:
//! * semicircular: one centre on the springing line, radius span/2;
//! * segmental: one centre below the springing line, radius R = (span²/4 + rise²)/(2 rise);
//! * pointed: two centres on the springing line at ±(span/2 − ρ), radius ρ (intrados)
//!   and ρ + thickness (extrados), meeting at the crown (x = 0).
//!
//! The joints are radial: joint j (j = 0..n) is at intrados angle u_j = 2β j/n from the
//! left springing (β the angular half-span of the intrados), on the line through the
//! centre of its arc; a crown joint of a pointed arch (n even) is vertical. Joint points
//! are computed once and shared by both neighbours. A voussoir is its intrados polyline
//! (`arc_segments` segments; a pointed keystone also takes the apex) plus its extrados
//! polyline. Where the springing joint is inclined (segmental arch), the top block of each
//! pier is a skewback whose top follows the joint.

use std::f64::consts::PI;

use serde::Deserialize;

use super::common::*;
use super::{GenError, GeneratedBlock};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    pub shape: String,
    pub span: f64,
    pub thickness: f64,
    pub voussoirs: usize,
    pub rise: Option<f64>,
    pub pointed_radius: Option<f64>,
    pub pier_height: f64,
    pub pier_width: Option<f64>,
    pub pier_courses: usize,
    pub base: bool,
    pub base_width: Option<f64>,
    pub arc_segments: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            shape: "semicircular".into(),
            span: 4.0,
            thickness: 0.4,
            voussoirs: 13,
            rise: None,
            pointed_radius: None,
            pier_height: 2.0,
            pier_width: None,
            pier_courses: 4,
            base: true,
            base_width: None,
            arc_segments: 1,
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    ("shape", "\"semicircular\", \"pointed\" or \"segmental\""),
    (
        "span",
        "the clear span between the intrados springings in m, > 0",
    ),
    (
        "thickness",
        "the radial thickness of the voussoirs in m, > 0",
    ),
    ("voussoirs", "the number of voussoirs, an integer >= 2"),
    (
        "rise",
        "the rise of a segmental arch in m, 0 < rise < span/2",
    ),
    (
        "pointed_radius",
        "the radius of the arcs of a pointed arch in m, > span/2",
    ),
    ("pier_height", "the height of the piers in m, >= 0"),
    ("pier_width", "the width of the piers in m, > 0"),
    (
        "pier_courses",
        "the number of blocks in each pier, an integer >= 1",
    ),
    ("base", "true or false (a fixed base under both piers)"),
    (
        "base_width",
        "the width of the fixed base in m, centred under the arch, at least the piers' outer width",
    ),
    (
        "arc_segments",
        "the number of straight segments per voussoir face, an integer >= 1",
    ),
];

#[derive(Clone, Copy, PartialEq)]
enum Side {
    Left,
    Crown,
    Right,
}

/// Unit vector at angle `a`, exact at 0 and π.
fn dir(a: f64) -> P {
    if (a - PI).abs() < 1e-14 {
        [-1.0, 0.0]
    } else if a.abs() < 1e-14 {
        [1.0, 0.0]
    } else {
        [a.cos(), a.sin()]
    }
}

fn at(c: P, r: f64, a: f64) -> P {
    let d = dir(a);
    [c[0] + r * d[0], c[1] + r * d[1]]
}

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("arch", params, KEYS)?;
    let s = positive("span", p.span, "m")?;
    let t = positive("thickness", p.thickness, "m")?;
    if p.voussoirs < 2 {
        return Err(gen_err(
            Some("voussoirs"),
            format!("voussoirs must be at least 2, got {}", p.voussoirs),
            "give voussoirs >= 2",
        ));
    }
    let n = p.voussoirs;
    let m = count("arc_segments", p.arc_segments)?;
    let nc = count("pier_courses", p.pier_courses)?;
    let hp = non_negative("pier_height", p.pier_height, "m")?;
    let pw = positive("pier_width", p.pier_width.unwrap_or(t), "m")?;
    check_count("voussoirs", n as f64 + 2.0 * nc as f64 + 1.0)?;
    if (n as f64) * (m as f64) > 1e7 {
        return Err(gen_err(
            Some("arc_segments"),
            format!("{n} voussoirs x {m} arc segments is too many vertices"),
            "give fewer arc_segments",
        ));
    }
    let ys = hp;
    // Faces: centres (left, right), intrados radius, springing angle (left), apex angles
    // (left circle) of the intrados and extrados.
    let (cl, cr, ri, a_spring, apex_i, apex_e, same_centre);
    match p.shape.as_str() {
        "semicircular" | "pointed" | "segmental" => {}
        other => {
            return Err(gen_err(
                Some("shape"),
                format!("unknown arch shape '{other}'"),
                "give shape = \"semicircular\", \"pointed\" or \"segmental\"",
            ))
        }
    }
    if p.shape != "segmental" && p.rise.is_some() {
        return Err(gen_err(
            Some("rise"),
            "rise applies to segmental arches only",
            "remove rise or set shape = \"segmental\"",
        ));
    }
    if p.shape != "pointed" && p.pointed_radius.is_some() {
        return Err(gen_err(
            Some("pointed_radius"),
            "pointed_radius applies to pointed arches only",
            "remove pointed_radius or set shape = \"pointed\"",
        ));
    }
    match p.shape.as_str() {
        "semicircular" => {
            cl = [0.0, ys];
            cr = cl;
            ri = 0.5 * s;
            a_spring = PI;
            apex_i = 0.5 * PI;
            apex_e = 0.5 * PI;
            same_centre = true;
        }
        "segmental" => {
            let r = positive("rise", p.rise.unwrap_or(0.25 * s), "m")?;
            if r >= 0.5 * s {
                return Err(gen_err(
                    Some("rise"),
                    format!("rise {r} m must be less than span/2 = {} m", 0.5 * s),
                    format!(
                        "give rise < {} (a semicircular arch has rise = span/2)",
                        0.5 * s
                    ),
                ));
            }
            let rad = (0.25 * s * s + r * r) / (2.0 * r);
            cl = [0.0, ys + r - rad];
            cr = cl;
            ri = rad;
            a_spring = 0.5 * PI + (0.5 * s / rad).asin();
            apex_i = 0.5 * PI;
            apex_e = 0.5 * PI;
            same_centre = true;
        }
        _ => {
            let rho = positive("pointed_radius", p.pointed_radius.unwrap_or(s), "m")?;
            if rho <= 0.5 * s * (1.0 + 1e-9) {
                return Err(gen_err(
                    Some("pointed_radius"),
                    format!(
                        "pointed_radius {rho} m must be more than span/2 = {} m",
                        0.5 * s
                    ),
                    format!(
                        "give pointed_radius > {} (default = span, an equilateral arch)",
                        0.5 * s
                    ),
                ));
            }
            cl = [rho - 0.5 * s, ys];
            cr = [0.5 * s - rho, ys];
            ri = rho;
            a_spring = PI;
            apex_i = ((0.5 * s - rho) / rho).acos();
            apex_e = ((0.5 * s - rho) / (rho + t)).acos();
            same_centre = false;
        }
    }
    let re = ri + t;
    let beta = a_spring - apex_i;
    // Right-circle angles are mirrors: θ_R = π − θ_L.
    let joints: Vec<(Side, f64)> = (0..=n)
        .map(|j| {
            let u = 2.0 * beta * j as f64 / n as f64;
            if 2 * j == n {
                (Side::Crown, 0.5 * PI)
            } else if 2 * j < n {
                (Side::Left, a_spring - u)
            } else {
                (Side::Right, PI - apex_i - (u - beta))
            }
        })
        .collect();
    let apex_pt = |r: f64, a: f64| -> P { [0.0, cl[1] + r * a.sin()] };
    let joint_pt = |j: usize, outer: bool| -> P {
        let (side, a) = joints[j];
        let r = if outer { re } else { ri };
        if j == 0 && !outer {
            return [-0.5 * s, ys];
        }
        if j == n && !outer {
            return [0.5 * s, ys];
        }
        if j == 0 || j == n {
            let base = joint_pt_inner(j, s, ys);
            let d = dir(a);
            return [base[0] + t * d[0], base[1] + t * d[1]];
        }
        match side {
            Side::Left => at(cl, r, a),
            Side::Right => at(cr, r, a),
            Side::Crown => {
                if same_centre {
                    [0.0, cl[1] + r]
                } else {
                    apex_pt(r, if outer { apex_e } else { apex_i })
                }
            }
        }
    };
    let inner: Vec<P> = (0..=n).map(|j| joint_pt(j, false)).collect();
    let outer: Vec<P> = (0..=n).map(|j| joint_pt(j, true)).collect();
    // Polyline along one face from joint j to joint j+1, endpoints included.
    let face = |j: usize, is_outer: bool| -> Vec<P> {
        let (r, apex, ends) = if is_outer {
            (re, apex_e, &outer)
        } else {
            (ri, apex_i, &inner)
        };
        let (s0, a0) = joints[j];
        let (s1, a1) = joints[j + 1];
        let mut pts = vec![ends[j]];
        if same_centre {
            for k in 1..m {
                pts.push(at(cl, r, a0 + (a1 - a0) * k as f64 / m as f64));
            }
        } else {
            let half = m.div_ceil(2);
            if s0 == Side::Left {
                let end = if s1 == Side::Left { a1 } else { apex };
                let mm = if s1 == Side::Right { half } else { m };
                for k in 1..mm {
                    pts.push(at(cl, r, a0 + (end - a0) * k as f64 / mm as f64));
                }
                if s1 == Side::Right {
                    pts.push(apex_pt(r, apex));
                }
            }
            if s1 == Side::Right {
                let start = if s0 == Side::Right { a0 } else { PI - apex };
                let mm = if s0 == Side::Left { half } else { m };
                for k in 1..mm {
                    pts.push(at(cr, r, start + (a1 - start) * k as f64 / mm as f64));
                }
            }
        }
        pts.push(ends[j + 1]);
        pts
    };
    let mut out = Vec::new();
    // Piers / springers.
    let xl = -0.5 * s - pw;
    let xr = -0.5 * s;
    let inclined = (a_spring - PI).abs() > 1e-9;
    let tol = 1e-9 * s;
    if inclined && outer[0][0] < xl - tol {
        return Err(gen_err(
            Some("pier_width"),
            format!(
                "pier_width {pw} m is narrower than the springing joint ({} m wide)",
                xr - outer[0][0]
            ),
            format!("give pier_width >= {:.6}", xr - outer[0][0]),
        ));
    }
    if !inclined && pw < t * (1.0 - 1e-9) {
        return Err(gen_err(
            Some("pier_width"),
            format!("pier_width {pw} m is narrower than the springing joint ({t} m)"),
            format!("give pier_width >= {t}"),
        ));
    }
    // Top block of a support whose top is the springing joint, from height y0.
    let top_block = |y0: f64, right: bool| -> Vec<P> {
        if !right {
            let (i0, e0) = (inner[0], outer[0]);
            let mut v = vec![[xl, y0], [xr, y0], i0, e0];
            if inclined && e0[0] > xl + tol {
                v.push([xl, e0[1]]);
            } else if !inclined {
                v = rect(xl, y0, xr, ys);
            }
            v
        } else {
            let (i0, e0) = (inner[n], outer[n]);
            let (xa, xb) = (0.5 * s, 0.5 * s + pw);
            if !inclined {
                return rect(xa, y0, xb, ys);
            }
            let mut v = vec![[xa, y0], [xb, y0]];
            if e0[0] < xb - tol {
                v.push([xb, e0[1]]);
            }
            v.push(e0);
            v.push(i0);
            v
        }
    };
    if hp > 0.0 {
        if p.base {
            // default: one pier width beyond each pier; wider where blocks that topple
            // off the piers must land on it (a collapse under ground motion)
            let outer = 0.5 * s + pw;
            let half = match p.base_width {
                None => outer + pw,
                Some(w) => {
                    let w = positive("base_width", w, "m")?;
                    if 0.5 * w < outer {
                        return Err(gen_err(
                            Some("base_width"),
                            format!(
                                "base_width {w} m is narrower than the piers ({} m)",
                                2.0 * outer
                            ),
                            format!("give base_width >= {}", 2.0 * outer),
                        ));
                    }
                    0.5 * w
                }
            };
            out.push(block("base", rect(-half, -pw, half, 0.0), true));
        }
        let yk: Vec<f64> = (0..=nc)
            .map(|k| {
                if k == nc {
                    ys
                } else {
                    ys * k as f64 / nc as f64
                }
            })
            .collect();
        for (side, x0, x1) in [("l", xl, xr), ("r", 0.5 * s, 0.5 * s + pw)] {
            for k in 0..nc {
                let v = if k + 1 == nc {
                    top_block(yk[k], side == "r")
                } else {
                    rect(x0, yk[k], x1, yk[k + 1])
                };
                out.push(block(format!("pier_{side}_{}", k + 1), v, false));
            }
        }
    } else {
        out.push(block("spring_l", top_block(-t, false), true));
        out.push(block("spring_r", top_block(-t, true), true));
    }
    for j in 0..n {
        let mut v = face(j, false);
        let mut e = face(j, true);
        e.reverse();
        v.extend(e);
        out.push(block(format!("v{}", j + 1), v, false));
    }
    Ok(out)
}

/// Intrados springing points (exact).
fn joint_pt_inner(j: usize, s: f64, ys: f64) -> P {
    if j == 0 {
        [-0.5 * s, ys]
    } else {
        [0.5 * s, ys]
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    fn check_arch(src: &str, n: usize, piers: usize, t: f64) {
        let b = run("arch", src);
        check_blocks(&b);
        let fixed = b.iter().filter(|x| x.fixed).count();
        assert_eq!(b.len(), n + piers + fixed, "{src}");
        for j in 1..n {
            let l = shared_length(
                &find(&b, &format!("v{j}")).vertices,
                &find(&b, &format!("v{}", j + 1)).vertices,
            );
            assert!(l > 0.999 * t, "{src}: joint {j} length {l}");
        }
        // the springing voussoirs rest on their supports along the whole joint
        let (sl, sr) = if piers > 0 {
            (
                format!("pier_l_{}", piers / 2),
                format!("pier_r_{}", piers / 2),
            )
        } else {
            ("spring_l".into(), "spring_r".into())
        };
        for (v, s) in [("v1".to_string(), sl), (format!("v{n}"), sr)] {
            let l = shared_length(&find(&b, &v).vertices, &find(&b, &s).vertices);
            assert!((l - t).abs() < 1e-9, "{src}: {v} on {s}: {l}");
        }
        assert_connected(&b, 1e-6);
    }

    #[test]
    fn arch_shapes() {
        check_arch("", 13, 8, 0.4);
        check_arch("voussoirs = 12\narc_segments = 4", 12, 8, 0.4);
        check_arch("shape = \"pointed\"", 13, 8, 0.4);
        check_arch(
            "shape = \"pointed\"\nvoussoirs = 8\narc_segments = 3\npointed_radius = 3.0",
            8,
            8,
            0.4,
        );
        check_arch("shape = \"segmental\"", 13, 8, 0.4);
        check_arch("shape = \"segmental\"\nrise = 0.5\nvoussoirs = 6\narc_segments = 2\npier_width = 0.6\npier_courses = 3", 6, 6, 0.4);
        check_arch("pier_height = 0", 13, 0, 0.4);
        check_arch(
            "pier_height = 0\nshape = \"segmental\"\nthickness = 0.3",
            13,
            0,
            0.3,
        );
        check_arch(
            "pier_height = 0\nshape = \"pointed\"\nvoussoirs = 10",
            10,
            0,
            0.4,
        );
        check_arch(
            "base = false\npier_width = 1.0\nspan = 10\nthickness = 0.5\nvoussoirs = 21",
            21,
            8,
            0.5,
        );
    }

    #[test]
    fn arch_area_converges_to_the_ring() {
        // semicircular, many segments: half annulus
        let b = run("arch", "arc_segments = 64\npier_height = 0");
        let a = total_area(&b[2..]);
        let exact = 0.5 * std::f64::consts::PI * (2.4f64.powi(2) - 2.0f64.powi(2));
        assert!((a - exact).abs() < 1e-3 * exact, "{a} vs {exact}");
        // segmental: rise 1 on span 4: R = 2.5, half angle asin(0.8)
        let b = run(
            "arch",
            "shape = \"segmental\"\nrise = 1.0\narc_segments = 64\npier_height = 0",
        );
        let a = total_area(&b[2..]);
        let exact = (0.8f64).asin() * (2.9f64.powi(2) - 2.5f64.powi(2));
        assert!((a - exact).abs() < 1e-3 * exact, "{a} vs {exact}");
        // springing of a semicircular arch is horizontal and shared exactly with the pier
        let b = run("arch", "");
        let v1 = &find(&b, "v1").vertices;
        assert_eq!(v1[0], [-2.0, 2.0]);
        assert!(v1.contains(&[-2.4, 2.0]));
    }

    #[test]
    fn arch_bad_parameters() {
        assert_err_key("arch", "shape = \"gothic\"", "shape");
        assert_err_key("arch", "span = 0", "span");
        assert_err_key("arch", "thickness = -1", "thickness");
        assert_err_key("arch", "voussoirs = 1", "voussoirs");
        assert_err_key("arch", "shape = \"segmental\"\nrise = 2.0", "rise");
        assert_err_key("arch", "shape = \"segmental\"\nrise = 0", "rise");
        assert_err_key("arch", "rise = 1.0", "rise");
        assert_err_key(
            "arch",
            "shape = \"pointed\"\npointed_radius = 2.0",
            "pointed_radius",
        );
        assert_err_key("arch", "pier_height = -1", "pier_height");
        assert_err_key("arch", "pier_width = 0.2", "pier_width");
        assert_err_key("arch", "pier_courses = 0", "pier_courses");
        assert_err_key("arch", "arc_segments = 0", "arc_segments");
        assert_err_key("arch", "voussoir = 9", "voussoir");
        assert_err_key("arch", "voussoirs = 3000000", "voussoirs");
    }
}
