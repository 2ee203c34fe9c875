//! Deterministic parallel assembly of symmetric sparse matrices and vectors.
//!
//! An [`AssemblyPlan`] is computed once per topology (element → dof map). It owns the
//! [`CsrPattern`] and two gather maps: for every stored matrix entry (and every vector
//! entry) the list of positions in an element buffer that add into it, in a fixed order
//! (ascending element, then ascending local slot). Assembly is then two parallel passes:
//! the element kernels fill their dense blocks of one big buffer, and every entry sums
//! its contributions in the fixed order. No atomics, no locks, and the floating-point
//! result is bit-identical for any number of threads.

use crate::csr::{CsrMatrix, CsrPattern, ROW_CHUNK};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// A dof slot that is not an unknown (for example a fixed support): the rows and columns
/// of an element matrix (and the entries of an element vector) at such a slot are
/// dropped during assembly.
pub const CONSTRAINED: u32 = u32::MAX;

/// Number of elements handled by one rayon task when the element kernels run. Fixed.
const ELEM_CHUNK: usize = 256;

/// Element → dof connectivity in compressed form: element `e` has the dof slots
/// `dofs[ptr[e]..ptr[e + 1]]` (global unknown numbers, or [`CONSTRAINED`]).
#[derive(Debug, Clone)]
pub struct Connectivity {
    ptr: Vec<usize>,
    dofs: Vec<u32>,
}

impl Default for Connectivity {
    fn default() -> Self {
        Self::new()
    }
}

impl Connectivity {
    /// Empty connectivity.
    pub fn new() -> Self {
        Self {
            ptr: vec![0],
            dofs: Vec::new(),
        }
    }

