//! [`FaerCholeskySubstructured`] (`faer-substructured`): sparse Cholesky by nested
//! substructuring, the subdomains factorized at the same time on the rayon pool, and
//! only what depends on changed values refactorized.
//!
//! faer's supernodal factorization parallelises only inside dense supernodes, which are
//! small on 2D meshes (`docs/solvers.md`). Here the unknowns are split into k parts by a
//! partition handed over with [`LinearBackend::set_partition`] (dfem gives one of whole
//! blocks, so that every cut runs along joints, numbered by recursive bisection) or else
//! by METIS recursive bisection of the node graph. Parts `lo..hi` are split at
//! mid = lo + (hi − lo) / 2 into `lo..mid` and `mid..hi`, recursively, which makes a
//! binary tree (Saad, *Iterative methods for sparse linear systems*, 2nd ed., §14.2,
//! "Schur complement approaches"; George's nested dissection, with subdomains as leaves):
//!
//! * **interfaces**: at a tree node, among the unknowns of its parts not already on an
//!   ancestor's interface, the unknowns of one side coupled to the other side — the side
//!   with fewer of them, the right one on a tie — form the node's interface Γ. Every
//!   coupling between the two sides then has an end in Γ. Across a joint of node-to-node
//!   contacts this is the joint nodes of one block: half of what a two-sided interface
//!   would take. With k = 2 there is one interface, Γ of the root;
//! * **subdomains** (leaves): the principal sub-matrix Kᵢ = A\[Iᵢ ∪ Bᵢ, Iᵢ ∪ Bᵢ\] of the
//!   interior Iᵢ (the rest of part i) and the interface unknowns Bᵢ coupled to it, ordered
//!   with Iᵢ first (METIS nested dissection of Iᵢ by default, or AMD) and Bᵢ last,
//!   one rayon task per subdomain: a partial factorization on faer's symbolic structure
//!   (`crate::partial`, private) computes the interior columns \[Lᵢ,II; Lᵢ,BI\] of Kᵢ's
//!   Cholesky factor and stops before Bᵢ, leaving what the subdomain subtracts from
//!   the interface, Cᵢ = A_BᵢIᵢ A_IᵢIᵢ⁻¹ A_IᵢBᵢ = Lᵢ,BI Lᵢ,BIᵀ (dense, |Bᵢ| × |Bᵢ|) —
//!   no Cholesky of Kᵢ's trailing block;
//! * **interface fronts** (inner nodes): the dense matrix M on (Γ, B) — B the ancestors'
//!   interface unknowns coupled inside the node — holds A_ΓΓ and A_BΓ minus the children's
//!   Schur complements (in child order). Its partial Cholesky factorization (faer's dense
//!   kernels on `Par::rayon(t)`, t = 2 by default: a fixed task split whatever the pool)
//!   L_ΓΓ = chol(M_ΓΓ), X = M_BΓ L_ΓΓ⁻ᵀ leaves the node's Schur complement on B,
//!   C = −M_BB + X Xᵀ, for its parent. At the root B is empty: L_ΓΓ factors the last
//!   interface system;
//! * **solve**: forward through the tree (leaves: yᵢ = Lᵢ,II⁻¹ bᵢ, passing Lᵢ,BI yᵢ up;
//!   fronts: y_Γ = L_ΓΓ⁻¹(b_Γ − what the children passed), passing X y_Γ up), then backward
//!   from the root (x_Γ = L_ΓΓ⁻ᵀ(y_Γ − Xᵀ x_B); leaves x_Iᵢ = Lᵢ,IIᵀ⁻¹(yᵢ − Lᵢ,BIᵀ x_B)),
//!   the two subtrees of a node on two rayon tasks.
//!
//! Together these are the Cholesky factorization of A in the order leaves' interiors,
//! then the interfaces from the deepest to the root. **Reuse**: a subdomain whose
//! interior rows (A_IᵢIᵢ, A_IᵢBᵢ) hold the same values, bit for bit, as at its last
//! factorization keeps its factor and Cᵢ, which depend on nothing else; a front is redone
//! only when a child or its own entries of A changed. A secant iteration in which the
//! contacts of one subdomain changed state costs that subdomain plus the fronts on its
//! path to the root. The kernel knows nothing of contacts: the test is on the values.
//!
//! Every sparse factorization and solve is sequential inside its task (or splits faer's
//! kernels into a fixed number of tasks, [`FaerCholeskySubstructured::with_subdomain_threads`])
//! and every sum over children is in child order, so the results are bit-identical for
//! any number of threads. `min_pivot_ratio` is that of the global factorization in the
//! order above: the smallest L_jj² / a_jj over the interiors and the interfaces. A
//! non-positive pivot is reported at its unknown (`pivot` NaN).

use crate::backend::{same_bits, LinearBackend, SolveError, SolverStats};
use crate::csr::{CsrMatrix, CsrPattern};
use crate::ordering::{metis_bisection_partition, FillOrdering};
use crate::partial::{col_mut, PartialLlt};
use crate::split::{Half, InteriorOrder};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::{Accum, Mat, MatRef, Par};
use std::sync::Arc;
use std::time::Instant;

