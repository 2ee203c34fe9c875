//! `slope`: a toppling rock slope of columns on a stepped base (Goodman and Bray 1976;
//! Hoek and Bray, Rock Slope Engineering; docs/validation.md V7). The defaults build the
//! worked example.
//!
//! Geometry. The toppling joints (the column faces) dip `joint_dip` = 60° into the slope,
//! so the cross joints that form the column bases dip ψ_p = 90° − 60° = 30° toward the
//! face. Work in the frame of the base planes: x' along the base planes, pointing into the
//! slope and up, x' = (cos ψ_p, sin ψ_p); y' normal to them, y' = (−sin ψ_p, cos ψ_p),
//! which is the column axis (it leans toward the face: toppling). Column i (1 from the
//! toe) is the rectangle
//!     x' ∈ [(i−1) Δx, i Δx],  y' ∈ [(i−1) b, (i−1) b + y_i],
//! Δx = `column_width`, b = `step`, y_i = `heights[i−1]`: each base is one step b higher
//! (in y') than the one below, so the column's lower right face leans on the riser of
//! the next step. The toe of column 1 is at the origin; the fixed block "base" is the
//! staircase (treads at ψ_p, risers along y') closed below, with a horizontal ground
//! in front of the toe.
//!
//! Check against the worked example (Hoek and Bray's constants a₁ = Δx tan(ψ_f − ψ_p),
//! a₂ = Δx tan(ψ_p − ψ_s), b = Δx tan(ψ_b − ψ_p), heights y_n = n (a₁ − b) below the
//! crest and y_n = y_{n−1} − a₂ − b above it):
//! * the base line through the step corners rises b per Δx in the x' frame, so it dips
//!   ψ_b = ψ_p + atan(b/Δx) = 30° + atan(0.1) = 35.71° (35.8° in the source, where
//!   b = 10 tan 5.8° = 1.016 m was rounded to 1.0 m);
//! * the tops of columns 1..10 rise b + (y_{n+1} − y_n) = 1 + 4 = 5 = a₁ per Δx, so the
//!   face is at ψ_p + atan(a₁/Δx) = 30° + 26.57° = 56.57° ≈ 56.6°;
//! * above the crest the tops change by b − 5.9 = −4.9 = −a₂ per Δx, so the upper slope
//!   is at ψ_p − atan(a₂/Δx) = 30° − 26.10° = 3.90° ≈ 4°.
//!
//! The tests measure these three angles on the generated blocks.

use serde::Deserialize;

use super::common::*;
use super::{GenError, GeneratedBlock};

/// Column heights of the worked example, from the toe (m).
pub const WORKED_EXAMPLE_HEIGHTS: [f64; 16] = [
    4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0, 32.0, 36.0, 40.0, 34.1, 28.2, 22.3, 16.4, 10.5, 4.6,
];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    pub column_width: f64,
    pub heights: Vec<f64>,
    pub joint_dip: f64,
    pub step: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            column_width: 10.0,
            heights: WORKED_EXAMPLE_HEIGHTS.to_vec(),
            joint_dip: 60.0,
            step: 1.0,
        }
    }
}

pub const KEYS: &[(&str, &str)] = &[
    (
        "column_width",
        "the column width Δx along the base planes in m, > 0",
    ),
    (
        "heights",
        "an array of column heights from the toe in m, each > 0",
    ),
    (
        "joint_dip",
        "the dip of the column faces into the slope in degrees, 0 < joint_dip <= 90",
    ),
    ("step", "the step b between successive bases in m, >= 0"),
];

