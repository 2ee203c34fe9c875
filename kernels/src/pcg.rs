//! Preconditioned conjugate gradients for symmetric positive definite matrices, with three
//! preconditioners ([`Preconditioner`]):
//!
//! * **Jacobi**: the inverse diagonal (the default).
//! * **Block-Jacobi**: a dense Cholesky factor of each diagonal block A\[B, B\], the blocks
//!   given as disjoint lists of unknowns (for example the unknowns of one discrete block
//!   of the structure); unknowns in no block get the Jacobi scaling.
//! * **Two-level**: block-Jacobi plus a coarse correction on a coarse space Z (n × m,
//!   [`CoarseSpace`]; for blocky structures each block's two translations and in-plane
//!   rotation, see [`CoarseSpace::rigid_body_modes_2d`]). With E = Zᵀ A Z and
//!   Q = Z E⁻¹ Zᵀ, the *balanced* (BNN, default) variant is
//!   M⁻¹ = Q + (I − Q A) M_BJ⁻¹ (I − A Q), the *additive* one M⁻¹ = Q + M_BJ⁻¹. Both are
//!   symmetric positive definite. W = A Z is formed once at set-up, so one application
//!   costs one block-Jacobi sweep, two coarse solves (balanced) and products with the
//!   sparse Z and W, but no extra product with A. E is sparse (blocks couple only with
//!   their neighbours) and is factorized with [`FaerCholesky`].
//!
//! Determinism: every reduction (dot products, Zᵀ r, Wᵀ s) sums in a fixed order over fixed
//! chunks, products are row-wise, block solves are sequential within a block and the
//! coarse solve runs on one thread, so the iterates are bit-identical for any number of
//! rayon threads.

use crate::assembly::CONSTRAINED;
use crate::backend::{same_bits, LinearBackend, SolveError, SolverStats};
use crate::csr::{CsrMatrix, CsrPattern, ROW_CHUNK};
use crate::faer_backend::FaerCholesky;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Length of the fixed chunks of the deterministic reductions.
const DOT_CHUNK: usize = 4096;

/// Marks an unknown that belongs to no block.
const NO_BLOCK: u32 = u32::MAX;

/// Deterministic dot product: partial sums over fixed chunks of 4096 entries,
/// computed in parallel, then added in chunk order.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    assert_eq!(x.len(), y.len());
    let partial: Vec<f64> = x
        .par_chunks(DOT_CHUNK)
        .zip(y.par_chunks(DOT_CHUNK))
        .map(|(a, b)| a.iter().zip(b).map(|(u, v)| u * v).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// Short dot product with four interleaved partial sums (a fixed order, so the result
/// does not depend on the thread count), for the dense block kernels.
#[inline]
fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// How the coarse correction of [`Preconditioner::TwoLevel`] is combined with the
/// block-Jacobi smoother.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoarseCorrection {
    /// M⁻¹ = Q + M_BJ⁻¹: cheapest (one coarse solve per iteration), weaker.
    Additive,
    /// M⁻¹ = Q + (I − Q A) M_BJ⁻¹ (I − A Q) (balancing / BNN): two coarse solves per
    /// iteration; the smoother never sees the coarse-space error. The default.
    #[default]
    Balanced,
}

/// The preconditioner of [`Pcg`]. Block lists hold unknown numbers (0-based, `< n`);
/// the blocks must be disjoint, and every block's diagonal sub-matrix must be positive
/// definite. Set-up of a block of size b costs O(b³) and b² / 2 stored values.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Preconditioner {
    /// Inverse diagonal.
    #[default]
    Jacobi,
    /// Dense Cholesky of each diagonal block; Jacobi on unknowns outside every block.
    BlockJacobi {
        /// Disjoint lists of unknowns, one per block.
        blocks: Vec<Vec<usize>>,
    },
    /// Block-Jacobi plus a coarse correction on the coarse space given by
    /// [`Pcg::set_coarse_space`] (required: set-up fails without it).
    TwoLevel {
        /// Disjoint lists of unknowns, one per block (the smoother's blocks).
        blocks: Vec<Vec<usize>>,
        /// Additive or balanced combination.
        correction: CoarseCorrection,
    },
}

