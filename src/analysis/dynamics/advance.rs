//! Advancing the run in time: the steps to a target time, halved where a try fails or
//! jumps over an impact and grown back after, the release of contacts that let go, the
//! error-controlled step, and the commit of a converged step (velocities, accelerations,
//! the energy audit; docs/theory.md, "Impacts" and "Energy audit").

use super::*;

/// The least slip rate (m/s) of a stick–slip event, |Δδₛ|/h or |δ̇ₛ| at the step's end,
/// for the step to be cut around it ([`Dynamics::slip_event`]); a rate, the same at every
/// cut, so that an event counted is placed to dt/2^event_cuts: the joints of a rock mass
/// that stick and slip slower at nearly every step cost the tunnel earthquake 7 times the
/// steps (docs/decisions/0036-stick-slip-events.md).
const EVENT_SLIP_RATE: f64 = 1e-4;

impl Dynamics<'_> {
    /// Elastic energy (J) of a state: blocks ½ ∫ σᵀ Dₑ⁻¹ σ, contacts ½ (Fₙ²/kₙ + Fₛ²/kₛ).
    pub(super) fn elastic_energy(
        &self,
        mesh: &Mesh,
        stress: &[[f64; 3]],
        force: &[[f64; 2]],
    ) -> f64 {
        let t = self.scene.model.thickness;
        let mut e = 0.0;
        for (k, s) in stress.iter().enumerate() {
            let c = &self.compliance[k];
            let mut q = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    q += s[i] * c[i][j] * s[j];
                }
            }
            e += 0.5 * q * t * mesh.triangle_area(k);
        }
        for (f, k) in force.iter().zip(&self.springs) {
            if k.kn > 0.0 {
                e += 0.5 * f[0] * f[0] / k.kn;
            }
            if k.ks > 0.0 {
                e += 0.5 * f[1] * f[1] / k.ks;
            }
        }
        e
    }

    pub(super) fn commit(&mut self, acc: Accepted) {
        let Accepted {
            trial,
            v,
            a,
            f_visc,
            h,
            ground,
            ground_du,
            ground_v1,
            ..
        } = acc;
        let dq = &trial.dq;
        let g0 = self.ground(self.time);
        let (work_ground, viscous) = if self.settings.absolute {
            // the foundation's work through the contacts that touch it: −Δu_g · ιᵀ(F_int +
            // C v)ₘ (the internal and viscous forces of everything else have no
            // resultant); the dissipation is that of the motion relative to the ground
            let dq_rel = self.relative(dq, ground_du);
            let mean: Vec<f64> = (0..dq.len())
                .map(|i| 0.5 * (self.f_int[i] + self.f_visc[i] + trial.f_int[i] + f_visc[i]))
                .collect();
            let r = self.resultant(&mean);
            (
                -(ground_du[0] * r[0] + ground_du[1] * r[1]),
                0.5 * (dot(&dq_rel, &self.f_visc) + dot(&dq_rel, &f_visc)),
            )
        } else {
            let (fg0, fg1) = (self.f_ground(g0), self.f_ground(ground));
            (
                0.5 * (dot(dq, &fg0) + dot(dq, &fg1)),
                0.5 * (dot(dq, &self.f_visc) + dot(dq, &f_visc)),
            )
        };
        let e = &mut self.energy;
        e.work_static += dot(dq, &self.f_static);
        e.work_ground += work_ground;
        e.viscous += viscous;
        // friction: the shear force's work beyond its elastic energy (the normal band
        // with its opening is elastic: no dissipation)
        let mut contact = 0.0;
        for (k, sp) in self.springs.iter().enumerate() {
            let f0 = self.true_force(k);
            let (f1, d) = (trial.force[k], trial.rel[k]);
            if sp.ks > 0.0 && (f0[1] != 0.0 || f1[1] != 0.0) {
                contact += 0.5 * (f0[1] + f1[1]) * (d[1] - (f1[1] - f0[1]) / sp.ks);
            }
        }
        // work of the blocks' relative motion on the contacts beyond their elastic energy
        self.energy.contact += contact;
        self.energy.kinetic = if self.settings.inertia { 0.5 } else { 0.0 }
            * (0..v.len())
                .map(|i| self.mass[i] * v[i] * v[i])
                .sum::<f64>();
        self.energy.elastic = self.elastic_energy(&trial.mesh, &trial.stress, &trial.force);
        for (u, d) in self.committed.u.iter_mut().zip(dq) {
            *u += d;
        }
        self.f_int = trial.f_int;
        // an open contact keeps its opening, as the normal force it would carry if the
        // band could pull (Fₙ = kₙ × opening > 0, never applied): the contact law then
        // closes it only when the opening is taken up, not at the next compressive
        // increment (a rocking block lands where it lifted off)
        let mut force = trial.force;
        for (k, f) in force.iter_mut().enumerate() {
            if trial.state[k] == ContactState::Open {
                *f = [
                    self.committed.force[k][0] + self.springs[k].kn * trial.rel[k][0],
                    0.0,
                ];
            }
        }
        self.committed.stress = trial.stress;
        self.committed.force = force;
        self.committed.state = trial.state;
        self.cur = trial.mesh;
        self.v = v;
        self.a = a;
        self.f_visc = f_visc;
        self.time += h;
        self.ground_u = [0, 1].map(|c| self.ground_u[c] + ground_du[c]);
        self.ground_v = ground_v1;
        self.stats.increments += 1;
    }

    /// Whether a converged step closes a contact faster than the step can resolve: a
    /// contact that ends closed after approaching by more than the band thickness h
    /// within the step. Such a step jumps over the impact, from free flight to a band
    /// compressed beyond its thickness, and lands at forces far above the impact's
    /// (v √(kₙ m) for a mass m meeting the band at speed v); with the impact spread over
    /// steps shorter than the contact's period 2π √(m/kₙ) the band is compressed by
    /// v √(m/kₙ), which stays within h for blocks of masonry at the speeds of a collapse.
    /// The same limit on the approach per step as DDA's (Shi 1988: the step is cut until
    /// no contact penetrates more than a set fraction of the block size in it).
    pub(super) fn too_fast(&self, acc: &Accepted) -> bool {
        let band = self.law.elastic.band;
        (0..acc.trial.state.len()).any(|k| {
            let d = acc.trial.rel[k][0];
            if acc.frozen[k] {
                // held open: the gap it ends with, Fₙ₀/kₙ + Δδₙ, becomes elastic energy
                // ½ kₙ δ² next step that no work paid for: a tenth of the band at most
                let kn = self.springs[k].kn;
                kn > 0.0 && self.committed.force[k][0] / kn + d < -HELD_PENETRATION * band
            } else {
                acc.trial.state[k] != ContactState::Open && -d > band
            }
        })
    }

    /// The local error (m) of a converged step of length h: the largest node displacement
    /// of the Newmark family's local truncation error e = h² (β − 1/6) (a₁ − a₀)
    /// (Zienkiewicz and Xie 1991, the difference between the step's displacement and a
    /// third-order Taylor expansion), over all nodes. Zero without inertia.
    pub(super) fn step_error(&self, acc: &Accepted, h: f64) -> f64 {
        if !self.settings.inertia {
            return 0.0;
        }
        let c = h * h * (self.settings.scheme.beta - 1.0 / 6.0);
        // of the motion relative to the ground (the foundation's own is exact)
        let g0 = self.ground(self.time);
        let da = [acc.ground[0] - g0[0], acc.ground[1] - g0[1]];
        let e: Vec<f64> = self
            .relative(&acc.a, da)
            .iter()
            .zip(&self.a)
            .map(|(a1, a0)| c * (a1 - a0))
            .collect();
        (0..self.cur.nodes.len() as u32)
            .map(|n| {
                let d = self.cur.node_displacement(n, &e);
                d[0].hypot(d[1])
            })
            .fold(0.0, f64::max)
    }

    /// Advance to time `target` (s), cutting the step when it does not converge.
    /// Returns false when even the smallest step fails.
    pub(super) fn advance_to(&mut self, target: f64) -> Result<bool> {
        let hmin = self.settings.dt / 2f64.powi(self.settings.max_cuts as i32);
        let hevent = self.settings.dt / 2f64.powi(self.settings.event_cuts as i32);
        let mut h = target - self.time;
        while self.time < target - 1e-9 * self.settings.dt {
            h = h.min(target - self.time);
            let last_resort = h <= hmin * (1.0 + 1e-9);
            let mut accepted = self.step(h, last_resort, None)?;
            let mut saved = None;
            if let Some(released) = accepted.as_ref().and_then(|acc| self.released(acc)) {
                // contacts that carried force at the start let go within the step: their
                // force, still in a₀ and F_int(u₀), would act over the whole step through
                // the (½ − β) h² a₀ and (1 − γ) h a₀ terms of the update (and α_m M a₀,
                // α_f F_int(u₀)), an impulse of about ½ h Fₙ where the band releases in a
                // fraction of the step: energy fed into the free motion (a block dropped on
                // its base bounced higher than it fell). The step is redone from the
                // start's acceleration and internal force without them.
                let start = (self.a.clone(), self.f_int.clone());
                if crate::analysis::tracing() {
                    let k: Vec<usize> = (0..released.len()).filter(|&k| released[k]).collect();
                    eprintln!("  release redo: contacts {k:?}");
                }
                // the redo starts from the first try's answer, which differs from the
                // redo's by the released contacts' small share of the start: 2–3
                // iterations instead of the 5–7 of a start from rest (docs/decisions/
                // 0022-release-redo-and-held-open-contacts.md)
                let first = accepted.as_ref().map(|acc| acc.trial.dq.clone());
                self.release(&released);
                let before = self.stats.iterations;
                accepted = self.step(h, last_resort, first.as_deref())?;
                self.stats.release_redos += 1;
                self.stats.release_redo_iterations += self.stats.iterations - before;
                saved = Some(start);
            }
            // the local error of a step, computed once for the cut and the growth of the
            // next step of an error-controlled run, and for the summary's estimate
            let error = match &accepted {
                Some(acc) => self.step_error(acc, h),
                None => 0.0,
            };
            let cut = match &accepted {
                None => true,
                // an impact the step cannot resolve: cut it (see `too_fast`)
                Some(acc) if h > hmin * (1.0 + 1e-9) && self.too_fast(acc) => {
                    if crate::analysis::tracing() {
                        eprintln!("  impact cut");
                    }
                    self.stats.impact_cuts += 1;
                    true
                }
                Some(_)
                    if h > hmin * (1.0 + 1e-9)
                        && self.settings.adaptive.is_some_and(|tol| error > tol) =>
                {
                    self.stats.error_cuts += 1;
                    true
                }
                // a contact starts or stops slipping, or reverses, within the step: cut
                // it until the event is placed to within dt/2^event_cuts
                Some(acc) if h > hevent * (1.0 + 1e-9) && self.slip_event(acc) => {
                    self.stats.event_cuts += 1;
                    true
                }
                Some(_) => false,
            };
            if cut {
                if let Some((a, f)) = saved {
                    (self.a, self.f_int) = (a, f);
                }
                // the bonds broken in the step's tries are given back: its retry starts
                // from the committed state as it was
                OpenFlips::give_back(&mut self.committed.history, &mut self.bonds_broken_here);
                if accepted.is_some() {
                    h *= 0.5;
                    continue;
                }
            }
            match accepted {
                Some(acc) => {
                    let before: Vec<bool> = self
                        .committed
                        .state
                        .iter()
                        .map(|s| *s == ContactState::Open)
                        .collect();
                    // an error-controlled step grows only where the doubled step would
                    // stay within the tolerance (the local error grows as h³)
                    let grow = self.settings.adaptive.is_none_or(|tol| error < tol / 8.0);
                    self.stats.bonds_broken += self.bonds_broken_here.len();
                    self.stats.step_error_max = self.stats.step_error_max.max(error);
                    self.stats.step_error_sum += error;
                    self.bonds_broken_here.clear();
                    self.commit(acc);
                    if crate::analysis::tracing() {
                        eprintln!(
                            "  commit t {:.6} h {h:.3e} E_k {:.4e} E_el {:.4e}",
                            self.time, self.energy.kinetic, self.energy.elastic
                        );
                    }
                    let switched = before
                        .iter()
                        .zip(&self.committed.state)
                        .any(|(o, s)| *o != (*s == ContactState::Open));
                    let changed = self.update_contacts();
                    if self.settings.reset_on_impact
                        && self.settings.inertia
                        && (switched || changed)
                    {
                        self.filtered_acceleration();
                    }
                    if grow {
                        h *= 2.0;
                    }
                }
                None => {
                    if h <= hmin * (1.0 + 1e-9) {
                        return Ok(false);
                    }
                    h *= 0.5;
                }
            }
        }
        self.time = target;
        Ok(true)
    }

    /// Whether a converged step holds a stick–slip event: a contact closed at both its
    /// ends that sticks at one and slips at the other, or slips at both in opposite
    /// directions (its shear force Fₛ changed sign), or slips at both in the same
    /// direction but ends with its slip velocity against its friction force
    /// (Fₛ δ̇ₛ < 0: the slip reversed within the step, the increment Δδₛ keeping the
    /// sign of the slip before the reversal). Where such an event falls inside a step the
    /// friction force jumps by up to 2 μ Fₙ there, while the scheme's trapezoidal rule
    /// v₁ = v₀ + h((1−γ) a₀ + γ a₁) spreads the jump over the whole step: an error of the
    /// order of μ Fₙ h/m in the velocity per event, which cutting the step around the
    /// event reduces (docs/theory.md §5, "Stick–slip events").
    pub(super) fn slip_event(&self, acc: &Accepted) -> bool {
        use ContactState::{Open, Slip, Stick};
        // the velocities relative to the ground (the foundation's own in the absolute
        // frame), at the step's end
        let v = self.relative(&acc.v, acc.ground_v1);
        let mesh = &acc.trial.mesh;
        let slip_rate = |k: usize| {
            let c = &mesh.contacts[k];
            let vn = |n: u32| mesh.node_displacement(n, &v);
            let r = crate::geometry::polygon::sub(vn(c.node_m), c.at_l(vn));
            crate::analysis::config::in_contact_frame(c.normal, r)[1]
        };
        (0..acc.trial.state.len()).any(|k| {
            let (s0, s1) = (self.committed.state[k], acc.trial.state[k]);
            let (f0, f1) = (self.committed.force[k][1], acc.trial.force[k][1]);
            let event = match (s0, s1) {
                (Stick, Slip) | (Slip, Stick) => true,
                (Slip, Slip) => f0 * f1 < 0.0 || f1 * slip_rate(k) < 0.0,
                (Open, _) | (_, Open) | (Stick, Stick) => false,
            };
            event && (acc.trial.rel[k][1].abs() / acc.h).max(slip_rate(k).abs()) > EVENT_SLIP_RATE
        })
    }

    /// The contacts a converged step opens that were closed at its start, if any (with
    /// `impact_reset` and inertia: the steps [`Dynamics::advance_to`] redoes).
    pub(super) fn released(&self, acc: &Accepted) -> Option<Vec<bool>> {
        let released: Vec<bool> = self
            .committed
            .state
            .iter()
            .zip(acc.trial.state.iter().zip(&acc.frozen))
            // not a contact held open after cycling (at the kink, not letting go)
            .map(|(s0, (s1, f))| *s0 != ContactState::Open && *s1 == ContactState::Open && !f)
            .collect();
        (self.settings.reset_on_impact && self.settings.inertia && released.contains(&true))
            .then_some(released)
    }

    /// The start of a step in which the contacts `released` let go: the internal force
    /// F_int(u₀) without their forces, and the acceleration
    /// (M + βh² K_s) a₀ = F − F_int(u₀) − C v₀ with them open (the released contact
    /// exerts nothing over the step; the stiff modes of the others stay filtered as in
    /// [`Dynamics::filtered_acceleration`]). The committed state itself is kept: the
    /// band's elastic energy at the start, ½ Fₙ²/kₙ, is what the release loses.
    pub(super) fn release(&mut self, released: &[bool]) {
        let mut free = self.committed.clone();
        for (k, _) in released.iter().enumerate().filter(|(_, r)| **r) {
            free.force[k] = [0.0; 2];
            free.state[k] = ContactState::Open;
        }
        let states = free.state.clone();
        let kept = std::mem::replace(&mut self.committed, free);
        self.f_int = self.trial(&vec![0.0; self.cur.n_dofs]).f_int;
        self.committed = kept;
        self.filtered_acceleration_with(&states);
    }

    /// The force (N) contact `k` carries: the committed one, zero when it is open.
    pub(super) fn true_force(&self, k: usize) -> [f64; 2] {
        if self.committed.state[k] == ContactState::Open {
            [0.0, 0.0]
        } else {
            self.committed.force[k]
        }
    }
}
