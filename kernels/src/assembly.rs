//! Deterministic parallel assembly of sparse matrices and vectors: every element matrix is
//! added straight into the CSR values, in a fixed colour order.
//!
//! An [`AssemblyPlan`] is computed once per topology (element → dof map). It owns the
//! [`CsrPattern`] and a *scatter map*: for every element, the position in the value array
//! of each entry of its element matrix (4 bytes each), or, for an element whose unknowns
//! come in pairs (x, y of a node: dofs d, d + 1 with rows of the same columns), one
//! position per 2×2 block and one row length per pair (12 numbers for a CST triangle
//! instead of 36). The elements are cut into chunks of
//! [`ELEM_CHUNK`] consecutive elements, and the chunks are coloured so that no two chunks
//! of one colour share an unknown (hence no matrix entry). An assembly runs the colours
//! one after the other; the chunks of one colour run in parallel (rayon), each on one
//! thread, element by element in ascending order, and each element's matrix is evaluated
//! into a small buffer in cache and added into the values at once. The additions into any
//! entry therefore come in one fixed order (colour, then element, then slot) whatever the
//! number of threads and however rayon splits the work: the result is bit-identical for
//! any thread count, with no atomics, no locks, no element buffer and no gather pass. Each
//! chunk first zeroes the entries whose first addition it makes (runs of consecutive
//! positions, computed with the plan), so the zeroing is done in cache just before the
//! additions, every addition is a plain `+=` (no branch) and there is no separate zeroing
//! pass over the values.
//!
//! Elements may be split into *groups* (consecutive ranges: say the triangles of the
//! blocks, then the contacts): the colours of group 0 all run before those of group 1, and
//! so on. A matrix can then be assembled in parts whose sum is bit-identical to the whole
//! ([`AssemblyPlan::assemble_groups`] onto a base holding the earlier groups), and a few
//! changed elements can be re-assembled alone ([`AssemblyPlan::reassemble`]).
//!
//! Why hand-written rather than a crate: faer's `SparseColMat::new_from_argsort` sums
//! triplets through an argsort (8-byte indices and a value per triplet: the byte traffic
//! of the element-buffer design this replaces, benches/assembly.rs), and no crate offers
//! deterministic colour-ordered scatter into a fixed CSR pattern.

use crate::csr::{CsrMatrix, CsrPattern, ROW_CHUNK};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::{Arc, OnceLock};
use topology::{build_pattern, colour_chunks};

mod topology;

/// A dof slot that is not an unknown (for example a fixed support): the rows and columns
/// of an element matrix (and the entries of an element vector) at such a slot are
/// dropped during assembly.
pub const CONSTRAINED: u32 = u32::MAX;

/// Number of consecutive elements in one chunk (the unit of work of one thread, and of
/// the colouring). Fixed, so that nothing depends on the thread count.
pub const ELEM_CHUNK: usize = 2048;

/// Scatter position of a slot pair with a [`CONSTRAINED`] row or column.
const SKIP: u32 = u32::MAX;

/// How an element kernel hands over its matrix, and how it is added into the result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// The kernel writes the upper triangle of a symmetric m×m matrix, packed by rows:
    /// (0,0), (0,1), …, (0,m−1), (1,1), …, (m−1,m−1) (m(m+1)/2 values). Each value goes
    /// into both (i, j) and (j, i), so the result is symmetric to the bit.
    Packed,
    /// The kernel writes a full row-major m×m matrix, symmetric up to round-off; entries
    /// (a, b) and (b, a) both receive ½(K_ab + K_ba), so the result is symmetric to the bit.
    Symmetrised,
    /// The kernel writes a full row-major m×m matrix, added as it is (an unsymmetric
    /// tangent, for an LU backend).
    Unsymmetric,
}

impl Form {
    /// Length of the element buffer for an element with `m` dof slots.
    pub fn buffer_len(self, m: usize) -> usize {
        match self {
            Form::Packed => m * (m + 1) / 2,
            Form::Symmetrised | Form::Unsymmetric => m * m,
        }
    }
}

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

    /// Number of dof slots of element `e`.
    fn slots(&self, e: usize) -> usize {
        self.ptr[e + 1] - self.ptr[e]
    }
}

