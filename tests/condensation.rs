//! `faer-condensed` (issue 6, "skip what a scene doesn't need": static condensation of the
//! blocks' interiors), run through the analyses against `faer-cholesky`, which factorizes
//! the whole matrix in another order.
//!
//! The model is the `column` example (`dfem example column`), a multi-drum column: six
//! marble drums of 0.8 m × 1.0 m, deformable, meshed at `mesh` m, stacked on a fixed base with dry joints (φ = 35°, no cohesion or
//! tension). Contacts act on the drums' top and bottom faces only, so the drums' sides and
//! insides are interior (4,582 of 4,956 unknowns at 0.05 m) and the condensed matrix's
//! factorization costs a tenth of the whole one's.
//!
//! Tolerance 1e-9 (max-norm relative, on the unknowns): both backends are backward-stable
//! Cholesky factorizations of the same matrices, so each solve differs by round-off
//! amplified by the stiffness' condition number (~1e5 here), about 1e-12 measured; the
//! nonlinear iterations then stop at the same iterate as long as every contact takes the
//! same state, which the equal iteration counts check. A wrong Schur complement, coupling
//! term or correction would give errors of order 1.

mod common;

use dfem::analysis::{self, Outcome, Status};
use dfem::solve::{configure, LinearBackend};
use dfem_kernels::{max_relative_difference, FaerCholesky, FaerCholeskyCondensed};

const TOL: f64 = 1e-9;

/// The `column` example with its drums meshed at `mesh` m and the `[analysis]` table
/// `analysis`.
fn drums(mesh: f64, analysis: &str) -> String {
    dfem::scene::examples::drum_column(mesh, analysis)
}

fn run_with(text: &str, backend: &mut dyn LinearBackend) -> Outcome {
    let sc = common::scene(text);
    let mesh = dfem::mesh::build(&sc);
    configure(backend, &mesh).unwrap();
    analysis::run(&sc, &mesh, backend).unwrap()
}

/// The same analysis with the whole matrix's Cholesky and with the condensed one; the
/// condensed backend is returned to be inspected.
fn both(text: &str, forced: bool) -> (Outcome, Outcome, FaerCholeskyCondensed) {
    let whole = run_with(text, &mut FaerCholesky::new());
    let mut condensed = FaerCholeskyCondensed::new().forced(forced);
    let out = run_with(text, &mut condensed);
    (whole, out, condensed)
}

#[test]
fn a_static_lateral_load_gives_the_whole_matrix_result() {
    let text = drums(
        0.05,
        "[analysis]\ntype = \"static\"\nlateral = 0.1\nload_steps = 5\ngravity_steps = 1\n",
    );
    let (whole, cond, be) = both(&text, false);
    assert_eq!(whole.status, Status::Stable);
    assert_eq!(cond.status, Status::Stable);
    assert!(be.is_condensed(), "the condensation pays on this column");
    assert_eq!(be.split_sizes(), Some((4582, 374)));
    assert_eq!(whole.stats.iterations, cond.stats.iterations);
    let d = max_relative_difference(&cond.u, &whole.u);
    eprintln!(
        "static: {} iterations, max relative difference {d:e}",
        whole.stats.iterations
    );
    assert!(d < TOL, "{d:e}");
    // the top drum moves sideways (a rocking column: the joints open on the windward side)
    let top = whole.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(top > 1e-6, "{top:e}");
}

/// The multi-drum column's lateral capacity is the rigid stack's rocking limit about the
/// bottom joint's toe, λ = b / H = 0.8 / 6 = 0.1333 (the column above any joint rocks
/// when λ W h_c > W b / 2, h_c = H_above / 2; the bottom joint has the most above it;
/// sliding needs λ > tan 35° = 0.70). The drums deform a little and the joints' springs
/// let the toe sink, so λ is a little lower: 0.13313 measured with both backends at
/// 0.1 m triangles (bracket 1e-3). The condensation is forced here (at 0.1 m the whole
/// matrix is too small for it to pay), so that every path of a capacity search — failing
/// trials, cut increments, restarts, thousands of factorizations — goes through it.
#[test]
fn the_column_rocks_at_b_over_h_with_and_without_condensation() {
    let text = drums(0.1, "[analysis]\ntype = \"capacity\"\n");
    let (whole, cond, be) = both(&text, true);
    assert!(be.is_condensed());
    let (lw, lc) = (whole.load_factor.unwrap(), cond.load_factor.unwrap());
    let closed = 0.8 / 6.0;
    assert!((lw - closed).abs() / closed < 0.005, "whole: {lw}");
    eprintln!("capacity: whole {lw}, condensed {lc}, b/H {closed}");
    assert!(
        (lc - lw).abs() / lw < 1e-6,
        "condensed {lc} against whole {lw}"
    );
}

#[test]
fn a_dynamic_run_gives_the_whole_matrix_result() {
    let text = drums(
        0.05,
        "[analysis]\ntype = \"dynamic\"\ndt = 0.005\nduration = 0.1\n\
         ground_motion = { expression = \"0.15*sin(31.4*t)\", units = \"g\" }\n",
    );
    let (whole, cond, be) = both(&text, false);
    assert!(be.is_condensed());
    assert_eq!(whole.status, cond.status);
    let d = max_relative_difference(&cond.u, &whole.u);
    eprintln!("dynamic: max relative difference {d:e}");
    assert!(d < TOL, "{d:e}");
    // the dynamic driver keeps the drums' triangles on the step's start geometry (they
    // turn by less than 10⁻³ rad a step), so their interiors' rows stay the same within
    // a step: the six interiors are refactorized at a step's first factorization and at
    // the recomputed accelerations after impacts and releases (408 for 260
    // factorizations of 20 steps), where with the triangles on the trial's geometry
    // every factorization redid all six (more than 6 × 260)
    let (interiors, factorizations) = (be.interior_factorizations(), cond.stats.factorizations);
    eprintln!(
        "dynamic: {interiors} interior factorizations, {factorizations} factorizations, {} steps, {} iterations",
        cond.stats.increments, cond.stats.iterations
    );
    assert!(factorizations > 5 * cond.stats.increments);
    assert!(
        2 * interiors < 6 * factorizations,
        "{interiors} interior factorizations for {factorizations} factorizations"
    );
}

#[test]
fn rigid_blocks_are_factorized_whole_bit_for_bit() {
    let sc = common::scene(&dfem::scene::examples::scaled_wall(8, true));
    let mesh = dfem::mesh::build(&sc);
    let mut plain = FaerCholesky::new();
    configure(&mut plain, &mesh).unwrap();
    let whole = analysis::run(&sc, &mesh, &mut plain).unwrap();
    let mut be = FaerCholeskyCondensed::new();
    configure(&mut be, &mesh).unwrap();
    let cond = analysis::run(&sc, &mesh, &mut be).unwrap();
    assert!(!be.is_condensed());
    assert_eq!(whole.u, cond.u);
    assert_eq!(whole.stats.iterations, cond.stats.iterations);
}

#[test]
fn check_counts_the_interiors() {
    let dir = common::tmp_dir("condensation_check");
    let file = dir.join("column.toml");
    std::fs::write(&file, dfem::scene::examples::get("column").unwrap()).unwrap();
    let out = common::dfem_ok(&["check", file.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("interior dofs: 4582 in 6 deformable blocks"),
        "{text}"
    );
}
