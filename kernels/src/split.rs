//! [`FaerCholeskySplit`]: sparse Cholesky LLᵀ that factorizes the two halves of a
//! METIS vertex bisection at the same time, on two threads, and joins them through the
//! dense Schur complement of the separator.
//!
//! faer's supernodal factorization parallelises only inside dense supernodes, which on 2D
//! meshes are small; the two subtrees below a separator are independent, and this
//! backend runs them on two rayon tasks. With the unknowns split into interiors I₁, I₂
//! and a separator S (no coupling between I₁ and I₂):
//!
//! * half k is the principal sub-matrix Kₖ = A\[Iₖ ∪ S, Iₖ ∪ S\], ordered by METIS
//!   nested dissection of Iₖ (or the global AMD order restricted to Iₖ) with S last, and factorized by faer: Kₖ = Lₖ Lₖᵀ, whose trailing block Lₖ,SS gives
//!   Lₖ,SS Lₖ,SSᵀ = A_SS − A_SIₖ A_IₖIₖ⁻¹ A_IₖS;
//! * the separator's Schur complement is C = L₁,SS L₁,SSᵀ + L₂,SS L₂,SSᵀ − A_SS (dense,
//!   |S| × |S|; |S| ≈ 2·√n on a 2D mesh), factorized by a dense Cholesky;
//! * a solve is a forward solve with each Lₖ (in parallel), a dense solve with C, and a
//!   backward solve with each Lₖ (in parallel).
//!
//! This is the first level of a nested-dissection tree, the same factor as a global
//! factorization in the order (I₁, I₂, S). Every half is factorized sequentially and the
//! dense steps run on one thread, so the result does not depend on the thread count.
//! When a split is not possible (tiny or disconnected matrix, empty separator or part,
//! or faer reorders S away from the end) the backend factorizes the whole matrix with
//! one [`FaerCholesky`] instead. `min_pivot_ratio` is not computed (NaN). A non-positive
//! pivot inside a half is reported at its unknown; one in the separator's dense Schur
//! complement at the first separator unknown, with `pivot` NaN.

use crate::backend::{same_bits, LinearBackend, SolveError, SolverStats};
use crate::cholesky::CholeskyCore;
use crate::csr::{CsrMatrix, CsrPattern};
use crate::faer_backend::FaerCholesky;
use crate::ordering::{metis_separator, FillOrdering};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::SymbolicSparseColMatRef;
use faer::{Accum, Conj, Mat, MatMut, Par};
use std::sync::Arc;
use std::time::Instant;

/// How the interior unknowns of a [`Half`] are ordered (the separator always comes last).
#[derive(Debug, Clone, Copy)]
pub(crate) enum InteriorOrder<'a> {
    /// A global order restricted to the interior: `rank[unknown]` = its position.
    GlobalRank(&'a [u32]),
    /// METIS nested dissection of the interior's own graph.
    Metis,
    /// faer's AMD on the interior's own pattern.
    Amd,
}

/// A principal sub-matrix K = A\[I ∪ S, I ∪ S\] (an interior I and the separator or
/// interface unknowns S it couples to, last) with its sparse Cholesky factorization. Its
/// trailing block L_SS satisfies L_SS L_SSᵀ = K_SS − A_SI A_II⁻¹ A_IS, and L_SI y for
/// y = L_II⁻¹ b_I is the interior's contribution to a forward solve: the pieces of a
/// one-level substructuring (here and in [`crate::substructure`]). `threads` > 1 runs
/// faer's numeric factorization on `Par::rayon(threads)` (a fixed split of the dense
/// supernode kernels: the same bits in any pool).
pub(crate) struct Half {
    /// Local unknown → global unknown: the interior first, then S in separator order.
    pub(crate) dofs: Vec<u32>,
    pub(crate) n_int: usize,
    /// Stored entry of K → stored entry of A.
    pub(crate) value_map: Vec<usize>,
    pub(crate) core: CholeskyCore,
    /// Permuted position (minus n_int) of the k-th separator unknown.
    pub(crate) s_pos: Vec<usize>,
    /// The values of K loaded by the last [`Half::factorize`].
    pub(crate) values: CsrMatrix,
    /// Scratch vector in permuted order.
    v: Vec<f64>,
}

