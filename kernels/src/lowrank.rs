//! Solves with a matrix that differs from a factorized one by a change on few unknowns,
//! at about the cost of one solve with the held factor (issue 6: a secant iteration of
//! docs/theory.md §4 in which a few contacts changed state, their stiffness ΔK_c = Bᵀ Δk B
//! of docs/theory.md §3 added to the factorized K_old).
//!
//! **Method** (the Woodbury identity applied inside the factor). With the held factor
//! P K_old Pᵀ = L Lᵀ ([`FaerCholesky`](crate::FaerCholesky), P its fill-reducing
//! permutation) and the change split into signed rank-one terms
//! ΔK = K_new − K_old = U S Uᵀ (U: n × r, S = diag(±1)),
//!
//! ```text
//! P K_new Pᵀ = L (I + W S Wᵀ) Lᵀ,   W = L⁻¹ P U,
//! K_new⁻¹ f = Pᵀ L⁻ᵀ (I − W C⁻¹ Wᵀ) L⁻¹ P f,   C = S + Wᵀ W   (r × r).
//! ```
//!
//! * *Terms.* ΔK is read as the difference of the new values and those of the held
//!   factorization; its nonzero entries fall into connected blocks (one per changed
//!   contact, or a few contacts sharing nodes), and each block's dense symmetric
//!   q × q matrix is split by its eigendecomposition, D = Σ λ v vᵀ, into terms
//!   u = √|λ| v with sign sgn λ, eigenvalues below 10⁻¹³ of the block's largest dropped
//!   (a contact's Bᵀ Δk B has rank ≤ 2 however many unknowns its faces carry).
//! * *W.* A column of W is a sparse forward solve: L⁻¹ u has its nonzeros in the
//!   elimination-tree reach of u's unknowns — the supernodes on their paths to the
//!   root —, so a block's columns are computed together as a dense array over the rows
//!   of that reach, supernode by supernode (a dense triangular solve with the diagonal
//!   block, then the rows below it updated): each costs about one solve restricted to
//!   the paths, not the whole factor.
//! * *C.* C = S + Σ over supernodes of Y_sᵀ Y_s, Y_s the rows of supernode s of the
//!   columns whose reach contains s (the paths of scattered contacts share only the top
//!   separators). Its eigendecomposition gives C⁻¹ and the test of positive definiteness:
//!   by the inertia of [[I, W], [Wᵀ, −S]] (whose two Schur complements are −C and
//!   I + W S Wᵀ), K_new is positive definite exactly when C has as many negative
//!   eigenvalues as S has −1's. A change that makes K_new indefinite, or so nearly
//!   singular that an eigenvalue of C falls below 10⁻⁹ of max(1, the largest) (a contact
//!   opening into a mechanism), gives [`SolveError::NotPositiveDefinite`]: the caller then
//!   refactorizes, which reports the failed pivot.
//! * *Solve.* One forward and one backward substitution with faer's factor (faer's own
//!   kernels), between them Wᵀ y over the reach rows, C⁻¹ by its eigenvectors and
//!   y −= W v: one solve plus O(nnz W + r²).
//!
//! faer has no update or downdate of a sparse Cholesky factor, hence this module; it
//! changes nothing in the factor (the held factor stays that of K_old and can serve the
//! next change too). Cost: the terms' reaches (the paths to the root of the elimination
//! tree, the top separators' dense blocks the largest part) times the rank, plus r³ for C:
//! cheap for a few scattered contacts, a refactorization's worth once r reaches a few
//! hundred (docs/performance.md, "The cost of a secant iteration").
//!
//! Symbolic/numeric separation as elsewhere in the kernels: the elimination tree of the
//! supernodes (or columns, for a simplicial factor) is built once per analysis of the held
//! backend; [`LowRankCorrection::update`] does the numeric work for one K_new and
//! [`LowRankCorrection::solve`] applies it to any number of right-hand sides.
//!
//! *Threads.* The results do not depend on the number of threads: the two substitutions
//! of a solve run on independent subtrees of the supernodal elimination tree in parallel
//! (`Split`, in the private submodule `substitution`), every entry receiving the same
//! operations in the same order as in faer's sequential substitution, and the scan of ΔK
//! runs in chunks of rows whose changes are read in order; the rest (W, C and its
//! eigendecomposition) is sequential.

use crate::backend::SolveError;
use crate::cholesky::{CholAnalysis, CholeskyCore};
use crate::csr::CsrMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::triangular_solve as sparse_tri;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::time::Instant;
use substitution::Split;

