//! The iteration loop on a toy problem with a closed-form answer: a block held by a wall
//! spring k_w (x) on a frictional contact (normal spring kₙ, shear spring kₛ, friction
//! coefficient μ, no cohesion, no tension), loaded by (Fx, Fy), solved by secant steps
//! (the shear spring left out where the contact slips, nothing where it is open).

use super::*;

/// The toy: two unknowns (u_x, u_y; m), one contact.
struct Toy {
    kw: f64,
    kn: f64,
    ks: f64,
    mu: f64,
    load: [f64; 2],
    u: [f64; 2],
    state: [ContactState; 1],
    force: [[f64; 2]; 1],
    r: [f64; 2],
    stats: Stats,
    /// The window of iterations without progress before the loop stalls.
    window: usize,
    /// Escalations left ([`Problem::escalate`]).
    escalations: usize,
}

impl Toy {
    fn new(kw: f64, load: [f64; 2]) -> Toy {
        let mut t = Toy {
            kw,
            kn: 1e9,
            ks: 1e9,
            mu: 0.5,
            load,
            u: [0.0; 2],
            state: [ContactState::Stick],
            force: [[0.0; 2]],
            r: [0.0; 2],
            stats: Stats::default(),
            window: 5,
            escalations: 0,
        };
        t.evaluate();
        t
    }

    /// The contact's law at `u`: compression N = −kₙ u_y where u_y < 0, the shear kₛ u_x
    /// returned to μ N; the out-of-balance force F − F_int.
    fn evaluate(&mut self) {
        let [ux, uy] = self.u;
        let normal = (-self.kn * uy).max(0.0);
        let limit = self.mu * normal;
        let trial = self.ks * ux;
        let (state, shear) = if uy > 0.0 {
            (ContactState::Open, 0.0)
        } else if trial.abs() <= limit {
            (ContactState::Stick, trial)
        } else {
            (ContactState::Slip, limit.copysign(trial))
        };
        self.state = [state];
        self.force = [[-normal, shear]];
        self.r = [self.load[0] - (self.kw * ux + shear), self.load[1] + normal];
    }

    fn norm(&self) -> f64 {
        self.r[0].hypot(self.r[1])
    }
}

impl Problem for Toy {
    fn stats(&mut self) -> &mut Stats {
        &mut self.stats
    }
    fn contacts(&self) -> Contacts<'_> {
        Contacts {
            state: &self.state,
            force: &self.force,
        }
    }
    fn scale(&self) -> f64 {
        self.load[0].hypot(self.load[1])
    }
    fn assess(
        &mut self,
        _it: usize,
        _prev: Contacts<'_>,
        _stall: &mut Stall,
    ) -> Result<Option<Assessment>> {
        Ok(Some(Assessment {
            norm: self.norm(),
            scale: self.scale(),
        }))
    }
    fn accepts(&mut self, it: usize, changed: bool) -> bool {
        it > 0 && !changed
    }
    fn stall_window(&self) -> usize {
        self.window
    }
    fn escalate(&mut self, _it: usize, _stall: &Stall, _a: &Assessment) -> bool {
        let go = self.escalations > 0;
        self.escalations = self.escalations.saturating_sub(1);
        go
    }
    /// The secant step: K_s = diag(k_w + kₛ [stick], kₙ [closed]); where it is singular
    /// in x (a slipping block with no wall), the elastic step kₛ; where the block is
    /// open and free, nothing resists it: the call stops (a singular matrix).
    fn correct(&mut self, _it: usize, _a: &Assessment, _changed: bool) -> Result<Flow> {
        let state = self.state[0];
        let kx = self.kw
            + if state == ContactState::Stick {
                self.ks
            } else {
                0.0
            };
        let ky = if state == ContactState::Open {
            0.0
        } else {
            self.kn
        };
        if ky == 0.0 && kx == 0.0 {
            return Ok(Flow::Stop);
        }
        let kx = if kx == 0.0 { self.ks } else { kx };
        let ky = if ky == 0.0 { self.kn } else { ky };
        self.u[0] += self.r[0] / kx;
        self.u[1] += self.r[1] / ky;
        self.evaluate();
        Ok(Flow::Continue)
    }
}

fn controls() -> IterationControls {
    IterationControls {
        tolerance: 1e-9,
        max_iterations: 100,
        stall_progress: 0.9,
    }
}

