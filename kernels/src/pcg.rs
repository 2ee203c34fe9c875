//! Preconditioned conjugate gradients with a Jacobi (diagonal) preconditioner.
//!
//! Every reduction uses fixed chunks whose partial sums are added in chunk order, and the
//! matrix-vector product is row-wise, so the iterates are bit-identical for any number of
//! rayon threads.

use crate::backend::{LinearBackend, SolveError, SolverStats};
use crate::csr::{CsrMatrix, CsrPattern};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Length of the fixed chunks of the deterministic reductions.
const DOT_CHUNK: usize = 4096;

/// Deterministic dot product: partial sums over fixed chunks of 4096 entries,
/// computed in parallel, then added in chunk order.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    assert_eq!(x.len(), y.len());
    let partial: Vec<f64> = x
        .par_chunks(DOT_CHUNK)
        .zip(y.par_chunks(DOT_CHUNK))
        .map(|(a, b)| a.iter().zip(b).map(|(u, v)| u * v).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// Conjugate gradients with a Jacobi preconditioner, for symmetric positive definite
/// matrices. Starts from x = 0; stops when ‖b − A x‖₂ ≤ `tolerance` · ‖b‖₂.
pub struct Pcg {
    /// Relative residual tolerance (default 1e-10).
    pub tolerance: f64,
    /// Maximum number of iterations; `None` (default) means 2 n + 100.
    pub max_iterations: Option<usize>,
    matrix: Option<CsrMatrix>,
    inv_diag: Vec<f64>,
    pattern_id: Option<u64>,
    stats: SolverStats,
}

impl Default for Pcg {
    fn default() -> Self {
        Self::new()
    }
}

impl Pcg {
    /// Tolerance 1e-10, default iteration limit.
    pub fn new() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: None,
            matrix: None,
            inv_diag: Vec::new(),
            pattern_id: None,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Sets the relative residual tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// Sets the maximum number of iterations.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = Some(max_iterations);
        self
    }
}

impl LinearBackend for Pcg {
    fn name(&self) -> &'static str {
        "pcg"
    }

    /// Nothing to analyze: records the pattern id only.
    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        self.pattern_id = Some(pattern.id());
        Ok(())
    }

    /// Copies the matrix and inverts its diagonal; a non-positive diagonal entry gives
    /// [`SolveError::NotPositiveDefinite`].
    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        let t = Instant::now();
        self.matrix = None;
        let d = a.diagonal();
        if let Some((i, &v)) = d.iter().enumerate().find(|(_, &v)| v.is_nan() || v <= 0.0) {
            return Err(SolveError::NotPositiveDefinite { index: i, pivot: v });
        }
        self.inv_diag = d.iter().map(|v| 1.0 / v).collect();
        self.matrix = Some(a.clone());
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let a = self.matrix.as_ref().ok_or_else(|| {
            SolveError::Other("solve called without a successful factorization".into())
        })?;
        let n = a.n();
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "right-hand side has length {}, expected {n}",
                rhs.len()
            )));
        }
        let t = Instant::now();
        self.stats.solves += 1;
        let max_it = self.max_iterations.unwrap_or(2 * n + 100);
        let mut r = rhs.to_vec();
        let mut x = vec![0.0; n];
        let bnorm = dot(&r, &r).sqrt();
        if bnorm == 0.0 {
            rhs.fill(0.0);
            self.stats.solve_seconds += t.elapsed().as_secs_f64();
            return Ok(());
        }
        let m = &self.inv_diag;
        let mut z: Vec<f64> = r.iter().zip(m).map(|(ri, mi)| ri * mi).collect();
        let mut p = z.clone();
        let mut q = vec![0.0; n];
        let mut rz = dot(&r, &z);
        let mut res = 1.0;
        let mut it = 0;
        while it < max_it {
            a.mul_vec(&p, &mut q);
            let pq = dot(&p, &q);
            if pq <= 0.0 || !pq.is_finite() {
                self.stats.iterations += it;
                self.stats.solve_seconds += t.elapsed().as_secs_f64();
                return Err(SolveError::Other(format!(
                    "pcg breakdown at iteration {it}: pᵀAp = {pq:e} (matrix not positive definite?)"
                )));
            }
            let alpha = rz / pq;
            x.par_iter_mut()
                .zip(&p)
                .for_each(|(xi, pi)| *xi += alpha * pi);
            r.par_iter_mut()
                .zip(&q)
                .for_each(|(ri, qi)| *ri -= alpha * qi);
            it += 1;
            res = dot(&r, &r).sqrt() / bnorm;
            if res <= self.tolerance {
                break;
            }
            z.par_iter_mut()
                .zip(&r)
                .zip(m)
                .for_each(|((zi, ri), mi)| *zi = ri * mi);
            let rz_new = dot(&r, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            p.par_iter_mut()
                .zip(&z)
                .for_each(|(pi, zi)| *pi = zi + beta * *pi);
        }
        self.stats.iterations += it;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        if res <= self.tolerance {
            rhs.copy_from_slice(&x);
            Ok(())
        } else {
            Err(SolveError::NoConvergence {
                iterations: it,
                residual: res,
            })
        }
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }
}
