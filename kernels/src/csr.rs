//! Compressed sparse row storage with the pattern and the values as separate types.
//!
//! A [`CsrPattern`] is built once per topology and shared (through an `Arc`) by every
//! [`CsrMatrix`] holding values on it. Patterns are always *full symmetric*: both
//! triangles are stored, the columns of each row are sorted, and the diagonal is always
//! present. Because the pattern is symmetric, the same arrays read as a compressed
//! sparse *column* structure describe the same pattern, which is how the direct
//! backends pass matrices to faer without copying.

use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

static NEXT_PATTERN_ID: AtomicU64 = AtomicU64::new(1);

/// Number of rows handled by one rayon task in row-parallel kernels. Fixed, so that the
/// work split never depends on the number of threads.
pub(crate) const ROW_CHUNK: usize = 2048;

/// Sparsity pattern of a square matrix with a symmetric structure (both triangles stored).
///
/// Invariants: `row_ptr.len() == n + 1`, `row_ptr[0] == 0`, non-decreasing; the column
/// indices of each row are strictly increasing and `< n`; every diagonal entry is
/// present; `(i, j)` present implies `(j, i)` present.
#[derive(Debug)]
pub struct CsrPattern {
    n: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<u32>,
    id: u64,
}

impl CsrPattern {
    /// Builds a pattern from its raw arrays after checking every invariant listed on the
    /// type (sorted rows, indices in range, diagonal present, symmetric structure).
    ///
    /// `n` must be below `u32::MAX`.
    pub fn from_parts(n: usize, row_ptr: Vec<usize>, col_idx: Vec<u32>) -> Result<Self, String> {
        if n >= u32::MAX as usize {
            return Err(format!(
                "too many rows: {n} (the limit is {})",
                u32::MAX - 1
            ));
        }
        if row_ptr.len() != n + 1 {
            return Err(format!(
                "row_ptr has {} entries, expected n + 1 = {}",
                row_ptr.len(),
                n + 1
            ));
        }
        if row_ptr[0] != 0 || row_ptr[n] != col_idx.len() {
            return Err("row_ptr must start at 0 and end at col_idx.len()".into());
        }
        for i in 0..n {
            if row_ptr[i] > row_ptr[i + 1] {
                return Err(format!("row_ptr decreases at row {i}"));
            }
            let cols = &col_idx[row_ptr[i]..row_ptr[i + 1]];
            if cols.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("columns of row {i} are not strictly increasing"));
            }
            if cols.last().is_some_and(|&c| c as usize >= n) {
                return Err(format!("column index out of range in row {i}"));
            }
            if cols.binary_search(&(i as u32)).is_err() {
                return Err(format!("diagonal entry ({i}, {i}) is missing"));
            }
        }
        let p = Self::from_parts_unchecked(n, row_ptr, col_idx);
        for i in 0..n {
            for &j in p.row_cols(i) {
                if p.find(j as usize, i).is_none() {
                    return Err(format!(
                        "pattern is not symmetric: ({i}, {j}) present, ({j}, {i}) missing"
                    ));
                }
            }
        }
        Ok(p)
    }

    /// Builds a pattern without checks (the caller guarantees the invariants).
    pub(crate) fn from_parts_unchecked(n: usize, row_ptr: Vec<usize>, col_idx: Vec<u32>) -> Self {
        debug_assert_eq!(row_ptr.len(), n + 1);
        Self {
            n,
            row_ptr,
            col_idx,
            id: NEXT_PATTERN_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// Builds the full symmetric pattern containing every `(i, j)` of `entries`, its
    /// transpose `(j, i)`, and the whole diagonal. Duplicates are merged.
    ///
    /// # Panics
    /// If an index is `>= n`.
    pub fn from_entries(n: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut rows: Vec<Vec<u32>> = (0..n).map(|i| vec![i as u32]).collect();
        for (i, j) in entries {
            assert!(i < n && j < n, "entry ({i}, {j}) out of range for n = {n}");
            rows[i].push(j as u32);
            if i != j {
                rows[j].push(i as u32);
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        row_ptr.push(0);
        let mut col_idx = Vec::new();
        for mut r in rows {
            r.sort_unstable();
            r.dedup();
            col_idx.extend_from_slice(&r);
            row_ptr.push(col_idx.len());
        }
        Self::from_parts_unchecked(n, row_ptr, col_idx)
    }

    /// Number of rows (= number of columns = number of unknowns).
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.col_idx.len()
    }

    /// Row pointers: the entries of row `i` are `row_ptr[i]..row_ptr[i + 1]`.
    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }

    /// Column index of every stored entry, sorted within each row.
    pub fn col_idx(&self) -> &[u32] {
        &self.col_idx
    }

    /// Column indices of row `row`.
    pub fn row_cols(&self, row: usize) -> &[u32] {
        &self.col_idx[self.row_ptr[row]..self.row_ptr[row + 1]]
    }

    /// Position of entry `(row, col)` in the value array, or `None` when it is not in the
    /// pattern (binary search within the row).
    pub fn find(&self, row: usize, col: usize) -> Option<usize> {
        if row >= self.n || col >= self.n {
            return None;
        }
        let start = self.row_ptr[row];
        self.row_cols(row)
            .binary_search(&(col as u32))
            .ok()
            .map(|k| start + k)
    }

    /// Position of the diagonal entry of every row in the value array.
    pub fn diagonal_positions(&self) -> Vec<usize> {
        (0..self.n)
            .map(|i| {
                self.find(i, i)
                    .expect("the diagonal is always in the pattern")
            })
            .collect()
    }

    /// Identifier unique to this constructed pattern (a global counter); backends use it
    /// as the cache key of their symbolic analysis.
    pub fn id(&self) -> u64 {
        self.id
    }
}

/// A square sparse matrix: a shared [`CsrPattern`] and one value per stored entry.
///
/// The structure is symmetric; the values are symmetric for every matrix assembled by
/// [`crate::assembly::AssemblyPlan::assemble`] (the direct backends assume it).
#[derive(Debug, Clone)]
pub struct CsrMatrix {
    /// The sparsity pattern, shared between matrices of the same topology.
    pub pattern: Arc<CsrPattern>,
    /// One value per stored entry, in the order of `pattern.col_idx()`.
    pub values: Vec<f64>,
}

impl CsrMatrix {
    /// A matrix with all stored values zero.
    pub fn zeros(pattern: Arc<CsrPattern>) -> Self {
        let values = vec![0.0; pattern.nnz()];
        Self { pattern, values }
    }

    /// Number of rows.
    pub fn n(&self) -> usize {
        self.pattern.n()
    }

    /// `y = A x`. Rows are processed in parallel (rayon) in fixed chunks; each row is
    /// summed sequentially in column order, so the result is bit-identical for any
    /// number of threads.
    ///
    /// # Panics
    /// If `x` or `y` does not have length `n`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n();
        assert_eq!(x.len(), n, "x has the wrong length");
        assert_eq!(y.len(), n, "y has the wrong length");
        let rp = self.pattern.row_ptr();
        let ci = self.pattern.col_idx();
        let v = &self.values;
        y.par_chunks_mut(ROW_CHUNK).enumerate().for_each(|(c, ys)| {
            let r0 = c * ROW_CHUNK;
            for (k, yi) in ys.iter_mut().enumerate() {
                let i = r0 + k;
                let mut s = 0.0;
                for p in rp[i]..rp[i + 1] {
                    s += v[p] * x[ci[p] as usize];
                }
                *yi = s;
            }
        });
    }

    /// The diagonal `a_ii`.
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.n())
            .map(|i| self.values[self.pattern.find(i, i).expect("diagonal present")])
            .collect()
    }

    /// Entry `(row, col)`, 0 when it is not in the pattern.
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.pattern.find(row, col).map_or(0.0, |k| self.values[k])
    }

    /// Adds `value` to entry `(row, col)`. Returns `false` (and changes nothing) when the
    /// entry is not in the pattern.
    pub fn add(&mut self, row: usize, col: usize, value: f64) -> bool {
        match self.pattern.find(row, col) {
            Some(k) => {
                self.values[k] += value;
                true
            }
            None => false,
        }
    }

    /// Dense row-major copy (`n × n`), for tests and small problems.
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.n();
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            for p in self.pattern.row_ptr()[i]..self.pattern.row_ptr()[i + 1] {
                d[i * n + self.pattern.col_idx()[p] as usize] += self.values[p];
            }
        }
        d
    }
}