/// Sliding against the wall spring: u_x = (Fx − μ N)/k_w, u_y = Fy/kₙ (N = −Fy), the
/// contact slipping; the stick → slip change takes one more secant step.
#[test]
fn a_slipping_block_converges_to_the_closed_form() {
    let mut toy = Toy::new(1e7, [800.0, -1000.0]);
    let end = iterate(&mut toy, &controls()).unwrap();
    let Ending::Converged(it) = end else {
        panic!("{end:?}")
    };
    let (ux, uy) = ((800.0 - 0.5 * 1000.0) / 1e7, -1000.0 / 1e9);
    assert!(
        (toy.u[0] - ux).abs() <= 1e-9 * ux.abs(),
        "{} {ux}",
        toy.u[0]
    );
    assert!(
        (toy.u[1] - uy).abs() <= 1e-9 * uy.abs(),
        "{} {uy}",
        toy.u[1]
    );
    assert_eq!(toy.state[0], ContactState::Slip);
    // stick (it 0), slip found (it 1), slipping again at the answer (it 2)
    assert_eq!(it, 2);
    assert_eq!(toy.stats.iterations, 3);
}

/// Below the friction limit the block sticks: u_x = Fx/(k_w + kₛ).
#[test]
fn a_sticking_block_converges_to_the_closed_form() {
    let mut toy = Toy::new(1e7, [200.0, -1000.0]);
    let end = iterate(&mut toy, &controls()).unwrap();
    assert!(matches!(end, Ending::Converged(_)), "{end:?}");
    let ux = 200.0 / (1e7 + 1e9);
    assert!((toy.u[0] - ux).abs() <= 1e-6 * ux, "{} {ux}", toy.u[0]);
    assert_eq!(toy.state[0], ContactState::Stick);
}

/// With no wall the block slides away: the out-of-balance force stays at Fx − μ N and
/// the loop stops when the stall window runs out, not at `max_iterations`.
#[test]
fn a_block_that_slides_away_stalls() {
    let mut toy = Toy::new(0.0, [800.0, -1000.0]);
    let end = iterate(&mut toy, &controls()).unwrap();
    assert_eq!(end, Ending::Stalled);
    assert!(toy.norm() > 0.2 * 800.0, "{}", toy.norm());
    let n = toy.stats.iterations;
    assert!(
        (toy.window..2 * toy.window + 3).contains(&n),
        "{n} iterations"
    );
}

/// An escalation starts the stall window again: two escalations, three windows.
#[test]
fn an_escalation_restarts_the_stall_window() {
    let mut plain = Toy::new(0.0, [800.0, -1000.0]);
    iterate(&mut plain, &controls()).unwrap();
    let mut toy = Toy::new(0.0, [800.0, -1000.0]);
    toy.escalations = 2;
    let end = iterate(&mut toy, &controls()).unwrap();
    assert_eq!(end, Ending::Stalled);
    assert_eq!(
        toy.stats.iterations,
        plain.stats.iterations + 2 * toy.window
    );
}

/// A block pulled off its contact has a singular matrix once it opens: the problem stops
/// the loop at that iteration.
#[test]
fn a_singular_matrix_stops_the_loop() {
    let mut toy = Toy::new(0.0, [0.0, 1000.0]);
    let end = iterate(&mut toy, &controls()).unwrap();
    assert_eq!(end, Ending::Stopped);
    assert_eq!(toy.state[0], ContactState::Open);
    assert_eq!(toy.stats.iterations, 2);
}

/// Without progress nor a stall window, the loop ends after `max_iterations`.
#[test]
fn iterations_run_out() {
    let mut toy = Toy::new(0.0, [800.0, -1000.0]);
    toy.window = usize::MAX;
    let end = iterate(&mut toy, &controls()).unwrap();
    assert_eq!(end, Ending::Exhausted);
    assert_eq!(toy.stats.iterations, controls().max_iterations);
}

/// A state change of a loaded contact blocks convergence even at a small residual; one
/// of a contact that carries nothing does not.
#[test]
fn only_loaded_contacts_count_as_changed() {
    let prev = Contacts {
        state: &[ContactState::Stick, ContactState::Stick],
        force: &[[-10.0, 1.0], [0.0, 0.0]],
    };
    let quiet = Contacts {
        state: &[ContactState::Stick, ContactState::Open],
        force: &[[-10.0, 1.0], [0.0, 0.0]],
    };
    let loud = Contacts {
        state: &[ContactState::Slip, ContactState::Stick],
        force: &[[-10.0, 1.0], [0.0, 0.0]],
    };
    assert!(!changed_states(quiet, prev, 1e-3));
    assert!(changed_states(loud, prev, 1e-3));
}