/// The nodes of one block of a 2D structure, for [`CoarseSpace::rigid_body_modes_2d`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockNodes2d {
    /// Unknowns (x, y displacement) of each node; [`CONSTRAINED`] for a fixed component.
    pub dofs: Vec<[u32; 2]>,
    /// Coordinates of each node (any length unit, the same for every block).
    pub xy: Vec<[f64; 2]>,
}

impl BlockNodes2d {
    /// The block's unknowns (constrained components left out), in node order: a block
    /// list for [`Preconditioner::BlockJacobi`] or [`Preconditioner::TwoLevel`].
    pub fn dof_list(&self) -> Vec<usize> {
        self.dofs
            .iter()
            .flatten()
            .filter(|&&d| d != CONSTRAINED)
            .map(|&d| d as usize)
            .collect()
    }
}

/// A coarse space Z (n × m, sparse, stored by rows and by columns) for the two-level
/// preconditioner: its columns should span the near-null space of the matrix (the
/// rigid-body motions of weakly connected parts).
#[derive(Debug, Clone, PartialEq)]
pub struct CoarseSpace {
    n: usize,
    m: usize,
    /// CSR of Z: row i has columns `col[row_ptr[i]..row_ptr[i + 1]]` (ascending).
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl CoarseSpace {
    /// From columns given as (row, value) lists. Rows must be `< n` and not repeated
    /// within a column, values finite; columns that are entirely zero are dropped. The
    /// remaining columns must be linearly independent (else the coarse matrix is singular
    /// and the preconditioner set-up fails).
    pub fn from_columns(n: usize, columns: &[Vec<(usize, f64)>]) -> Result<Self, SolveError> {
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        let mut m = 0u32;
        let mut mark = vec![u32::MAX; n];
        for (j, c) in columns.iter().enumerate() {
            if c.iter().all(|&(_, v)| v == 0.0) {
                continue;
            }
            for &(i, v) in c {
                if i >= n {
                    return Err(SolveError::Other(format!(
                        "coarse space column {j}: row {i} out of range (n = {n})"
                    )));
                }
                if !v.is_finite() {
                    return Err(SolveError::Other(format!(
                        "coarse space column {j}: non-finite value at row {i}"
                    )));
                }
                if mark[i] == m {
                    return Err(SolveError::Other(format!(
                        "coarse space column {j}: row {i} given twice"
                    )));
                }
                mark[i] = m;
                if v != 0.0 {
                    rows[i].push((m, v));
                }
            }
            m += 1;
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        row_ptr.push(0);
        let mut col = Vec::new();
        let mut val = Vec::new();
        for r in rows {
            // columns were pushed in ascending order
            for (c, v) in r {
                col.push(c);
                val.push(v);
            }
            row_ptr.push(col.len());
        }
        Ok(Self {
            n,
            m: m as usize,
            row_ptr,
            col,
            val,
        })
    }

    /// The in-plane rigid-body motions of each block of a 2D structure: translation in x,
    /// translation in y, and rotation about the centroid of the block's free nodes, made
    /// orthonormal within each block (modified Gram–Schmidt; a mode that is dependent on
    /// the others there, e.g. the rotation of a block with a single free node, is dropped).
    /// Up to 3 columns per block, `n` = number of unknowns.
    pub fn rigid_body_modes_2d(n: usize, blocks: &[BlockNodes2d]) -> Result<Self, SolveError> {
        let mut columns = Vec::with_capacity(3 * blocks.len());
        for (b, blk) in blocks.iter().enumerate() {
            if blk.dofs.len() != blk.xy.len() {
                return Err(SolveError::Other(format!(
                    "block {b}: {} dof pairs but {} coordinates",
                    blk.dofs.len(),
                    blk.xy.len()
                )));
            }
            let mut rows = Vec::new();
            let mut centre = [0.0, 0.0];
            let mut count = 0.0;
            for (d, p) in blk.dofs.iter().zip(&blk.xy) {
                if !(p[0].is_finite() && p[1].is_finite()) {
                    return Err(SolveError::Other(format!(
                        "block {b}: non-finite node coordinates"
                    )));
                }
                for &k in d {
                    if k != CONSTRAINED && k as usize >= n {
                        return Err(SolveError::Other(format!(
                            "block {b}: unknown {k} out of range (n = {n})"
                        )));
                    }
                }
                if d.iter().any(|&k| k != CONSTRAINED) {
                    centre[0] += p[0];
                    centre[1] += p[1];
                    count += 1.0;
                }
            }
            if count == 0.0 {
                continue;
            }
            centre = [centre[0] / count, centre[1] / count];
            // dense local columns over the block's free unknowns
            let mut modes = [Vec::new(), Vec::new(), Vec::new()];
            for (d, p) in blk.dofs.iter().zip(&blk.xy) {
                let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                for (comp, &k) in d.iter().enumerate() {
                    if k == CONSTRAINED {
                        continue;
                    }
                    rows.push(k as usize);
                    let (tx, ty, rot) = if comp == 0 {
                        (1.0, 0.0, -dy)
                    } else {
                        (0.0, 1.0, dx)
                    };
                    modes[0].push(tx);
                    modes[1].push(ty);
                    modes[2].push(rot);
                }
            }
            let mut kept: Vec<Vec<f64>> = Vec::new();
            for mut v in modes {
                let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                if norm0 == 0.0 {
                    continue;
                }
                for q in &kept {
                    let p: f64 = v.iter().zip(q).map(|(a, b)| a * b).sum();
                    v.iter_mut().zip(q).for_each(|(a, b)| *a -= p * b);
                }
                let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                if norm > 1e-10 * norm0 {
                    v.iter_mut().for_each(|a| *a /= norm);
                    kept.push(v);
                }
            }
            for v in kept {
                columns.push(rows.iter().copied().zip(v).collect::<Vec<_>>());
            }
        }
        Self::from_columns(n, &columns)
    }

    /// Number of rows (unknowns).
    pub fn n_rows(&self) -> usize {
        self.n
    }

    /// Number of (non-zero) columns.
    pub fn n_columns(&self) -> usize {
        self.m
    }
}

/// A sparse n × m matrix stored by rows and by columns (Z or W = A Z).
struct TallSparse {
    m: usize,
    row_ptr: Vec<usize>,
    row_col: Vec<u32>,
    row_val: Vec<f64>,
    col_ptr: Vec<usize>,
    col_row: Vec<u32>,
    col_val: Vec<f64>,
}

impl TallSparse {
    fn from_rows(m: usize, row_ptr: Vec<usize>, row_col: Vec<u32>, row_val: Vec<f64>) -> Self {
        let n = row_ptr.len() - 1;
        let mut count = vec![0usize; m + 1];
        for &c in &row_col {
            count[c as usize + 1] += 1;
        }
        for j in 0..m {
            count[j + 1] += count[j];
        }
        let col_ptr = count.clone();
        let mut next = count;
        let mut col_row = vec![0u32; row_col.len()];
        let mut col_val = vec![0.0; row_col.len()];
        for i in 0..n {
            for k in row_ptr[i]..row_ptr[i + 1] {
                let c = row_col[k] as usize;
                col_row[next[c]] = i as u32;
                col_val[next[c]] = row_val[k];
                next[c] += 1;
            }
        }
        Self {
            m,
            row_ptr,
            row_col,
            row_val,
            col_ptr,
            col_row,
            col_val,
        }
    }

    /// y = Mᵀ x (length m), each column summed in row order.
    fn tr_mul(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(ROW_CHUNK).enumerate().for_each(|(c, ys)| {
            for (k, yj) in ys.iter_mut().enumerate() {
                let j = c * ROW_CHUNK + k;
                let mut s = 0.0;
                for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                    s += self.col_val[p] * x[self.col_row[p] as usize];
                }
                *yj = s;
            }
        });
    }

    /// y += alpha · M c (length n), row-wise.
    fn mul_add(&self, alpha: f64, c: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(ROW_CHUNK)
            .enumerate()
            .for_each(|(ch, ys)| {
                for (k, yi) in ys.iter_mut().enumerate() {
                    let i = ch * ROW_CHUNK + k;
                    let mut s = 0.0;
                    for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                        s += self.row_val[p] * c[self.row_col[p] as usize];
                    }
                    *yi += alpha * s;
                }
            });
    }
}

