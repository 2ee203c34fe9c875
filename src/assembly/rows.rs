//! The rows one process assembles in a distributed run (`mpirun -n N dfem run ...`).
//!
//! The unknowns are split into N parts by the block partition
//! ([`crate::solve::block_partition`]: whole blocks, cuts along joints), the same partition
//! the distributed linear backends (PETSc, MUMPS) use for their rows. Process r evaluates
//! only the element matrices of the triangles and contacts that touch one of its own
//! unknowns (docs/theory.md §2 and §3): those are all the elements that add into its rows, so
//! its rows come out bit-identical to a serial assembly, and it evaluates about 1/N of the
//! elements (plus the contacts along the cuts, which both sides evaluate). The processes
//! then exchange their rows (`MPI_Allgatherv` of the values, [`dfem_ffi::allgather`]), so
//! that every process ends with the whole matrix, bit-identical to the serial one: the
//! static and dynamic drivers use it beyond the linear solve (the reuse iterations'
//! products, the LU of the tangent steps, the pinned rows), and they take the same
//! decisions on every process only if they see the same matrix.

use dfem_kernels::{Connectivity, CsrMatrix, CsrPattern, CONSTRAINED};
use std::ops::Range;

/// Which process owns each unknown's row, and which process this is.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranks {
    /// `part[i]`: the process (rank, 0-based) whose rows include unknown i; one entry per
    /// unknown.
    pub part: Vec<u32>,
    /// This process's rank.
    pub rank: u32,
    /// Number of processes.
    pub size: u32,
}

/// What the assembly of one process needs: the elements it evaluates and how the rows are
/// exchanged.
pub(super) struct RowExchange {
    /// Element e is evaluated here (it has a slot at one of this process's unknowns).
    active: Vec<bool>,
    /// The rows in the order of the exchanged buffer: rank 0's rows ascending, then rank
    /// 1's, and so on.
    order: Vec<u32>,
    /// Values (stored entries) of each rank's rows.
    counts: Vec<usize>,
    /// This rank's rows: `order[own]`.
    own: Range<usize>,
}

impl RowExchange {
    /// `None` when `ranks` does not fit (one process, or a partition of another number of
    /// unknowns): then everything is assembled here.
    pub(super) fn new(ranks: &Ranks, conn: &Connectivity, pattern: &CsrPattern) -> Option<Self> {
        let n = pattern.n();
        if ranks.size <= 1
            || ranks.part.len() != n
            || ranks.rank >= ranks.size
            || ranks.part.iter().any(|&p| p >= ranks.size)
        {
            return None;
        }
        let mine = |d: u32| d != CONSTRAINED && ranks.part[d as usize] == ranks.rank;
        let active = (0..conn.len())
            .map(|e| conn.dofs(e).iter().any(|&d| mine(d)))
            .collect();
        let size = ranks.size as usize;
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by_key(|&i| (ranks.part[i as usize], i));
        let mut counts = vec![0usize; size];
        let mut rows = vec![0usize; size + 1];
        for i in 0..n {
            let p = ranks.part[i] as usize;
            counts[p] += pattern.row_cols(i).len();
            rows[p + 1] += 1;
        }
        for r in 0..size {
            rows[r + 1] += rows[r];
        }
        let r = ranks.rank as usize;
        Some(Self {
            active,
            order,
            counts,
            own: rows[r]..rows[r + 1],
        })
    }

    /// The elements this process evaluates.
    pub(super) fn active(&self) -> &[bool] {
        &self.active
    }

    /// Replaces the rows of the other processes in `out` (which holds this process's rows,
    /// assembled) with theirs: afterwards every process holds the same whole matrix.
    /// Collective: every process calls it with the same pattern.
    pub(super) fn complete(&self, out: &mut CsrMatrix) {
        let local = self.pack(out);
        let mut all = vec![0.0; out.values.len()];
        // an MPI failure aborts the run in MPI's default error handler before returning;
        // anything else here is a bug (the counts come from the same pattern everywhere)
        dfem_ffi::allgather(&local, &self.counts, &mut all)
            .unwrap_or_else(|e| panic!("exchanging the assembled rows: {e}"));
        self.unpack(&all, out);
    }

    /// The values of this process's rows of `out`, row after row (ascending).
    pub(super) fn pack(&self, out: &CsrMatrix) -> Vec<f64> {
        let rp = out.pattern.row_ptr();
        let mut local = Vec::with_capacity(self.counts.iter().max().copied().unwrap_or(0));
        for &i in &self.order[self.own.clone()] {
            local.extend_from_slice(&out.values[rp[i as usize]..rp[i as usize + 1]]);
        }
        local
    }

    /// Sets the rows of `out` from `all`, every process's [`Self::pack`] in rank order.
    pub(super) fn unpack(&self, all: &[f64], out: &mut CsrMatrix) {
        let rp = out.pattern.row_ptr();
        let mut at = 0;
        for &i in &self.order {
            let r = rp[i as usize]..rp[i as usize + 1];
            let len = r.len();
            out.values[r].copy_from_slice(&all[at..at + len]);
            at += len;
        }
    }
}
