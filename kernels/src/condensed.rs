//! [`FaerCholeskyCondensed`] (`faer-condensed`): sparse Cholesky with the blocks'
//! interiors condensed out — static condensation (Guyan reduction without approximation).
//!
//! A deformable block's unknowns split into its interior I_b — the unknowns coupled to
//! its own block's unknowns only, which no contact touches — and the rest of the model R
//! (every block's boundary unknowns, the rigid blocks' three). With the interiors first,
//!
//!   K = \[K_II K_IR; K_RI K_RR\],  K_II = diag(K_{I_b I_b}),
//!
//! and the Cholesky factorization of K is that of each block's K_{I_b I_b} (independent,
//! in parallel) followed by that of the condensed matrix on R,
//!
//!   S = K_RR − Σ_b K_{R I_b} K_{I_b I_b}⁻¹ K_{I_b R}
//!
//! (Saad, *Iterative methods for sparse linear systems*, 2nd ed., §14.2): each block adds a
//! dense clique on its boundary unknowns B_b (the Schur complement of its interior,
//! computed by `crate::partial` (private) on faer's symbolic structure, as the subdomains of
//! [`crate::substructure`]), and S is factorized by [`FaerCholesky`] (AMD), sparse.
//!
//! **What it saves.** In a nonlinear iteration of docs/theory.md §4 only contacts change state,
//! and a contact's stiffness enters K_RR alone: every block whose interior rows (K_{I_b I_b},
//! K_{I_b R}) hold the same values, bit for bit, keeps its factor and its clique, and the
//! refactorization is that of S — a matrix on the boundary unknowns only. A change of a few
//! contacts goes further, to the low-rank correction of S's held factor
//! ([`LinearBackend::solve_changed`], through [`FaerCholesky`]'s). A block's interior
//! changes only with its geometry or material (a new increment of the updated Lagrangian
//! geometry, or a new time step's effective matrix with another step), and then only that
//! block is redone. Rigid blocks have no interior; a scene of rigid blocks or of blocks
//! meshed without interior nodes gains nothing and pays the bookkeeping (use
//! `faer-cholesky`).
//!
//! **Which unknowns are interior** the caller says ([`LinearBackend::set_interiors`]:
//! the unknowns of a deformable block's nodes that no contact acts on), and the pattern
//! confirms: an unknown stays in R if its row couples to another block's interior. The
//! factorization is exact whatever the split — a contact that acts on an interior node
//! (one found during a dynamic run) only makes that block's interior change, which is
//! then refactorized — so the split decides the cost, never the result. Without the
//! interiors (never handed over) the backend is a plain [`FaerCholesky`].
//!
//! **When it pays** is decided at each analysis from the symbolic multiply-adds
//! ([`CONDENSE_MAX_SHARE`]); otherwise the whole matrix is factorized, bit for bit as by
//! `faer-cholesky`.
//!
//! Determinism: each block's factorization is sequential inside its rayon task, the
//! cliques are subtracted in block order and the forward solve's coupling terms added in
//! block order, so the results are bit-identical for any number of threads.

use crate::backend::{check_values, same_bits, LinearBackend, SolveError, SolverStats};
use crate::cholesky::cholesky_flops;
use crate::csr::{CsrMatrix, CsrPattern};
use crate::faer_backend::FaerCholesky;
use crate::split::InteriorOrder;
use crate::substructure::{Ctx, Leaf};
use faer::Par;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// A block's interior and where its clique goes in S.
struct Interior {
    leaf: Leaf,
    /// Its boundary unknowns B_b as positions in R (increasing with the global unknowns).
    bnd_root: Vec<u32>,
    /// For the lower triangle (k ≥ l) of its clique, row by row: the two stored entries of
    /// S it is subtracted from, (k, l) and (l, k) (the same one on the diagonal).
    scatter: Vec<(u32, u32)>,
    /// The Schur complement term K_{B I} K_{I I}⁻¹ K_{I B} of the last factorization
    /// (lower triangle, B order, row-major packed as `scatter`).
    clique: Vec<f64>,
    /// The smallest pivot ratio of its last factorization, and its unknown.
    pivot: (f64, usize),
    factored: bool,
}

/// The plan of one pattern.
struct Plan {
    pattern: Arc<CsrPattern>,
    interiors: Vec<Interior>,
    /// Before [`FaerCholeskyCondensed::finish`]: each interior's unknowns, its boundary
    /// unknowns B_b and their positions in R.
    pending: Vec<(Vec<u32>, Vec<u32>, Vec<u32>)>,
    /// R: global unknown of each position of S.
    root_dofs: Vec<u32>,
    /// `(entry of S, entry of K)` for the entries of K_RR.
    root_map: Vec<(u32, usize)>,
    /// S's values (the matrix handed to the root factorization).
    s: CsrMatrix,
    /// S for the matrix of a [`LinearBackend::solve_changed`] (S's pattern; allocated at
    /// the first call).
    s_changed: Option<CsrMatrix>,
    /// Scratch right-hand side on R.
    rhs_root: Vec<f64>,
    diag_pos: Vec<usize>,
}