    /// Appends an element with the given dof slots (global unknowns or [`CONSTRAINED`]).
    pub fn push(&mut self, dofs: &[u32]) {
        self.dofs.extend_from_slice(dofs);
        self.ptr.push(self.dofs.len());
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    /// `true` when there is no element.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Dof slots of element `e`.
    pub fn dofs(&self, e: usize) -> &[u32] {
        &self.dofs[self.ptr[e]..self.ptr[e + 1]]
    }
}

/// Pattern and scatter/gather maps for one topology; see the module documentation.
#[derive(Debug)]
pub struct AssemblyPlan {
    pattern: Arc<CsrPattern>,
    conn: Connectivity,
    /// Offset of element e's dense ne×ne block in the matrix element buffer (len n_el + 1).
    mat_offset: Vec<usize>,
    /// Offset of element e's ne-vector in the vector element buffer (len n_el + 1).
    vec_offset: Vec<usize>,
    /// For CSR entry k, its contributions are `gather_pos[gather_ptr[k]..gather_ptr[k + 1]]`.
    gather_ptr: Vec<usize>,
    gather_pos: Vec<usize>,
    /// For unknown i, its vector contributions are `vgather_pos[vgather_ptr[i]..vgather_ptr[i + 1]]`.
    vgather_ptr: Vec<usize>,
    vgather_pos: Vec<usize>,
    /// For CSR entry k = (i, j), the position of (j, i).
    transpose: Vec<usize>,
    /// Buffers reused by every assembly with this plan, so that an assembly allocates
    /// nothing: on a wall of 786,080 triangles a fresh 242 MB element buffer and a fresh
    /// array of sums per assembly spent more time in page faults than in the kernels
    /// (benches/assembly.rs: 0.274 s per assembly on 2 threads before, see
    /// docs/performance.md "Assembly").
    scratch: Mutex<Scratch>,
}

/// See [`AssemblyPlan`]'s `scratch`.
#[derive(Debug, Default)]
struct Scratch {
    /// Element matrices (`mat_offset`) and element vectors (`vec_offset`).
    mat: Vec<f64>,
    vec: Vec<f64>,
    /// Every stored entry's sum of contributions (the symmetric assembly averages it
    /// with its transpose's).
    sums: Vec<f64>,
}

/// What one chunk of rows contributes while the plan is built.
#[derive(Default)]
struct RowChunk {
    row_len: Vec<usize>,
    cols: Vec<u32>,
    gather_len: Vec<usize>,
    gather_pos: Vec<usize>,
    vgather_len: Vec<usize>,
    vgather_pos: Vec<usize>,
}

fn prefix_sum(lens: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut out = vec![0];
    let mut acc = 0;
    for l in lens {
        acc += l;
        out.push(acc);
    }
    out
}

impl AssemblyPlan {
    /// Pattern + scatter/gather maps, computed once per topology (parallel over fixed
    /// chunks of rows). Every unknown `0..n_dofs` gets a diagonal entry, even when no
    /// element touches it.
    ///
    /// # Panics
    /// If a dof slot is neither [`CONSTRAINED`] nor below `n_dofs`, or `n_dofs >= u32::MAX`.
    pub fn new(n_dofs: usize, conn: &Connectivity) -> Self {
        assert!(n_dofs < u32::MAX as usize, "too many unknowns");
        let n_el = conn.len();
        let ne = |e: usize| conn.ptr[e + 1] - conn.ptr[e];
        let mat_offset = prefix_sum((0..n_el).map(|e| ne(e) * ne(e)));
        let vec_offset = conn.ptr.clone();

        // dof -> elements (ascending, without repeats)
        let mut count = vec![0usize; n_dofs + 1];
        for e in 0..n_el {
            for (a, &d) in conn.dofs(e).iter().enumerate() {
                if d == CONSTRAINED {
                    continue;
                }
                assert!(
                    (d as usize) < n_dofs,
                    "element {e} slot {a}: dof {d} >= n_dofs = {n_dofs}"
                );
                // count once per element: skip if the same dof appeared earlier in e
                if !conn.dofs(e)[..a].contains(&d) {
                    count[d as usize + 1] += 1;
                }
            }
        }
        for i in 0..n_dofs {
            count[i + 1] += count[i];
        }
        let de_ptr = count;
        let mut fill = de_ptr.clone();
        let mut de = vec![0u32; de_ptr[n_dofs]];
        for e in 0..n_el {
            let dofs = conn.dofs(e);
            for (a, &d) in dofs.iter().enumerate() {
                if d != CONSTRAINED && !dofs[..a].contains(&d) {
                    de[fill[d as usize]] = e as u32;
                    fill[d as usize] += 1;
                }
            }
        }

        let n_chunks = n_dofs.div_ceil(ROW_CHUNK);
        let chunks: Vec<RowChunk> = (0..n_chunks)
            .into_par_iter()
            .map(|c| {
                let mut out = RowChunk::default();
                let mut pairs: Vec<(u32, usize)> = Vec::new();
                for i in c * ROW_CHUNK..((c + 1) * ROW_CHUNK).min(n_dofs) {
                    let elems = &de[de_ptr[i]..de_ptr[i + 1]];
                    let start = out.cols.len();
                    out.cols.push(i as u32);
                    for &e in elems {
                        out.cols.extend(
                            conn.dofs(e as usize)
                                .iter()
                                .copied()
                                .filter(|&d| d != CONSTRAINED),
                        );
                    }
                    let row = &mut out.cols[start..];
                    row.sort_unstable();
                    let mut len = 0;
                    for k in 0..row.len() {
                        if k == 0 || row[k] != row[len - 1] {
                            row[len] = row[k];
                            len += 1;
                        }
                    }
                    out.cols.truncate(start + len);
                    out.row_len.push(len);
                    let cols = &out.cols[start..];

                    pairs.clear();
                    let mut vlen = 0;
                    for &e in elems {
                        let e = e as usize;
                        let dofs = conn.dofs(e);
                        let m = dofs.len();
                        for (a, &da) in dofs.iter().enumerate() {
                            if da as usize != i {
                                continue;
                            }
                            out.vgather_pos.push(vec_offset[e] + a);
                            vlen += 1;
                            for (b, &db) in dofs.iter().enumerate() {
                                if db == CONSTRAINED {
                                    continue;
                                }
                                let k = cols.binary_search(&db).expect("column in row") as u32;
                                pairs.push((k, mat_offset[e] + a * m + b));
                            }
                        }
                    }
                    out.vgather_len.push(vlen);
                    pairs.sort_unstable();
                    let mut k_cur = 0u32;
                    let mut run = 0usize;
                    for &(k, pos) in &pairs {
                        while k_cur < k {
                            out.gather_len.push(run);
                            run = 0;
                            k_cur += 1;
                        }
                        run += 1;
                        out.gather_pos.push(pos);
                    }
                    while (k_cur as usize) < len {
                        out.gather_len.push(run);
                        run = 0;
                        k_cur += 1;
                    }
                }
                out
            })
            .collect();

        let row_ptr = prefix_sum(chunks.iter().flat_map(|c| c.row_len.iter().copied()));
        let mut col_idx = Vec::with_capacity(row_ptr[n_dofs]);
        let gather_ptr = prefix_sum(chunks.iter().flat_map(|c| c.gather_len.iter().copied()));
        let mut gather_pos = Vec::with_capacity(gather_ptr[gather_ptr.len() - 1]);
        let vgather_ptr = prefix_sum(chunks.iter().flat_map(|c| c.vgather_len.iter().copied()));
        let mut vgather_pos = Vec::with_capacity(vgather_ptr[n_dofs]);
        for c in &chunks {
            col_idx.extend_from_slice(&c.cols);
            gather_pos.extend_from_slice(&c.gather_pos);
            vgather_pos.extend_from_slice(&c.vgather_pos);
        }
        debug_assert_eq!(gather_ptr.len(), col_idx.len() + 1);
        let pattern = Arc::new(CsrPattern::from_parts_unchecked(n_dofs, row_ptr, col_idx));
        let mut transpose = vec![0usize; pattern.nnz()];
        {
            let rp = pattern.row_ptr();
            let ci = pattern.col_idx();
            transpose
                .par_chunks_mut(ROW_CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| {
                    let k0 = c * ROW_CHUNK;
                    // row of the first entry of the chunk
                    let mut i = rp.partition_point(|&x| x <= k0) - 1;
                    for (j, t) in chunk.iter_mut().enumerate() {
                        let k = k0 + j;
                        while rp[i + 1] <= k {
                            i += 1;
                        }
                        *t = pattern.find(ci[k] as usize, i).expect("symmetric pattern");
                    }
                });
        }
        Self {
            transpose,
            pattern,
            conn: conn.clone(),
            mat_offset,
            vec_offset,
            gather_ptr,
            gather_pos,
            vgather_ptr,
            vgather_pos,
            scratch: Mutex::new(Scratch::default()),
        }
    }