pub fn generate(params: &toml::Table) -> Result<Vec<GeneratedBlock>, GenError> {
    let p: Params = parse_params("slope", params, KEYS)?;
    let dx = positive("column_width", p.column_width, "m")?;
    let b = non_negative("step", p.step, "m")?;
    let dip = p.joint_dip;
    if !(dip.is_finite() && dip > 0.0 && dip <= 90.0) {
        return Err(gen_err(
            Some("joint_dip"),
            format!("joint_dip must be in (0, 90] degrees, got {dip}"),
            "give 0 < joint_dip <= 90 (60 in the worked example)",
        ));
    }
    if p.heights.is_empty() {
        return Err(gen_err(
            Some("heights"),
            "heights is empty",
            "give at least one column height, e.g. heights = [4.0, 8.0, 12.0]",
        ));
    }
    check_count("heights", p.heights.len() as f64 + 1.0)?;
    for (i, &h) in p.heights.iter().enumerate() {
        if !(h.is_finite() && h > 0.0) {
            return Err(gen_err(
                Some("heights"),
                format!("height {} (column {}) must be a positive number", h, i + 1),
                "give every column height > 0 (m)",
            ));
        }
    }
    let psi = (90.0 - dip).to_radians();
    let (sn, cs) = psi.sin_cos();
    // base-plane frame -> global
    let g = |xp: f64, yp: f64| -> P { [xp * cs - yp * sn, xp * sn + yp * cs] };
    let n = p.heights.len();
    let xs: Vec<f64> = (0..=n).map(|i| i as f64 * dx).collect();
    let steps: Vec<f64> = (0..n).map(|i| i as f64 * b).collect();
    let mut out = Vec::with_capacity(n + 1);
    // staircase from the toe to the heel
    let mut stair: Vec<P> = Vec::new();
    for i in 0..n {
        if i == 0 || b > 0.0 {
            stair.push(g(xs[i], steps[i]));
        }
        stair.push(g(xs[i + 1], steps[i]));
    }
    // a tread/riser pair is collinear only when b = 0: then only the ends remain
    if b == 0.0 {
        stair = vec![g(xs[0], 0.0), g(xs[n], 0.0)];
    }
    let heel = *stair.last().unwrap();
    let depth = dx.max(0.1 * heel[1]);
    let left = -dx;
    let mut base = vec![[left, -depth], [heel[0], -depth]];
    if heel[1] > -depth {
        base.push(heel);
    }
    for q in stair.iter().rev().skip(1) {
        base.push(*q);
    }
    base.push([left, 0.0]);
    let base = clean(base, 1e-12 * dx).ok_or_else(|| {
        gen_err(
            None,
            "the slope base is degenerate",
            "check column_width and heights",
        )
    })?;
    out.push(block("base", base, true));
    for (i, &h) in p.heights.iter().enumerate() {
        let v = vec![
            g(xs[i], steps[i]),
            g(xs[i + 1], steps[i]),
            g(xs[i + 1], steps[i] + h),
            g(xs[i], steps[i] + h),
        ];
        out.push(block(format!("col{}", i + 1), v, false));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;

    fn angle(a: [f64; 2], b: [f64; 2]) -> f64 {
        (b[1] - a[1]).atan2(b[0] - a[0]).to_degrees()
    }

    #[test]
    fn worked_example_geometry() {
        let b = run("slope", "");
        assert_eq!(b.len(), 17);
        check_blocks(&b);
        assert!(find(&b, "base").fixed);
        let col = |i: usize| &find(&b, &format!("col{i}")).vertices;
        // overall base line through the toe corners of columns 1 and 16
        let base = angle(col(1)[0], col(16)[0]);
        assert!(
            (base - 35.71).abs() < 0.01 && (base - 35.8).abs() < 0.1,
            "base {base}"
        );
        // face: top toe-side corners of columns 1..10
        let face = angle(col(1)[3], col(10)[3]);
        assert!((face - 56.6).abs() < 0.05, "face {face}");
        let crest = angle(col(10)[3], col(16)[3]);
        assert!((crest - 4.0).abs() < 0.15, "crest {crest}");
        // the columns lean 30° from vertical (joints dip 60°)
        let lean = angle(col(5)[0], col(5)[3]);
        assert!((lean - 120.0).abs() < 1e-9);
        // contacts: each column on its tread (10 m) and on the next column / riser
        for i in 1..=16 {
            let l = shared_length(col(i), &find(&b, "base").vertices);
            let riser = if i < 16 { 1.0 } else { 0.0 };
            assert!((l - (10.0 + riser)).abs() < 1e-9, "col{i} on base: {l}");
        }
        let hs = super::WORKED_EXAMPLE_HEIGHTS;
        for i in 1..16 {
            let l = shared_length(col(i), col(i + 1));
            let expect = (hs[i - 1] - 1.0).min(hs[i]);
            assert!(
                (l - expect).abs() < 1e-9,
                "col{i}-col{}: {l} vs {expect}",
                i + 1
            );
        }
        let area: f64 = total_area(&b[1..]);
        assert!((area - 10.0 * hs.iter().sum::<f64>()).abs() < 1e-6);
    }

    #[test]
    fn other_slopes() {
        let b = run(
            "slope",
            "column_width = 2.0\nheights = [3.0, 5.0, 6.0, 2.0]\njoint_dip = 75\nstep = 0.0",
        );
        assert_eq!(b.len(), 5);
        check_blocks(&b);
        assert_connected(&b, 1e-6);
        let b = run("slope", "heights = [10.0]\njoint_dip = 90");
        check_blocks(&b);
    }

    #[test]
    fn slope_bad_parameters() {
        assert_err_key("slope", "column_width = 0", "column_width");
        assert_err_key("slope", "heights = []", "heights");
        assert_err_key("slope", "heights = [1.0, -2.0]", "heights");
        assert_err_key("slope", "heights = [1.0, \"x\"]", "heights");
        assert_err_key("slope", "joint_dip = 0", "joint_dip");
        assert_err_key("slope", "joint_dip = 100", "joint_dip");
        assert_err_key("slope", "step = -1", "step");
        assert_err_key("slope", "width = 3", "width");
    }
}
