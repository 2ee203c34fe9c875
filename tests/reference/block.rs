//! Closed forms for a single rigid block (BENCHMARKS V1 and V2). Written for dfem's
//! validation tests; no dfem code.
//!
//! * V1: Hoek and Bray, "Rock Slope Engineering" (1977/1981), the four modes of a block of
//!   breadth b (along the slope) and height d on an incline α with friction φ, under
//!   gravity only: sliding iff α > φ, toppling iff b/d < tan α (the weight's line of
//!   action falls outside the base).
//! * V2: the same block under gravity plus a horizontal body force λ·W pointing down the
//!   slope (the "tilting table", pseudo-static). The resultant of W and λW is inclined
//!   by atan λ to the vertical, so the block behaves as on an incline α + atan λ under
//!   gravity alone: it slides when α + atan λ > φ, i.e. λ > tan(φ − α), and topples when
//!   α + atan λ > atan(b/d), i.e. λ > tan(atan(b/d) − α) = (b/d − tan α)/(1 + (b/d) tan α).
//!   On a flat base (α = 0): λ_c = min(b/d, tan φ). A column of equal stacked blocks with
//!   the same friction behaves as one block of the column's total height for toppling
//!   (it rocks about its toe) and slides at its base at tan φ (every joint carries
//!   the same ratio of shear to normal force, λ).
//!
//! Angles in degrees, ratios dimensionless. Equalities are counted as stable (failure
//! needs a strict inequality).

#![allow(dead_code)]

/// Mode of a block (Hoek and Bray 1977).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Neither slides nor topples.
    Stable,
    /// Slides (α > φ), does not topple.
    Sliding,
    /// Topples (b/d < tan α), does not slide.
    Toppling,
    /// Both.
    SlidingToppling,
}

fn mode_of(slides: bool, topples: bool) -> Mode {
    match (slides, topples) {
        (false, false) => Mode::Stable,
        (true, false) => Mode::Sliding,
        (false, true) => Mode::Toppling,
        (true, true) => Mode::SlidingToppling,
    }
}

/// Mode of a block of breadth b and height d (`b_over_d` = b/d) on an incline of
/// `alpha_deg` with friction angle `phi_deg`, gravity only. Source: Hoek and Bray (1977),
/// BENCHMARKS V1: sliding iff α > φ, toppling iff b/d < tan α.
pub fn hoek_bray_mode(alpha_deg: f64, phi_deg: f64, b_over_d: f64) -> Mode {
    let slides = alpha_deg > phi_deg;
    let topples = b_over_d < alpha_deg.to_radians().tan();
    mode_of(slides, topples)
}

/// Horizontal coefficient λ (force λ·W, down the slope) above which a block on an
/// incline `alpha_deg` slides: tan(φ − α) (negative when it slides under gravity alone).
/// Source: BENCHMARKS V2 (equivalent-incline argument in the module header).
pub fn incline_sliding_coefficient(alpha_deg: f64, phi_deg: f64) -> f64 {
    (phi_deg - alpha_deg).to_radians().tan()
}

/// Horizontal coefficient λ above which a block of ratio b/d on an incline `alpha_deg`
/// topples: (b/d − tan α)/(1 + (b/d) tan α). Source: BENCHMARKS V2.
pub fn incline_toppling_coefficient(alpha_deg: f64, b_over_d: f64) -> f64 {
    let ta = alpha_deg.to_radians().tan();
    (b_over_d - ta) / (1.0 + b_over_d * ta)
}

/// Critical horizontal coefficient of a block on an incline (λ·W down the slope) and
/// the mode that starts there: min(tan(φ − α), (b/d − tan α)/(1 + (b/d) tan α)),
/// `SlidingToppling` when the two are equal to 1e-12. Source: BENCHMARKS V2.
pub fn incline_critical_coefficient(alpha_deg: f64, phi_deg: f64, b_over_d: f64) -> (f64, Mode) {
    let s = incline_sliding_coefficient(alpha_deg, phi_deg);
    let t = incline_toppling_coefficient(alpha_deg, b_over_d);
    if (s - t).abs() <= 1e-12 * (1.0 + s.abs()) {
        (s, Mode::SlidingToppling)
    } else if s < t {
        (s, Mode::Sliding)
    } else {
        (t, Mode::Toppling)
    }
}

/// Critical horizontal coefficient of a block (or a column of equal stacked blocks, with
/// b/d the ratio of the column) on a flat fixed base: min(b/d, tan φ) and the mode
/// (`Toppling` if b/d < tan φ, `Sliding` if tan φ < b/d). Source: BENCHMARKS V2.
pub fn flat_critical_coefficient(b_over_d: f64, phi_deg: f64) -> (f64, Mode) {
    incline_critical_coefficient(0.0, phi_deg, b_over_d)
}

/// Mode of a block on an incline under a horizontal coefficient λ (down the slope):
/// the gravity-only mode on the equivalent incline α + atan λ. Source: BENCHMARKS V2.
pub fn mode_under_coefficient(alpha_deg: f64, phi_deg: f64, b_over_d: f64, lambda: f64) -> Mode {
    hoek_bray_mode(alpha_deg + lambda.atan().to_degrees(), phi_deg, b_over_d)
}