mod substitution;

/// Eigenvalues of a block of ΔK below this fraction of its largest are dropped.
const DROP: f64 = 1e-13;
/// An eigenvalue of C below this fraction of its largest reports a (nearly) singular K_new.
const SINGULAR: f64 = 1e-9;
/// With a rank limit r ([`LowRankCorrection::with_max_rank`]), a change with more than
/// `ENTRIES_PER_RANK` × r nonzero entries is refused as soon as the scan of ΔK meets them
/// (before any block is formed): a contact's Bᵀ Δk B has rank ≤ 2 and at most 8 × 8
/// entries (two nodes of two unknowns on each face, docs/theory.md §3), 32 entries per unit of
/// rank, so this leaves a factor 2 while refusing a change of every entry (a new
/// geometry) after reading about 64 r of them.
const ENTRIES_PER_RANK: usize = 64;
/// With a rank limit r, a connected block of ΔK on more than `UNKNOWNS_PER_RANK` × r
/// unknowns is refused before its dense eigendecomposition (q³ work): a contact adds at
/// most 8 unknowns and rank ≥ 1 when it changed.
const UNKNOWNS_PER_RANK: usize = 8;
const NONE: usize = usize::MAX;

/// The elimination tree of the held factor's supernodes (columns for a simplicial one).
struct Tree {
    pattern_id: u64,
    /// First column of each node, and one past the last node's end.
    begin: Vec<usize>,
    /// Rows below the diagonal block of node s: `rows[row_ptr[s]..row_ptr[s + 1]]`.
    row_ptr: Vec<usize>,
    rows: Vec<u32>,
    /// Values of node s (its (c + p) × c block, column-major): `val_ptr[s]..val_ptr[s + 1]`.
    val_ptr: Vec<usize>,
    parent: Vec<usize>,
    /// Node of each (permuted) column.
    node_of: Vec<u32>,
    /// Permutation: `fwd[p]` = original index of permuted index p; `inv` its inverse.
    fwd: Vec<usize>,
    inv: Vec<usize>,
    /// faer's scratch for one right-hand side.
    mem: MemBuffer,
    /// The partition of a supernodal tree for substitutions on several threads (None:
    /// simplicial, or no subtree worth a task).
    split: Option<Split>,
}

impl Tree {
    fn new(factor: &CholeskyCore) -> Result<Self, SolveError> {
        let an = held(factor)?;
        let n = an.pattern.n();
        let (begin, row_ptr, rows, val_ptr) = match an.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => {
                let ns = s.n_supernodes();
                let mut begin: Vec<usize> =
                    s.supernode_begin().iter().map(|&b| b as usize).collect();
                begin.push(n);
                let mut row_ptr = vec![0];
                let mut rows = Vec::new();
                for k in 0..ns {
                    rows.extend_from_slice(s.supernode(k).pattern());
                    row_ptr.push(rows.len());
                }
                let val_ptr = s.col_ptr_for_val().iter().map(|&v| v as usize).collect();
                (begin, row_ptr, rows, val_ptr)
            }
            SymbolicCholeskyRaw::Simplicial(s) => {
                // faer stores each column of L with its diagonal first
                let cp = s.col_ptr();
                let ri = s.row_idx();
                let mut row_ptr = vec![0];
                let mut rows = Vec::with_capacity(ri.len().saturating_sub(n));
                for j in 0..n {
                    let (a, b) = (cp[j] as usize, cp[j + 1] as usize);
                    if a == b || ri[a] as usize != j {
                        return Err(SolveError::Other(format!(
                            "low-rank correction: column {j} of the simplicial factor does not start with its diagonal"
                        )));
                    }
                    rows.extend_from_slice(&ri[a + 1..b]);
                    row_ptr.push(rows.len());
                }
                let val_ptr = cp.iter().map(|&v| v as usize).collect();
                ((0..=n).collect(), row_ptr, rows, val_ptr)
            }
        };
        let nodes = begin.len() - 1;
        let mut node_of = vec![0u32; n];
        for s in 0..nodes {
            node_of[begin[s]..begin[s + 1]].fill(s as u32);
        }
        let parent: Vec<usize> = (0..nodes)
            .map(|s| {
                rows[row_ptr[s]..row_ptr[s + 1]]
                    .iter()
                    .min()
                    .map_or(NONE, |&r| node_of[r as usize] as usize)
            })
            .collect();
        let (fwd, inv) = match an.symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (
                    f.iter().map(|&v| v as usize).collect(),
                    i.iter().map(|&v| v as usize).collect(),
                )
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let req = an.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        let mem = MemBuffer::try_new(req)
            .map_err(|_| SolveError::Other("out of memory for faer scratch".into()))?;
        let split = matches!(an.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
            .then(|| Split::new(&begin, &row_ptr, &rows, &parent, &node_of))
            .flatten();
        Ok(Self {
            pattern_id: an.pattern.id(),
            begin,
            row_ptr,
            rows,
            val_ptr,
            parent,
            node_of,
            fwd,
            inv,
            mem,
            split,
        })
    }