/// When the condensation pays, from the multiply-adds of the symbolic analyses (the model
/// alone decides, not the machine): the condensed matrix's factorization — what an
/// iteration that changes contacts only refactorizes, and what the low-rank corrections
/// work on — at most this share of the whole matrix's. The interiors' factorizations
/// come on top only where a block's geometry changed (once an increment). On a 2D wall
/// of bricks with contacts all round, the cliques of the bricks' boundaries make S cost
/// more than the whole matrix (docs/performance.md, "Static condensation of the blocks' interiors"), and the
/// backend factorizes the whole matrix instead.
pub const CONDENSE_MAX_SHARE: f64 = 0.5;

/// Below this many multiply-adds of the whole matrix's factorization (about a millisecond)
/// the bookkeeping of the condensation costs more than it saves: the whole is factorized.
pub const CONDENSE_MIN_FLOPS: f64 = 1e6;

/// What the last analysis found and chose ([`FaerCholeskyCondensed::decision`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Unknowns in the blocks' interiors.
    pub interior: usize,
    /// Unknowns kept (R, S's size).
    pub kept: usize,
    /// Blocks with an interior.
    pub blocks: usize,
    /// Multiply-adds of S's numeric factorization (AMD).
    pub condensed_flops: f64,
    /// Multiply-adds of the whole matrix's numeric factorization (AMD).
    pub whole_flops: f64,
    /// Whether the condensation pays ([`CONDENSE_MAX_SHARE`], [`CONDENSE_MIN_FLOPS`]; or
    /// forced).
    pub pays: bool,
}

/// Sparse Cholesky with the blocks' interiors condensed out (see the module docs).
pub struct FaerCholeskyCondensed {
    /// The interior groups of [`LinearBackend::set_interiors`].
    groups: Option<Vec<u32>>,
    plan: Option<Plan>,
    /// The whole matrix's factorization, used when the condensation does not pay (or is
    /// not possible): every call then goes to it, bit for bit `faer-cholesky`.
    whole: FaerCholesky,
    use_whole: bool,
    /// Numeric factorizations of the whole matrix since the last analysis.
    whole_factorizations: usize,
    decision: Option<Decision>,
    /// This backend's own counters (the condensed mode's work, the analyses); [`stats`]
    /// adds the whole matrix's backend's.
    own: SolverStats,
    /// Condense whenever there are interiors, paying or not (for measurements).
    forced: bool,
    root: FaerCholesky,
    /// The values of K of the last successful factorization.
    last: Vec<f64>,
    factored: bool,
    threads: usize,
    stats: SolverStats,
    /// Partial factorizations of single interiors done so far (an interior whose rows
    /// did not change since its last one is not refactorized).
    interior_factorizations: usize,
}

impl Default for FaerCholeskyCondensed {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerCholeskyCondensed {
    /// A backend with the interiors' factorizations on the rayon pool and S's on one
    /// thread (`with_threads` to change).
    pub fn new() -> Self {
        Self {
            groups: None,
            plan: None,
            whole: FaerCholesky::new(),
            use_whole: false,
            whole_factorizations: 0,
            decision: None,
            own: SolverStats::default(),
            forced: false,
            // S is made of the blocks' Schur complements, a dense clique per block
            // (the column's drums: 68 unknowns each), which faer's flop-ratio test of
            // the AMD-ordered pattern leaves to the simplicial factorization; the
            // supernodal one factorizes those cliques with dense kernels: 16–20 % less
            // CPU time on the rocking column, whose time steps refactorize S at every
            // iteration (docs/decisions/0021-start-geometry-interiors.md)
            root: FaerCholesky::new().with_supernodal_threshold(0.0),
            last: Vec::new(),
            factored: false,
            threads: 1,
            interior_factorizations: 0,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Threads of the condensed matrix's numeric factorization (faer's `Par::rayon`).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads.max(1);
        self.root = FaerCholesky::new()
            .with_supernodal_threshold(0.0)
            .with_threads(self.threads);
        self.whole = FaerCholesky::new().with_threads(self.threads);
        self
    }

    /// Condense whenever some unknowns are interior, whether it pays or not
    /// ([`CONDENSE_MAX_SHARE`]); for measurements and tests.
    pub fn forced(mut self, on: bool) -> Self {
        self.forced = on;
        self
    }

    /// The split and the choice of the last analysis; `None` when nothing was interior
    /// (or no interiors were handed over).
    pub fn decision(&self) -> Option<Decision> {
        self.decision
    }

    /// Partial factorizations of single block interiors done so far: a factorization of
    /// the condensed form redoes only the interiors whose rows changed.
    pub fn interior_factorizations(&self) -> usize {
        self.interior_factorizations
    }