impl Half {
    pub(crate) fn new(
        a: &CsrPattern,
        interior: Vec<u32>,
        sep: &[u32],
        order: InteriorOrder<'_>,
        threads: usize,
    ) -> Result<Self, SolveError> {
        let n_int = interior.len();
        let mut dofs = interior;
        dofs.extend_from_slice(sep);
        let nl = dofs.len();
        let mut local = vec![u32::MAX; a.n()];
        for (l, &g) in dofs.iter().enumerate() {
            local[g as usize] = l as u32;
        }
        // the sub-pattern, rows sorted by local column
        let mut row_ptr = Vec::with_capacity(nl + 1);
        row_ptr.push(0);
        let mut col_idx = Vec::new();
        let mut value_map = Vec::new();
        let mut row: Vec<(u32, usize)> = Vec::new();
        for &g in &dofs {
            row.clear();
            let g = g as usize;
            for (k, &c) in a.row_cols(g).iter().enumerate() {
                let lc = local[c as usize];
                if lc != u32::MAX {
                    row.push((lc, a.row_ptr()[g] + k));
                }
            }
            row.sort_unstable();
            for &(c, p) in &row {
                col_idx.push(c);
                value_map.push(p);
            }
            row_ptr.push(col_idx.len());
        }
        let pattern = Arc::new(CsrPattern::from_parts_unchecked(nl, row_ptr, col_idx));
        // the interior block in the given order (global AMD restricted to this half, or
        // METIS nested dissection of the half), then S in separator order
        let mut fwd = match order {
            InteriorOrder::GlobalRank(rank) => {
                let mut f: Vec<u32> = (0..n_int as u32).collect();
                f.sort_by_key(|&l| rank[dofs[l as usize] as usize]);
                f
            }
            InteriorOrder::Metis => {
                let sub = sub_pattern(&pattern, n_int);
                crate::ordering::metis_nested_dissection(&sub)?.0
            }
            InteriorOrder::Amd => amd_order(&pattern, n_int)?,
        };
        fwd.extend(n_int as u32..nl as u32);
        let mut inv = vec![0u32; nl];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old as usize] = new as u32;
        }
        let mut core = CholeskyCore::llt_with_perm(fwd, inv, threads);
        core.analyze(&pattern)?;
        let an = core.analysis.as_ref().expect("analyzed");
        if !matches!(an.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
            return Err(SolveError::Other("not supernodal".into()));
        }
        // faer may reorder (postorder): find where the separator ended up
        let inv_final: Vec<usize> = match an.symbolic.perm() {
            Some(p) => p.arrays().1.iter().map(|&x| x as usize).collect(),
            None => (0..nl).collect(),
        };
        let mut s_pos = Vec::with_capacity(sep.len());
        for k in 0..sep.len() {
            let p = inv_final[n_int + k];
            if p < n_int {
                return Err(SolveError::Other("separator not ordered last".into()));
            }
            s_pos.push(p - n_int);
        }
        let values = CsrMatrix::zeros(pattern.clone());
        Ok(Self {
            dofs,
            n_int,
            value_map,
            core,
            s_pos,
            values,
            v: vec![0.0; nl],
        })
    }

    /// Copies the values of K from A.
    pub(crate) fn load(&mut self, a: &CsrMatrix) {
        for (v, &p) in self.values.values.iter_mut().zip(&self.value_map) {
            *v = a.values[p];
        }
    }

    /// Copies the values from A and factorizes.
    pub(crate) fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.load(a);
        self.core.factorize(&self.values).map_err(|e| match e {
            SolveError::NotPositiveDefinite { index, pivot } => SolveError::NotPositiveDefinite {
                index: self.dofs[index] as usize,
                pivot,
            },
            SolveError::Singular { index } => SolveError::Singular {
                index: self.dofs[index] as usize,
            },
            other => other,
        })
    }

    /// The trailing |S| × |S| block of L (permuted separator order), dense.
    pub(crate) fn trailing_block(&self) -> Mat<f64> {
        let an = self.core.analysis.as_ref().expect("analyzed");
        let ns = self.s_pos.len();
        let p0 = self.n_int;
        let mut out = Mat::<f64>::zeros(ns, ns);
        if let SymbolicCholeskyRaw::Supernodal(sym) = an.symbolic.raw() {
            let r = SupernodalLltRef::new(sym, &an.l_values);
            for s in 0..sym.n_supernodes() {
                let node = r.supernode(s);
                let start = node.start();
                let val = node.val();
                let size = val.ncols();
                if start + size <= p0 {
                    continue;
                }
                let pattern = node.pattern();
                for c in start.max(p0)..start + size {
                    let jc = c - start;
                    for ir in jc..size {
                        out[(start + ir - p0, c - p0)] = val[(ir, jc)];
                    }
                    for (idx, &row) in pattern.iter().enumerate() {
                        out[(row as usize - p0, c - p0)] = val[(size + idx, jc)];
                    }
                }
            }
        }
        out
    }

    /// Forward solve with the interior right-hand side `b` (global) and zero on S; returns
    /// L_SI y_I in separator order (the coupling term of the global forward solve).
    pub(crate) fn forward(&mut self, b: &[f64], lss: &Mat<f64>) -> Vec<f64> {
        let an = self.core.analysis.as_mut().expect("analyzed");
        let inv = an.symbolic.perm().map(|p| p.arrays().1.to_vec());
        self.v.fill(0.0);
        for j in 0..self.n_int {
            let p = inv.as_ref().map_or(j, |i| i[j] as usize);
            self.v[p] = b[self.dofs[j] as usize];
        }
        if let SymbolicCholeskyRaw::Supernodal(sym) = an.symbolic.raw() {
            let n = self.v.len();
            SupernodalLltRef::new(sym, &an.l_values).l_solve_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut self.v, n, 1),
                Par::Seq,
                MemStack::new(&mut an.mem),
            );
        }
        // the S part is g = −L_SS⁻¹ L_SI y: L_SI y = −L_SS g
        let ns = self.s_pos.len();
        let g = &self.v[self.n_int..];
        let mut c = vec![0.0; ns];
        for (i, ci) in c.iter_mut().enumerate() {
            let mut s = 0.0;
            for (k, gk) in g.iter().enumerate().take(i + 1) {
                s += lss[(i, k)] * gk;
            }
            *ci = -s;
        }
        (0..ns).map(|k| c[self.s_pos[k]]).collect()
    }

    /// Backward solve after [`Half::forward`], given the separator solution `xs`
    /// (separator order); returns the interior unknowns in interior order
    /// (`dofs[..n_int]`).
    pub(crate) fn backward(&mut self, xs: &[f64], lss: &Mat<f64>) -> Vec<f64> {
        let ns = self.s_pos.len();
        let mut xp = vec![0.0; ns];
        for (k, &p) in self.s_pos.iter().enumerate() {
            xp[p] = xs[k];
        }
        // w = L_SSᵀ x_S
        for i in 0..ns {
            let mut s = 0.0;
            for (k, xk) in xp.iter().enumerate().skip(i) {
                s += lss[(k, i)] * xk;
            }
            self.v[self.n_int + i] = s;
        }
        let an = self.core.analysis.as_mut().expect("analyzed");
        if let SymbolicCholeskyRaw::Supernodal(sym) = an.symbolic.raw() {
            let n = self.v.len();
            SupernodalLltRef::new(sym, &an.l_values).l_transpose_solve_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut self.v, n, 1),
                Par::Seq,
                MemStack::new(&mut an.mem),
            );
        }
        let inv = an.symbolic.perm().map(|p| p.arrays().1.to_vec());
        (0..self.n_int)
            .map(|j| self.v[inv.as_ref().map_or(j, |i| i[j] as usize)])
            .collect()
    }

    /// Number of stored entries of K in the interior rows (A_II and A_IS): the first ones
    /// of `values`, since the interior rows come first.
    pub(crate) fn interior_nnz(&self) -> usize {
        self.values.pattern.row_ptr()[self.n_int]
    }

    /// Whether the interior rows of K (A_II and A_IS) hold in A the values loaded by the
    /// last factorization, bit for bit.
    pub(crate) fn interior_unchanged(&self, a: &CsrMatrix) -> bool {
        let m = self.interior_nnz();
        self.value_map[..m]
            .iter()
            .zip(&self.values.values[..m])
            .all(|(&p, v)| a.values[p].to_bits() == v.to_bits())
    }

    /// The smallest pivot ratio L_jj² / a_jj over the interior unknowns (the pivots of a
    /// global factorization that eliminates this interior first) and its global unknown;
    /// `diag(i)` = a_ii. `(∞, 0)` with no interior.
    pub(crate) fn interior_min_pivot_ratio(&self, diag: impl Fn(usize) -> f64) -> (f64, usize) {
        let an = self.core.analysis.as_ref().expect("analyzed");
        let d = an.factor_diagonal();
        let mut best = (f64::INFINITY, 0usize);
        for (p, &l) in d.iter().enumerate() {
            let local = an.original(p);
            if local >= self.n_int {
                continue;
            }
            let g = self.dofs[local] as usize;
            let aii = diag(g);
            let r = if aii != 0.0 { l * l / aii.abs() } else { l * l };
            if r < best.0 || r.is_nan() && !best.0.is_nan() {
                best = (r, g);
            }
        }
        best
    }
}