/// Row-by-row sparse product (Gustavson) of a CSR `a` (rows × inner) with a CSR `b`
/// (inner × m): returns the CSR arrays of a·b with every structurally reached entry kept
/// (also numerical zeros), columns ascending. Row i sums its terms in a fixed order.
#[allow(clippy::too_many_arguments)]
fn spgemm(
    rows: usize,
    a_ptr: &[usize],
    a_idx: &[u32],
    a_val: &[f64],
    b_ptr: &[usize],
    b_idx: &[u32],
    b_val: &[f64],
    m: usize,
) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..rows.div_ceil(ROW_CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut acc = vec![0.0; m];
            let mut used = vec![false; m];
            let mut list: Vec<u32> = Vec::new();
            let mut lens = Vec::new();
            let mut idx = Vec::new();
            let mut val = Vec::new();
            for i in c * ROW_CHUNK..((c + 1) * ROW_CHUNK).min(rows) {
                for p in a_ptr[i]..a_ptr[i + 1] {
                    let k = a_idx[p] as usize;
                    let av = a_val[p];
                    for q in b_ptr[k]..b_ptr[k + 1] {
                        let j = b_idx[q] as usize;
                        if !used[j] {
                            used[j] = true;
                            list.push(j as u32);
                        }
                        acc[j] += av * b_val[q];
                    }
                }
                list.sort_unstable();
                for &j in &list {
                    idx.push(j);
                    val.push(acc[j as usize]);
                    acc[j as usize] = 0.0;
                    used[j as usize] = false;
                }
                lens.push(list.len());
                list.clear();
            }
            (lens, idx, val)
        })
        .collect();
    let mut ptr = Vec::with_capacity(rows + 1);
    ptr.push(0);
    let mut idx = Vec::new();
    let mut val = Vec::new();
    for (lens, i, v) in chunks {
        for l in lens {
            ptr.push(ptr.last().unwrap() + l);
        }
        idx.extend(i);
        val.extend(v);
    }
    (ptr, idx, val)
}

