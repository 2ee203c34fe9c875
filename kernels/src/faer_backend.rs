//! Direct solvers on faer's sparse factorizations: [`FaerCholesky`] (LLᵀ),
//! [`FaerLdlt`] (LDLᵀ without pivoting) and [`FaerLu`] (LU with partial pivoting).
//!
//! All of them keep the symbolic analysis (fill-reducing ordering — AMD by default, METIS
//! nested dissection on request for the Cholesky backends —, elimination tree, supernodes),
//! the factor value buffer and the scratch memory for as long as the pattern id does not
//! change. By default they factorize and solve with `Par::Seq`: faer's sparse
//! factorizations gain little from a second thread on 2D problems, and sequential runs
//! give the same bits for any rayon pool size. `with_threads(k)` on the Cholesky backends
//! passes `Par::rayon(k)` to faer's dense supernode kernels instead (not bit-identical to
//! the sequential run).
//!
//! `factorize` with values bit-identical to those of the last successful factorization of
//! the same pattern returns at once (counted in `SolverStats::skipped_factorizations`).
//!
//! The symmetric CSR matrix is passed to faer as a compressed-sparse-column view of the
//! same arrays (a structurally symmetric CSR is its own CSC); with `Side::Lower` faer
//! reads only the entries with row ≥ column.

use crate::backend::{same_bits, LinearBackend, SolveError, SolverStats};
use crate::cholesky::{check_rhs, col_ptr_u32, faer_err, CholeskyCore, Kind};
use crate::csr::{CsrMatrix, CsrPattern};
use crate::lowrank::LowRankCorrection;
use crate::ordering::FillOrdering;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{
    factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu,
};
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};
use std::sync::Arc;
use std::time::Instant;

pub use crate::cholesky::{DEFAULT_SUPERNODAL_THRESHOLD, SUPERNODAL_FLOP_RATIO};

/// Sparse Cholesky LLᵀ (faer; AMD or METIS ordering, see [`FaerCholesky::with_ordering`];
/// supernodal or simplicial chosen by faer).
/// Fails with [`SolveError::NotPositiveDefinite`] on a non-positive pivot; after a
/// success, `stats().min_pivot_ratio` = minᵢ L_ii² / a_ii.
/// [`LinearBackend::solve_changed`] solves with a matrix that differs from the factorized
/// one by a low-rank change through a [`LowRankCorrection`] of the held factor (rank
/// limit [`CHANGED_MAX_RANK`], see [`FaerCholesky::with_changed_max_rank`]).
pub struct FaerCholesky(CholeskyCore, LowRankCorrection);

/// Default rank limit of [`FaerCholesky`]'s `solve_changed`: a correction of rank r costs
/// about 0.18–0.32 of a numeric refactorization at r = 18–45 and 0.73–1.03 at r = 449 on
/// the 100 × 100 deformable wall, relatively more on smaller models, whose change the
/// static driver keeps lower itself (`Driver::low_rank_limit` in
/// src/analysis/statics.rs); docs/decisions/0012-low-rank-correction-limits.md.
pub const CHANGED_MAX_RANK: usize = 256;

/// Sparse LDLᵀ without pivoting (faer). Negative pivots are accepted (indefinite
/// matrices without a zero leading minor still factor); an exactly zero pivot gives
/// [`SolveError::Singular`]. Semi-definiteness shows through
/// `stats().min_pivot_ratio` = minᵢ D_ii / |a_ii| (≈ 1e-16 or negative for a mechanism):
/// the caller decides on the threshold.
pub struct FaerLdlt(CholeskyCore);

impl Default for FaerCholesky {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerCholesky {
    /// A backend with no analysis yet.
    pub fn new() -> Self {
        Self(
            CholeskyCore::new(Kind::Llt),
            LowRankCorrection::new().with_max_rank(CHANGED_MAX_RANK),
        )
    }

    /// Sets the rank limit of [`LinearBackend::solve_changed`] (default
    /// [`CHANGED_MAX_RANK`]): a change of higher rank is refused with an error, and the
    /// caller refactorizes; 0 refuses every change but none.
    pub fn with_changed_max_rank(mut self, r: usize) -> Self {
        self.1 = LowRankCorrection::new().with_max_rank(r);
        self
    }

