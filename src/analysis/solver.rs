//! The nonlinear solver under every analysis: the one iteration loop that static load
//! increments, arc-length increments and time steps all go through (docs/theory.md §4,
//! "The iteration loop").
//!
//! A [`Problem`] holds an iterate (the unknowns' increment and its trial,
//! [`super::config::Trial`]: contact states, forces and the out-of-balance force) and
//! knows how to assess it and correct it; the loop of [`iterate`] owns what is the same
//! for all of them:
//!
//! * the convergence test: the out-of-balance norm ‖r‖ ≤ tol · scale (N), with the
//!   contacts that carry a force that matters (above tol · scale) in the same states as
//!   at the last iteration, where the problem asks for that ([`Problem::accepts`]);
//! * the stall window: an iteration that does not lower ‖r‖ below `stall_progress` times
//!   its best value so far counts towards the window; when the window is full the problem
//!   may escalate (the static secant iterations go on with tangent steps), then the bonds
//!   that cycled between closed and open break ([`OpenFlips`], once per call), then the
//!   iterations stop as stalled;
//! * the contact-state bookkeeping between iterations (the last iteration's states and
//!   forces, the closed ↔ open changes of bonded contacts).
//!
//! The correction itself (which matrix: secant, tangent or blended) is the problem's
//! [`Problem::correct`]; every problem solves it with the shared correction solver
//! (`correction::CorrectionSolver`, src/analysis/correction.rs), backtracks along it with
//! the one line search of [`backtrack`], and safeguards it with [`safeguard`].

use super::Stats;
use crate::material::{ContactState, History};
use crate::Result;

/// A bonded contact that has changed between closed and open this many times in the
/// iterations of one call of [`iterate`] breaks where they stall (closed → open → closed →
/// open): docs/decisions/0009-breaking-cycling-bonds.md.
pub const BOND_BREAK_FLIPS: u32 = 3;

/// Step lengths 1, ½, ¼, ⅛ of the line search of an iteration on the out-of-balance norm
/// ([`backtrack`]), static and dynamic alike.
pub const LINE_SEARCH_STEPS: usize = 4;

/// Step lengths 1 … 2⁻¹¹ of the long line searches ([`backtrack`]): the static driver's
/// safeguard and the arc-length corrector's backtracking, where a step short of a contact's
/// kink can be 10⁻³ of the Newton step (docs/decisions/0027-contact-state-corrector-and-chords.md).
pub const LONG_LINE_SEARCH_STEPS: usize = 12;

/// The step a line search kept ([`backtrack`]).
pub struct Step<T> {
    /// The out-of-balance norm (N) at the step.
    pub norm: f64,
    /// The step length α.
    pub alpha: f64,
    /// What the problem evaluated at the step (its trial, unknowns, …).
    pub at: T,
    /// Whether the step kept was the last one evaluated.
    pub last: bool,
}

/// Backtracking along a correction: the step lengths α = 1, ½, … 2^(1 − `steps`) are
/// evaluated in turn by `eval(α)` → (out-of-balance norm, what was evaluated), `None`
/// when the step leaves the model (then no shorter one is tried); the first whose norm
/// is at most `rn` (N) ends the search (or the first of all, `full`: a step always
/// taken whole), else the best of them is kept. `discard` receives what is not kept.
/// `None` when not even the full step could be evaluated.
pub fn backtrack<T>(
    steps: usize,
    rn: f64,
    full: bool,
    mut eval: impl FnMut(f64) -> Option<(f64, T)>,
    mut discard: impl FnMut(T),
) -> Option<Step<T>> {
    let mut alpha = 1.0;
    let mut best: Option<Step<T>> = None;
    for _ in 0..steps {
        let Some((norm, at)) = eval(alpha) else {
            break;
        };
        let last = best.as_ref().is_none_or(|b| norm < b.norm);
        if last {
            let step = Step {
                norm,
                alpha,
                at,
                last,
            };
            if let Some(worse) = best.replace(step) {
                discard(worse.at);
            }
        } else {
            if let Some(b) = best.as_mut() {
                b.last = false;
            }
            discard(at);
        }
        if norm <= rn || full {
            break;
        }
        alpha *= 0.5;
    }
    best
}