/// Dense Cholesky factors of the diagonal blocks.
struct BlockJacobi {
    /// Unknowns of all blocks, block after block.
    flat_dofs: Vec<u32>,
    /// Block b covers `flat_dofs[offset[b]..offset[b + 1]]`.
    offset: Vec<usize>,
    /// Packed lower-triangular factor of block b (row-major, row i has i + 1 entries)
    /// starts at `factor_offset[b]`.
    factor_offset: Vec<usize>,
    factors: Vec<f64>,
    /// Position of each unknown in `flat_dofs`, or `NO_BLOCK`.
    pos: Vec<u32>,
    /// 1 / a_ii for unknowns outside every block.
    inv_diag: Vec<f64>,
}

impl BlockJacobi {
    fn new(a: &CsrMatrix, blocks: &[Vec<usize>]) -> Result<Self, SolveError> {
        let n = a.n();
        let mut pos = vec![NO_BLOCK; n];
        let mut flat_dofs = Vec::new();
        let mut offset = vec![0];
        for (b, blk) in blocks.iter().enumerate() {
            for &d in blk {
                if d >= n {
                    return Err(SolveError::Other(format!(
                        "block {b}: unknown {d} out of range (n = {n})"
                    )));
                }
                if pos[d] != NO_BLOCK {
                    return Err(SolveError::Other(format!(
                        "block {b}: unknown {d} is already in a block (blocks must be disjoint)"
                    )));
                }
                if flat_dofs.len() >= u32::MAX as usize - 1 {
                    return Err(SolveError::Other("too many blocked unknowns".into()));
                }
                pos[d] = flat_dofs.len() as u32;
                flat_dofs.push(d as u32);
            }
            offset.push(flat_dofs.len());
        }
        let diag = a.diagonal();
        if let Some((i, &v)) = diag
            .iter()
            .enumerate()
            .find(|(_, &v)| v.is_nan() || v <= 0.0)
        {
            return Err(SolveError::NotPositiveDefinite { index: i, pivot: v });
        }
        let inv_diag = diag.iter().map(|v| 1.0 / v).collect();
        let rp = a.pattern.row_ptr();
        let ci = a.pattern.col_idx();
        let factors: Vec<Vec<f64>> = (0..blocks.len())
            .into_par_iter()
            .map(|b| {
                let (o0, o1) = (offset[b], offset[b + 1]);
                let len = o1 - o0;
                let mut l = vec![0.0; len * (len + 1) / 2];
                for li in 0..len {
                    let i = flat_dofs[o0 + li] as usize;
                    for p in rp[i]..rp[i + 1] {
                        let q = pos[ci[p] as usize];
                        if q != NO_BLOCK && (q as usize) >= o0 && (q as usize) < o1 {
                            let lj = q as usize - o0;
                            if lj <= li {
                                l[li * (li + 1) / 2 + lj] = a.values[p];
                            }
                        }
                    }
                }
                // in-place Cholesky, row by row
                for i in 0..len {
                    let ri = i * (i + 1) / 2;
                    for j in 0..=i {
                        let rj = j * (j + 1) / 2;
                        let s = l[ri + j] - dot4(&l[ri..ri + j], &l[rj..rj + j]);
                        if j == i {
                            if s.is_nan() || s <= 0.0 {
                                return Err(SolveError::NotPositiveDefinite {
                                    index: flat_dofs[o0 + i] as usize,
                                    pivot: s,
                                });
                            }
                            l[ri + i] = s.sqrt();
                        } else {
                            l[ri + j] = s / l[rj + j];
                        }
                    }
                }
                Ok(l)
            })
            .collect::<Result<_, _>>()?;
        let mut factor_offset = Vec::with_capacity(blocks.len() + 1);
        factor_offset.push(0);
        for f in &factors {
            factor_offset.push(factor_offset.last().unwrap() + f.len());
        }
        Ok(Self {
            flat_dofs,
            offset,
            factor_offset,
            factors: factors.concat(),
            pos,
            inv_diag,
        })
    }