    /// The shared core (its analysis holds the factor).
    pub(crate) fn core(&self) -> &CholeskyCore {
        &self.0
    }

    /// `LinearBackend::solve`: with more than one rayon thread, the substitutions on
    /// independent subtrees of the supernodal elimination tree in parallel
    /// ([`LowRankCorrection`]'s split, bit-identical to faer's sequential solve); else,
    /// and for a simplicial factor, faer's solve.
    fn solve_held(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        if self.0.threads <= 1 && rayon::current_num_threads() > 1 {
            let t = Instant::now();
            let mut correction = std::mem::take(&mut self.1);
            let done = correction.solve_held(&self.0, rhs);
            self.1 = correction;
            if done? {
                self.0.stats.solves += 1;
                self.0.stats.solve_seconds += t.elapsed().as_secs_f64();
                return Ok(());
            }
        }
        self.0.solve(rhs)
    }
}

/// The low-rank correction's operations on a held [`FaerCholesky`] factor (the work is in
/// [`crate::lowrank`], on the backend's core; these take the backend, so that the
/// correction does not import the backend that holds one).
impl LowRankCorrection {
    /// Prepares solves with `k_new` (same pattern as the matrix `factor` last factorized,
    /// any units as long as they are K's) from `factor`'s held factorization of K_old.
    ///
    /// Errors: no factorization held, another pattern, a rank above the limit
    /// ([`SolveError::Other`]); K_new not positive definite or nearly singular
    /// ([`SolveError::NotPositiveDefinite`], `index` an unknown of the offending block
    /// of ΔK, `pivot` NaN).
    pub fn update(&mut self, factor: &FaerCholesky, k_new: &CsrMatrix) -> Result<(), SolveError> {
        self.update_on(&factor.0, k_new)
    }

    /// rhs ← K_new⁻¹ rhs: [`update`](Self::update) for `k_new` unless the last successful
    /// one was made for the same values and the same held factorization (several solves
    /// with one K_new), then [`solve`](Self::solve). The work of
    /// [`FaerCholesky`]'s `LinearBackend::solve_changed`.
    pub fn solve_changed(
        &mut self,
        factor: &FaerCholesky,
        k_new: &CsrMatrix,
        rhs: &mut [f64],
    ) -> Result<(), SolveError> {
        self.solve_changed_on(&factor.0, k_new, rhs)
    }

    /// rhs ← K_new⁻¹ rhs for the K_new of the last successful [`update`](Self::update),
    /// with the same held factorization (else an error).
    pub fn solve(&mut self, factor: &FaerCholesky, rhs: &mut [f64]) -> Result<(), SolveError> {
        self.solve_on(&factor.0, rhs)
    }
}

impl Default for FaerLdlt {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerLdlt {
    /// `LinearBackend::solve`: faer's.
    fn solve_held(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        self.0.solve(rhs)
    }

