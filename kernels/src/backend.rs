//! The linear solver interface shared by every backend: the [`LinearBackend`] trait, its
//! errors and counters, and the small helpers the implementations share. The backends
//! depend on this module, never the reverse; building one by name is [`crate::registry`].

use crate::csr::{CsrMatrix, CsrPattern};
use std::sync::Arc;

/// Why a factorization or a solve failed. Indices are unknown numbers in the original
/// (unpermuted) numbering.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A Cholesky (LLᵀ) pivot was not positive. `pivot` is the value of the failed pivot
    /// (the corresponding LDLᵀ pivot, same units as the matrix entries), NaN if unknown.
    #[error("the matrix is not positive definite: pivot {pivot:e} at unknown {index}")]
    NotPositiveDefinite {
        /// Unknown (original numbering) whose pivot failed.
        index: usize,
        /// Value of the failed pivot.
        pivot: f64,
    },
    /// An exactly zero pivot (LDLᵀ) or a non-finite solution (LU).
    #[error("the matrix is singular: zero pivot at unknown {index}")]
    Singular {
        /// Unknown (original numbering) at the zero pivot.
        index: usize,
    },
    /// An iterative solver did not reach its tolerance.
    #[error("no convergence after {iterations} iterations (relative residual {residual:e})")]
    NoConvergence {
        /// Iterations performed.
        iterations: usize,
        /// Final relative residual ‖b − A x‖ / ‖b‖.
        residual: f64,
    },
    /// The backend does not offer this operation (e.g.
    /// [`LinearBackend::solve_changed`]); the caller takes another way.
    #[error("the linear backend '{backend}' does not support {operation}")]
    Unsupported {
        /// The backend's name.
        backend: &'static str,
        /// What was asked of it.
        operation: &'static str,
    },
    /// Anything else (wrong sizes, solve before factorize, index overflow, ...).
    #[error("{0}")]
    Other(String),
}

/// Counters and timers of a backend, cumulative since its creation (except the fields
/// documented as "last").
#[derive(Debug, Clone, Default)]
pub struct SolverStats {
    /// Number of symbolic analyses actually performed (cache misses).
    pub symbolic_factorizations: usize,
    /// Number of numeric factorizations (or preconditioner setups for iterative solvers).
    pub numeric_factorizations: usize,
    /// Number of calls to `factorize` that returned at once because the values were
    /// bit-identical to those of the last successful factorization of the same pattern
    /// (not counted in `numeric_factorizations`).
    pub skipped_factorizations: usize,
    /// Number of solves.
    pub solves: usize,
    /// Total iterations of an iterative solver (0 for direct solvers).
    pub iterations: usize,
    /// Iterations of the last solve of an iterative solver (0 for direct solvers).
    pub last_iterations: usize,
    /// True relative residual ‖b − A x‖₂ / ‖b‖₂ of the last solve, recomputed from the
    /// returned x (not the recursively updated residual). Iterative solvers only; NaN
    /// for the direct backends, which do not keep A.
    pub last_true_residual: f64,
    /// Wall time spent in symbolic analyses, seconds.
    pub symbolic_seconds: f64,
    /// Part of `symbolic_seconds` spent in an external fill-reducing ordering (METIS),
    /// seconds; 0 with AMD, which faer computes inside its symbolic phase.
    pub ordering_seconds: f64,
    /// Wall time spent in numeric factorizations, seconds.
    pub numeric_seconds: f64,
    /// Wall time spent in solves, seconds.
    pub solve_seconds: f64,
    /// Stored entries of the factor (L for Cholesky, L + U for LU) of the last analysis.
    pub factor_nnz: usize,
    /// smallest pivot ratio d_i / a_ii seen at the last factorization (a measure of near-singularity: ~1e-16 for a mechanism).
    /// NaN when the backend does not measure it (iterative solvers; MUMPS, which reports 0
    /// when its null-pivot detection fires and NaN otherwise): callers treat NaN as "no
    /// singularity detected" and rely on the factorization or solve failing instead.
    pub min_pivot_ratio: f64,
    /// Unknown (original numbering) where `min_pivot_ratio` was reached.
    pub min_pivot_index: usize,
    /// Multiply-adds of one numeric factorization with the last analysis, from its symbolic
    /// structure (Σ over the columns of L of m(m + 1)/2, m the column's entries, plus the
    /// dense work of a substructured backend); 0 when the backend does not report it. A
    /// measure of work that does not depend on the machine's load.
    pub factor_flops: f64,
    /// Memory held by the factor or preconditioner of the last factorization, bytes, as
    /// reported by the backend; 0 when it does not report it (then see `factor_nnz`).
    pub memory_bytes: usize,
    /// Successful calls to [`LinearBackend::solve_changed`] (0 for the backends that do
    /// not support it).
    pub changed_solves: usize,
    /// Rank of the change of the last successful [`LinearBackend::solve_changed`] (the
    /// signed rank-one terms of K_new − K_old it corrected for).
    pub last_changed_rank: usize,
    /// Largest rank among the successful [`LinearBackend::solve_changed`] calls.
    pub max_changed_rank: usize,
    /// Wall time spent in [`LinearBackend::solve_changed`] (successful or not), seconds.
    pub changed_seconds: f64,
}