    /// Whether the interiors are condensed out now (`false`: the whole matrix is
    /// factorized, as by `faer-cholesky`).
    pub fn is_condensed(&self) -> bool {
        !self.use_whole
    }

    /// Unknowns condensed out (the blocks' interiors) and kept (R) by the last analysis;
    /// `None` when it did not condense.
    pub fn split_sizes(&self) -> Option<(usize, usize)> {
        self.plan.as_ref().filter(|_| !self.use_whole).map(|p| {
            let r = p.root_dofs.len();
            (p.pattern.n() - r, r)
        })
    }

    /// The split of `pattern` into the interiors and R, and S's pattern; `None` when no
    /// unknown is interior or R is empty (nothing would ever change but the interiors, and
    /// faer's own factorization of the whole is faster than the interiors' partial ones).
    /// The interiors' analyses are left to [`Self::finish`].
    fn build(&self, pattern: &Arc<CsrPattern>) -> Result<Option<Plan>, SolveError> {
        let n = pattern.n();
        let group: &[u32] = match &self.groups {
            Some(b) if b.len() == n => b,
            Some(b) => {
                return Err(SolveError::Other(format!(
                    "faer-condensed: {} interior groups for a matrix of {n} unknowns",
                    b.len()
                )))
            }
            None => return Ok(None),
        };
        let interior: Vec<bool> = (0..n)
            .map(|i| {
                let b = group[i];
                b != u32::MAX
                    && pattern
                        .row_cols(i)
                        .iter()
                        .all(|&c| matches!(group[c as usize], g if g == b || g == u32::MAX))
            })
            .collect();
        // R and each position in it
        let mut root_pos = vec![u32::MAX; n];
        let mut root_dofs = Vec::new();
        for i in 0..n {
            if !interior[i] {
                root_pos[i] = root_dofs.len() as u32;
                root_dofs.push(i as u32);
            }
        }
        if root_dofs.is_empty() || root_dofs.len() == n {
            return Ok(None);
        }
        // the interiors, grouped by block in the order of their first unknown
        let mut groups: Vec<Vec<u32>> = Vec::new();
        let mut group_of_block = std::collections::HashMap::new();
        for i in 0..n {
            if interior[i] {
                let g = *group_of_block.entry(group[i]).or_insert_with(|| {
                    groups.push(Vec::new());
                    groups.len() - 1
                });
                groups[g].push(i as u32);
            }
        }
        let bnds: Vec<Vec<u32>> = groups
            .iter()
            .map(|ids| {
                let mut b: Vec<u32> = ids
                    .iter()
                    .flat_map(|&i| pattern.row_cols(i as usize).iter().copied())
                    .filter(|&c| !interior[c as usize])
                    .collect();
                b.sort_unstable();
                b.dedup();
                b
            })
            .collect();
        // S's pattern: K_RR's, plus each block's clique on its boundary
        let mut rows: Vec<Vec<u32>> = root_dofs
            .iter()
            .map(|&g| {
                pattern
                    .row_cols(g as usize)
                    .iter()
                    .filter(|&&c| !interior[c as usize])
                    .map(|&c| root_pos[c as usize])
                    .collect()
            })
            .collect();
        for b in &bnds {
            for &g in b {
                let row = &mut rows[root_pos[g as usize] as usize];
                row.extend(b.iter().map(|&c| root_pos[c as usize]));
            }
        }
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        row_ptr.push(0);
        let mut col_idx = Vec::new();
        for row in &mut rows {
            row.sort_unstable();
            row.dedup();
            col_idx.extend_from_slice(row);
            row_ptr.push(col_idx.len());
        }
        drop(rows);
        let s_pattern = Arc::new(
            CsrPattern::from_parts(root_dofs.len(), row_ptr, col_idx).map_err(SolveError::Other)?,
        );
        let find = |r: u32, c: u32| -> u32 {
            s_pattern
                .find(r as usize, c as usize)
                .expect("in S's pattern by construction") as u32
        };
        let mut root_map = Vec::new();
        for (r, &g) in root_dofs.iter().enumerate() {
            let start = pattern.row_ptr()[g as usize];
            for (t, &c) in pattern.row_cols(g as usize).iter().enumerate() {
                if !interior[c as usize] {
                    root_map.push((find(r as u32, root_pos[c as usize]), start + t));
                }
            }
        }
        let pending = groups
            .into_iter()
            .zip(bnds)
            .map(|(ids, b)| {
                let bnd_root: Vec<u32> = b.iter().map(|&g| root_pos[g as usize]).collect();
                (ids, b, bnd_root)
            })
            .collect();
        let nr = root_dofs.len();
        Ok(Some(Plan {
            diag_pos: pattern.diagonal_positions(),
            pattern: pattern.clone(),
            interiors: Vec::new(),
            pending,
            root_dofs,
            root_map,
            s: CsrMatrix::zeros(s_pattern),
            s_changed: None,
            rhs_root: vec![0.0; nr],
        }))
    }

