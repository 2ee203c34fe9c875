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

impl Reused {
    /// The solution of a zero right-hand side.
    fn zero(n: usize) -> Reused {
        Reused {
            x: vec![0.0; n],
            iterations: 0,
        }
    }
}

/// ‖r − K x‖₂, with `kx` as scratch.
fn residual_norm(k: &CsrMatrix, x: &[f64], r: &[f64], kx: &mut [f64]) -> f64 {
    k.mul_vec(x, kx);
    r.iter()
        .zip(kx.iter())
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
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
    pcg(k, &mut |z| backend.solve(z), r, tolerance, max_iterations)
}

/// [`solve_with_factor`] preconditioned with the held factorization corrected for a
/// low-rank change: M⁻¹ z = `near`⁻¹ z by `backend.solve_changed(near, z)`
/// ([`LinearBackend::solve_changed`]; `near`: a symmetric positive definite matrix that
/// differs from the factorized one on few contacts, close to `k`). Across load increments
/// `k` is the secant matrix on the new geometry and `near` the held one with the contacts
/// that changed state since corrected (`CorrectionSolver::reuse` in src/analysis/correction.rs):
/// K near⁻¹ differs from the identity by the geometry's small change only. `None` when
/// the backend refuses the change (its first call, which makes the correction; later
/// calls reuse it) or as [`solve_with_factor`].
pub fn solve_with_changed_factor(
    k: &CsrMatrix,
    near: &CsrMatrix,
    backend: &mut dyn LinearBackend,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<Reused> {
    pcg(
        k,
        &mut |z| backend.solve_changed(near, z),
        r,
        tolerance,
        max_iterations,
    )
}

/// The conjugate gradients of [`solve_with_factor`] with the preconditioner solve
/// `precondition` (z ← M⁻¹ z in place, M symmetric positive definite).
fn pcg(
    k: &CsrMatrix,
    precondition: &mut dyn FnMut(&mut [f64]) -> Result<(), dfem_kernels::SolveError>,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<Reused> {
    let n = r.len();
    let bnorm = dot(r, r).sqrt();
    if bnorm == 0.0 {
        return Some(Reused::zero(n));
    }
    let mut x = vec![0.0; n];
    let mut res = r.to_vec();
    let mut z = res.clone();
    precondition(&mut z).ok()?;
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
            return confirmed(k, x, r, 10.0 * tolerance * bnorm, &mut kp, it);
        }
        z.copy_from_slice(&res);
        precondition(&mut z).ok()?;
        let rz_new = dot(&res, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    None
}

/// Solve `k · x = r` with `backend.solve_changed` (the held factorization of a nearby
/// matrix corrected exactly for the change, [`LinearBackend::solve_changed`]: no
/// iteration), the result confirmed by its true residual ‖r − K x‖₂ ≤ `tolerance` ‖r‖₂ as
/// those of [`solve_with_factor`] are. `None` when the backend refuses (unsupported, a
/// change of too high a rank, K not positive definite) or the residual is above: the
/// caller iterates or refactorizes.
pub fn solve_changed(
    k: &CsrMatrix,
    backend: &mut dyn LinearBackend,
    r: &[f64],
    tolerance: f64,
) -> Option<Reused> {
    let bnorm = dot(r, r).sqrt();
    if bnorm == 0.0 {
        return Some(Reused::zero(r.len()));
    }
    let mut x = r.to_vec();
    backend.solve_changed(k, &mut x).ok()?;
    let mut scratch = vec![0.0; r.len()];
    confirmed(k, x, r, tolerance * bnorm, &mut scratch, 0)
}

/// `x` after `iterations` iterations of [`solve_with_factor`] or [`gmres_with_factor`]
/// when its true residual ‖r − K x‖₂ is within `limit` (the callers give 10 × the
/// tolerance their own estimate met: the factor allows for its round-off drift) and it is
/// finite; `None` otherwise. `scratch`: a work vector of the size of `r`.
fn confirmed(
    k: &CsrMatrix,
    x: Vec<f64>,
    r: &[f64],
    limit: f64,
    scratch: &mut [f64],
    iterations: usize,
) -> Option<Reused> {
    let ok = residual_norm(k, &x, r, scratch) <= limit && x.iter().all(|v| v.is_finite());
    ok.then_some(Reused { x, iterations })
}

/// Serial dot product (a fixed order: the same bits for any number of threads), for the
/// many short reductions of [`gmres_with_factor`]'s orthogonalization, where a parallel
/// one costs more in synchronization than it saves on a loaded 2-core machine.
fn sdot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Solve `k · x = r` for a nonsymmetric `k` (Newton's tangent, docs/theory.md §4) by GMRES,
/// right-preconditioned with the factorization that `backend` holds (of a nearby symmetric
/// matrix: the secant stiffness, of which the tangent differs by the slipping contacts'
/// friction–normal coupling). Full (unrestarted) Arnoldi with modified Gram–Schmidt and
/// Givens rotations; it keeps the preconditioned vectors M⁻¹vⱼ, so x = Σ yⱼ M⁻¹vⱼ costs no
/// further solve. Stops when the Arnoldi residual is ≤ `tolerance` ‖r‖₂ and then checks the
/// true residual ‖r − K x‖₂ (≤ 10 `tolerance` ‖r‖₂); `None` when that takes more than
/// `max_iterations` (each one preconditioner solve and one product with K), when a solve
/// fails or when the result is not finite: the caller factorizes `k` itself. Memory: 2
/// `max_iterations` vectors of the size of `r`. Deterministic for any number of threads
/// (as [`solve_with_factor`]).
pub fn gmres_with_factor(
    k: &CsrMatrix,
    backend: &mut dyn LinearBackend,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<Reused> {
    gmres(k, &mut |z| backend.solve(z), r, tolerance, max_iterations)
}

/// [`gmres_with_factor`] right-preconditioned with the held factorization corrected for
/// a low-rank change: M⁻¹ z = `near`⁻¹ z by `backend.solve_changed(near, z)`
/// ([`LinearBackend::solve_changed`]; `near`: the symmetric matrix nearby, e.g. the secant
/// stiffness in the current contact states, when the backend holds the factorization of
/// that of older ones). When the backend refuses the change (at its first call, which
/// makes the correction) the held factorization alone preconditions, as in
/// [`gmres_with_factor`]. Also returns whether the correction was used.
pub fn gmres_with_changed_factor(
    k: &CsrMatrix,
    near: &CsrMatrix,
    backend: &mut dyn LinearBackend,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> (Option<Reused>, bool) {
    let mut corrected = true;
    let mut first = true;
    let out = gmres(
        k,
        &mut |z| {
            if first {
                // the first call makes the correction (and may refuse it); the later ones
                // reuse it and fail only where a plain solve would
                first = false;
                let keep = z.to_vec();
                if backend.solve_changed(near, z).is_ok() {
                    return Ok(());
                }
                // the Arnoldi vectors keep each preconditioned vector (a flexible
                // GMRES), so the preconditioner may change between iterations
                corrected = false;
                z.copy_from_slice(&keep);
            }
            if corrected {
                backend.solve_changed(near, z)
            } else {
                backend.solve(z)
            }
        },
        r,
        tolerance,
        max_iterations,
    );
    (out, corrected)
}

/// The GMRES of [`gmres_with_factor`] with the preconditioner solve `precondition`
/// (z ← M⁻¹ z in place).
fn gmres(
    k: &CsrMatrix,
    precondition: &mut dyn FnMut(&mut [f64]) -> Result<(), dfem_kernels::SolveError>,
    r: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<Reused> {
    let n = r.len();
    let beta = sdot(r, r).sqrt();
    if beta == 0.0 {
        return Some(Reused::zero(n));
    }
    // Arnoldi basis V, preconditioned basis Z, Hessenberg columns after the rotations
    let mut v: Vec<Vec<f64>> = vec![r.iter().map(|a| a / beta).collect()];
    let mut z: Vec<Vec<f64>> = Vec::new();
    let mut h: Vec<Vec<f64>> = Vec::new();
    let mut rot: Vec<(f64, f64)> = Vec::new();
    let mut g = vec![beta];
    let mut w = vec![0.0; n];
    for j in 0..max_iterations {
        let mut zj = v[j].clone();
        precondition(&mut zj).ok()?;
        k.mul_vec(&zj, &mut w);
        z.push(zj);
        let mut hj = vec![0.0; j + 2];
        for (i, vi) in v.iter().enumerate() {
            let hij = sdot(&w, vi);
            hj[i] = hij;
            for (a, b) in w.iter_mut().zip(vi) {
                *a -= hij * b;
            }
        }
        let wn = sdot(&w, &w).sqrt();
        hj[j + 1] = wn;
        for (i, &(c, s)) in rot.iter().enumerate() {
            let (a, b) = (hj[i], hj[i + 1]);
            hj[i] = c * a + s * b;
            hj[i + 1] = -s * a + c * b;
        }
        let d = hj[j].hypot(hj[j + 1]);
        if !d.is_finite() || d == 0.0 {
            return None;
        }
        let (c, s) = (hj[j] / d, hj[j + 1] / d);
        hj[j] = d;
        hj[j + 1] = 0.0;
        rot.push((c, s));
        g.push(-s * g[j]);
        g[j] *= c;
        h.push(hj);
        let done = g[j + 1].abs() <= tolerance * beta || wn == 0.0;
        if done || j + 1 == max_iterations {
            // back substitution H y = g, then x = Z y
            let m = j + 1;
            let mut y = vec![0.0; m];
            for i in (0..m).rev() {
                let s: f64 = (i + 1..m).map(|l| h[l][i] * y[l]).sum();
                y[i] = (g[i] - s) / h[i][i];
            }
            let mut x = vec![0.0; n];
            for (zl, yl) in z.iter().zip(&y) {
                for (a, b) in x.iter_mut().zip(zl) {
                    *a += yl * b;
                }
            }
            return confirmed(k, x, r, 10.0 * tolerance * beta, &mut w, m);
        }
        v.push(w.iter().map(|a| a / wn).collect());
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

    /// The right-hand side of the tests.
    fn rhs() -> Vec<f64> {
        (0..201).map(|i| ((i * 37) % 11) as f64 - 5.0).collect()
    }

    /// `a⁻¹ b` by `backend` (a direct one).
    fn direct(mut backend: Box<dyn LinearBackend>, a: &CsrMatrix, b: &[f64]) -> Vec<f64> {
        backend.factorize(a).unwrap();
        let mut x = b.to_vec();
        backend.solve(&mut x).unwrap();
        x
    }

    /// Every entry of `x` within `tol` times the largest of `exact` of it.
    fn assert_close(x: &[f64], exact: &[f64], tol: f64) {
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in x.iter().zip(exact) {
            assert!((a - b).abs() <= tol * scale, "{a} vs {b}");
        }
    }

    #[test]
    fn a_rank_two_change_converges_in_three_iterations_to_the_direct_solution() {
        let k_old: Vec<f64> = (0..200).map(|i| 1.0 + (i % 7) as f64).collect();
        let mut k_new = k_old.clone();
        // two springs change (two "contacts" change state): a rank-2 change
        k_new[40] *= 0.1;
        k_new[150] *= 5.0;
        let (a_old, a_new) = (chain(&k_old), chain(&k_new));
        let rhs = rhs();
        let exact = direct(Box::new(FaerCholesky::new()), &a_new, &rhs);

        let mut held = FaerCholesky::new();
        held.factorize(&a_old).unwrap();
        let out = solve_with_factor(&a_new, &mut held, &rhs, 1e-10, 10).unwrap();
        // CG preconditioned by the old factor: the preconditioned operator is the identity
        // plus a rank-2 term, so at most 3 iterations in exact arithmetic
        assert!(out.iterations <= 3, "{} iterations", out.iterations);
        assert_close(&out.x, &exact, 1e-9);
        // too few iterations allowed: the caller is told to refactorize
        assert!(solve_with_factor(&a_new, &mut held, &rhs, 1e-12, 1).is_none());
    }

    #[test]
    fn across_a_change_of_geometry_the_corrected_factor_leaves_only_the_geometry_to_iterate() {
        let k_old: Vec<f64> = (0..200).map(|i| 1.0 + (i % 7) as f64).collect();
        // two springs change state (rank 2) ...
        let mut k_states = k_old.clone();
        k_states[30] *= 0.02;
        k_states[170] *= 4.0;
        // ... and the geometry moves: every spring changes by up to 10⁻³ (a full-rank
        // change, as of every entry of K between two load increments)
        let k_new: Vec<f64> = k_states
            .iter()
            .enumerate()
            .map(|(i, k)| k * (1.0 + 1e-3 * (i as f64).sin()))
            .collect();
        let (a_old, near, a_new) = (chain(&k_old), chain(&k_states), chain(&k_new));
        let rhs = rhs();
        let exact = direct(Box::new(FaerCholesky::new()), &a_new, &rhs);

        let mut held = FaerCholesky::new();
        held.factorize(&a_old).unwrap();
        let out = solve_with_changed_factor(&a_new, &near, &mut held, &rhs, 1e-10, 10).unwrap();
        // near⁻¹ K = I + E with ‖E‖ ≤ 10⁻³ (the springs' relative change): each iteration
        // gains at least a factor 10⁻³ on the error, so 10⁻¹⁰ takes at most 4
        assert!(out.iterations <= 4, "{} iterations", out.iterations);
        assert_close(&out.x, &exact, 1e-9);
        // the held factor alone: the rank-2 change of state to iterate on as well
        let plain = solve_with_factor(&a_new, &mut held, &rhs, 1e-10, 10).unwrap();
        assert!(plain.iterations > out.iterations, "{}", plain.iterations);
        assert_close(&plain.x, &exact, 1e-9);
        // a backend that refuses the change: no answer (the caller refactorizes)
        let mut refusing = FaerCholesky::new().with_changed_max_rank(0);
        refusing.factorize(&a_old).unwrap();
        assert!(solve_with_changed_factor(&a_new, &near, &mut refusing, &rhs, 1e-10, 10).is_none());
    }

    /// `sym` (the chain of springs `k`) with two one-sided couplings at springs `a` and `b`
    /// (a slipping contact's friction–normal term of Newton's tangent is one such entry):
    /// K = K_s + a rank-2 nonsymmetric change; with the test's right-hand side and K⁻¹ of
    /// it by LU.
    fn coupled(sym: &CsrMatrix, k: &[f64], a: usize, b: usize) -> (CsrMatrix, Vec<f64>, Vec<f64>) {
        let mut tangent = sym.clone();
        tangent.add(a, a + 1, -0.6 * k[a]);
        tangent.add(b + 1, b, 0.6 * k[b]);
        let rhs = rhs();
        let exact = direct(crate::solve::backend("faer-lu").unwrap(), &tangent, &rhs);
        (tangent, rhs, exact)
    }

    #[test]
    fn gmres_on_a_nonsymmetric_rank_two_change_matches_lu_in_three_iterations() {
        let k: Vec<f64> = (0..200).map(|i| 1.0 + (i % 7) as f64).collect();
        let sym = chain(&k);
        let (tangent, rhs, exact) = coupled(&sym, &k, 40, 150);

        let mut held = FaerCholesky::new();
        held.factorize(&sym).unwrap();
        let out = gmres_with_factor(&tangent, &mut held, &rhs, 1e-12, 10).unwrap();
        // right-preconditioned by K_s: K K_s⁻¹ = I + rank 2, so GMRES ends in at most 3
        // iterations in exact arithmetic
        assert!(out.iterations <= 3, "{} iterations", out.iterations);
        assert_close(&out.x, &exact, 1e-10);
        // too few iterations allowed: the caller factorizes the tangent itself
        assert!(gmres_with_factor(&tangent, &mut held, &rhs, 1e-12, 1).is_none());
    }

    #[test]
    fn gmres_with_the_corrected_factor_needs_only_the_nonsymmetric_part() {
        let k: Vec<f64> = (0..200).map(|i| 1.0 + (i % 7) as f64).collect();
        let sym_old = chain(&k);
        // two springs changed state since the held factorization (rank 2) ...
        let mut k_new = k.clone();
        k_new[20] *= 0.05;
        k_new[120] *= 3.0;
        let near = chain(&k_new);
        // ... and the tangent adds two one-sided couplings (rank 2, nonsymmetric)
        let (tangent, rhs, exact) = coupled(&near, &k_new, 60, 180);

        let mut held = FaerCholesky::new();
        held.factorize(&sym_old).unwrap();
        let (out, corrected) =
            gmres_with_changed_factor(&tangent, &near, &mut held, &rhs, 1e-12, 10);
        let out = out.unwrap();
        assert!(corrected);
        // K near⁻¹ = I + rank 2: at most 3 iterations in exact arithmetic, against up to 5
        // with the held factor alone (I + rank 4)
        assert!(out.iterations <= 3, "{} iterations", out.iterations);
        assert_close(&out.x, &exact, 1e-10);
        let plain = gmres_with_factor(&tangent, &mut held, &rhs, 1e-12, 10).unwrap();
        assert!(plain.iterations > out.iterations, "{}", plain.iterations);
        // a backend that refuses the change: the held factor alone, the same answer
        let mut refusing = FaerCholesky::new().with_changed_max_rank(0);
        refusing.factorize(&sym_old).unwrap();
        let (out, corrected) =
            gmres_with_changed_factor(&tangent, &near, &mut refusing, &rhs, 1e-12, 10);
        let out = out.unwrap();
        assert!(!corrected);
        assert_eq!(out.iterations, plain.iterations);
        assert_close(&out.x, &exact, 1e-10);
    }
}
