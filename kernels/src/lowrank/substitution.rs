//! The substitutions with the held factor L on several threads, bit-identical to faer's
//! sequential ones: the partition of the supernodal elimination tree into independent
//! subtrees ([`Split`]) and the per-supernode steps that repeat faer's kernels.

use super::{Tree, NONE};
use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Conj, MatMut, MatRef, Par};
use rayon::prelude::*;

/// The partition of a supernodal elimination tree for the substitutions with L on several
/// threads: disjoint subtrees ("parts"), each done on its own rayon task on a copy of its
/// columns of y, and the rest (the parts' ancestors — the top separators — and the
/// subtrees too small for a task), done sequentially.
///
/// In L⁻¹ y the parts run first; a part's products for rows above it (in the rest) are
/// kept and subtracted when the sequential pass over the supernodes reaches the one that
/// made them. In L⁻ᵀ y the rest runs first (it reads only its ancestors), then the parts,
/// each reading the rows above it from a copy. Every entry of y thus receives the same
/// floating-point operations in the same order as in faer's sequential substitution
/// (`l_solve_with_conj`, `l_transpose_solve_with_conj`, whose per-supernode steps
/// [`node_forward`] and [`node_backward`] repeat with the same kernels): the result is
/// bit-identical to it whatever the number of threads, and the partition depends on the
/// tree only.
pub(super) struct Split {
    pub(super) parts: Vec<Part>,
    /// Part of each supernode (`NONE` for the rest) and its index among the part's.
    part_of: Vec<(usize, usize)>,
    /// One scratch per part.
    scratch: Vec<PartScratch>,
}

/// A subtree of [`Split`].
pub(super) struct Part {
    /// Its supernodes, ascending, and the offset of each one's columns in the part's
    /// copy of y (one past the last at the end).
    nodes: Vec<usize>,
    local: Vec<usize>,
    /// The columns of the part (permuted numbering), in the order of the copy.
    cols: Vec<u32>,
    /// For each entry of its supernodes' patterns, one supernode after the other: the row's
    /// position in the copy, or `OUTSIDE` for a row of the rest; `pat_ptr[i]` the first
    /// entry of supernode `nodes[i]`.
    map: Vec<u32>,
    pat_ptr: Vec<usize>,
    /// The pattern rows outside the part, in the same order; those of supernode `nodes[i]`
    /// are `outside[out_ptr[i]..out_ptr[i + 1]]`.
    outside: Vec<u32>,
    out_ptr: Vec<usize>,
}

const OUTSIDE: u32 = u32::MAX;

#[derive(Default)]
struct PartScratch {
    /// The part's columns of y.
    x: Vec<f64>,
    /// Values for the rows of `outside`: the products to subtract (L⁻¹), or y's final
    /// values there (L⁻ᵀ).
    out: Vec<f64>,
    /// One supernode's product with its rows below the diagonal block.
    tmp: Vec<f64>,
}

/// The partition is searched by splitting the heaviest subtree into its children (its
/// root going to the sequential rest) while it weighs more than `1 / SPLIT_PARTS` of the
/// substitution's flops, keeping the candidate partition whose estimated time on two
/// threads (the rest, plus the parts given heaviest first to the less loaded thread) is
/// least: on the 40 × 40 wall P2 (rigid, 531 supernodes) 0.54 of the sequential flops,
/// three parts; the same for the deformable one (3457 supernodes, four parts).
const SPLIT_PARTS: f64 = 32.0;
/// A factor whose substitution costs fewer flops (a few tens of microseconds) is not
/// split: rayon's tasks would cost about as much.
const SPLIT_MIN_WORK: f64 = 2e5;
/// Subtrees lighter than `1 / SPLIT_SMALL` of the work stay in the sequential rest.
const SPLIT_SMALL: f64 = 64.0;