    /// The pattern of the assembled matrices.
    pub fn pattern(&self) -> &Arc<CsrPattern> {
        &self.pattern
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.conn.len()
    }

    /// Number of unknowns.
    pub fn n_dofs(&self) -> usize {
        self.pattern.n()
    }

    /// The connectivity the plan was built from.
    pub fn connectivity(&self) -> &Connectivity {
        &self.conn
    }

    /// Assembles a symmetric matrix: `kernel(e, out)` fills element e's dense row-major
    /// ne×ne matrix (ne = number of dof slots of e, including [`CONSTRAINED`] ones, whose
    /// rows and columns are then dropped); `out` is zeroed before the call.
    /// The element kernels run in parallel (rayon); each matrix entry then sums its
    /// contributions in a fixed order, so the result is bit-identical for any number of
    /// threads. The result is made exactly symmetric: entries (i, j) and (j, i) both get
    /// ½ (sum into (i, j) + sum into (j, i)), so that element matrices that are symmetric
    /// only up to rounding still give a matrix whose triangles agree to the bit (the
    /// direct backends read only one triangle). All values of `out` are overwritten.
    ///
    /// # Panics
    /// If `out` does not use this plan's pattern.
    pub fn assemble<F: Fn(usize, &mut [f64]) + Sync>(&self, kernel: F, out: &mut CsrMatrix) {
        self.check_pattern(out);
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        let Scratch { mat, sums, .. } = &mut *scratch;
        fill_element_buffer(&self.mat_offset, &kernel, mat);
        sums.resize(self.pattern.nnz(), 0.0);
        gather(&self.gather_ptr, &self.gather_pos, mat, sums);
        let t = &self.transpose;
        out.values
            .par_chunks_mut(ROW_CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let k0 = c * ROW_CHUNK;
                for (j, v) in chunk.iter_mut().enumerate() {
                    let k = k0 + j;
                    *v = 0.5 * (sums[k] + sums[t[k]]);
                }
            });
    }