    fn width(&self, s: usize) -> usize {
        self.begin[s + 1] - self.begin[s]
    }

    fn pattern(&self, s: usize) -> &[u32] {
        &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    /// Supernode s of the factor `l`: its (c + p) × c block, column-major.
    fn node_l<'a>(&self, l: &'a [f64], s: usize) -> MatRef<'a, f64> {
        MatRef::from_column_major_slice(
            &l[self.val_ptr[s]..self.val_ptr[s + 1]],
            self.width(s) + self.pattern(s).len(),
            self.width(s),
        )
    }

    /// y ← L⁻¹ y, or L⁻ᵀ y if `transpose` (y permuted, length n): on the [`Split`]'s
    /// parts in parallel when there is one and rayon has more than one thread, else with
    /// faer's sequential kernels; the same bits either way.
    fn substitute(&mut self, an: &CholAnalysis, y: &mut [f64], transpose: bool) {
        match self.split.take() {
            // on one thread the parts' copies would only cost (a few % of a substitution)
            Some(mut split) if rayon::current_num_threads() > 1 => {
                split.substitute(self, &an.l_values, y, transpose);
                self.split = Some(split);
            }
            split => {
                self.split = split;
                substitute(an, y, transpose, &mut self.mem)
            }
        }
    }
}

/// The held backend's analysis, if it holds a successful LLᵀ factorization.
fn held(factor: &CholeskyCore) -> Result<&CholAnalysis, SolveError> {
    match &factor.analysis {
        Some(an) if an.factored => Ok(an),
        _ => Err(SolveError::Other(
            "low-rank correction: the backend holds no successful factorization (call factorize first)"
                .into(),
        )),
    }
}

/// W's rows on one supernode of the union of the terms' reaches.
struct NodeW {
    /// The supernode.
    s: usize,
    /// The terms whose reach contains it (indices among all the terms, ascending).
    terms: Vec<usize>,
    /// W[columns of s, terms]: width(s) × terms.len(), column-major.
    x: Vec<f64>,
}

/// Counters of a [`LowRankCorrection`].
#[derive(Debug, Clone, Default)]
pub struct LowRankStats {
    /// Rank r of the last change (signed rank-one terms kept).
    pub rank: usize,
    /// Connected blocks of the last change.
    pub blocks: usize,
    /// Rows of W stored for the last change (the columns of the union of the terms'
    /// reaches).
    pub reach_rows: usize,
    /// Entries of W stored for the last change (Σ over those supernodes of their width
    /// times the terms reaching them).
    pub w_entries: usize,
    /// Wall time of the last [`LowRankCorrection::update`], s.
    pub update_seconds: f64,
    /// Wall time of the last [`LowRankCorrection::solve`], s.
    pub solve_seconds: f64,
}

/// The correction of a held [`FaerCholesky`](crate::FaerCholesky) factor of K_old for a
/// K_new on the same pattern (see the module's documentation). Its operations on the
/// backend (`update`, `solve`, `solve_changed`) are defined next to the backend, in
/// [`crate::faer_backend`].
///
/// ```text
/// backend.factorize(&k_old)?;
/// let mut c = LowRankCorrection::new();
/// c.update(&backend, &k_new)?;     // Err(NotPositiveDefinite) → refactorize instead
/// c.solve(&backend, &mut f)?;      // f ← K_new⁻¹ f
/// ```
#[derive(Default)]
pub struct LowRankCorrection {
    tree: Option<Tree>,
    /// (pattern id, numeric factorizations) of the factor the last update was made for.
    factor_id: Option<(u64, usize)>,
    /// W, supernode by supernode, ascending.
    nodes: Vec<NodeW>,
    /// For each block of ΔK: one past its last term, and its first unknown.
    blocks: Vec<(usize, usize)>,
    signs: Vec<f64>,
    /// Eigenvectors of C (r × r, column-major) and the reciprocals of its eigenvalues.
    c_vectors: Vec<f64>,
    c_inv_values: Vec<f64>,
    max_rank: Option<usize>,
    stats: LowRankStats,
    /// K_new's values at the last successful update (for [`LowRankCorrection::solve_changed`]).
    new_values: Vec<f64>,
}

