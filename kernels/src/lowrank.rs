//! Solves with a matrix that differs from a factorized one by a change on few unknowns,
//! at about the cost of one solve with the held factor (issue 6: a secant iteration of
//! docs/theory.md §4 in which a few contacts changed state, their stiffness ΔK_c = Bᵀ Δk B
//! of docs/theory.md §3 added to the factorized K_old).
//!
//! **Method** (the Woodbury identity applied inside the factor). With the held factor
//! P K_old Pᵀ = L Lᵀ ([`FaerCholesky`], P its fill-reducing permutation) and the change
//! split into signed rank-one terms ΔK = K_new − K_old = U S Uᵀ (U: n × r, S = diag(±1)),
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
//! (`Split`, private), every entry receiving the same operations in the same order as in faer's
//! sequential substitution, and the scan of ΔK runs in chunks of rows whose changes are
//! read in order; the rest (W, C and its eigendecomposition) is sequential.

use crate::backend::{LinearBackend, SolveError};
use crate::csr::CsrMatrix;
use crate::faer_backend::FaerCholesky;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::matmul::{matmul, matmul_with_conj};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_lower_triangular_in_place_with_conj,
    solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::triangular_solve as sparse_tri;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::time::Instant;

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
    fn new(factor: &FaerCholesky) -> Result<Self, SolveError> {
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
    fn substitute(
        &mut self,
        an: &crate::faer_backend::CholAnalysis,
        y: &mut [f64],
        transpose: bool,
    ) {
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

/// The partition of a supernodal elimination tree for the substitutions with L on several
/// threads: disjoint subtrees ("parts"), each done on its own rayon task on a copy of its
/// columns of y, and the rest (the parts' ancestors — the top separators — and the
/// subtrees too small for a task), done sequentially.
///
/// In L⁻¹ y the parts run first; a part's products for rows above it (in the rest) are
/// kept and subtracted when the sequential pass over the supernodes reaches the one that
/// made them. In L⁻ᵀ y the rest runs first (it reads only its ancestors), then the parts,
/// each reading the rows above it from a copy. Every entry of y thus receives the same
/// floating-point operations in the same order as in faer's sequential substitution
/// (`l_solve_with_conj`, `l_transpose_solve_with_conj`, whose per-supernode steps
/// [`node_forward`] and [`node_backward`] repeat with the same kernels): the result is
/// bit-identical to it whatever the number of threads, and the partition depends on the
/// tree only.
struct Split {
    parts: Vec<Part>,
    /// Part of each supernode (`NONE` for the rest) and its index among the part's.
    part_of: Vec<(usize, usize)>,
    /// One scratch per part.
    scratch: Vec<PartScratch>,
}

/// A subtree of [`Split`].
struct Part {
    /// Its supernodes, ascending, and the offset of each one's columns in the part's
    /// copy of y (one past the last at the end).
    nodes: Vec<usize>,
    local: Vec<usize>,
    /// The columns of the part (permuted numbering), in the order of the copy.
    cols: Vec<u32>,
    /// For each entry of its supernodes' patterns, one supernode after the other: the row's
    /// position in the copy, or `OUTSIDE` for a row of the rest; `pat_ptr[i]` the first
    /// entry of supernode `nodes[i]`.
    map: Vec<u32>,
    pat_ptr: Vec<usize>,
    /// The pattern rows outside the part, in the same order; those of supernode `nodes[i]`
    /// are `outside[out_ptr[i]..out_ptr[i + 1]]`.
    outside: Vec<u32>,
    out_ptr: Vec<usize>,
}

const OUTSIDE: u32 = u32::MAX;

#[derive(Default)]
struct PartScratch {
    /// The part's columns of y.
    x: Vec<f64>,
    /// Values for the rows of `outside`: the products to subtract (L⁻¹), or y's final
    /// values there (L⁻ᵀ).
    out: Vec<f64>,
    /// One supernode's product with its rows below the diagonal block.
    tmp: Vec<f64>,
}

/// The partition is searched by splitting the heaviest subtree into its children (its
/// root going to the sequential rest) while it weighs more than `1 / SPLIT_PARTS` of the
/// substitution's flops, keeping the candidate partition whose estimated time on two
/// threads (the rest, plus the parts given heaviest first to the less loaded thread) is
/// least: on the 40 × 40 wall P2 (rigid, 531 supernodes) 0.54 of the sequential flops,
/// three parts; the same for the deformable one (3457 supernodes, four parts).
const SPLIT_PARTS: f64 = 32.0;
/// A factor whose substitution costs fewer flops (a few tens of microseconds) is not
/// split: rayon's tasks would cost about as much.
const SPLIT_MIN_WORK: f64 = 2e5;
/// Subtrees lighter than `1 / SPLIT_SMALL` of the work stay in the sequential rest.
const SPLIT_SMALL: f64 = 64.0;

impl Split {
    /// The partition of the supernodal tree given by `begin`, `row_ptr`, `rows`, `parent`
    /// and `node_of` (as in [`Tree`]), or None when it has fewer than two parts.
    fn new(
        begin: &[usize],
        row_ptr: &[usize],
        rows: &[u32],
        parent: &[usize],
        node_of: &[u32],
    ) -> Option<Self> {
        let nodes = parent.len();
        let mut work = vec![0.0f64; nodes];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        let mut roots = Vec::new();
        for s in 0..nodes {
            let (c, p) = (
                (begin[s + 1] - begin[s]) as f64,
                (row_ptr[s + 1] - row_ptr[s]) as f64,
            );
            // flops of the supernode's step: its triangle and its rows below
            work[s] += c * (c + 2.0 * p);
            match parent[s] {
                NONE => roots.push(s),
                // a parent after its children (faer's supernodes are so numbered; the
                // passes below rely on it)
                q if q > s && q < nodes => {
                    work[q] += work[s];
                    children[q].push(s);
                }
                _ => return None,
            }
        }
        let total: f64 = roots.iter().map(|&r| work[r]).sum();
        if total < SPLIT_MIN_WORK {
            return None;
        }
        // the work on two threads: the rest, then the parts (those not too small) each
        // given, heaviest first, to the less loaded thread
        let on_two = |cand: &[usize]| {
            let mut w: Vec<f64> = cand
                .iter()
                .map(|&s| work[s])
                .filter(|&w| w >= total / SPLIT_SMALL)
                .collect();
            w.sort_by(|a, b| b.total_cmp(a));
            let mut t = [0.0f64; 2];
            for x in &w {
                t[usize::from(t[1] < t[0])] += x;
            }
            total - w.iter().sum::<f64>() + t[0].max(t[1])
        };
        // split the heaviest subtree into its children while it weighs more than
        // 1 / SPLIT_PARTS of the work, keeping the candidates that do best on two threads
        let mut cand = roots;
        let mut best = (on_two(&cand), cand.clone());
        while let Some((i, &h)) = cand
            .iter()
            .enumerate()
            .filter(|&(_, &s)| !children[s].is_empty())
            .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]).then(b.1.cmp(a.1)))
        {
            if work[h] <= total / SPLIT_PARTS {
                break;
            }
            cand.swap_remove(i);
            cand.extend_from_slice(&children[h]);
            let t = on_two(&cand);
            if t < best.0 {
                best = (t, cand.clone());
            }
        }
        let mut cand = best.1;
        cand.retain(|&s| work[s] >= total / SPLIT_SMALL);
        if cand.len() < 2 {
            return None;
        }
        cand.sort_unstable();
        let mut part_of = vec![(NONE, 0); nodes];
        let mut parts = Vec::with_capacity(cand.len());
        for (pi, &root) in cand.iter().enumerate() {
            let mut members = vec![root];
            let mut i = 0;
            while i < members.len() {
                members.extend_from_slice(&children[members[i]]);
                i += 1;
            }
            members.sort_unstable();
            let mut local = vec![0];
            let mut cols = Vec::new();
            for (i, &s) in members.iter().enumerate() {
                part_of[s] = (pi, i);
                cols.extend(begin[s] as u32..begin[s + 1] as u32);
                local.push(cols.len());
            }
            let mut map = Vec::new();
            let mut pat_ptr = vec![0];
            let mut outside = Vec::new();
            let mut out_ptr = vec![0];
            for &s in &members {
                for &r in &rows[row_ptr[s]..row_ptr[s + 1]] {
                    // the row's supernode and its place in the copy
                    let a = node_of[r as usize] as usize;
                    match part_of[a] {
                        (p, i) if p == pi => {
                            map.push((local[i] + r as usize - begin[a]) as u32);
                        }
                        _ => {
                            map.push(OUTSIDE);
                            outside.push(r);
                        }
                    }
                }
                pat_ptr.push(map.len());
                out_ptr.push(outside.len());
            }
            parts.push(Part {
                nodes: members,
                local,
                cols,
                map,
                pat_ptr,
                outside,
                out_ptr,
            });
        }
        let scratch = parts.iter().map(|_| PartScratch::default()).collect();
        Some(Self {
            parts,
            part_of,
            scratch,
        })
    }

    /// y ← L⁻¹ y, or L⁻ᵀ y if `transpose`.
    fn substitute(&mut self, t: &Tree, l: &[f64], y: &mut [f64], transpose: bool) {
        if transpose {
            self.backward(t, l, y);
        } else {
            self.forward(t, l, y);
        }
    }

    /// Each part's copy of its columns of y.
    fn gather(&mut self, y: &[f64]) {
        for (part, sc) in self.parts.iter().zip(self.scratch.iter_mut()) {
            sc.x.clear();
            sc.x.extend(part.cols.iter().map(|&c| y[c as usize]));
        }
    }

    /// Each part's copy back into its columns of y.
    fn scatter(&self, y: &mut [f64]) {
        for (part, sc) in self.parts.iter().zip(&self.scratch) {
            for (&c, &v) in part.cols.iter().zip(&sc.x) {
                y[c as usize] = v;
            }
        }
    }

    /// y ← L⁻¹ y (y permuted, length n), `l` the supernodal factor's values.
    fn forward(&mut self, t: &Tree, l: &[f64], y: &mut [f64]) {
        self.gather(y);
        self.parts
            .par_iter()
            .zip(self.scratch.par_iter_mut())
            .for_each(|(part, sc)| {
                sc.out.clear();
                for (i, &s) in part.nodes.iter().enumerate() {
                    let map = &part.map[part.pat_ptr[i]..part.pat_ptr[i + 1]];
                    sc.tmp.resize(map.len(), 0.0);
                    let x = &mut sc.x[part.local[i]..part.local[i + 1]];
                    node_forward(t.node_l(l, s), x, &mut sc.tmp);
                    for (&m, &v) in map.iter().zip(&sc.tmp) {
                        if m == OUTSIDE {
                            sc.out.push(v);
                        } else {
                            sc.x[m as usize] -= v;
                        }
                    }
                }
            });
        self.scatter(y);
        let mut tmp = Vec::new();
        for (s, &(pi, i)) in self.part_of.iter().enumerate() {
            if pi != NONE {
                let part = &self.parts[pi];
                let (a, b) = (part.out_ptr[i], part.out_ptr[i + 1]);
                for (&r, &v) in part.outside[a..b].iter().zip(&self.scratch[pi].out[a..b]) {
                    y[r as usize] -= v;
                }
                continue;
            }
            let pattern = t.pattern(s);
            tmp.resize(pattern.len(), 0.0);
            let b0 = t.begin[s];
            node_forward(t.node_l(l, s), &mut y[b0..b0 + t.width(s)], &mut tmp);
            for (&r, &v) in pattern.iter().zip(&tmp) {
                y[r as usize] -= v;
            }
        }
    }

    /// y ← L⁻ᵀ y (y permuted, length n), `l` the supernodal factor's values.
    fn backward(&mut self, t: &Tree, l: &[f64], y: &mut [f64]) {
        let mut tmp = Vec::new();
        for (s, &(pi, _)) in self.part_of.iter().enumerate().rev() {
            if pi == NONE {
                tmp.clear();
                tmp.extend(t.pattern(s).iter().map(|&r| y[r as usize]));
                let b0 = t.begin[s];
                node_backward(t.node_l(l, s), &mut y[b0..b0 + t.width(s)], &tmp);
            }
        }
        self.gather(y);
        for (part, sc) in self.parts.iter().zip(self.scratch.iter_mut()) {
            sc.out.clear();
            sc.out.extend(part.outside.iter().map(|&r| y[r as usize]));
        }
        self.parts
            .par_iter()
            .zip(self.scratch.par_iter_mut())
            .for_each(|(part, sc)| {
                for (i, &s) in part.nodes.iter().enumerate().rev() {
                    let map = &part.map[part.pat_ptr[i]..part.pat_ptr[i + 1]];
                    let mut out = sc.out[part.out_ptr[i]..part.out_ptr[i + 1]].iter();
                    sc.tmp.clear();
                    for &m in map {
                        sc.tmp.push(if m == OUTSIDE {
                            *out.next().expect("outside row")
                        } else {
                            sc.x[m as usize]
                        });
                    }
                    let x = &mut sc.x[part.local[i]..part.local[i + 1]];
                    node_backward(t.node_l(l, s), x, &sc.tmp);
                }
            });
        self.scatter(y);
    }
}

