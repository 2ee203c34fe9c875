//! The correction solver shared by the static and the dynamic drivers: the linear algebra
//! of a correction δ = K⁻¹ r (docs/theory.md §4, "Increments and iterations"). The drivers
//! assemble their matrices (secant, tangent, effective) into its buffers; it solves with
//! a fresh factorization, with the held one corrected exactly for the contacts that
//! changed state (a low-rank update), with the held one as a preconditioner (conjugate
//! gradients for a secant matrix, GMRES for a tangent one), or with an LU of the tangent
//! from the same backend registry and options as `--solver`
//! ([`crate::solve::tangent_backend`]). It keeps what the backend holds factorized, so
//! that a correction in the same contact states is a solve only.

use super::Stats;
use crate::assembly::{LocalStiffness, System};
use crate::material::ContactState;
use crate::mesh::Mesh;
use crate::solve::LinearBackend;
use crate::Result;
use dfem_kernels::{CsrMatrix, CsrPattern, SolverStats};
use std::sync::Arc;

/// The matrix whose factorization the main backend holds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Held {
    Nothing,
    /// The elastic stiffness of the initial configuration.
    K0,
    /// A secant stiffness, with the contact states it was assembled for.
    Secant(Vec<ContactState>),
}

/// One of the solver's two matrix buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Buffer {
    /// `kbuf`: the iteration matrix.
    Main,
    /// `aux`: a second matrix on the same pattern (the static driver's matrix the held
    /// factorization is corrected to, the dynamic driver's tangent effective matrix).
    Aux,
}

/// The linear algebra state of a driver's corrections: the run's backend and the tangent
/// LU, what the backend holds factorized, and the matrix buffers the driver assembles
/// into (the static driver's on the geometry of its last converged increment).
pub(crate) struct CorrectionSolver<'a> {
    pub kbuf: CsrMatrix,
    /// The contacts' local stiffnesses `kbuf` was last assembled with, with no unknown
    /// pinned and nothing added since (`None`: unknown), for [`System::stiffness_update`].
    pub kbuf_local: Option<Vec<LocalStiffness>>,
    /// The second buffer, on `kbuf`'s pattern (its values allocated at its first use,
    /// [`CorrectionSolver::aux_values`]), with what `aux_local` says it holds, as
    /// `kbuf_local`.
    pub aux: CsrMatrix,
    pub aux_local: Option<Vec<LocalStiffness>>,
    /// Whether the secant matrix that the main backend holds factorized (`Held::Secant`;
    /// its values: [`LinearBackend::factorized_values`]) was assembled on the current
    /// geometry (false once a converged increment moved it, [`CorrectionSolver::moved`]).
    pub held_current: bool,
    /// The secant matrix in the held factorization's contact states assembled on the
    /// current geometry, when that factorization is of an older one (computed once per
    /// increment by the static driver's `near_into_aux`; empty: not yet).
    pub held_on_cur: Vec<f64>,
    /// GMRES on the held factorization failed on a tangent step of the current
    /// increment: the increment's later tangent steps do not try it again.
    pub gmres_failed: bool,
    /// The elastic stiffness K₀ on the current geometry (no unknowns pinned), assembled
    /// when first needed after a commit.
    pub k0: Option<CsrMatrix>,
    pub backend: &'a mut dyn LinearBackend,
    lu: Option<Box<dyn LinearBackend>>,
    /// What the main backend holds factorized.
    pub held: Held,
}

