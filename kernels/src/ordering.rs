//! Fill-reducing orderings for the sparse Cholesky backends: faer's AMD, or METIS nested
//! dissection on the compressed (node) graph.
//!
//! Unknowns that belong to one mesh node (2 or 3 displacement components) have identical
//! rows in the pattern. [`metis_nested_dissection`] merges every run of consecutive
//! unknowns with identical rows into one graph vertex (weighted by the run length), orders
//! that smaller graph with `METIS_NodeND`, and expands the vertex permutation back to the
//! unknowns, keeping the unknowns of one vertex together and in their original order.

use crate::backend::SolveError;
use crate::csr::CsrPattern;
use std::sync::Mutex;

/// Which fill-reducing ordering the Cholesky backends compute in their symbolic phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FillOrdering {
    /// Approximate minimum degree (faer's own), the default: cheap, good on small and
    /// medium problems.
    #[default]
    Amd,
    /// METIS nested dissection on the node graph (`METIS_NodeND`): less fill on large
    /// 2D/3D meshes, a costlier analysis (paid once per pattern).
    Metis,
}

/// Serialises the calls into METIS: its bundled GKlib keeps some global state, and the
/// ordering is computed once per pattern, so the lock costs nothing measurable.
static METIS_LOCK: Mutex<()> = Mutex::new(());

/// A fill-reducing permutation of the unknowns of `pattern` by METIS nested dissection.
///
/// Returns `(fwd, inv)` with `fwd[new] = old` and `inv[old] = new` (faer's convention for
/// `SymmetricOrdering::Custom`). Runs of consecutive unknowns with identical rows (the
/// components of one node) become one weighted vertex of the graph given to METIS.
/// Deterministic: METIS runs with its fixed default seed.
pub fn metis_nested_dissection(pattern: &CsrPattern) -> Result<(Vec<u32>, Vec<u32>), SolveError> {
    let n = pattern.n();
    if n == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let NodeGraph {
        first,
        mut xadj,
        mut adjncy,
        mut vwgt,
    } = node_graph(pattern)?;
    let nv = first.len() - 1;
    let mut perm = vec![0i32; nv];
    let mut iperm = vec![0i32; nv];
    if nv > 1 {
        let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
        let mut nvtxs = nv as i32;
        let status = {
            let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
            // SAFETY: every array has the length METIS expects (xadj nv + 1, adjncy
            // xadj[nv], vwgt/perm/iperm nv, options METIS_NOPTIONS), the graph is
            // symmetric (the pattern is) and has no self loops; METIS only reads the
            // inputs and writes perm/iperm.
            unsafe {
                metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
                options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
                metis_sys::METIS_NodeND(
                    &mut nvtxs,
                    xadj.as_mut_ptr(),
                    adjncy.as_mut_ptr(),
                    vwgt.as_mut_ptr(),
                    options.as_mut_ptr(),
                    perm.as_mut_ptr(),
                    iperm.as_mut_ptr(),
                )
            }
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(SolveError::Other(format!(
                "METIS_NodeND failed with status {status}"
            )));
        }
    }
    // METIS: perm[new vertex] = old vertex. Check it is a permutation before trusting it.
    let mut seen = vec![false; nv];
    for &p in &perm {
        let p = p as usize;
        if p >= nv || seen[p] {
            return Err(SolveError::Other(
                "METIS_NodeND returned an invalid permutation".into(),
            ));
        }
        seen[p] = true;
    }
    let mut fwd = Vec::with_capacity(n);
    for &v in &perm {
        let v = v as usize;
        fwd.extend(first[v] as u32..first[v + 1] as u32);
    }
    let mut inv = vec![0u32; n];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old as usize] = new as u32;
    }
    Ok((fwd, inv))
}

/// The graph of the pattern with every run of consecutive unknowns with identical rows
/// merged into one vertex: `first[v]..first[v + 1]` are the unknowns of vertex v; CSR
/// adjacency without self loops (METIS' `xadj`/`adjncy`), vertex weights = run lengths.
pub(crate) struct NodeGraph {
    pub first: Vec<usize>,
    pub xadj: Vec<i32>,
    pub adjncy: Vec<i32>,
    pub vwgt: Vec<i32>,
}