/// Supernode step of L⁻¹ y as faer's `l_solve_with_conj` does it: x ← L_ss⁻¹ x (x the
/// supernode's rows of y), tmp ← L_bs x (its rows below the diagonal block, subtracted by
/// the caller).
fn node_forward(ls: MatRef<'_, f64>, x: &mut [f64], tmp: &mut [f64]) {
    let (c, p) = (x.len(), tmp.len());
    let mut x = MatMut::from_column_major_slice_mut(x, c, 1);
    solve_lower_triangular_in_place_with_conj(ls.subrows(0, c), Conj::No, x.rb_mut(), Par::Seq);
    matmul_with_conj(
        MatMut::from_column_major_slice_mut(tmp, p, 1),
        Accum::Replace,
        ls.subrows(c, p),
        Conj::No,
        x.rb(),
        Conj::No,
        1.0,
        Par::Seq,
    );
}

/// Supernode step of L⁻ᵀ y as faer's `l_transpose_solve_with_conj` does it:
/// x ← L_ss⁻ᵀ (x − L_bsᵀ tmp), tmp the values of y at the supernode's pattern rows.
fn node_backward(ls: MatRef<'_, f64>, x: &mut [f64], tmp: &[f64]) {
    let (c, p) = (x.len(), tmp.len());
    let mut x = MatMut::from_column_major_slice_mut(x, c, 1);
    matmul_with_conj(
        x.rb_mut(),
        Accum::Add,
        ls.subrows(c, p).transpose(),
        Conj::No,
        MatRef::from_column_major_slice(tmp, p, 1),
        Conj::No,
        -1.0,
        Par::Seq,
    );
    solve_upper_triangular_in_place_with_conj(
        ls.subrows(0, c).transpose(),
        Conj::No,
        x.rb_mut(),
        Par::Seq,
    );
}