/// Pattern, scatter map and colour order for one topology; see the module documentation.
#[derive(Debug)]
pub struct AssemblyPlan {
    pattern: Arc<CsrPattern>,
    conn: Connectivity,
    /// Group g is the elements `group_start[g]..group_start[g + 1]`.
    group_start: Vec<usize>,
    /// Chunk c is the elements `chunk_start[c]..chunk_start[c + 1]`; its elements' scatter
    /// maps follow one another from `map[chunk_map[c]]`.
    chunk_start: Vec<usize>,
    chunk_map: Vec<usize>,
    /// Colour of every chunk; colours are numbered in the order they run (group by group).
    chunk_colour: Vec<u32>,
    /// The chunks of colour k are `colour_chunks[colour_ptr[k]..colour_ptr[k + 1]]`.
    colour_ptr: Vec<usize>,
    colour_chunks: Vec<u32>,
    /// The colours of group g are `group_colour[g]..group_colour[g + 1]`.
    group_colour: Vec<usize>,
    /// Whether element e's map is paired (see `map`).
    paired: Vec<bool>,
    /// Whether every element of chunk c is paired with 6 slots (a CST triangle, a
    /// vertex-to-edge contact between deformable blocks): its maps are then 12 numbers
    /// each, and the chunk runs a loop without per-element lookups.
    chunk_paired6: Vec<bool>,
    /// The entries whose first addition (in the order of a whole assembly) chunk c makes,
    /// as runs (start, length) of consecutive positions:
    /// `zero_runs[chunk_zero[c]..chunk_zero[c + 1]]`. The chunk zeroes them before its
    /// elements add into them.
    chunk_zero: Vec<usize>,
    zero_runs: Vec<(u32, u32)>,
    /// The scatter maps of the elements, one after the other. A *general* map (m slots)
    /// has one position per slot pair, m² of them, in the order (0,0), (0,1), (1,0), (0,2),
    /// (2,0), …, (1,1), (1,2), (2,1), …: each diagonal pair, then each pair right of it
    /// followed by its mirror. A *paired* map (slots 2i, 2i + 1 hold dofs d, d + 1, the
    /// rows d and d + 1 have the same columns, the unknowns are distinct and the four
    /// has the n = m/2 row lengths of rows dofs[2i], then one position per block, the
    /// position of entry (dofs[2i], dofs[2j]), in the same order over the n nodes: the
    /// block's other entries are at +1, + row length and + row length + 1. [`SKIP`] for
    /// a constrained slot.
    map: Vec<u32>,
    /// Entries into which no element adds (the diagonal of an unknown no element
    /// touches): every assembly zeroes them.
    untouched: Vec<u32>,
    /// `first_in_group[g]`: the entries whose first addition comes from group g (empty
    /// for g = 0); an assembly that stops before group g zeroes them.
    first_in_group: Vec<Vec<u32>>,
    /// dof → elements touching it (ascending), built by the first [`Self::reassemble`].
    adjacency: OnceLock<(Vec<usize>, Vec<u32>)>,
    /// Where every element's scatter map starts in `map` (`n_elements + 1` offsets), built
    /// by the first [`Self::general_map`]: the update path looks up maps of elements
    /// scattered over the plan, which a walk along each one's chunk made cost more than a
    /// whole assembly on the rigid P2 wall (docs/performance.md).
    map_start: OnceLock<Vec<usize>>,
}

/// The value array of the matrix being assembled, shared by the threads of one colour.
/// Chunks of one colour share no unknown, so no two threads ever touch the same entry.
#[derive(Clone, Copy)]
struct SharedValues(*mut f64);
// SAFETY: see the type's documentation: concurrent accesses are to disjoint entries.
unsafe impl Send for SharedValues {}
unsafe impl Sync for SharedValues {}

impl SharedValues {
    /// Pointer to entry `k` (a method, so that closures capture the whole `Sync` wrapper).
    ///
    /// # Safety
    /// `k` is within the array.
    #[inline(always)]
    unsafe fn at(self, k: usize) -> *mut f64 {
        // SAFETY: as the function's contract
        unsafe { self.0.add(k) }
    }
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

/// Calls `f(pair, a, b)` for the slot pairs of an m×m element matrix in scatter order
/// (see [`AssemblyPlan`]'s `scatter`).
fn for_pairs(m: usize, mut f: impl FnMut(usize, usize, usize)) {
    let mut s = 0;
    for a in 0..m {
        f(s, a, a);
        s += 1;
        for b in a + 1..m {
            f(s, a, b);
            f(s + 1, b, a);
            s += 2;
        }
    }
}

impl AssemblyPlan {
    /// Pattern, scatter map and colouring for one group of elements; see
    /// [`Self::with_groups`].
    pub fn new(n_dofs: usize, conn: &Connectivity) -> Self {
        Self::with_groups(n_dofs, conn, &[conn.len()])
    }

