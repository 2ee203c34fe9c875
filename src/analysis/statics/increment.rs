//! One load increment of the static driver as a [`Problem`] of the nonlinear solver
//! ([`crate::analysis::solver`]): the external force `f_ext` and the prescribed motions
//! fixed, the unknowns' increment iterated until the out-of-balance force λF − F_int is
//! within the tolerance and no loaded contact changes state (docs/theory.md,
//! "Iterations"). The corrections: secant steps (tangent steps once the contact states
//! settle, or after the secant window stalls), with a line search on the out-of-balance
//! norm, the safeguards of a step that does not lower it, the blended step where the
//! secant matrix is singular and the search along the free blocks' motion.

use super::*;
use crate::analysis::solver::{
    self, Assessment, Contacts, Ending, Flow, Keep, OpenFlips, Problem, Stall,
};

/// The iterate of one increment of [`Driver::iterate`].
pub(super) struct Increment<'d, 'a> {
    pub d: &'d mut Driver<'a>,
    pub f_ext: &'d [f64],
    pub presc: &'d [Point],
    /// The iterations start from an extrapolated increment (not from zero).
    pub extrapolated: bool,
    /// The unknowns' increment (m, rad) and its trial.
    pub dq: Vec<f64>,
    pub trial: Trial,
    /// The out-of-balance force of `trial` (N), and the force that measures it.
    pub r: Vec<f64>,
    pub scale: f64,
    /// The size of the model (m): a correction larger than half of it is a divergence.
    pub size: f64,
    /// Consecutive iterations whose secant matrix was singular.
    pub singular_streak: usize,
    /// The secant iterations stalled: tangent steps from here on.
    pub tangent_only: bool,
}

impl Increment<'_, '_> {
    /// What the increment ended as: the converged trial, or why it failed with the
    /// failure mode.
    pub fn finish(
        self,
        end: Ending,
    ) -> Result<std::result::Result<Trial, (IncrementFailure, Failure)>> {
        let Increment {
            d,
            f_ext,
            trial,
            dq,
            r,
            scale,
            singular_streak,
            ..
        } = self;
        match end {
            Ending::Converged(it) => {
                d.report.iterations = it;
                d.report.residual = Driver::norm(&r) / scale;
                Ok(Ok(trial))
            }
            Ending::Stopped => Ok(Err((
                IncrementFailure::Divergence,
                d.failure(dq, &trial, f_ext, true),
            ))),
            Ending::Stalled | Ending::Exhausted => {
                let r = d.out_of_balance(f_ext, &trial.f_int);
                let residual = Driver::norm(&r) / scale;
                // the mechanism: the null space of the secant matrix when it is singular,
                // else the increment itself
                let singular = singular_streak > 0;
                let mode = if singular && d.settings.strategy != Strategy::Initial {
                    d.mechanism_mode(&trial, &r)?
                } else {
                    dq
                };
                Ok(Err((
                    IncrementFailure::NoConvergence { residual },
                    d.failure(mode, &trial, f_ext, singular),
                )))
            }
        }
    }
}

impl Problem for Increment<'_, '_> {
    fn stats(&mut self) -> &mut Stats {
        &mut self.d.stats
    }