/// A secant correction reuses the held factorization as a preconditioner when at most this
/// many contacts changed state since it was computed: conjugate gradients need about one
/// iteration per unit of rank of the change plus three for a change of geometry, and an
/// iteration costs a tenth to a twentieth of a numeric factorization. Since the low-rank
/// path ([`CorrectionSolver::changed`]) takes the changes on an unchanged geometry, this applies to
/// the first correction of an increment and to changes the backend refused
/// (docs/decisions/0012-low-rank-correction-limits.md).
pub(crate) const REUSE_MAX_CHANGES: usize = 4;
/// The iteration matrix is updated ([`System::stiffness_update`]) rather than assembled
/// again when at most 1/`UPDATE_MAX_SHARE` of the contacts changed their local stiffness:
/// the update finds the entries and elements a changed contact touches one by one, which
/// costs more than assembling all contacts once many changed (a tangent step after a
/// secant one changes every slipping contact's; docs/decisions/0010-gmres-tangent-steps.md).
pub(crate) const UPDATE_MAX_SHARE: usize = 32;
/// GMRES iterations of a tangent correction preconditioned with the held secant
/// factorization ([`CorrectionSolver::gmres`]) after which the tangent matrix is
/// factorized with LU instead: an LU of the tangent costs about 40 preconditioned
/// iterations (docs/decisions/0010-gmres-tangent-steps.md).
pub(crate) const TANGENT_MAX_ITERATIONS: usize = 30;
/// A tangent correction of the secant strategy that GMRES on the secant factorization did
/// not solve is solved with an LU factorization of the tangent only when the held Cholesky
/// factor has at most this many entries; above, the secant correction is taken instead
/// (an LU of the 10⁶-unknown wall's tangent ran out of memory;
/// docs/decisions/0011-tangent-lu-size-limit.md).
pub(crate) const TANGENT_LU_MAX_ENTRIES: usize = 50_000_000;
/// The loosest relative residual of a tangent correction by GMRES.
pub(crate) const TANGENT_TOLERANCE: f64 = 1e-3;
/// Conjugate-gradient iterations after which the reused factorization stops paying and the
/// secant matrix is refactorized.
pub(crate) const REUSE_MAX_ITERATIONS: usize = 8;
/// On the rigid P2 wall a secant correction is solved with the held factorization
/// corrected for the change ([`CorrectionSolver::changed`]) when at most this many contacts changed
/// state since it was computed (each a change of rank ≤ 2); larger models allow more
/// ([`CorrectionSolver::low_rank_limit`]; docs/decisions/0012-low-rank-correction-limits.md).
pub(crate) const LOW_RANK_MAX_CHANGES: usize = 64;
/// Unknowns of the rigid P2 wall, where [`LOW_RANK_MAX_CHANGES`] was measured. The
/// break-even rank of the correction grows with the model ([`CorrectionSolver::low_rank_limit`]).
pub(crate) const LOW_RANK_REFERENCE_DOFS: f64 = 4860.0;
/// The most contacts a low-rank correction takes on any model: the backend refuses ranks
/// above its own limit (`dfem_kernels::faer_backend::CHANGED_MAX_RANK` = 256), and a
/// contact that changed state is a change of rank 1 or 2.
pub(crate) const LOW_RANK_CAP: usize = 256;
/// Relative residual of a correction computed with a reused factorization: far below the
/// out-of-balance tolerances (≥ 1e-8), so the iterations see no difference.
pub(crate) const REUSE_TOLERANCE: f64 = 1e-10;

impl<'a> CorrectionSolver<'a> {
    /// A solver with `backend` and empty buffers on `pattern`'s matrix (no values in
    /// `aux` until its first use: most runs never need it, and on the 10⁶-unknown wall
    /// they are as large as the matrix's).
    pub fn new(backend: &'a mut dyn LinearBackend, pattern: Arc<CsrPattern>) -> Self {
        let kbuf = CsrMatrix::zeros(pattern);
        let aux = CsrMatrix {
            pattern: kbuf.pattern.clone(),
            values: Vec::new(),
        };
        CorrectionSolver {
            kbuf,
            kbuf_local: None,
            aux,
            aux_local: None,
            held_current: false,
            held_on_cur: Vec::new(),
            gmres_failed: false,
            k0: None,
            backend,
            lu: None,
            held: Held::Nothing,
        }
    }

