//! [`PartialLlt`]: a supernodal Cholesky factorization that stops before a trailing block
//! of unknowns and leaves that block's Schur complement.
//!
//! For K = \[K_II K_IB; K_BI K_BB\] (interior I first, B last, n_I = |I|) it computes
//! the factor columns of I, \[L_II; L_BI\] with K_II = L_II L_IIᵀ and L_BI = K_BI L_II⁻ᵀ,
//! and the product L_BI L_BIᵀ = K_BI K_II⁻¹ K_IB of the dense Schur complement
//! C = K_BB − L_BI L_BIᵀ
//! (Saad, *Iterative methods for sparse linear systems*, 2nd ed., §14.2), without the
//! Cholesky of C that a factorization of the whole of K computes (|B|³/6 multiply-adds)
//! and without forming C back from it as K_BB − L_BB L_BBᵀ (another |B|³/6): the Schur
//! complement MUMPS returns with ICNTL(19). faer's supernodal numeric factorization runs
//! over every supernode, so this is a factorization of our own on faer's symbolic
//! structure (supernodes, their row patterns and the layout of the values, which it
//! keeps): left-looking over the supernodes of I — each gathers the updates of the
//! supernodes below it that reach its columns (one dense product each, scattered), then a
//! dense Cholesky of its diagonal block and a triangular solve of the rows below — and
//! every supernode's rows in B add to L_BI L_BIᵀ at once (one dense product L_Bs L_Bsᵀ,
//! scattered). A supernode that faer's relaxation made straddle I and B is factorized in
//! its columns of I only. Dense kernels: faer's, on `Par` as given (a fixed split of the
//! work: the same bits in any pool). The forward and backward solves with \[L_II; L_BI\]
//! are the other half ([`PartialLlt::forward`], [`PartialLlt::backward`]).

use crate::backend::SolveError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// A supernode with columns in I.
struct Sn {
    /// First (permuted) column.
    begin: usize,
    /// Its columns in I (all of them unless it straddles I and B).
    w: usize,
    /// Offset of its values in the factor's value array.
    off: usize,
    /// Rows of its value block: its full width plus its row pattern.
    nrows: usize,
    /// The rows below its first `w` (block rows w.., increasing): the rest of its diagonal
    /// rows (in B) if it straddles, then its row pattern.
    below: Vec<u32>,
    /// Index in `below` of the first row in B.
    q: usize,
}

/// The partial factorization's plan for one symbolic structure; the values live in the
/// factor's value array (faer's supernodal layout), owned by the caller.
pub(crate) struct PartialLlt {
    n_int: usize,
    nb: usize,
    sn: Vec<Sn>,
    /// Supernode (index in `sn`) of each column in I.
    sn_of: Vec<u32>,
    /// `(destination in the values, entry of K)`: the lower triangle of K's columns in I.
    a_map: Vec<(usize, usize)>,
    /// Values used: the columns in I of every supernode.
    n_values: usize,
    /// The most rows below a supernode (the length of the substitutions' work vector).
    max_below: usize,
}

