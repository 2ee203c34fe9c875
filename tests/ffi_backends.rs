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
    for name in dfem_ffi::BACKENDS {
        let t0 = std::time::Instant::now();
        let (_, out) = common::solve_with(&sc, name);
        let l = out.load_factor.expect("a capacity run gives λ");
        eprintln!(
            "{name}: λ = {l} (faer {lambda}), {} increments, {} iterations, {:.2} s",
            out.stats.increments,
            out.stats.iterations,
            t0.elapsed().as_secs_f64()
        );
        // The capacity search brackets λ to a relative width of 1e-3 (`bracket`); near
        // the collapse load the contact states at the end of an increment depend on the
        // last digits of the solves (PETSc's CG stops at a relative residual of 1e-12), so
        // two backends may end a bracket apart (measured: MUMPS and faer to the bit, PETSc
        // 1.1e-3 below).
        assert!(
            common::rel_err(l, lambda) <= 2e-3,
            "{name}: λ = {l}, faer {lambda}"
        );
        assert_eq!(
            std::mem::discriminant(&out.status),
            std::mem::discriminant(&reference.status),
            "{name}"
        );
    }
}