    /// New buffers for a new contact set's `pattern` (the dynamic driver's search for new
    /// contacts); nothing held.
    pub fn new_pattern(&mut self, pattern: Arc<CsrPattern>) {
        self.kbuf = CsrMatrix::zeros(pattern);
        self.aux = CsrMatrix {
            pattern: self.kbuf.pattern.clone(),
            values: Vec::new(),
        };
        self.kbuf_local = None;
        self.aux_local = None;
        self.k0 = None;
        self.held = Held::Nothing;
        self.held_on_cur.clear();
    }

    /// `aux` with its values allocated (zeros at its first use).
    pub fn aux_values(&mut self) -> &mut CsrMatrix {
        if self.aux.values.is_empty() {
            self.aux.values = vec![0.0; self.kbuf.values.len()];
        }
        &mut self.aux
    }

    /// A converged increment moved the geometry: the buffers' contents are of the old
    /// one, and a held secant factorization is now of an older geometry (across
    /// increments it preconditions with the change of state corrected,
    /// [`CorrectionSolver::reuse`]).
    pub fn moved(&mut self) {
        self.k0 = None;
        self.kbuf_local = None;
        self.aux_local = None;
        self.held_current = false;
        self.held_on_cur.clear();
        self.gmres_failed = false;
    }

    /// The backend of the tangent (nonsymmetric) matrices, created at its first use for
    /// the run's backend ([`crate::solve::tangent_backend`]).
    pub fn tangent_lu(&mut self) -> Result<&mut dyn LinearBackend> {
        if self.lu.is_none() {
            self.lu = Some(crate::solve::tangent_backend(self.backend.name())?);
        }
        Ok(self.lu.as_mut().expect("created above").as_mut())
    }

    /// The tangent LU's counters, when it was created.
    pub fn tangent_stats(&self) -> Option<SolverStats> {
        self.lu.as_ref().map(|l| l.stats().clone())
    }

    /// Factorize `kbuf` with the main backend (which then holds nothing known to the
    /// static driver's reuse); `check_pivots`: a factorization with a pivot below
    /// [`crate::analysis::SINGULAR_PIVOT_RATIO`] counts as failed (a singular matrix).
    pub fn factorize(&mut self, check_pivots: bool) -> bool {
        self.held = Held::Nothing;
        self.backend.factorize(&self.kbuf).is_ok()
            && !(check_pivots && crate::analysis::singular_pivots(&*self.backend))
    }

    /// Solve with the main backend's factorization in place: `false` when the solve
    /// fails or gives a value that is not finite.
    pub fn solve(&mut self, x: &mut [f64]) -> bool {
        self.backend.solve(x).is_ok() && x.iter().all(|v| v.is_finite())
    }

    /// Solve `kbuf` x = r with a fresh factorization: the tangent LU (`tangent`: `kbuf`
    /// nonsymmetric, any pivot accepted) or the main backend (a pivot below
    /// [`crate::analysis::SINGULAR_PIVOT_RATIO`] fails). `None` when the matrix cannot be
    /// factorized or the solution is not finite. What the main backend holds is the
    /// caller's to record ([`CorrectionSolver::hold_secant`]).
    pub fn factor_solve(&mut self, tangent: bool, r: &[f64]) -> Result<Option<Vec<f64>>> {
        let mut x = r.to_vec();
        Ok(self.factor_solve_each(tangent, &mut [&mut x])?.then_some(x))
    }

    /// [`CorrectionSolver::factor_solve`] for every right-hand side of `xs`, in place:
    /// `false` when the factorization or a solve fails or a solution is not finite.
    pub fn factor_solve_each(&mut self, tangent: bool, xs: &mut [&mut Vec<f64>]) -> Result<bool> {
        let backend: &mut dyn LinearBackend = if tangent {
            self.tangent_lu()?;
            self.lu.as_mut().expect("created above").as_mut()
        } else {
            &mut *self.backend
        };
        let ok = backend.factorize(&self.kbuf).is_ok()
            && (tangent || !crate::analysis::singular_pivots(&*backend))
            && xs.iter_mut().all(|x| backend.solve(x).is_ok())
            && xs.iter().all(|x| x.iter().all(|v| v.is_finite()));
        Ok(ok)
    }