/// A sparse linear solver: symbolic analysis once per pattern, numeric factorization
/// whenever the values change, any number of solves.
pub trait LinearBackend: Send {
    /// Name as accepted by [`backend_from_name`](crate::registry::backend_from_name).
    fn name(&self) -> &'static str;
    /// Symbolic phase (ordering, elimination structure). Cached by pattern id: a second call with the same pattern does nothing.
    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError>;
    /// Numeric phase; calls analyze if the pattern changed. For direct solvers, fills min_pivot_ratio.
    /// Values bit-identical to those of the last successful factorization of the same
    /// pattern return at once and count in `skipped_factorizations`.
    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError>;
    /// Solve A x = rhs in place, with the last factorized matrix.
    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError>;
    /// Counters and timers.
    fn stats(&self) -> &SolverStats;
    /// Solve `a` x = rhs in place, `a` on the pattern of the last factorized matrix and
    /// differing from it by a change of low rank (a secant iteration of docs/theory.md §4 in
    /// which a few contacts changed state: ΔK = Σ over them of Bᵀ Δk B, docs/theory.md §3),
    /// without refactorizing: the held factorization stays that of the old matrix and
    /// serves the next call too. Exact up to round-off (not an iteration). Errors when the
    /// change is too large to pay (every entry changed, a rank above the backend's cap),
    /// when `a` is not positive definite ([`SolveError::NotPositiveDefinite`]), when no
    /// factorization is held; the default is [`SolveError::Unsupported`]. On any error
    /// the caller refactorizes (or iterates with the held factor as a preconditioner);
    /// `rhs` is then unspecified.
    fn solve_changed(&mut self, _a: &CsrMatrix, _rhs: &mut [f64]) -> Result<(), SolveError> {
        Err(SolveError::Unsupported {
            backend: self.name(),
            operation: "solves with a changed matrix (solve_changed)",
        })
    }
    /// The values (in the pattern's storage order) of the matrix whose factorization the
    /// backend holds, for a caller that builds the matrix a
    /// [`LinearBackend::solve_changed`] is to correct it to; `None` when no factorization
    /// is held or the backend does not keep them (the default).
    fn factorized_values(&self) -> Option<&[f64]> {
        None
    }
    /// Whether a failed Cholesky factorization computes the value of the failed pivot for
    /// its error ([`SolveError::NotPositiveDefinite`]'s `pivot`: faer's backends run an
    /// LDLᵀ factorization of the same matrix for it, as dear as a successful
    /// factorization) or leaves it NaN. On by default; the nonlinear drivers, which only
    /// ask whether a factorization succeeded (a singular secant matrix is an expected
    /// state there, met at every iteration of a mechanism), turn it off. Backends without
    /// that extra work ignore it (the default).
    fn set_failed_pivot_value(&mut self, _on: bool) {}
    /// Near-null space of the matrices to come: for elasticity of blocky structures, the
    /// rigid-body modes (docs/theory.md §2: two translations and the rotation about each
    /// block's centroid, restricted to that block's unknowns), as dense vectors of length n.
    /// Algebraic multigrid builds its coarse spaces from them (PETSc GAMG); direct solvers
    /// and the built-in PCG ignore them (the default). Call before `factorize`.
    fn set_near_null_space(&mut self, _modes: &[Vec<f64>]) -> Result<(), SolveError> {
        Ok(())
    }
    /// Number of parts this backend wants the unknowns partitioned into, to be handed
    /// over with [`LinearBackend::set_partition`]: the subdomains of
    /// `faer-substructured`, the MPI ranks of a distributed PETSc. `None` (the default)
    /// when the backend uses no partition.
    fn partition_parts(&self) -> Option<usize> {
        None
    }
    /// A partition of the unknowns: `part[i]` is the part (0-based) of unknown i, one
    /// entry per unknown of the matrices to come. dfem computes it from the structure
    /// (whole blocks, cuts along joints: `dfem::solve::block_partition`). Backends that
    /// use no partition ignore it (the default); the others use it from their next
    /// analysis on instead of their own. Call before `factorize`.
    fn set_partition(&mut self, _part: &[u32]) -> Result<(), SolveError> {
        Ok(())
    }
    /// The blocks' interiors: `group[i]` is the index of the block whose interior unknown
    /// i is — an unknown whose stiffness comes from its own block alone, on a node that
    /// no contact acts on — and `u32::MAX` for every other unknown (contact nodes, rigid
    /// blocks), one entry per unknown of the matrices to come. A backend that condenses
    /// the interiors out (`faer-condensed`, [`crate::condensed`]) uses it; the others
    /// ignore it (the default). Call before `factorize`.
    fn set_interiors(&mut self, _group: &[u32]) -> Result<(), SolveError> {
        Ok(())
    }
}

