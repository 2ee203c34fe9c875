//! What an [`AssemblyPlan`](super::AssemblyPlan) derives from the connectivity alone: the
//! matrix's symmetric pattern and the colouring of the element chunks (no two chunks of
//! one colour share an unknown).

use super::{prefix_sum, Connectivity, CONSTRAINED};
use crate::csr::{CsrPattern, ROW_CHUNK};
use rayon::prelude::*;

/// The full symmetric pattern of a connectivity, with every diagonal entry (parallel over
/// fixed chunks of rows).
pub(super) fn build_pattern(n_dofs: usize, conn: &Connectivity) -> CsrPattern {
    let n_el = conn.len();
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
    let chunks: Vec<(Vec<usize>, Vec<u32>)> = (0..n_dofs.div_ceil(ROW_CHUNK))
        .into_par_iter()
        .map(|c| {
            let (mut lens, mut cols) = (Vec::new(), Vec::new());
            for i in c * ROW_CHUNK..((c + 1) * ROW_CHUNK).min(n_dofs) {
                let start = cols.len();
                cols.push(i as u32);
                for &e in &de[de_ptr[i]..de_ptr[i + 1]] {
                    cols.extend(
                        conn.dofs(e as usize)
                            .iter()
                            .copied()
                            .filter(|&d| d != CONSTRAINED),
                    );
                }
                let row = &mut cols[start..];
                row.sort_unstable();
                let mut len = 0;
                for k in 0..row.len() {
                    if k == 0 || row[k] != row[len - 1] {
                        row[len] = row[k];
                        len += 1;
                    }
                }
                cols.truncate(start + len);
                lens.push(len);
            }
            (lens, cols)
        })
        .collect();
    let row_ptr = prefix_sum(chunks.iter().flat_map(|c| c.0.iter().copied()));
    let mut col_idx = Vec::with_capacity(row_ptr[n_dofs]);
    for c in &chunks {
        col_idx.extend_from_slice(&c.1);
    }
    CsrPattern::from_parts_unchecked(n_dofs, row_ptr, col_idx)
}

/// Greedy colouring of the chunks, group by group, in chunk order: a chunk takes the
/// smallest colour that no earlier chunk of its group sharing one of its unknowns has.
/// Colours are kept as bit masks per unknown, 64 to a palette. Returns each chunk's colour
/// (numbered consecutively across groups) and where each group's colours start.
pub(super) fn colour_chunks(
    n_dofs: usize,
    conn: &Connectivity,
    group_start: &[usize],
    chunk_start: &[usize],
) -> (Vec<u32>, Vec<usize>) {
    let n_chunks = chunk_start.len() - 1;
    let mut colour = vec![0u32; n_chunks];
    let mut group_colour = vec![0];
    let mut palettes: Vec<Vec<u64>> = Vec::new();
    let mut c = 0;
    for g in 0..group_start.len() - 1 {
        for p in &mut palettes {
            p.fill(0);
        }
        let mut used = 0;
        while c < n_chunks && chunk_start[c] < group_start[g + 1] {
            let dofs = || {
                (chunk_start[c]..chunk_start[c + 1])
                    .flat_map(|e| conn.dofs(e))
                    .filter(|&&d| d != CONSTRAINED)
                    .map(|&d| d as usize)
            };
            let mut p = 0;
            let bit = loop {
                if p == palettes.len() {
                    palettes.push(vec![0; n_dofs]);
                }
                let taken = dofs().fold(0u64, |t, d| t | palettes[p][d]);
                if taken != u64::MAX {
                    break (!taken).trailing_zeros();
                }
                p += 1;
            };
            for d in dofs() {
                palettes[p][d] |= 1 << bit;
            }
            let k = 64 * p + bit as usize;
            used = used.max(k + 1);
            colour[c] = (group_colour[g] + k) as u32;
            c += 1;
        }
        group_colour.push(group_colour[g] + used);
    }
    (colour, group_colour)
}
