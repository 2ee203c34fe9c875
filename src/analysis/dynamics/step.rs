//! The balance of a time step and the linear algebra of its corrections: the scheme's
//! out-of-balance force, the effective matrix (1−α_m)/(βh²) M + (1−α_f) γ/(βh) C +
//! (1−α_f) K_s with the contacts' dashpots and Rayleigh damping, the tangent step by GMRES
//! on its factorization, and the line search (docs/theory.md §5).

use super::*;
use crate::analysis::correction::Buffer;

impl Dynamics<'_> {
    /// The out-of-balance force of a trial increment `dq` of a step (docs/theory.md §5, the
    /// generalized-α balance): r = F_ext − M a_{1−α_m} − (1−α_f)(C v₁ + F_int(q₁)) −
    /// α_f (C v₀ + F_int(q₀)) (N), with the Newmark kinematics of `k` for a₁ and v₁; the
    /// viscous forces C v₁ of the trial states (the dashpots of closed contacts, the
    /// blocks' Kelvin–Voigt viscosity, Rayleigh damping).
    pub(super) fn balance(&mut self, k: &StepTerms, dq: &[f64], trial: &Trial) -> Balance {
        let n = dq.len();
        let StepTerms {
            am,
            af,
            beta,
            gamma,
            c0,
            h,
            vg1,
            ..
        } = *k;
        let [ra0, ra1] = self.settings.rayleigh;
        let a1: Vec<f64> = (0..n)
            .map(|i| c0 * (dq[i] - h * self.v[i] - h * h * (0.5 - beta) * self.a[i]))
            .collect();
        let v1: Vec<f64> = if self.settings.inertia {
            (0..n)
                .map(|i| self.v[i] + h * ((1.0 - gamma) * self.a[i] + gamma * a1[i]))
                .collect()
        } else {
            dq.iter().map(|d| d / h).collect()
        };
        // the damping acts on the velocity relative to the ground
        let v1r = self.relative(&v1, vg1);
        let mut fv1: Vec<f64> = (0..n).map(|i| ra0 * self.mass[i] * v1r[i]).collect();
        if ra1 > 0.0 {
            // stiffness-proportional damping with the secant stiffness of the states at the
            // step's start (the committed stiffness, as OpenSees' `betaKcomm`), on the
            // trial's geometry: with the trial's states, a contact that changed between
            // stick and slip switched a₁ kₛ δ̇ₛ on and off, and the iterations cycled about
            // it (a rigid wall under El Centro failed within 0.02 s:
            // docs/decisions/0023-dashpots-and-rayleigh.md); none from a contact with no
            // force at the start (`DASHPOT_FORCE`), nor across one open in the trial (no
            // damping force across an open band, as for the dashpots)
            let local: Vec<LocalStiffness> = (0..self.springs.len())
                .map(|c| self.rayleigh_local(c, trial.state[c]))
                .collect();
            self.system
                .stiffness_into(&trial.mesh, &local, &mut self.lin.kbuf);
            let mut kv = vec![0.0; n];
            self.lin.kbuf.mul_vec(&v1r, &mut kv);
            for (f, x) in fv1.iter_mut().zip(&kv) {
                *f += ra1 * x;
            }
        }
        let lc = self.cbuf.is_some().then(|| self.dashpots(&trial.state));
        if let (Some(lc), Some(cbuf)) = (lc, self.cbuf.as_mut()) {
            self.system.damping_into(&trial.mesh, &lc, cbuf);
            let mut cv = vec![0.0; n];
            cbuf.mul_vec(&v1r, &mut cv);
            for (f, x) in fv1.iter_mut().zip(&cv) {
                *f += x;
            }
        }
        let f_inertia: Vec<f64> = if self.settings.inertia {
            (0..n)
                .map(|i| self.mass[i] * ((1.0 - am) * a1[i] + am * self.a[i]))
                .collect()
        } else {
            vec![0.0; n]
        };
        let r: Vec<f64> = (0..n)
            .map(|i| {
                k.fe[i]
                    - f_inertia[i]
                    - (1.0 - af) * (fv1[i] + trial.f_int[i])
                    - af * (self.f_visc[i] + self.f_int[i])
            })
            .collect();
        let scale = norm(&k.fe)
            .max(norm(&f_inertia))
            .max(norm(&trial.f_int))
            .max(1e-300);
        Balance {
            rn: norm(&r),
            r,
            scale,
            v1,
            a1,
            fv1,
        }
    }

    /// Try one step of length h from the committed state; `None` when it does not
    /// converge (the caller cuts it). `last_resort`: the step cannot be cut further, and
    /// contacts that cycle are held open ([`FREEZE_FLIPS`]). `start`: the increment of
    /// the unknowns the iterations start from, in the trial's own contact states (the
    /// answer of a first try of the same step, which [`Dynamics::advance_to`] redoes);
    /// `None`: the committed state carried along by the ground, in the committed states.
    pub(super) fn step(
        &mut self,
        h: f64,
        last_resort: bool,
        start: Option<&[f64]>,
    ) -> Result<Option<Accepted>> {
        let s = self.settings.scheme;
        let inertia = self.settings.inertia;
        // without inertia: backward Euler, v₁ = Δu/h, the balance taken at t₁
        let (am, af, beta, gamma) = if inertia {
            (s.alpha_m, s.alpha_f, s.beta, s.gamma)
        } else {
            (0.0, 0.0, 1.0, 1.0)
        };
        let n = self.cur.n_dofs;
        let t0 = self.time;
        let (g0, g1) = (self.ground(t0), self.ground(t0 + h));
        let absolute = self.settings.absolute;
        let fe: Vec<f64> = if absolute {
            // the ground reaches the blocks through the contacts of the moving foundation
            self.f_static.clone()
        } else {
            let (fg0, fg1) = (self.f_ground(g0), self.f_ground(g1));
            (0..n)
                .map(|i| self.f_static[i] + (1.0 - af) * fg1[i] + af * fg0[i])
                .collect()
        };
        // the foundation's motion over the step by the scheme's Newmark relations, the
        // same ones as the blocks' (absolute frame; with Newmark's average acceleration
        // the run then equals the relative frame's to round-off)
        let (dug, vg1) = if absolute {
            let vg = self.ground_v;
            (
                [0, 1].map(|c| h * vg[c] + h * h * ((0.5 - beta) * g0[c] + beta * g1[c])),
                [0, 1].map(|c| vg[c] + h * ((1.0 - gamma) * g0[c] + gamma * g1[c])),
            )
        } else {
            ([0.0; 2], [0.0; 2])
        };
        let c0 = if inertia { 1.0 / (beta * h * h) } else { 0.0 };
        self.dashpot_floor = DASHPOT_FORCE * norm(&fe).max(norm(&self.f_int));
        let terms = StepTerms {
            am,
            af,
            beta,
            gamma,
            c0,
            h,
            fe,
            vg1,
        };
        // start from the committed state carried along by the ground (the first solve is
        // the linearized step: a predictor that moves stiff contacts would start far
        // from the answer)
        let dq: Vec<f64> = match start {
            Some(s) => s.to_vec(),
            None => self.absolute_from_relative(&vec![0.0; n], dug),
        };
        let trial = self.trial_moving(&dq, dug);
        let contacts = trial.state.len();
        let size = {
            let b = crate::geometry::polygon::bbox(&self.cur.nodes);
            (b[2] - b[0]).hypot(b[3] - b[1]).max(1e-9)
        };
        let bal = self.balance(&terms, &dq, &trial);
        let controls = IterationControls {
            tolerance: self.settings.tolerance,
            max_iterations: self.settings.max_iterations,
            stall_progress: STALL_PROGRESS,
        };
        let mut step = step_try::StepTry {
            d: self,
            terms,
            t0,
            g1,
            dug,
            vg1,
            last_resort,
            started: start.is_some(),
            dq,
            trial,
            bal,
            flips: vec![0; contacts],
            slip_flips: vec![0; contacts],
            weight: vec![1.0; contacts],
            frozen: vec![false; contacts],
            closed_max: vec![0.0; contacts],
            last_rn: f64::INFINITY,
            last_tangent: false,
            size,
        };
        let end = solver::iterate(&mut step, &controls)?;
        Ok(step.finish(end))
    }

    /// The tangent step of [`Dynamics::step`] from `dq` and the line search along it: the
    /// effective matrix with the contacts' tangent stiffness in the trial's states (the
    /// slipping contacts' friction–normal coupling, [`tangent_local`]; the normal springs
    /// of `secant`, which carry the anti-chatter weights), solved by GMRES preconditioned
    /// with the backend's factorization of the secant effective matrix (an inexact Newton
    /// step, to a tenth of the tolerance, as the static driver's). `None` when GMRES does
    /// not converge within `TANGENT_MAX_ITERATIONS` or the step leaves the model.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn tangent_step(
        &mut self,
        trial: &Trial,
        blocks: Option<&Mesh>,
        secant: &[LocalStiffness],
        frozen: &[bool],
        terms: &StepTerms,
        dq: &[f64],
        bal: &Balance,
        it: usize,
        dug: [f64; 2],
        size: f64,
    ) -> Option<(Vec<f64>, Trial, Balance, bool)> {
        let local: Vec<LocalStiffness> = (0..secant.len())
            .map(|k| match frozen[k] {
                true => secant[k],
                false => {
                    let mut l = tangent_local(
                        self.springs[k],
                        trial.state[k],
                        trial.force[k][1],
                        self.law.tan_phi,
                    );
                    l[0][0] = secant[k][0][0];
                    l
                }
            })
            .collect();
        self.effective_into(blocks, &trial.mesh, &local, &trial.state, terms, true);
        let tolerance =
            (0.1 * self.settings.tolerance * bal.scale / bal.rn.max(1e-300)).clamp(1e-10, 1e-3);
        let x = self.lin.gmres(
            Buffer::Aux,
            false,
            &bal.r,
            tolerance,
            f64::INFINITY,
            &mut self.stats,
        )?;
        let step = self.search(terms, dq, &x, bal, it, frozen, dug, size);
        if crate::analysis::tracing() {
            eprintln!(
                "  tangent step: ratio {:.3}",
                step.as_ref().map_or(f64::NAN, |s| s.2.rn / bal.rn)
            );
        }
        step
    }

    /// The geometry of the deformable blocks' triangles in the iteration matrix of a
    /// trial on `trial` ([`Dynamics::effective_into`]): the step's start for the blocks
    /// with interior nodes (whose rows only the triangles fill) that turned by at most
    /// [`START_GEOMETRY_TURN`] from it, the trial's for the others (`None`: the start's
    /// for all, `Some(None)`: the trial's for all). A block without interior nodes gains
    /// nothing from the start's geometry (no row of it stays the same while its contacts
    /// change), so it keeps the trial's.
    pub(super) fn blocks_geometry(&self, trial: &Mesh) -> Option<Option<Mesh>> {
        let turns = turns(&self.cur, trial);
        let at_trial: Vec<bool> = self
            .cur
            .blocks
            .iter()
            .zip(&turns)
            .map(|(b, &t)| {
                let interior = b.nodes.len() > b.boundary.len();
                b.dofs == BlockDofs::Deformable && (t > START_GEOMETRY_TURN || !interior)
            })
            .collect();
        let deformable = |b: usize| self.cur.blocks[b].dofs == BlockDofs::Deformable;
        if !(0..at_trial.len()).any(deformable) {
            // no triangles, whose geometry is all this chooses: the trial's, the one the
            // contacts take, so that the damping matrix `balance` assembled for the trial
            // serves the iteration matrix too (`Dynamics::effective_into`)
            return Some(None);
        }
        if !at_trial.contains(&true) {
            return None;
        }
        if (0..at_trial.len()).all(|b| at_trial[b] || !deformable(b)) {
            return Some(None);
        }
        let mut m = self.cur.clone();
        for (b, _) in at_trial.iter().enumerate().filter(|(_, &t)| t) {
            let r = self.cur.blocks[b].nodes.start as usize..self.cur.blocks[b].nodes.end as usize;
            m.nodes[r.clone()].copy_from_slice(&trial.nodes[r]);
        }
        Some(Some(m))
    }

    /// The state of contact `c` at the step's start as its damping sees it: the committed
    /// one, open where the contact carried less than the step's [`DASHPOT_FORCE`] there.
    pub(super) fn damped_state(&self, c: usize) -> ContactState {
        let [fn0, fs0] = self.committed.force[c];
        if fn0.hypot(fs0) < self.dashpot_floor {
            ContactState::Open
        } else {
            self.committed.state[c]
        }
    }

    /// The local stiffness (N/m) of contact `c` in the stiffness-proportional Rayleigh
    /// term a₁ K of a trial in which it is in `state`: the secant one of its state at the
    /// step's start ([`Dynamics::damped_state`]), none where it is open in the trial.
    pub(super) fn rayleigh_local(&self, c: usize, state: ContactState) -> LocalStiffness {
        match state {
            ContactState::Open => [[0.0; 2]; 2],
            _ => secant_local(self.springs[c], self.damped_state(c)),
        }
    }

    /// The contacts' local dashpot matrices for the trial states `state`.
    pub(super) fn dashpots(&self, state: &[ContactState]) -> Vec<LocalStiffness> {
        (0..self.visc.len())
            .map(|c| {
                // the dashpots act while the band is closed, slipping or not (in parallel
                // with the friction slider: a viscous shear that vanished at the onset of
                // slip would make the force jump by cₛ γ̇ there and the iterations cycle
                // between stick and slip), at the start of the step and in the trial: a
                // contact that closes within the step meets the band's spring alone until
                // the step's end (its dashpot, engaged at δ = 0 with the full approach
                // speed, would make the force jump there from 0 to cₙ v, a law with no
                // solution at the kink that the iterations cycle around: open → closed
                // with a dashpot force that reopens it → open)
                // with no force at the step's start (`DASHPOT_FORCE`), none over the step
                let state = match (self.damped_state(c), state[c]) {
                    (ContactState::Open, _) => ContactState::Open,
                    (_, ContactState::Slip) => ContactState::Stick,
                    (_, s) => s,
                };
                secant_local(self.visc[c], state)
            })
            .collect()
    }

    /// The step's effective matrix (1−α_m) c₀ M + (1−α_f) c₁ C + (1−α_f) K for the
    /// contacts' local stiffnesses `local` (K with its Rayleigh damping,
    /// (1−α_f) c₁ a₁ K) and C of the dashpots in the trial states `state`, into the
    /// correction solver's `kbuf`; into its `aux` when `second` (the tangent's, with the C of the `kbuf` built before
    /// it in the same iteration).
    ///
    /// The contacts in the trial's geometry `contacts`, the blocks' triangles (and their
    /// Kelvin–Voigt viscosity) in `blocks` (`None`: the step's start geometry;
    /// [`Dynamics::blocks_geometry`]), as the static driver's iteration matrix is on the
    /// last converged geometry (the out-of-balance force, which decides convergence, is
    /// always the trial geometry's). The interior rows of a block on the start geometry
    /// then stay the same within a step, and the condensed backend does not refactorize
    /// its interior after the step's first iteration (on the rocking drums of
    /// docs/decisions/0021-start-geometry-interiors.md, those
    /// refactorizations had taken a third of the run). The contacts stay in the trial's
    /// geometry: with them on the start's too, the seed arch's voussoirs, which turn by
    /// up to 10⁻² rad within a step of the collapse, took 2–11 times the iterations.
    pub(super) fn effective_into(
        &mut self,
        blocks: Option<&Mesh>,
        contacts: &Mesh,
        local: &[LocalStiffness],
        state: &[ContactState],
        terms: &StepTerms,
        second: bool,
    ) {
        let [ra0, ra1] = self.settings.rayleigh;
        let StepTerms { am, af, c0, .. } = *terms;
        let c1 = terms.gamma / (terms.beta * terms.h);
        // the Rayleigh term's contacts in the states `balance` takes them in (the start's):
        // K(local) scaled by (1 + c₁ a₁) below, so the contacts enter as
        // (local + c₁ a₁ K_R) / (1 + c₁ a₁), the blocks' triangles as (1 + c₁ a₁) K
        let with_rayleigh: Vec<LocalStiffness>;
        let local = if ra1 > 0.0 {
            let w = c1 * ra1;
            with_rayleigh = (0..local.len())
                .map(|c| {
                    let r = self.rayleigh_local(c, state[c]);
                    let l = local[c];
                    [0, 1].map(|i| [0, 1].map(|j| (l[i][j] + w * r[i][j]) / (1.0 + w)))
                })
                .collect();
            &with_rayleigh
        } else {
            local
        };
        let out = if second {
            self.lin.aux_values()
        } else {
            &mut self.lin.kbuf
        };
        let blocks = blocks.unwrap_or(&self.cur);
        self.system
            .stiffness_split_into(blocks, contacts, local, out);
        if !second {
            if let (true, Some(cbuf), Some(cmat)) = (
                std::ptr::eq(blocks, contacts),
                self.cbuf.as_ref(),
                self.cmat.as_mut(),
            ) {
                // everything in the trial's geometry: C is the one `balance` assembled for
                // this trial (the caller's `bal`), in the same states
                cmat.values.copy_from_slice(&cbuf.values);
            } else {
                let lc = self.cmat.is_some().then(|| self.dashpots(state));
                if let (Some(lc), Some(cmat)) = (lc, self.cmat.as_mut()) {
                    self.system.damping_split_into(blocks, contacts, &lc, cmat);
                }
            }
        }
        let out = if second {
            &mut self.lin.aux
        } else {
            &mut self.lin.kbuf
        };
        let kf = (1.0 - af) * (1.0 + c1 * ra1);
        let mf = (1.0 - am) * c0 + (1.0 - af) * c1 * ra0;
        match &self.cmat {
            Some(c) => {
                for (k, cv) in out.values.iter_mut().zip(&c.values) {
                    *k = kf * *k + (1.0 - af) * c1 * cv;
                }
            }
            None => out.values.iter_mut().for_each(|k| *k *= kf),
        }
        for (i, &p) in self.diag.iter().enumerate() {
            out.values[p] += mf * self.mass[i];
        }
    }

    /// Backtracking along the correction `x` from `dq` on the out-of-balance norm
    /// ([`solver::backtrack`]): where
    /// the full step overshoots (a contact cycling between its open and closed
    /// linearizations, each of which carries the iterate past the kink of the law), a
    /// shorter one lands near the kink. Returns the best of the tried steps: its unknowns,
    /// trial and balance, and whether it was the last one evaluated (then `cbuf` holds its
    /// C); `None` when even the full step leaves the model (a step larger than half its
    /// size, `size` in m, or not finite).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn search(
        &mut self,
        terms: &StepTerms,
        dq: &[f64],
        x: &[f64],
        bal: &Balance,
        it: usize,
        frozen: &[bool],
        dug: [f64; 2],
        size: f64,
    ) -> Option<(Vec<f64>, Trial, Balance, bool)> {
        // the first iteration's residual is that of the committed state, before any
        // inertia: its full step is the linearized step, always taken
        let eval = |alpha: f64| {
            let cand: Vec<f64> = dq.iter().zip(x).map(|(d, x)| d + alpha * x).collect();
            let dmax = cand.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if !dmax.is_finite() || dmax > 0.5 * size {
                return None;
            }
            let mut t = self.trial_moving(&cand, dug);
            hold_open(&mut t, frozen);
            let b = self.balance(terms, &cand, &t);
            Some((b.rn, (cand, t, b)))
        };
        let best = solver::backtrack(LINE_SEARCH_STEPS, bal.rn, it == 0, eval, drop)?;
        let (c, t, b) = best.at;
        Some((c, t, b, best.last))
    }
}