/// The held backend's analysis, if it holds a successful LLᵀ factorization.
fn held(factor: &FaerCholesky) -> Result<&crate::faer_backend::CholAnalysis, SolveError> {
    match &factor.core().analysis {
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

/// The correction of a held [`FaerCholesky`] factor of K_old for a K_new on the same
/// pattern (see the module's documentation).
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

    /// Prepares solves with `k_new` (same pattern as the matrix `factor` last factorized,
    /// any units as long as they are K's) from `factor`'s held factorization of K_old.
    ///
    /// Errors: no factorization held, another pattern, a rank above the limit
    /// ([`SolveError::Other`]); K_new not positive definite or nearly singular
    /// ([`SolveError::NotPositiveDefinite`], `index` an unknown of the offending block
    /// of ΔK, `pivot` NaN).
    pub fn update(&mut self, factor: &FaerCholesky, k_new: &CsrMatrix) -> Result<(), SolveError> {
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
        self.factor_id = Some((an.pattern.id(), factor.stats().numeric_factorizations));
        self.new_values.clone_from(&k_new.values);
        Ok(())
    }

    /// rhs ← K_old⁻¹ rhs with the held factor alone, its substitutions on the tree's
    /// [`Split`] (bit-identical to faer's solve; [`FaerCholesky`]'s `LinearBackend::solve`
    /// with more than one rayon thread). `false` when that does not apply (nothing
    /// factorized, a simplicial factor, a tree without parts, one thread, a right-hand
    /// side of another length): the caller takes faer's solve, which also reports the
    /// errors.
    pub(crate) fn solve_held(
        &mut self,
        factor: &FaerCholesky,
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
        let current = held(factor)
            .map(|an| (an.pattern.id(), factor.stats().numeric_factorizations))
            .ok();
        let fresh = current.is_some()
            && self.factor_id == current
            && crate::backend::same_bits(&self.new_values, &k_new.values);
        if !fresh {
            self.update(factor, k_new)?;
        }
        self.solve(factor, rhs)
    }

    /// rhs ← K_new⁻¹ rhs for the K_new of the last successful [`update`](Self::update),
    /// with the same held factorization (else an error).
    pub fn solve(&mut self, factor: &FaerCholesky, rhs: &mut [f64]) -> Result<(), SolveError> {
        let t = Instant::now();
        let an = held(factor)?;
        if self.factor_id != Some((an.pattern.id(), factor.stats().numeric_factorizations)) {
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
fn substitute(
    an: &crate::faer_backend::CholAnalysis,
    y: &mut [f64],
    transpose: bool,
    mem: &mut MemBuffer,
) {
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
mod tests {
    use super::*;
    use crate::csr::CsrPattern;
    use std::sync::Arc;

    /// A spring: nodes a and b, stiffness (kx, ky) on their relative displacement, N/m
    /// (b = None: a spring to the ground).
    #[derive(Clone, Copy)]
    struct Spring {
        a: usize,
        b: Option<usize>,
        k: [f64; 2],
    }

    /// An nx × ny grid of nodes with two unknowns each (x, y), springs between
    /// neighbours (normal stiffness 1 along the joining line, shear 0.4 across, a few
    /// varied by ±30 %) and the bottom row tied to the ground: a small analogue of the
    /// wall's contacts.
    fn grid(nx: usize, ny: usize) -> (usize, Vec<Spring>) {
        let id = |i: usize, j: usize| j * nx + i;
        let vary = |s: usize| 1.0 + 0.3 * (((s * 7919) % 13) as f64 / 6.0 - 1.0);
        let mut springs = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let s = springs.len();
                if i + 1 < nx {
                    springs.push(Spring {
                        a: id(i, j),
                        b: Some(id(i + 1, j)),
                        k: [vary(s), 0.4],
                    });
                }
                if j + 1 < ny {
                    springs.push(Spring {
                        a: id(i, j),
                        b: Some(id(i, j + 1)),
                        k: [0.4, vary(s + 1)],
                    });
                }
                if j == 0 {
                    springs.push(Spring {
                        a: id(i, j),
                        b: None,
                        k: [1.0, 1.0],
                    });
                }
            }
        }
        (2 * nx * ny, springs)
    }

    /// The stiffness of `springs` on n unknowns (pattern from all of `pattern_of`).
    fn stiffness(n: usize, pattern_of: &[Spring], springs: &[Spring]) -> CsrMatrix {
        let mut e: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        for s in pattern_of {
            if let Some(b) = s.b {
                for c in 0..2 {
                    e.push((2 * s.a + c, 2 * b + c));
                    e.push((2 * b + c, 2 * s.a + c));
                }
            }
        }
        let mut k = CsrMatrix::zeros(Arc::new(CsrPattern::from_entries(n, e)));
        for s in springs {
            for c in 0..2 {
                let (i, kc) = (2 * s.a + c, s.k[c]);
                k.add(i, i, kc);
                if let Some(b) = s.b {
                    let j = 2 * b + c;
                    k.add(j, j, kc);
                    k.add(i, j, -kc);
                    k.add(j, i, -kc);
                }
            }
        }
        k
    }

    fn load(n: usize) -> Vec<f64> {
        (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 5.0).collect()
    }

    fn norm(v: impl Iterator<Item = f64>) -> f64 {
        v.map(|a| a * a).sum::<f64>().sqrt()
    }

    fn residual(k: &CsrMatrix, x: &[f64], f: &[f64]) -> f64 {
        let mut kx = vec![0.0; x.len()];
        k.mul_vec(x, &mut kx);
        norm(f.iter().zip(&kx).map(|(a, b)| a - b)) / norm(f.iter().copied())
    }

    fn backends() -> [FaerCholesky; 2] {
        [
            FaerCholesky::new().with_supernodal_threshold(0.0),
            FaerCholesky::new().with_supernodal_threshold(f64::INFINITY),
        ]
    }

    /// Ground —k1— node 0 —k2— node 1 (x only; y held by ground springs of 1): with a
    /// load F at node 1, u₀ = F/k1 and u₁ = F/k1 + F/k2 for any k2 > 0. k1 = 2, k2 = 3
    /// factorized, k2 changed to 0.5 (a downdate) and to 30 (an update): a few roundings
    /// of numbers of order 1, so 1e-14.
    #[test]
    fn two_springs_closed_form() {
        let chain = |k2: f64| {
            vec![
                Spring {
                    a: 0,
                    b: None,
                    k: [2.0, 1.0],
                },
                Spring {
                    a: 1,
                    b: None,
                    k: [0.0, 1.0],
                },
                Spring {
                    a: 0,
                    b: Some(1),
                    k: [k2, 0.0],
                },
            ]
        };
        let old = chain(3.0);
        for mut backend in backends() {
            backend.factorize(&stiffness(4, &old, &old)).unwrap();
            let mut c = LowRankCorrection::new();
            for k2 in [0.5, 30.0] {
                c.update(&backend, &stiffness(4, &old, &chain(k2))).unwrap();
                assert_eq!(c.stats().rank, 1);
                let mut x = vec![0.0, 0.0, 1.0, 0.0];
                c.solve(&backend, &mut x).unwrap();
                let want = [0.5, 0.0, 0.5 + 1.0 / k2, 0.0];
                for (a, b) in x.iter().zip(want) {
                    assert!((a - b).abs() < 1e-14, "k2 = {k2}: {x:?} against {want:?}");
                }
            }
            // k2 → 0 leaves node 1 free along x: singular, reported
            let err = c
                .update(&backend, &stiffness(4, &old, &chain(0.0)))
                .unwrap_err();
            assert!(
                matches!(err, SolveError::NotPositiveDefinite { index, .. } if index == 0 || index == 2),
                "{err:?}"
            );
            // and a spring of negative stiffness beyond it: indefinite, reported
            let err = c
                .update(&backend, &stiffness(4, &old, &chain(-1.0)))
                .unwrap_err();
            assert!(
                matches!(err, SolveError::NotPositiveDefinite { .. }),
                "{err:?}"
            );
            let mut x = vec![1.0; 4];
            assert!(
                c.solve(&backend, &mut x).is_err(),
                "no solve after a failed update"
            );
        }
    }

    /// Springs of a 30 × 20 grid opened (both stiffnesses removed: a rank-2 downdate),
    /// slipping (shear removed: rank 1), stiffened (×5 normal: a rank-1 update), two
    /// changes sharing a node (one block of ΔK): the solution against faer's fresh
    /// factorization of K_new, supernodal and simplicial. Both carry an error of about
    /// cond(K)·ε (cond ≈ 10⁴ for this grid held at one edge), so they agree to 1e-9
    /// relative; the true residual of the correction ‖f − K x‖/‖f‖ is below 1e-12.
    #[test]
    fn against_a_fresh_factorization() {
        let (n, old) = grid(30, 20);
        let mut new = old.clone();
        let mut expected_rank = 0;
        for (t, s) in (0..old.len()).step_by(47).enumerate() {
            match t % 3 {
                0 => {
                    new[s].k = [0.0, 0.0];
                    expected_rank += 2;
                }
                1 => {
                    let normal = if new[s].k[0] == 0.4 { 1 } else { 0 };
                    new[s].k[1 - normal] = 0.0;
                    expected_rank += 1;
                }
                _ => {
                    new[s].k = [5.0 * new[s].k[0], new[s].k[1]];
                    expected_rank += 1;
                }
            }
        }
        // two changes sharing node a of spring 99 (springs 99 and 100 leave it)
        assert_eq!(old[99].a, old[100].a);
        new[99].k = [0.0, 0.0];
        new[100].k[0] *= 0.5;
        expected_rank += 3;
        let (k_old, k_new) = (stiffness(n, &old, &old), stiffness(n, &old, &new));
        let f = load(n);
        for (mut backend, mut fresh) in backends().into_iter().zip(backends()) {
            backend.factorize(&k_old).unwrap();
            let mut c = LowRankCorrection::new();
            let mut x = f.clone();
            assert!(c.solve(&backend, &mut x).is_err(), "solve before update");
            c.update(&backend, &k_new).unwrap();
            assert_eq!(c.stats().rank, expected_rank);
            c.solve(&backend, &mut x).unwrap();
            fresh.factorize(&k_new).unwrap();
            let mut want = f.clone();
            fresh.solve(&mut want).unwrap();
            let diff = norm(x.iter().zip(&want).map(|(a, b)| a - b)) / norm(want.iter().copied());
            assert!(diff < 1e-9, "relative difference {diff:e}");
            let res = residual(&k_new, &x, &f);
            assert!(res < 1e-12, "true residual {res:e}");
            // no change: the plain solve with the held factor, bit for bit
            c.update(&backend, &k_old).unwrap();
            assert_eq!(c.stats().rank, 0);
            let (mut a, mut b) = (f.clone(), f.clone());
            c.solve(&backend, &mut a).unwrap();
            backend.solve(&mut b).unwrap();
            assert!(a
                .iter()
                .zip(&b)
                .all(|(p, q)| (p - q).abs() <= 1e-14 * q.abs().max(1e-3)));
            // a refactorization makes the update stale
            backend.factorize(&k_new).unwrap();
            assert!(c.solve(&backend, &mut a).is_err(), "stale update");
        }
    }

    /// All springs around an interior node opened: the node floats, K_new is singular,
    /// the update reports it at one of the node's unknowns or a neighbour's.
    #[test]
    fn downdate_to_a_mechanism_is_reported() {
        let (n, old) = grid(12, 8);
        let node = 5 * 12 + 6;
        let mut new = old.clone();
        let mut around = vec![node];
        for s in new.iter_mut() {
            if s.a == node || s.b == Some(node) {
                around.push(if s.a == node { s.b.unwrap() } else { s.a });
                s.k = [0.0, 0.0];
            }
        }
        assert_eq!(around.len(), 5);
        for mut backend in backends() {
            backend.factorize(&stiffness(n, &old, &old)).unwrap();
            let mut c = LowRankCorrection::new();
            let err = c.update(&backend, &stiffness(n, &old, &new)).unwrap_err();
            match err {
                SolveError::NotPositiveDefinite { index, .. } => {
                    assert!(around.contains(&(index / 2)), "unknown {index}")
                }
                e => panic!("{e:?}"),
            }
            // one spring left: positive definite again, and solved
            new[old.iter().position(|s| s.a == node).unwrap()].k = [0.1, 0.1];
            let k_new = stiffness(n, &old, &new);
            c.update(&backend, &k_new).unwrap();
            let f = load(n);
            let mut x = f.clone();
            c.solve(&backend, &mut x).unwrap();
            assert!(residual(&k_new, &x, &f) < 1e-12);
            new = old.clone();
            for s in new.iter_mut() {
                if s.a == node || s.b == Some(node) {
                    s.k = [0.0, 0.0];
                }
            }
        }
    }

    /// The substitutions on the [`Split`]'s parts give faer's sequential ones bit for bit
    /// (the same operations on every entry, in the same order: see [`Split`]) in rayon
    /// pools of 1, 2 and 8 threads (the split called directly: `Tree::substitute` takes
    /// faer's kernels on one thread), forward and backward, on the supernodal factor of
    /// an 80 × 60 grid (METIS and AMD orderings), whose tree has at least two parts.
    #[test]
    fn split_substitution_is_faers_bit_for_bit() {
        let (n, springs) = grid(80, 60);
        let k = stiffness(n, &springs, &springs);
        for name in ["faer-cholesky", "faer-cholesky-metis"] {
            let mut backend = FaerCholesky::new().with_supernodal_threshold(0.0);
            if name.ends_with("metis") {
                backend = backend.with_ordering(crate::ordering::FillOrdering::Metis);
            }
            backend.factorize(&k).unwrap();
            let an = held(&backend).unwrap();
            let mut tree = Tree::new(&backend).unwrap();
            let parts = tree.split.as_ref().map_or(0, |s| s.parts.len());
            assert!(parts >= 2, "{name}: {parts} parts");
            let f = load(n);
            for transpose in [false, true] {
                let mut want = f.clone();
                substitute(an, &mut want, transpose, &mut tree.mem);
                for threads in [1, 2, 8] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let mut y = f.clone();
                    let mut split = tree.split.take().expect("split");
                    pool.install(|| split.substitute(&tree, &an.l_values, &mut y, transpose));
                    tree.split = Some(split);
                    assert!(
                        crate::backend::same_bits(&y, &want),
                        "{name}, transpose {transpose}, {threads} threads"
                    );
                }
            }
        }
    }

    /// [`FaerCholesky`]'s solve on 2 and 8 threads (the split's substitutions) gives its
    /// solve on one thread (faer's `solve_in_place_with_conj`, permutation included) bit
    /// for bit, on the 80 × 60 grid with both orderings.
    #[test]
    fn held_solve_on_threads_is_faers_bit_for_bit() {
        let (n, springs) = grid(80, 60);
        let k = stiffness(n, &springs, &springs);
        for ordering in [
            crate::ordering::FillOrdering::Amd,
            crate::ordering::FillOrdering::Metis,
        ] {
            let mut backend = FaerCholesky::new()
                .with_supernodal_threshold(0.0)
                .with_ordering(ordering);
            backend.factorize(&k).unwrap();
            let f = load(n);
            let pool = |t| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap()
            };
            let mut want = f.clone();
            pool(1).install(|| backend.solve(&mut want)).unwrap();
            let mut c = LowRankCorrection::new();
            let mut y = f.clone();
            assert!(!pool(1).install(|| c.solve_held(&backend, &mut y)).unwrap());
            for threads in [2, 8] {
                let mut y = f.clone();
                assert!(pool(threads)
                    .install(|| c.solve_held(&backend, &mut y))
                    .unwrap());
                assert!(
                    crate::backend::same_bits(&y, &want),
                    "{ordering:?}, {threads}"
                );
                let mut y = f.clone();
                pool(threads).install(|| backend.solve(&mut y)).unwrap();
                assert!(
                    crate::backend::same_bits(&y, &want),
                    "{ordering:?}, {threads}"
                );
            }
            assert_eq!(backend.stats().solves, 3);
        }
    }

    /// Timing of one solve's two substitutions (L⁻¹ then L⁻ᵀ) on the supernodal factor of
    /// a 120 × 100 grid (24,000 unknowns, x and y uncoupled: two 12,000-unknown problems;
    /// factor about the size of the deformable 40 × 40 wall P2's): faer's
    /// sequential kernels against the [`Split`] in pools of 1 and 2 threads, 400 rounds
    /// taken in turn, minimum and median printed (docs/performance.md, "P2: the 40 × 40 wall against OpenSees"). Not a
    /// check of speed (that depends on the machine's load); the bits are checked.
    /// `cargo test --release -p dfem-kernels --lib split_substitution_timing -- --ignored --nocapture`
    #[test]
    #[ignore]
    fn split_substitution_timing() {
        let (n, springs) = grid(120, 100);
        let k = stiffness(n, &springs, &springs);
        let mut backend = FaerCholesky::new().with_supernodal_threshold(0.0);
        backend.factorize(&k).unwrap();
        let an = held(&backend).unwrap();
        let mut tree = Tree::new(&backend).unwrap();
        println!(
            "factor nnz {}, {} parts",
            an.l_values.len(),
            tree.split.as_ref().map_or(0, |s| s.parts.len())
        );
        let f = load(n);
        let pools: Vec<rayon::ThreadPool> = [1, 2]
            .iter()
            .map(|&t| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap()
            })
            .collect();
        let mut times = vec![Vec::new(); 3];
        let mut want = f.clone();
        for round in 0..400 {
            let t = Instant::now();
            let mut y = f.clone();
            substitute(an, &mut y, false, &mut tree.mem);
            substitute(an, &mut y, true, &mut tree.mem);
            times[0].push(t.elapsed().as_secs_f64());
            if round == 0 {
                want = y;
            }
            for (i, pool) in pools.iter().enumerate() {
                let t = Instant::now();
                let mut y = f.clone();
                let mut split = tree.split.take().expect("split");
                pool.install(|| {
                    split.substitute(&tree, &an.l_values, &mut y, false);
                    split.substitute(&tree, &an.l_values, &mut y, true);
                });
                tree.split = Some(split);
                times[i + 1].push(t.elapsed().as_secs_f64());
                assert!(crate::backend::same_bits(&y, &want));
            }
        }
        for (name, mut t) in ["faer sequential", "split, 1 thread", "split, 2 threads"]
            .into_iter()
            .zip(times)
        {
            t.sort_by(f64::total_cmp);
            println!(
                "{name}: min {:.1} µs, median {:.1} µs",
                1e6 * t[0],
                1e6 * t[t.len() / 2]
            );
        }
    }

    /// The scan of ΔK in chunks of rows (an 80 × 60 grid: 9600 unknowns, three chunks)
    /// reports what a sequential scan would: with a rank limit of 2 and every entry
    /// changed, the 129th changed entry's row (the first one, in row order, beyond
    /// 64 × 2); a NaN in the last chunk after that: still the limit; a NaN with few
    /// changes before it: the NaN, at its row; and a rank-5 change spread over the
    /// chunks is split into one block and one term per changed spring direction (x and y
    /// unknowns are not coupled in this grid): 5 blocks, rank 5.
    #[test]
    fn chunked_scan_reports_as_a_sequential_one() {
        let (n, old) = grid(80, 60);
        let k_old = stiffness(n, &old, &old);
        assert!(k_old.values.len() > 2 * crate::backend::SAME_BITS_CHUNK);
        let limits = Some((ENTRIES_PER_RANK * 2, UNKNOWNS_PER_RANK * 2));
        let rp = k_old.pattern.row_ptr();
        let row_of = |e: usize| (0..n).find(|&i| rp[i + 1] > e).unwrap();
        let mut scaled = k_old.clone();
        scaled.values.iter_mut().for_each(|v| *v *= 1.001);
        // entries are numbered row by row: the 129th nonzero change is entry 128
        let err = |k: &CsrMatrix| match split_change(k, &k_old.values, limits) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("accepted"),
        };
        let want = format!(
            "more than 128 entries changed (from row {} on)",
            row_of(128)
        );
        assert!(err(&scaled).contains(&want), "{}", err(&scaled));
        let last = k_old.values.len() - 1;
        scaled.values[last] = f64::NAN;
        assert!(err(&scaled).contains(&want), "{}", err(&scaled));
        let mut nan = k_old.clone();
        nan.values[7] *= 2.0;
        nan.values[last] = f64::NAN;
        let e = err(&nan);
        assert!(
            e.contains("non-finite") && e.contains(&format!("at row {}", n - 1)),
            "{e}"
        );
        let mut new = old.clone();
        for s in [3, 4000, 9000] {
            new[s].k[0] *= 2.0;
        }
        new[9500].k = [0.0, 0.0];
        let terms = split_change(&stiffness(n, &old, &new), &k_old.values, limits).unwrap();
        let rank: usize = terms.iter().map(|b| b.signs.len()).sum();
        assert_eq!((terms.len(), rank), (5, 5));
    }

    /// A non-finite value in K_new, or a matrix of another size, is an error, not a panic.
    #[test]
    fn bad_input_is_an_error() {
        let (n, old) = grid(6, 5);
        let k_old = stiffness(n, &old, &old);
        let mut backend = FaerCholesky::new();
        let mut c = LowRankCorrection::new();
        assert!(c.update(&backend, &k_old).is_err(), "nothing factorized");
        backend.factorize(&k_old).unwrap();
        let mut k_new = k_old.clone();
        k_new.values[7] = f64::NAN;
        assert!(c.update(&backend, &k_new).is_err());
        let (m, small) = grid(3, 2);
        assert!(c.update(&backend, &stiffness(m, &small, &small)).is_err());
        c.update(&backend, &k_old).unwrap();
        assert!(c.solve(&backend, &mut vec![1.0; n + 1]).is_err());
    }

    /// The rank limit refuses a larger change with an error naming the fix.
    #[test]
    fn rank_limit() {
        let (n, old) = grid(6, 5);
        let mut new = old.clone();
        new[3].k = [0.0, 0.0];
        let mut backend = FaerCholesky::new();
        backend.factorize(&stiffness(n, &old, &old)).unwrap();
        let mut c = LowRankCorrection::new().with_max_rank(1);
        let err = c.update(&backend, &stiffness(n, &old, &new)).unwrap_err();
        assert!(err.to_string().contains("rank 2") && err.to_string().contains("refactorize"));
    }

    /// `LinearBackend::solve_changed` of `faer-cholesky` (through the trait object, as
    /// the driver calls it): the grid's springs changed as in
    /// [`against_a_fresh_factorization`] (rank 5) give faer's fresh solution of K_new to
    /// the same 1e-9 (both carry cond(K)·ε ≈ 10⁻¹², see there) and count in the
    /// backend's stats; the held factor still solves K_old (compared with a second
    /// backend's factorization of K_old: bit-identical, the same factorization); a second
    /// call with the same K_new reuses the update and gives the same bits.
    #[test]
    fn solve_changed_through_the_trait() {
        let (n, old) = grid(20, 12);
        let mut new = old.clone();
        new[30].k = [0.0, 0.0];
        new[101].k[0] *= 4.0;
        new[250].k = [0.0, 0.0];
        let (k_old, k_new) = (stiffness(n, &old, &old), stiffness(n, &old, &new));
        let f = load(n);
        for name in ["faer-cholesky", "faer-cholesky-metis"] {
            let mut backend = crate::backend::backend_from_name(name).unwrap();
            let mut x = f.clone();
            assert!(
                backend.solve_changed(&k_new, &mut x).is_err(),
                "{name}: nothing factorized"
            );
            backend.factorize(&k_old).unwrap();
            let mut x = f.clone();
            backend.solve_changed(&k_new, &mut x).unwrap();
            let mut fresh = crate::backend::backend_from_name(name).unwrap();
            fresh.factorize(&k_new).unwrap();
            let mut want = f.clone();
            fresh.solve(&mut want).unwrap();
            let diff = norm(x.iter().zip(&want).map(|(a, b)| a - b)) / norm(want.iter().copied());
            assert!(diff < 1e-9, "{name}: relative difference {diff:e}");
            let st = backend.stats();
            assert_eq!(
                (st.changed_solves, st.last_changed_rank, st.max_changed_rank),
                (1, 5, 5),
                "{name}"
            );
            assert_eq!(st.numeric_factorizations, 1, "{name}: no refactorization");
            let mut again = f.clone();
            backend.solve_changed(&k_new, &mut again).unwrap();
            assert!(crate::backend::same_bits(&again, &x), "{name}");
            let (mut a, mut b) = (f.clone(), f.clone());
            backend.solve(&mut a).unwrap();
            fresh.factorize(&k_old).unwrap();
            fresh.solve(&mut b).unwrap();
            assert!(crate::backend::same_bits(&a, &b), "{name}: the held factor");
        }
    }

    /// A change of every entry (the matrix of a new geometry: all values × 1.001) is
    /// refused after reading 64 × the rank limit of them, with an error naming the fix;
    /// so is one connected change on more unknowns than 8 × the limit (a row of springs
    /// along the grid all changed, one block of 2 × 20 unknowns, limit 2), before its
    /// eigendecomposition; the backend then refactorizes as usual. Backends without the
    /// path report `Unsupported`.
    #[test]
    fn solve_changed_refuses_what_does_not_pay() {
        let (n, old) = grid(20, 12);
        let k_old = stiffness(n, &old, &old);
        let f = load(n);
        let mut backend = FaerCholesky::new().with_changed_max_rank(2);
        backend.factorize(&k_old).unwrap();
        let mut scaled = k_old.clone();
        scaled.values.iter_mut().for_each(|v| *v *= 1.001);
        let err = backend.solve_changed(&scaled, &mut f.clone()).unwrap_err();
        assert!(
            err.to_string().contains("more than 128 entries changed")
                && err.to_string().contains("refactorize"),
            "{err}"
        );
        // the horizontal springs of the bottom row (nodes 0..20), stiffened: one block
        let mut new = old.clone();
        for s in new.iter_mut() {
            if s.a < 19 && s.b == Some(s.a + 1) {
                s.k[0] *= 2.0;
            }
        }
        let err = backend
            .solve_changed(&stiffness(n, &old, &new), &mut f.clone())
            .unwrap_err();
        assert!(err.to_string().contains("on 20 unknowns"), "{err}");
        assert_eq!(backend.stats().changed_solves, 0);
        backend.factorize(&scaled).unwrap();
        let mut x = f.clone();
        backend.solve(&mut x).unwrap();
        assert!(residual(&scaled, &x, &f) < 1e-12);
        for name in ["faer-ldlt", "faer-lu", "pcg", "faer-cholesky-split"] {
            let mut other = crate::backend::backend_from_name(name).unwrap();
            other.factorize(&k_old).unwrap();
            let err = other.solve_changed(&scaled, &mut f.clone()).unwrap_err();
            assert!(
                matches!(err, SolveError::Unsupported { backend, .. } if backend == name),
                "{name}: {err:?}"
            );
        }
    }
}
