//! One arc-length increment as a [`Problem`] of the nonlinear solver
//! ([`crate::analysis::solver`]): the unknowns' increment Δu and the load factor's Δλ
//! iterated under the increment's constraint (theory.md Eq. A1–A3) until the
//! out-of-balance force λ P̂ + base − F_int is within the tolerance. The contact-state
//! corrector freezes a contact that keeps changing state at the chord of its law (Eq. F1)
//! and checks the converged iterate against the true laws (Eq. F2); the corrections are
//! safeguarded Newton steps (the tangent step, or the secant one where it does better).

use super::*;
use crate::analysis::solver::{Assessment, Contacts, Ending, Flow, Problem, Stall};

/// The iterate of one increment of [`Driver::arc_step`].
pub(super) struct PathStep<'d, 'a, 'p> {
    pub d: &'d mut Driver<'a>,
    /// The external force without the push (N), and P̂ (N per unit λ).
    pub base: &'p [f64],
    pub p: &'p [f64],
    /// λ at the increment's start, and the increment's constraint.
    pub lam0: f64,
    pub constraint: Constraint,
    pub dq: Vec<f64>,
    pub dlam: f64,
    pub trial: Trial,
    /// The out-of-balance force of `trial` (N), the force that measures it, and their
    /// ratio.
    pub r: Vec<f64>,
    pub scale: f64,
    pub residual: f64,
    /// The out-of-balance force with the true laws at the last check of Eq. F2 (N), and
    /// the checks in a row that have not lowered it.
    pub last_check: f64,
    pub stuck: usize,
    /// `accept_residual`: keep the best iterate with the true laws.
    pub keep: bool,
    pub best_true: Option<Box<Unconverged>>,
    /// The energy dissipated by the converged iterate (J).
    pub dissipated: f64,
    /// Why the increment stopped, where it did before its iterations ran out.
    pub failure: Option<StepFailure>,
    /// The size of the model (m): a correction larger than half of it is a divergence.
    pub size: f64,
}

impl PathStep<'_, '_, '_> {
    /// The external force at λ₀ + Δλ (N).
    fn f_ext(&self) -> Vec<f64> {
        let lam = self.lam0 + self.dlam;
        self.base
            .iter()
            .zip(self.p)
            .map(|(b, q)| b + lam * q)
            .collect()
    }

    /// The converged increment (its trial, Δλ and the energy it dissipated), or why it
    /// failed.
    pub fn finish(self, end: Ending) -> std::result::Result<(Trial, f64, f64), StepFailure> {
        match end {
            Ending::Converged(it) => {
                self.d.report.iterations = it;
                self.d.report.residual = self.residual;
                Ok((self.trial, self.dlam, self.dissipated))
            }
            Ending::Stopped => Err(self
                .failure
                .unwrap_or(StepFailure::NoConvergence(self.residual, self.best_true))),
            Ending::Stalled | Ending::Exhausted => {
                Err(StepFailure::NoConvergence(self.residual, self.best_true))
            }
        }
    }
}

