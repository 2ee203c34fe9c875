//! The Cholesky core shared by faer's LLᵀ and LDLᵀ backends ([`crate::faer_backend`]) and
//! by the backends built from it ([`crate::split`], [`crate::condensed`], the low-rank
//! correction of [`crate::lowrank`]): the symbolic analysis kept per pattern, the numeric
//! factorization with its pivot report, the solve, the flop counts, the supernodal switch,
//! and the small conversions to faer that [`crate::faer_backend`]'s LU uses too.
//! A module of its own so that the low-rank correction, which reads the held factor, and
//! the backend that holds a correction do not import each other.

use crate::backend::{same_bits, SolveError, SolverStats};
use crate::csr::{CsrMatrix, CsrPattern};
use crate::ordering::{metis_nested_dissection, FillOrdering};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Arc;
use std::time::Instant;

/// Row pointers converted to faer's index type (u32): the pattern must have fewer than
/// 2³² stored entries.
pub(crate) fn col_ptr_u32(p: &CsrPattern) -> Result<Vec<u32>, SolveError> {
    if p.nnz() >= u32::MAX as usize {
        return Err(SolveError::Other(format!(
            "the matrix has {} stored entries; the faer backends use 32-bit indices",
            p.nnz()
        )));
    }
    Ok(p.row_ptr().iter().map(|&x| x as u32).collect())
}

/// A faer error as a [`SolveError`].
pub(crate) fn faer_err(e: impl std::fmt::Debug) -> SolveError {
    SolveError::Other(format!("faer: {e:?}"))
}

/// Checks that a right-hand side has the matrix's order `n`.
pub(crate) fn check_rhs(n: usize, rhs: &[f64]) -> Result<(), SolveError> {
    if rhs.len() != n {
        return Err(SolveError::Other(format!(
            "right-hand side has length {}, expected {n}",
            rhs.len()
        )));
    }
    Ok(())
}

/// Which factorization a [`CholeskyCore`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    /// LLᵀ (Cholesky).
    Llt,
    /// LDLᵀ without pivoting.
    Ldlt,
}

/// Symbolic analysis and buffers kept for one pattern.
pub(crate) struct CholAnalysis {
    pub(crate) pattern: Arc<CsrPattern>,
    col_ptr: Vec<u32>,
    pub(crate) symbolic: SymbolicCholesky<u32>,
    pub(crate) l_values: Vec<f64>,
    pub(crate) mem: MemBuffer,
    diag_pos: Vec<usize>,
    pub(crate) factored: bool,
    /// Values of the last successful factorization (to skip an identical one).
    pub(crate) last_values: Vec<f64>,
}

/// faer's numeric LDLᵀ factorization of `mat` (the pattern of `symbolic`) into
/// `l_values`; `Err(index)`: a zero pivot at that (faer's) index.
fn numeric_ldlt(
    symbolic: &SymbolicCholesky<u32>,
    l_values: &mut [f64],
    mem: &mut MemBuffer,
    mat: SparseColMatRef<'_, u32, f64>,
    par: Par,
) -> Result<(), usize> {
    symbolic
        .factorize_numeric_ldlt(
            l_values,
            mat,
            Side::Lower,
            LdltRegularization::default(),
            par,
            MemStack::new(mem),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|LdltError::ZeroPivot { index }| index)
}

impl CholAnalysis {
    /// Permuted column of a failed pivot from faer's error index (0-based permuted column
    /// in both the simplicial and the supernodal variants, checked by the tests); clamped
    /// to a valid index.
    fn failed_column(&self, index: usize) -> usize {
        index.min(self.pattern.n().saturating_sub(1))
    }

    /// Original index of permuted index `p`.
    pub(crate) fn original(&self, p: usize) -> usize {
        match self.symbolic.perm() {
            Some(perm) => perm.arrays().0[p] as usize,
            None => p,
        }
    }

    /// Multiply-adds of a numeric factorization ([`symbolic_flops`]).
    pub(crate) fn flops(&self) -> f64 {
        symbolic_flops(&self.symbolic)
    }

