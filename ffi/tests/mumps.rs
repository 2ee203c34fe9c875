//! The MUMPS backend on small matrices with known answers.
#![cfg(feature = "mumps")]

use dfem_ffi::mumps::{Mumps, Symmetry};
use dfem_kernels::{CsrMatrix, CsrPattern, LinearBackend};
use std::sync::Arc;

/// The 1D Laplacian tridiag(-1, 2, -1) of order n (Dirichlet at both ends).
fn laplacian(n: usize) -> CsrMatrix {
    let p = Arc::new(CsrPattern::from_entries(n, (0..n - 1).map(|i| (i, i + 1))));
    let mut a = CsrMatrix::zeros(p);
    for i in 0..n {
        a.add(i, i, 2.0);
        if i + 1 < n {
            a.add(i, i + 1, -1.0);
            a.add(i + 1, i, -1.0);
        }
    }
    a
}

#[test]
fn laplacian_solution_is_the_closed_form() {
    // A x = e_k has the closed form x_i = G(i, k), the discrete Green's function
    // G(i, k) = (min(i,k) + 1)(n - max(i,k)) / (n + 1); both factorizations are exact up
    // to round-off (cond(A) ~ 4 n² / π² ~ 4e3 here, so 1e-12 leaves a margin of 1e3).
    let n = 100;
    let a = laplacian(n);
    for sym in [
        Symmetry::Symmetric,
        Symmetry::PositiveDefinite,
        Symmetry::General,
    ] {
        let mut m = Mumps::new(sym).unwrap();
        m.factorize(&a).unwrap();
        for k in [0, 37, 99] {
            let mut x = vec![0.0; n];
            x[k] = 1.0;
            m.solve(&mut x).unwrap();
            for (i, xi) in x.iter().enumerate() {
                let g = ((i.min(k) + 1) * (n - i.max(k))) as f64 / (n + 1) as f64;
                assert!(
                    (xi - g).abs() <= 1e-12 * g.abs().max(1.0),
                    "{sym:?} x[{i}] = {xi}, G = {g}"
                );
            }
        }
        assert_eq!(m.stats().symbolic_factorizations, 1);
        assert_eq!(m.stats().numeric_factorizations, 1);
        assert_eq!(m.stats().solves, 3);
        assert!(
            m.stats().factor_nnz >= n,
            "factor entries {}",
            m.stats().factor_nnz
        );
        assert!(m.stats().min_pivot_ratio.is_nan());
        // same values again: skipped; new values on the same pattern: no new analysis
        m.factorize(&a).unwrap();
        assert_eq!(m.stats().skipped_factorizations, 1);
        let mut b = a.clone();
        b.values.iter_mut().for_each(|v| *v *= 2.0);
        m.factorize(&b).unwrap();
        assert_eq!(m.stats().symbolic_factorizations, 1);
        assert_eq!(m.stats().numeric_factorizations, 2);
    }
}

#[test]
fn a_mechanism_is_reported_as_a_null_pivot() {
    // The Laplacian with free ends (Neumann: row sums zero) is singular with null space
    // span{1}. Shifted by s·I its smallest eigenvalue is s: with s = 1e-15 (relative to the
    // diagonal 2, far below NULL_PIVOT_THRESHOLD = 1e-12) MUMPS' null-pivot detection must
    // flag one pivot; with s = 1e-6 (a stiff-but-sound structure) none. Exactly singular
    // (s = 0) it is an error.
    let n = 50;
    let neumann = |s: f64| {
        let mut a = laplacian(n);
        a.add(0, 0, -1.0);
        a.add(n - 1, n - 1, -1.0);
        for i in 0..n {
            a.add(i, i, s);
        }
        a
    };
    let mut m = Mumps::new(Symmetry::Symmetric).unwrap();
    m.factorize(&neumann(1e-15)).unwrap();
    assert_eq!(m.stats().min_pivot_ratio, 0.0);
    assert!(m.stats().min_pivot_index < n);
    m.factorize(&neumann(1e-6)).unwrap();
    assert!(m.stats().min_pivot_ratio.is_nan());
    m.factorize(&neumann(0.0)).unwrap();
    assert_eq!(m.stats().min_pivot_ratio, 0.0);
    // without pivoting (SYM = 1) the exact zero pivot is an error
    let mut spd = Mumps::new(Symmetry::PositiveDefinite).unwrap();
    let e = spd.factorize(&neumann(0.0)).unwrap_err().to_string();
    assert!(e.contains("singular"), "{e}");
}

#[test]
fn an_indefinite_matrix_is_an_error_for_the_symmetric_modes() {
    // diag(1, -1, 1): one negative pivot.
    let p = Arc::new(CsrPattern::from_entries(3, []));
    let mut a = CsrMatrix::zeros(p);
    a.add(0, 0, 1.0);
    a.add(1, 1, -1.0);
    a.add(2, 2, 1.0);
    for sym in [Symmetry::Symmetric, Symmetry::PositiveDefinite] {
        let mut m = Mumps::new(sym).unwrap();
        let e = m.factorize(&a).unwrap_err().to_string();
        assert!(e.contains("not positive definite"), "{sym:?}: {e}");
    }
    // LU solves it: x = (1, -2, 3) for b = (1, 2, 3)
    let mut lu = Mumps::new(Symmetry::General).unwrap();
    lu.factorize(&a).unwrap();
    let mut x = vec![1.0, 2.0, 3.0];
    lu.solve(&mut x).unwrap();
    assert_eq!(x, vec![1.0, -2.0, 3.0]);
}
