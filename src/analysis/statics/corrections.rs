//! The static driver's corrections: which matrix a correction is solved with (the
//! strategy's secant, tangent or elastic matrix, the tangent of the secant strategy by
//! GMRES on the held secant factor, the blended step K_s + ε K₀ where the secant matrix is
//! singular), assembled on the geometry of the last converged increment and solved by
//! the shared correction solver ([`crate::analysis::correction`]; docs/theory.md §4,
//! "Increments and iterations").

use super::*;
use crate::analysis::correction::{
    Assembly, Buffer, CorrectionSolver, Secant, REUSE_TOLERANCE, TANGENT_TOLERANCE,
};

impl<'a> Driver<'a> {
    /// The correction solver, and where the driver's matrices are assembled: the
    /// geometry of the last converged increment, the pinned unknowns, and the contacts'
    /// secant stiffness.
    pub(super) fn lin_at(
        &mut self,
    ) -> (
        &mut CorrectionSolver<'a>,
        Assembly<'_, impl Secant + '_>,
        &mut Stats,
    ) {
        let (law, area, flips) = (&self.law, &self.area, &self.flips);
        let at = Assembly {
            system: &self.system,
            mesh: &self.cur,
            pins: &self.pins,
            secant: move |states: &[ContactState]| {
                contact_local(law, area, flips, &[], states, false)
            },
        };
        (&mut self.lin, at, &mut self.stats)
    }

    /// Assemble the iteration matrix for the contacts' local stiffnesses `local` into
    /// `kbuf` on the geometry of the last converged increment, the pinned unknowns taken
    /// out ([`CorrectionSolver::assemble`]).
    pub(super) fn assemble_kbuf(&mut self, local: Vec<LocalStiffness>) {
        let (lin, at, _) = self.lin_at();
        lin.assemble(&at, local, Buffer::Main);
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
            CorrectionSolver::pin_rows(&self.pins, &mut k);
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
    /// [`CorrectionSolver::reuse`] exploits.
    pub(super) fn correction(
        &mut self,
        trial: &Trial,
        states: &[ContactState],
        r: &[f64],
        tangent: bool,
    ) -> Result<Option<Vec<f64>>> {
        match self.settings.strategy {
            Strategy::Initial => {
                let mut x = r.to_vec();
                Ok(self.solve_k0(&mut x)?.then_some(x))
            }
            Strategy::Secant | Strategy::Newton => {
                let mut newton = self.settings.strategy == Strategy::Newton || tangent;
                if newton && self.settings.strategy == Strategy::Secant {
                    if let Some(x) = self.tangent_with_secant_factor(trial, states, r) {
                        return Ok(Some(x));
                    }
                    // no LU of the tangent where its factor would not fit: the secant
                    // correction instead (the safeguard's alternative step)
                    newton = !self.lin.tangent_lu_too_large();
                    if !newton {
                        self.stats.tangent_lu_skipped += 1;
                    }
                }
                let local = self.local_stiffness(trial, states, newton);
                self.assemble_kbuf(local);
                if !newton {
                    if let Some(x) = self.lin.changed(states, r, &mut self.stats) {
                        return Ok(Some(x));
                    }
                    let across = self.settings.reuse_across_increments;
                    let reused = {
                        let (lin, at, stats) = self.lin_at();
                        lin.reuse(&at, states, r, across, stats)
                    };
                    if let Some(x) = reused {
                        return Ok(Some(x));
                    }
                    self.lin.hold_secant(states);
                }
                // LU has no pivot measure: a matrix singular up to round-off shows as a
                // step of the size of the model
                let size = self.model_size();
                let x = self.lin.factor_solve(newton, r)?;
                Ok(x.filter(|x| !newton || x.iter().all(|v| v.abs() <= 0.1 * size)))
            }
        }
    }

    /// The tangent correction K_t⁻¹ r of the secant strategy (a symmetric secant matrix
    /// plus the slipping contacts' friction–normal coupling) by GMRES preconditioned with
    /// the held secant factorization (factorized first, in `states`, when none is held),
    /// instead of an LU factorization of K_t, which costs several Cholesky
    /// factorizations. `None`: the caller factorizes K_t (GMRES did not converge within
    /// `TANGENT_MAX_ITERATIONS`, or the secant matrix is singular).
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
            if !self.lin.factorize(true) {
                return None;
            }
            self.lin.hold_secant(states);
        }
        // the secant matrix in `states` (in `aux`), when the held factorization is of a
        // few contacts in other states (on this geometry or, corrected for the change of
        // state, an older one: `near_into_aux`): GMRES is then preconditioned with the
        // factorization corrected for them (`LinearBackend::solve_changed`), which leaves
        // the friction–normal coupling of the slipping contacts alone to iterate on (and
        // the geometry's change)
        let near = match self.lin.changed_since_factor(states) {
            Some(c) if c > 0 && c <= self.lin.low_rank_limit() => {
                let (lin, at, _) = self.lin_at();
                lin.near_into_aux(&at, states, false)
            }
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
        // a step of the size of the model: K_t singular up to round-off, as in `correction`
        let largest = 0.1 * self.model_size();
        self.lin
            .gmres(Buffer::Main, near, r, tolerance, largest, &mut self.stats)
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
        CorrectionSolver::pin_rows(&self.pins, &mut self.lin.kbuf);
        let mut x = r.to_vec();
        let ok = self.lin.factorize(false) && self.lin.solve(&mut x);
        Ok(ok.then_some(x))
    }
}

/// The contacts' local stiffness matrices (N/m) in the given states, of contacts with
/// the laws `law` and areas `area` (m²); `newton` adds the slip contacts' friction–normal
/// coupling with the sign of the shear force in `force` (N; read only then). A contact
/// that changed state `flips[k]` ≥ `arc_length::FLIP_LIMIT` times keeps its elastic
/// springs: they bound every tangent of the law, so the iterations contract to the state
/// at the kink instead of cycling.
pub(super) fn contact_local(
    law: &PerContact<JointLaw>,
    area: &[f64],
    flips: &[u32],
    force: &[[f64; 2]],
    states: &[ContactState],
    newton: bool,
) -> Vec<LocalStiffness> {
    (0..area.len())
        .map(|k| {
            let law = law.get(k);
            let s = law.springs(area[k]);
            if flips.get(k).is_some_and(|&n| n >= arc_length::FLIP_LIMIT) {
                return [[s.kn, 0.0], [0.0, s.ks]];
            }
            if newton {
                tangent_local(s, states[k], force[k][1], law.tan_phi())
            } else {
                secant_local(s, states[k])
            }
        })
        .collect()
}