    /// Take the pinned unknowns out of `k`: their rows and columns are zeroed but for the
    /// diagonal (kept, or the mean diagonal where it is not positive), so that a solve
    /// leaves them unchanged when their right-hand side is zero.
    pub fn pin_rows(pins: &[(usize, f64)], k: &mut CsrMatrix) {
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

    /// Assemble the matrix of the contacts' local stiffnesses `local` on `at.mesh` into the
    /// buffer `into`, with the unknowns `at.pins` taken out. When the buffer holds the
    /// matrix of the same geometry for other local stiffnesses, only the contacts whose
    /// local stiffness changed are assembled again ([`System::stiffness_update`]:
    /// bit-identical to a whole assembly), when at most 1/[`UPDATE_MAX_SHARE`] of them did.
    pub fn assemble(
        &mut self,
        at: &Assembly<'_, impl Secant>,
        local: Vec<LocalStiffness>,
        into: Buffer,
    ) {
        let (out, out_local) = match into {
            Buffer::Main => (&mut self.kbuf, &mut self.kbuf_local),
            Buffer::Aux => (&mut self.aux, &mut self.aux_local),
        };
        let few = |prev: &[LocalStiffness]| {
            let changed = prev.iter().zip(&local).filter(|(a, b)| a != b).count();
            UPDATE_MAX_SHARE * changed <= local.len()
        };
        match out_local.take() {
            Some(prev) if at.pins.is_empty() && few(&prev) => {
                at.system.stiffness_update(at.mesh, &prev, &local, out)
            }
            _ => at.system.stiffness_into(at.mesh, &local, out),
        }
        if at.pins.is_empty() {
            *out_local = Some(local);
        } else {
            Self::pin_rows(at.pins, out);
        }
    }

    /// Whether an LU factorization of the tangent would exceed
    /// [`TANGENT_LU_MAX_ENTRIES`], estimated from the held Cholesky factor's entries
    /// (`SolverStats::factor_nnz`; an LU of the same matrix holds L and U with pivoting's
    /// extra fill, several times as many) or, for a backend that does not report them
    /// (iterative ones), from the matrix's stored entries × 8 (the ratio of the Cholesky
    /// factor's entries to the matrix's on the walls of docs/performance.md, "Memory").
    /// The size of the model alone decides, never the machine's free memory, so that the
    /// results do not depend on the machine.
    pub fn tangent_lu_too_large(&self) -> bool {
        let factor = match self.backend.stats().factor_nnz {
            0 => 8 * self.kbuf.values.len(),
            f => f,
        };
        factor > TANGENT_LU_MAX_ENTRIES
    }

    /// Record that the main backend holds (or is about to hold) the factorization of
    /// `kbuf`, the secant matrix in `states` on the current geometry.
    pub fn hold_secant(&mut self, states: &[ContactState]) {
        self.held = Held::Secant(states.to_vec());
        self.held_current = true;
        self.held_on_cur.clear();
    }

    /// Contacts whose state in `now` differs from that of the held secant factorization;
    /// `None` when no secant factorization is held.
    pub fn changed_since_factor(&self, now: &[ContactState]) -> Option<usize> {
        let Held::Secant(states) = &self.held else {
            return None;
        };
        Some(states.iter().zip(now).filter(|(a, b)| a != b).count())
    }

    /// The most contacts changed state since the held factorization for which the
    /// low-rank correction ([`CorrectionSolver::changed`], and across increments [`CorrectionSolver::reuse`])
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
    pub fn low_rank_limit(&self) -> usize {
        let n = self.kbuf.pattern.n() as f64;
        let scaled = LOW_RANK_MAX_CHANGES as f64 * (n / LOW_RANK_REFERENCE_DOFS).sqrt();
        (scaled as usize).clamp(LOW_RANK_MAX_CHANGES, LOW_RANK_CAP)
    }

    /// `aux` ← the matrix that the held secant factorization, of H = K_s(held states) on
    /// its own geometry, is to be corrected to ([`LinearBackend::solve_changed`]) for the
    /// secant matrix K_s(`states`) on the current geometry: K_s(`states`) itself when the factorization
    /// is of the current geometry; on an older geometry, H plus the change of state on the current geometry,
    ///
    ///   N = H + K_s(`states`) − K_s(held states)   (entry by entry; H where the two agree),
    ///
    /// a change of H on the contacts that changed state only (rank ≤ 2 each), which the
    /// backend's low-rank correction accepts, and near K_s(`states`): the two differ by
    /// the geometry's change over the increments since the factorization (mm on m-sized
    /// blocks), which the conjugate gradients of [`CorrectionSolver::reuse`] or the GMRES of
    /// [`CorrectionSolver::gmres`] iterate on. `in_kbuf`: `kbuf` holds
    /// K_s(`states`) (else it is assembled into `aux`). `false` when no secant
    /// factorization is held, or the backend does not give its values (then it offers no
    /// `solve_changed` either).
    pub fn near_into_aux(
        &mut self,
        at: &Assembly<'_, impl Secant>,
        states: &[ContactState],
        in_kbuf: bool,
    ) -> bool {
        let Held::Secant(held_states) = &self.held else {
            return false;
        };
        if self.backend.factorized_values().is_none() {
            return false;
        }
        if self.aux.values.is_empty() {
            self.aux.values = vec![0.0; self.kbuf.values.len()];
        }
        if !self.held_current && self.held_on_cur.is_empty() {
            let local = (at.secant)(held_states);
            self.assemble(at, local, Buffer::Aux);
            self.held_on_cur.clone_from(&self.aux.values);
        }
        if in_kbuf {
            self.aux.values.copy_from_slice(&self.kbuf.values);
            self.aux_local.clone_from(&self.kbuf_local);
        } else {
            let local = (at.secant)(states);
            self.assemble(at, local, Buffer::Aux);
        }
        if !self.held_current {
            // exactly H where the contact states agree, so that the change read by the
            // backend is the changed contacts' alone
            let held = self
                .backend
                .factorized_values()
                .expect("checked above; nothing factorized since");
            for ((a, h), b) in self.aux.values.iter_mut().zip(held).zip(&self.held_on_cur) {
                *a = if *a == *b { *h } else { h + (*a - b) };
            }
            self.aux_local = None;
        }
        true
    }

    /// The secant correction K_s⁻¹ r by the held secant factorization corrected exactly
    /// for the contacts that changed state since it was computed
    /// ([`LinearBackend::solve_changed`]: the Woodbury identity inside the factor, no
    /// iteration), when between 1 and [`CorrectionSolver::low_rank_limit`] did (`kbuf` holds the new
    /// K_s). Within an increment the iteration matrix changes only by those contacts'
    /// stiffness (it is assembled on the last converged geometry, see
    /// the static driver's `correction`); across increments every entry changes and the backend
    /// refuses after reading a few of them. `None`: the backend refused (unsupported, a
    /// rank above its limit, a new geometry, K_s not positive definite) or the result's
    /// true residual is above 10 × [`REUSE_TOLERANCE`]; then [`CorrectionSolver::reuse`] or a
    /// refactorization.
    pub fn changed(
        &mut self,
        now: &[ContactState],
        r: &[f64],
        stats: &mut Stats,
    ) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        if changed == 0 || changed > self.low_rank_limit() || !self.held_current {
            return None;
        }
        let start = std::time::Instant::now();
        let out = crate::solve::reuse::solve_changed(
            &self.kbuf,
            &mut *self.backend,
            r,
            10.0 * REUSE_TOLERANCE,
        )?;
        stats.low_rank_corrections += 1;
        let rank = self.backend.stats().last_changed_rank;
        if crate::analysis::tracing() {
            eprintln!(
                "  low-rank correction: {changed} contacts changed, rank {rank}, {:.3e} s",
                start.elapsed().as_secs_f64()
            );
        }
        stats.low_rank_max_rank = stats.low_rank_max_rank.max(rank);
        Some(out.x)
    }

