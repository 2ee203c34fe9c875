//! One try of a time step as a [`Problem`] of the nonlinear solver
//! ([`crate::analysis::solver`]): the step's increment Δu iterated until the balance of
//! the scheme (docs/theory.md §5) is within the tolerance and no loaded
//! contact changes state. The corrections: the secant effective matrix, with the
//! anti-chatter rules of the contacts that keep opening and closing within the step (their
//! normal spring kept, weakened while open, or the contact held open), a tangent step by
//! GMRES where the secant iterations are slow, and the step's line search.

use super::*;
use crate::analysis::solver::{
    self, Assessment, Contacts, Ending, Flow, Keep, OpenFlips, Problem, Stall,
};

/// The iterate of one try of [`Dynamics::step`].
pub(super) struct StepTry<'d, 'a> {
    pub d: &'d mut Dynamics<'a>,
    pub terms: StepTerms,
    /// The step starts at `t0` (s); at its end the ground is at `g1` (m/s²), moved by `dug`
    /// (m) with velocity `vg1` (m/s) in the absolute frame.
    pub t0: f64,
    pub g1: [f64; 2],
    pub dug: [f64; 2],
    pub vg1: [f64; 2],
    /// The try of the smallest step: no stall window, every cycling contact held open.
    pub last_resort: bool,
    /// The try starts from a given increment (a redo), not from the committed state.
    pub started: bool,
    pub dq: Vec<f64>,
    pub trial: Trial,
    pub bal: Balance,
    /// Per contact: its open ↔ closed and stick ↔ slip changes in this try, the weight of
    /// its normal spring while open, whether it is held open, and the largest force (N) it
    /// carried closed.
    pub flips: Vec<u32>,
    pub slip_flips: Vec<u32>,
    pub weight: Vec<f64>,
    pub frozen: Vec<bool>,
    pub closed_max: Vec<f64>,
    /// The out-of-balance norm of the last iteration (N), and whether its step was a
    /// tangent one.
    pub last_rn: f64,
    pub last_tangent: bool,
    /// The size of the model (m): a correction larger than half of it is a divergence.
    pub size: f64,
}

impl StepTry<'_, '_> {
    /// The converged step, or `None`: the try failed (the caller cuts the step).
    pub fn finish(self, end: Ending) -> Option<Accepted> {
        match end {
            Ending::Converged(_) => Some(Accepted {
                trial: self.trial,
                v: self.bal.v1,
                a: self.bal.a1,
                f_visc: self.bal.fv1,
                h: self.terms.h,
                ground: self.g1,
                ground_du: self.dug,
                ground_v1: self.vg1,
                frozen: self.frozen,
            }),
            Ending::Stalled | Ending::Exhausted | Ending::Stopped => None,
        }
    }
}

impl Problem for StepTry<'_, '_> {
    fn stats(&mut self) -> &mut Stats {
        &mut self.d.stats
    }

