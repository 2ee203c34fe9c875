//! The static driver's low-rank path (issue 6; `CorrectionSolver::changed` in
//! src/analysis/correction.rs, `LinearBackend::solve_changed`): a secant correction in which
//! a few contacts changed state since the held factorization is solved with that factor
//! corrected exactly for the change (the Woodbury identity inside the factor,
//! kernels/src/lowrank.rs) instead of conjugate gradients on it or a refactorization.
//!
//! The P2 wall of docs/performance.md scaled down (12 courses of 12 rigid bricks, and 6 of
//! 6 deformable ones), gravity then 0.3 g lateral with Mohr–Coulomb joints (friction
//! 0.6), run twice: with `faer-cholesky` as is, and with its low-rank path disabled (rank
//! limit 0, so every change is refused and the driver iterates or refactorizes as before
//! the path existed). Every correction of both runs solves its linear system to a true
//! relative residual ≤ 10⁻⁹ (the path's check, `REUSE_TOLERANCE` × 10; conjugate gradients
//! the same; a refactorization to round-off), but the tangent steps by GMRES that end an
//! increment are inexact by design (their linear residual is a tenth of the converged
//! out-of-balance force, `Driver::tangent_with_secant_factor`), and with the path they
//! are preconditioned with the corrected factorization, so they stop at other inexact
//! solutions. Both runs converge every increment to the same out-of-balance tolerance
//! (10⁻⁶ of the force scale here), with the same contact states; the displacements may
//! differ by what that tolerance leaves free, bounded here by 10⁻⁶ of the largest
//! (measured: 4·10⁻⁸ rigid, 3·10⁻¹¹ deformable, where fewer tangent steps are taken).

mod common;
use dfem::analysis::{self, Outcome, Status};
use dfem_kernels::{FaerCholesky, LinearBackend};

/// P2 (benches/scenes/p2_wall40_rigid.toml) with n × n bricks of `kind` and `steps`
/// lateral steps.
fn scene(n: usize, kind: &str, steps: usize) -> dfem::scene::Scene {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/scenes/p2_wall40_rigid.toml"
    ))
    .unwrap()
    .replace("courses = 40", &format!("courses = {n}"))
    .replace(
        "bricks_per_course = 40",
        &format!("bricks_per_course = {n}"),
    )
    .replace("kind = \"rigid\"", &format!("kind = \"{kind}\""))
    .replace("load_steps = 30", &format!("load_steps = {steps}"))
        + "tolerance = 1e-6\n";
    common::scene(&text)
}

fn run(sc: &dfem::scene::Scene, mut backend: FaerCholesky) -> Outcome {
    let mesh = dfem::mesh::build(sc);
    let backend: &mut dyn LinearBackend = &mut backend;
    analysis::run(sc, &mesh, backend).unwrap()
}

/// The largest difference of the two runs' displacements over the largest of `b`'s.
fn relative_difference(a: &Outcome, b: &Outcome) -> f64 {
    let scale = b.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff =
        a.u.iter()
            .zip(&b.u)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

fn check(n: usize, kind: &str, steps: usize) {
    let sc = scene(n, kind, steps);
    let with = run(&sc, FaerCholesky::new());
    let without = run(&sc, FaerCholesky::new().with_changed_max_rank(0));
    let label = format!("{n} x {n} {kind}");
    assert_eq!(with.status, Status::Stable, "{label}");
    assert_eq!(without.status, Status::Stable, "{label}");
    // the path is taken, and only with it
    assert!(
        with.stats.low_rank_corrections > 0,
        "{label}: {:?}",
        with.stats
    );
    assert!(with.stats.low_rank_max_rank > 0, "{label}");
    assert_eq!(without.stats.low_rank_corrections, 0, "{label}");
    // it saves factorizations or iterations
    assert!(
        with.stats.factorizations + with.stats.reuse_iterations
            < without.stats.factorizations + without.stats.reuse_iterations,
        "{label}: with {:?}, without {:?}",
        with.stats,
        without.stats
    );
    let relative = relative_difference(&with, &without);
    eprintln!(
        "{label}: displacements differ by {:e} of the largest; with the path {:?}, without {:?}",
        relative,
        (
            with.stats.factorizations,
            with.stats.reuse_iterations,
            with.stats.low_rank_corrections,
            with.stats.low_rank_max_rank
        ),
        (without.stats.factorizations, without.stats.reuse_iterations)
    );
    assert!(
        relative <= 1e-6,
        "{label}: displacements differ by {relative:e} of the largest"
    );
    assert_eq!(with.contact_states, without.contact_states, "{label}");
}

#[test]
fn rigid_wall_same_results_with_and_without_the_low_rank_path() {
    check(12, "rigid", 10);
}

#[test]
fn deformable_wall_same_results_with_and_without_the_low_rank_path() {
    check(6, "deformable", 10);
}

/// The held factorization kept across load increments (`reuse_across_increments`,
/// `CorrectionSolver::reuse`): the first corrections of an increment by conjugate gradients
/// preconditioned with the previous geometry's factor corrected for the contacts that
/// changed state, instead of a refactorization. Every such correction is solved to a true
/// relative residual ≤ 10⁻⁹ (as the other paths), so the run converges every increment to
/// the same out-of-balance tolerance (10⁻⁶) in the same contact states; the displacements
/// may differ by what that tolerance leaves free (the bound of `check`, 10⁻⁶ of the
/// largest), and fewer factorizations are computed.
#[test]
fn rigid_wall_same_results_with_the_factor_kept_across_increments() {
    let off = scene(12, "rigid", 10);
    let on = {
        let mut sc = off.clone();
        sc.analysis
            .settings
            .statics_mut()
            .expect("a static scene")
            .reuse_across_increments = true;
        sc
    };
    let with = run(&on, FaerCholesky::new());
    let without = run(&off, FaerCholesky::new());
    assert_eq!(with.status, Status::Stable);
    assert_eq!(without.status, Status::Stable);
    assert!(
        with.stats.factorizations < without.stats.factorizations,
        "with {:?}, without {:?}",
        with.stats,
        without.stats
    );
    let relative = relative_difference(&with, &without);
    eprintln!(
        "kept across increments: displacements differ by {:e} of the largest; factorizations {} against {}",
        relative,
        with.stats.factorizations,
        without.stats.factorizations
    );
    assert!(relative <= 1e-6, "{relative:e}");
    assert_eq!(with.contact_states, without.contact_states);
}