/// Counters and timers of [`FaerCholeskySubstructured`], beyond [`SolverStats`];
/// cumulative since creation except the fields about the last analysis or factorization.
#[derive(Debug, Clone, Default)]
pub struct SubstructureStats {
    /// Subdomains (leaves with interior unknowns) of the last analysis.
    pub subdomains: usize,
    /// Interface unknowns of the last analysis (all fronts).
    pub interface_size: usize,
    /// Unknowns of each subdomain's matrix Kᵢ (interior + its interface), last analysis.
    pub subdomain_sizes: Vec<usize>,
    /// |Bᵢ| of each subdomain, last analysis.
    pub subdomain_interface_sizes: Vec<usize>,
    /// (|Γ|, |B|) of each interface front, depth first (root last), last analysis.
    pub front_sizes: Vec<(usize, usize)>,
    /// Multiply-adds of each subdomain's refactorization (the partial factorization of Kᵢ,
    /// its interior columns with the product L_BI L_BIᵀ), last analysis.
    pub subdomain_flops: Vec<f64>,
    /// Multiply-adds of each front (partial Cholesky: |Γ|³/6 + |B| |Γ|²/2 + |B|² |Γ|/2),
    /// in the order of `front_sizes`.
    pub front_flops: Vec<f64>,
    /// Multiply-adds on the longest chain of work that cannot run in parallel (a leaf and
    /// the fronts above it, the more expensive subtree at each front): with as many cores
    /// as subdomains, a factorization takes at least this much work's time.
    pub critical_path_flops: f64,
    /// Numeric factorizations of subdomains (each subdomain counts once per factorization).
    pub subdomain_factorizations: usize,
    /// Subdomains kept (factor and Schur complement reused) at a factorization.
    pub subdomain_reuses: usize,
    /// The subdomains (depth-first leaf order) refactorized by the last numeric
    /// factorization.
    pub last_refactorized: Vec<usize>,
    /// Fronts recomputed by the last numeric factorization.
    pub last_fronts: usize,
    /// Multiply-adds of what the last numeric factorization recomputed (subdomains and
    /// fronts), the load-independent measure of its work.
    pub last_flops: f64,
    /// The longest chain of the last numeric factorization in time, s: a redone leaf
    /// counts the CPU time of its thread (sparse factorization and Schur complement;
    /// `CLOCK_THREAD_CPUTIME_ID`, NaN off Linux), a kept one nothing, a redone front its
    /// wall time (dense kernels on `Par::rayon(t)`), the slower subtree at each front.
    /// What that factorization takes with a free core per subdomain: on a shared machine,
    /// where the wall time includes waits for a core, the estimate that does not depend
    /// on the other jobs.
    pub last_critical_path_seconds: f64,
    /// Sparse factorizations of the subdomains, summed over subdomains (wall time inside
    /// each task), s.
    pub subdomain_factor_seconds: f64,
    /// Schur complements of the subdomains (L_BI L_BIᵀ brought to Bᵢ order; its products
    /// are in the partial factorization), summed, s.
    pub schur_seconds: f64,
    /// Interface fronts: assembly and dense partial factorization, summed over fronts, s.
    pub interface_seconds: f64,
}

/// A subdomain: Kᵢ and its factor's columns of the interior (also a block's interior in
/// [`crate::condensed`]).
pub(crate) struct Leaf {
    pub(crate) half: Half,
    /// The partial factorization of Kᵢ (interior columns; values in the half's factor).
    partial: PartialLlt,
    /// Local unknown of Kᵢ → its position in the factor's order.
    perm_inv: Vec<u32>,
    /// Scratch vector of the solves (factor order); between the forward and the backward
    /// solve it holds the interior's y.
    v: Vec<f64>,
    /// Interior solution of the last backward solve (interior order).
    x: Vec<f64>,
    /// Wall time (inside its task) of the last refactorization, s: sparse factorization,
    /// Schur complement; negative once counted in the statistics.
    times: (f64, f64),
    /// CPU time of its thread during the last refactorization (both parts), s.
    cpu: f64,
}

/// An interface front.
struct Front {
    /// Its interface unknowns Γ (global, increasing); F = Γ then B.
    own: Vec<u32>,
    children: Vec<Node>,
    /// Position in F of each child's boundary unknowns.
    child_pos: Vec<Vec<u32>>,
    /// `(r, c, p)`, r ≥ c in F: entry p of A goes to M\[r, c\] (A_ΓΓ and A_BΓ).
    a_map: Vec<(u32, u32, usize)>,
    /// The values of `a_map` at the last factorization.
    last_a: Vec<f64>,
    /// After factorization: L_ΓΓ (leading block) and X (below it), lower.
    m: Mat<f64>,
    /// y_Γ of the last forward solve, then x_Γ of the backward solve.
    y: Vec<f64>,
    /// Wall time (inside its task) of the last recomputation, s; negative once counted in
    /// the statistics.
    time: f64,
}

enum Kind {
    Leaf(Box<Leaf>),
    Front(Box<Front>),
}

/// A tree node: what it passes to its parent is its Schur complement on `bnd`.
struct Node {
    /// The ancestors' interface unknowns coupled inside the node (global, increasing).
    bnd: Vec<u32>,
    /// Its Schur complement C on `bnd` (lower triangle).
    c: Mat<f64>,
    factored: bool,
    /// Smallest pivot ratio inside the node and its unknown.
    min_pivot: (f64, usize),
    kind: Kind,
}

fn ratio_min(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    if b.0 < a.0 || b.0.is_nan() && !a.0.is_nan() {
        b
    } else {
        a
    }
}

/// The tasks of faer's dense kernels for `t` threads (1 = sequential).
fn par_of(t: usize) -> Par {
    if t <= 1 {
        Par::Seq
    } else {
        Par::rayon(t)
    }
}

/// What a factorization needs besides the matrix.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub(crate) a: &'a CsrMatrix,
    pub(crate) diag_pos: &'a [usize],
    pub(crate) leaf_par: Par,
    pub(crate) front_par: Par,
}

