//! Numerical stress suite (issue "Reliability"): the same closed-form problems pushed to
//! extreme parameters. Every case must either converge to the answer it should or report a
//! failure with a reason; no NaN or infinity may reach the results. Each case prints one
//! row (parameter, expected, computed, error, iterations, factorizations, smallest pivot
//! ratio d_i/a_ii as a condition estimate) of the table in docs/stress.md:
//!
//!     cargo test --release --test stress -- --nocapture --include-ignored
//!
//! The long cases (deformable blocks, the widest sweeps) are behind `--ignored`.

mod common;
use dfem::analysis::{Outcome, Status};

/// Rows of the table, printed on stderr.
fn row(case: &str, param: &str, expected: f64, got: f64, out: &Outcome) {
    let s = &out.stats;
    eprintln!(
        "| {case} | {param} | {expected:.6e} | {got:.6e} | {:.2e} | {} | {} | {:.1e} |",
        common::rel_err(got, expected),
        s.iterations,
        s.factorizations,
        s.min_pivot_ratio
    );
}

/// No NaN or infinity anywhere in the results.
fn assert_finite(out: &Outcome) {
    assert!(out.u.iter().all(|v| v.is_finite()), "non-finite unknowns");
    assert!(out.node_disp.iter().flatten().all(|v| v.is_finite()));
    assert!(out.stress.iter().flatten().all(|v| v.is_finite()));
    assert!(out.contact_forces.iter().flatten().all(|v| v.is_finite()));
    assert!(out.load_factor.is_none_or(|l| l.is_finite()));
}

/// A block b × d (m) on a fixed base, joint friction φ (degrees), every length times
/// `scale` (the joint band too, so that the problem is geometrically similar).
fn tilting(b: f64, d: f64, phi: f64, kind: &str, scale: f64) -> String {
    let s = scale;
    let band = 0.01 * s * d.min(b).min(1.0);
    common::stone_and_dry_joint(20e9, 8e9, band, phi)
        + &format!(
            r#"
[[block]]
name = "base"
material = "stone"
support = "fixed"
vertices = [[{x0}, {y0}], [{x1}, {y0}], [{x1}, 0.0], [{x0}, 0.0]]
[[block]]
name = "box"
material = "stone"
kind = "{kind}"
vertices = [[0.0, 0.0], [{bs}, 0.0], [{bs}, {ds}], [0.0, {ds}]]
[analysis]
type = "capacity"
load_steps = 2
"#,
            x0 = -0.5 * b * s,
            x1 = 1.5 * b * s,
            y0 = -0.5 * d.min(b) * s,
            bs = b * s,
            ds = d * s,
        )
}

/// Capacity of the block: min(b/d, tan φ) within 1 % with the right mode (1 % is the
/// validation tolerance of the tilting test; the bracket is 1e-3).
fn tilting_case(case: &str, param: &str, b: f64, d: f64, phi: f64, kind: &str, scale: f64) {
    let sc = common::scene(&tilting(b, d, phi, kind, scale));
    let (_, out) = common::solve(&sc);
    assert_finite(&out);
    let Status::Failed { reason, .. } = &out.status else {
        panic!("{case} {param}: the block should fail under a growing lateral load");
    };
    assert!(!reason.is_empty());
    let lam = out.load_factor.expect("a capacity");
    let (topple, slide) = (b / d, phi.to_radians().tan());
    let (exact, mode) = if topple < slide {
        (topple, "toppling")
    } else {
        (slide, "sliding")
    };
    row(case, param, exact, lam, &out);
    if exact == 0.0 {
        // no friction: the block slides under the first lateral increment
        assert!(lam <= 1e-3, "{case} {param}: λ = {lam}, expected 0");
    } else {
        assert!(
            common::rel_err(lam, exact) < 0.01,
            "{case} {param}: λ = {lam}, expected {exact}"
        );
        assert_eq!(out.mechanism.as_ref().unwrap().mode, mode, "{case} {param}");
    }
}

#[test]
fn aspect_ratios_from_1_to_100_either_way() {
    for bd in [0.01f64, 0.05, 0.2, 1.0, 5.0, 20.0, 100.0] {
        tilting_case(
            "aspect",
            &format!("b/d = {bd}"),
            bd.min(1.0),
            1.0f64.min(1.0 / bd),
            30.0,
            "rigid",
            1.0,
        );
    }
}

#[test]
fn friction_angles_from_0_to_89_degrees() {
    for phi in [0.0, 1.0, 10.0, 26.0, 45.0, 70.0, 85.0, 89.0] {
        tilting_case(
            "friction",
            &format!("φ = {phi}°"),
            0.5,
            1.0,
            phi,
            "rigid",
            1.0,
        );
    }
}

