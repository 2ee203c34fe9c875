//! The PETSc backend on small matrices with known answers.
#![cfg(feature = "petsc")]

use dfem_ffi::petsc::Petsc;
use dfem_kernels::{CsrMatrix, CsrPattern, LinearBackend, SolveError};
use std::sync::Arc;

/// The 2D 5-point Laplacian on an m × m grid (Dirichlet), SPD.
fn laplacian_2d(m: usize) -> CsrMatrix {
    let n = m * m;
    let id = |i: usize, j: usize| j * m + i;
    let mut e = Vec::new();
    for j in 0..m {
        for i in 0..m {
            if i + 1 < m {
                e.push((id(i, j), id(i + 1, j)));
            }
            if j + 1 < m {
                e.push((id(i, j), id(i, j + 1)));
            }
        }
    }
    let mut a = CsrMatrix::zeros(Arc::new(CsrPattern::from_entries(n, e.iter().copied())));
    for k in 0..n {
        a.add(k, k, 4.0);
    }
    for &(p, q) in &e {
        a.add(p, q, -1.0);
        a.add(q, p, -1.0);
    }
    a
}

fn residual(a: &CsrMatrix, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    a.mul_vec(x, &mut ax);
    let r: f64 = ax.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum();
    let bn: f64 = b.iter().map(|v| v * v).sum();
    (r / bn).sqrt()
}

#[test]
fn default_cg_gamg_solves_to_the_tolerance_and_reports_it() {
    // x* = known vector, b = A x*: the error of the solve is bounded by
    // cond(A) × residual; cond ≈ 4 (m+1)² / π² ≈ 1.1e3 for m = 50, residual ≤ 1e-12,
    // so 1e-8 on the relative error has a margin of ~10.
    let a = laplacian_2d(50);
    let n = a.pattern.n();
    let xs: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.3)
        .collect();
    let mut b = vec![0.0; n];
    a.mul_vec(&xs, &mut b);
    let mut p = Petsc::new("").unwrap();
    p.factorize(&a).unwrap();
    assert_eq!(p.method(), "cg+gamg");
    let mut x = b.clone();
    p.solve(&mut x).unwrap();
    let err = x
        .iter()
        .zip(&xs)
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f64::max);
    let xmax = xs.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(err <= 1e-8 * xmax, "error {err:e}");
    let s = p.stats().clone();
    assert!(s.last_true_residual <= 1e-11, "{}", s.last_true_residual);
    assert!((s.last_true_residual - residual(&a, &x, &b)).abs() <= 1e-14);
    // GAMG on the Laplacian: O(10) iterations, far below CG alone (~m = 50 or more)
    assert!(
        s.last_iterations > 0 && s.last_iterations < 40,
        "{}",
        s.last_iterations
    );
    // same values: skipped; a second solve reuses the preconditioner
    p.factorize(&a).unwrap();
    assert_eq!(s.symbolic_factorizations, 1);
    assert_eq!(p.stats().skipped_factorizations, 1);
}

#[test]
fn options_reach_the_options_database() {
    // preonly + Cholesky: a direct solve, one "iteration", residual at round-off
    let a = laplacian_2d(20);
    let n = a.pattern.n();
    let mut p = Petsc::new("-ksp_type preonly -pc_type cholesky").unwrap();
    p.factorize(&a).unwrap();
    assert_eq!(p.method(), "preonly+cholesky");
    let mut x = vec![1.0; n];
    p.solve(&mut x).unwrap();
    assert!(
        p.stats().last_true_residual < 1e-13,
        "{}",
        p.stats().last_true_residual
    );
    assert_eq!(p.stats().last_iterations, 1);
}

#[test]
fn a_cap_on_iterations_is_no_convergence() {
    // Jacobi-preconditioned CG on the 2D Laplacian needs ~O(m) iterations for 1e-12:
    // two cannot reach it.
    let a = laplacian_2d(30);
    let n = a.pattern.n();
    let mut p = Petsc::new("-ksp_type cg -pc_type jacobi -ksp_max_it 2").unwrap();
    p.factorize(&a).unwrap();
    let mut x = vec![1.0; n];
    match p.solve(&mut x) {
        Err(SolveError::NoConvergence {
            iterations,
            residual,
        }) => {
            assert_eq!(iterations, 2);
            assert!(residual > 1e-6);
        }
        r => panic!("expected no convergence, got {r:?}"),
    }
}

#[test]
fn near_null_space_is_accepted_and_helps_gamg() {
    // 2D elasticity-like coupling is not needed to check the plumbing: on the Laplacian
    // the near-null space is the constant vector; GAMG with it converges as without
    // (the default for scalar problems is the constant), a zero vector is dropped.
    let a = laplacian_2d(40);
    let n = a.pattern.n();
    let mut p = Petsc::new("").unwrap();
    p.set_near_null_space(&[vec![1.0; n], vec![0.0; n]])
        .unwrap();
    p.factorize(&a).unwrap();
    let mut x = vec![1.0; n];
    p.solve(&mut x).unwrap();
    assert!(p.stats().last_true_residual <= 1e-11);
    assert!(p.stats().last_iterations < 40);
}