impl Node {
    /// Refactorizes what changed below and in this node; `Ok(true)` if anything did.
    fn refresh(&mut self, cx: Ctx<'_>) -> Result<bool, SolveError> {
        let changed = match &mut self.kind {
            Kind::Leaf(leaf) => {
                if self.factored && leaf.half.interior_unchanged(cx.a) {
                    return Ok(false);
                }
                self.factored = false;
                let (c, pivots) = leaf.refactorize(cx)?;
                self.c = c;
                self.min_pivot = pivots;
                true
            }
            Kind::Front(front) => {
                let children = match front.children.as_mut_slice() {
                    [a, b] => {
                        let (ra, rb) = rayon::join(|| a.refresh(cx), || b.refresh(cx));
                        ra? | rb?
                    }
                    list => {
                        let mut any = false;
                        for ch in list {
                            any |= ch.refresh(cx)?;
                        }
                        any
                    }
                };
                let own_changed = front
                    .a_map
                    .iter()
                    .zip(&front.last_a)
                    .any(|(&(_, _, p), v)| cx.a.values[p].to_bits() != v.to_bits());
                if self.factored && !children && !own_changed {
                    return Ok(false);
                }
                self.factored = false;
                let (c, pivots) = front.refactorize(self.bnd.len(), cx)?;
                self.c = c;
                self.min_pivot = front
                    .children
                    .iter()
                    .map(|ch| ch.min_pivot)
                    .fold(pivots, ratio_min);
                true
            }
        };
        self.factored = true;
        Ok(changed)
    }

    /// Forward solve of the subtree with the global right-hand side `b`; returns what it
    /// passes up on `bnd` (the term to subtract from the parent's right-hand side).
    fn forward(&mut self, b: &[f64]) -> Vec<f64> {
        match &mut self.kind {
            Kind::Leaf(leaf) => leaf.forward(b),
            Kind::Front(front) => {
                let ws: Vec<Vec<f64>> = match front.children.as_mut_slice() {
                    [x, y] => {
                        let (wa, wb) = rayon::join(|| x.forward(b), || y.forward(b));
                        vec![wa, wb]
                    }
                    list => list.iter_mut().map(|ch| ch.forward(b)).collect(),
                };
                let o = front.own.len();
                let mut r: Vec<f64> = front.own.iter().map(|&i| b[i as usize]).collect();
                let mut up = vec![0.0; self.bnd.len()];
                for (w, pos) in ws.iter().zip(&front.child_pos) {
                    for (&p, v) in pos.iter().zip(w) {
                        let p = p as usize;
                        if p < o {
                            r[p] -= v;
                        } else {
                            up[p - o] += v;
                        }
                    }
                }
                let (l, x) = front.m.as_ref().split_at_row(o);
                let l = l.subcols(0, o);
                solve_lower_triangular_in_place(l, col_mut(&mut r), Par::Seq);
                // up += X y
                for (j, &yj) in r.iter().enumerate() {
                    let col = x.col(j);
                    for (i, u) in up.iter_mut().enumerate() {
                        *u += col[i] * yj;
                    }
                }
                front.y = r;
                up
            }
        }
    }

    /// Backward solve of the subtree given the solution on `bnd`; the results stay in
    /// the nodes (see [`Node::scatter`]).
    fn backward(&mut self, xb: &[f64]) {
        match &mut self.kind {
            Kind::Leaf(leaf) => leaf.x = leaf.backward(xb),
            Kind::Front(front) => {
                let o = front.own.len();
                let (l, x) = front.m.as_ref().split_at_row(o);
                let l = l.subcols(0, o);
                // y − Xᵀ x_B, then L_ΓΓᵀ x_Γ = that
                for (j, yj) in front.y.iter_mut().enumerate() {
                    let col = x.col(j);
                    let mut s = 0.0;
                    for (i, &v) in xb.iter().enumerate() {
                        s += col[i] * v;
                    }
                    *yj -= s;
                }
                solve_upper_triangular_in_place(l.transpose(), col_mut(&mut front.y), Par::Seq);
                let full = |p: u32| {
                    let p = p as usize;
                    if p < o {
                        front.y[p]
                    } else {
                        xb[p - o]
                    }
                };
                let xs: Vec<Vec<f64>> = front
                    .child_pos
                    .iter()
                    .map(|pos| pos.iter().map(|&p| full(p)).collect())
                    .collect();
                match front.children.as_mut_slice() {
                    [a, b] => {
                        rayon::join(|| a.backward(&xs[0]), || b.backward(&xs[1]));
                    }
                    list => {
                        for (ch, x) in list.iter_mut().zip(&xs) {
                            ch.backward(x);
                        }
                    }
                }
            }
        }
    }

    /// Writes the solution held in the subtree into `x` (global numbering).
    fn scatter(&self, x: &mut [f64]) {
        match &self.kind {
            Kind::Leaf(leaf) => {
                for (&i, &v) in leaf.half.dofs[..leaf.half.n_int].iter().zip(&leaf.x) {
                    x[i as usize] = v;
                }
            }
            Kind::Front(front) => {
                for (&i, &v) in front.own.iter().zip(&front.y) {
                    x[i as usize] = v;
                }
                for ch in &front.children {
                    ch.scatter(x);
                }
            }
        }
    }