impl LowRankCorrection {
    /// A correction with no change yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Refuse changes of rank above `r` (an error, after the terms are split and before
    /// W is computed): beyond a few hundred terms a refactorization is cheaper.
    pub fn with_max_rank(mut self, r: usize) -> Self {
        self.max_rank = Some(r);
        self
    }

    /// Counters of the last update and solve.
    pub fn stats(&self) -> &LowRankStats {
        &self.stats
    }

    /// [`update`](Self::update) on the held backend's core.
    pub(crate) fn update_on(
        &mut self,
        factor: &CholeskyCore,
        k_new: &CsrMatrix,
    ) -> Result<(), SolveError> {
        let t = Instant::now();
        self.factor_id = None;
        self.nodes.clear();
        self.blocks.clear();
        self.signs.clear();
        self.stats = LowRankStats::default();
        let an = held(factor)?;
        if an.pattern.id() != k_new.pattern.id()
            && (an.pattern.row_ptr() != k_new.pattern.row_ptr()
                || an.pattern.col_idx() != k_new.pattern.col_idx())
            || k_new.values.len() != an.last_values.len()
        {
            return Err(SolveError::Other(
                "low-rank correction: the new matrix has another pattern than the factorized one"
                    .into(),
            ));
        }
        if self.tree.as_ref().map(|t| t.pattern_id) != Some(an.pattern.id()) {
            self.tree = Some(Tree::new(factor)?);
        }
        let tree = self.tree.as_ref().expect("tree");
        let limits = self
            .max_rank
            .map(|r| (ENTRIES_PER_RANK * r.max(1), UNKNOWNS_PER_RANK * r.max(1)));
        let mut terms = split_change(k_new, &an.last_values, limits)?;
        terms.retain(|b| !b.signs.is_empty());
        let rank: usize = terms.iter().map(|b| b.signs.len()).sum();
        if let Some(max) = self.max_rank {
            if rank > max {
                return Err(SolveError::Other(format!(
                    "low-rank correction: the change has rank {rank}, above the limit {max}; refactorize"
                )));
            }
        }
        // W over the union of the reaches, C = S + WᵀW supernode by supernode
        self.nodes = forward(tree, &an.l_values, &terms)?;
        for b in &terms {
            let end = self.signs.len() + b.signs.len();
            self.blocks.push((end, b.unknowns[0]));
            self.signs.extend_from_slice(&b.signs);
        }
        let r = self.signs.len();
        let mut c = Mat::<f64>::zeros(r, r);
        let mut g = Mat::<f64>::zeros(0, 0);
        for nw in &self.nodes {
            let rs = nw.terms.len();
            let x = MatRef::from_column_major_slice(&nw.x, tree.width(nw.s), rs);
            g.resize_with(rs, rs, |_, _| 0.0);
            matmul(g.as_mut(), Accum::Replace, x.transpose(), x, 1.0, Par::Seq);
            for (a, &ta) in nw.terms.iter().enumerate() {
                for (b, &tb) in nw.terms.iter().enumerate() {
                    c[(ta, tb)] += g[(a, b)];
                }
            }
        }
        for (i, &s) in self.signs.iter().enumerate() {
            c[(i, i)] += s;
        }
        self.c_vectors.clear();
        self.c_inv_values.clear();
        if r > 0 {
            let (lam, u) = symmetric_eigen(c.as_ref()).map_err(|e| {
                SolveError::Other(format!("low-rank correction: eigensolver: {e:?}"))
            })?;
            // C = S + WᵀW with S = diag(±1): its scale is at least 1
            let big = (0..r).map(|i| lam[i].abs()).fold(1.0, f64::max);
            let negative_terms = self.signs.iter().filter(|&&s| s < 0.0).count();
            let negative = (0..r).filter(|&i| lam[i] < 0.0).count();
            // the eigenvalue closest to zero, or the first wrongly signed one
            let bad = (0..r)
                .find(|&i| lam[i].abs() <= SINGULAR * big || lam[i].is_nan())
                .or((negative != negative_terms).then(|| {
                    // eigenvalues ascend: the negative one next to zero
                    negative.saturating_sub(1)
                }));
            if let Some(i) = bad {
                // the term the offending eigenvector weighs most, and its block
                let term = (0..r)
                    .max_by(|&a, &b| u[(a, i)].abs().total_cmp(&u[(b, i)].abs()))
                    .unwrap_or(0);
                let index = self.blocks.iter().find(|b| term < b.0).map_or(0, |b| b.1);
                self.nodes.clear();
                self.blocks.clear();
                self.signs.clear();
                return Err(SolveError::NotPositiveDefinite {
                    index,
                    pivot: f64::NAN,
                });
            }
            for j in 0..r {
                self.c_vectors.extend((0..r).map(|i| u[(i, j)]));
            }
            self.c_inv_values.extend((0..r).map(|i| 1.0 / lam[i]));
        }
        self.stats = LowRankStats {
            rank: r,
            blocks: self.blocks.len(),
            reach_rows: self.nodes.iter().map(|nw| tree.width(nw.s)).sum(),
            w_entries: self.nodes.iter().map(|nw| nw.x.len()).sum(),
            update_seconds: t.elapsed().as_secs_f64(),
            solve_seconds: 0.0,
        };
        self.factor_id = Some((an.pattern.id(), factor.stats.numeric_factorizations));
        self.new_values.clone_from(&k_new.values);
        Ok(())
    }

