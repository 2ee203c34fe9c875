//! The correction solver of the static driver: the linear algebra of a correction. The
//! secant matrix factorized with its symbolic phase reused, the held factorization
//! corrected for the contacts that changed state by a low-rank update, tangent steps by
//! GMRES on the held factor or by an LU, the blended step K_s + ε K₀ where the secant matrix
//! is singular, and the buffers they assemble into (docs/theory.md §4, "Increments and
//! iterations").

use super::*;

/// The linear algebra state of the static driver's corrections: the run's backend and the
/// tangent LU, what the backend holds factorized, and the matrix buffers they assemble
/// into (on the current geometry).
pub(super) struct Corrections<'a> {
    pub kbuf: CsrMatrix,
    /// The contacts' local stiffnesses `kbuf` was last assembled with on `cur`, with no
    /// unknown pinned and nothing added since (`None`: unknown), for
    /// [`System::stiffness_update`].
    pub kbuf_local: Option<Vec<LocalStiffness>>,
    /// A second persistent matrix buffer, on `cur` as `kbuf`: the matrix that the held
    /// secant factorization corrected for a low-rank change solves with
    /// ([`Driver::near_into_aux`]), while `kbuf` holds the iteration matrix; with what
    /// `aux_local` says it holds, as `kbuf_local`. Its values are allocated at its first
    /// use.
    pub aux: CsrMatrix,
    pub aux_local: Option<Vec<LocalStiffness>>,
    /// Whether the secant matrix that the main backend holds factorized (`Held::Secant`;
    /// its values: [`LinearBackend::factorized_values`]) was assembled on `cur` (false
    /// once a converged increment moved the geometry, [`Driver::commit`]).
    pub held_current: bool,
    /// The secant matrix in the held factorization's contact states assembled on `cur`,
    /// when that factorization is of an older geometry (computed once per increment,
    /// [`Driver::near_into_aux`]; empty: not yet).
    pub held_on_cur: Vec<f64>,
    /// GMRES on the held secant factorization failed on a tangent step of the current
    /// increment: the increment's later tangent steps do not try it again
    /// ([`Driver::tangent_with_secant_factor`]).
    pub gmres_failed: bool,
    /// The elastic stiffness K₀ on `cur` (no unknowns pinned), assembled when first needed
    /// after a commit ([`Driver::elastic_on_cur`]).
    pub k0: Option<CsrMatrix>,
    pub backend: &'a mut dyn LinearBackend,
    pub lu: Option<Box<dyn LinearBackend>>,
    /// What the main backend holds factorized.
    pub held: Held,
}