    /// A backend with no analysis yet.
    pub fn new() -> Self {
        Self(CholeskyCore::new(Kind::Ldlt))
    }
}

/// The settings and queries of the backends on a [`CholeskyCore`] (field `.0`): one
/// definition for [`FaerCholesky`] and [`FaerLdlt`].
macro_rules! core_settings {
    ($t:ty) => {
        impl $t {
            /// Whether the last analysis chose faer's supernodal factorization, rather than its
            /// simplicial one (`None` before the first analysis).
            pub fn supernodal(&self) -> Option<bool> {
                self.0.supernodal()
            }

            /// Sets faer's supernodal threshold (takes effect at the next analysis):
            /// supernodal where the flops per factor entry exceed 40 times it;
            /// [`DEFAULT_SUPERNODAL_THRESHOLD`] (default: a ratio of
            /// [`SUPERNODAL_FLOP_RATIO`]), 1 = faer's automatic choice, 0 = always
            /// supernodal, `f64::INFINITY` = always simplicial.
            pub fn with_supernodal_threshold(mut self, threshold: f64) -> Self {
                self.0.supernodal_threshold = threshold;
                self.0.analysis = None;
                self
            }

            /// Sets the fill-reducing ordering (takes effect at the next analysis): AMD (default)
            /// or METIS nested dissection; the backend's name gets a `-metis` suffix with METIS.
            pub fn with_ordering(mut self, ordering: FillOrdering) -> Self {
                self.0.ordering = ordering;
                self.0.analysis = None;
                self
            }

            /// The fill-reducing ordering in use.
            pub fn ordering(&self) -> FillOrdering {
                self.0.ordering
            }

            /// Number of threads for faer's numeric factorization and solve (default 1 =
            /// sequential, bit-identical for any rayon pool; k > 1 passes `Par::rayon(k)`, which
            /// parallelises inside the dense supernode kernels only and is not bit-identical to
            /// the sequential run). Takes effect at the next analysis.
            pub fn with_threads(mut self, threads: usize) -> Self {
                self.0.threads = threads.max(1);
                self.0.analysis = None;
                self
            }

            /// Sets faer's supernode relaxation (amalgamation) thresholds: two adjacent
            /// supernodes with `c` columns in total and a fraction `z` of explicit zeros after
            /// merging are merged when `c <= relax[k].0 && z < relax[k].1` for some k. `None`
            /// restores faer's defaults `[(4, 1.0), (16, 0.8), (48, 0.1), (usize::MAX, 0.05)]`.
            /// Takes effect at the next analysis.
            pub fn with_supernode_relaxation(mut self, relax: Option<Vec<(usize, f64)>>) -> Self {
                self.0.relax = relax;
                self.0.analysis = None;
                self
            }

            /// Whether to ask Linux for transparent huge pages for the factor (default `true`).
            /// Takes effect at the next analysis.
            pub fn with_huge_pages(mut self, on: bool) -> Self {
                self.0.huge_pages = on;
                self.0.analysis = None;
                self
            }
        }
    };
}
core_settings!(FaerCholesky);
core_settings!(FaerLdlt);

macro_rules! chol_backend {
    ($t:ty, $name:literal, $metis_name:literal $(, $extra:item)*) => {
        impl LinearBackend for $t {
            fn name(&self) -> &'static str {
                match self.0.ordering {
                    FillOrdering::Amd => $name,
                    FillOrdering::Metis => $metis_name,
                }
            }
            fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
                self.0.analyze(pattern)
            }
            fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
                self.0.factorize(a)
            }
            fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
                self.solve_held(rhs)
            }
            fn stats(&self) -> &SolverStats {
                &self.0.stats
            }
            $($extra)*
        }
    };
}
chol_backend!(
    FaerCholesky,
    "faer-cholesky",
    "faer-cholesky-metis",
    fn solve_changed(&mut self, a: &CsrMatrix, rhs: &mut [f64]) -> Result<(), SolveError> {
        let t = Instant::now();
        let mut correction = std::mem::take(&mut self.1);
        let out = correction.solve_changed(self, a, rhs);
        let rank = correction.stats().rank;
        self.1 = correction;
        let stats = &mut self.0.stats;
        stats.changed_seconds += t.elapsed().as_secs_f64();
        if out.is_ok() {
            stats.changed_solves += 1;
            stats.last_changed_rank = rank;
            stats.max_changed_rank = stats.max_changed_rank.max(rank);
        }
        out
    },
    fn factorized_values(&self) -> Option<&[f64]> {
        let an = self.0.analysis.as_ref().filter(|an| an.factored)?;
        Some(&an.last_values)
    },
    fn set_failed_pivot_value(&mut self, on: bool) {
        self.0.failed_pivot_value = on;
    }
);
chol_backend!(FaerLdlt, "faer-ldlt", "faer-ldlt-metis");

struct LuAnalysis {
    pattern: Arc<CsrPattern>,
    col_ptr: Vec<u32>,
    symbolic: SymbolicLu<u32>,
    numeric: NumericLu<u32, f64>,
    mem: MemBuffer,
    factored: bool,
    /// Values of the last successful factorization (to skip an identical one).
    last_values: Vec<f64>,
}