    /// Visits the leaves (depth first) and fronts (after their children).
    fn visit<'a>(
        &'a self,
        leaf: &mut impl FnMut(&'a Leaf),
        front: &mut impl FnMut(&'a Front, &'a [u32]),
    ) {
        match &self.kind {
            Kind::Leaf(l) => leaf(l),
            Kind::Front(f) => {
                for ch in &f.children {
                    ch.visit(leaf, front);
                }
                front(f, &self.bnd);
            }
        }
    }

    /// The longest chain of `cost` through the tree: a leaf's cost, or a front's own plus
    /// the most expensive of its children's chains (they run in parallel).
    fn critical_path(&self, cost: &impl Fn(&Kind, &[u32]) -> f64) -> f64 {
        let below = match &self.kind {
            Kind::Leaf(_) => 0.0,
            Kind::Front(f) => f
                .children
                .iter()
                .map(|ch| ch.critical_path(cost))
                .fold(0.0, f64::max),
        };
        below + cost(&self.kind, &self.bnd)
    }

    /// See [`SubstructureStats::last_critical_path_seconds`]; before the times are
    /// marked counted.
    fn last_critical_path_seconds(&self) -> f64 {
        self.critical_path(&|kind, _| match kind {
            Kind::Leaf(l) if l.times.0 >= 0.0 => l.cpu,
            Kind::Leaf(_) => 0.0,
            Kind::Front(f) => f.time.max(0.0),
        })
    }

    /// See [`SubstructureStats::critical_path_flops`].
    fn critical_path_flops(&self) -> f64 {
        self.critical_path(&|kind, bnd| match kind {
            Kind::Leaf(l) => l.flops(),
            Kind::Front(f) => front_flops(f.own.len(), bnd.len()),
        })
    }

    fn memory_bytes(&self) -> usize {
        let own = 8 * self.c.nrows() * self.c.ncols();
        own + match &self.kind {
            Kind::Leaf(l) => 8 * (l.partial.n_values() + l.half.values.values.len()),
            Kind::Front(f) => {
                8 * f.m.nrows() * f.m.ncols()
                    + f.children.iter().map(Node::memory_bytes).sum::<usize>()
            }
        }
    }
}

/// Multiply-adds of a front's partial Cholesky with |Γ| = o, |B| = b: the Cholesky of
/// M_ΓΓ (o³/6), X = M_BΓ L⁻ᵀ (b o²/2) and the lower half of X Xᵀ (b² o/2).
fn front_flops(o: usize, b: usize) -> f64 {
    let (o, b) = (o as f64, b as f64);
    o * o * o / 6.0 + b * o * o / 2.0 + b * b * o / 2.0
}

impl Leaf {
    /// The subdomain of the unknowns `interior` (global, increasing) and the interface
    /// unknowns `bnd` they couple to (global, increasing): its sub-matrix's symbolic
    /// analysis (`order` for the interior, `bnd` last) and the plan of its partial
    /// factorization.
    pub(crate) fn new(
        pattern: &Arc<CsrPattern>,
        interior: Vec<u32>,
        bnd: &[u32],
        order: InteriorOrder<'_>,
        threads: usize,
    ) -> Result<Self, SolveError> {
        let half = Half::new(pattern, interior, bnd, order, threads)?;
        let an = half.core.analysis.as_ref().expect("analyzed");
        let nl = half.dofs.len();
        let perm_inv: Vec<u32> = match an.symbolic.perm() {
            Some(p) => p.arrays().1.to_vec(),
            None => (0..nl as u32).collect(),
        };
        let SymbolicCholeskyRaw::Supernodal(sym) = an.symbolic.raw() else {
            return Err(SolveError::Other("substructuring: not supernodal".into()));
        };
        let kp = &half.values.pattern;
        let entries = (0..nl).flat_map(|r| {
            let start = kp.row_ptr()[r];
            let pi = &perm_inv;
            kp.row_cols(r)
                .iter()
                .enumerate()
                .map(move |(t, &c)| (pi[r] as usize, pi[c as usize] as usize, start + t))
        });
        let partial = PartialLlt::new(sym, half.n_int, entries)?;
        Ok(Leaf {
            half,
            partial,
            v: vec![0.0; perm_inv.len()],
            perm_inv,
            x: Vec::new(),
            times: (-1.0, -1.0),
            cpu: 0.0,
        })
    }

    /// Stored values of its factor's interior columns.
    pub(crate) fn partial_values(&self) -> usize {
        self.partial.n_values()
    }

    /// Multiply-adds of a refactorization: the partial factorization of Kᵢ (its interior
    /// columns, the Schur complement's products included; [`PartialLlt::flops`]).
    pub(crate) fn flops(&self) -> f64 {
        self.partial.flops()
    }

    /// Partial factorization of Kᵢ (interior columns) and what its Schur complement
    /// subtracts from the interface, Cᵢ = L_BI L_BIᵀ = A_BᵢIᵢ A_IᵢIᵢ⁻¹ A_IᵢBᵢ (lower, Bᵢ
    /// order), with the smallest interior pivot ratio.
    pub(crate) fn refactorize(
        &mut self,
        cx: Ctx<'_>,
    ) -> Result<(Mat<f64>, (f64, usize)), SolveError> {
        let (t, cpu) = (Instant::now(), thread_cpu_seconds());
        self.half.load(cx.a);
        let an = self.half.core.analysis.as_mut().expect("analyzed");
        let cp = self
            .partial
            .factorize(&self.half.values.values, &mut an.l_values, cx.leaf_par)
            .map_err(|p| SolveError::NotPositiveDefinite {
                index: self.half.dofs[an.original(p)] as usize,
                pivot: f64::NAN,
            })?;
        let pivots = self
            .half
            .interior_min_pivot_ratio(|g| cx.a.values[cx.diag_pos[g]]);
        let t_factor = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let sp = &self.half.s_pos;
        let ns = sp.len();
        let mut c = Mat::<f64>::zeros(ns, ns);
        for l in 0..ns {
            for k in l..ns {
                c[(k, l)] = cp[(sp[k].max(sp[l]), sp[k].min(sp[l]))];
            }
        }
        self.times = (t_factor, t.elapsed().as_secs_f64());
        self.cpu = thread_cpu_seconds() - cpu;
        Ok((c, pivots))
    }