impl PartialLlt {
    /// The plan for K of `n` unknowns with the symbolic structure `sym` in the permuted
    /// order where I is the first `n_int` positions; K's stored entries are given by
    /// `entries`: `(permuted row, permuted column, index of the value)`, both triangles or
    /// one (only those with row ≥ column and column < n_int are used).
    pub(crate) fn new(
        sym: &SymbolicSupernodalCholesky<u32>,
        n_int: usize,
        entries: impl Iterator<Item = (usize, usize, usize)>,
    ) -> Result<Self, SolveError> {
        let n = sym.nrows();
        let begin = sym.supernode_begin();
        let end = sym.supernode_end();
        let vals = sym.col_ptr_for_val();
        let mut sn = Vec::new();
        let mut sn_of = vec![0u32; n_int];
        for s in 0..sym.n_supernodes() {
            let (b, e) = (begin[s] as usize, end[s] as usize);
            if b >= n_int {
                break;
            }
            let pattern = sym.supernode(s).pattern();
            if pattern.windows(2).any(|p| p[0] >= p[1])
                || pattern.first().is_some_and(|&r| (r as usize) < e)
            {
                return Err(SolveError::Other(
                    "partial factorization: a supernode's rows are not sorted below it".into(),
                ));
            }
            let w = e.min(n_int) - b;
            let below: Vec<u32> = (b + w..e)
                .map(|r| r as u32)
                .chain(pattern.iter().copied())
                .collect();
            let q = below.partition_point(|&r| (r as usize) < n_int);
            for c in &mut sn_of[b..b + w] {
                *c = sn.len() as u32;
            }
            sn.push(Sn {
                begin: b,
                w,
                off: vals[s] as usize,
                nrows: e - b + pattern.len(),
                below,
                q,
            });
        }
        // where each entry of K's lower triangle in I's columns goes
        let mut a_map = Vec::new();
        for (r, c, t) in entries {
            if r < c || c >= n_int {
                continue;
            }
            let s = &sn[sn_of[c] as usize];
            let row = if r < s.begin + s.w {
                r - s.begin
            } else {
                match s.below.binary_search(&(r as u32)) {
                    Ok(i) => s.w + i,
                    Err(_) => {
                        return Err(SolveError::Other(
                            "partial factorization: an entry of K outside the factor's pattern"
                                .into(),
                        ))
                    }
                }
            };
            a_map.push((s.off + (c - s.begin) * s.nrows + row, t));
        }
        let n_values = sn.iter().map(|s| s.w * s.nrows).sum();
        let max_below = sn.iter().map(|s| s.below.len()).max().unwrap_or(0);
        Ok(Self {
            n_int,
            nb: n - n_int,
            max_below,
            sn,
            sn_of,
            a_map,
            n_values,
        })
    }

    /// Stored values of the factor's columns in I.
    pub(crate) fn n_values(&self) -> usize {
        self.n_values
    }

    /// Multiply-adds: Σ over the columns j in I of m_j (m_j + 1) / 2, m_j the column's
    /// stored entries (the diagonal included) — the elimination of column j updates the
    /// m_j (m_j − 1) / 2 entries of the lower trailing matrix its entries reach, those
    /// of C included.
    pub(crate) fn flops(&self) -> f64 {
        self.sn
            .iter()
            .map(|s| {
                (0..s.w)
                    .map(|j| {
                        let m = (s.nrows - j) as f64;
                        m * (m + 1.0) / 2.0
                    })
                    .sum::<f64>()
            })
            .sum()
    }