    /// The interiors' symbolic analyses and the places of their cliques in S (once the
    /// condensation is chosen).
    fn finish(plan: &mut Plan) -> Result<(), SolveError> {
        let pattern = &plan.pattern;
        let sp = &plan.s.pattern;
        let find = |r: u32, c: u32| -> u32 {
            sp.find(r as usize, c as usize)
                .expect("in S's pattern by construction") as u32
        };
        plan.interiors = std::mem::take(&mut plan.pending)
            .into_par_iter()
            .map(|(ids, b, bnd_root)| {
                let leaf = Leaf::new(pattern, ids, &b, InteriorOrder::Amd, 1)?;
                let mut scatter = Vec::with_capacity(b.len() * (b.len() + 1) / 2);
                for k in 0..b.len() {
                    for l in 0..=k {
                        scatter.push((
                            find(bnd_root[k], bnd_root[l]),
                            find(bnd_root[l], bnd_root[k]),
                        ));
                    }
                }
                Ok(Interior {
                    leaf,
                    bnd_root,
                    clique: Vec::new(),
                    scatter,
                    pivot: (f64::INFINITY, 0),
                    factored: false,
                })
            })
            .collect::<Result<_, SolveError>>()?;
        Ok(())
    }

    /// `s` ← S's values for K's values `a`, with the interiors' cliques as held.
    fn fill_s(plan: &Plan, a: &[f64], s: &mut [f64]) {
        s.fill(0.0);
        for &(p, t) in &plan.root_map {
            s[p as usize] += a[t];
        }
        for int in &plan.interiors {
            for (&(p, q), &c) in int.scatter.iter().zip(&int.clique) {
                s[p as usize] -= c;
                if q != p {
                    s[q as usize] -= c;
                }
            }
        }
    }

    /// Forward solve through the interiors: S's right-hand side in `plan.rhs_root`.
    fn forward(plan: &mut Plan, rhs: &[f64]) {
        let ups: Vec<Vec<f64>> = plan
            .interiors
            .par_iter_mut()
            .map(|int| int.leaf.forward(rhs))
            .collect();
        for (r, &g) in plan.rhs_root.iter_mut().zip(&plan.root_dofs) {
            *r = rhs[g as usize];
        }
        // b_R − Σ_b K_{R I_b} K_{I_b I_b}⁻¹ b_{I_b}: each interior passes L_BI y
        for (int, up) in plan.interiors.iter().zip(ups) {
            for (&p, u) in int.bnd_root.iter().zip(up) {
                plan.rhs_root[p as usize] -= u;
            }
        }
    }

    /// Backward solve through the interiors, S's solution in `plan.rhs_root`; the whole
    /// solution into `rhs`.
    fn backward(plan: &mut Plan, rhs: &mut [f64]) {
        for (&g, &x) in plan.root_dofs.iter().zip(&plan.rhs_root) {
            rhs[g as usize] = x;
        }
        let xr = &plan.rhs_root;
        let xs: Vec<Vec<f64>> = plan
            .interiors
            .par_iter_mut()
            .map(|int| {
                let xb: Vec<f64> = int.bnd_root.iter().map(|&p| xr[p as usize]).collect();
                int.leaf.backward(&xb)
            })
            .collect();
        for (int, x) in plan.interiors.iter().zip(xs) {
            for (&g, v) in int.leaf.half.dofs[..int.leaf.half.n_int].iter().zip(x) {
                rhs[g as usize] = v;
            }
        }
    }

    /// Whether every interior's rows hold in `a` the values of its last factorization.
    fn interiors_unchanged(plan: &Plan, a: &CsrMatrix) -> bool {
        plan.interiors
            .par_iter()
            .all(|int| int.factored && int.leaf.half.interior_unchanged(a))
    }