    /// The secant correction K_s⁻¹ r computed with the held secant factorization as a
    /// preconditioner, when few contacts changed state since it was computed (`kbuf` holds
    /// the new K_s). `None`: refactorize.
    /// `across`: the scene allows it across increments (`reuse_across_increments`).
    pub fn reuse(
        &mut self,
        at: &Assembly<'_, impl Secant>,
        now: &[ContactState],
        r: &[f64],
        across: bool,
        stats: &mut Stats,
    ) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        // across increments (the factorization of an older geometry) the held factor
        // corrected for the change of state (`near_into_aux`) preconditions, up to the
        // low-rank path's limit of changed contacts
        let across = !self.held_current && changed > 0 && across;
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
            if !self.near_into_aux(at, now, true) {
                // the backend gives no corrected factor: refactorize
                return None;
            }
            crate::solve::reuse::solve_with_changed_factor(
                &self.kbuf,
                &self.aux,
                &mut *self.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        } else {
            crate::solve::reuse::solve_with_factor(
                &self.kbuf,
                &mut *self.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        };
        if crate::analysis::tracing() {
            eprintln!(
                "  PCG on the held factor: {changed} contacts changed, {} geometry, {:?} iterations",
                if self.held_current { "same" } else { "older" },
                out.as_ref().map(|o| o.iterations)
            );
        }
        let out = out?;
        stats.reused_factorizations += 1;
        stats.reuse_iterations += out.iterations;
        Some(out.x)
    }