impl Split {
    /// The partition of the supernodal tree given by `begin`, `row_ptr`, `rows`, `parent`
    /// and `node_of` (as in [`Tree`]), or None when it has fewer than two parts.
    pub(super) fn new(
        begin: &[usize],
        row_ptr: &[usize],
        rows: &[u32],
        parent: &[usize],
        node_of: &[u32],
    ) -> Option<Self> {
        let nodes = parent.len();
        let mut work = vec![0.0f64; nodes];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        let mut roots = Vec::new();
        for s in 0..nodes {
            let (c, p) = (
                (begin[s + 1] - begin[s]) as f64,
                (row_ptr[s + 1] - row_ptr[s]) as f64,
            );
            // flops of the supernode's step: its triangle and its rows below
            work[s] += c * (c + 2.0 * p);
            match parent[s] {
                NONE => roots.push(s),
                // a parent after its children (faer's supernodes are so numbered; the
                // passes below rely on it)
                q if q > s && q < nodes => {
                    work[q] += work[s];
                    children[q].push(s);
                }
                _ => return None,
            }
        }
        let total: f64 = roots.iter().map(|&r| work[r]).sum();
        if total < SPLIT_MIN_WORK {
            return None;
        }
        // the work on two threads: the rest, then the parts (those not too small) each
        // given, heaviest first, to the less loaded thread
        let on_two = |cand: &[usize]| {
            let mut w: Vec<f64> = cand
                .iter()
                .map(|&s| work[s])
                .filter(|&w| w >= total / SPLIT_SMALL)
                .collect();
            w.sort_by(|a, b| b.total_cmp(a));
            let mut t = [0.0f64; 2];
            for x in &w {
                t[usize::from(t[1] < t[0])] += x;
            }
            total - w.iter().sum::<f64>() + t[0].max(t[1])
        };
        // split the heaviest subtree into its children while it weighs more than
        // 1 / SPLIT_PARTS of the work, keeping the candidates that do best on two threads
        let mut cand = roots;
        let mut best = (on_two(&cand), cand.clone());
        while let Some((i, &h)) = cand
            .iter()
            .enumerate()
            .filter(|&(_, &s)| !children[s].is_empty())
            .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]).then(b.1.cmp(a.1)))
        {
            if work[h] <= total / SPLIT_PARTS {
                break;
            }
            cand.swap_remove(i);
            cand.extend_from_slice(&children[h]);
            let t = on_two(&cand);
            if t < best.0 {
                best = (t, cand.clone());
            }
        }
        let mut cand = best.1;
        cand.retain(|&s| work[s] >= total / SPLIT_SMALL);
        if cand.len() < 2 {
            return None;
        }
        cand.sort_unstable();
        let mut part_of = vec![(NONE, 0); nodes];
        let mut parts = Vec::with_capacity(cand.len());
        for (pi, &root) in cand.iter().enumerate() {
            let mut members = vec![root];
            let mut i = 0;
            while i < members.len() {
                members.extend_from_slice(&children[members[i]]);
                i += 1;
            }
            members.sort_unstable();
            let mut local = vec![0];
            let mut cols = Vec::new();
            for (i, &s) in members.iter().enumerate() {
                part_of[s] = (pi, i);
                cols.extend(begin[s] as u32..begin[s + 1] as u32);
                local.push(cols.len());
            }
            let mut map = Vec::new();
            let mut pat_ptr = vec![0];
            let mut outside = Vec::new();
            let mut out_ptr = vec![0];
            for &s in &members {
                for &r in &rows[row_ptr[s]..row_ptr[s + 1]] {
                    // the row's supernode and its place in the copy
                    let a = node_of[r as usize] as usize;
                    match part_of[a] {
                        (p, i) if p == pi => {
                            map.push((local[i] + r as usize - begin[a]) as u32);
                        }
                        _ => {
                            map.push(OUTSIDE);
                            outside.push(r);
                        }
                    }
                }
                pat_ptr.push(map.len());
                out_ptr.push(outside.len());
            }
            parts.push(Part {
                nodes: members,
                local,
                cols,
                map,
                pat_ptr,
                outside,
                out_ptr,
            });
        }
        let scratch = parts.iter().map(|_| PartScratch::default()).collect();
        Some(Self {
            parts,
            part_of,
            scratch,
        })
    }

    /// y ← L⁻¹ y, or L⁻ᵀ y if `transpose`.
    pub(super) fn substitute(&mut self, t: &Tree, l: &[f64], y: &mut [f64], transpose: bool) {
        if transpose {
            self.backward(t, l, y);
        } else {
            self.forward(t, l, y);
        }
    }

    /// Each part's copy of its columns of y.
    fn gather(&mut self, y: &[f64]) {
        for (part, sc) in self.parts.iter().zip(self.scratch.iter_mut()) {
            sc.x.clear();
            sc.x.extend(part.cols.iter().map(|&c| y[c as usize]));
        }
    }

    /// Each part's copy back into its columns of y.
    fn scatter(&self, y: &mut [f64]) {
        for (part, sc) in self.parts.iter().zip(&self.scratch) {
            for (&c, &v) in part.cols.iter().zip(&sc.x) {
                y[c as usize] = v;
            }
        }
    }

    /// y ← L⁻¹ y (y permuted, length n), `l` the supernodal factor's values.
    fn forward(&mut self, t: &Tree, l: &[f64], y: &mut [f64]) {
        self.gather(y);
        self.parts
            .par_iter()
            .zip(self.scratch.par_iter_mut())
            .for_each(|(part, sc)| {
                sc.out.clear();
                for (i, &s) in part.nodes.iter().enumerate() {
                    let map = &part.map[part.pat_ptr[i]..part.pat_ptr[i + 1]];
                    sc.tmp.resize(map.len(), 0.0);
                    let x = &mut sc.x[part.local[i]..part.local[i + 1]];
                    node_forward(t.node_l(l, s), x, &mut sc.tmp);
                    for (&m, &v) in map.iter().zip(&sc.tmp) {
                        if m == OUTSIDE {
                            sc.out.push(v);
                        } else {
                            sc.x[m as usize] -= v;
                        }
                    }
                }
            });
        self.scatter(y);
        let mut tmp = Vec::new();
        for (s, &(pi, i)) in self.part_of.iter().enumerate() {
            if pi != NONE {
                let part = &self.parts[pi];
                let (a, b) = (part.out_ptr[i], part.out_ptr[i + 1]);
                for (&r, &v) in part.outside[a..b].iter().zip(&self.scratch[pi].out[a..b]) {
                    y[r as usize] -= v;
                }
                continue;
            }
            let pattern = t.pattern(s);
            tmp.resize(pattern.len(), 0.0);
            let b0 = t.begin[s];
            node_forward(t.node_l(l, s), &mut y[b0..b0 + t.width(s)], &mut tmp);
            for (&r, &v) in pattern.iter().zip(&tmp) {
                y[r as usize] -= v;
            }
        }
    }

    /// y ← L⁻ᵀ y (y permuted, length n), `l` the supernodal factor's values.
    fn backward(&mut self, t: &Tree, l: &[f64], y: &mut [f64]) {
        let mut tmp = Vec::new();
        for (s, &(pi, _)) in self.part_of.iter().enumerate().rev() {
            if pi == NONE {
                tmp.clear();
                tmp.extend(t.pattern(s).iter().map(|&r| y[r as usize]));
                let b0 = t.begin[s];
                node_backward(t.node_l(l, s), &mut y[b0..b0 + t.width(s)], &tmp);
            }
        }
        self.gather(y);
        for (part, sc) in self.parts.iter().zip(self.scratch.iter_mut()) {
            sc.out.clear();
            sc.out.extend(part.outside.iter().map(|&r| y[r as usize]));
        }
        self.parts
            .par_iter()
            .zip(self.scratch.par_iter_mut())
            .for_each(|(part, sc)| {
                for (i, &s) in part.nodes.iter().enumerate().rev() {
                    let map = &part.map[part.pat_ptr[i]..part.pat_ptr[i + 1]];
                    let mut out = sc.out[part.out_ptr[i]..part.out_ptr[i + 1]].iter();
                    sc.tmp.clear();
                    for &m in map {
                        sc.tmp.push(if m == OUTSIDE {
                            *out.next().expect("outside row")
                        } else {
                            sc.x[m as usize]
                        });
                    }
                    let x = &mut sc.x[part.local[i]..part.local[i + 1]];
                    node_backward(t.node_l(l, s), x, &sc.tmp);
                }
            });
        self.scatter(y);
    }
}