    /// Forward solve of the interior with the global right-hand side `b` (zero on Bᵢ);
    /// returns L_BI y in Bᵢ order (the coupling term of the global forward solve).
    pub(crate) fn forward(&mut self, b: &[f64]) -> Vec<f64> {
        let h = &self.half;
        self.v.fill(0.0);
        for (&g, &p) in h.dofs[..h.n_int].iter().zip(&self.perm_inv) {
            self.v[p as usize] = b[g as usize];
        }
        let an = h.core.analysis.as_ref().expect("analyzed");
        self.partial.forward(&an.l_values, &mut self.v);
        // v_B = −L_BI y
        h.s_pos.iter().map(|&p| -self.v[h.n_int + p]).collect()
    }

    /// Backward solve after [`Leaf::forward`] given the solution `xb` on Bᵢ (Bᵢ order);
    /// returns the interior unknowns in interior order.
    pub(crate) fn backward(&mut self, xb: &[f64]) -> Vec<f64> {
        let h = &self.half;
        for (&p, &x) in h.s_pos.iter().zip(xb) {
            self.v[h.n_int + p] = x;
        }
        let an = h.core.analysis.as_ref().expect("analyzed");
        self.partial.backward(&an.l_values, &mut self.v);
        self.perm_inv[..h.n_int]
            .iter()
            .map(|&p| self.v[p as usize])
            .collect()
    }
}

impl Front {
    /// Assembles M, factorizes its Γ block and returns the Schur complement on B (lower)
    /// with the smallest pivot ratio of Γ.
    fn refactorize(
        &mut self,
        nb: usize,
        cx: Ctx<'_>,
    ) -> Result<(Mat<f64>, (f64, usize)), SolveError> {
        let t = Instant::now();
        let o = self.own.len();
        let nf = o + nb;
        let mut m = Mat::<f64>::zeros(nf, nf);
        for (&(r, c, p), last) in self.a_map.iter().zip(self.last_a.iter_mut()) {
            let v = cx.a.values[p];
            m[(r as usize, c as usize)] += v;
            *last = v;
        }
        for (ch, pos) in self.children.iter().zip(&self.child_pos) {
            for (l, &pl) in pos.iter().enumerate() {
                for (k, &pk) in pos.iter().enumerate().skip(l) {
                    m[(pk.max(pl) as usize, pk.min(pl) as usize)] -= ch.c[(k, l)];
                }
            }
        }
        let mut mem = MemBuffer::try_new(cholesky_in_place_scratch::<f64>(
            o,
            cx.front_par,
            Default::default(),
        ))
        .map_err(|_| SolveError::Other("out of memory for an interface Cholesky".into()))?;
        let (mut top, mut bottom) = m.as_mut().split_at_row_mut(o);
        let mut l = top.rb_mut().subcols_mut(0, o);
        if let Err(LltError::NonPositivePivot { index }) = cholesky_in_place(
            l.rb_mut(),
            Default::default(),
            cx.front_par,
            MemStack::new(&mut mem),
            Default::default(),
        ) {
            self.last_a.iter_mut().for_each(|v| *v = f64::NAN);
            return Err(SolveError::NotPositiveDefinite {
                index: self.own[index.min(o.saturating_sub(1))] as usize,
                pivot: f64::NAN,
            });
        }
        let mut pivots = (f64::INFINITY, 0usize);
        for (j, &g) in self.own.iter().enumerate() {
            let d = l[(j, j)];
            let aii = cx.a.values[cx.diag_pos[g as usize]];
            let r = if aii != 0.0 { d * d / aii.abs() } else { d * d };
            pivots = ratio_min(pivots, (r, g as usize));
        }
        let mut c = Mat::<f64>::zeros(nb, nb);
        if nb > 0 {
            // X = M_BΓ L_ΓΓ⁻ᵀ (in place), then C = −M_BB + X Xᵀ
            let (mut x, mut mbb) = bottom.rb_mut().split_at_col_mut(o);
            solve_lower_triangular_in_place(l.rb(), x.rb_mut().transpose_mut(), cx.front_par);
            let xr: MatRef<'_, f64> = x.rb();
            tri_matmul(
                mbb.rb_mut(),
                BlockStructure::TriangularLower,
                Accum::Add,
                xr,
                BlockStructure::Rectangular,
                xr.transpose(),
                BlockStructure::Rectangular,
                -1.0,
                cx.front_par,
            );
            for j in 0..nb {
                for i in j..nb {
                    c[(i, j)] = -mbb[(i, j)];
                }
            }
        }
        // keep L_ΓΓ and X only
        m.truncate(nf, o);
        self.m = m;
        self.time = t.elapsed().as_secs_f64();
        Ok((c, pivots))
    }
}

/// The tree before any factorization: for a leaf its interior, for a front its interface.
enum Plan {
    Leaf {
        interior: Vec<u32>,
        bnd: Vec<u32>,
    },
    Front {
        own: Vec<u32>,
        bnd: Vec<u32>,
        children: Vec<Plan>,
    },
}