pub(crate) fn node_graph(pattern: &CsrPattern) -> Result<NodeGraph, SolveError> {
    let n = pattern.n();
    // group[v] = first unknown of vertex v; vertex_of[i] = vertex of unknown i
    let mut first = Vec::with_capacity(n + 1);
    let mut vertex_of = vec![0u32; n];
    for (i, v) in vertex_of.iter_mut().enumerate() {
        if i == 0 || pattern.row_cols(i) != pattern.row_cols(i - 1) {
            first.push(i);
        }
        *v = (first.len() - 1) as u32;
    }
    first.push(n);
    let nv = first.len() - 1;
    // quotient graph without self loops; the columns of a row map to ascending vertices
    let mut xadj: Vec<i32> = Vec::with_capacity(nv + 1);
    let mut adjncy: Vec<i32> = Vec::new();
    xadj.push(0);
    for (v, &f) in first[..nv].iter().enumerate() {
        let mut last = u32::MAX;
        for &c in pattern.row_cols(f) {
            let w = vertex_of[c as usize];
            if w as usize != v && w != last {
                adjncy.push(w as i32);
                last = w;
            }
        }
        if adjncy.len() >= i32::MAX as usize {
            return Err(SolveError::Other(
                "graph too large for METIS' 32-bit indices".into(),
            ));
        }
        xadj.push(adjncy.len() as i32);
    }
    let vwgt: Vec<i32> = (0..nv).map(|v| (first[v + 1] - first[v]) as i32).collect();
    Ok(NodeGraph {
        first,
        xadj,
        adjncy,
        vwgt,
    })
}

/// A vertex separator of the node graph by METIS (`METIS_ComputeVertexSeparator`):
/// for each unknown 0 or 1 (the two parts) or 2 (the separator).
pub(crate) fn metis_separator(pattern: &CsrPattern) -> Result<Vec<u8>, SolveError> {
    let n = pattern.n();
    if n < 2 {
        return Err(SolveError::Other("too small to split".into()));
    }
    let mut g = node_graph(pattern)?;
    let nv = g.first.len() - 1;
    let mut part = vec![0i32; nv];
    let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
    let mut nvtxs = nv as i32;
    let mut sepsize = 0i32;
    let status = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: array lengths as METIS expects (xadj nv + 1, adjncy xadj[nv], vwgt and
        // part nv, options METIS_NOPTIONS); symmetric graph without self loops.
        unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
            metis_sys::METIS_ComputeVertexSeparator(
                &mut nvtxs,
                g.xadj.as_mut_ptr(),
                g.adjncy.as_mut_ptr(),
                g.vwgt.as_mut_ptr(),
                options.as_mut_ptr(),
                &mut sepsize,
                part.as_mut_ptr(),
            )
        }
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(SolveError::Other(format!(
            "METIS_ComputeVertexSeparator failed with status {status}"
        )));
    }
    let mut out = vec![0u8; n];
    for v in 0..nv {
        let p = part[v];
        if !(0..=2).contains(&p) {
            return Err(SolveError::Other(
                "METIS returned an invalid partition".into(),
            ));
        }
        out[g.first[v]..g.first[v + 1]].fill(p as u8);
    }
    Ok(out)
}

/// A partition of the unknowns of `pattern` into `nparts` parts of nearly equal size with
/// few couplings between parts (METIS k-way, `METIS_PartGraphKway`, on the node graph:
/// the components of a node stay together). Returns the part of each unknown. For
/// distributing the rows of a matrix over MPI ranks. Deterministic (METIS' fixed seed).
pub fn metis_partition(pattern: &CsrPattern, nparts: usize) -> Result<Vec<u32>, SolveError> {
    node_graph_partition(pattern, nparts, false)
}

/// [`metis_partition`] by recursive bisection (`METIS_PartGraphRecursive`): parts
/// `lo..mid` and `mid..hi` (mid = lo + (hi − lo) / 2) are the two sides of one bisection,
/// recursively from `0..nparts`, the nesting the substructured backend follows.
pub(crate) fn metis_bisection_partition(
    pattern: &CsrPattern,
    nparts: usize,
) -> Result<Vec<u32>, SolveError> {
    node_graph_partition(pattern, nparts, true)
}

fn node_graph_partition(
    pattern: &CsrPattern,
    nparts: usize,
    recursive: bool,
) -> Result<Vec<u32>, SolveError> {
    let n = pattern.n();
    if nparts <= 1 || n == 0 {
        return Ok(vec![0; n]);
    }
    let mut g = node_graph(pattern)?;
    let part = part_graph(
        &mut g.xadj,
        &mut g.adjncy,
        &mut g.vwgt,
        None,
        nparts,
        recursive,
    )?;
    let mut out = vec![0u32; n];
    for (v, &p) in part.iter().enumerate() {
        out[g.first[v]..g.first[v + 1]].fill(p);
    }
    Ok(out)
}