/// What [`safeguard`] keeps where the step along an iteration's first correction does not
/// lower the out-of-balance norm.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// The better of the two steps (the static iterations).
    Better,
    /// The alternative's step (a time step's iterations: the secant step after a tangent
    /// one that does not lower the norm).
    Alternative,
}

/// The safeguard of an iteration: the step along its first correction (out-of-balance
/// norm N, and what was evaluated; `None`: no such step) is taken where it lowers the
/// norm below `rn` (N); elsewhere the step along the alternative correction
/// (`alternative()`: the secant step for a tangent one, the tangent step for a secant one
/// that is not a descent direction) is tried, and `keep` says which is taken. Returns
/// the step taken and whether it was the first.
pub fn safeguard<T>(
    rn: f64,
    first: Option<(f64, T)>,
    keep: Keep,
    alternative: impl FnOnce() -> Result<Option<(f64, T)>>,
) -> Result<(Option<(f64, T)>, bool)> {
    if first.as_ref().is_some_and(|f| f.0 < rn) {
        return Ok((first, true));
    }
    let alt = alternative()?;
    Ok(match (keep, first, alt) {
        (Keep::Better, Some(f), Some(a)) if a.0 >= f.0 => (Some(f), true),
        (Keep::Better, Some(f), None) => (Some(f), true),
        (_, _, a) => (a, false),
    })
}

/// The controls of one call of [`iterate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterationControls {
    /// Relative out-of-balance tolerance: converged when ‖r‖ ≤ tolerance × scale.
    pub tolerance: f64,
    /// Iterations before the call stops as exhausted.
    pub max_iterations: usize,
    /// An iteration counts as progress when it lowers ‖r‖ below this fraction of the
    /// best value so far (the stall window's measure; [`Problem::stall_window`] its
    /// length).
    pub stall_progress: f64,
}

/// Where an iteration stands, as [`Problem::assess`] finds it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assessment {
    /// The out-of-balance norm ‖r‖ (N).
    pub norm: f64,
    /// The force that measures it (N): converged when `norm` ≤ tolerance × `scale`.
    pub scale: f64,
}

/// The contacts' states and their forces (N; normal, shear) of a trial.
#[derive(Debug, Clone, Copy)]
pub struct Contacts<'p> {
    pub state: &'p [ContactState],
    pub force: &'p [[f64; 2]],
}

impl<'t> From<&'t super::config::Trial> for Contacts<'t> {
    fn from(trial: &'t super::config::Trial) -> Self {
        Contacts {
            state: &trial.state,
            force: &trial.force,
        }
    }
}

/// What a problem's step of the loop asks the loop to do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// The problem has ended the call (a divergence, a failed factorization): the reason
    /// is the problem's to keep.
    Stop,
}

/// How a call of [`iterate`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ending {
    /// Converged at this iteration (0-based), the problem's trial the solution.
    Converged(usize),
    /// The stall window ran out and neither an escalation nor broken bonds helped.
    Stalled,
    /// `max_iterations` iterations without convergence.
    Exhausted,
    /// The problem stopped the call ([`Flow::Stop`]).
    Stopped,
}

/// The best out-of-balance norm of a call so far and the iteration that set it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stall {
    progress: f64,
    /// Best ‖r‖ (N).
    pub best: f64,
    /// The iteration that set `best`, or the last escalation or restart.
    pub since: usize,
}

impl Stall {
    fn new(progress: f64) -> Self {
        Stall {
            progress,
            best: f64::INFINITY,
            since: 0,
        }
    }

    /// Record iteration `it`'s norm; whether the window of `window` iterations without
    /// progress is full.
    fn stalled(&mut self, it: usize, norm: f64, window: usize) -> bool {
        if norm < self.progress * self.best {
            self.best = norm;
            self.since = it;
            false
        } else {
            it - self.since >= window
        }
    }