/// The leading `m × m` block of a pattern.
fn sub_pattern(pattern: &CsrPattern, m: usize) -> CsrPattern {
    let mut rp = Vec::with_capacity(m + 1);
    rp.push(0usize);
    let mut ci = Vec::new();
    for i in 0..m {
        for &c in pattern.row_cols(i) {
            if (c as usize) < m {
                ci.push(c);
            }
        }
        rp.push(ci.len());
    }
    CsrPattern::from_parts_unchecked(m, rp, ci)
}

/// AMD order of the leading `m × m` block of `pattern` (fwd\[new\] = old).
fn amd_order(pattern: &CsrPattern, m: usize) -> Result<Vec<u32>, SolveError> {
    let mut rp = Vec::with_capacity(m + 1);
    rp.push(0u32);
    let mut ci = Vec::new();
    for i in 0..m {
        for &c in pattern.row_cols(i) {
            if (c as usize) < m {
                ci.push(c);
            }
        }
        rp.push(ci.len() as u32);
    }
    let sym = SymbolicSparseColMatRef::new_checked(m, m, &rp, None, &ci);
    let mut fwd = vec![0u32; m];
    let mut inv = vec![0u32; m];
    let mut mem = MemBuffer::try_new(faer::sparse::linalg::amd::order_scratch::<u32>(m, ci.len()))
        .map_err(|_| SolveError::Other("out of memory for AMD".into()))?;
    faer::sparse::linalg::amd::order(
        &mut fwd,
        &mut inv,
        sym,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| SolveError::Other(format!("faer AMD: {e:?}")))?;
    Ok(fwd)
}