/// A partition of an undirected weighted graph into `nparts` parts by recursive
/// bisection (METIS, `METIS_PartGraphRecursive`): parts of nearly equal total vertex
/// weight with a small total weight of the edges cut, numbered along the bisections —
/// parts `lo..mid` and `mid..hi` (mid = lo + (hi − lo) / 2) are the two sides of one
/// bisection, recursively from `0..nparts` (the nesting `faer-substructured` follows). `vertex_weights[v]` ≥ 1
/// is the weight of vertex v; `edges` are `(a, b, weight)`, in any order, a repeated pair
/// adding its weights, self loops ignored. Returns the part of each vertex (`0..nparts`;
/// a part may be empty when there are fewer vertices than parts). Deterministic.
///
/// dfem partitions its blocks with it (vertices = blocks weighted by their unknowns, edges
/// = joints weighted by their contacts), so that every cut runs along joints.
pub fn metis_partition_graph(
    vertex_weights: &[u32],
    edges: &[(u32, u32, u32)],
    nparts: usize,
) -> Result<Vec<u32>, SolveError> {
    let nv = vertex_weights.len();
    if nv >= i32::MAX as usize {
        return Err(SolveError::Other(
            "graph too large for METIS' 32-bit indices".into(),
        ));
    }
    if let Some(&(a, b, _)) = edges
        .iter()
        .find(|&&(a, b, _)| a as usize >= nv || b as usize >= nv)
    {
        return Err(SolveError::Other(format!(
            "graph edge ({a}, {b}) out of range: {nv} vertices"
        )));
    }
    if nparts <= 1 || nv == 0 {
        return Ok(vec![0; nv]);
    }
    // symmetric adjacency, sorted, duplicates merged (weights summed)
    let mut adj: Vec<(u32, u32, u32)> = Vec::with_capacity(2 * edges.len());
    for &(a, b, w) in edges {
        if a != b {
            adj.push((a, b, w));
            adj.push((b, a, w));
        }
    }
    adj.sort_unstable_by_key(|&(a, b, _)| (a, b));
    let mut xadj = vec![0i32; nv + 1];
    let mut adjncy: Vec<i32> = Vec::with_capacity(adj.len());
    let mut adjwgt: Vec<i32> = Vec::with_capacity(adj.len());
    let mut last = (u32::MAX, u32::MAX);
    for &(a, b, w) in &adj {
        let w = i32::try_from(w.max(1)).unwrap_or(i32::MAX);
        if (a, b) == last {
            let l = adjwgt.len() - 1;
            adjwgt[l] = adjwgt[l].saturating_add(w);
        } else {
            adjncy.push(b as i32);
            adjwgt.push(w);
            xadj[a as usize + 1] += 1;
            last = (a, b);
        }
    }
    if adjncy.len() >= i32::MAX as usize {
        return Err(SolveError::Other(
            "graph too large for METIS' 32-bit indices".into(),
        ));
    }
    for v in 0..nv {
        xadj[v + 1] += xadj[v];
    }
    let mut vwgt: Vec<i32> = vertex_weights
        .iter()
        .map(|&w| i32::try_from(w.max(1)).unwrap_or(i32::MAX))
        .collect();
    part_graph(
        &mut xadj,
        &mut adjncy,
        &mut vwgt,
        Some(&mut adjwgt),
        nparts,
        true,
    )
}

/// `METIS_PartGraphKway` (or `METIS_PartGraphRecursive` if `recursive`) on a CSR graph
/// (symmetric, no self loops), one part per vertex; with fewer vertices than parts,
/// vertex v gets part v.
fn part_graph(
    xadj: &mut [i32],
    adjncy: &mut [i32],
    vwgt: &mut [i32],
    adjwgt: Option<&mut [i32]>,
    nparts: usize,
    recursive: bool,
) -> Result<Vec<u32>, SolveError> {
    let nv = xadj.len() - 1;
    if nv < nparts {
        return Ok((0..nv as u32).collect());
    }
    let mut part = vec![0i32; nv];
    let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
    let (mut nvtxs, mut ncon, mut np, mut cut) = (nv as i32, 1i32, nparts as i32, 0i32);
    let adjwgt = adjwgt.map_or(std::ptr::null_mut(), |w| w.as_mut_ptr());
    let status = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: array lengths as METIS expects (xadj nv + 1, adjncy and adjwgt (if not
        // null) xadj[nv], vwgt and part nv, options METIS_NOPTIONS); symmetric graph
        // without self loops; null pointers for the other optional arrays.
        unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
            let f = if recursive {
                metis_sys::METIS_PartGraphRecursive
            } else {
                metis_sys::METIS_PartGraphKway
            };
            f(
                &mut nvtxs,
                &mut ncon,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                vwgt.as_mut_ptr(),
                std::ptr::null_mut(),
                adjwgt,
                &mut np,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                &mut cut,
                part.as_mut_ptr(),
            )
        }
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(SolveError::Other(format!(
            "METIS partitioning failed with status {status}"
        )));
    }
    part.iter()
        .map(|&p| {
            if (0..nparts as i32).contains(&p) {
                Ok(p as u32)
            } else {
                Err(SolveError::Other(
                    "METIS returned an invalid partition".into(),
                ))
            }
        })
        .collect()
}