/// The line search on a norm with a known minimum: ‖r(α)‖ = |α − a| + 0.1 along the
/// correction from ‖r(0)‖ = a + 0.1.
fn norm_at(a: f64) -> impl FnMut(f64) -> Option<(f64, f64)> {
    move |alpha: f64| Some(((alpha - a).abs() + 0.1, alpha))
}

#[test]
fn backtracking_takes_the_first_step_that_lowers_the_norm() {
    // from ‖r‖ = 0.4: α = 1 gives 0.8, ½ gives 0.3 ≤ 0.4: taken
    let mut discarded = vec![];
    let s = backtrack(4, 0.4, false, norm_at(0.3), |a| discarded.push(a)).unwrap();
    assert_eq!((s.alpha, s.at, s.last), (0.5, 0.5, true));
    assert!((s.norm - 0.3).abs() < 1e-15);
    assert_eq!(discarded, vec![1.0]);
    // the full step is taken where it lowers the norm
    let s = backtrack(4, 0.4, false, norm_at(0.9), drop).unwrap();
    assert_eq!(s.alpha, 1.0);
}

#[test]
fn backtracking_keeps_the_best_step_when_none_lowers_the_norm() {
    // ‖r‖ = 0.05 is below the norm at every α: the best of 1, ½, ¼, ⅛ is ¼ (|¼ − 0.2|)
    let mut tried = vec![];
    let eval = |alpha: f64| {
        tried.push(alpha);
        Some(((alpha - 0.2).abs() + 0.1, alpha))
    };
    let s = backtrack(4, 0.05, false, eval, drop).unwrap();
    assert_eq!(tried, vec![1.0, 0.5, 0.25, 0.125]);
    assert_eq!(s.alpha, 0.25);
    // it was not the last evaluated (⅛ was)
    assert!(!s.last);
    // twelve steps go down to 2⁻¹¹
    let s = backtrack(12, 0.0, false, norm_at(0.0), drop).unwrap();
    assert_eq!(s.alpha, 2f64.powi(-11));
}

#[test]
fn backtracking_stops_where_a_step_leaves_the_model() {
    // the full step always taken (a time step's first iteration), however it does
    let s = backtrack(4, 0.0, true, norm_at(0.0), drop).unwrap();
    assert_eq!(s.alpha, 1.0);
    // the full step leaves the model: no shorter one is tried
    let s = backtrack(4, 0.0, false, |a: f64| (a < 1.0).then_some((a, a)), drop);
    assert!(s.is_none());
    // a step that leaves the model after one that stayed: the one that stayed
    let s = backtrack(4, 0.0, false, |a: f64| (a >= 0.5).then_some((a, a)), drop).unwrap();
    assert_eq!(s.alpha, 0.5);
}

#[test]
fn a_safeguard_tries_the_alternative_only_where_the_first_step_fails() {
    // the first step lowers the norm (0.5 < 1): taken, the alternative never computed
    let never = || -> Result<Option<(f64, &str)>> { panic!("not needed") };
    let (kept, first) = safeguard(1.0, Some((0.5, "tangent")), Keep::Better, never).unwrap();
    assert_eq!((kept, first), (Some((0.5, "tangent")), true));
    // it does not: the better of the two (Keep::Better) ...
    let alt = || Ok(Some((1.5, "secant")));
    let (kept, first) = safeguard(1.0, Some((2.0, "tangent")), Keep::Better, alt).unwrap();
    assert_eq!((kept, first), (Some((1.5, "secant")), false));
    let alt = || Ok(Some((3.0, "secant")));
    let (kept, first) = safeguard(1.0, Some((2.0, "tangent")), Keep::Better, alt).unwrap();
    assert_eq!((kept, first), (Some((2.0, "tangent")), true));
    // ... or the alternative's whatever it gives (Keep::Alternative)
    let alt = || Ok(Some((3.0, "secant")));
    let (kept, first) = safeguard(1.0, Some((2.0, "tangent")), Keep::Alternative, alt).unwrap();
    assert_eq!((kept, first), (Some((3.0, "secant")), false));
    // no first step at all: the alternative's, or nothing
    let (kept, _) = safeguard(1.0, None, Keep::Better, || Ok(Some((3.0, "secant")))).unwrap();
    assert_eq!(kept, Some((3.0, "secant")));
    let (kept, _) = safeguard::<&str>(1.0, None, Keep::Better, || Ok(None)).unwrap();
    assert_eq!(kept, None);
    // an alternative that cannot be computed leaves the first (Keep::Better)
    let (kept, first) = safeguard(1.0, Some((2.0, "tangent")), Keep::Better, || Ok(None)).unwrap();
    assert_eq!((kept, first), (Some((2.0, "tangent")), true));
}