    fn contacts(&self) -> Contacts<'_> {
        Contacts::from(&self.trial)
    }

    fn scale(&self) -> f64 {
        self.bal.scale
    }

    /// The closed ↔ open changes that break bonds are counted only where the joints have
    /// a bond to break.
    fn bonded(&self) -> bool {
        self.d.law.broken_bond([0.0; 2]).is_some()
    }

    /// The anti-chatter bookkeeping of the trial's contacts: a contact that keeps opening
    /// and closing within the step sits at the kink of its law (touching with no force:
    /// the chatter of a stiff contact), where the secant iteration cycles between the open
    /// and the closed linearization; its normal spring then stays in the matrix, weakened
    /// by a factor w that drops while the contact stays open (so that a contact that
    /// really separates is soon left free) and returns to 1 when it closes; one that
    /// carried no force closed (or any, in the last resort) is held open.
    fn assess(
        &mut self,
        it: usize,
        prev: Contacts<'_>,
        _stall: &mut Stall,
    ) -> Result<Option<Assessment>> {
        let trial = &mut self.trial;
        for k in 0..self.flips.len() {
            let open = trial.state[k] == ContactState::Open;
            if it > 0 && open != (prev.state[k] == ContactState::Open) {
                self.flips[k] += 1;
            }
            let pair = [trial.state[k], prev.state[k]];
            if it > 0 && pair.contains(&ContactState::Stick) && pair.contains(&ContactState::Slip) {
                self.slip_flips[k] += 1;
            }
            if self.flips[k] >= FLIPS_BEFORE_ELASTIC {
                self.weight[k] = if open {
                    self.weight[k] * OPEN_WEIGHT_DECAY
                } else {
                    1.0
                };
            }
            if !open {
                self.closed_max[k] =
                    self.closed_max[k].max(trial.force[k][0].hypot(trial.force[k][1]));
            }
            if (self.last_resort || self.closed_max[k] <= HOLD_OPEN_FORCE * self.bal.scale)
                && self.flips[k] >= FREEZE_FLIPS
                && !self.frozen[k]
            {
                if super::super::tracing() {
                    eprintln!("  hold open: contact {k}");
                }
                self.frozen[k] = true;
                self.d.stats.held_open += 1;
            }
        }
        if self
            .frozen
            .iter()
            .zip(&trial.state)
            .any(|(f, s)| *f && *s != ContactState::Open)
        {
            hold_open(trial, &self.frozen);
            self.bal = self.d.balance(&self.terms, &self.dq, trial);
        }
        if super::super::tracing() {
            eprintln!(
                "t {:.4} h {:.3e} it {it} residual {:.3e}",
                self.t0,
                self.terms.h,
                self.bal.rn / self.bal.scale
            );
            for k in 0..trial.state.len() {
                if trial.state[k] != prev.state[k] {
                    let c = &trial.mesh.contacts[k];
                    eprintln!(
                        "  contact {k} ({}-{}) {:?} -> {:?} force {:?} flips {} w {}",
                        c.block_l,
                        c.block_m,
                        prev.state[k],
                        trial.state[k],
                        trial.force[k],
                        self.flips[k],
                        self.weight[k]
                    );
                }
            }
        }
        Ok(Some(Assessment {
            norm: self.bal.rn,
            scale: self.bal.scale,
        }))
    }

    /// Converged after at least one correction, where no loaded contact changed state.
    fn accepts(&mut self, it: usize, changed: bool) -> bool {
        it > 0 && !changed
    }

    /// [`STALL_ITERATIONS`]; none in the last resort, which runs to `max_iterations`.
    fn stall_window(&self) -> usize {
        if self.last_resort {
            usize::MAX
        } else {
            STALL_ITERATIONS
        }
    }

    fn break_bonds(&mut self, flips: &OpenFlips) -> bool {
        self.d.break_cycling_bonds(flips, &self.frozen)
    }

    fn restart(&mut self) {
        self.trial = self.d.trial_moving(&self.dq, self.dug);
        if self.frozen.iter().any(|&f| f) {
            hold_open(&mut self.trial, &self.frozen);
        }
        self.bal = self.d.balance(&self.terms, &self.dq, &self.trial);
    }

    fn stalled(&mut self, _it: usize, stall: &Stall, _a: &Assessment) {
        if super::super::tracing() {
            eprintln!("  stalled: no progress since iteration {}", stall.since);
        }
        self.d.stats.stalled_steps += 1;
    }

    fn correct(&mut self, it: usize, _a: &Assessment, changed: bool) -> Result<Flow> {
        let d = &mut *self.d;
        let trial = &self.trial;
        // at the first iteration, the states of the last step (a contact exactly at its
        // friction limit evaluates as sticking, but it was slipping)
        let states = if it == 0 && !self.started {
            &d.committed.state
        } else {
            &trial.state
        };
        // the contacts' local stiffness in the matrix: secant, but for the anti-chatter
        // rules of `assess`
        let secant: Vec<LocalStiffness> = (0..d.springs.len())
            .map(|k| {
                if self.frozen[k] {
                    return [[0.0; 2]; 2];
                }
                let mut l = secant_local(d.springs[k], states[k]);
                if self.flips[k] >= FLIPS_BEFORE_ELASTIC {
                    l[0][0] = self.weight[k] * d.springs[k].kn;
                }
                if self.slip_flips[k] >= FLIPS_BEFORE_ELASTIC && states[k] != ContactState::Open {
                    l[1][1] = d.springs[k].ks;
                }
                l
            })
            .collect();
        // once no contact changes state, the step's problem is smooth but for the slipping
        // contacts' friction, which depends on their normal force: the secant matrix
        // leaves that out (and keeps kₛ on contacts that flipped between stick and slip),
        // so its iterations may contract slowly; a tangent step closes them in one or
        // two (docs/decisions/0019-dynamic-tangent-steps.md). Taken only where the secant
        // iteration is slow ([`TANGENT_SLOW`]), and then until a state changes.
        let bal = &self.bal;
        let tangent = it > 1
            && !changed
            && (self.last_tangent || bal.rn > TANGENT_SLOW * self.last_rn)
            && (0..trial.state.len())
                .any(|k| !self.frozen[k] && trial.state[k] == ContactState::Slip);
        self.last_rn = bal.rn;
        let geometry = d.blocks_geometry(&trial.mesh);
        let blocks = geometry.as_ref().map(|m| m.as_ref().unwrap_or(&trial.mesh));
        d.effective_into(
            blocks,
            &trial.mesh,
            &secant,
            &trial.state,
            &self.terms,
            false,
        );
        if !d.lin.factorize(false) {
            return Ok(Flow::Stop);
        }
        let (frozen, terms, dq, dug, size) =
            (&self.frozen, &self.terms, &self.dq, self.dug, self.size);
        // the tangent step where it lowers the out-of-balance force; else the secant step
        let first = match tangent {
            true => d
                .tangent_step(
                    trial, blocks, &secant, frozen, terms, dq, bal, it, dug, size,
                )
                .map(|s| (s.2.rn, s)),
            false => None,
        };
        let (found, tangent_kept) = solver::safeguard(bal.rn, first, Keep::Alternative, || {
            let mut x = bal.r.clone();
            if !d.lin.solve(&mut x) {
                return Ok(None);
            }
            Ok(d.search(terms, dq, &x, bal, it, frozen, dug, size)
                .map(|s| (s.2.rn, s)))
        })?;
        self.last_tangent = tangent_kept;
        let found = found.map(|(_, s)| s);
        let Some((cand, t, b, last)) = found else {
            return Ok(Flow::Stop);
        };
        self.dq = cand;
        self.trial = t;
        self.bal = if last {
            b
        } else {
            // `cbuf` holds C of the last candidate tried: assemble it for the one kept
            d.balance(&self.terms, &self.dq, &self.trial)
        };
        Ok(Flow::Continue)
    }
}