/// A secant correction reuses the held factorization as a preconditioner when at most this
/// many contacts changed state since it was computed: conjugate gradients need about one
/// iteration per unit of rank of the change plus three for a change of geometry, and an
/// iteration costs a tenth to a twentieth of a numeric factorization. Since the low-rank
/// path ([`Driver::changed`]) takes the changes on an unchanged geometry, this applies to
/// the first correction of an increment and to changes the backend refused
/// (docs/decisions/0012-low-rank-correction-limits.md).
pub(super) const REUSE_MAX_CHANGES: usize = 4;
/// The iteration matrix is updated ([`System::stiffness_update`]) rather than assembled
/// again when at most 1/`UPDATE_MAX_SHARE` of the contacts changed their local stiffness:
/// the update finds the entries and elements a changed contact touches one by one, which
/// costs more than assembling all contacts once many changed (a tangent step after a
/// secant one changes every slipping contact's; docs/decisions/0010-gmres-tangent-steps.md).
pub(super) const UPDATE_MAX_SHARE: usize = 32;
/// GMRES iterations of a tangent correction preconditioned with the held secant
/// factorization ([`Driver::tangent_with_secant_factor`]) after which the tangent matrix is
/// factorized with LU instead: an LU of the tangent costs about 40 preconditioned
/// iterations (docs/decisions/0010-gmres-tangent-steps.md).
pub(super) const TANGENT_MAX_ITERATIONS: usize = 30;
/// A tangent correction of the secant strategy that GMRES on the secant factorization did
/// not solve is solved with an LU factorization of the tangent only when the held Cholesky
/// factor has at most this many entries; above, the secant correction is taken instead
/// (an LU of the 10⁶-unknown wall's tangent ran out of memory;
/// docs/decisions/0011-tangent-lu-size-limit.md).
pub(super) const TANGENT_LU_MAX_ENTRIES: usize = 50_000_000;
/// The loosest relative residual of a tangent correction by GMRES.
pub(super) const TANGENT_TOLERANCE: f64 = 1e-3;
/// Conjugate-gradient iterations after which the reused factorization stops paying and the
/// secant matrix is refactorized.
pub(super) const REUSE_MAX_ITERATIONS: usize = 8;
/// On the rigid P2 wall a secant correction is solved with the held factorization
/// corrected for the change ([`Driver::changed`]) when at most this many contacts changed
/// state since it was computed (each a change of rank ≤ 2); larger models allow more
/// ([`Driver::low_rank_limit`]; docs/decisions/0012-low-rank-correction-limits.md).
pub(super) const LOW_RANK_MAX_CHANGES: usize = 64;
/// Unknowns of the rigid P2 wall, where [`LOW_RANK_MAX_CHANGES`] was measured. The
/// break-even rank of the correction grows with the model ([`Driver::low_rank_limit`]).
pub(super) const LOW_RANK_REFERENCE_DOFS: f64 = 4860.0;
/// The most contacts a low-rank correction takes on any model: the backend refuses ranks
/// above its own limit (`dfem_kernels::faer_backend::CHANGED_MAX_RANK` = 256), and a
/// contact that changed state is a change of rank 1 or 2.
pub(super) const LOW_RANK_CAP: usize = 256;
/// Relative residual of a correction computed with a reused factorization: far below the
/// out-of-balance tolerances (≥ 1e-8), so the iterations see no difference.
pub(super) const REUSE_TOLERANCE: f64 = 1e-10;

/// The backend of the tangent (nonsymmetric) matrices in `lu`, created at its first use
/// for the run's backend `main` ([`crate::solve::tangent_backend`]).
pub(super) fn tangent_lu<'b>(
    lu: &'b mut Option<Box<dyn LinearBackend>>,
    main: &str,
) -> Result<&'b mut dyn LinearBackend> {
    if lu.is_none() {
        *lu = Some(crate::solve::tangent_backend(main)?);
    }
    Ok(lu.as_mut().expect("created above").as_mut())
}