    /// Diagonal of the stored factor, in permuted order: L_pp for LLᵀ, D_pp for LDLᵀ.
    pub(crate) fn factor_diagonal(&self) -> Vec<f64> {
        let n = self.pattern.n();
        let mut d = vec![0.0; n];
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                let ri = s.row_idx();
                for (j, dj) in d.iter_mut().enumerate() {
                    let range = cp[j] as usize..cp[j + 1] as usize;
                    if let Some(k) = ri[range.clone()].iter().position(|&r| r as usize == j) {
                        *dj = self.l_values[range.start + k];
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let r = SupernodalLltRef::new(s, &self.l_values);
                for sn in 0..s.n_supernodes() {
                    let node = r.supernode(sn);
                    let start = node.start();
                    let val = node.val();
                    for k in 0..val.ncols() {
                        d[start + k] = val[(k, k)];
                    }
                }
            }
        }
        d
    }
}

/// Asks Linux for transparent huge pages on the (not yet touched) buffer: the first
/// factorization then takes a few hundred page faults instead of one per 4 KiB, and the
/// factorization runs with fewer TLB misses. A hint only: errors are ignored, and other
/// systems do nothing.
#[allow(unused_variables)]
fn advise_huge_pages(buf: &mut [f64]) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let bytes = std::mem::size_of_val(buf);
        if bytes < 2 * HUGE {
            return;
        }
        let start = buf.as_mut_ptr() as usize;
        let aligned = start.next_multiple_of(HUGE);
        let end = (start + bytes) / HUGE * HUGE;
        if end > aligned {
            // SAFETY: the range lies inside `buf`, which we borrow mutably; MADV_HUGEPAGE
            // changes no content, only how the pages are backed.
            unsafe {
                libc::madvise(
                    aligned as *mut libc::c_void,
                    end - aligned,
                    libc::MADV_HUGEPAGE,
                );
            }
        }
    }
}

/// Multiply-adds of a numeric factorization with the symbolic structure `symbolic`: Σ
/// over the columns of L of m(m + 1)/2, m the column's stored entries (the diagonal
/// included).
pub(crate) fn symbolic_flops(symbolic: &SymbolicCholesky<u32>) -> f64 {
    let col = |m: usize| (m * (m + 1) / 2) as f64;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s
            .col_ptr()
            .windows(2)
            .map(|w| col((w[1] - w[0]) as usize))
            .sum(),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let begin = s.supernode_begin();
            let end = s.supernode_end();
            // the values of supernode k: a (c + p) × c block, p rows below it
            let vals = s.col_ptr_for_val();
            (0..s.n_supernodes())
                .map(|k| {
                    let c = (end[k] - begin[k]) as usize;
                    let p = (vals[k + 1] - vals[k]) as usize / c.max(1) - c;
                    (0..c).map(|j| col(c - j + p)).sum::<f64>()
                })
                .sum()
        }
    }
}

/// [`symbolic_flops`] of the Cholesky factorization of a matrix with the symmetric pattern
/// `pattern` in faer's AMD order (the default backend's analysis, without allocating the
/// factor).
pub(crate) fn cholesky_flops(pattern: &CsrPattern) -> Result<f64, SolveError> {
    let n = pattern.n();
    let col_ptr = col_ptr_u32(pattern)?;
    let sym = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, pattern.col_idx());
    let symbolic = factorize_symbolic_cholesky(
        sym,
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(faer_err)?;
    Ok(symbolic_flops(&symbolic))
}

/// faer's choice between its simplicial and supernodal Cholesky factorizations compares
/// the symbolic factor's flops per entry, (Σⱼ cⱼ + Σⱼ cⱼ(cⱼ + 1)/2) / nnz(L) with cⱼ the
/// entries of column j, with 40 times the threshold it is given ([`SupernodalThreshold`];
/// 1 = faer's automatic choice, at a ratio of 40). dfem's matrices reach the crossover far
/// below 40: the contacts couple whole blocks (a rigid block's three unknowns, a deformable
/// block's contact nodes), which the supernodes take as dense blocks. The supernodal
/// factorization wins from a ratio of about 12 on (2.7–3.7× faster at 31.6–40), the
/// simplicial one, with its cheaper solves, only below; faer's LU takes the same
/// threshold on its own measure of L + U (`cargo bench --bench supernodal`;
/// docs/decisions/0015-supernodal-flop-ratio.md).
pub const SUPERNODAL_FLOP_RATIO: f64 = 12.0;
/// faer's own factor on the flop ratio (`CHOLESKY_SUPERNODAL_RATIO_FACTOR` and
/// `LU_SUPERNODAL_RATIO_FACTOR` in faer 0.24), by which its threshold is scaled.
const FAER_RATIO_FACTOR: f64 = 40.0;
/// The [`SupernodalThreshold`] that puts faer's switch at [`SUPERNODAL_FLOP_RATIO`].
pub const DEFAULT_SUPERNODAL_THRESHOLD: f64 = SUPERNODAL_FLOP_RATIO / FAER_RATIO_FACTOR;