    /// z = M_BJ⁻¹ r; `flat` is scratch of length `flat_dofs.len()`.
    fn apply(&self, r: &[f64], z: &mut [f64], flat: &mut [f64]) {
        flat.par_iter_mut()
            .zip(&self.flat_dofs)
            .for_each(|(f, &d)| *f = r[d as usize]);
        let mut slices = Vec::with_capacity(self.offset.len() - 1);
        let mut rest: &mut [f64] = &mut *flat;
        for w in self.offset.windows(2) {
            let (h, t) = rest.split_at_mut(w[1] - w[0]);
            slices.push(h);
            rest = t;
        }
        slices.into_par_iter().enumerate().for_each(|(b, x)| {
            let l = &self.factors[self.factor_offset[b]..self.factor_offset[b + 1]];
            let len = x.len();
            // L y = r
            for i in 0..len {
                let ri = i * (i + 1) / 2;
                x[i] = (x[i] - dot4(&l[ri..ri + i], &x[..i])) / l[ri + i];
            }
            // Lᵀ x = y
            for i in (0..len).rev() {
                let ri = i * (i + 1) / 2;
                x[i] /= l[ri + i];
                let xi = x[i];
                for k in 0..i {
                    x[k] -= l[ri + k] * xi;
                }
            }
        });
        let flat: &[f64] = flat;
        z.par_chunks_mut(ROW_CHUNK).enumerate().for_each(|(c, zs)| {
            for (k, zi) in zs.iter_mut().enumerate() {
                let i = c * ROW_CHUNK + k;
                let p = self.pos[i];
                *zi = if p == NO_BLOCK {
                    r[i] * self.inv_diag[i]
                } else {
                    flat[p as usize]
                };
            }
        });
    }
}

/// Coarse space data of the two-level preconditioner.
struct Coarse {
    z: TallSparse,
    /// W = A Z.
    w: TallSparse,
    /// Cholesky of E = Zᵀ A Z.
    e: FaerCholesky,
    correction: CoarseCorrection,
}