    /// The block of supernode `s` in `l` (column-major, `nrows × w`).
    fn block<'a>(&self, s: &Sn, l: &'a [f64]) -> MatRef<'a, f64> {
        MatRef::from_column_major_slice(&l[s.off..s.off + s.nrows * s.w], s.nrows, s.w)
    }

    /// Factorizes the columns in I of K (values `k`, indexed as the plan's entries) into
    /// `l` (faer's supernodal layout for `sym`; the columns in B are not touched) and
    /// returns L_BI L_BIᵀ = K_BI K_II⁻¹ K_IB (lower triangle, in the permuted order of
    /// B), which C = K_BB − L_BI L_BIᵀ subtracts. `Err(p)`: the pivot of permuted column
    /// p is not positive (or not a number).
    pub(crate) fn factorize(&self, k: &[f64], l: &mut [f64], par: Par) -> Result<Mat<f64>, usize> {
        let n_int = self.n_int;
        for s in &self.sn {
            l[s.off..s.off + s.nrows * s.w].fill(0.0);
        }
        for &(d, t) in &self.a_map {
            l[d] = k[t];
        }
        let max_w = self.sn.iter().map(|s| s.w).max().unwrap_or(0);
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(
            max_w,
            par,
            Default::default(),
        ));
        let mut c = Mat::<f64>::zeros(self.nb, self.nb);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); self.sn.len()];
        let mut ptr = vec![0usize; self.sn.len()];
        let mut pos = vec![0u32; n_int + self.nb];
        let mut work: Vec<f64> = Vec::new();
        for (si, s) in self.sn.iter().enumerate() {
            let (b, w) = (s.begin, s.w);
            for i in 0..w {
                pos[b + i] = i as u32;
            }
            for (i, &r) in s.below.iter().enumerate() {
                pos[r as usize] = (w + i) as u32;
            }
            // updates from the supernodes below that reach columns b..b + w
            for d in std::mem::take(&mut lists[si]) {
                let ds = &self.sn[d as usize];
                let p0 = ptr[d as usize];
                let rows = &ds.below[p0..];
                let m1 = rows.partition_point(|&r| (r as usize) < b + w);
                let kr = rows.len();
                work.resize(kr * m1, 0.0);
                let ld = self.block(ds, l).subrows(ds.w + p0, kr);
                let mut wm = MatMut::from_column_major_slice_mut(&mut work, kr, m1);
                matmul(
                    wm.as_mut(),
                    Accum::Replace,
                    ld,
                    ld.subrows(0, m1).transpose(),
                    1.0,
                    par,
                );
                let dst = &mut l[s.off..s.off + s.nrows * w];
                for j in 0..m1 {
                    let col = (rows[j] as usize - b) * s.nrows;
                    for i in j..kr {
                        dst[col + pos[rows[i] as usize] as usize] -= wm[(i, j)];
                    }
                }
                ptr[d as usize] = p0 + m1;
                if let Some(&r) = ds.below.get(p0 + m1).filter(|&&r| (r as usize) < n_int) {
                    lists[self.sn_of[r as usize] as usize].push(d);
                }
            }
            // the diagonal block, then the rows below
            let mut blk =
                MatMut::from_column_major_slice_mut(&mut l[s.off..s.off + s.nrows * w], s.nrows, w);
            let (mut top, mut bot) = blk.as_mut().split_at_row_mut(w);
            if let Err(LltError::NonPositivePivot { index }) = cholesky_in_place(
                top.as_mut(),
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            ) {
                return Err(b + index.min(w.saturating_sub(1)));
            }
            // a NaN pivot is not an error to faer's kernel
            if let Some(j) =
                (0..w).find(|&j| top[(j, j)].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
            {
                return Err(b + j);
            }
            solve_lower_triangular_in_place(top.as_ref(), bot.as_mut().transpose_mut(), par);
            // its rows in B update C
            let kb = s.below.len() - s.q;
            if kb > 0 {
                let x = bot.as_ref().subrows(s.q, kb);
                work.resize(kb * kb, 0.0);
                let mut g = MatMut::from_column_major_slice_mut(&mut work, kb, kb);
                tri_matmul(
                    g.as_mut(),
                    BlockStructure::TriangularLower,
                    Accum::Replace,
                    x,
                    BlockStructure::Rectangular,
                    x.transpose(),
                    BlockStructure::Rectangular,
                    1.0,
                    par,
                );
                let rb = &s.below[s.q..];
                for j in 0..kb {
                    let cj = rb[j] as usize - n_int;
                    for i in j..kb {
                        c[(rb[i] as usize - n_int, cj)] += g[(i, j)];
                    }
                }
            }
            if let Some(&r) = s.below.first().filter(|&&r| (r as usize) < n_int) {
                lists[self.sn_of[r as usize] as usize].push(si as u32);
            }
        }
        Ok(c)
    }

    /// Forward solve with \[L_II; L_BI\] in place on `v` (permuted order, length n):
    /// v_I ← y = L_II⁻¹ v_I and v_B ← v_B − L_BI y.
    pub(crate) fn forward(&self, l: &[f64], v: &mut [f64]) {
        // the rows below each supernode, L_below x, as one dense product into `g` and one
        // scatter (a scatter per column took 7 % of a deformable column's dynamic run)
        let mut g = vec![0.0; self.max_below];
        for s in &self.sn {
            let blk = self.block(s, l);
            let (head, tail) = v.split_at_mut(s.begin + s.w);
            let x = &mut head[s.begin..];
            solve_lower_triangular_in_place(blk.subrows(0, s.w), col_mut(x), Par::Seq);
            let nb = s.below.len();
            if nb == 0 {
                continue;
            }
            let base = s.begin + s.w;
            let g = &mut g[..nb];
            matmul(
                col_mut(g),
                Accum::Replace,
                blk.subrows(s.w, nb),
                MatRef::from_column_major_slice(x, s.w, 1),
                1.0,
                Par::Seq,
            );
            for (&r, &gi) in s.below.iter().zip(g.iter()) {
                tail[r as usize - base] -= gi;
            }
        }
    }

    /// Backward solve with \[L_II; L_BI\]ᵀ in place on `v` (permuted order): given
    /// v_B = x_B and v_I = y of [`PartialLlt::forward`], v_I ← L_IIᵀ⁻¹ (y − L_BIᵀ x_B).
    pub(crate) fn backward(&self, l: &[f64], v: &mut [f64]) {
        // the rows below each supernode gathered once into `g`, then x −= L_belowᵀ g as
        // one dense product (see `forward`)
        let mut g = vec![0.0; self.max_below];
        for s in self.sn.iter().rev() {
            let blk = self.block(s, l);
            let (head, tail) = v.split_at_mut(s.begin + s.w);
            let x = &mut head[s.begin..];
            let nb = s.below.len();
            if nb > 0 {
                let base = s.begin + s.w;
                let g = &mut g[..nb];
                for (gi, &r) in g.iter_mut().zip(&s.below) {
                    *gi = tail[r as usize - base];
                }
                matmul(
                    col_mut(x),
                    Accum::Add,
                    blk.subrows(s.w, nb).transpose(),
                    MatRef::from_column_major_slice(g, nb, 1),
                    -1.0,
                    Par::Seq,
                );
            }
            solve_upper_triangular_in_place(blk.subrows(0, s.w).transpose(), col_mut(x), Par::Seq);
        }
    }
}