/// Shared implementation of the LLᵀ and LDLᵀ backends.
pub(crate) struct CholeskyCore {
    kind: Kind,
    /// A given fill-reducing permutation `(fwd, inv)`, overriding `ordering`.
    pub(crate) custom_perm: Option<(Vec<u32>, Vec<u32>)>,
    pub(crate) ordering: FillOrdering,
    pub(crate) supernodal_threshold: f64,
    /// Threads given to faer's numeric kernels (1 = `Par::Seq`).
    pub(crate) threads: usize,
    /// faer's supernode relaxation thresholds (`None`: faer's defaults).
    pub(crate) relax: Option<Vec<(usize, f64)>>,
    /// Ask the kernel for transparent huge pages for the factor values.
    pub(crate) huge_pages: bool,
    /// A failed LLᵀ computes the failed pivot's value (an LDLᵀ factorization) for its
    /// error (`LinearBackend::set_failed_pivot_value`).
    pub(crate) failed_pivot_value: bool,
    pub(crate) analysis: Option<CholAnalysis>,
    pub(crate) stats: SolverStats,
}

impl CholeskyCore {
    /// An LLᵀ core with a given permutation, always supernodal, its numeric
    /// factorization on `Par::rayon(threads)` (1 = sequential).
    pub(crate) fn llt_with_perm(fwd: Vec<u32>, inv: Vec<u32>, threads: usize) -> Self {
        let mut c = Self::new(Kind::Llt);
        c.custom_perm = Some((fwd, inv));
        c.supernodal_threshold = 0.0;
        c.threads = threads.max(1);
        c
    }