#[test]
fn sizes_from_millimetres_to_kilometres() {
    for scale in [1e-3, 1e-1, 1.0, 1e1, 1e3] {
        tilting_case(
            "size",
            &format!("× {scale:e} m"),
            0.4,
            1.0,
            35.0,
            "rigid",
            scale,
        );
        tilting_case(
            "size",
            &format!("× {scale:e} m"),
            1.0,
            0.5,
            20.0,
            "rigid",
            scale,
        );
    }
}

#[test]
#[ignore = "deformable blocks at extreme aspect ratios and sizes: a few minutes"]
fn deformable_aspect_ratios_and_sizes() {
    for bd in [0.05f64, 0.2, 5.0, 20.0] {
        tilting_case(
            "aspect (deformable)",
            &format!("b/d = {bd}"),
            bd.min(1.0),
            1.0f64.min(1.0 / bd),
            30.0,
            "deformable",
            1.0,
        );
    }
    for scale in [1e-3, 1e3] {
        tilting_case(
            "size (deformable)",
            &format!("× {scale:e} m"),
            0.4,
            1.0,
            35.0,
            "deformable",
            scale,
        );
    }
}

/// A column of three deformable blocks 1 m × 0.5 m under gravity on a fixed base: the
/// top block's settlement is the sum of the joint closures below it plus the blocks'
/// shortening (tests/validation_stack.rs has the closed form's derivation; here the
/// joints' normal modulus runs from 10⁻⁶ to 10⁶ times the blocks' Young's modulus).
fn stack_case(ratio: f64) {
    const GAMMA: f64 = 25e3;
    const LAMBDA: f64 = 2e9;
    const MU: f64 = 3e9;
    const BAND: f64 = 0.01;
    const HB: f64 = 0.5;
    const N: usize = 3;
    let e = MU * (3.0 * LAMBDA + 2.0 * MU) / (LAMBDA + MU);
    let nu = LAMBDA / (2.0 * (LAMBDA + MU));
    let en = ratio * e;
    // shear springs soft against both (they would restrain the Poisson expansion that
    // the closed form leaves free)
    let gs = en.min(e) * 1e-4;
    let mut text = format!(
        r#"
[[material]]
name = "stone"
lame_lambda = {LAMBDA}
lame_mu = {MU}
unit_weight = {GAMMA}
[[joint]]
name = "bed"
normal_modulus = {en:e}
shear_modulus = {gs:e}
band = {BAND}
friction_angle = 30.0
[[block]]
name = "ground"
material = "stone"
support = "fixed"
vertices = [[-1.0, -1.0], [2.0, -1.0], [2.0, 0.0], [-1.0, 0.0]]
"#
    );
    for k in 0..N {
        let (y0, y1) = (k as f64 * HB, (k + 1) as f64 * HB);
        text += &format!("[[block]]\nname = \"s{k}\"\nmaterial = \"stone\"\nmesh_size = 0.125\nvertices = [[0.0, {y0}], [1.0, {y0}], [1.0, {y1}], [0.0, {y1}]]\n");
    }
    let sc = common::scene(&text);
    let (mesh, out) = common::solve(&sc);
    assert_finite(&out);
    assert!(
        matches!(out.status, Status::Stable),
        "ratio {ratio:e}: {:?}",
        out.status
    );
    // closed form for the top block's centroid: joints under weight above, plus the
    // plane-strain shortening under σ_yy(z) = −γ (H − z), averaged over the block
    let h_total = N as f64 * HB;
    let mut closure = 0.0;
    for j in 0..N {
        let above = (N - j) as f64 * HB * GAMMA; // N/m² on the joint
        closure += above * BAND / en;
    }
    let k = 1.0 - nu * nu;
    // v(z) = −(γ k / E)(H z − z²/2), averaged over the top block [z0, H]
    let z0 = h_total - HB;
    let avg = |z: f64| h_total * z * z / 2.0 - z * z * z / 6.0;
    let shortening = GAMMA * k / e * (avg(h_total) - avg(z0)) / HB;
    let expected = closure + shortening;
    // the top block is the last one (the ground is block 0)
    let got = -dfem::analysis::outcome_motion(&mesh, N, &out).0[1];
    row(
        "joint/block stiffness",
        &format!("Eₙ/E = {ratio:e}"),
        expected,
        got,
        &out,
    );
    assert!(
        common::rel_err(got, expected) < 0.01,
        "ratio {ratio:e}: settlement {got:e}, expected {expected:e}"
    );
}

#[test]
fn joint_to_block_stiffness_from_1e_minus_6_to_1e6() {
    for ratio in [1e-6, 1e-3, 1.0, 1e3, 1e6] {
        stack_case(ratio);
    }
}

#[test]
#[ignore = "every decade of the stiffness ratio"]
fn joint_to_block_stiffness_every_decade() {
    for p in -6..=6 {
        stack_case(10f64.powi(p));
    }
}