    /// Pattern, scatter map and colouring, computed once per topology. `group_ends`:
    /// the element index at which each group ends (increasing, the last one
    /// `conn.len()`); the groups' colours run in this order. Every unknown `0..n_dofs`
    /// gets a diagonal entry, even when no element touches it.
    ///
    /// # Panics
    /// If a dof slot is neither [`CONSTRAINED`] nor below `n_dofs`, if `n_dofs >=
    /// u32::MAX`, if the pattern has 2³² − 1 entries or more (the scatter map holds
    /// 32-bit positions), or if `group_ends` is not as described.
    pub fn with_groups(n_dofs: usize, conn: &Connectivity, group_ends: &[usize]) -> Self {
        assert!(n_dofs < u32::MAX as usize, "too many unknowns");
        let n_el = conn.len();
        assert!(
            group_ends.last() == Some(&n_el) && group_ends.windows(2).all(|w| w[0] <= w[1]),
            "group ends {group_ends:?} must increase to the number of elements, {n_el}"
        );
        let pattern = Arc::new(build_pattern(n_dofs, conn));
        assert!(
            pattern.nnz() < SKIP as usize,
            "{} stored entries: the scatter map holds 32-bit positions",
            pattern.nnz()
        );
        let mut group_start = vec![0];
        group_start.extend_from_slice(group_ends);

        // chunks of ELEM_CHUNK elements, never across a group boundary
        let mut chunk_start = vec![0];
        for g in 0..group_ends.len() {
            let mut e = group_start[g];
            while e < group_start[g + 1] {
                e = (e + ELEM_CHUNK).min(group_start[g + 1]);
                chunk_start.push(e);
            }
        }
        let n_chunks = chunk_start.len() - 1;
        let (chunk_colour, group_colour) = colour_chunks(n_dofs, conn, &group_start, &chunk_start);
        let n_colours = group_colour[group_colour.len() - 1];
        let colour_ptr = prefix_sum(
            (0..n_colours).map(|k| chunk_colour.iter().filter(|&&c| c as usize == k).count()),
        );
        let mut colour_chunks = vec![0u32; n_chunks];
        let mut fill = colour_ptr.clone();
        for (c, &k) in chunk_colour.iter().enumerate() {
            colour_chunks[fill[k as usize]] = c as u32;
            fill[k as usize] += 1;
        }

        // general maps of every element, in parallel over chunks
        let chunk_general = prefix_sum((0..n_chunks).map(|c| {
            (chunk_start[c]..chunk_start[c + 1])
                .map(|e| conn.slots(e).pow(2))
                .sum()
        }));
        let mut general = vec![SKIP; chunk_general[n_chunks]];
        for_chunk_pieces(&mut general, &chunk_general, |c, piece| {
            let mut s = 0;
            for e in chunk_start[c]..chunk_start[c + 1] {
                let dofs = conn.dofs(e);
                let m = dofs.len();
                for_pairs(m, |k, a, b| {
                    let (i, j) = (dofs[a], dofs[b]);
                    if i != CONSTRAINED && j != CONSTRAINED {
                        let p = pattern
                            .find(i as usize, j as usize)
                            .expect("entry in pattern");
                        piece[s + k] = p as u32;
                    }
                });
                s += m * m;
            }
        });

        // the first addition into every entry, in the order of a whole assembly: which
        // chunk makes it
        let nnz = pattern.nnz();
        let mut seen = vec![false; nnz];
        let mut first_in_group = vec![Vec::new(); group_ends.len()];
        let mut chunk_first = vec![Vec::new(); n_chunks];
        for g in 0..group_ends.len() {
            for &c in &colour_chunks[colour_ptr[group_colour[g]]..colour_ptr[group_colour[g + 1]]] {
                let c = c as usize;
                for &p in &general[chunk_general[c]..chunk_general[c + 1]] {
                    if p != SKIP && !seen[p as usize] {
                        seen[p as usize] = true;
                        if g > 0 {
                            first_in_group[g].push(p);
                        }
                        chunk_first[c].push(p);
                    }
                }
            }
        }
        let untouched = (0..nnz as u32).filter(|&k| !seen[k as usize]).collect();
        let chunk_runs: Vec<Vec<(u32, u32)>> = chunk_first
            .into_par_iter()
            .map(|mut ps| {
                ps.sort_unstable();
                let mut runs: Vec<(u32, u32)> = Vec::new();
                for p in ps {
                    match runs.last_mut() {
                        Some((s, l)) if *s + *l == p => *l += 1,
                        _ => runs.push((p, 1)),
                    }
                }
                runs
            })
            .collect();
        let chunk_zero = prefix_sum(chunk_runs.iter().map(Vec::len));
        let zero_runs = chunk_runs.concat();

        // paired maps where they apply
        let paired: Vec<bool> = (0..n_el)
            .into_par_iter()
            .map(|e| is_paired(&pattern, conn.dofs(e)))
            .collect();
        let chunk_paired6 = (0..n_chunks)
            .map(|c| (chunk_start[c]..chunk_start[c + 1]).all(|e| paired[e] && conn.slots(e) == 6))
            .collect();
        let chunk_map = prefix_sum((0..n_chunks).map(|c| {
            (chunk_start[c]..chunk_start[c + 1])
                .map(|e| map_len(conn.slots(e), paired[e]))
                .sum()
        }));
        let mut map = vec![SKIP; chunk_map[n_chunks]];
        for_chunk_pieces(&mut map, &chunk_map, |c, piece| {
            let (mut s, mut g) = (0, chunk_general[c]);
            for e in chunk_start[c]..chunk_start[c + 1] {
                let dofs = conn.dofs(e);
                let m = dofs.len();
                let gen = &general[g..g + m * m];
                let out = &mut piece[s..s + map_len(m, paired[e])];
                if paired[e] {
                    let n = m / 2;
                    let (lens, blocks) = out.split_at_mut(n);
                    for (i, l) in lens.iter_mut().enumerate() {
                        *l = pattern.row_cols(dofs[2 * i] as usize).len() as u32;
                    }
                    let mut k = 0;
                    for_pairs(n, |_, i, j| {
                        blocks[k] = gen[general_index(m, 2 * i, 2 * j)];
                        k += 1;
                    });
                } else {
                    out.copy_from_slice(gen);
                }
                s += out.len();
                g += m * m;
            }
        });

        Self {
            pattern,
            conn: conn.clone(),
            group_start,
            chunk_start,
            chunk_map,
            chunk_colour,
            colour_ptr,
            colour_chunks,
            group_colour,
            paired,
            chunk_paired6,
            chunk_zero,
            zero_runs,
            map,
            untouched,
            first_in_group,
            adjacency: OnceLock::new(),
            map_start: OnceLock::new(),
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

    /// Number of element groups.
    pub fn n_groups(&self) -> usize {
        self.group_start.len() - 1
    }

    /// The elements of group `g`.
    pub fn group(&self, g: usize) -> Range<usize> {
        self.group_start[g]..self.group_start[g + 1]
    }

    /// Number of colours of group `g` (how many times an assembly of the group waits for
    /// all threads).
    pub fn n_colours(&self, g: usize) -> usize {
        self.group_colour[g + 1] - self.group_colour[g]
    }

    /// Length of group `g`'s scatter maps (4-byte numbers).
    pub fn map_len(&self, g: usize) -> usize {
        let c0 = self.chunk_of(self.group_start[g]);
        let c1 = self.chunk_of(self.group_start[g + 1]);
        self.chunk_map[c1] - self.chunk_map[c0]
    }

    /// Number of group `g`'s elements with a paired scatter map.
    pub fn n_paired(&self, g: usize) -> usize {
        self.paired[self.group(g)].iter().filter(|&&p| p).count()
    }

    /// Number of stored entries into which group `g`'s elements add.
    pub fn entries_of_group(&self, g: usize) -> usize {
        let mut seen = vec![false; self.pattern.nnz()];
        let mut pos = Vec::new();
        for e in self.group(g) {
            self.general_map(e, &mut pos);
            for &p in &pos {
                if p != SKIP {
                    seen[p as usize] = true;
                }
            }
        }
        seen.iter().filter(|&&s| s).count()
    }

    /// The chunk that starts at element `e` (or the end, for `e = n_elements`).
    fn chunk_of(&self, e: usize) -> usize {
        self.chunk_start.partition_point(|&s| s < e)
    }

    /// Assembles a symmetric matrix from element matrices symmetric up to round-off:
    /// `kernel(e, out)` fills element e's dense row-major m×m matrix (m = number of dof
    /// slots of e, including [`CONSTRAINED`] ones, whose rows and columns are dropped);
    /// `out` is zeroed before the call. Entries (a, b) and (b, a) of an element both add
    /// ½(K_ab + K_ba), so the result is symmetric to the bit (the direct backends read only
    /// one triangle). Bit-identical for any number of threads; all values of `out` are
    /// overwritten.
    ///
    /// # Panics
    /// If `out` does not use this plan's pattern.
    pub fn assemble<F: Fn(usize, &mut [f64]) + Sync>(&self, kernel: F, out: &mut CsrMatrix) {
        self.assemble_groups(Form::Symmetrised, 0..self.n_groups(), None, kernel, out);
    }

    /// Assembles a symmetric matrix from the packed upper triangles of its element
    /// matrices ([`Form::Packed`]): half the kernel's writes, and symmetric to the bit by
    /// construction. Otherwise as [`Self::assemble`].
    ///
    /// # Panics
    /// If `out` does not use this plan's pattern.
    pub fn assemble_packed<F: Fn(usize, &mut [f64]) + Sync>(&self, kernel: F, out: &mut CsrMatrix) {
        self.assemble_groups(Form::Packed, 0..self.n_groups(), None, kernel, out);
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
        self.assemble_groups(Form::Unsymmetric, 0..self.n_groups(), None, kernel, out);
    }

    /// Assembles the elements of the groups `groups` onto `base`: `out = base + Σ`
    /// (element matrices of those groups). With `groups.start == 0`, `base` must be `None`
    /// (the sum starts from zero); otherwise `base` must hold the result of an assembly of
    /// the groups `0..groups.start` (any [`Form`]), and then `out` is bit-identical to an
    /// assembly of the groups `0..groups.end` in one call: the additions into every entry
    /// come in the same order. Entries no element of `0..groups.end` adds into are zero.
    /// `kernel(e, buf)` fills element e's matrix in the given `form` (`buf` zeroed before
    /// the call; [`Form::buffer_len`] values). Bit-identical for any number of threads.
    ///
    /// # Panics
    /// If `out` (or `base`) does not use this plan's pattern, or `base` is given exactly
    /// when `groups.start == 0`, or `groups` is not within `0..n_groups()`.
    pub fn assemble_groups<F: Fn(usize, &mut [f64]) + Sync>(
        &self,
        form: Form,
        groups: Range<usize>,
        base: Option<&CsrMatrix>,
        kernel: F,
        out: &mut CsrMatrix,
    ) {
        self.assemble_groups_of(form, groups, base, None, kernel, out);
    }

    /// [`Self::assemble_groups`] over the elements `e` with `active[e]` only (all of them
    /// with `None`): the others are skipped, their kernel never called. The rows every
    /// element of which (every element with a slot at the row's unknown) is active come
    /// out bit-identical to those of [`Self::assemble_groups`] (the same additions in the
    /// same order); the values of the other rows are unspecified. A distributed run
    /// assembles the rows of its own unknowns this way, `active` marking the elements
    /// that touch one of them.
    ///
    /// # Panics
    /// As [`Self::assemble_groups`], or if `active` does not have one flag per element.
    pub fn assemble_groups_of<F: Fn(usize, &mut [f64]) + Sync>(
        &self,
        form: Form,
        groups: Range<usize>,
        base: Option<&CsrMatrix>,
        active: Option<&[bool]>,
        kernel: F,
        out: &mut CsrMatrix,
    ) {
        if let Some(a) = active {
            assert_eq!(a.len(), self.n_elements(), "one flag per element");
        }
        self.check_pattern(out);
        assert!(
            groups.start <= groups.end && groups.end <= self.n_groups(),
            "groups {groups:?} of {}",
            self.n_groups()
        );
        let values = SharedValues(out.values.as_mut_ptr());
        match base {
            None => {
                assert!(groups.start == 0, "groups after the first need a base");
                // SAFETY: the untouched entries are distinct positions within `values`
                unsafe { zero_entries(values, &self.untouched) };
            }
            Some(b) => {
                assert!(
                    groups.start > 0,
                    "the first group starts from zero, not a base"
                );
                self.check_pattern(b);
                out.values
                    .par_chunks_mut(ROW_CHUNK * 8)
                    .zip(b.values.par_chunks(ROW_CHUNK * 8))
                    .for_each(|(o, b)| o.copy_from_slice(b));
            }
        }
        for later in &self.first_in_group[groups.end..] {
            // SAFETY: distinct positions within `values`
            unsafe { zero_entries(values, later) };
        }
        let colours = self.group_colour[groups.start]..self.group_colour[groups.end];
        match form {
            Form::Packed => self.run::<PACKED, F>(colours, &kernel, active, values),
            Form::Symmetrised => self.run::<SYMMETRISED, F>(colours, &kernel, active, values),
            Form::Unsymmetric => self.run::<UNSYMMETRIC, F>(colours, &kernel, active, values),
        }
    }

    /// Runs the colours `colours` in order, each colour's chunks in parallel, skipping the
    /// elements not `active` (when given). Each chunk first zeroes the entries whose first
    /// addition it makes (in cache, just before its additions), then adds its elements.
    fn run<const FORM: u8, F: Fn(usize, &mut [f64]) + Sync>(
        &self,
        colours: Range<usize>,
        kernel: &F,
        active: Option<&[bool]>,
        values: SharedValues,
    ) {
        let buffer_len = |m: usize| {
            if FORM == PACKED {
                m * (m + 1) / 2
            } else {
                m * m
            }
        };
        for k in colours {
            let chunks = &self.colour_chunks[self.colour_ptr[k]..self.colour_ptr[k + 1]];
            chunks.par_iter().for_each(|&c| {
                let c = c as usize;
                for &(start, len) in &self.zero_runs[self.chunk_zero[c]..self.chunk_zero[c + 1]] {
                    // SAFETY: the runs are positions within the values, and only this
                    // chunk adds into them in this colour (chunks of one colour share no
                    // unknown)
                    unsafe { std::ptr::write_bytes(values.at(start as usize), 0, len as usize) };
                }
                let elements = self.chunk_start[c]..self.chunk_start[c + 1];
                let mut s = self.chunk_map[c];
                if self.chunk_paired6[c] {
                    // every element a paired 6-slot one (12 map numbers): no per-element
                    // lookups, and n = 3 a literal so that everything unrolls
                    let maps = &self.map[s..s + 12 * elements.len()];
                    for (e, map) in elements.zip(maps.chunks_exact(12)) {
                        if active.is_some_and(|a| !a[e]) {
                            continue;
                        }
                        let mut b = [0.0; 36];
                        let b = &mut b[..buffer_len(6)];
                        kernel(e, b);
                        // SAFETY: the map's positions are within the values, and no other
                        // thread touches them (chunks of one colour share no unknown)
                        unsafe { scatter_paired::<FORM>(3, b, map, values) };
                    }
                    return;
                }
                let mut buf = Vec::new();
                for e in elements {
                    let m = self.conn.slots(e);
                    let paired = self.paired[e];
                    let map = &self.map[s..s + map_len(m, paired)];
                    s += map.len();
                    if active.is_some_and(|a| !a[e]) {
                        continue;
                    }
                    // SAFETY (every scatter): chunks of one colour share no unknown, so this
                    // thread is the only one touching these positions, all within the values
                    if paired && m == 4 {
                        // a contact between deformable nodes: n = 2 a literal
                        let mut b = [0.0; 16];
                        let b = &mut b[..buffer_len(4)];
                        kernel(e, b);
                        unsafe { scatter_paired::<FORM>(2, b, map, values) };
                        continue;
                    }
                    buf.clear();
                    buf.resize(buffer_len(m), 0.0);
                    kernel(e, &mut buf);
                    if paired {
                        unsafe { scatter_paired::<FORM>(m / 2, &buf, map, values) };
                    } else {
                        scatter_element::<FORM, _>(m, &buf, map, |p, v| unsafe {
                            put(values, p, v)
                        });
                    }
                }
            });
        }
    }

    /// Re-assembles only the entries the elements `changed` add into, after their
    /// matrices changed: `out` must hold an assembly (any path, any [`Form`] whose element
    /// values are those of `form` for the unchanged elements) of all groups with the old
    /// element matrices, and `base` the assembly of the groups before the first group of
    /// a changed element (`None` when that is group 0). Every entry a changed element adds
    /// into is recomputed from `base` and all the elements of the later groups that add
    /// into it, in the order of a whole assembly, so `out` becomes bit-identical to a
    /// whole assembly with the new matrices; the other entries are left as they are.
    /// Sequential: meant for a few changed elements (a few percent of a group at most;
    /// past that, [`Self::assemble_groups`] onto `base` is faster).
    ///
    /// # Panics
    /// If `out` or `base` does not use this plan's pattern, an element is out of range,
    /// or `base` is given exactly when a changed element is in group 0.
    pub fn reassemble<F: Fn(usize, &mut [f64])>(
        &self,
        form: Form,
        changed: &[usize],
        base: Option<&CsrMatrix>,
        kernel: F,
        out: &mut CsrMatrix,
    ) {
        self.check_pattern(out);
        let Some(&e_min) = changed.iter().min() else {
            return;
        };
        assert!(
            changed.iter().all(|&e| e < self.n_elements()),
            "element out of range"
        );
        let g0 = self.group_start.partition_point(|&s| s <= e_min) - 1;
        assert_eq!(
            base.is_some(),
            g0 > 0,
            "a base exactly when group 0 is unchanged"
        );
        let (adj_ptr, adj) = self.adjacency.get_or_init(|| self.dof_elements());

        // the entries to recompute
        let nnz = self.pattern.nnz();
        let mut marked = vec![0u64; nnz.div_ceil(64)];
        let mut entries = Vec::new();
        let mut pos = Vec::new();
        for &e in changed {
            self.general_map(e, &mut pos);
            for &p in &pos {
                let k = p as usize;
                if p != SKIP && marked[k / 64] & (1 << (k % 64)) == 0 {
                    marked[k / 64] |= 1 << (k % 64);
                    entries.push(k);
                }
            }
        }
        let is_marked = |p: u32| {
            let k = p as usize;
            p != SKIP && marked[k / 64] & (1 << (k % 64)) != 0
        };
        // the elements of groups ≥ g0 that add into one of them, in assembly order
        let mut elems: Vec<u32> = changed
            .iter()
            .flat_map(|&e| self.conn.dofs(e))
            .filter(|&&d| d != CONSTRAINED)
            .flat_map(|&d| &adj[adj_ptr[d as usize]..adj_ptr[d as usize + 1]])
            .copied()
            .filter(|&f| f as usize >= self.group_start[g0])
            .collect();
        elems.sort_unstable_by_key(|&f| (self.chunk_colour[self.chunk_of_element(f as usize)], f));
        elems.dedup();
        elems.retain(|&f| {
            self.general_map(f as usize, &mut pos);
            pos.iter().any(|&p| is_marked(p))
        });

        for &k in &entries {
            out.values[k] = base.map_or(0.0, |b| b.values[k]);
        }
        let values = SharedValues(out.values.as_mut_ptr());
        let mut buf = Vec::new();
        for &f in &elems {
            let f = f as usize;
            let m = self.conn.slots(f);
            buf.clear();
            buf.resize(form.buffer_len(m), 0.0);
            kernel(f, &mut buf);
            self.general_map(f, &mut pos);
            let pos = &pos[..];
            let put_marked = |p: u32, v: f64| {
                if is_marked(p) {
                    // SAFETY: a position of the plan's pattern in `out`, one thread
                    unsafe { put(values, p, v) }
                }
            };
            match form {
                Form::Packed => scatter_element::<PACKED, _>(m, &buf, pos, put_marked),
                Form::Symmetrised => scatter_element::<SYMMETRISED, _>(m, &buf, pos, put_marked),
                Form::Unsymmetric => scatter_element::<UNSYMMETRIC, _>(m, &buf, pos, put_marked),
            }
        }
    }

    /// The chunk holding element `e`.
    fn chunk_of_element(&self, e: usize) -> usize {
        self.chunk_start.partition_point(|&s| s <= e) - 1
    }

    /// Element `e`'s scatter positions as a general map (see [`AssemblyPlan`]'s `map`),
    /// into `out`.
    fn general_map(&self, e: usize, out: &mut Vec<u32>) {
        let starts = self.map_start.get_or_init(|| {
            prefix_sum((0..self.n_elements()).map(|f| map_len(self.conn.slots(f), self.paired[f])))
        });
        let m = self.conn.slots(e);
        let map = &self.map[starts[e]..starts[e + 1]];
        out.clear();
        if !self.paired[e] {
            out.extend_from_slice(map);
            return;
        }
        let n = m / 2;
        let (lens, blocks) = map.split_at(n);
        out.resize(m * m, SKIP);
        for_pairs(m, |k, a, b| {
            let p = blocks[general_index(n, a / 2, b / 2)];
            out[k] = p + (a % 2) as u32 * lens[a / 2] + (b % 2) as u32;
        });
    }

    /// dof → elements touching it, ascending (CSR arrays).
    fn dof_elements(&self) -> (Vec<usize>, Vec<u32>) {
        let n = self.n_dofs();
        let mut count = vec![0usize; n + 1];
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for e in 0..self.n_elements() {
                let dofs = self.conn.dofs(e);
                for (a, &d) in dofs.iter().enumerate() {
                    if d != CONSTRAINED && !dofs[..a].contains(&d) {
                        f(e, d);
                    }
                }
            }
        };
        each(&mut |_, d| count[d as usize + 1] += 1);
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut adj = vec![0u32; count[n]];
        each(&mut |e, d| {
            adj[fill[d as usize]] = e as u32;
            fill[d as usize] += 1;
        });
        (count, adj)
    }

    fn check_pattern(&self, out: &CsrMatrix) {
        assert_eq!(
            out.pattern.id(),
            self.pattern.id(),
            "the matrix does not use the plan's pattern"
        );
    }

    /// Assembles a vector: `kernel(e, out)` fills element e's m-vector (zeroed before the
    /// call; entries at [`CONSTRAINED`] slots are dropped). Summed in the colour order of
    /// the matrices, so bit-identical for any number of threads. All entries of `out` are
    /// overwritten.
    ///
    /// # Panics
    /// If `out.len() != n_dofs`.
    pub fn assemble_vector<F: Fn(usize, &mut [f64]) + Sync>(&self, kernel: F, out: &mut [f64]) {
        assert_eq!(
            out.len(),
            self.pattern.n(),
            "the vector has the wrong length"
        );
        out.fill(0.0);
        let values = SharedValues(out.as_mut_ptr());
        for k in 0..self.group_colour[self.n_groups()] {
            let chunks = &self.colour_chunks[self.colour_ptr[k]..self.colour_ptr[k + 1]];
            chunks.par_iter().for_each(|&c| {
                let mut buf = Vec::new();
                for e in self.chunk_start[c as usize]..self.chunk_start[c as usize + 1] {
                    let dofs = self.conn.dofs(e);
                    buf.clear();
                    buf.resize(dofs.len(), 0.0);
                    kernel(e, &mut buf);
                    for (&d, &v) in dofs.iter().zip(&buf) {
                        if d != CONSTRAINED {
                            // SAFETY: chunks of one colour share no unknown; d < n_dofs
                            unsafe { *values.at(d as usize) += v };
                        }
                    }
                }
            });
        }
    }
}

/// Expands a packed upper triangle ([`Form::Packed`]) into a full row-major m×m matrix.
pub fn unpack_symmetric(m: usize, packed: &[f64], full: &mut [f64]) {
    let mut t = 0;
    for a in 0..m {
        for b in a..m {
            full[a * m + b] = packed[t];
            full[b * m + a] = packed[t];
            t += 1;
        }
    }
}

const PACKED: u8 = 0;
const SYMMETRISED: u8 = 1;
const UNSYMMETRIC: u8 = 2;

/// Hands the values of one element matrix (`buf`, in the form `FORM`) to `put` with their
/// scatter positions, in scatter order. `m` is passed as a literal where it is known (6),
/// so that the loops unroll.
#[inline(always)]
fn scatter_element<const FORM: u8, P: FnMut(u32, f64)>(
    m: usize,
    buf: &[f64],
    pos: &[u32],
    mut put: P,
) {
    let mut s = 0;
    let mut t = 0;
    for a in 0..m {
        put(
            pos[s],
            if FORM == PACKED {
                buf[t]
            } else {
                buf[a * m + a]
            },
        );
        s += 1;
        t += 1;
        for b in a + 1..m {
            let (x, y) = match FORM {
                PACKED => (buf[t], buf[t]),
                SYMMETRISED => {
                    let v = 0.5 * (buf[a * m + b] + buf[b * m + a]);
                    (v, v)
                }
                _ => (buf[a * m + b], buf[b * m + a]),
            };
            put(pos[s], x);
            put(pos[s + 1], y);
            s += 2;
            t += 1;
        }
    }
}

/// Adds `v` into the entry at scatter position `p` (nothing for [`SKIP`]).
///
/// # Safety
/// `p` is [`SKIP`] or within the array `values` points to, and no other thread accesses
/// it.
#[inline(always)]
unsafe fn put(values: SharedValues, p: u32, v: f64) {
    if p != SKIP {
        // SAFETY: as the function's contract
        unsafe { *values.at(p as usize) += v };
    }
}

/// Adds the matrix of a paired element (n nodes, `buf` in the form `FORM`) through its
/// paired map (see [`AssemblyPlan`]'s `map`): block by block, each block as two pairs of
/// consecutive entries (one 16-byte load, add and store each). The same additions, in the same order per entry, as
/// [`scatter_element`] on the general map. Plain loops (no closures), so that with a
/// literal `n` everything unrolls into constant offsets.
///
/// # Safety
/// The map's positions are within the array `values` points to, and no other thread
/// accesses them.
#[inline(always)]
unsafe fn scatter_paired<const FORM: u8>(n: usize, buf: &[f64], map: &[u32], values: SharedValues) {
    let (lens, blocks) = map.split_at(n);
    let mut k = 0;
    for i in 0..n {
        for j in i..n {
            // SAFETY: as the function's contract
            unsafe {
                add_block::<FORM>(n, buf, i, j, lens[i], blocks[k], values);
                k += 1;
                if j > i {
                    add_block::<FORM>(n, buf, j, i, lens[j], blocks[k], values);
                    k += 1;
                }
            }
        }
    }
}

/// Adds block (i, j) (slots 2i, 2i + 1 by 2j, 2j + 1) of a paired element's matrix at
/// position `p` (row length `len`).
///
/// # Safety
/// As [`scatter_paired`].
#[inline(always)]
unsafe fn add_block<const FORM: u8>(
    n: usize,
    buf: &[f64],
    i: usize,
    j: usize,
    len: u32,
    p: u32,
    values: SharedValues,
) {
    let m = 2 * n;
    let val = |a: usize, b: usize| match FORM {
        PACKED => {
            let (r, c) = if a <= b { (a, b) } else { (b, a) };
            buf[r * (2 * m - r + 1) / 2 + c - r]
        }
        SYMMETRISED if a != b => 0.5 * (buf[a * m + b] + buf[b * m + a]),
        _ => buf[a * m + b],
    };
    let r0 = p as usize;
    let r1 = r0 + len as usize;
    let (a, b) = (2 * i, 2 * j);
    // SAFETY: as the function's contract
    unsafe {
        add_pair(values.at(r0), [val(a, b), val(a, b + 1)]);
        add_pair(values.at(r1), [val(a + 1, b), val(a + 1, b + 1)]);
    }
}

/// `q[0] += v[0]; q[1] += v[1]`, written so that it compiles to one vector load, add and
/// store.
///
/// # Safety
/// `q` and `q + 1` are valid for reads and writes and no other thread accesses them.
#[inline(always)]
unsafe fn add_pair(q: *mut f64, v: [f64; 2]) {
    // SAFETY: as the function's contract
    unsafe {
        let q = q.cast::<[f64; 2]>();
        let old = q.read_unaligned();
        q.write_unaligned([old[0] + v[0], old[1] + v[1]]);
    }
}

/// Length of the scatter map of an element with `m` slots, paired or general.
fn map_len(m: usize, paired: bool) -> usize {
    if paired {
        m / 2 + (m / 2).pow(2)
    } else {
        m * m
    }
}

/// Index of slot pair (a, b) in the order of [`for_pairs`] over m slots.
fn general_index(m: usize, a: usize, b: usize) -> usize {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    // pairs before row lo's diagonal: Σ_{k<lo} (2(m − k) − 1) = lo (2m − lo)
    let start = lo * (2 * m - lo);
    match hi - lo {
        0 => start,
        d if a < b => start + 2 * d - 1,
        d => start + 2 * d,
    }
}

/// Whether an element's map can be paired (see [`AssemblyPlan`]'s `map`).
fn is_paired(pattern: &CsrPattern, dofs: &[u32]) -> bool {
    let m = dofs.len();
    if m == 0 || !m.is_multiple_of(2) {
        return false;
    }
    let n = m / 2;
    let node_ok = |i: usize| {
        let d = dofs[2 * i];
        d != CONSTRAINED
            && dofs[2 * i + 1] == d + 1
            && !(0..i).any(|k| dofs[2 * k].abs_diff(d) < 2)
            && pattern.row_cols(d as usize) == pattern.row_cols(d as usize + 1)
    };
    (0..n).all(node_ok)
}

/// Calls `f(c, piece)` in parallel for the pieces `data[offsets[c]..offsets[c + 1]]`.
fn for_chunk_pieces<T: Send>(
    data: &mut [T],
    offsets: &[usize],
    f: impl Fn(usize, &mut [T]) + Sync,
) {
    let mut pieces: Vec<(usize, &mut [T])> = Vec::with_capacity(offsets.len() - 1);
    let mut rest = data;
    for c in 0..offsets.len() - 1 {
        let (head, tail) = rest.split_at_mut(offsets[c + 1] - offsets[c]);
        pieces.push((c, head));
        rest = tail;
    }
    pieces.into_par_iter().for_each(|(c, piece)| f(c, piece));
}

/// Zeroes the entries `list` (scatter positions), in parallel.
///
/// # Safety
/// The positions are distinct and within the array `values` points to.
unsafe fn zero_entries(values: SharedValues, list: &[u32]) {
    list.par_chunks(ROW_CHUNK * 8).for_each(|ks| {
        for &k in ks {
            // SAFETY: as the function's contract
            unsafe { *values.at(k as usize) = 0.0 };
        }
    });
}

#[cfg(test)]
mod tests;