/// Sparse LU with partial pivoting (faer, COLAMD column ordering); the symbolic analysis
/// and the numeric storage are reused across factorizations of the same pattern.
/// Works for unsymmetric values on the (structurally symmetric) CSR pattern: the CSR
/// arrays read as CSC are Aᵀ, which is factorized, and solves use the transposed solve.
/// `min_pivot_ratio` is not computed (NaN); a singular matrix shows as a
/// [`SolveError::Singular`] at the first non-finite solution entry.
pub struct FaerLu {
    analysis: Option<LuAnalysis>,
    supernodal_threshold: f64,
    stats: SolverStats,
}

impl Default for FaerLu {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerLu {
    /// A backend with no analysis yet.
    pub fn new() -> Self {
        Self {
            analysis: None,
            supernodal_threshold: DEFAULT_SUPERNODAL_THRESHOLD,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Sets faer's supernodal threshold (takes effect at the next analysis), as
    /// [`FaerCholesky::with_supernodal_threshold`]; faer's LU measures the flops per entry
    /// of L + U from the column elimination tree.
    pub fn with_supernodal_threshold(mut self, threshold: f64) -> Self {
        self.supernodal_threshold = threshold;
        self.analysis = None;
        self
    }
}

impl LinearBackend for FaerLu {
    fn name(&self) -> &'static str {
        "faer-lu"
    }

    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        if self
            .analysis
            .as_ref()
            .is_some_and(|a| a.pattern.id() == pattern.id())
        {
            return Ok(());
        }
        self.analysis = None;
        let t = Instant::now();
        let n = pattern.n();
        let col_ptr = col_ptr_u32(pattern)?;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, pattern.col_idx());
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold(self.supernodal_threshold),
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(sym, params).map_err(faer_err)?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_transpose_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req)
            .map_err(|_| SolveError::Other("out of memory for faer scratch".into()))?;
        self.analysis = Some(LuAnalysis {
            pattern: pattern.clone(),
            col_ptr,
            symbolic,
            numeric: NumericLu::new(),
            mem,
            factored: false,
            last_values: Vec::new(),
        });
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        let t = Instant::now();
        let an = self.analysis.as_mut().expect("analyzed");
        if a.values.len() != an.pattern.nnz() {
            an.factored = false;
            return Err(SolveError::Other(
                "matrix values do not match the pattern".into(),
            ));
        }
        if an.factored && same_bits(&a.values, &an.last_values) {
            self.stats.skipped_factorizations += 1;
            return Ok(());
        }
        an.factored = false;
        let n = an.pattern.n();
        let sym =
            SymbolicSparseColMatRef::new_checked(n, n, &an.col_ptr, None, an.pattern.col_idx());
        let mat = SparseColMatRef::new(sym, &a.values);
        let r = an
            .symbolic
            .factorize_numeric_lu(
                &mut an.numeric,
                mat,
                Par::Seq,
                MemStack::new(&mut an.mem),
                Default::default(),
            )
            .map(|_| ());
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t.elapsed().as_secs_f64();
        match r {
            Ok(()) => {
                an.last_values.clear();
                an.last_values.extend_from_slice(&a.values);
                an.factored = true;
                Ok(())
            }
            Err(LuError::SymbolicSingular { index }) => Err(SolveError::Singular { index }),
            Err(LuError::Generic(e)) => Err(faer_err(e)),
        }
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let an = match &mut self.analysis {
            Some(an) if an.factored => an,
            _ => {
                return Err(SolveError::Other(
                    "solve called without a successful factorization".into(),
                ))
            }
        };
        let n = an.pattern.n();
        check_rhs(n, rhs)?;
        let t = Instant::now();
        {
            let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
            LuRef::new_unchecked(&an.symbolic, &an.numeric).solve_transpose_in_place_with_conj(
                Conj::No,
                x,
                Par::Seq,
                MemStack::new(&mut an.mem),
            );
        }
        self.stats.solves += 1;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        if let Some(i) = rhs.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::Singular { index: i });
        }
        Ok(())
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }
}