    /// Assembles a matrix whose element matrices are not symmetric (a tangent stiffness
    /// with friction coupling, for an LU backend): like [`Self::assemble`], same pattern and
    /// determinism, but entry (i, j) is exactly the sum into (i, j), not symmetrised.
    ///
    /// # Panics
    /// If `out` does not use this plan's pattern.
    pub fn assemble_unsymmetric<F: Fn(usize, &mut [f64]) + Sync>(
        &self,
        kernel: F,
        out: &mut CsrMatrix,
    ) {
        self.check_pattern(out);
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        fill_element_buffer(&self.mat_offset, &kernel, &mut scratch.mat);
        gather(
            &self.gather_ptr,
            &self.gather_pos,
            &scratch.mat,
            &mut out.values,
        );
    }

    fn check_pattern(&self, out: &CsrMatrix) {
        assert_eq!(
            out.pattern.id(),
            self.pattern.id(),
            "the matrix does not use the plan's pattern"
        );
    }

    /// Assembles a vector: `kernel(e, out)` fills element e's ne-vector (zeroed before the
    /// call; entries at [`CONSTRAINED`] slots are dropped). Same determinism guarantee as
    /// [`Self::assemble`]. All entries of `out` are overwritten.
    ///
    /// # Panics
    /// If `out.len() != n_dofs`.
    pub fn assemble_vector<F: Fn(usize, &mut [f64]) + Sync>(&self, kernel: F, out: &mut [f64]) {
        assert_eq!(
            out.len(),
            self.pattern.n(),
            "the vector has the wrong length"
        );
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        fill_element_buffer(&self.vec_offset, &kernel, &mut scratch.vec);
        gather(&self.vgather_ptr, &self.vgather_pos, &scratch.vec, out);
    }
}

/// Runs the element kernels in parallel over fixed chunks of elements into `buf` (sized
/// here), each element's block zeroed just before its kernel writes it.
fn fill_element_buffer<F: Fn(usize, &mut [f64]) + Sync>(
    offset: &[usize],
    kernel: &F,
    buf: &mut Vec<f64>,
) {
    let n_el = offset.len() - 1;
    buf.resize(offset[n_el], 0.0);
    let mut pieces: Vec<(usize, &mut [f64])> = Vec::with_capacity(n_el.div_ceil(ELEM_CHUNK));
    let mut rest: &mut [f64] = buf;
    let mut e0 = 0;
    while e0 < n_el {
        let e1 = (e0 + ELEM_CHUNK).min(n_el);
        let (head, tail) = rest.split_at_mut(offset[e1] - offset[e0]);
        pieces.push((e0, head));
        rest = tail;
        e0 = e1;
    }
    pieces.into_par_iter().for_each(|(e0, piece)| {
        let e1 = (e0 + ELEM_CHUNK).min(n_el);
        let base = offset[e0];
        for e in e0..e1 {
            let block = &mut piece[offset[e] - base..offset[e + 1] - base];
            block.fill(0.0);
            kernel(e, block);
        }
    });
}

/// `out[k] = sum of buf[pos[ptr[k]..ptr[k + 1]]]`, summed in the stored order.
fn gather(ptr: &[usize], pos: &[usize], buf: &[f64], out: &mut [f64]) {
    out.par_chunks_mut(ROW_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let k0 = c * ROW_CHUNK;
            for (j, o) in chunk.iter_mut().enumerate() {
                let k = k0 + j;
                let mut s = 0.0;
                for &p in &pos[ptr[k]..ptr[k + 1]] {
                    s += buf[p];
                }
                *o = s;
            }
        });
}
