//! The deformable running-bond wall under its own weight in one increment (issue 4, the
//! stall of the static iterations; docs/decisions/
//! 0007-free-motion-constants.md): the built-in `wall` example with N courses of N bricks, `lateral = 0`,
//! `load_steps = 1`, `tolerance = 1e-8`. At N = 60 the iterations used to stall at an
//! out-of-balance force of 3.5·10⁻⁵ of the load (bricks near the top held only by
//! slipping bed joints and open head joints, `Driver::free_motion` in
//! src/analysis/statics.rs); N = 30, 40 and 50 converged.
//!
//! The settlement of the top course's middle brick (its nodes' mean vertical motion) is
//! compared with the stack-of-blocks closed form of docs/validation.md V9 applied to one
//! column of the wall: the bed joints j = 1 … N (the base's included) carry the courses
//! above them, (N − j + 1) γ h_b per unit area, and shorten by that times h / Eₙ; the
//! bricks shorten under σ_yy(z) = −γ (H − z). The wall is in plane stress: with its
//! sides free (σ_xx = 0) a brick's vertical strain is σ_yy / E, with its Poisson
//! expansion fully restrained by the bed joints (ε_xx = 0) it is σ_yy (1 − ν²) / E. The
//! dry joints restrain it partly (they slip near the top, the head joints open), so
//! the settlement lies between the two; ν = 0.2 puts 4 % of the bricks' share between
//! them. 0.5 % either side is the discretisation (validation_stack.rs: the CST's
//! linear interpolation of the quadratic displacement leaves 0.15 %).

mod common;
use dfem::analysis::Status;
use dfem::material::young_poisson;

/// The built-in wall example scaled to n × n deformable bricks, gravity alone in one
/// increment at tolerance 1e-8.
fn scene(n: usize) -> String {
    dfem::scene::examples::get("wall")
        .unwrap()
        .replace("courses = 10", &format!("courses = {n}"))
        .replace("bricks_per_course = 5", &format!("bricks_per_course = {n}"))
        .replace(
            "type = \"static\"",
            "type = \"static\"\nlateral = 0.0\nload_steps = 1\ngravity_steps = 1\ntolerance = 1e-8",
        )
}

/// Settles to equilibrium and to the closed-form bounds; returns the counters.
fn check(n: usize) -> dfem::analysis::Stats {
    let sc = common::scene(&scene(n));
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{n} x {n} wall under gravity");
    let mat = &sc.materials[0];
    let joint = &sc.joints[0];
    let gamma = mat.unit_weight;
    let (e, nu) = young_poisson(mat.lame_lambda, mat.lame_mu);
    let hb = 0.2;
    let height = n as f64 * hb;
    // the top course's brick nearest the middle of the wall
    let mid = 0.5 * n as f64 * 0.4;
    let (top, _) = mesh
        .blocks
        .iter()
        .enumerate()
        .filter(|(_, b)| (b.centroid[1] - (height - 0.5 * hb)).abs() < 1e-6)
        .map(|(i, b)| (i, (b.centroid[0] - mid).abs()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a top course");
    let (d, _) = dfem::analysis::outcome_motion(&mesh, top, &out);
    let settlement = -d[1];
    let joints: f64 = (1..=n)
        .map(|j| (n - j + 1) as f64 * gamma * hb * joint.band / joint.normal_modulus)
        .sum();
    // ∫₀^z γ (H − ζ) / E dζ averaged over the top brick, z from the base
    let z0 = height - hb;
    let mean = height * (z0 + hb / 2.0) - (z0 * z0 + z0 * hb + hb * hb / 3.0) / 2.0;
    let bricks = gamma / e * mean;
    let (lo, hi) = (joints + (1.0 - nu * nu) * bricks, joints + bricks);
    eprintln!(
        "{n} x {n}: {} iterations, settlement {settlement:.6e} m, closed form between \
         {lo:.6e} (restrained) and {hi:.6e} m (free)",
        out.stats.iterations
    );
    assert!(
        settlement > 0.995 * lo && settlement < 1.005 * hi,
        "settlement {settlement:.6e} m outside [{lo:.6e}, {hi:.6e}]"
    );
    out.stats
}

/// The 30 × 30 wall converged before the stall was cured and must still.
#[test]
fn wall_30_settles_under_gravity() {
    check(30);
}

/// The 60 × 60 wall (43,082 unknowns) that stalled at 3.5·10⁻⁵ of the load: 59
/// iterations, about 25 s in release on the 2-core machine under load (no smaller wall
/// that stalled was found: 60 × 24, 60 × 40, 70 × 30 and 50 × 50 converged before).
#[test]
fn wall_60_settles_under_gravity() {
    let stats = check(60);
    // the cure is what converged it: without free motions this wall stalls
    assert!(stats.free_motions > 0, "no free motion: {stats:?}");
}
