//! Reuse of a factorization for a nearby matrix.
//!
//! Between two secant iterations the stiffness changes only where contacts changed state
//! (each such contact is a rank-2 change of K) and, slightly, with the trial geometry. The
//! factorization of the previous matrix, K₀ = L Lᵀ, is then an excellent preconditioner for
//! the new one: the preconditioned operator K₀⁻¹ K is the identity plus a perturbation of
//! rank ≈ 2 × (contacts changed) plus a small one, so conjugate gradients on it converge in a
//! few iterations, each costing one triangular solve pair and one product with K, far less
//! than a numeric refactorization. When they do not converge within a few iterations the
//! caller refactorizes (the iterations stop paying). No crate offers CG with an arbitrary
//! factorization as preconditioner over our `LinearBackend` trait, hence this small loop.

use dfem_kernels::{pcg::dot, CsrMatrix, LinearBackend};

/// Outcome of [`solve_with_factor`].
#[derive(Debug, Clone)]
pub struct Reused {
    /// The solution x of K x = r.
    pub x: Vec<f64>,
    /// Conjugate-gradient iterations performed (each one preconditioner solve).
    pub iterations: usize,
}

/// Solve `k · x = r` by conjugate gradients preconditioned with the factorization that
/// `backend` holds (of a matrix close to `k`, both symmetric positive definite). Stops when
/// ‖r − K x‖₂ ≤ `tolerance` ‖r‖₂ (the true residual, recomputed at the end); returns `None`
/// when that takes more than `max_iterations`, when a solve fails or when K is not positive
/// on the search direction (a singular or indefinite K: the caller refactorizes and its
/// pivot check decides). Deterministic: the products and dot products are bit-identical for
/// any number of threads.
pub fn solve_with_factor(
    k: &CsrMatrix,
    backend: &mut dyn LinearBackend,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<Reused> {
    let n = r.len();
    let bnorm = dot(r, r).sqrt();
    if bnorm == 0.0 {
        return Some(Reused {
            x: vec![0.0; n],
            iterations: 0,
        });
    }
    let mut x = vec![0.0; n];
    let mut res = r.to_vec();
    let mut z = res.clone();
    backend.solve(&mut z).ok()?;
    let mut p = z.clone();
    let mut rz = dot(&res, &z);
    let mut kp = vec![0.0; n];
    for it in 1..=max_iterations {
        k.mul_vec(&p, &mut kp);
        let pkp = dot(&p, &kp);
        if pkp.is_nan() || pkp <= 0.0 || !rz.is_finite() {
            return None;
        }
        let alpha = rz / pkp;
        for i in 0..n {
            x[i] += alpha * p[i];
            res[i] -= alpha * kp[i];
        }
        if dot(&res, &res).sqrt() <= tolerance * bnorm {
            // confirm with the true residual (the recurrence drifts in round-off)
            k.mul_vec(&x, &mut kp);
            let true_res = r
                .iter()
                .zip(&kp)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            if true_res <= 10.0 * tolerance * bnorm && x.iter().all(|v| v.is_finite()) {
                return Some(Reused { x, iterations: it });
            }
            return None;
        }
        z.copy_from_slice(&res);
        backend.solve(&mut z).ok()?;
        let rz_new = dot(&res, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use dfem_kernels::{CsrPattern, FaerCholesky};
    use std::sync::Arc;

    /// A chain of `n` unknowns joined by springs `k[i]` between i and i+1, the first one
    /// tied to the ground by a spring of 1 (SPD tridiagonal).
    fn chain(k: &[f64]) -> CsrMatrix {
        let n = k.len() + 1;
        let mut entries = Vec::new();
        for i in 0..n {
            entries.push((i, i));
            if i + 1 < n {
                entries.push((i, i + 1));
                entries.push((i + 1, i));
            }
        }
        let mut m = CsrMatrix::zeros(Arc::new(CsrPattern::from_entries(n, entries)));
        m.add(0, 0, 1.0);
        for (i, &ki) in k.iter().enumerate() {
            m.add(i, i, ki);
            m.add(i + 1, i + 1, ki);
            m.add(i, i + 1, -ki);
            m.add(i + 1, i, -ki);
        }
        m
    }

    #[test]
    fn a_rank_two_change_converges_in_three_iterations_to_the_direct_solution() {
        let k_old: Vec<f64> = (0..200).map(|i| 1.0 + (i % 7) as f64).collect();
        let mut k_new = k_old.clone();
        // two springs change (two "contacts" change state): a rank-2 change
        k_new[40] *= 0.1;
        k_new[150] *= 5.0;
        let (a_old, a_new) = (chain(&k_old), chain(&k_new));
        let rhs: Vec<f64> = (0..201).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();

        let mut direct = FaerCholesky::new();
        direct.factorize(&a_new).unwrap();
        let mut exact = rhs.clone();
        direct.solve(&mut exact).unwrap();

        let mut held = FaerCholesky::new();
        held.factorize(&a_old).unwrap();
        let out = solve_with_factor(&a_new, &mut held, &rhs, 1e-10, 10).unwrap();
        // CG preconditioned by the old factor: the preconditioned operator is the identity
        // plus a rank-2 term, so at most 3 iterations in exact arithmetic
        assert!(out.iterations <= 3, "{} iterations", out.iterations);
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in out.x.iter().zip(&exact) {
            assert!((a - b).abs() <= 1e-9 * scale, "{a} vs {b}");
        }
        // too few iterations allowed: the caller is told to refactorize
        assert!(solve_with_factor(&a_new, &mut held, &rhs, 1e-12, 1).is_none());
    }
}