    /// Start the measure of progress again (the iterate's law changed: it is a new
    /// problem from here).
    pub fn forget_best(&mut self) {
        self.best = f64::INFINITY;
    }
}

/// A nonlinear problem that [`iterate`] solves: its iterate, and how to assess and
/// correct it.
pub trait Problem {
    /// The counters the loop adds its iterations to.
    fn stats(&mut self) -> &mut Stats;
    /// The contacts of the current iterate's trial.
    fn contacts(&self) -> Contacts<'_>;
    /// The force scale (N) of the last assessment, or of the start before the first.
    fn scale(&self) -> f64;
    /// Whether a contact has a bond that can break ([`OpenFlips`] counts nothing
    /// otherwise).
    fn bonded(&self) -> bool {
        false
    }
    /// The out-of-balance norm and its scale at iteration `it` (`prev`: the last
    /// iteration's contacts); the problem may change the trial first (contacts held or
    /// frozen) and restart the measure of progress (`stall`). `None` stops the call.
    fn assess(
        &mut self,
        it: usize,
        prev: Contacts<'_>,
        stall: &mut Stall,
    ) -> Result<Option<Assessment>>;
    /// Whether the iterate, whose norm is within the tolerance, is the solution:
    /// `changed` says whether a contact that carries a force that matters changed state
    /// since the last iteration.
    fn accepts(&mut self, it: usize, changed: bool) -> bool;
    /// Iterations without progress before the call stalls.
    fn stall_window(&self) -> usize;
    /// At a full stall window: go on with a stronger correction (the window then starts
    /// again). Whether it did.
    fn escalate(&mut self, _it: usize, _stall: &Stall, _a: &Assessment) -> bool {
        false
    }
    /// At a full stall window: break the bonds that `flips` counted cycling; whether any
    /// broke. The trial is then evaluated again ([`Problem::restart`]).
    fn break_bonds(&mut self, _flips: &OpenFlips) -> bool {
        false
    }
    /// Evaluate the trial of the current iterate again (after bonds broke).
    fn restart(&mut self) {}
    /// The call stalls at iteration `it` (for traces and counters).
    fn stalled(&mut self, _it: usize, _stall: &Stall, _a: &Assessment) {}
    /// Correct the iterate at iteration `it` (its assessment `a`, `changed` as for
    /// [`Problem::accepts`]).
    fn correct(&mut self, it: usize, a: &Assessment, changed: bool) -> Result<Flow>;
}

/// Iterate `problem` to convergence under `controls`.
pub fn iterate(problem: &mut impl Problem, controls: &IterationControls) -> Result<Ending> {
    let mut prev_state = problem.contacts().state.to_vec();
    let mut prev_force = problem.contacts().force.to_vec();
    let mut open_flips = OpenFlips::new(problem.bonded(), prev_state.len());
    let mut bonds_broken = false;
    let mut stall = Stall::new(controls.stall_progress);
    for it in 0..controls.max_iterations {
        problem.stats().iterations += 1;
        let prev = Contacts {
            state: &prev_state,
            force: &prev_force,
        };
        let negligible = controls.tolerance * problem.scale();
        open_flips.count(it, problem.contacts(), prev, negligible);
        let Some(a) = problem.assess(it, prev, &mut stall)? else {
            return Ok(Ending::Stopped);
        };
        // a state change counts only where the contact carries a force that matters at
        // the tolerance: contacts with no force (head joints under gravity) flip with
        // round-off
        let negligible = controls.tolerance * a.scale;
        let changed = changed_states(problem.contacts(), prev, negligible);
        if a.norm <= negligible && problem.accepts(it, changed) {
            return Ok(Ending::Converged(it));
        }
        if stall.stalled(it, a.norm, problem.stall_window()) {
            if problem.escalate(it, &stall, &a) {
                stall.since = it;
            } else if !bonds_broken && problem.break_bonds(&open_flips) {
                // the iterations cycled on bonds that cannot hold: go on with them broken
                // (once a call: where they still stall the load is beyond what the
                // contacts can hold)
                bonds_broken = true;
                problem.restart();
                stall = Stall {
                    since: it,
                    ..Stall::new(controls.stall_progress)
                };
                prev_state.clear();
                prev_state.extend_from_slice(problem.contacts().state);
                prev_force.clear();
                prev_force.extend_from_slice(problem.contacts().force);
                continue;
            } else {
                problem.stalled(it, &stall, &a);
                return Ok(Ending::Stalled);
            }
        }
        prev_state.clear();
        prev_state.extend_from_slice(problem.contacts().state);
        prev_force.clear();
        prev_force.extend_from_slice(problem.contacts().force);
        if problem.correct(it, &a, changed)? == Flow::Stop {
            return Ok(Ending::Stopped);
        }
    }
    Ok(Ending::Exhausted)
}