    /// rhs ← K_old⁻¹ rhs with the held factor alone, its substitutions on the tree's
    /// [`Split`] (bit-identical to faer's solve; `FaerCholesky`'s `LinearBackend::solve`
    /// with more than one rayon thread). `false` when that does not apply (nothing
    /// factorized, a simplicial factor, a tree without parts, one thread, a right-hand
    /// side of another length): the caller takes faer's solve, which also reports the
    /// errors.
    pub(crate) fn solve_held(
        &mut self,
        factor: &CholeskyCore,
        rhs: &mut [f64],
    ) -> Result<bool, SolveError> {
        let Ok(an) = held(factor) else {
            return Ok(false);
        };
        if rayon::current_num_threads() <= 1
            || rhs.len() != an.pattern.n()
            || !matches!(an.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
        {
            return Ok(false);
        }
        if self.tree.as_ref().map(|t| t.pattern_id) != Some(an.pattern.id()) {
            self.tree = Some(Tree::new(factor)?);
        }
        let tree = self.tree.as_mut().expect("tree");
        if tree.split.is_none() {
            return Ok(false);
        }
        let mut y: Vec<f64> = tree.fwd.iter().map(|&i| rhs[i]).collect();
        tree.substitute(an, &mut y, false);
        tree.substitute(an, &mut y, true);
        for (p, &i) in tree.fwd.iter().enumerate() {
            rhs[i] = y[p];
        }
        Ok(true)
    }

    /// [`solve_changed`](Self::solve_changed) on the held backend's core.
    pub(crate) fn solve_changed_on(
        &mut self,
        factor: &CholeskyCore,
        k_new: &CsrMatrix,
        rhs: &mut [f64],
    ) -> Result<(), SolveError> {
        let current = held(factor)
            .map(|an| (an.pattern.id(), factor.stats.numeric_factorizations))
            .ok();
        let fresh = current.is_some()
            && self.factor_id == current
            && crate::backend::same_bits(&self.new_values, &k_new.values);
        if !fresh {
            self.update_on(factor, k_new)?;
        }
        self.solve_on(factor, rhs)
    }

    /// [`solve`](Self::solve) on the held backend's core.
    pub(crate) fn solve_on(
        &mut self,
        factor: &CholeskyCore,
        rhs: &mut [f64],
    ) -> Result<(), SolveError> {
        let t = Instant::now();
        let an = held(factor)?;
        if self.factor_id != Some((an.pattern.id(), factor.stats.numeric_factorizations)) {
            return Err(SolveError::Other(
                "low-rank correction: no update for the backend's current factorization (call update after factorize)"
                    .into(),
            ));
        }
        let tree = self.tree.as_mut().expect("tree of the update");
        let n = tree.fwd.len();
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "right-hand side has length {}, expected {n}",
                rhs.len()
            )));
        }
        let mut y: Vec<f64> = tree.fwd.iter().map(|&i| rhs[i]).collect();
        tree.substitute(an, &mut y, false);
        let r = self.signs.len();
        if r > 0 {
            // z = Wᵀ y, v = C⁻¹ z, y −= W v
            let mut z = vec![0.0; r];
            for nw in &self.nodes {
                let (b0, c) = (tree.begin[nw.s], tree.width(nw.s));
                let ys = &y[b0..b0 + c];
                for (j, &t) in nw.terms.iter().enumerate() {
                    let col = &nw.x[j * c..(j + 1) * c];
                    z[t] += col.iter().zip(ys).map(|(w, y)| w * y).sum::<f64>();
                }
            }
            let vt_z: Vec<f64> = (0..r)
                .map(|j| {
                    let v = &self.c_vectors[j * r..(j + 1) * r];
                    self.c_inv_values[j] * v.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>()
                })
                .collect();
            let mut v = vec![0.0; r];
            for (j, &a) in vt_z.iter().enumerate() {
                let col = &self.c_vectors[j * r..(j + 1) * r];
                v.iter_mut().zip(col).for_each(|(vi, ci)| *vi += a * ci);
            }
            for nw in &self.nodes {
                let (b0, c) = (tree.begin[nw.s], tree.width(nw.s));
                let ys = &mut y[b0..b0 + c];
                for (j, &t) in nw.terms.iter().enumerate() {
                    let a = v[t];
                    let col = &nw.x[j * c..(j + 1) * c];
                    ys.iter_mut().zip(col).for_each(|(y, w)| *y -= a * w);
                }
            }
        }
        tree.substitute(an, &mut y, true);
        for (p, &i) in tree.fwd.iter().enumerate() {
            rhs[i] = y[p];
        }
        self.stats.solve_seconds = t.elapsed().as_secs_f64();
        Ok(())
    }
}