/// Builds the plan of the parts `lo..hi` whose unknowns not on an ancestor's interface
/// are `inside`; `on_gamma` marks the ancestors' interface unknowns (updated), `mark` is
/// scratch (one entry per unknown, stamped with `stamp`).
#[allow(clippy::too_many_arguments)]
fn plan(
    pattern: &CsrPattern,
    part: &[u32],
    lo: u32,
    hi: u32,
    inside: Vec<u32>,
    on_gamma: &mut [bool],
    mark: &mut [u32],
    stamp: &mut u32,
) -> Option<Plan> {
    if inside.is_empty() {
        return None;
    }
    *stamp += 1;
    let s = *stamp;
    let mut bnd: Vec<u32> = Vec::new();
    for &i in &inside {
        for &j in pattern.row_cols(i as usize) {
            if on_gamma[j as usize] && mark[j as usize] != s {
                mark[j as usize] = s;
                bnd.push(j);
            }
        }
    }
    bnd.sort_unstable();
    if hi - lo <= 1 {
        return Some(Plan::Leaf {
            interior: inside,
            bnd,
        });
    }
    let mid = lo + (hi - lo) / 2;
    // the unknowns of each side coupled to the other side
    *stamp += 1;
    let s = *stamp;
    for &i in &inside {
        mark[i as usize] = s;
    }
    let coupled = |i: u32, mark: &[u32]| {
        let left = part[i as usize] < mid;
        pattern
            .row_cols(i as usize)
            .iter()
            .any(|&j| mark[j as usize] == s && (part[j as usize] < mid) != left)
    };
    let (mut lb, mut rb) = (Vec::new(), Vec::new());
    for &i in &inside {
        if coupled(i, mark) {
            if part[i as usize] < mid {
                lb.push(i);
            } else {
                rb.push(i);
            }
        }
    }
    let own = if rb.len() <= lb.len() { rb } else { lb };
    for &i in &own {
        on_gamma[i as usize] = true;
    }
    let (left, right): (Vec<u32>, Vec<u32>) = inside
        .into_iter()
        .filter(|&i| !on_gamma[i as usize])
        .partition(|&i| part[i as usize] < mid);
    let children: Vec<Plan> = [(lo, mid, left), (mid, hi, right)]
        .into_iter()
        .filter_map(|(a, b, set)| plan(pattern, part, a, b, set, on_gamma, mark, stamp))
        .collect();
    if own.is_empty() && children.len() == 1 {
        // nothing to join: the single child stands for this node
        return children.into_iter().next();
    }
    Some(Plan::Front { own, bnd, children })
}

/// Builds the nodes of a plan (the subdomains' symbolic analyses in parallel).
fn build(
    pattern: &Arc<CsrPattern>,
    plan: Plan,
    order: InteriorOrder<'_>,
    threads: usize,
) -> Result<Node, SolveError> {
    match plan {
        Plan::Leaf { interior, bnd } => {
            let leaf = Leaf::new(pattern, interior, &bnd, order, threads)?;
            Ok(Node {
                bnd,
                c: Mat::zeros(0, 0),
                factored: false,
                min_pivot: (f64::INFINITY, 0),
                kind: Kind::Leaf(Box::new(leaf)),
            })
        }
        Plan::Front { own, bnd, children } => {
            // F numbering: own then bnd
            let o = own.len();
            let pos_of = |g: u32| -> Option<u32> {
                own.binary_search(&g)
                    .ok()
                    .or_else(|| bnd.binary_search(&g).ok().map(|k| o + k))
                    .map(|p| p as u32)
            };
            let mut a_map = Vec::new();
            for (r, &g) in own.iter().enumerate() {
                let start = pattern.row_ptr()[g as usize];
                for (t, &c) in pattern.row_cols(g as usize).iter().enumerate() {
                    if let Some(pc) = pos_of(c) {
                        let pc = pc as usize;
                        // own × own once (lower), bnd × own always (below the own block)
                        if pc <= r || pc >= o {
                            a_map.push((pc.max(r) as u32, pc.min(r) as u32, start + t));
                        }
                    }
                }
            }
            let mut child_pos = Vec::with_capacity(children.len());
            for ch in &children {
                let cb = match ch {
                    Plan::Leaf { bnd, .. } | Plan::Front { bnd, .. } => bnd,
                };
                let pos: Option<Vec<u32>> = cb.iter().map(|&g| pos_of(g)).collect();
                child_pos.push(pos.ok_or_else(|| {
                    SolveError::Other(
                        "substructuring: a child's interface is not its parent's".into(),
                    )
                })?);
            }
            let mut plans = children.into_iter();
            let nodes: Vec<Node> = match (plans.next(), plans.next()) {
                (Some(a), Some(b)) => {
                    let (na, nb) = rayon::join(
                        || build(pattern, a, order, threads),
                        || build(pattern, b, order, threads),
                    );
                    vec![na?, nb?]
                }
                (Some(a), None) => vec![build(pattern, a, order, threads)?],
                _ => Vec::new(),
            };
            let na = a_map.len();
            Ok(Node {
                bnd,
                c: Mat::zeros(0, 0),
                factored: false,
                min_pivot: (f64::INFINITY, 0),
                kind: Kind::Front(Box::new(Front {
                    own,
                    children: nodes,
                    child_pos,
                    a_map,
                    last_a: vec![f64::NAN; na],
                    m: Mat::zeros(0, 0),
                    y: Vec::new(),
                    time: -1.0,
                })),
            })
        }
    }
}

