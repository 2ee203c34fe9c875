//! The built-in tunnel in jointed rock (`dfem example tunnel`: a 20 m × 20 m rock mass
//! cut by two joint sets, a circular opening of radius 3 m, a fixed frame) under its own
//! weight, with gravity in 10 and in 50 increments (docs/decisions/
//! 0008-slope-line-search.md).
//!
//! Under gravity the elastic predictor of the first increment puts the rock above
//! mid-height in tension (it hangs from the top frame), so 273 of the 552 contacts open at
//! once and 44 blocks are left with no closed contact. No backtracked step length then
//! lowers the out-of-balance norm: the blocks fall until they touch, and the norm rises as
//! soon as they do. The opening pattern does not depend on the size of the increment (the
//! joints have no tensile strength), so before the slope line search
//! (`Driver::slope_search`) the run with 50 increments failed in its first one ("failed
//! under gravity at 0.0 % of the self-weight"); it now stands in 615 iterations (the one
//! with 10 increments: 680, before 710).
//!
//! Reference: the loading is proportional, so both runs must reach the same equilibrium up
//! to the path dependence of friction and of the joints' cohesion: the largest settlement
//! of a block, measured at 0.1814 mm (10 increments, as before the slope search) and
//! 0.1824 mm (50), 0.55 % apart; 0.1819 mm when the slope search may also crack joints
//! (not kept, see `Driver::slope_search`). 1 % is allowed.

//!
//! The same tunnel with no frame on top (`free_surface = true`) failed under gravity at
//! 72 % of its weight, a false collapse: the iterations cycled on bonded joints (c =
//! 50 kPa, no tensile strength) that could hold neither closed nor open, and the damped
//! dynamic run of the same scene stands. The static driver now breaks such bonds where the
//! increment would otherwise fail (`Driver::break_cycling_bonds`, docs/theory.md, "Bonds
//! that cannot hold"), and the static run stands on an equilibrium near the dynamic one's.

mod common;
use dfem::analysis::Status;

/// The tunnel example with gravity in `steps` increments.
fn scene(steps: usize) -> String {
    dfem::scene::examples::get("tunnel").unwrap().replace(
        "type = \"static\"",
        &format!("type = \"static\"\ngravity_steps = {steps}"),
    )
}

/// Stands; returns the largest settlement of a block's reference point (m) and the counters.
fn settle(steps: usize) -> (f64, dfem::analysis::Stats) {
    let sc = common::scene(&scene(steps));
    let (mesh, out) = common::solve(&sc);
    assert_eq!(
        out.status,
        Status::Stable,
        "tunnel under gravity in {steps} increments"
    );
    let settlement = largest_settlement(&mesh, &out);
    eprintln!(
        "{steps} increments: largest settlement {settlement:.5e} m, {} iterations, {} \
         factorizations, {} slope searches",
        out.stats.iterations, out.stats.factorizations, out.stats.slope_searches
    );
    (settlement, out.stats)
}

#[test]
fn tunnel_stands_under_gravity_in_small_and_large_increments() {
    let (coarse, cut) = settle(10);
    let (fine, stats) = settle(50);
    // what made the 50-increment run stand
    assert!(stats.slope_searches > 0, "no slope search: {stats:?}");
    // the counter of cuts against the increments run: the 50 converge uncut; the first of
    // the 10 is cut (to a fortieth of the weight, measured) and the phase goes on at that
    // step, 10 × 2^cuts increments
    assert_eq!((stats.load_cuts, stats.increments), (0, 50), "{stats:?}");
    assert!(cut.load_cuts > 0, "{cut:?}");
    assert_eq!(cut.increments, 10 << cut.load_cuts, "{cut:?}");
    assert!(
        (fine - coarse).abs() <= 0.01 * coarse,
        "settlements {coarse:.5e} m (10 increments) and {fine:.5e} m (50) differ by more than 1 %"
    );
    // the magnitude measured (a block of the crown settling by 0.18 mm), so that a run
    // that stands on another equilibrium is caught
    assert!(
        (1.7e-4..1.95e-4).contains(&coarse),
        "settlement {coarse:.5e} m"
    );
}

/// The largest settlement of a block's reference point (m).
fn largest_settlement(mesh: &dfem::mesh::Mesh, out: &dfem::analysis::Outcome) -> f64 {
    (0..mesh.blocks.len())
        .map(|b| -dfem::analysis::outcome_motion(mesh, b, out).0[1])
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn free_surface_tunnel_stands_as_its_damped_dynamic_run_does() {
    let text = dfem::scene::examples::get("tunnel")
        .unwrap()
        .replace("frame = 1.0", "frame = 1.0\nfree_surface = true");
    assert!(text.contains("free_surface = true"));
    let sc = common::scene(&text);
    let (mesh, out) = common::solve(&sc);
    assert_eq!(
        out.status,
        Status::Stable,
        "free-surface tunnel under gravity"
    );
    // what made it stand (before: "failed under gravity at 72.2 % of the self-weight")
    assert!(out.stats.bonds_broken > 0, "{:?}", out.stats);
    let static_settlement = largest_settlement(&mesh, &out);
    // the same weight applied at once, with mass-proportional damping a₀ = 20/s: at rest
    // to 10⁻¹⁰ m by t = 0.3 s (measured)
    let dynamic = text.replace(
        "type = \"static\"",
        "type = \"dynamic\"\ndt = 0.005\nduration = 0.5\nrayleigh = [20.0, 0.0]",
    );
    let sc = common::scene(&dynamic);
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "the damped dynamic run");
    let dynamic_settlement = largest_settlement(&mesh, &out);
    eprintln!(
        "largest settlement: static {static_settlement:.4e} m, damped dynamic \
         {dynamic_settlement:.4e} m"
    );
    // Two equilibria of a frictional, path-dependent rock mass: the weight applied at once
    // overshoots and slips the joints further than the static increments do (measured:
    // 0.180 mm static, 0.209 mm dynamic, 14 % apart). 25 % allowed; a block that fell or
    // a different mechanism would move by millimetres.
    assert!(
        (static_settlement - dynamic_settlement).abs() <= 0.25 * dynamic_settlement,
        "static {static_settlement:.4e} m against dynamic {dynamic_settlement:.4e} m"
    );
    // the crown's settlement of the framed tunnel (the test above: 0.1814 mm) is a bound
    // of the same magnitude
    assert!(
        (1.5e-4..2.5e-4).contains(&static_settlement),
        "settlement {static_settlement:.4e} m"
    );
}