/// y ← L⁻¹ y, or L⁻ᵀ y if `transpose`, with faer's kernels (y permuted, length n).
fn substitute(an: &CholAnalysis, y: &mut [f64], transpose: bool, mem: &mut MemBuffer) {
    let n = y.len();
    let y = MatMut::from_column_major_slice_mut(y, n, 1);
    match an.symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => {
            let f = SupernodalLltRef::new(s, &an.l_values);
            let stack = MemStack::new(mem);
            if transpose {
                f.l_transpose_solve_with_conj(Conj::No, y, Par::Seq, stack)
            } else {
                f.l_solve_with_conj(Conj::No, y, Par::Seq, stack)
            }
        }
        SymbolicCholeskyRaw::Simplicial(s) => {
            let f = SparseColMatRef::new(s.factor(), &an.l_values[..]);
            if transpose {
                sparse_tri::solve_lower_triangular_transpose_in_place(f, Conj::No, y, Par::Seq)
            } else {
                sparse_tri::solve_lower_triangular_in_place(f, Conj::No, y, Par::Seq)
            }
        }
    }
}

/// Eigenvalues (ascending) and eigenvectors (the columns) of the symmetric `a` (its lower
/// triangle read), computed sequentially: faer's `self_adjoint_eigen` runs on faer's
/// global parallelism, whose results change with the number of threads.
fn symmetric_eigen(
    a: MatRef<'_, f64>,
) -> Result<(Vec<f64>, Mat<f64>), faer::linalg::evd::EvdError> {
    use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
    let n = a.nrows();
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let mut mem = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    ));
    self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )?;
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

/// The signed rank-one terms of one connected block of ΔK.
struct Terms {
    /// Its unknowns (original numbering), ascending.
    unknowns: Vec<usize>,
    /// Term t: `vectors[t * q..(t + 1) * q]` over `unknowns` (q of them), with sign `signs[t]`.
    vectors: Vec<f64>,
    signs: Vec<f64>,
}

/// A changed entry of K: row, column, new − old value.
type Change = (usize, usize, f64);
/// The changes of a chunk of rows, and where it met a non-finite value (row, entry).
type ScannedRows = (Vec<Change>, Option<(usize, usize)>);