    /// [`LinearBackend::factorize`] of the condensed form: the interiors whose rows
    /// changed, then S.
    fn factorize_condensed(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        if self.factored && same_bits(&a.values, &self.last) {
            self.own.skipped_factorizations += 1;
            return Ok(());
        }
        self.factored = false;
        let t = Instant::now();
        let plan = self.plan.as_mut().expect("analyzed");
        let cx = Ctx {
            a,
            diag_pos: &plan.diag_pos,
            leaf_par: Par::Seq,
            front_par: Par::Seq,
        };
        // the interiors whose rows changed, in parallel; the first failed pivot in block
        // order is reported
        let redone: Vec<Result<bool, SolveError>> = plan
            .interiors
            .par_iter_mut()
            .map(|int| {
                if int.factored && int.leaf.half.interior_unchanged(a) {
                    return Ok(false);
                }
                int.factored = false;
                let (c, piv) = int.leaf.refactorize(cx)?;
                let nb = int.bnd_root.len();
                int.clique.clear();
                for k in 0..nb {
                    for l in 0..=k {
                        int.clique.push(c[(k, l)]);
                    }
                }
                int.pivot = piv;
                int.factored = true;
                Ok(true)
            })
            .collect();
        let redone = redone.into_iter().collect::<Result<Vec<bool>, _>>()?;
        self.interior_factorizations += redone.iter().filter(|&&r| r).count();
        let mut best = (f64::INFINITY, 0usize);
        for &(r, i) in plan.interiors.iter().map(|int| &int.pivot) {
            if r < best.0 || r.is_nan() && !best.0.is_nan() {
                best = (r, i);
            }
        }
        let mut values = std::mem::take(&mut plan.s.values);
        Self::fill_s(plan, &a.values, &mut values);
        plan.s.values = values;
        let root = self.root.factorize(&plan.s);
        self.own.numeric_factorizations += 1;
        self.own.numeric_seconds += t.elapsed().as_secs_f64();
        root.map_err(|e| self.map_root_error(e))?;
        let rs = self.root.stats();
        // the smallest pivot ratio of the whole factorization: over the interiors (each
        // from its last factorization) and S
        let (rr, ri) = (rs.min_pivot_ratio, rs.min_pivot_index);
        if rr < best.0 || rr.is_nan() {
            best = (rr, self.root_index(ri));
        }
        self.own.min_pivot_ratio = best.0;
        self.own.min_pivot_index = best.1;
        self.last.clear();
        self.last.extend_from_slice(&a.values);
        self.factored = true;
        Ok(())
    }

    /// Switches to the condensed form: the interiors' analyses, and the whole matrix's
    /// analysis dropped.
    fn condense(&mut self) -> Result<(), SolveError> {
        let t = Instant::now();
        let plan = self.plan.as_mut().expect("a condensation planned");
        Self::finish(plan)?;
        self.root.analyze(&plan.s.pattern)?;
        self.own.factor_nnz = self.root.stats().factor_nnz
            + plan
                .interiors
                .iter()
                .map(|i| i.leaf.partial_values())
                .sum::<usize>();
        self.own.factor_flops = self.root.stats().factor_flops
            + plan.interiors.iter().map(|i| i.leaf.flops()).sum::<f64>();
        self.retire_whole();
        self.use_whole = false;
        self.factored = false;
        self.own.symbolic_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Drops the whole matrix's analysis (its factor's memory) when the condensation is
    /// chosen, its counters kept in this backend's own.
    fn retire_whole(&mut self) {
        let w = self.whole.stats();
        let o = &mut self.own;
        o.numeric_factorizations += w.numeric_factorizations;
        o.skipped_factorizations += w.skipped_factorizations;
        o.solves += w.solves;
        o.numeric_seconds += w.numeric_seconds;
        o.solve_seconds += w.solve_seconds;
        o.changed_solves += w.changed_solves;
        o.max_changed_rank = o.max_changed_rank.max(w.max_changed_rank);
        o.changed_seconds += w.changed_seconds;
        self.whole = FaerCholesky::new().with_threads(self.threads);
    }

    /// `stats` ← this backend's own counters plus the whole matrix's backend's; the
    /// fields about the last analysis, factorization or solve from the mode in use.
    fn merge_stats(&mut self) {
        let (o, w) = (&self.own, self.whole.stats());
        let last = if self.use_whole { w } else { o };
        self.stats = SolverStats {
            symbolic_factorizations: o.symbolic_factorizations,
            numeric_factorizations: o.numeric_factorizations + w.numeric_factorizations,
            skipped_factorizations: o.skipped_factorizations + w.skipped_factorizations,
            solves: o.solves + w.solves,
            iterations: 0,
            last_iterations: 0,
            last_true_residual: f64::NAN,
            symbolic_seconds: o.symbolic_seconds,
            ordering_seconds: 0.0,
            numeric_seconds: o.numeric_seconds + w.numeric_seconds,
            solve_seconds: o.solve_seconds + w.solve_seconds,
            factor_nnz: last.factor_nnz,
            min_pivot_ratio: last.min_pivot_ratio,
            min_pivot_index: last.min_pivot_index,
            factor_flops: last.factor_flops,
            memory_bytes: 0,
            changed_solves: o.changed_solves + w.changed_solves,
            last_changed_rank: last.last_changed_rank,
            max_changed_rank: o.max_changed_rank.max(w.max_changed_rank),
            changed_seconds: o.changed_seconds + w.changed_seconds,
        };
    }

    fn root_index(&self, p: usize) -> usize {
        self.plan
            .as_ref()
            .and_then(|pl| pl.root_dofs.get(p))
            .map_or(p, |&g| g as usize)
    }