impl Driver<'_> {
    /// Take the pinned unknowns out of `k`: their rows and columns are zeroed but for the
    /// diagonal (kept, or the mean diagonal where it is not positive), so that a solve
    /// leaves them unchanged when their right-hand side is zero.
    pub(super) fn pin_rows(pins: &[(usize, f64)], k: &mut CsrMatrix) {
        if pins.is_empty() {
            return;
        }
        let n = k.pattern.n();
        let mut pinned = vec![false; n];
        for &(d, _) in pins {
            pinned[d] = true;
        }
        let pattern = k.pattern.clone();
        let rp = pattern.row_ptr();
        // row of every stored entry, in storage order
        let rows: Vec<usize> = (0..n)
            .flat_map(|i| std::iter::repeat_n(i, rp[i + 1] - rp[i]))
            .collect();
        let ci = pattern.col_idx();
        let diag_sum: f64 = rows
            .iter()
            .zip(ci)
            .zip(&k.values)
            .filter(|((i, j), _)| **i == **j as usize)
            .map(|(_, v)| v.abs())
            .sum();
        let mean = (diag_sum / n.max(1) as f64).max(1e-300);
        for ((&i, &j), v) in rows.iter().zip(ci).zip(k.values.iter_mut()) {
            let j = j as usize;
            if i == j {
                if pinned[i] && *v <= 0.0 {
                    *v = mean;
                }
            } else if pinned[i] || pinned[j] {
                *v = 0.0;
            }
        }
    }

    /// The elastic stiffness K₀ (N/m) on the geometry of the last converged increment,
    /// no unknowns pinned: assembled once per increment, when first asked for (the
    /// blended steps of a singular secant matrix ask for it at every iteration).
    pub(super) fn elastic_on_cur(&mut self) -> &CsrMatrix {
        if self.lin.k0.is_none() {
            let local = self.elastic_local();
            let mut k = CsrMatrix::zeros(self.system.plan.pattern().clone());
            self.system.stiffness_into(&self.cur, &local, &mut k);
            self.lin.k0 = Some(k);
        }
        self.lin.k0.as_ref().expect("assembled above")
    }

    /// Solve with the elastic stiffness of the initial configuration (factorized once).
    pub(super) fn solve_k0(&mut self, rhs: &mut [f64]) -> Result<bool> {
        if self.lin.held != Held::K0 {
            let mut k = self.elastic_on_cur().clone();
            Self::pin_rows(&self.pins, &mut k);
            let ok = self.lin.backend.factorize(&k).is_ok()
                && !crate::analysis::singular_pivots(&*self.lin.backend);
            self.lin.held = Held::K0;
            if !ok {
                return Ok(false);
            }
        }
        Ok(self.lin.backend.solve(rhs).is_ok())
    }

    /// One correction δ = K⁻¹ r with the strategy's matrix; `None` when that matrix is
    /// singular (a mechanism in the current contact states).
    /// `states`: the contact states the matrix is built in (the trial's, or at the first
    /// iteration of an increment those of the last converged one).
    ///
    /// The matrix is assembled on the geometry of the last converged increment, not the
    /// trial's: the out-of-balance force, which decides convergence, is always that of the
    /// trial geometry (the updated Lagrangian scheme of docs/theory.md §4), so the converged
    /// state is the same, while the iteration matrix stays fixed within an increment but
    /// for the contacts that change state. An iteration in which no contact changed then
    /// finds the matrix bit-identical and skips the factorization (only a solve), and one
    /// in which a few changed is a low-rank change of the held factorization, which
    /// [`Driver::reuse`] exploits.
    pub(super) fn correction(
        &mut self,
        trial: &Trial,
        states: &[ContactState],
        r: &[f64],
        tangent: bool,
    ) -> Result<Option<Vec<f64>>> {
        let mut x = r.to_vec();
        match self.settings.strategy {
            Strategy::Initial => Ok(self.solve_k0(&mut x)?.then_some(x)),
            Strategy::Secant | Strategy::Newton => {
                let mut newton = self.settings.strategy == Strategy::Newton || tangent;
                if newton && self.settings.strategy == Strategy::Secant {
                    if let Some(x) = self.tangent_with_secant_factor(trial, states, r) {
                        return Ok(Some(x));
                    }
                    // no LU of the tangent where its factor would not fit: the secant
                    // correction instead (the safeguard's alternative step)
                    newton = !self.tangent_lu_too_large();
                    if !newton {
                        self.stats.tangent_lu_skipped += 1;
                    }
                }
                let local = self.local_stiffness(trial, states, newton);
                self.assemble_kbuf(local);
                if !newton {
                    if let Some(x) = self.changed(states, r) {
                        return Ok(Some(x));
                    }
                    if let Some(x) = self.reuse(states, r) {
                        return Ok(Some(x));
                    }
                    self.hold_secant(states);
                }
                let backend: &mut dyn LinearBackend = if newton {
                    tangent_lu(&mut self.lin.lu, self.lin.backend.name())?
                } else {
                    &mut *self.lin.backend
                };
                let ok = backend.factorize(&self.lin.kbuf).is_ok()
                    && (newton || !crate::analysis::singular_pivots(&*backend))
                    && backend.solve(&mut x).is_ok()
                    && x.iter().all(|v| v.is_finite());
                // LU has no pivot measure: a matrix singular up to round-off shows as a
                // step of the size of the model
                let size = self.model_size();
                let huge = newton && x.iter().any(|v| v.abs() > 0.1 * size);
                Ok((ok && !huge).then_some(x))
            }
        }
    }

    /// Whether an LU factorization of the tangent would exceed
    /// [`TANGENT_LU_MAX_ENTRIES`], estimated from the held Cholesky factor's entries
    /// (`SolverStats::factor_nnz`; an LU of the same matrix holds L and U with pivoting's
    /// extra fill, several times as many) or, for a backend that does not report them
    /// (iterative ones), from the matrix's stored entries × 8 (the ratio of the
    /// Cholesky factor's entries to the matrix's on the walls of docs/performance.md, "Memory").
    /// The size of the model alone decides, never the machine's free memory, so that the
    /// results do not depend on the machine.
    pub(super) fn tangent_lu_too_large(&self) -> bool {
        let factor = match self.lin.backend.stats().factor_nnz {
            0 => 8 * self.lin.kbuf.values.len(),
            f => f,
        };
        factor > TANGENT_LU_MAX_ENTRIES
    }

    /// Assemble the iteration matrix for the contacts' local stiffnesses `local` into
    /// `kbuf`, on the geometry of the last converged increment, with the pinned unknowns
    /// taken out. When `kbuf` holds the matrix of the same geometry for other local
    /// stiffnesses, only the contacts whose local stiffness changed are assembled again
    /// ([`System::stiffness_update`]: bit-identical to a whole assembly).
    pub(super) fn assemble_kbuf(&mut self, local: Vec<LocalStiffness>) {
        Self::assemble(
            &self.system,
            &self.cur,
            &self.pins,
            local,
            &mut self.lin.kbuf,
            &mut self.lin.kbuf_local,
        );
    }

    /// [`Driver::assemble_kbuf`] into `aux` (the second buffer, tracked by `aux_local`).
    pub(super) fn assemble_aux(&mut self, local: Vec<LocalStiffness>) {
        Self::assemble(
            &self.system,
            &self.cur,
            &self.pins,
            local,
            &mut self.lin.aux,
            &mut self.lin.aux_local,
        );
    }

    /// Assemble the matrix of the local stiffnesses `local` on `mesh` into `out`, with the
    /// unknowns `pins` taken out; `out_local`: what `out` holds (`None`: unknown), for
    /// the update of only the contacts that changed.
    pub(super) fn assemble(
        system: &System,
        mesh: &Mesh,
        pins: &[(usize, f64)],
        local: Vec<LocalStiffness>,
        out: &mut CsrMatrix,
        out_local: &mut Option<Vec<LocalStiffness>>,
    ) {
        let few = |prev: &[LocalStiffness]| {
            let changed = prev.iter().zip(&local).filter(|(a, b)| a != b).count();
            UPDATE_MAX_SHARE * changed <= local.len()
        };
        match out_local.take() {
            Some(prev) if pins.is_empty() && few(&prev) => {
                system.stiffness_update(mesh, &prev, &local, out)
            }
            _ => system.stiffness_into(mesh, &local, out),
        }
        if pins.is_empty() {
            *out_local = Some(local);
        } else {
            Self::pin_rows(pins, out);
        }
    }

    /// Record that the main backend holds (or is about to hold) the factorization of
    /// `kbuf`, the secant matrix in `states` on `cur`.
    pub(super) fn hold_secant(&mut self, states: &[ContactState]) {
        self.lin.held = Held::Secant(states.to_vec());
        self.lin.held_current = true;
        self.lin.held_on_cur.clear();
    }

    /// `aux` ← the matrix that the held secant factorization, of H = K_s(held states) on
    /// its own geometry, is to be corrected to ([`LinearBackend::solve_changed`]) for the
    /// secant matrix K_s(`states`) on `cur`: K_s(`states`) itself when the factorization
    /// is of `cur`; on an older geometry, H plus the change of state on `cur`,
    ///
    ///   N = H + K_s(`states`) − K_s(held states)   (entry by entry; H where the two agree),
    ///
    /// a change of H on the contacts that changed state only (rank ≤ 2 each), which the
    /// backend's low-rank correction accepts, and near K_s(`states`): the two differ by
    /// the geometry's change over the increments since the factorization (mm on m-sized
    /// blocks), which the conjugate gradients of [`Driver::reuse`] or the GMRES of
    /// [`Driver::tangent_with_secant_factor`] iterate on. `in_kbuf`: `kbuf` holds
    /// K_s(`states`) (else it is assembled into `aux`). `false` when no secant
    /// factorization is held, or the backend does not give its values (then it offers no
    /// `solve_changed` either).
    pub(super) fn near_into_aux(&mut self, states: &[ContactState], in_kbuf: bool) -> bool {
        let Held::Secant(held_states) = &self.lin.held else {
            return false;
        };
        if self.lin.backend.factorized_values().is_none() {
            return false;
        }
        if self.lin.aux.values.is_empty() {
            self.lin.aux.values = vec![0.0; self.lin.kbuf.values.len()];
        }
        if !self.lin.held_current && self.lin.held_on_cur.is_empty() {
            let local = self.secant_local(&held_states.clone());
            self.assemble_aux(local);
            self.lin.held_on_cur.clone_from(&self.lin.aux.values);
        }
        if in_kbuf {
            self.lin.aux.values.copy_from_slice(&self.lin.kbuf.values);
            self.lin.aux_local.clone_from(&self.lin.kbuf_local);
        } else {
            let local = self.secant_local(states);
            self.assemble_aux(local);
        }
        if !self.lin.held_current {
            // exactly H where the contact states agree, so that the change read by the
            // backend is the changed contacts' alone
            let held = self
                .lin
                .backend
                .factorized_values()
                .expect("checked above; nothing factorized since");
            for ((a, h), b) in self
                .lin
                .aux
                .values
                .iter_mut()
                .zip(held)
                .zip(&self.lin.held_on_cur)
            {
                *a = if *a == *b { *h } else { h + (*a - b) };
            }
            self.lin.aux_local = None;
        }
        true
    }

    /// The tangent correction K_t⁻¹ r of the secant strategy (a symmetric secant matrix
    /// plus the slipping contacts' friction–normal coupling) by GMRES preconditioned with
    /// the held secant factorization (factorized first, in `states`, when none is held),
    /// instead of an LU factorization of K_t, which costs several Cholesky
    /// factorizations. `None`: the caller factorizes K_t (GMRES did not converge within
    /// [`TANGENT_MAX_ITERATIONS`], or the secant matrix is singular).
    pub(super) fn tangent_with_secant_factor(
        &mut self,
        trial: &Trial,
        states: &[ContactState],
        r: &[f64],
    ) -> Option<Vec<f64>> {
        if self.lin.gmres_failed {
            // it failed earlier in this increment: on the 10⁶-unknown wall
            // (docs/decisions/0011-tangent-lu-size-limit.md) it then failed at every later tangent step of the
            // increment (31 in a row, 30 iterations each)
            return None;
        }
        if !matches!(self.lin.held, Held::Secant(_)) {
            let local = self.local_stiffness(trial, states, false);
            self.assemble_kbuf(local);
            self.lin.held = Held::Nothing;
            let ok = self.lin.backend.factorize(&self.lin.kbuf).is_ok()
                && !crate::analysis::singular_pivots(&*self.lin.backend);
            if !ok {
                return None;
            }
            self.hold_secant(states);
        }
        // the secant matrix in `states` (in `aux`), when the held factorization is of a
        // few contacts in other states (on this geometry or, corrected for the change of
        // state, an older one: `near_into_aux`): GMRES is then preconditioned with the
        // factorization corrected for them (`LinearBackend::solve_changed`), which leaves
        // the friction–normal coupling of the slipping contacts alone to iterate on (and
        // the geometry's change)
        let near = match self.changed_since_factor(states) {
            Some(c) if c > 0 && c <= self.low_rank_limit() => self.near_into_aux(states, false),
            _ => false,
        };
        let local = self.local_stiffness(trial, states, true);
        self.assemble_kbuf(local);
        // an inexact Newton step: the linear residual left is a tenth of what counts as
        // converged (relative to ‖r‖: between REUSE_TOLERANCE and TANGENT_TOLERANCE), so
        // that the step converges the increment as the exact one does, up to the
        // nonlinearity, which the next iteration corrects either way
        let rn = Self::norm(r);
        let tolerance =
            (0.1 * self.converged_norm / rn.max(1e-300)).clamp(REUSE_TOLERANCE, TANGENT_TOLERANCE);
        let (out, corrected) = match near {
            true => crate::solve::reuse::gmres_with_changed_factor(
                &self.lin.kbuf,
                &self.lin.aux,
                &mut *self.lin.backend,
                r,
                tolerance,
                TANGENT_MAX_ITERATIONS,
            ),
            false => (
                crate::solve::reuse::gmres_with_factor(
                    &self.lin.kbuf,
                    &mut *self.lin.backend,
                    r,
                    tolerance,
                    TANGENT_MAX_ITERATIONS,
                ),
                false,
            ),
        };
        let Some(out) = out else {
            self.lin.gmres_failed = true;
            if crate::analysis::tracing() {
                eprintln!("  tangent by GMRES failed (corrected preconditioner: {corrected})");
            }
            return None;
        };
        // a step of the size of the model: K_t singular up to round-off, as in `correction`
        let size = self.model_size();
        if out.x.iter().any(|v| v.abs() > 0.1 * size) {
            return None;
        }
        self.stats.reused_factorizations += 1;
        self.stats.reuse_iterations += out.iterations;
        if crate::analysis::tracing() {
            eprintln!(
                "  tangent by GMRES: {} iterations (corrected preconditioner: {corrected})",
                out.iterations
            );
        }
        Some(out.x)
    }

    /// Contacts whose state in `now` differs from that of the held secant factorization;
    /// `None` when no secant factorization is held.
    pub(super) fn changed_since_factor(&self, now: &[ContactState]) -> Option<usize> {
        let Held::Secant(states) = &self.lin.held else {
            return None;
        };
        Some(states.iter().zip(now).filter(|(a, b)| a != b).count())
    }

    /// The most contacts changed state since the held factorization for which the
    /// low-rank correction ([`Driver::changed`], and across increments [`Driver::reuse`])
    /// is tried instead of a refactorization: [`LOW_RANK_MAX_CHANGES`] × √(n / n_P2), n the
    /// unknowns, between [`LOW_RANK_MAX_CHANGES`] and [`LOW_RANK_CAP`]. A correction of
    /// rank r costs about r solves restricted to the paths of the changed unknowns to the
    /// root of the elimination tree, whose top separators (√n unknowns on a wall, dense)
    /// make a path cost ∝ n, while a nested-dissection factorization of a wall costs
    /// ∝ n^1.5: the break-even rank grows as √n. Measured (docs/performance.md, "The
    /// cost of a secant iteration"): a correction at 0.45 of a
    /// refactorization for a median 22 changed contacts on the rigid P2 wall (4,860
    /// unknowns), at 0.13–0.17 for 39 on the 10⁵-unknown wall. The size of the model alone
    /// decides (no timing), so that the results do not depend on the machine.
    pub(super) fn low_rank_limit(&self) -> usize {
        let n = self.lin.kbuf.pattern.n() as f64;
        let scaled = LOW_RANK_MAX_CHANGES as f64 * (n / LOW_RANK_REFERENCE_DOFS).sqrt();
        (scaled as usize).clamp(LOW_RANK_MAX_CHANGES, LOW_RANK_CAP)
    }

    /// The secant correction K_s⁻¹ r by the held secant factorization corrected exactly
    /// for the contacts that changed state since it was computed
    /// ([`LinearBackend::solve_changed`]: the Woodbury identity inside the factor, no
    /// iteration), when between 1 and [`Driver::low_rank_limit`] did (`kbuf` holds the new
    /// K_s). Within an increment the iteration matrix changes only by those contacts'
    /// stiffness (it is assembled on the last converged geometry, see
    /// [`Driver::correction`]); across increments every entry changes and the backend
    /// refuses after reading a few of them. `None`: the backend refused (unsupported, a
    /// rank above its limit, a new geometry, K_s not positive definite) or the result's
    /// true residual is above 10 × [`REUSE_TOLERANCE`]; then [`Driver::reuse`] or a
    /// refactorization.
    pub(super) fn changed(&mut self, now: &[ContactState], r: &[f64]) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        if changed == 0 || changed > self.low_rank_limit() || !self.lin.held_current {
            return None;
        }
        let start = std::time::Instant::now();
        let out = crate::solve::reuse::solve_changed(
            &self.lin.kbuf,
            &mut *self.lin.backend,
            r,
            10.0 * REUSE_TOLERANCE,
        )?;
        self.stats.low_rank_corrections += 1;
        let rank = self.lin.backend.stats().last_changed_rank;
        if crate::analysis::tracing() {
            eprintln!(
                "  low-rank correction: {changed} contacts changed, rank {rank}, {:.3e} s",
                start.elapsed().as_secs_f64()
            );
        }
        self.stats.low_rank_max_rank = self.stats.low_rank_max_rank.max(rank);
        Some(out.x)
    }

    /// The secant correction K_s⁻¹ r computed with the held secant factorization as a
    /// preconditioner, when few contacts changed state since it was computed (`kbuf` holds
    /// the new K_s). `None`: refactorize.
    pub(super) fn reuse(&mut self, now: &[ContactState], r: &[f64]) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        // across increments (the factorization of an older geometry) the held factor
        // corrected for the change of state (`near_into_aux`) preconditions, up to the
        // low-rank path's limit of changed contacts
        let across = !self.lin.held_current && changed > 0 && self.settings.reuse_across_increments;
        let limit = if across {
            self.low_rank_limit()
        } else {
            REUSE_MAX_CHANGES
        };
        if changed > limit {
            if crate::analysis::tracing() {
                eprintln!("  refactorization: {changed} contacts changed");
            }
            return None;
        }
        let out = if across {
            if !self.near_into_aux(now, true) {
                // the backend gives no corrected factor: refactorize
                return None;
            }
            crate::solve::reuse::solve_with_changed_factor(
                &self.lin.kbuf,
                &self.lin.aux,
                &mut *self.lin.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        } else {
            crate::solve::reuse::solve_with_factor(
                &self.lin.kbuf,
                &mut *self.lin.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        };
        if crate::analysis::tracing() {
            eprintln!(
                "  PCG on the held factor: {changed} contacts changed, {} geometry, {:?} iterations",
                if self.lin.held_current { "same" } else { "older" },
                out.as_ref().map(|o| o.iterations)
            );
        }
        let out = out?;
        self.stats.reused_factorizations += 1;
        self.stats.reuse_iterations += out.iterations;
        Some(out.x)
    }

    /// The mechanism of a singular secant matrix K_s: the solution of (K_s + ε K₀) x = r,
    /// ε = 10⁻⁸, is dominated by the part of r that K_s cannot resist, i.e. by K_s's null
    /// space (the blocks' free motions).
    pub(super) fn mechanism_mode(&mut self, trial: &Trial, r: &[f64]) -> Result<Vec<f64>> {
        Ok(self
            .blended_step(trial, r, 1e-8)?
            .unwrap_or_else(|| vec![0.0; r.len()]))
    }

    /// Solve (K_s + ε K₀) x = r, both in the configuration of the last converged
    /// increment (as every iteration matrix: see [`Driver::correction`]).
    pub(super) fn blended_step(
        &mut self,
        trial: &Trial,
        r: &[f64],
        eps: f64,
    ) -> Result<Option<Vec<f64>>> {
        let local = self.local_stiffness(trial, &trial.state, false);
        if self.pins.is_empty() {
            // K_s: where `kbuf` holds the secant matrix of these or nearby states (the
            // correction that found K_s singular assembled it), only the contacts whose
            // stiffness differs are assembled again (bit-identical to a whole assembly)
            self.assemble_kbuf(local);
        } else {
            // (pinned rows are pinned once, after the blend)
            self.system
                .stiffness_into(&self.cur, &local, &mut self.lin.kbuf);
        }
        self.lin.kbuf_local = None;
        self.elastic_on_cur();
        let k0 = self.lin.k0.as_ref().expect("assembled above");
        for (a, b) in self.lin.kbuf.values.iter_mut().zip(&k0.values) {
            *a += eps * b;
        }
        Self::pin_rows(&self.pins, &mut self.lin.kbuf);
        self.lin.held = Held::Nothing;
        let mut x = r.to_vec();
        let ok = self.lin.backend.factorize(&self.lin.kbuf).is_ok()
            && self.lin.backend.solve(&mut x).is_ok()
            && x.iter().all(|v| v.is_finite());
        Ok(ok.then_some(x))
    }
}
