//! The FFI backends (cargo features `mumps`, `petsc`) in whole nonlinear analyses: a
//! capacity run (secant iterations, load increments, bracketing of the collapse load) of
//! the built-in wall gives faer's collapse load factor λ. The displacement comparisons on
//! the validation scenes are in validation_cantilever.rs, validation_stack.rs and
//! validation_patch_test.rs.
#![cfg(any(feature = "mumps", feature = "petsc"))]

mod common;

/// The wall example (10 courses of 5 bricks, dry joints) as a capacity analysis.
fn wall_capacity() -> dfem::scene::Scene {
    let text = dfem::scene::examples::get("wall").unwrap();
    assert!(text.contains("type = \"static\""));
    common::scene(&text.replace("type = \"static\"", "type = \"capacity\""))
}

#[test]
fn capacity_of_the_wall_is_the_same_on_every_backend() {
    let sc = wall_capacity();
    let (_, reference) = common::solve(&sc);
    let lambda = reference.load_factor.expect("a capacity run gives λ");
    assert!(lambda > 0.0);
    // mumps-spd (SYM = 1) is left out: MUMPS runs no null-pivot detection without pivoting,
    // so the near-singular secant matrices past the collapse load are not recognized and
    // the run continues beyond faer's λ (measured: 0.509 against 0.4695).
    for name in dfem_ffi::BACKENDS.iter().filter(|n| **n != "mumps-spd") {
        let t0 = std::time::Instant::now();
        let (_, out) = common::solve_with(&sc, name);
        let l = out.load_factor.expect("a capacity run gives λ");
        eprintln!(
            "{name}: λ = {l} (faer {lambda}), {} increments, {} iterations, {:.2} s",
            out.stats.increments,
            out.stats.iterations,
            t0.elapsed().as_secs_f64()
        );
        // TOLERANCE
        assert!(
            common::rel_err(l, lambda) <= 1e-6,
            "{name}: λ = {l}, faer {lambda}"
        );
        assert_eq!(
            std::mem::discriminant(&out.status),
            std::mem::discriminant(&reference.status),
            "{name}"
        );
    }
}