    fn map_root_error(&self, e: SolveError) -> SolveError {
        match e {
            SolveError::NotPositiveDefinite { index, pivot } => SolveError::NotPositiveDefinite {
                index: self.root_index(index),
                pivot,
            },
            SolveError::Singular { index } => SolveError::Singular {
                index: self.root_index(index),
            },
            other => other,
        }
    }
}

impl LinearBackend for FaerCholeskyCondensed {
    fn name(&self) -> &'static str {
        "faer-condensed"
    }

    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        let current = match &self.plan {
            Some(p) => Some(p.pattern.id()),
            None => self.whole.core().analysis.as_ref().map(|a| a.pattern.id()),
        };
        if current == Some(pattern.id()) {
            return Ok(());
        }
        self.plan = None;
        self.use_whole = true;
        self.factored = false;
        self.whole_factorizations = 0;
        self.decision = None;
        let t = Instant::now();
        self.whole.analyze(pattern)?;
        let w = self.whole.stats().factor_flops;
        if let Some(plan) = self.build(pattern)? {
            let root_flops = cholesky_flops(&plan.s.pattern)?;
            let pays =
                self.forced || w >= CONDENSE_MIN_FLOPS && root_flops <= CONDENSE_MAX_SHARE * w;
            self.decision = Some(Decision {
                interior: plan.pattern.n() - plan.root_dofs.len(),
                kept: plan.root_dofs.len(),
                blocks: plan.pending.len(),
                condensed_flops: root_flops,
                whole_flops: w,
                pays,
            });
            if pays {
                self.plan = Some(plan);
                if self.forced {
                    self.condense()?;
                }
            }
        }
        self.own.symbolic_factorizations += 1;
        self.own.symbolic_seconds += t.elapsed().as_secs_f64();
        self.merge_stats();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        check_values(a)?;
        self.analyze(&a.pattern)?;
        // the second factorization of other values on this pattern: the model iterates
        // (contacts change), and the condensation chosen at the analysis takes over (as
        // at a first solve with a changed matrix)
        if self.use_whole
            && self.plan.is_some()
            && self.whole_factorizations > 0
            && self
                .whole
                .factorized_values()
                .is_none_or(|v| !same_bits(v, &a.values))
        {
            self.condense()?;
        }
        let out = match self.use_whole {
            true => {
                let out = self.whole.factorize(a);
                self.whole_factorizations += 1;
                out
            }
            false => self.factorize_condensed(a),
        };
        self.merge_stats();
        out
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        if self.use_whole {
            let out = self.whole.solve(rhs);
            self.merge_stats();
            return out;
        }
        if !self.factored {
            return Err(SolveError::Other("solve before a factorization".into()));
        }
        let t = Instant::now();
        let plan = self.plan.as_mut().expect("factored");
        if rhs.len() != plan.pattern.n() {
            return Err(SolveError::Other(
                "right-hand side of the wrong length".into(),
            ));
        }
        Self::forward(plan, rhs);
        self.root.solve(&mut plan.rhs_root)?;
        Self::backward(plan, rhs);
        self.own.solves += 1;
        self.own.solve_seconds += t.elapsed().as_secs_f64();
        self.merge_stats();
        Ok(())
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }

    /// A change confined to R (contacts' stiffness): S changes by the same entries, and
    /// S's held factorization is corrected for them ([`FaerCholesky`]'s low-rank
    /// correction); a change inside an interior is refused.
    fn solve_changed(&mut self, a: &CsrMatrix, rhs: &mut [f64]) -> Result<(), SolveError> {
        if self.use_whole && self.plan.is_some() {
            // the model iterates: the condensed form of the held matrix takes over, and
            // the correction is made to it
            if let Some(held) = self.whole.factorized_values() {
                let held = CsrMatrix {
                    pattern: self.plan.as_ref().expect("checked").pattern.clone(),
                    values: held.to_vec(),
                };
                self.condense()?;
                let out = self.factorize_condensed(&held);
                self.merge_stats();
                out?;
            }
        }
        if self.use_whole {
            let out = self.whole.solve_changed(a, rhs);
            self.merge_stats();
            return out;
        }
        let t = Instant::now();
        let out = (|| {
            if !self.factored {
                return Err(SolveError::Other("no factorization held".into()));
            }
            check_values(a)?;
            let plan = self.plan.as_mut().expect("factored");
            if a.pattern.id() != plan.pattern.id() || rhs.len() != plan.pattern.n() {
                return Err(SolveError::Other("a matrix on another pattern".into()));
            }
            if !Self::interiors_unchanged(plan, a) {
                return Err(SolveError::Other(
                    "faer-condensed: a block's interior changed (refactorize)".into(),
                ));
            }
            let mut s_new = plan
                .s_changed
                .take()
                .unwrap_or_else(|| CsrMatrix::zeros(plan.s.pattern.clone()));
            Self::fill_s(plan, &a.values, &mut s_new.values);
            Self::forward(plan, rhs);
            let out = self.root.solve_changed(&s_new, &mut plan.rhs_root);
            plan.s_changed = Some(s_new);
            out?;
            Self::backward(plan, rhs);
            Ok(())
        })();
        if out.is_ok() {
            let rank = self.root.stats().last_changed_rank;
            self.own.changed_solves += 1;
            self.own.last_changed_rank = rank;
            self.own.max_changed_rank = self.own.max_changed_rank.max(rank);
        }
        self.own.changed_seconds += t.elapsed().as_secs_f64();
        self.merge_stats();
        out
    }

    fn factorized_values(&self) -> Option<&[f64]> {
        match self.use_whole {
            true => self.whole.factorized_values(),
            false => self.factored.then_some(&self.last[..]),
        }
    }

    fn set_failed_pivot_value(&mut self, on: bool) {
        self.whole.set_failed_pivot_value(on);
        self.root.set_failed_pivot_value(on);
    }

    fn set_interiors(&mut self, group: &[u32]) -> Result<(), SolveError> {
        self.groups = Some(group.to_vec());
        self.plan = None;
        self.use_whole = false;
        self.factored = false;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two or more "blocks" of a 2D grid each (unknowns row by row), coupled by springs
    /// between their edge unknowns: K = Σ springs k (eᵢ − eⱼ)(eᵢ − eⱼ)ᵀ + a small shift.
    fn blocks(nb: usize, nx: usize, ny: usize, contact_k: f64) -> (CsrMatrix, Vec<u32>) {
        let per = nx * ny;
        let n = nb * per;
        let mut springs: Vec<(usize, usize, f64)> = Vec::new();
        for b in 0..nb {
            let id = |i: usize, j: usize| b * per + j * nx + i;
            for j in 0..ny {
                for i in 0..nx {
                    if i + 1 < nx {
                        springs.push((id(i, j), id(i + 1, j), 1.0 + 0.1 * (i + j) as f64));
                    }
                    if j + 1 < ny {
                        springs.push((id(i, j), id(i, j + 1), 2.0 + 0.05 * i as f64));
                    }
                }
            }
            if b + 1 < nb {
                // block b's right edge to block b + 1's left edge
                for j in 0..ny {
                    springs.push((id(nx - 1, j), (b + 1) * per + j * nx, contact_k));
                }
            }
        }
        let mut entries: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        for &(i, j, _) in &springs {
            entries.push((i, j));
            entries.push((j, i));
        }
        let pattern = Arc::new(CsrPattern::from_entries(n, entries));
        let mut a = CsrMatrix::zeros(pattern);
        for i in 0..n {
            a.add(i, i, 1e-3);
        }
        for &(i, j, k) in &springs {
            add_spring(&mut a, i, j, k);
        }
        let group = (0..n).map(|i| (i / per) as u32).collect();
        (a, group)
    }

    /// a += k (eᵢ − eⱼ)(eᵢ − eⱼ)ᵀ: a spring between unknowns i and j.
    fn add_spring(a: &mut CsrMatrix, i: usize, j: usize, k: f64) {
        a.add(i, i, k);
        a.add(j, j, k);
        a.add(i, j, -k);
        a.add(j, i, -k);
    }

    fn load(n: usize) -> Vec<f64> {
        (0..n).map(|i| ((i * 7 % 11) as f64 - 5.0) * 0.3).collect()
    }

    fn reference(a: &CsrMatrix, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        let mut f = FaerCholesky::new();
        f.factorize(a).unwrap();
        f.solve(&mut x).unwrap();
        x
    }

    /// The backend with the condensation forced, given the interiors `group` and
    /// factorized on `a`.
    fn factorized_condensed(a: &CsrMatrix, group: &[u32]) -> FaerCholeskyCondensed {
        let mut c = FaerCholeskyCondensed::new().forced(true);
        c.set_interiors(group).unwrap();
        c.factorize(a).unwrap();
        c
    }

    fn close(x: &[f64], y: &[f64]) -> f64 {
        crate::backend::max_relative_difference(x, y)
    }

    #[test]
    fn condensed_solve_is_the_whole_matrix_solve() {
        let (a, group) = blocks(3, 7, 5, 0.5);
        let n = a.n();
        let mut c = factorized_condensed(&a, &group);
        // interior: every unknown but the coupled edges (5 per edge: 2 edges × 5 + 2 × 5)
        let (int, root) = c.split_sizes().unwrap();
        assert_eq!((int, root), (n - 20, 20));
        let b = load(n);
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        assert!(
            close(&x, &reference(&a, &b)) < 1e-12,
            "{}",
            close(&x, &reference(&a, &b))
        );
        assert!(c.stats().min_pivot_ratio > 0.0 && c.stats().min_pivot_ratio < 1.0);
    }

    #[test]
    fn a_contact_change_refactorizes_the_boundary_only_or_corrects_it() {
        let (a, group) = blocks(4, 6, 6, 0.5);
        let n = a.n();
        let mut c = factorized_condensed(&a, &group);
        // stiffen one contact spring between blocks 1 and 2 (unknowns 36 + 5 and 72)
        let (i, j) = (36 + 5, 72);
        let mut a2 = a.clone();
        add_spring(&mut a2, i, j, 3.0);
        let b = load(n);
        let want = reference(&a2, &b);
        // a low-rank correction of the held factor of S
        let mut x = b.clone();
        c.solve_changed(&a2, &mut x).unwrap();
        assert!(close(&x, &want) < 1e-11, "corrected: {}", close(&x, &want));
        assert_eq!(c.stats().changed_solves, 1);
        // a refactorization that keeps every interior's factor
        let leaves_before: Vec<f64> = c
            .plan
            .as_ref()
            .unwrap()
            .interiors
            .iter()
            .map(|i| i.clique[0])
            .collect();
        c.factorize(&a2).unwrap();
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        assert!(
            close(&x, &want) < 1e-12,
            "refactorized: {}",
            close(&x, &want)
        );
        let leaves_after: Vec<f64> = c
            .plan
            .as_ref()
            .unwrap()
            .interiors
            .iter()
            .map(|i| i.clique[0])
            .collect();
        assert_eq!(leaves_before, leaves_after);
        // a change inside block 0's interior is refused by solve_changed, then refactorized
        let mut a3 = a2.clone();
        a3.add(7, 7, 1.0);
        let mut x = b.clone();
        assert!(c.solve_changed(&a3, &mut x).is_err());
        c.factorize(&a3).unwrap();
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        assert!(close(&x, &reference(&a3, &b)) < 1e-12);
    }

    #[test]
    fn without_blocks_it_is_a_plain_cholesky() {
        let (a, _) = blocks(2, 4, 3, 1.0);
        let mut c = FaerCholeskyCondensed::new().forced(true);
        c.factorize(&a).unwrap();
        assert!(!c.is_condensed());
        assert_eq!(c.split_sizes(), None);
        let b = load(a.n());
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        assert!(close(&x, &reference(&a, &b)) < 1e-13);
    }

    #[test]
    fn an_indefinite_interior_is_reported_at_its_unknown() {
        let (mut a, group) = blocks(2, 4, 4, 1.0);
        // unknown 5 is inside block 0
        let d = a.get(5, 5);
        a.add(5, 5, -2.0 * d);
        let mut c = FaerCholeskyCondensed::new().forced(true);
        c.set_interiors(&group).unwrap();
        match c.factorize(&a) {
            Err(SolveError::NotPositiveDefinite { index, .. }) => assert!(index < 16, "{index}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_condensation_takes_over_at_the_second_factorization_where_it_pays() {
        // three 50 × 50 grids joined edge to edge: S is the 200 unknowns of the joined
        // edges
        let (a, group) = blocks(3, 50, 50, 0.5);
        let mut c = FaerCholeskyCondensed::new();
        c.set_interiors(&group).unwrap();
        let b = load(a.n());
        c.factorize(&a).unwrap();
        assert!(
            !c.is_condensed(),
            "the first factorization is the whole matrix's"
        );
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        let mut plain = FaerCholesky::new();
        plain.factorize(&a).unwrap();
        let mut y = b.clone();
        plain.solve(&mut y).unwrap();
        assert_eq!(x, y, "bit for bit faer-cholesky before the switch");
        // a contact spring changes: the second factorization is condensed
        let mut a2 = a.clone();
        add_spring(&mut a2, 49, 2500, 1.0);
        c.factorize(&a2).unwrap();
        assert!(c.is_condensed());
        assert_eq!(c.split_sizes(), Some((a.n() - 200, 200)));
        let mut x = b.clone();
        c.solve(&mut x).unwrap();
        assert!(close(&x, &reference(&a2, &b)) < 1e-12);
        assert_eq!(c.stats().numeric_factorizations, 2);
        assert_eq!(c.stats().symbolic_factorizations, 1);
    }

    #[test]
    fn a_wall_of_small_blocks_with_contacts_all_round_is_not_condensed() {
        // 60 blocks of 6 × 40 in a row, joined on every row of their edges: S holds a
        // third of the unknowns (4,720 of 14,400) and the cliques of the blocks' edges
        // make its factorization dearer than the whole matrix's (6.5·10⁶ multiply-adds
        // against 4.7·10⁶)
        let (a, group) = blocks(60, 6, 40, 0.5);
        let mut c = FaerCholeskyCondensed::new();
        c.set_interiors(&group).unwrap();
        for k in 0..3 {
            let mut ak = a.clone();
            ak.add(3, 3, k as f64);
            c.factorize(&ak).unwrap();
        }
        assert!(!c.is_condensed());
    }
}