/// Whether two value arrays are bit-identical (the skip test of `factorize`, and of
/// `solve_changed`'s reuse of its last correction). Long arrays are compared in chunks of
/// [`SAME_BITS_CHUNK`] on rayon's threads (a yes or no: the same answer on any number).
pub fn same_bits(a: &[f64], b: &[f64]) -> bool {
    let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
    a.len() == b.len()
        && if a.len() <= SAME_BITS_CHUNK {
            same(a, b)
        } else {
            use rayon::prelude::*;
            a.par_chunks(SAME_BITS_CHUNK)
                .zip(b.par_chunks(SAME_BITS_CHUNK))
                .all(|(x, y)| same(x, y))
        }
}

/// Entries per task of [`same_bits`] (and of the low-rank correction's scan of a changed
/// matrix): 16 384 × 8 bytes, a few microseconds of reading, well above rayon's cost of a
/// task.
pub const SAME_BITS_CHUNK: usize = 1 << 14;

/// maxᵢ |xᵢ − yᵢ| / maxᵢ |yᵢ|: how far a solution `x` is from a reference `y`, relative
/// to the reference's largest entry (NaN when `y` is all zeros).
pub fn max_relative_difference(x: &[f64], y: &[f64]) -> f64 {
    let d = x
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    d / y.iter().map(|v| v.abs()).fold(0.0, f64::max)
}

/// Checks that a matrix's values fit its pattern (before a numeric factorization).
pub(crate) fn check_values(a: &CsrMatrix) -> Result<(), SolveError> {
    if a.values.len() != a.pattern.nnz() {
        return Err(SolveError::Other(
            "matrix values do not match the pattern".into(),
        ));
    }
    Ok(())
}
