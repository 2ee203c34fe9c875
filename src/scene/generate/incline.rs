//! `incline`: one block on an inclined plane (Hoek and Bray 1977; docs/validation.md V1, V5).
//!
//! The fixed slope block has its top face from (0, 0) rising at α to
//! (L cos α, L sin α) (a triangle; a trapezoid 0.1 L thick at the toe when α < 5°).
//! The block "block", b along the slope and d high, sits on that face with its base
//! centred at mid-slope.

use serde::Deserialize;

use super::common::*;
use super::{GenError, GeneratedBlock};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// α, degrees.
    pub slope_angle: f64,
    /// b, along the slope, m.
    pub breadth: f64,
    /// d, normal to the slope, m.
    pub height: f64,
    /// L, length of the slope face, m (default b + 2 (b + d)).
    pub slope_length: Option<f64>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            slope_angle: 30.0,
            breadth: 1.0,
            height: 1.0,
            slope_length: None,
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    ("slope_angle", "an angle in degrees, 0 <= slope_angle < 90"),
    ("breadth", "the block's length along the slope in m, > 0"),
    ("height", "the block's height normal to the slope in m, > 0"),
    (
        "slope_length",
        "the length of the slope face in m, > breadth",
    ),
];

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("incline", params, KEYS)?;
    let alpha = p.slope_angle;
    if !(alpha.is_finite() && (0.0..90.0).contains(&alpha)) {
        return Err(gen_err(
            Some("slope_angle"),
            format!("slope_angle must be in [0, 90) degrees, got {alpha}"),
            "give 0 <= slope_angle < 90",
        ));
    }
    let b = positive("breadth", p.breadth, "m")?;
    let d = positive("height", p.height, "m")?;
    let l = match p.slope_length {
        None => b + 2.0 * (b + d),
        Some(l) => {
            let l = positive("slope_length", l, "m")?;
            if l <= b {
                return Err(gen_err(
                    Some("slope_length"),
                    format!("slope_length {l} m leaves no room for the block of breadth {b} m"),
                    format!("give slope_length > {b}"),
                ));
            }
            l
        }
    };
    let (s, c) = alpha.to_radians().sin_cos();
    let top = [l * c, l * s];
    let slope = if alpha >= 5.0 {
        vec![[0.0, 0.0], [top[0], 0.0], top]
    } else {
        let t = 0.1 * l;
        vec![[0.0, -t], [top[0], -t], top, [0.0, 0.0]]
    };
    let s0 = 0.5 * (l - b);
    let s1 = s0 + b;
    let (p0, p1) = ([s0 * c, s0 * s], [s1 * c, s1 * s]);
    let n = [-s * d, c * d];
    let blk = vec![
        p0,
        p1,
        [p1[0] + n[0], p1[1] + n[1]],
        [p0[0] + n[0], p0[1] + n[1]],
    ];
    Ok(vec![
        block("slope", slope, true),
        block("block", blk, false),
    ])
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    #[test]
    fn incline_default_and_variants() {
        for src in [
            "",
            "slope_angle = 0",
            "slope_angle = 3.0\nbreadth = 4\nheight = 12",
            "slope_angle = 45\nslope_length = 5",
        ] {
            let b = run("incline", src);
            assert_eq!(b.len(), 2);
            check_blocks(&b);
            assert!(b[0].fixed && !b[1].fixed);
            let bl = find(&b, "block");
            let len = shared_length(&bl.vertices, &find(&b, "slope").vertices);
            let breadth = if src.contains("breadth = 4") {
                4.0
            } else {
                1.0
            };
            assert!((len - breadth).abs() < 1e-9, "{src}: contact length {len}");
        }
        let b = run("incline", "breadth = 4\nheight = 12");
        let a = total_area(&b[1..]);
        assert!((a - 48.0).abs() < 1e-9);
    }

    #[test]
    fn incline_bad_parameters() {
        assert_err_key("incline", "slope_angle = 90", "slope_angle");
        assert_err_key("incline", "slope_angle = -1", "slope_angle");
        assert_err_key("incline", "breadth = 0", "breadth");
        assert_err_key("incline", "height = -2", "height");
        assert_err_key("incline", "slope_length = 0.5", "slope_length");
        assert_err_key("incline", "slop_angle = 30", "slop_angle");
        assert_err_key("incline", "breadth = \"wide\"", "breadth");
    }
}