/// ΔK = values of `k_new` − `old`, split into connected blocks and each block into signed
/// rank-one terms by its eigendecomposition.
/// `limits`: the largest number of changed entries and of unknowns in one block (refused
/// with an error as soon as exceeded).
fn split_change(
    k_new: &CsrMatrix,
    old: &[f64],
    limits: Option<(usize, usize)>,
) -> Result<Vec<Terms>, SolveError> {
    let (max_entries, max_block) = limits.unwrap_or((usize::MAX, usize::MAX));
    let p = &k_new.pattern;
    let n = p.n();
    let (rp, ci) = (p.row_ptr(), p.col_idx());
    // the scan, in chunks of rows on rayon's threads; each chunk stops at its first
    // non-finite value or once it alone holds more than `max_entries` changes, and the
    // chunks are read in order: the same entries and the same error as a sequential scan
    let chunk_rows = (crate::backend::SAME_BITS_CHUNK * n / rp[n].max(1)).max(1);
    let scanned: Vec<ScannedRows> = (0..n)
        .into_par_iter()
        .step_by(chunk_rows)
        .map(|r0| {
            let mut changed = Vec::new();
            for i in r0..(r0 + chunk_rows).min(n) {
                for e in rp[i]..rp[i + 1] {
                    let d = k_new.values[e] - old[e];
                    if !d.is_finite() {
                        return (changed, Some((i, e)));
                    }
                    if d != 0.0 {
                        changed.push((i, ci[e] as usize, d));
                        if changed.len() > max_entries {
                            return (changed, None);
                        }
                    }
                }
            }
            (changed, None)
        })
        .collect();
    let mut changed = Vec::new();
    for (part, bad) in scanned {
        for c in part {
            if changed.len() == max_entries {
                return Err(SolveError::Other(format!(
                    "low-rank correction: more than {max_entries} entries changed (from row {} on); refactorize",
                    c.0
                )));
            }
            changed.push(c);
        }
        if let Some((i, e)) = bad {
            return Err(SolveError::Other(format!(
                "low-rank correction: the new matrix has the non-finite value {} at row {i}, column {}",
                k_new.values[e], ci[e]
            )));
        }
    }
    // union-find over the touched unknowns
    let mut unknowns: Vec<usize> = changed.iter().flat_map(|&(i, j, _)| [i, j]).collect();
    unknowns.sort_unstable();
    unknowns.dedup();
    let pos = |i: usize| unknowns.binary_search(&i).expect("touched unknown");
    let mut root: Vec<usize> = (0..unknowns.len()).collect();
    fn find(root: &mut [usize], mut a: usize) -> usize {
        while root[a] != a {
            root[a] = root[root[a]];
            a = root[a];
        }
        a
    }
    for &(i, j, _) in &changed {
        let (a, b) = (find(&mut root, pos(i)), find(&mut root, pos(j)));
        if a != b {
            root[a.max(b)] = a.min(b);
        }
    }
    let mut block_of = vec![NONE; unknowns.len()];
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    let mut local = vec![0; unknowns.len()];
    for a in 0..unknowns.len() {
        let r = find(&mut root, a);
        if block_of[r] == NONE {
            block_of[r] = blocks.len();
            blocks.push(Vec::new());
        }
        block_of[a] = block_of[r];
        local[a] = blocks[block_of[a]].len();
        blocks[block_of[a]].push(unknowns[a]);
    }
    if let Some(b) = blocks.iter().find(|b| b.len() > max_block) {
        return Err(SolveError::Other(format!(
            "low-rank correction: a connected change on {} unknowns (from unknown {}), above the limit {max_block}; refactorize",
            b.len(),
            b[0]
        )));
    }
    let mut dense: Vec<Mat<f64>> = blocks
        .iter()
        .map(|b| Mat::zeros(b.len(), b.len()))
        .collect();
    for &(i, j, d) in &changed {
        let (a, b) = (pos(i), pos(j));
        // both triangles are stored: the mean of (i, j) and (j, i)
        dense[block_of[a]][(local[a], local[b])] += 0.5 * d;
        dense[block_of[a]][(local[b], local[a])] += 0.5 * d;
    }
    blocks
        .into_iter()
        .zip(dense)
        .map(|(unknowns, d)| {
            let q = unknowns.len();
            let (lam, u) = symmetric_eigen(d.as_ref()).map_err(|e| {
                SolveError::Other(format!(
                    "low-rank correction: no eigendecomposition of the change at unknowns {unknowns:?}: {e:?}"
                ))
            })?;
            let mut out = Terms {
                unknowns,
                vectors: Vec::new(),
                signs: Vec::new(),
            };
            let big = (0..q).map(|i| lam[i].abs()).fold(0.0, f64::max);
            for t in 0..q {
                if lam[t].abs() > DROP * big {
                    let s = lam[t].abs().sqrt();
                    out.vectors.extend((0..q).map(|i| s * u[(i, t)]));
                    out.signs.push(lam[t].signum());
                }
            }
            Ok(out)
        })
        .collect()
}