    /// GMRES on the buffer `matrix` preconditioned with the main backend's factorization,
    /// to the relative residual `tolerance` in at most [`TANGENT_MAX_ITERATIONS`]
    /// iterations (an inexact Newton step); `corrected`: the factorization corrected for
    /// the change to `aux` ([`LinearBackend::solve_changed`], `matrix` then `Main`).
    /// Counted in `stats` as a reused factorization. `None`: GMRES did not converge (then
    /// `gmres_failed` is set), or a
    /// component of the solution is above `largest` (a matrix singular up to round-off).
    pub fn gmres(
        &mut self,
        matrix: Buffer,
        corrected: bool,
        r: &[f64],
        tolerance: f64,
        largest: f64,
        stats: &mut Stats,
    ) -> Option<Vec<f64>> {
        let k = match matrix {
            Buffer::Main => &self.kbuf,
            Buffer::Aux => &self.aux,
        };
        let (out, corrected) = match corrected {
            true => crate::solve::reuse::gmres_with_changed_factor(
                k,
                &self.aux,
                &mut *self.backend,
                r,
                tolerance,
                TANGENT_MAX_ITERATIONS,
            ),
            false => (
                crate::solve::reuse::gmres_with_factor(
                    k,
                    &mut *self.backend,
                    r,
                    tolerance,
                    TANGENT_MAX_ITERATIONS,
                ),
                false,
            ),
        };
        if crate::analysis::tracing() {
            eprintln!(
                "  tangent by GMRES: {:?} iterations (corrected preconditioner: {corrected})",
                out.as_ref().map(|o| o.iterations)
            );
        }
        let Some(out) = out else {
            self.gmres_failed = true;
            return None;
        };
        if out.x.iter().any(|v| v.abs() > largest) {
            return None;
        }
        stats.reused_factorizations += 1;
        stats.reuse_iterations += out.iterations;
        Some(out.x)
    }
}

/// Where a driver's matrices are assembled: the system, the geometry (the static
/// driver's last converged one), the pinned unknowns, and the contacts' secant local
/// stiffness in given contact states.
pub(crate) struct Assembly<'s, F: Secant> {
    pub system: &'s System,
    pub mesh: &'s Mesh,
    pub pins: &'s [(usize, f64)],
    pub secant: F,
}

/// The contacts' secant local stiffness matrices (N/m) in given contact states.
pub(crate) trait Secant: Fn(&[ContactState]) -> Vec<LocalStiffness> {}

impl<F: Fn(&[ContactState]) -> Vec<LocalStiffness>> Secant for F {}

#[cfg(test)]
#[path = "correction_tests.rs"]
mod tests;