/// A slice as a one-column matrix.
pub(crate) fn col_mut(v: &mut [f64]) -> MatMut<'_, f64> {
    let n = v.len();
    MatMut::from_column_major_slice_mut(v, n, 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cholesky::CholeskyCore;
    use crate::csr::{CsrMatrix, CsrPattern};
    use faer::linalg::solvers::Solve;
    use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    use std::sync::Arc;

    /// The 5-point Laplacian of an nx × ny grid plus 0.01 on the diagonal (SPD), with a
    /// few deterministic pseudo-random perturbations of the off-diagonal values.
    fn grid(nx: usize, ny: usize) -> CsrMatrix {
        let id = |i: usize, j: usize| j * nx + i;
        let mut e = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                e.push((id(i, j), id(i, j)));
                if i + 1 < nx {
                    e.push((id(i, j), id(i + 1, j)));
                    e.push((id(i + 1, j), id(i, j)));
                }
                if j + 1 < ny {
                    e.push((id(i, j), id(i, j + 1)));
                    e.push((id(i, j + 1), id(i, j)));
                }
            }
        }
        let p = Arc::new(CsrPattern::from_entries(nx * ny, e));
        let mut a = CsrMatrix::zeros(p.clone());
        for r in 0..p.n() {
            for c in p.row_cols(r).to_vec() {
                let c = c as usize;
                let v = if r == c {
                    4.01
                } else {
                    -1.0 + 0.1 * (((r.min(c) * 7 + r.max(c) * 13) % 10) as f64 / 10.0)
                };
                a.add(r, c, v);
            }
        }
        a
    }

    /// Against faer's factorization of the whole matrix in the same order (an
    /// independent computation: faer's own numeric kernel): the interior columns of the
    /// factor agree to 1e-12 relative (round-off of a Cholesky of a matrix with condition
    /// number ~1e3, summed in another order) and C = K_BB − L_BB L_BBᵀ of faer's factor
    /// to 1e-12 of its largest entry; the forward and backward solves solve K x = b to
    /// 1e-12. The last `nb` unknowns of the grid (natural order: its last rows) are B.
    #[test]
    fn partial_factorization_matches_faers_whole_factorization() {
        let (nx, ny) = (23, 31);
        let a = grid(nx, ny);
        let n = a.n();
        for nb in [nx, 2 * nx + 5, 3, 1, 7 * nx + 2] {
            let n_int = n - nb;
            // METIS-free order: the interior reversed-natural, B last (so faer's
            // supernodes are not all trivially contiguous)
            let mut fwd: Vec<u32> = (0..n_int as u32).rev().collect();
            fwd.extend(n_int as u32..n as u32);
            let mut inv = vec![0u32; n];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old as usize] = new as u32;
            }
            let mut core = CholeskyCore::llt_with_perm(fwd, inv, 1);
            core.factorize(&a).unwrap();
            let an = core.analysis.as_ref().unwrap();
            let SymbolicCholeskyRaw::Supernodal(sym) = an.symbolic.raw() else {
                panic!("not supernodal")
            };
            let pinv: Vec<usize> = match an.symbolic.perm() {
                Some(p) => p.arrays().1.iter().map(|&x| x as usize).collect(),
                None => (0..n).collect(),
            };
            assert!((n_int..n).all(|i| pinv[i] >= n_int));
            let entries = (0..n).flat_map(|r| {
                let s = a.pattern.row_ptr()[r];
                let pinv = &pinv;
                a.pattern
                    .row_cols(r)
                    .iter()
                    .enumerate()
                    .map(move |(t, &c)| (pinv[r], pinv[c as usize], s + t))
            });
            let plan = PartialLlt::new(sym, n_int, entries).unwrap();
            let mut l = vec![0.0; an.l_values.len()];
            let c = plan.factorize(&a.values, &mut l, Par::Seq).unwrap();
            // the interior columns
            let lmax = an.l_values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for s in &plan.sn {
                for j in 0..s.w {
                    for i in 0..s.nrows {
                        let k = s.off + j * s.nrows + i;
                        let d = (l[k] - an.l_values[k]).abs();
                        assert!(
                            d <= 1e-12 * lmax,
                            "entry {k}: {} vs {}",
                            l[k],
                            an.l_values[k]
                        );
                    }
                }
            }
            // K_BB − L_BI L_BIᵀ against L_BB L_BBᵀ (dense, permuted B order)
            let mut lbb = Mat::<f64>::zeros(nb, nb);
            let r = SupernodalLltRef::new(sym, &an.l_values);
            for s in 0..sym.n_supernodes() {
                let node = r.supernode(s);
                let (start, val) = (node.start(), node.val());
                for jc in 0..val.ncols() {
                    let col = start + jc;
                    if col < n_int {
                        continue;
                    }
                    for ir in jc..val.ncols() {
                        lbb[(start + ir - n_int, col - n_int)] = val[(ir, jc)];
                    }
                    for (idx, &row) in node.pattern().iter().enumerate() {
                        lbb[(row as usize - n_int, col - n_int)] = val[(val.ncols() + idx, jc)];
                    }
                }
            }
            let mut kbb = Mat::<f64>::zeros(nb, nb);
            for row in n_int..n {
                for &col in a.pattern.row_cols(row) {
                    let col = col as usize;
                    if col >= n_int {
                        kbb[(pinv[row] - n_int, pinv[col] - n_int)] = a.get(row, col);
                    }
                }
            }
            let llt = &lbb * lbb.transpose();
            let scale = kbb.norm_max();
            for j in 0..nb {
                for i in j..nb {
                    let d = (kbb[(i, j)] - c[(i, j)] - llt[(i, j)]).abs();
                    assert!(d <= 1e-12 * scale, "C({i}, {j}) off by {d:e}");
                }
            }
            // a solve: forward, dense Schur solve, backward
            let x_true: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            let mut b = vec![0.0; n];
            a.mul_vec(&x_true, &mut b);
            let mut v = vec![0.0; n];
            for i in 0..n {
                v[pinv[i]] = b[i];
            }
            plan.forward(&l, &mut v);
            let mut s = Mat::<f64>::zeros(nb, nb);
            for j in 0..nb {
                for i in 0..nb {
                    s[(i, j)] = kbb[(i, j)] - if i >= j { c[(i, j)] } else { c[(j, i)] };
                }
            }
            let xb = s
                .llt(faer::Side::Lower)
                .unwrap()
                .solve(faer::Mat::from_fn(nb, 1, |i, _| v[n_int + i]));
            for i in 0..nb {
                v[n_int + i] = xb[(i, 0)];
            }
            plan.backward(&l, &mut v);
            let err = (0..n)
                .map(|i| (v[pinv[i]] - x_true[i]).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-12 * 5.0 * 1e3, "solve error {err:e}");
        }
    }
}