/// W = L⁻¹ P U for all the terms: the forward solves over the union of the reaches of
/// the blocks' unknowns (the supernodes on their paths to the root), all the terms
/// reaching a supernode solved together with its diagonal block (a dense triangular
/// solve with as many right-hand sides), then subtracted from the rows below it.
fn forward(tree: &Tree, l: &[f64], blocks: &[Terms]) -> Result<Vec<NodeW>, SolveError> {
    let nn = tree.begin.len() - 1;
    let mut pos = vec![NONE; nn];
    let mut stamp = vec![NONE; nn];
    let mut nodes: Vec<NodeW> = Vec::new();
    let mut first = 0;
    for (bi, b) in blocks.iter().enumerate() {
        let k = b.signs.len();
        for &i in &b.unknowns {
            let mut s = tree.node_of[tree.inv[i]] as usize;
            while s != NONE && stamp[s] != bi {
                stamp[s] = bi;
                if pos[s] == NONE {
                    pos[s] = nodes.len();
                    nodes.push(NodeW {
                        s,
                        terms: Vec::new(),
                        x: Vec::new(),
                    });
                }
                nodes[pos[s]].terms.extend(first..first + k);
                s = tree.parent[s];
            }
        }
        first += k;
    }
    nodes.sort_unstable_by_key(|nw| nw.s);
    for (i, nw) in nodes.iter_mut().enumerate() {
        pos[nw.s] = i;
        nw.x = vec![0.0; tree.width(nw.s) * nw.terms.len()];
    }
    let outside = |s: usize, p: usize| {
        SolveError::Other(format!(
            "low-rank correction: row {p} of supernode {s} lies outside the elimination-tree path"
        ))
    };
    let mut first = 0;
    for b in blocks {
        let (q, k) = (b.unknowns.len(), b.signs.len());
        for (a, &i) in b.unknowns.iter().enumerate() {
            let p = tree.inv[i];
            let nw = &mut nodes[pos[tree.node_of[p] as usize]];
            let (c, row) = (tree.width(nw.s), p - tree.begin[nw.s]);
            for t in 0..k {
                let j = nw
                    .terms
                    .binary_search(&(first + t))
                    .expect("term at its node");
                nw.x[j * c + row] = b.vectors[t * q + a];
            }
        }
        first += k;
    }
    let mut tmp = Mat::<f64>::zeros(0, 0);
    let mut cols = Vec::new();
    for ni in 0..nodes.len() {
        let s = nodes[ni].s;
        let c = tree.width(s);
        let pattern = tree.pattern(s);
        let ls = MatRef::from_column_major_slice(
            &l[tree.val_ptr[s]..tree.val_ptr[s + 1]],
            c + pattern.len(),
            c,
        );
        let rs = nodes[ni].terms.len();
        {
            let mut x = MatMut::from_column_major_slice_mut(&mut nodes[ni].x, c, rs);
            solve_lower_triangular_in_place(ls.subrows(0, c), x.rb_mut(), Par::Seq);
            tmp.resize_with(pattern.len(), rs, |_, _| 0.0);
            matmul(
                tmp.as_mut(),
                Accum::Replace,
                ls.subrows(c, pattern.len()),
                x.rb(),
                1.0,
                Par::Seq,
            );
        }
        // subtract from the ancestors' rows, a run of rows of one supernode at a time
        let mut i0 = 0;
        while i0 < pattern.len() {
            let a = tree.node_of[pattern[i0] as usize] as usize;
            let i1 = i0
                + pattern[i0..]
                    .iter()
                    .take_while(|&&p| tree.node_of[p as usize] as usize == a)
                    .count();
            let pa = pos[a];
            if pa == NONE || pa <= ni {
                return Err(outside(s, pattern[i0] as usize));
            }
            let (head, tail) = nodes.split_at_mut(pa);
            let target = &mut tail[0];
            cols.clear();
            for t in &head[ni].terms {
                let j = target
                    .terms
                    .binary_search(t)
                    .map_err(|_| outside(s, pattern[i0] as usize))?;
                cols.push(j);
            }
            let (ca, ba) = (tree.width(a), tree.begin[a]);
            for (ii, &p) in pattern[i0..i1].iter().enumerate() {
                let row = p as usize - ba;
                for (j, &ja) in cols.iter().enumerate() {
                    target.x[ja * ca + row] -= tmp[(i0 + ii, j)];
                }
            }
            i0 = i1;
        }
    }
    Ok(nodes)
}

#[cfg(test)]
mod tests;
