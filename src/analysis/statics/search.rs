//! The step lengths of the static driver's corrections: the line search on the
//! out-of-balance norm, the slope search where no step length lowers it, and the search
//! along the free motion of blocks held only by slipping and open contacts
//! (docs/theory.md §4, "Increments and iterations").

use super::*;

/// Finest step 2⁻ᵏ of the grid on which [`Driver::free_motion`] seeks its roots.
pub(super) const MODE_GRID: usize = 24;
/// A block is free (held only by slipping and open contacts) when its motion in the
/// mechanism step is this many times its motion in the iteration's correction (10⁴ where
/// it is free, the ratio of the two ε, and 1 elsewhere).
pub(super) const MODE_RATIO: f64 = 100.0;
/// At most this many groups of free blocks move in one iteration (those with the largest
/// out-of-balance force along their motion).
pub(super) const MODE_GROUPS: usize = 8;

impl Driver<'_> {
    /// The slope line search: the step length α* along the correction `delta` from `dq`
    /// where the out-of-balance force r(α) = f_ext − f_int(dq + α δ) stops doing work along
    /// δ, the root of s(α) = r(α)·δ (N·m), sought on the grid α = 2⁻ᵏ, k = 0 …
    /// [`MODE_GRID`], from the largest step down, and interpolated linearly between the
    /// first grid point where s > 0 and the one before it (docs/theory.md, "The slope line
    /// search"). Where the contact laws derive from a potential (frozen normal forces, or
    /// no friction) s is minus the derivative of the total potential energy along δ, so
    /// α* is its minimum on the line: the step a mechanism's blocks make until a contact
    /// of theirs closes or sticks, which the norm of r cannot find, because it rises as
    /// soon as they touch however far they fall before. `None` when δ is not a descent
    /// direction (s(0) ≤ 0), when s > 0 at α = 1 (the full step already lowers the
    /// energy everywhere along it), and when the contacts' history at α* is not
    /// `history`, that of the backtracked step it would replace: a root far along δ may
    /// carry cohesive joints past their strength, which they do not regain when the next
    /// iterations correct the step (taken regardless, it cracked the wall over the fault
    /// of examples/fault_offset, which then followed the drop by 17 mm instead of
    /// bridging it), and a root short of the backtracked step may spare joints that the
    /// path cracks. So the search changes where the iterate goes, never which contacts
    /// have cracked or softened there.
    pub(super) fn slope_search(
        &self,
        dq: &[f64],
        delta: &[f64],
        r0: &[f64],
        history: &[crate::material::History],
        f_ext: &[f64],
        presc: &[Point],
    ) -> Option<(f64, Trial, Vec<f64>)> {
        let slope = |r: &[f64]| r.iter().zip(delta).map(|(x, y)| x * y).sum::<f64>();
        let s0 = slope(r0);
        if s0 <= 0.0 || !s0.is_finite() {
            return None;
        }
        let at =
            |alpha: f64| -> Vec<f64> { dq.iter().zip(delta).map(|(a, b)| a + alpha * b).collect() };
        // (α, s) at the last grid point where the slope was not positive, and at the
        // first one below it where it is
        let mut above: Option<(f64, f64)> = None;
        let mut below = (0.0, s0);
        let mut alpha = 1.0f64;
        for _ in 0..=MODE_GRID {
            let t = self.trial(&at(alpha), presc);
            let s = slope(&self.out_of_balance(f_ext, &t.f_int));
            self.recycle(t);
            if s > 0.0 {
                below = (alpha, s);
                break;
            }
            above = Some((alpha, s));
            alpha *= 0.5;
        }
        let (ah, sh) = above?;
        let (al, sl) = below;
        let root = al + (ah - al) * sl / (sl - sh);
        let cand = at(root);
        let t = self.trial(&cand, presc);
        if t.history != history {
            self.recycle(t);
            return None;
        }
        let rn = Self::norm(&self.out_of_balance(f_ext, &t.f_int));
        Some((rn, t, cand))
    }

    /// Backtracking on the out-of-balance norm along `delta` from `dq` over the step
    /// lengths 1, ½, … 2^(1 − `steps`) (one step without `line_search`), the external
    /// force `f_ext` fixed: the best of the tried steps (norm, trial, increment).
    pub(super) fn line_search(
        &self,
        dq: &[f64],
        delta: &[f64],
        rn: f64,
        f_ext: &[f64],
        presc: &[Point],
        steps: usize,
    ) -> (f64, Trial, Vec<f64>) {
        let steps = if self.settings.line_search { steps } else { 1 };
        let (rn2, t, cand, _) =
            self.line_search_along(dq, delta, rn, &Load::Fixed(f_ext), presc, steps);
        (rn2, t, cand)
    }

    /// Backtracking on the out-of-balance norm along `delta` from `dq` over the step
    /// lengths α = 1, ½, … 2^(1 − `steps`), the external force moving with α as `load`
    /// says (the static driver's [`Driver::line_search`], the arc-length corrector's
    /// backtracking): the first step that does not raise the norm above `rn` (N), else
    /// the best of them, as (its norm, its trial, the increment, α).
    pub(super) fn line_search_along(
        &self,
        dq: &[f64],
        delta: &[f64],
        rn: f64,
        load: &Load,
        presc: &[Point],
        steps: usize,
    ) -> (f64, Trial, Vec<f64>, f64) {
        let eval = |alpha: f64| {
            let cand: Vec<f64> = dq.iter().zip(delta).map(|(a, b)| a + alpha * b).collect();
            let t = self.trial(&cand, presc);
            let rn2 = Self::norm(&self.out_of_balance(&load.at(alpha), &t.f_int));
            Some((rn2, (t, cand)))
        };
        let best = solver::backtrack(steps, rn, false, eval, |(t, _)| self.recycle(t))
            .expect("the full step is always evaluated");
        (best.norm, best.at.0, best.at.1, best.alpha)
    }

    /// The unknowns of each block (m, rad): a rigid block's three, a deformable block's
    /// nodes' two each, none for a fixed block.
    pub(super) fn block_dofs(&self) -> Vec<Vec<usize>> {
        (0..self.cur.blocks.len())
            .map(|b| self.cur.block_unknowns(b))
            .collect()
    }

    /// The free motion of the blocks that only slipping and open contacts hold, and the
    /// distance each group of them must travel for one of its contacts to stick.
    ///
    /// `m` = (K_s + ε K₀)⁻¹ r with ε = [`MODE_BLEND`] and `step` the correction of the
    /// iteration, (K_s + 10⁻² K₀)⁻¹ r: where K_s is regular the two agree, where it is
    /// singular (a block whose contacts all slip or are open, in the direction they slip)
    /// `m` is 10⁴ times larger. Those blocks, grouped by their closed contacts, each move
    /// along their part of `m` to the root of their slope s_g(α) = Σ_{i ∈ g} rᵢ(α) mᵢ, where
    /// r(α) is the out-of-balance force at `from` + α m (an energy line search: with the
    /// normal forces frozen the contact laws derive from a convex potential and s_g is
    /// minus its derivative along the group's motion). Along that motion the slope stays
    /// at the group's out-of-balance force until one of its contacts sticks or reverses,
    /// while the norm of r stays flat: the norm cannot find the distance, the slope's root
    /// can. The roots are found on the grid α = 2⁻ᵏ, k = 0 … [`MODE_GRID`], interpolated
    /// linearly. Returns each group's motion α_g m as (unknown, increment) pairs, or `None`
    /// when no block is free or no group finds a root.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn free_motion(
        &self,
        from: &[f64],
        from_state: &[ContactState],
        m: &[f64],
        step: &[f64],
        f_ext: &[f64],
        presc: &[Point],
    ) -> Option<Vec<Vec<(usize, f64)>>> {
        let dofs = self.block_dofs();
        let amax = |v: &[f64], d: &[usize]| d.iter().fold(0.0f64, |a, &i| a.max(v[i].abs()));
        let free: Vec<bool> = dofs
            .iter()
            .map(|d| !d.is_empty() && amax(m, d) > MODE_RATIO * amax(step, d))
            .collect();
        if !free.contains(&true) {
            return None;
        }
        // groups: free blocks joined by closed contacts
        let nb = dofs.len();
        let mut parent: Vec<usize> = (0..nb).collect();
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for (k, c) in self.cur.contacts.iter().enumerate() {
            let (l, n) = (c.block_l as usize, c.block_m as usize);
            if free[l] && free[n] && from_state[k] != ContactState::Open {
                let (a, b) = (root(&mut parent, l), root(&mut parent, n));
                parent[a] = b;
            }
        }
        let group: Vec<Option<usize>> = (0..nb)
            .map(|b| free[b].then(|| root(&mut parent, b)))
            .collect();
        let mut mf = vec![0.0; m.len()];
        for (b, d) in dofs.iter().enumerate() {
            if free[b] {
                for &i in d {
                    mf[i] = m[i];
                }
            }
        }
        for &(d, _) in &self.pins {
            mf[d] = 0.0;
        }
        let size = self.model_size();
        let slopes = |r: &[f64]| {
            let mut s = vec![0.0; nb];
            for (b, d) in dofs.iter().enumerate() {
                if let Some(g) = group[b] {
                    s[g] += d.iter().map(|&i| r[i] * mf[i]).sum::<f64>();
                }
            }
            s
        };
        let at = |a: f64| -> Vec<f64> { from.iter().zip(&mf).map(|(x, y)| x + a * y).collect() };
        // the slopes read the out-of-balance force at the free blocks' unknowns only: the
        // elements of those blocks give it, at a fraction of a whole trial's cost
        let part = crate::analysis::config::Part::of_blocks(&self.cur, &free);
        let slope_at =
            |a: f64| slopes(&self.out_of_balance(f_ext, &self.f_int_of_part(&at(a), presc, &part)));
        let mmax = mf.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut prev = (0.0, slope_at(0.0));
        let s0 = prev.1.clone();
        let mut alpha: Vec<Option<f64>> = vec![None; nb];
        for k in (0..=MODE_GRID).rev() {
            let a = 0.5f64.powi(k as i32);
            if a * mmax > 0.1 * size {
                break;
            }
            let s = slope_at(a);
            for g in 0..nb {
                if group[g] == Some(g) && alpha[g].is_none() && prev.1[g] > 0.0 && s[g] <= 0.0 {
                    let (a0, s0) = (prev.0, prev.1[g]);
                    alpha[g] = Some(a0 + (a - a0) * s0 / (s0 - s[g]));
                }
            }
            prev = (a, s);
            if (0..nb).all(|g| group[g] != Some(g) || alpha[g].is_some()) {
                break;
            }
        }
        // each group's motion, the groups whose out-of-balance force is largest first
        let mut groups: Vec<usize> = (0..nb).filter(|&g| alpha[g].is_some()).collect();
        groups.sort_by(|a, b| s0[*b].total_cmp(&s0[*a]));
        groups.truncate(MODE_GROUPS);
        let moves: Vec<Vec<(usize, f64)>> = groups
            .iter()
            .map(|&g| {
                let a = alpha[g].unwrap_or(0.0);
                (0..nb)
                    .filter(|&b| group[b] == Some(g))
                    .flat_map(|b| dofs[b].iter().map(|&i| (i, a * mf[i])))
                    .collect()
            })
            .collect();
        if crate::analysis::tracing() {
            let nf = free.iter().filter(|f| **f).count();
            eprintln!(
                "  free motion: {nf} free blocks, {} groups with a root",
                moves.len()
            );
        }
        (!moves.is_empty()).then_some(moves)
    }
}