/// Supernode step of L⁻¹ y as faer's `l_solve_with_conj` does it: x ← L_ss⁻¹ x (x the
/// supernode's rows of y), tmp ← L_bs x (its rows below the diagonal block, subtracted by
/// the caller).
fn node_forward(ls: MatRef<'_, f64>, x: &mut [f64], tmp: &mut [f64]) {
    let (c, p) = (x.len(), tmp.len());
    let mut x = MatMut::from_column_major_slice_mut(x, c, 1);
    solve_lower_triangular_in_place_with_conj(ls.subrows(0, c), Conj::No, x.rb_mut(), Par::Seq);
    matmul_with_conj(
        MatMut::from_column_major_slice_mut(tmp, p, 1),
        Accum::Replace,
        ls.subrows(c, p),
        Conj::No,
        x.rb(),
        Conj::No,
        1.0,
        Par::Seq,
    );
}

/// Supernode step of L⁻ᵀ y as faer's `l_transpose_solve_with_conj` does it:
/// x ← L_ss⁻ᵀ (x − L_bsᵀ tmp), tmp the values of y at the supernode's pattern rows.
fn node_backward(ls: MatRef<'_, f64>, x: &mut [f64], tmp: &[f64]) {
    let (c, p) = (x.len(), tmp.len());
    let mut x = MatMut::from_column_major_slice_mut(x, c, 1);
    matmul_with_conj(
        x.rb_mut(),
        Accum::Add,
        ls.subrows(c, p).transpose(),
        Conj::No,
        MatRef::from_column_major_slice(tmp, p, 1),
        Conj::No,
        -1.0,
        Par::Seq,
    );
    solve_upper_triangular_in_place_with_conj(
        ls.subrows(0, c).transpose(),
        Conj::No,
        x.rb_mut(),
        Par::Seq,
    );
}