/// Whether a contact that carries a force above `negligible` (N), `now` or at the last
/// iteration (`prev`), is in another state than at the last iteration.
pub fn changed_states(now: Contacts<'_>, prev: Contacts<'_>, negligible: f64) -> bool {
    let matters = |f: [f64; 2]| f[0].hypot(f[1]) > negligible;
    now.state
        .iter()
        .zip(prev.state)
        .enumerate()
        .any(|(k, (a, b))| a != b && (matters(now.force[k]) || matters(prev.force[k])))
}

/// Per contact, the changes between closed and open in the iterations of one call of
/// [`iterate`], counted where the contact carries a force that matters on one side: what
/// breaks the bonds that cannot hold ([`BOND_BREAK_FLIPS`]). Empty, counting nothing,
/// where no joint has a bond to break.
pub struct OpenFlips(Vec<u32>);

impl OpenFlips {
    pub fn new(bonded: bool, contacts: usize) -> Self {
        OpenFlips(vec![0; if bonded { contacts } else { 0 }])
    }

    /// Count the changes from the last iteration's contacts `prev` to those of `now`,
    /// where the contact carries a force above `negligible` (N) on one side; nothing at
    /// the first iteration (`it` = 0).
    pub fn count(&mut self, it: usize, now: Contacts<'_>, prev: Contacts<'_>, negligible: f64) {
        if it == 0 {
            return;
        }
        let matters = |f: [f64; 2]| f[0].hypot(f[1]) > negligible;
        for (k, flips) in self.0.iter_mut().enumerate() {
            let open = now.state[k] == ContactState::Open;
            if open != (prev.state[k] == ContactState::Open)
                && (matters(now.force[k]) || matters(prev.force[k]))
            {
                *flips += 1;
            }
        }
    }

    /// Break the bond of every contact that changed [`BOND_BREAK_FLIPS`] times, is not
    /// `skip`ped and whose bond `broken_bond(k, history)` breaks: its `history` set to
    /// broken, the history it had pushed onto `broken` (to give back if the iterations
    /// still fail). Whether any broke.
    pub fn break_bonds(
        &self,
        history: &mut [History],
        broken_bond: impl Fn(usize, History) -> Option<History>,
        skip: impl Fn(usize) -> bool,
        broken: &mut Vec<(usize, History)>,
    ) -> bool {
        let mut broke = false;
        for (k, &flips) in self.0.iter().enumerate() {
            if flips < BOND_BREAK_FLIPS || k >= history.len() || skip(k) {
                continue;
            }
            if let Some(b) = broken_bond(k, history[k]) {
                if super::tracing() {
                    eprintln!("  bond broken: contact {k} after {flips} changes");
                }
                broken.push((k, history[k]));
                history[k] = b;
                broke = true;
            }
        }
        broke
    }

    /// Give the bonds broken by [`OpenFlips::break_bonds`] back to `history` (`broken`
    /// emptied): the iterations they were broken in did not lead to a committed state.
    pub fn give_back(history: &mut [History], broken: &mut Vec<(usize, History)>) {
        for (k, h) in broken.drain(..) {
            history[k] = h;
        }
    }
}

#[cfg(test)]
#[path = "solver_tests.rs"]
mod tests;