/// The analysis of one pattern with one partition.
struct Analysis {
    pattern: Arc<CsrPattern>,
    root: Node,
    diag_pos: Vec<usize>,
    factored: bool,
    last_values: Vec<f64>,
}

impl Analysis {
    fn new(
        pattern: &Arc<CsrPattern>,
        part: &[u32],
        ordering: FillOrdering,
        threads: usize,
    ) -> Result<Self, SolveError> {
        let n = pattern.n();
        if part.len() != n {
            return Err(SolveError::Other(format!(
                "the partition covers {} unknowns, the matrix has {n}",
                part.len()
            )));
        }
        let k = part.iter().map(|&p| p as usize + 1).max().unwrap_or(1);
        if k > n.max(1) {
            return Err(SolveError::Other(format!(
                "the partition names part {} for {n} unknowns",
                k - 1
            )));
        }
        let mut on_gamma = vec![false; n];
        let mut mark = vec![0u32; n];
        let mut stamp = 0;
        let plan = plan(
            pattern,
            part,
            0,
            k as u32,
            (0..n as u32).collect(),
            &mut on_gamma,
            &mut mark,
            &mut stamp,
        );
        let order = match ordering {
            FillOrdering::Metis => InteriorOrder::Metis,
            FillOrdering::Amd => InteriorOrder::Amd,
        };
        let root = match plan {
            Some(p) => build(pattern, p, order, threads)?,
            None => {
                // no unknowns at all: an empty front
                Node {
                    bnd: Vec::new(),
                    c: Mat::zeros(0, 0),
                    factored: false,
                    min_pivot: (f64::INFINITY, 0),
                    kind: Kind::Front(Box::new(Front {
                        own: Vec::new(),
                        children: Vec::new(),
                        child_pos: Vec::new(),
                        a_map: Vec::new(),
                        last_a: Vec::new(),
                        m: Mat::zeros(0, 0),
                        y: Vec::new(),
                        time: 0.0,
                    })),
                }
            }
        };
        Ok(Self {
            pattern: pattern.clone(),
            root,
            diag_pos: pattern.diagonal_positions(),
            factored: false,
            last_values: Vec::new(),
        })
    }
}

/// Sparse Cholesky LLᵀ by nested substructuring, k subdomains factorized in parallel,
/// unchanged subdomains reused; see the module documentation. Name `faer-substructured`.
pub struct FaerCholeskySubstructured {
    parts: usize,
    ordering: FillOrdering,
    interface_threads: usize,
    subdomain_threads: usize,
    partition: Option<Vec<u32>>,
    inner: Option<Box<Analysis>>,
    stats: SolverStats,
    sub_stats: SubstructureStats,
}

impl Default for FaerCholeskySubstructured {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerCholeskySubstructured {
    /// Two subdomains, interiors ordered by METIS nested dissection, each subdomain
    /// factorized sequentially, the interface fronts on two rayon tasks; no analysis yet.
    pub fn new() -> Self {
        Self {
            parts: 2,
            ordering: FillOrdering::Metis,
            interface_threads: 2,
            subdomain_threads: 1,
            partition: None,
            inner: None,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
            sub_stats: SubstructureStats::default(),
        }
    }

    /// Number of subdomains (at least 1) asked for through
    /// [`LinearBackend::partition_parts`] and used by the METIS bisection of the node
    /// graph when no partition is given. Takes effect at the next analysis.
    pub fn with_subdomains(mut self, k: usize) -> Self {
        self.parts = k.max(1);
        self.inner = None;
        self
    }

    /// Ordering of each subdomain's interior (takes effect at the next analysis): METIS
    /// nested dissection (default; least fill) or AMD (cheaper analysis).
    pub fn with_ordering(mut self, ordering: FillOrdering) -> Self {
        self.ordering = ordering;
        self.inner = None;
        self
    }

    /// Rayon tasks of the dense interface kernels (`Par::rayon(t)`; default 2; 1 =
    /// sequential). The split of the work depends on t only, so the results are the same
    /// for any pool size; different t may differ in the last bits.
    pub fn with_interface_threads(mut self, t: usize) -> Self {
        self.interface_threads = t.max(1);
        self
    }

    /// Rayon tasks inside each subdomain's sparse factorization and Schur complement
    /// (`Par::rayon(t)` for faer's dense supernode kernels, default 1 = sequential): lets
    /// a second core help when fewer subdomains than cores are refactorized. Like the
    /// interface, a fixed split of the work: the same bits in any pool. Takes effect at
    /// the next analysis.
    pub fn with_subdomain_threads(mut self, t: usize) -> Self {
        self.subdomain_threads = t.max(1);
        self.inner = None;
        self
    }