impl Coarse {
    fn new(
        a: &CsrMatrix,
        space: &CoarseSpace,
        correction: CoarseCorrection,
    ) -> Result<Self, SolveError> {
        let n = a.n();
        if space.n != n {
            return Err(SolveError::Other(format!(
                "the coarse space has {} rows, the matrix {n}",
                space.n
            )));
        }
        let m = space.m;
        if m == 0 {
            return Err(SolveError::Other(
                "the coarse space has no non-zero column".into(),
            ));
        }
        let z = TallSparse::from_rows(
            m,
            space.row_ptr.clone(),
            space.col.clone(),
            space.val.clone(),
        );
        let (wp, wi, wv) = spgemm(
            n,
            a.pattern.row_ptr(),
            a.pattern.col_idx(),
            &a.values,
            &z.row_ptr,
            &z.row_col,
            &z.row_val,
            m,
        );
        let w = TallSparse::from_rows(m, wp, wi, wv);
        // E = Zᵀ W: Zᵀ by rows is Z by columns
        let (ep, ei, ev) = spgemm(
            m, &z.col_ptr, &z.col_row, &z.col_val, &w.row_ptr, &w.row_col, &w.row_val, m,
        );
        let pattern = CsrPattern::from_parts(m, ep, ei)
            .map_err(|e| SolveError::Other(format!("coarse matrix pattern: {e}")))?;
        let emat = CsrMatrix {
            pattern: Arc::new(pattern),
            values: ev,
        };
        let mut e = FaerCholesky::new();
        e.factorize(&emat).map_err(|err| {
            SolveError::Other(format!(
                "coarse matrix Zᵀ A Z is not positive definite ({err}): are the coarse-space columns linearly independent?"
            ))
        })?;
        // a near-zero pivot: the columns are (numerically) dependent
        let ratio = e.stats().min_pivot_ratio;
        if ratio.is_nan() || ratio <= 1e-12 {
            return Err(SolveError::Other(format!(
                "coarse matrix Zᵀ A Z is numerically singular (smallest pivot ratio {ratio:e} at coarse column {}): the coarse-space columns are linearly dependent",
                e.stats().min_pivot_index
            )));
        }
        Ok(Self {
            z,
            w,
            e,
            correction,
        })
    }
}

/// Set-up preconditioner.
enum Prec {
    Jacobi(Vec<f64>),
    Block(BlockJacobi),
    TwoLevel(BlockJacobi, Box<Coarse>),
}

/// Scratch vectors of one preconditioner application.
#[derive(Default)]
struct Work {
    flat: Vec<f64>,
    rr: Vec<f64>,
    c: Vec<f64>,
    d: Vec<f64>,
}

impl Prec {
    /// z = M⁻¹ r.
    fn apply(&mut self, r: &[f64], z: &mut [f64], w: &mut Work) -> Result<(), SolveError> {
        match self {
            Prec::Jacobi(inv) => {
                z.par_iter_mut()
                    .zip(r)
                    .zip(inv.as_slice())
                    .for_each(|((zi, ri), mi)| *zi = ri * mi);
            }
            Prec::Block(bj) => {
                w.flat.resize(bj.flat_dofs.len(), 0.0);
                bj.apply(r, z, &mut w.flat);
            }
            Prec::TwoLevel(bj, co) => {
                w.flat.resize(bj.flat_dofs.len(), 0.0);
                w.c.resize(co.z.m, 0.0);
                w.d.resize(co.z.m, 0.0);
                // c = E⁻¹ Zᵀ r
                co.z.tr_mul(r, &mut w.c);
                co.e.solve(&mut w.c)?;
                match co.correction {
                    CoarseCorrection::Additive => {
                        bj.apply(r, z, &mut w.flat);
                        co.z.mul_add(1.0, &w.c, z);
                    }
                    CoarseCorrection::Balanced => {
                        // r' = r − W c, s = M_BJ⁻¹ r'
                        w.rr.clear();
                        w.rr.extend_from_slice(r);
                        co.w.mul_add(-1.0, &w.c, &mut w.rr);
                        bj.apply(&w.rr, z, &mut w.flat);
                        // d = E⁻¹ Wᵀ s; z = s + Z (c − d)
                        co.w.tr_mul(z, &mut w.d);
                        co.e.solve(&mut w.d)?;
                        w.c.iter_mut().zip(&w.d).for_each(|(c, d)| *c -= d);
                        co.z.mul_add(1.0, &w.c, z);
                    }
                }
            }
        }
        Ok(())
    }
}

