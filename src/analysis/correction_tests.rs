//! The correction solver on a 4 × 4 matrix with known solutions: K = tridiag(1, 4, 1)
//! (symmetric positive definite), stored with a full pattern so that any entry can
//! change; every solution is checked by its residual ‖K x − r‖ / ‖r‖.

use super::*;
use crate::material::ContactState::{Slip, Stick};

const N: usize = 4;

fn pattern() -> Arc<CsrPattern> {
    let row_ptr = (0..=N).map(|i| i * N).collect();
    let col_idx = (0..N * N).map(|k| (k % N) as u32).collect();
    Arc::new(CsrPattern::from_parts(N, row_ptr, col_idx).expect("a full pattern"))
}

/// tridiag(1, 4, 1) in the full pattern's row-major order.
fn tridiagonal() -> Vec<f64> {
    (0..N * N)
        .map(|k| match (k / N).abs_diff(k % N) {
            0 => 4.0,
            1 => 1.0,
            _ => 0.0,
        })
        .collect()
}

fn relative_residual(values: &[f64], x: &[f64], r: &[f64]) -> f64 {
    let mut e2 = 0.0;
    for i in 0..N {
        let kx: f64 = (0..N).map(|j| values[i * N + j] * x[j]).sum();
        e2 += (kx - r[i]).powi(2);
    }
    (e2 / r.iter().map(|v| v * v).sum::<f64>()).sqrt()
}

const R: [f64; N] = [1.0, -2.0, 0.5, 3.0];

#[test]
fn fresh_secant_and_tangent_solves() {
    let mut b = crate::solve::backend("faer-cholesky").unwrap();
    let mut lin = CorrectionSolver::new(b.as_mut(), pattern());
    lin.kbuf.values = tridiagonal();
    let x = lin.factor_solve(false, &R).unwrap().expect("K is regular");
    assert!(relative_residual(&lin.kbuf.values, &x, &R) < 1e-14);
    // a nonsymmetric tangent (a friction–normal coupling at (0, 1)): the LU
    lin.kbuf.values[1] += 0.7;
    let x = lin.factor_solve(true, &R).unwrap().expect("K_t is regular");
    assert!(relative_residual(&lin.kbuf.values, &x, &R) < 1e-14);
    assert_eq!(lin.tangent_stats().unwrap().numeric_factorizations, 1);
}

#[test]
fn a_singular_secant_matrix_is_refused() {
    let mut b = crate::solve::backend("faer-cholesky").unwrap();
    let mut lin = CorrectionSolver::new(b.as_mut(), pattern());
    // unknowns 0 and 1 joined by a spring and held by nothing else: their common motion
    // is a free mode (a block that touches nothing in that direction)
    let mut k = tridiagonal();
    k[..2 * N].copy_from_slice(&[1.0, -1.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0]);
    k[2 * N + 1] = 0.0;
    k[N + 2] = 0.0;
    lin.kbuf.values = k;
    assert!(lin.factor_solve(false, &R).unwrap().is_none());
    assert!(!lin.factorize(true));
}

#[test]
fn pinned_unknowns_stay_put() {
    let mut b = crate::solve::backend("faer-cholesky").unwrap();
    let mut lin = CorrectionSolver::new(b.as_mut(), pattern());
    lin.kbuf.values = tridiagonal();
    CorrectionSolver::pin_rows(&[(1, 0.0)], &mut lin.kbuf);
    let mut r = R;
    r[1] = 0.0;
    let x = lin.factor_solve(false, &r).unwrap().unwrap();
    assert_eq!(x[1], 0.0);
    // the others solve K with row and column 1 taken out
    let k = tridiagonal();
    for i in [0, 2, 3] {
        let kx: f64 = [0, 2, 3].iter().map(|&j| k[i * N + j] * x[j]).sum();
        assert!((kx - r[i]).abs() < 1e-14 * 4.0);
    }
}

#[test]
fn a_change_of_state_is_solved_by_the_low_rank_update() {
    let mut b = crate::solve::backend("faer-cholesky").unwrap();
    let mut lin = CorrectionSolver::new(b.as_mut(), pattern());
    let mut stats = Stats::default();
    lin.kbuf.values = tridiagonal();
    assert!(lin.factorize(true));
    lin.hold_secant(&[Stick, Stick]);
    // no contact changed: nothing to correct
    assert!(lin.changed(&[Stick, Stick], &R, &mut stats).is_none());
    // contact 0 slips: its shear spring leaves unknowns 0 and 1 (a rank-1 change)
    for (i, j, v) in [(0, 0, -1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, -1.0)] {
        lin.kbuf.values[i * N + j] += v;
    }
    let x = lin
        .changed(&[Slip, Stick], &R, &mut stats)
        .expect("a rank-1 change of the held factor");
    assert!(relative_residual(&lin.kbuf.values, &x, &R) < 1e-9);
    assert_eq!(stats.low_rank_corrections, 1);
    // after a converged increment moved the geometry, the update is not exact: refused
    lin.moved();
    assert!(lin.changed(&[Slip, Stick], &R, &mut stats).is_none());
}

#[test]
fn gmres_on_the_held_secant_factor_solves_the_tangent() {
    let mut b = crate::solve::backend("faer-cholesky").unwrap();
    let mut lin = CorrectionSolver::new(b.as_mut(), pattern());
    let mut stats = Stats::default();
    lin.kbuf.values = tridiagonal();
    assert!(lin.factorize(true));
    // the tangent: the secant plus a nonsymmetric coupling, in the second buffer
    let mut kt = tridiagonal();
    kt[1] += 0.7;
    kt[2 * N + 3] -= 0.4;
    lin.aux_values().values.copy_from_slice(&kt);
    let x = lin
        .gmres(Buffer::Aux, false, &R, 1e-12, f64::INFINITY, &mut stats)
        .expect("GMRES converges within n iterations");
    assert!(relative_residual(&kt, &x, &R) < 1e-10);
    assert_eq!(stats.reused_factorizations, 1);
    assert!(stats.reuse_iterations >= 1 && stats.reuse_iterations <= N);
    // a solution beyond the bound (a matrix singular up to round-off) is refused, and
    // does not count as a failure of GMRES
    assert!(lin
        .gmres(Buffer::Aux, false, &R, 1e-12, 1e-9, &mut stats)
        .is_none());
    assert!(!lin.gmres_failed);
}