impl Problem for PathStep<'_, '_, '_> {
    fn stats(&mut self) -> &mut Stats {
        &mut self.d.stats
    }

    fn contacts(&self) -> Contacts<'_> {
        Contacts::from(&self.trial)
    }

    fn scale(&self) -> f64 {
        self.scale
    }

    fn assess(
        &mut self,
        it: usize,
        prev: Contacts<'_>,
        stall: &mut Stall,
    ) -> Result<Option<Assessment>> {
        let fe = self.f_ext();
        let d = &mut *self.d;
        self.r = d.out_of_balance(&fe, &self.trial.f_int);
        self.scale = d.force_scale(&fe, &self.trial.f_int);
        let mut rn = Driver::norm(&self.r);
        if rn <= d.settings.tolerance * self.scale && d.frozen.iter().any(Option::is_some) {
            // converged with contacts frozen: the true laws decide (Eq. F2)
            let zero = vec![[0.0; 2]; d.cur.blocks.len()];
            let held = std::mem::take(&mut d.frozen);
            let truth = d.trial(&self.dq, &zero);
            let r_true = d.out_of_balance(&fe, &truth.f_int);
            let s_true = d.force_scale(&fe, &truth.f_int);
            let rn_true = Driver::norm(&r_true);
            if self.keep {
                Unconverged::keep(&mut self.best_true, rn_true / s_true, &truth, self.dlam);
            }
            let n_frozen = held.iter().filter(|f| f.is_some()).count();
            if super::super::super::tracing() {
                eprintln!(
                    "arc corrector: converged with {n_frozen} contacts frozen at {:.3e}; with the true laws {:.3e}",
                    rn / self.scale,
                    rn_true / s_true
                );
            }
            // the chords to this point (regula falsi on the kinks)
            d.frozen = held
                .iter()
                .enumerate()
                .map(|(k, f)| f.map(|_| d.freeze(k, &truth)))
                .collect();
            d.stats.contact_releases += 1;
            (self.trial, self.r, self.scale, rn) = (truth, r_true, s_true, rn_true);
            if rn > d.settings.tolerance * self.scale {
                if (rn - self.last_check).abs() <= CHECK_SAME * self.last_check {
                    // the chords of the last check led back to the same point: regula
                    // falsi makes no progress
                    self.stuck += 1;
                    if self.stuck >= CHECK_LIMIT {
                        self.residual = rn / self.scale;
                        self.failure = Some(StepFailure::NoConvergence(
                            self.residual,
                            self.best_true.take(),
                        ));
                        return Ok(None);
                    }
                } else {
                    self.stuck = 0;
                }
                self.last_check = rn;
                // go on from here, the frozen laws now the chords to this point (their
                // forces the true ones): a new start for the stall test
                stall.forget_best();
            } else {
                d.frozen.iter_mut().for_each(|f| *f = None);
            }
        }
        let trial = &self.trial;
        self.residual = rn / self.scale;
        if self.keep && d.frozen.iter().all(Option::is_none) {
            Unconverged::keep(&mut self.best_true, self.residual, trial, self.dlam);
        }
        if let Some(pr) = d.progress.as_deref_mut() {
            pr.iteration(it, self.residual);
        }
        if it > 0 {
            for (c, (a, b)) in d.flips.iter_mut().zip(prev.state.iter().zip(&trial.state)) {
                *c += u32::from(a != b);
            }
            // the contact-state corrector: a contact that keeps changing state at a kink
            // of its law is frozen in the state it has now (Eq. F1)
            for k in 0..d.flips.len() {
                if d.flips[k] >= FLIP_LIMIT && d.frozen[k].is_none() {
                    d.frozen[k] = Some(d.freeze(k, trial));
                }
            }
            if super::super::super::tracing() {
                for (k, (a, b)) in prev
                    .state
                    .iter()
                    .zip(&trial.state)
                    .enumerate()
                    .filter(|(_, (a, b))| a != b)
                    .take(4)
                {
                    eprintln!(
                        "  flip {k} at {:?}: {a:?} -> {b:?} ({} flips), force {:?}, Δδ {:?}, law {:?}",
                        d.cur.nodes[d.cur.contacts[k].node_m as usize],
                        d.flips[k],
                        trial.force[k],
                        trial.rel[k],
                        d.law.get(k).springs(d.area[k])
                    );
                }
            }
        }
        if super::super::super::tracing() {
            eprintln!(
                "arc it {it} residual {:.3e} load {:.6e}",
                self.residual,
                self.lam0 + self.dlam
            );
        }
        Ok(Some(Assessment {
            norm: rn,
            scale: self.scale,
        }))
    }

    /// Converged on the out-of-balance force alone: the forces are the laws' at the
    /// iterate, so a small residual is equilibrium whatever states the last iterate had
    /// (at the kink of a law the two states give the same force); the predictor is taken
    /// only where it meets the constraint (a push) or, under dissipation control, spends
    /// enough energy.
    fn accepts(&mut self, it: usize, _changed: bool) -> bool {
        let dissipated = self.d.dissipated(&self.trial);
        let accept = match self.constraint {
            Constraint::Cylinder(_) => it > 0,
            Constraint::Dissipation(tau) => it > 0 || dissipated >= PREDICTOR_DISSIPATION * tau,
            // the predictor moves the block by Δa: it meets the constraint
            Constraint::Push(_) => true,
        };
        self.dissipated = dissipated;
        accept
    }

    fn stall_window(&self) -> usize {
        STALL_ITERATIONS
    }

    /// Safeguarded Newton: the tangent step, or the secant one where the tangent step
    /// does not lower the out-of-balance force (a piece whose contacts are all softening
    /// has a tangent near zero, and its step throws the piece far).
    fn correct(&mut self, _it: usize, a: &Assessment, _changed: bool) -> Result<Flow> {
        let (rn, scale) = (a.norm, a.scale);
        let lam = self.lam0 + self.dlam;
        let (pb, c) = ((self.p, self.base), self.constraint);
        let d = &mut *self.d;
        let (trial, r, dq) = (&self.trial, &self.r, &self.dq);
        let mut pick = d.corrector(trial, r, rn, pb, dq, lam, c, true)?;
        let tangent_rn = pick.as_ref().map(|t| t.0 / scale);
        let mut secant_rn = None;
        if pick.as_ref().is_none_or(|t| t.0 > rn) {
            if let Some(sec) = d.corrector(trial, r, rn, pb, dq, lam, c, false)? {
                secant_rn = Some(sec.0 / scale);
                // the secant step where it lowers the out-of-balance force; also where the
                // tangent step raises it over 100-fold (a stiff brick crack that closes in
                // it) and the secant one less
                let blown = pick
                    .as_ref()
                    .is_none_or(|t| t.0 > 100.0 * rn && sec.0 < t.0);
                if sec.0 < rn || blown {
                    pick = Some(sec);
                }
            }
        }
        if super::super::super::tracing() {
            if let Some((_, next, dl_it, _)) = &pick {
                let (k, m) = next
                    .iter()
                    .zip(dq)
                    .map(|(a, b)| (a - b).abs())
                    .enumerate()
                    .fold((0, 0.0), |b, (i, v)| if v > b.1 { (i, v) } else { b });
                eprintln!("  step: tangent {tangent_rn:?} secant {secant_rn:?}, largest move {m:.3e} at unknown {k}, δλ {dl_it:.3e}");
            }
        }
        let Some((_, next, dl_it, t)) = pick else {
            self.failure = Some(StepFailure::NoConvergence(
                self.residual,
                self.best_true.take(),
            ));
            return Ok(Flow::Stop);
        };
        self.dq = next;
        self.dlam += dl_it;
        self.trial = t;
        let dmax = self.dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !dmax.is_finite() || dmax > 0.5 * self.size {
            self.failure = Some(StepFailure::Divergence);
            return Ok(Flow::Stop);
        }
        Ok(Flow::Continue)
    }
}