/// Preconditioned conjugate gradients for symmetric positive definite matrices. Starts
/// from x = 0; stops when the recursively updated residual satisfies
/// ‖r‖₂ ≤ `tolerance` · ‖b‖₂, then reports the true residual ‖b − A x‖₂ / ‖b‖₂ in
/// `stats().last_true_residual` and the iteration count in `stats().last_iterations`.
pub struct Pcg {
    /// Relative residual tolerance (default 1e-10).
    pub tolerance: f64,
    /// Maximum number of iterations; `None` (default) means 2 n + 100.
    pub max_iterations: Option<usize>,
    preconditioner: Preconditioner,
    coarse_space: Option<CoarseSpace>,
    matrix: Option<CsrMatrix>,
    prec: Option<Prec>,
    work: Work,
    pattern_id: Option<u64>,
    stats: SolverStats,
}

impl Default for Pcg {
    fn default() -> Self {
        Self::new()
    }
}

impl Pcg {
    /// Jacobi preconditioner, tolerance 1e-10, default iteration limit.
    pub fn new() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: None,
            preconditioner: Preconditioner::Jacobi,
            coarse_space: None,
            matrix: None,
            prec: None,
            work: Work::default(),
            pattern_id: None,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        }
    }

    /// Sets the relative residual tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// Sets the maximum number of iterations.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = Some(max_iterations);
        self
    }

    /// Sets the preconditioner (set up at the next `factorize`).
    pub fn with_preconditioner(mut self, preconditioner: Preconditioner) -> Self {
        self.set_preconditioner(preconditioner);
        self
    }

    /// Sets the preconditioner; the next `factorize` sets it up (a `solve` before that
    /// fails).
    pub fn set_preconditioner(&mut self, preconditioner: Preconditioner) {
        self.preconditioner = preconditioner;
        self.invalidate();
    }

    /// Sets the coarse space (near-null space) of [`Preconditioner::TwoLevel`]; the next
    /// `factorize` sets it up (a `solve` before that fails).
    pub fn with_coarse_space(mut self, space: CoarseSpace) -> Self {
        self.set_coarse_space(space);
        self
    }

    /// See [`Pcg::with_coarse_space`].
    pub fn set_coarse_space(&mut self, space: CoarseSpace) {
        self.coarse_space = Some(space);
        self.invalidate();
    }

    /// The preconditioner in use.
    pub fn preconditioner(&self) -> &Preconditioner {
        &self.preconditioner
    }

    fn invalidate(&mut self) {
        self.matrix = None;
        self.prec = None;
    }

    fn setup(&self, a: &CsrMatrix) -> Result<Prec, SolveError> {
        Ok(match &self.preconditioner {
            Preconditioner::Jacobi => {
                let d = a.diagonal();
                if let Some((i, &v)) = d.iter().enumerate().find(|(_, &v)| v.is_nan() || v <= 0.0) {
                    return Err(SolveError::NotPositiveDefinite { index: i, pivot: v });
                }
                Prec::Jacobi(d.iter().map(|v| 1.0 / v).collect())
            }
            Preconditioner::BlockJacobi { blocks } => Prec::Block(BlockJacobi::new(a, blocks)?),
            Preconditioner::TwoLevel { blocks, correction } => {
                let space = self.coarse_space.as_ref().ok_or_else(|| {
                    SolveError::Other(
                        "the two-level preconditioner needs a coarse space (Pcg::set_coarse_space)"
                            .into(),
                    )
                })?;
                let bj = BlockJacobi::new(a, blocks)?;
                let co = Coarse::new(a, space, *correction)?;
                Prec::TwoLevel(bj, Box::new(co))
            }
        })
    }
}