    pub(crate) fn new(kind: Kind) -> Self {
        Self {
            kind,
            custom_perm: None,
            ordering: FillOrdering::Amd,
            supernodal_threshold: DEFAULT_SUPERNODAL_THRESHOLD,
            threads: 1,
            relax: None,
            huge_pages: true,
            failed_pivot_value: true,
            analysis: None,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Whether the last analysis chose faer's supernodal factorization (`None` before the
    /// first analysis).
    pub(crate) fn supernodal(&self) -> Option<bool> {
        let an = self.analysis.as_ref()?;
        Some(matches!(
            an.symbolic.raw(),
            SymbolicCholeskyRaw::Supernodal(_)
        ))
    }

    fn par(&self) -> Par {
        if self.threads <= 1 {
            Par::Seq
        } else {
            Par::rayon(self.threads)
        }
    }

    pub(crate) fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
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
        let mut params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold(self.supernodal_threshold),
            ..Default::default()
        };
        if let Some(relax) = &self.relax {
            params.supernodal_params.relax = Some(relax);
        }
        let symbolic = match (&self.custom_perm, self.ordering) {
            (Some((fwd, inv)), _) => {
                if fwd.len() != n || inv.len() != n {
                    return Err(SolveError::Other("permutation of the wrong length".into()));
                }
                let perm = PermRef::new_checked(fwd, inv, n);
                factorize_symbolic_cholesky(
                    sym,
                    Side::Lower,
                    SymmetricOrdering::Custom(perm),
                    params,
                )
                .map_err(faer_err)?
            }
            (None, FillOrdering::Amd) => {
                factorize_symbolic_cholesky(sym, Side::Lower, SymmetricOrdering::Amd, params)
                    .map_err(faer_err)?
            }
            (None, FillOrdering::Metis) => {
                if n > i32::MAX as usize {
                    return Err(SolveError::Other(format!(
                        "{n} unknowns: too many for METIS' 32-bit indices"
                    )));
                }
                let t_order = Instant::now();
                let (fwd, inv) = metis_nested_dissection(pattern)?;
                self.stats.ordering_seconds += t_order.elapsed().as_secs_f64();
                let perm = PermRef::new_checked(&fwd, &inv, n);
                factorize_symbolic_cholesky(
                    sym,
                    Side::Lower,
                    SymmetricOrdering::Custom(perm),
                    params,
                )
                .map_err(faer_err)?
            }
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(self.par(), Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(self.par(), Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, self.par()),
        ]);
        let mem = MemBuffer::try_new(req)
            .map_err(|_| SolveError::Other("out of memory for faer scratch".into()))?;
        let mut l_values = vec![0.0; symbolic.len_val()];
        if self.huge_pages {
            advise_huge_pages(&mut l_values);
        }
        self.stats.factor_nnz = l_values.len();
        let analysis = CholAnalysis {
            pattern: pattern.clone(),
            col_ptr,
            symbolic,
            l_values,
            mem,
            diag_pos: pattern.diagonal_positions(),
            factored: false,
            last_values: Vec::new(),
        };
        self.stats.factor_flops = analysis.flops();
        self.analysis = Some(analysis);
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    pub(crate) fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        let t = Instant::now();
        let kind = self.kind;
        let par = self.par();
        let failed_pivot_value = self.failed_pivot_value;
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
        let result = match kind {
            Kind::Llt => an
                .symbolic
                .factorize_numeric_llt(
                    &mut an.l_values,
                    mat,
                    Side::Lower,
                    LltRegularization::default(),
                    par,
                    MemStack::new(&mut an.mem),
                    Default::default(),
                )
                .map(|_| ())
                .map_err(|LltError::NonPositivePivot { index }| Ok(index)),
            Kind::Ldlt => numeric_ldlt(&an.symbolic, &mut an.l_values, &mut an.mem, mat, par)
                .map_err(|index| Err(SolveError::Singular { index })),
        };
        self.stats.numeric_factorizations += 1;
        // faer reports the failed pivot 1-based from its simplicial kernels (`k + 1`) and
        // 0-based from its supernodal (dense) ones: bring both to 0-based permuted indices.
        let simplicial = matches!(an.symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_));
        let zero_based =
            |i: usize| if simplicial { i.saturating_sub(1) } else { i }.min(n.saturating_sub(1));
        let result = match result {
            Err(Ok(p)) => Err(Ok(zero_based(p))),
            Err(Err(SolveError::Singular { index })) => Err(Err(SolveError::Singular {
                index: zero_based(index),
            })),
            other => other,
        };
        let outcome = match result {
            Ok(()) => {
                let d = an.factor_diagonal();
                let mut best = (f64::INFINITY, 0usize);
                for (p, &dp) in d.iter().enumerate() {
                    let di = if kind == Kind::Llt { dp * dp } else { dp };
                    let i = an.original(p);
                    let aii = a.values[an.diag_pos[i]];
                    let ratio = if aii != 0.0 { di / aii.abs() } else { di };
                    // NaN ratios (NaN input) are reported first
                    if ratio < best.0 || ratio.is_nan() && !best.0.is_nan() {
                        best = (ratio, i);
                    }
                }
                if n == 0 {
                    best = (f64::NAN, 0);
                }
                self.stats.min_pivot_ratio = best.0;
                self.stats.min_pivot_index = best.1;
                an.last_values.clear();
                an.last_values.extend_from_slice(&a.values);
                an.factored = true;
                Ok(())
            }
            Err(Err(SolveError::Singular { index })) => {
                let i = an.original(an.failed_column(index));
                self.stats.min_pivot_ratio = 0.0;
                self.stats.min_pivot_index = i;
                Err(SolveError::Singular { index: i })
            }
            Err(Err(e)) => Err(e),
            Err(Ok(index)) => {
                let p = an.failed_column(index);
                // LLᵀ failed at permuted column p: the LDLᵀ pivot there is the failed value.
                let i = an.original(p);
                let pivot = if failed_pivot_value {
                    match numeric_ldlt(&an.symbolic, &mut an.l_values, &mut an.mem, mat, par) {
                        Ok(()) => an.factor_diagonal()[p],
                        Err(index) if an.failed_column(index) == p => 0.0,
                        Err(_) => f64::NAN,
                    }
                } else {
                    f64::NAN
                };
                self.stats.min_pivot_ratio = f64::NAN;
                self.stats.min_pivot_index = i;
                Err(SolveError::NotPositiveDefinite { index: i, pivot })
            }
        };
        self.stats.numeric_seconds += t.elapsed().as_secs_f64();
        outcome
    }

    pub(crate) fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let par = self.par();
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
        let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
        let stack = MemStack::new(&mut an.mem);
        match self.kind {
            Kind::Llt => LltRef::new(&an.symbolic, &an.l_values).solve_in_place_with_conj(
                Conj::No,
                x,
                par,
                stack,
            ),
            Kind::Ldlt => LdltRef::new(&an.symbolic, &an.l_values).solve_in_place_with_conj(
                Conj::No,
                x,
                par,
                stack,
            ),
        }
        self.stats.solves += 1;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }
}
