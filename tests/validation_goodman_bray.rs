//! Toppling rock slope (Goodman and Bray 1976; Hoek and Bray, Rock Slope Engineering;
//! docs/validation.md V7): 16 columns on a stepped base, the worked example's geometry from
//! dfem's `slope` generator. Limit equilibrium (the block-by-block recursion, written
//! independently in `tests/reference/goodman_bray.rs`) gives the friction angle at which
//! the slope just stands: 38.16° (38.15° in the source). dfem's critical friction angle,
//! bracketed by bisection over φ (the same φ on faces and bases), must agree within 1°.

mod common;
#[path = "reference/mod.rs"]
mod reference;

use dfem::analysis::Status;
use reference::goodman_bray::{goodman_bray_limit_friction, ToppleSlope};

fn scene(phi: f64) -> String {
    format!(
        r#"
[[material]]
name = "rock"
lame_lambda = 10e9
lame_mu = 10e9
unit_weight = 25e3
[[joint]]
name = "joints"
normal_modulus = 10e9
shear_modulus = 4e9
band = 0.01
friction_angle = {phi}
[[generate]]
type = "slope"
material = "rock"
kind = "rigid"
[analysis]
type = "static"
load_steps = 5
"#
    )
}

fn stands(phi: f64) -> bool {
    let sc = common::scene(&scene(phi));
    let (_, out) = common::solve(&sc);
    matches!(out.status, Status::Stable)
}

#[test]
fn critical_friction_angle_matches_limit_equilibrium() {
    let reference = goodman_bray_limit_friction(&ToppleSlope::worked_example());
    let (mut lo, mut hi) = (reference - 6.0, reference + 6.0);
    assert!(stands(hi), "the slope must stand at φ = {hi}");
    assert!(!stands(lo), "the slope must fail at φ = {lo}");
    while hi - lo > 0.1 {
        let mid = 0.5 * (lo + hi);
        if stands(mid) {
            hi = mid
        } else {
            lo = mid
        }
    }
    let phi = 0.5 * (lo + hi);
    eprintln!("dfem critical φ = {phi:.2}°, limit equilibrium {reference:.2}°");
    assert!(
        (phi - reference).abs() < 1.0,
        "dfem {phi}°, limit equilibrium {reference}°"
    );
}