    /// Counters and timers of the substructuring.
    pub fn substructure_stats(&self) -> &SubstructureStats {
        &self.sub_stats
    }
}

impl LinearBackend for FaerCholeskySubstructured {
    fn name(&self) -> &'static str {
        "faer-substructured"
    }

    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        if self
            .inner
            .as_ref()
            .is_some_and(|a| a.pattern.id() == pattern.id())
        {
            return Ok(());
        }
        self.inner = None;
        let t = Instant::now();
        let part = match &self.partition {
            Some(p) => p.clone(),
            None => metis_bisection_partition(pattern, self.parts)?,
        };
        let partition_seconds = t.elapsed().as_secs_f64();
        let an = Analysis::new(pattern, &part, self.ordering, self.subdomain_threads)?;
        let ss = &mut self.sub_stats;
        let mut leaves = Vec::new();
        let mut fronts = Vec::new();
        let mut leaf_flops = Vec::new();
        an.root.visit(
            &mut |l| {
                leaf_flops.push(l.flops());
                let nnz = l.partial.n_values();
                leaves.push((
                    l.half.dofs.len(),
                    l.half.n_int,
                    nnz,
                    l.half.core.stats.ordering_seconds,
                ));
            },
            &mut |f, bnd| fronts.push((f.own.len(), bnd.len())),
        );
        ss.subdomain_sizes = leaves.iter().map(|l| l.0).collect();
        ss.subdomain_interface_sizes = leaves.iter().map(|l| l.0 - l.1).collect();
        ss.front_sizes = fronts;
        let nnz = leaves.iter().map(|l| l.2).sum::<usize>()
            + ss.front_sizes
                .iter()
                .map(|&(o, b)| o * (o + 1) / 2 + o * b)
                .sum::<usize>();
        let ordering_seconds = partition_seconds + leaves.iter().map(|l| l.3).sum::<f64>();
        ss.front_flops = ss
            .front_sizes
            .iter()
            .map(|&(o, b)| front_flops(o, b))
            .collect();
        ss.subdomain_flops = leaf_flops;
        ss.critical_path_flops = an.root.critical_path_flops();
        self.stats.factor_flops =
            ss.subdomain_flops.iter().sum::<f64>() + ss.front_flops.iter().sum::<f64>();
        ss.subdomains = ss.subdomain_sizes.len();
        ss.interface_size = ss.front_sizes.iter().map(|f| f.0).sum();
        self.stats.factor_nnz = nnz;
        self.stats.ordering_seconds += ordering_seconds;
        self.inner = Some(Box::new(an));
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        crate::backend::check_values(a)?;
        let an = self.inner.as_mut().expect("analyzed");
        if an.factored && same_bits(&a.values, &an.last_values) {
            self.stats.skipped_factorizations += 1;
            return Ok(());
        }
        an.factored = false;
        let t0 = Instant::now();
        let cx = Ctx {
            a,
            diag_pos: &an.diag_pos,
            leaf_par: par_of(self.subdomain_threads),
            front_par: par_of(self.interface_threads),
        };
        let r = an.root.refresh(cx);
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t0.elapsed().as_secs_f64();
        if let Err(e) = r {
            mark_counted(&mut an.root);
            self.stats.min_pivot_ratio = f64::NAN;
            if let SolveError::NotPositiveDefinite { index, .. } = e {
                self.stats.min_pivot_index = index;
            }
            return Err(e);
        }
        // counters: which subdomains were redone (their times are this call's)
        let mut leaves = Vec::new();
        let mut fronts = Vec::new();
        an.root
            .visit(&mut |l| leaves.push((l.times, l.flops())), &mut |f, bnd| {
                fronts.push((f.time, front_flops(f.own.len(), bnd.len())))
            });
        let ss = &mut self.sub_stats;
        ss.last_critical_path_seconds = an.root.last_critical_path_seconds();
        ss.last_refactorized.clear();
        ss.last_fronts = 0;
        ss.last_flops = 0.0;
        for (i, &((tf, ts), flops)) in leaves.iter().enumerate() {
            if tf >= 0.0 {
                ss.last_refactorized.push(i);
                ss.last_flops += flops;
                ss.subdomain_factorizations += 1;
                ss.subdomain_factor_seconds += tf;
                ss.schur_seconds += ts;
            } else {
                ss.subdomain_reuses += 1;
            }
        }
        for &(t, flops) in fronts.iter().filter(|f| f.0 >= 0.0) {
            ss.last_fronts += 1;
            ss.interface_seconds += t;
            ss.last_flops += flops;
        }
        mark_counted(&mut an.root);
        let (ratio, index) = an.root.min_pivot;
        self.stats.min_pivot_ratio = if a.pattern.n() == 0 { f64::NAN } else { ratio };
        self.stats.min_pivot_index = index;
        an.last_values.clear();
        an.last_values.extend_from_slice(&a.values);
        an.factored = true;
        self.stats.memory_bytes = an.root.memory_bytes();
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let an = match &mut self.inner {
            Some(an) if an.factored => an,
            _ => {
                return Err(SolveError::Other(
                    "solve called without a successful factorization".into(),
                ))
            }
        };
        let n = an.pattern.n();
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "right-hand side has length {}, expected {n}",
                rhs.len()
            )));
        }
        let t = Instant::now();
        let up = an.root.forward(rhs);
        an.root.backward(&vec![0.0; up.len()]);
        an.root.scatter(rhs);
        self.stats.solves += 1;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }

    fn partition_parts(&self) -> Option<usize> {
        Some(self.parts)
    }

    fn set_partition(&mut self, part: &[u32]) -> Result<(), SolveError> {
        if self.partition.as_deref() != Some(part) {
            self.partition = Some(part.to_vec());
            self.inner = None;
        }
        Ok(())
    }
}

/// CPU time consumed by the calling thread so far, s (NaN where unavailable).
fn thread_cpu_seconds() -> f64 {
    #[cfg(target_os = "linux")]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec into `ts`, which outlives the call.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0 {
            return ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        }
    }
    f64::NAN
}

/// Marks the times of every node as counted (negative): the next factorization's
/// counters then see only what it recomputed.
fn mark_counted(node: &mut Node) {
    match &mut node.kind {
        Kind::Leaf(l) => l.times = (-1.0, -1.0),
        Kind::Front(f) => {
            f.time = -1.0;
            for ch in &mut f.children {
                mark_counted(ch);
            }
        }
    }
}

#[cfg(test)]
mod tests;