impl LinearBackend for Pcg {
    fn name(&self) -> &'static str {
        "pcg"
    }

    /// Nothing to analyze: records the pattern id only.
    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        self.pattern_id = Some(pattern.id());
        Ok(())
    }

    /// Copies the matrix and sets the preconditioner up (inverse diagonal, block
    /// factors, coarse matrix). A non-positive diagonal entry or block pivot gives
    /// [`SolveError::NotPositiveDefinite`]. Values bit-identical to the last set-up (same
    /// pattern, preconditioner and coarse space unchanged) return at once.
    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        if a.values.len() != a.pattern.nnz() {
            self.invalidate();
            return Err(SolveError::Other(
                "matrix values do not match the pattern".into(),
            ));
        }
        if let (Some(m), Some(_)) = (&self.matrix, &self.prec) {
            if m.pattern.id() == a.pattern.id() && same_bits(&m.values, &a.values) {
                self.stats.skipped_factorizations += 1;
                return Ok(());
            }
        }
        let t = Instant::now();
        self.invalidate();
        let prec = self.setup(a);
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t.elapsed().as_secs_f64();
        self.prec = Some(prec?);
        self.matrix = Some(a.clone());
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let (a, prec) = match (&self.matrix, &mut self.prec) {
            (Some(a), Some(p)) => (a, p),
            _ => {
                return Err(SolveError::Other(
                    "solve called without a successful factorization".into(),
                ))
            }
        };
        let n = a.n();
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "right-hand side has length {}, expected {n}",
                rhs.len()
            )));
        }
        let t = Instant::now();
        self.stats.solves += 1;
        let max_it = self.max_iterations.unwrap_or(2 * n + 100);
        let work = &mut self.work;
        let mut r = rhs.to_vec();
        let mut x = vec![0.0; n];
        let bnorm = dot(&r, &r).sqrt();
        if bnorm == 0.0 {
            rhs.fill(0.0);
            self.stats.last_iterations = 0;
            self.stats.last_true_residual = 0.0;
            self.stats.solve_seconds += t.elapsed().as_secs_f64();
            return Ok(());
        }
        if !bnorm.is_finite() {
            return Err(SolveError::Other(
                "the right-hand side is not finite".into(),
            ));
        }
        let mut z = vec![0.0; n];
        let mut q = vec![0.0; n];
        let mut res = 1.0;
        let mut it = 0;
        let mut failure = None;
        if let Err(e) = prec.apply(&r, &mut z, work) {
            failure = Some(e);
        }
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        while failure.is_none() && it < max_it {
            a.mul_vec(&p, &mut q);
            let pq = dot(&p, &q);
            if pq <= 0.0 || !pq.is_finite() {
                failure = Some(SolveError::Other(format!(
                    "pcg breakdown at iteration {it}: pᵀAp = {pq:e} (matrix not positive definite?)"
                )));
                break;
            }
            let alpha = rz / pq;
            x.par_iter_mut()
                .zip(&p)
                .for_each(|(xi, pi)| *xi += alpha * pi);
            r.par_iter_mut()
                .zip(&q)
                .for_each(|(ri, qi)| *ri -= alpha * qi);
            it += 1;
            res = dot(&r, &r).sqrt() / bnorm;
            if res <= self.tolerance {
                break;
            }
            if let Err(e) = prec.apply(&r, &mut z, work) {
                failure = Some(e);
                break;
            }
            let rz_new = dot(&r, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            p.par_iter_mut()
                .zip(&z)
                .for_each(|(pi, zi)| *pi = zi + beta * *pi);
        }
        // true residual of the iterate
        a.mul_vec(&x, &mut q);
        q.par_iter_mut()
            .zip(rhs.par_iter())
            .for_each(|(qi, bi)| *qi = bi - *qi);
        let true_res = dot(&q, &q).sqrt() / bnorm;
        self.stats.iterations += it;
        self.stats.last_iterations = it;
        self.stats.last_true_residual = true_res;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        if let Some(e) = failure {
            return Err(e);
        }
        if res <= self.tolerance {
            rhs.copy_from_slice(&x);
            Ok(())
        } else {
            Err(SolveError::NoConvergence {
                iterations: it,
                residual: res,
            })
        }
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }
}