/// The split analysis of one pattern.
struct Split {
    pattern: Arc<CsrPattern>,
    halves: [Half; 2],
    sep: Vec<u32>,
    /// A_SS (dense, separator order).
    ass_map: Vec<(usize, usize, usize)>,
    /// Cholesky factor of the separator's Schur complement (lower, dense).
    c_factor: Mat<f64>,
    lss: [Mat<f64>; 2],
    factored: bool,
    last_values: Vec<f64>,
}

enum Inner {
    None,
    Split(Box<Split>),
    Whole(Box<FaerCholesky>, Arc<CsrPattern>),
}

/// Sparse Cholesky LLᵀ on two threads through a METIS vertex bisection; see the module
/// documentation. Name `faer-cholesky-split`.
pub struct FaerCholeskySplit {
    ordering: FillOrdering,
    inner: Inner,
    stats: SolverStats,
}

impl Default for FaerCholeskySplit {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerCholeskySplit {
    /// A backend with no analysis yet.
    pub fn new() -> Self {
        Self {
            ordering: FillOrdering::Metis,
            inner: Inner::None,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Ordering of the two halves (takes effect at the next analysis): METIS nested
    /// dissection of each half (default; least fill) or the global AMD order restricted
    /// to each half (cheaper analysis, about 10 % more fill on 2D meshes).
    pub fn with_ordering(mut self, ordering: FillOrdering) -> Self {
        self.ordering = ordering;
        self.inner = Inner::None;
        self
    }

    /// `true` when the last analysis split the matrix (else one whole factorization).
    pub fn is_split(&self) -> bool {
        matches!(self.inner, Inner::Split(_))
    }

    fn try_split(pattern: &Arc<CsrPattern>, ordering: FillOrdering) -> Result<Split, SolveError> {
        let part = metis_separator(pattern)?;
        let mut sets: [Vec<u32>; 3] = [Vec::new(), Vec::new(), Vec::new()];
        for (i, &p) in part.iter().enumerate() {
            sets[p as usize].push(i as u32);
        }
        if sets.iter().any(|s| s.is_empty()) {
            return Err(SolveError::Other("empty part".into()));
        }
        let [i1, i2, sep] = sets;
        let rank = match ordering {
            FillOrdering::Amd => {
                let fwd = amd_order(pattern, pattern.n())?;
                let mut rank = vec![0u32; fwd.len()];
                for (new, &old) in fwd.iter().enumerate() {
                    rank[old as usize] = new as u32;
                }
                Some(rank)
            }
            FillOrdering::Metis => None,
        };
        let order = match &rank {
            Some(r) => InteriorOrder::GlobalRank(r),
            None => InteriorOrder::Metis,
        };
        let (h1, h2) = rayon::join(
            || Half::new(pattern, i1, &sep, order, 1),
            || Half::new(pattern, i2, &sep, order, 1),
        );
        let (h1, h2) = (h1?, h2?);
        let ns = sep.len();
        let mut ass_map = Vec::new();
        for (k, &g) in sep.iter().enumerate() {
            for (l, &h) in sep.iter().enumerate() {
                if let Some(p) = pattern.find(g as usize, h as usize) {
                    ass_map.push((k, l, p));
                }
            }
        }
        Ok(Split {
            pattern: pattern.clone(),
            halves: [h1, h2],
            sep,
            ass_map,
            c_factor: Mat::zeros(ns, ns),
            lss: [Mat::zeros(0, 0), Mat::zeros(0, 0)],
            factored: false,
            last_values: Vec::new(),
        })
    }
}

impl LinearBackend for FaerCholeskySplit {
    fn name(&self) -> &'static str {
        "faer-cholesky-split"
    }

    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        let same = match &self.inner {
            Inner::Split(s) => s.pattern.id() == pattern.id(),
            Inner::Whole(_, p) => p.id() == pattern.id(),
            Inner::None => false,
        };
        if same {
            return Ok(());
        }
        self.inner = Inner::None;
        let t = Instant::now();
        match Self::try_split(pattern, self.ordering) {
            Ok(s) => {
                self.stats.factor_nnz = s
                    .halves
                    .iter()
                    .map(|h| h.core.analysis.as_ref().map_or(0, |a| a.l_values.len()))
                    .sum::<usize>()
                    + s.sep.len() * (s.sep.len() + 1) / 2;
                self.inner = Inner::Split(Box::new(s));
            }
            Err(_) => {
                let mut whole = FaerCholesky::new();
                whole.analyze(pattern)?;
                self.stats.factor_nnz = whole.stats().factor_nnz;
                self.inner = Inner::Whole(Box::new(whole), pattern.clone());
            }
        }
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        crate::backend::check_values(a)?;
        let t = Instant::now();
        let result = match &mut self.inner {
            Inner::None => unreachable!("analyzed"),
            Inner::Whole(w, _) => {
                let before = w.stats().skipped_factorizations;
                let r = w.factorize(a);
                if w.stats().skipped_factorizations > before {
                    self.stats.skipped_factorizations += 1;
                    return r;
                }
                r
            }
            Inner::Split(s) => {
                if s.factored && same_bits(&a.values, &s.last_values) {
                    self.stats.skipped_factorizations += 1;
                    return Ok(());
                }
                s.factored = false;
                let [h1, h2] = &mut s.halves;
                let (r1, r2) = rayon::join(|| h1.factorize(a), || h2.factorize(a));
                r1?;
                r2?;
                let ns = s.sep.len();
                s.lss = [s.halves[0].trailing_block(), s.halves[1].trailing_block()];
                // C = L1 L1ᵀ + L2 L2ᵀ − A_SS, in separator order
                let mut c = Mat::<f64>::zeros(ns, ns);
                for (h, l) in s.halves.iter().zip(&s.lss) {
                    let mut t = Mat::<f64>::zeros(ns, ns);
                    matmul(
                        t.as_mut(),
                        Accum::Replace,
                        l.as_ref(),
                        l.transpose(),
                        1.0,
                        Par::Seq,
                    );
                    for i in 0..ns {
                        for j in 0..=i {
                            c[(i, j)] += t[(h.s_pos[i], h.s_pos[j])];
                        }
                    }
                }
                for &(k, l, p) in &s.ass_map {
                    if l <= k {
                        c[(k, l)] -= a.values[p];
                    }
                }
                let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(
                    ns,
                    Par::Seq,
                    Default::default(),
                ));
                match cholesky_in_place(
                    c.as_mut(),
                    Default::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                ) {
                    Ok(_) => {
                        s.c_factor = c;
                        s.last_values.clear();
                        s.last_values.extend_from_slice(&a.values);
                        s.factored = true;
                        Ok(())
                    }
                    Err(_) => Err(SolveError::NotPositiveDefinite {
                        index: s.sep[0] as usize,
                        pivot: f64::NAN,
                    }),
                }
            }
        };
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t.elapsed().as_secs_f64();
        result
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let t = Instant::now();
        let r = match &mut self.inner {
            Inner::Whole(w, _) => w.solve(rhs),
            Inner::Split(s) if s.factored => {
                let n = s.pattern.n();
                if rhs.len() != n {
                    return Err(SolveError::Other(format!(
                        "right-hand side has length {}, expected {n}",
                        rhs.len()
                    )));
                }
                let [h1, h2] = &mut s.halves;
                let [l1, l2] = &s.lss;
                let b: &[f64] = rhs;
                let (c1, c2) = rayon::join(|| h1.forward(b, l1), || h2.forward(b, l2));
                let ns = s.sep.len();
                let mut xs: Vec<f64> = (0..ns)
                    .map(|k| b[s.sep[k] as usize] - c1[k] - c2[k])
                    .collect();
                faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(
                    s.c_factor.as_ref(),
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut xs, ns, 1),
                    Par::Seq,
                    MemStack::new(&mut MemBuffer::new(faer::dyn_stack::StackReq::EMPTY)),
                );
                let xs_ref = &xs;
                let (x1, x2) = rayon::join(|| h1.backward(xs_ref, l1), || h2.backward(xs_ref, l2));
                for (h, x) in [(&*h1, x1), (&*h2, x2)] {
                    for (&g, v) in h.dofs[..h.n_int].iter().zip(x) {
                        rhs[g as usize] = v;
                    }
                }
                for (k, &g) in s.sep.iter().enumerate() {
                    rhs[g as usize] = xs[k];
                }
                Ok(())
            }
            _ => Err(SolveError::Other(
                "solve called without a successful factorization".into(),
            )),
        };
        self.stats.solves += 1;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        r
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }
}