    fn contacts(&self) -> Contacts<'_> {
        Contacts::from(&self.trial)
    }

    fn scale(&self) -> f64 {
        self.scale
    }

    /// The closed ↔ open changes that break bonds are counted only where a joint has a
    /// bond to break ([`Driver::break_cycling_bonds`]).
    fn bonded(&self) -> bool {
        self.d
            .law
            .laws
            .iter()
            .any(|l| l.broken_bond([0.0; 2]).is_some())
    }

    fn assess(
        &mut self,
        it: usize,
        prev: Contacts<'_>,
        _stall: &mut Stall,
    ) -> Result<Option<Assessment>> {
        let d = &mut *self.d;
        self.r = d.out_of_balance(self.f_ext, &self.trial.f_int);
        if !d.pins.is_empty() {
            self.scale = d.force_scale(self.f_ext, &self.trial.f_int);
        }
        let (scale, trial) = (self.scale, &self.trial);
        let rn = Driver::norm(&self.r);
        if let Some(p) = d.progress.as_deref_mut() {
            p.iteration(it, rn / scale);
        }
        let negligible = d.settings.tolerance * scale;
        d.converged_norm = negligible;
        if super::super::tracing() {
            let count = |s: ContactState| trial.state.iter().filter(|x| **x == s).count();
            eprintln!(
                "it {it} residual {:.3e} open {} slip {}",
                rn / scale,
                count(ContactState::Open),
                count(ContactState::Slip)
            );
            // changes of state of the contacts that carry a force: stick→slip,
            // slip→stick, closed→open, open→closed
            let matters = |k: usize| {
                trial.force[k][0].hypot(trial.force[k][1]) > negligible
                    || prev.force[k][0].hypot(prev.force[k][1]) > negligible
            };
            let mut tr = [0usize; 4];
            for (k, (a, b)) in trial.state.iter().zip(prev.state).enumerate() {
                if a != b && matters(k) {
                    tr[match (b, a) {
                        (ContactState::Stick, ContactState::Slip) => 0,
                        (ContactState::Slip, ContactState::Stick) => 1,
                        (_, ContactState::Open) => 2,
                        _ => 3,
                    }] += 1;
                }
            }
            eprintln!(
                "  changes stick>slip {} slip>stick {} >open {} open> {}",
                tr[0], tr[1], tr[2], tr[3]
            );
        }
        Ok(Some(Assessment { norm: rn, scale }))
    }

    /// Converged where no loaded contact changed state, after at least one correction
    /// unless the iterations started from an extrapolated increment.
    fn accepts(&mut self, it: usize, changed: bool) -> bool {
        (it > 0 || self.extrapolated) && !changed
    }

    fn stall_window(&self) -> usize {
        self.d.stall_window(self.tangent_only)
    }

    /// The secant iterations stagnate, which on large walls they do below the limit load
    /// a little above the tolerance: go on with tangent steps, which take the friction's
    /// dependence on the normal force into account, before declaring the load beyond what
    /// the contacts can hold (docs/decisions/0003-stall-window-and-tangent-fallback.md).
    fn escalate(&mut self, it: usize, stall: &Stall, a: &Assessment) -> bool {
        if self.d.settings.strategy != Strategy::Secant || self.tangent_only {
            return false;
        }
        self.tangent_only = true;
        self.d.stats.tangent_fallbacks += 1;
        if super::super::tracing() {
            eprintln!(
                "  secant stalled at it {it}: best {:.3e}, now {:.3e}: tangent steps",
                stall.best / a.scale,
                a.norm / a.scale
            );
        }
        true
    }

    fn break_bonds(&mut self, flips: &OpenFlips) -> bool {
        self.d.break_cycling_bonds(flips)
    }

    fn restart(&mut self) {
        let t = self.d.trial(&self.dq, self.presc);
        self.d.recycle(std::mem::replace(&mut self.trial, t));
    }

    fn stalled(&mut self, it: usize, stall: &Stall, a: &Assessment) {
        // the load is beyond what the contacts can hold from here
        if super::super::tracing() {
            eprintln!(
                "  stalled at it {it}: best {:.3e}, now {:.3e} (tangent steps: {})",
                stall.best / a.scale,
                a.norm / a.scale,
                self.tangent_only
            );
        }
    }

    fn correct(&mut self, it: usize, a: &Assessment, changed: bool) -> Result<Flow> {
        let (rn, scale, size) = (a.norm, a.scale, self.size);
        let (f_ext, presc) = (self.f_ext, self.presc);
        let d = &mut *self.d;
        let strategy = d.settings.strategy;
        // the secant strategy takes a tangent step once the contact states have settled:
        // with the states fixed the problem is linear but for the friction limit's
        // dependence on the normal force, which the secant matrix leaves out (the secant
        // iterations then contract by a constant factor, ~0.7 on the measured walls; the
        // tangent step closes them in one or two:
        // docs/decisions/0002-safeguarded-secant-steps.md)
        let tangent = strategy == Strategy::Newton
            || self.tangent_only
            || (strategy == Strategy::Secant
                && it > 1
                && !changed
                && self.trial.state.contains(&ContactState::Slip));
        // the first correction of an increment is built in the states the last increment
        // converged in: at dq = 0 every contact reports its committed force, which reads
        // as sticking even where it was open or slipping, and an all-sticking (elastic)
        // predictor overshoots where the joints had opened
        let states =
            if it == 0 && !self.extrapolated && d.committed.state.len() == self.trial.state.len() {
                d.committed.state.clone()
            } else {
                self.trial.state.clone()
            };
        let r = &self.r;
        // a correction of the size of the model comes from a matrix singular but for
        // round-off (whether the factorization flags it depends on the backend's pivot
        // threshold): treated as singular, so that the backends agree
        let correction = d
            .correction(&self.trial, &states, r, tangent)?
            .filter(|x| x.iter().all(|v| v.abs() <= 0.5 * size));
        let delta = match correction {
            Some(x) => {
                self.singular_streak = 0;
                x
            }
            None => {
                // the secant matrix is singular in the current states (a mechanism, or a
                // transient set of open contacts): step with K_s + ε K₀, stiffer than the
                // secant (so the iteration contracts, as the seed's excess-force
                // iteration with K₀ does) but much closer to it
                self.singular_streak += 1;
                match d.blended_step(&self.trial, r, BLEND)? {
                    Some(x) => x,
                    None => {
                        let mut x = r.clone();
                        if !d.solve_k0(&mut x)? {
                            return Ok(Flow::Stop);
                        }
                        x
                    }
                }
            }
        };
        let dq = &self.dq;
        // line search on the out-of-balance norm
        let best = d.line_search(dq, &delta, rn, f_ext, presc, LINE_SEARCH_STEPS);
        if super::super::tracing() {
            eprintln!(
                "  step tangent {tangent} singular {} ratio {:.3}",
                self.singular_streak,
                best.0 / rn
            );
        }
        let trial = &self.trial;
        let first = Some((best.0, (best.1, best.2)));
        let kept = if tangent {
            // safeguarded Newton: where the tangent step does not reduce the
            // out-of-balance force (slip/open cycling at a lightly loaded contact), take
            // the secant step instead, if it is better
            solver::safeguard(rn, first, Keep::Better, || {
                let local = d.local_stiffness(trial, &trial.state, false);
                d.assemble_kbuf(local);
                let x = d.lin.factor_solve(false, r)?;
                d.lin.hold_secant(&trial.state);
                let x = match x {
                    Some(x) => Some(x),
                    None => d.blended_step(trial, r, BLEND)?,
                };
                Ok(x.map(|x| {
                    let (n, t, c) = d.line_search(dq, &x, rn, f_ext, presc, LINE_SEARCH_STEPS);
                    (n, (t, c))
                }))
            })?
            .0
        } else if strategy == Strategy::Secant && self.singular_streak == 0 {
            // safeguarded secant: a regular secant step that no step length makes reduce
            // the out-of-balance force is not a descent direction (with many contacts
            // slipping K_s is far from the Jacobian, which couples the friction to the
            // normal force); take the tangent step where it does better
            solver::safeguard(rn, first, Keep::Better, || {
                let x = d
                    .correction(trial, &states, r, true)?
                    .filter(|x| x.iter().all(|v| v.abs() <= 0.5 * size));
                // the tangent of the current states is the Jacobian where no contact sits
                // at a kink of its law, so a short enough step along it lowers the norm:
                // backtrack further than for the secant step
                Ok(x.map(|x| {
                    let (n, t, c) = d.line_search(dq, &x, rn, f_ext, presc, LONG_LINE_SEARCH_STEPS);
                    if super::super::tracing() {
                        eprintln!("  safeguard tangent ratio {:.3}", n / rn);
                    }
                    (n, (t, c))
                }))
            })?
            .0
        } else {
            first
        };
        let (n, (t, c)) = kept.expect("a first step is given: the safeguard keeps a step");
        let mut best = (n, t, c);
        if d.settings.line_search && best.0 >= rn {
            // no step length lowered the norm, nor did the safeguards' other steps: the
            // step length where the out-of-balance force stops working along the
            // correction (see `slope_search`), taken whatever its norm
            if let Some(alt) = d.slope_search(dq, &delta, r, &best.1.history, f_ext, presc) {
                if super::super::tracing() {
                    eprintln!(
                        "  slope search: norm {:.3e} -> {:.3e}",
                        best.0 / scale,
                        alt.0 / scale
                    );
                }
                d.recycle(std::mem::replace(&mut best, alt).1);
                d.stats.slope_searches += 1;
            }
        }
        if self.singular_streak >= MODE_STREAK
            && strategy != Strategy::Initial
            && best.0 > MODE_PROGRESS * rn
        {
            // the step moved little: blocks held only by slipping and open contacts carry
            // an out-of-balance force that no contact of theirs resists (K_s is singular
            // there) and the residual's norm does not fall along their free motion until
            // one of those contacts sticks: search along that motion
            if let Some(m) = d.blended_step(&self.trial, r, MODE_BLEND)? {
                if let Some(moves) = d.free_motion(&best.2, &best.1.state, &m, &delta, f_ext, presc)
                {
                    let mut cand = best.2.clone();
                    for (i, v) in moves.into_iter().flatten() {
                        cand[i] += v;
                    }
                    let t = d.trial(&cand, presc);
                    let rn2 = Driver::norm(&d.out_of_balance(f_ext, &t.f_int));
                    if super::super::tracing() {
                        eprintln!(
                            "  free motion: norm {:.3e} -> {:.3e}",
                            best.0 / scale,
                            rn2 / scale
                        );
                    }
                    if rn2 < MODE_ACCEPT * best.0 {
                        best = (rn2, t, cand);
                        d.stats.free_motions += 1;
                    }
                }
            }
        }
        let (_, t, cand) = best;
        d.recycle(std::mem::replace(&mut self.trial, t));
        self.dq = cand;
        let dmax = self.dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !dmax.is_finite() || dmax > 0.5 * size {
            return Ok(Flow::Stop);
        }
        Ok(Flow::Continue)
    }
}
