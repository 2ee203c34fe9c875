//! A static or capacity analysis run: the gravity phase, the lateral load or the push in
//! increments (cut where they fail), the capacity search on the load factor, the fallout
//! of local failures, and the outcome.

use super::*;

/// Fallout ([`Driver::fall_out`]): a failure mode that moves at most this many blocks, or
/// [`FALLOUT_MAX_SHARE`] of the free blocks if that is more, is a local failure (key
/// blocks falling out of a tunnel's roof: 6, then 6 behind them, of the 1,348 blocks of
/// the growth bench's excavation at s = 0.55 m, docs/decisions/0032-fallout-constants.md); a larger one is the
/// structure's.
pub(super) const FALLOUT_MAX_BLOCKS: usize = 8;
/// See [`FALLOUT_MAX_BLOCKS`].
pub(super) const FALLOUT_MAX_SHARE: f64 = 0.01;
/// A push whose force along the push ends more than this fraction below its peak on the
/// path has passed its peak: a mechanism, however its last increment ended
/// (docs/decisions/0037-stall-or-mechanism.md).
const PEAK_DROP: f64 = 1e-3;

impl Driver<'_> {
    /// A phase starts: `name` for the progress report, `increments` planned (if known),
    /// `scale` its load factor per unit of the phase's factor.
    pub(super) fn begin_phase(
        &mut self,
        name: &'static str,
        increments: Option<usize>,
        scale: f64,
    ) {
        self.report = Report {
            phase: name,
            scale,
            ..Report::default()
        };
        if let Some(p) = self.progress.as_deref_mut() {
            p.phase(name, increments);
        }
    }

    /// Report a converged increment at the phase's factor `factor`.
    pub(super) fn converged(&mut self, factor: f64) {
        self.report.increments += 1;
        if let Some(p) = self.progress.as_deref_mut() {
            p.increment(&Increment {
                phase: self.report.phase,
                increment: self.report.increments,
                load_factor: factor * self.report.scale,
                iterations: self.report.iterations,
                residual: self.report.residual,
            });
        }
    }

    /// Run a phase from factor 0 to 1 in `steps` increments (cut when they fail).
    /// Returns the factor reached (1 when the phase completed).
    pub(super) fn run_phase(
        &mut self,
        phase: &Phase,
        steps: usize,
    ) -> Result<(f64, Option<String>)> {
        let mut s = 0.0;
        let mut ds = 1.0 / steps as f64;
        let mut cuts = 0;
        // the last converged increment of this phase (its step in the phase's factor and
        // its unknowns' increment): the next one starts from it, scaled to its own step
        // (a linear extrapolation of the path, which saves the first iterations of every
        // increment of a proportional loading)
        let mut last: Option<(f64, Vec<f64>)> = None;
        if !phase.pin_step.is_empty() || !self.pins.is_empty() || !self.fallen.is_empty() {
            // the held factorizations were computed with other unknowns pinned
            self.lin.held = Held::Nothing;
        }
        if let Some(b) = phase.record {
            let p = self.push_point(b, 0.0, None);
            self.push_curve.push(p);
        }
        while s < 1.0 - 1e-12 {
            let target = (s + ds).min(1.0);
            let f: Vec<f64> = phase
                .base
                .iter()
                .zip(&phase.step)
                .map(|(b, st)| b + target * st)
                .collect();
            let presc: Vec<Point> = phase
                .presc_step
                .iter()
                .map(|p| [p[0] * (target - s), p[1] * (target - s)])
                .collect();
            self.pins = phase
                .pin_step
                .iter()
                .map(|&(d, v)| (d, v * (target - s)))
                .chain(self.fallen_pins.iter().copied())
                .collect();
            // (not under a prescribed motion, whose elastic predictor starts closer: a
            // settlement or fault offset that slips joints changes its path every increment)
            let guess = last
                .as_ref()
                .filter(|_| {
                    phase.presc_step.iter().all(|p| *p == [0.0, 0.0]) && phase.pin_step.is_empty()
                })
                .map(|(step, dq)| dq.iter().map(|x| x * (target - s) / step).collect());
            match self.increment(&f, &presc, guess)? {
                Ok(trial) => {
                    let dq = trial.dq.clone();
                    last = Some((target - s, dq.clone()));
                    let reaction = phase.record.map(|b| self.reaction(b, &trial.f_int, &f));
                    self.commit(trial, &dq, &presc);
                    s = target;
                    self.converged(s);
                    if let Some(b) = phase.record {
                        let p = self.push_point(b, s, reaction);
                        self.push_curve.push(p);
                    }
                }
                Err((why, dq)) => {
                    self.failure_mode = Some(dq);
                    if cuts >= self.settings.max_cuts {
                        if self.settings.fallout && self.fall_out() {
                            // the rest of the structure takes the phase again from
                            // where it stood, in the phase's own increments
                            cuts = 0;
                            ds = 1.0 / steps as f64;
                            last = None;
                            continue;
                        }
                        let held = self.failure_mode.as_ref().is_some_and(|f| !f.mechanism);
                        return Ok((s, Some(describe(&why, held))));
                    }
                    cuts += 1;
                    self.stats.load_cuts += 1;
                    ds *= 0.5;
                }
            }
        }
        // the fallen blocks stay held for the phases and paths that follow
        self.pins = self.fallen_pins.clone();
        Ok((1.0, None))
    }

    /// Fallout (docs/theory.md, "Fallout"): the blocks that move in the failure mode of
    /// the failed increment ([`Driver::failure_mode`], classified by
    /// [`crate::analysis::mechanism::classify`]) fall out of the structure when they are few: at
    /// most [`FALLOUT_MAX_BLOCKS`] or [`FALLOUT_MAX_SHARE`] of the free blocks at a time.
    /// Each is held where it stood at the last converged increment (its unknowns pinned),
    /// and its contacts carry no force from then on; the committed state keeps the rest.
    /// Returns whether any block fell; a larger mechanism is the structure's failure.
    pub(super) fn fall_out(&mut self) -> bool {
        let Some(f) = self.failure_mode.as_ref() else {
            return false;
        };
        let mech = crate::analysis::mechanism::classify(
            self.scene, &self.cur, &f.mode, &f.states, &f.forces, &f.loads,
        );
        let mut before = vec![false; self.cur.blocks.len()];
        for &b in &self.fallen {
            before[b] = true;
        }
        let moving: Vec<usize> = mech.moving().into_iter().filter(|&b| !before[b]).collect();
        let free = self
            .cur
            .blocks
            .iter()
            .filter(|b| b.dofs != crate::mesh::BlockDofs::Fixed)
            .count();
        let limit = FALLOUT_MAX_BLOCKS.max((FALLOUT_MAX_SHARE * free as f64) as usize);
        if moving.is_empty() || moving.len() > limit {
            return false;
        }
        let dofs = self.block_dofs();
        let mut now = vec![false; self.cur.blocks.len()];
        for &b in &moving {
            now[b] = true;
            self.fallen_pins.extend(dofs[b].iter().map(|&d| (d, 0.0)));
        }
        // the contacts of the blocks falling now (those of the blocks fallen before are
        // in the list already)
        for (k, c) in self.cur.contacts.iter().enumerate() {
            let (l, m) = (c.block_l as usize, c.block_m as usize);
            if (now[l] || now[m]) && !before[l] && !before[m] {
                self.fallen_contacts.push(k);
                self.committed.force[k] = [0.0, 0.0];
                self.committed.state[k] = ContactState::Open;
            }
        }
        if crate::analysis::tracing() {
            eprintln!("fallout: blocks {moving:?} fall out");
        }
        self.stats.fallen_blocks += moving.len();
        self.fallen.extend(moving);
        self.lin.held = Held::Nothing;
        self.failure_mode = None;
        true
    }

    /// The forces (N, horizontal and vertical) and moment (N·m) that hold the rigid block
    /// `block` on its prescribed path: the internal minus the external force at its
    /// unknowns (the vertical one is zero up to the tolerance when it moves freely).
    pub(super) fn reaction(&self, block: usize, f_int: &[f64], f_ext: &[f64]) -> [f64; 3] {
        match self.cur.blocks[block].dofs {
            crate::mesh::BlockDofs::Rigid { first, .. } => {
                let f = first as usize;
                [0, 1, 2].map(|i| f_int[f + i] - f_ext[f + i])
            }
            _ => [0.0; 3],
        }
    }

    /// A point of the displacement-controlled curve at the phase's factor `s`.
    pub(super) fn push_point(
        &self,
        block: usize,
        s: f64,
        reaction: Option<[f64; 3]>,
    ) -> crate::analysis::curve::CurvePoint {
        let at =
            |b: usize| crate::analysis::curve::block_displacement(&self.cur, &self.committed.u, b);
        crate::analysis::curve::CurvePoint {
            load_factor: s,
            displacement: at(block),
            reaction: Some(reaction.unwrap_or([0.0; 3])),
            top: at(self.top_block.unwrap_or(block)),
        }
    }

    pub(super) fn external(&self, acc: Point, with_loads: bool) -> Vec<f64> {
        let mut f = loads::body_force(self.scene, &self.cur, acc);
        if with_loads {
            for (a, b) in f.iter_mut().zip(loads::applied(self.scene, &self.cur)) {
                *a += b;
            }
        }
        f
    }

    pub(super) fn outcome(
        &self,
        status: Status,
        mesh0: &Mesh,
        load_factor: Option<f64>,
        mechanism: Option<Mechanism>,
    ) -> Outcome {
        let node_disp = self
            .cur
            .nodes
            .iter()
            .zip(&mesh0.nodes)
            .map(|(a, b)| [a[0] - b[0], a[1] - b[1]])
            .collect();
        Outcome {
            status,
            u: self.committed.u.clone(),
            node_disp,
            stress: self.committed.stress.clone(),
            contact_forces: self.committed.force.clone(),
            contact_states: self.committed.state.clone(),
            contact_history: self.committed.history_of_all(self.cur.contacts.len()),
            stats: self.stats.clone(),
            load_factor,
            mechanism,
            current: Some(self.cur.clone()),
            capacity_curve: None,
            history: None,
            fallen: self.fallen.clone(),
        }
    }
}

/// Why an increment failed, in words; `held`: every contact of its last trial sticks
/// ([`Failure::mechanism`] false), so that the contacts are not what gives way.
pub(super) fn describe(why: &IncrementFailure, held: bool) -> String {
    match why {
        IncrementFailure::NoConvergence { residual } if held => format!("the out-of-balance force stays at {residual:.2e} of the load with every contact sticking: the iterations stopped converging"),
        IncrementFailure::NoConvergence { residual } => format!("the out-of-balance force stays at {residual:.2e} of the load: the contacts cannot hold it"),
        IncrementFailure::Divergence => "the displacements grow without bound: the blocks move without restraint".to_string(),
    }
}

/// The outcome of the run that `d` ended with `status` (load factor `lf`, mechanism `mech`),
/// with the backends' counters and the time since `start`.
fn finish(
    d: &mut Driver,
    mesh: &Mesh,
    start: Instant,
    status: Status,
    lf: Option<f64>,
    mech: Option<Mechanism>,
) -> Outcome {
    let bs = d.lin.backend.stats();
    let lu = d.lin.tangent_stats().unwrap_or_default();
    d.stats.factorizations = bs.numeric_factorizations + lu.numeric_factorizations;
    d.stats.tangent_factorizations = lu.numeric_factorizations;
    d.stats.symbolic_factorizations = bs.symbolic_factorizations + lu.symbolic_factorizations;
    d.stats.min_pivot_ratio = bs.min_pivot_ratio;
    d.stats.wall_time_s = start.elapsed().as_secs_f64();
    if crate::analysis::tracing() {
        eprintln!("solver {bs:?}");
        if let Some(l) = d.lin.tangent_stats() {
            eprintln!("solver (tangent LU) {l:?}");
        }
        eprintln!("analysis {} s", d.stats.wall_time_s);
    }
    d.outcome(status, mesh, lf, mech)
}

/// The outcome of a run whose increment failed (`what`: where, e.g. "under gravity at
/// 40 % of the self-weight: why", at load factor `lf`): a failure with its mechanism
/// classified from the last failing increment, or, where that increment shows no
/// mechanism ([`Failure::mechanism`]), iterations that stopped converging.
fn fail(d: &mut Driver, mesh: &Mesh, start: Instant, what: String, lf: Option<f64>) -> Outcome {
    if let Some(f) = d.failure_mode.as_ref().filter(|f| !f.mechanism) {
        let status = Status::NotConverged {
            reason: format!("did not converge {what}"),
            residual: f.residual,
            block: f.worst,
        };
        return finish(d, mesh, start, status, lf, None);
    }
    let what = format!("failed {what}");
    let mech = d
        .failure_mode
        .as_ref()
        .map(|f| classify(d.scene, &d.cur, &f.mode, &f.states, &f.forces, &f.loads));
    let blocks = mech.as_ref().map(|m| m.moving()).unwrap_or_default();
    finish(
        d,
        mesh,
        start,
        Status::Failed {
            reason: what,
            blocks,
        },
        lf,
        mech,
    )
}

/// [`run()`], reporting phases, iterations and converged increments to `progress`;
/// `ranks`: this process's rows in a distributed run ([`System::distributed`]). The phases
/// in turn: gravity and the loads, the prescribed displacements, then the push, the
/// lateral load or the capacity search.
pub fn run_with_progress<'a>(
    scene: &'a Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &'a mut dyn LinearBackend,
    progress: &'a mut dyn Progress,
) -> Result<Outcome> {
    let start = Instant::now();
    let mut driver = Driver::new(scene, mesh, ranks, backend)?;
    driver.progress = Some(progress);
    let d = &mut driver;
    if let Some(out) = unsupported(d, mesh, start) {
        return Ok(out);
    }
    let f_grav = match gravity_phase(d, mesh, start)? {
        Ok(f) => f,
        Err(out) => return Ok(out),
    };
    if let Some(out) = prescribed_phase(d, mesh, start, &f_grav)? {
        return Ok(out);
    }
    if let Some(push) = d.settings.push {
        return push_phase(d, mesh, start, &push);
    }
    match scene.analysis.kind {
        AnalysisType::Static => lateral_phase(d, mesh, start),
        AnalysisType::Capacity => capacity_search(d, mesh, start),
        AnalysisType::Dynamic => unreachable!("the dynamic driver runs elsewhere"),
    }
}

/// [`fail`] where the run has shown a mechanism already (a push past its peak, a
/// capacity search with a failed probe that showed one): a failure, its mechanism
/// classified from the last failing increment whatever that increment showed itself.
fn fail_mechanism(
    d: &mut Driver,
    mesh: &Mesh,
    start: Instant,
    what: String,
    lf: Option<f64>,
) -> Outcome {
    if let Some(f) = d.failure_mode.as_mut() {
        f.mechanism = true;
    }
    fail(d, mesh, start, what, lf)
}

/// Groups of blocks with no chain of contacts down to a fixed block fall: a result.
fn unsupported(d: &mut Driver, mesh: &Mesh, start: Instant) -> Option<Outcome> {
    let scene = d.scene;
    let floating = crate::analysis::support::unsupported_blocks(mesh);
    if !floating.is_empty() {
        let names: Vec<&str> = floating
            .iter()
            .take(5)
            .map(|&b| scene.blocks[b].name.as_str())
            .collect();
        let reason = format!(
            "{} block(s) have no path of contacts to a fixed block and fall: {}{}",
            floating.len(),
            names.join(", "),
            if floating.len() > 5 { ", ..." } else { "" }
        );
        let blocks = (0..mesh.blocks.len())
            .filter(|&b| mesh.blocks[b].dofs != crate::mesh::BlockDofs::Fixed)
            .map(|b| {
                (
                    b,
                    if floating.contains(&b) {
                        crate::analysis::mechanism::Motion::Falling
                    } else {
                        crate::analysis::mechanism::Motion::None
                    },
                )
            })
            .collect();
        let mech = Mechanism {
            blocks,
            mode: "mixed".into(),
        };
        return Some(finish(
            d,
            mesh,
            start,
            Status::Failed {
                reason,
                blocks: floating,
            },
            None,
            Some(mech),
        ));
    }
    None
}

/// Gravity and the loads (or the release of an in-situ stress's out-of-balance force):
/// the gravity force (N), or the outcome where the structure fails under it.
fn gravity_phase(
    d: &mut Driver,
    mesh: &Mesh,
    start: Instant,
) -> Result<std::result::Result<Vec<f64>, Outcome>> {
    let scene = d.scene;
    let g = scene.model.gravity;
    let n = mesh.n_dofs;
    let steps = scene.analysis.load_steps;
    let zero_presc = vec![[0.0; 2]; mesh.blocks.len()];
    // increments of the gravity phase (`gravity_steps`, default `load_steps`): gravity on
    // a structure that stands is nearly linear and needs few
    let gravity_steps = d.settings.gravity_steps.unwrap_or(steps);
    // phase 1: gravity and loads; from an in-situ stress, the release of its out-of-
    // balance force (the excavation): from the internal forces of the initial state, in
    // equilibrium with themselves, to gravity and the loads (docs/theory.md, "In-situ
    // stress")
    let f_grav = d.external(g, true);
    let base = match scene.in_situ {
        None => vec![0.0; n],
        Some(_) => {
            let t = d.trial(&vec![0.0; n], &zero_presc);
            let f0 = t.f_int.clone();
            d.recycle(t);
            f0
        }
    };
    let step: Vec<f64> = f_grav.iter().zip(&base).map(|(g, b)| g - b).collect();
    if scene.in_situ.is_some() {
        d.scale_floor = Driver::norm(&step);
    }
    let phase = Phase {
        step,
        base,
        presc_step: zero_presc.clone(),
        pin_step: Vec::new(),
        record: None,
    };
    d.begin_phase("gravity", Some(gravity_steps), 1.0);
    let (s, why) = d.run_phase(&phase, gravity_steps)?;
    if let Some(why) = why {
        let of = if scene.in_situ.is_some() {
            "of the excavation (the in-situ stress's out-of-balance force released)"
        } else {
            "of the self-weight"
        };
        return Ok(Err(fail(
            d,
            mesh,
            start,
            format!("under gravity at {:.1} % {of}: {why}", 100.0 * s),
            None,
        )));
    }
    Ok(Ok(f_grav))
}

/// The prescribed displacements of fixed blocks under the gravity force `f_grav` (N): the
/// outcome where the structure fails under them.
fn prescribed_phase(
    d: &mut Driver,
    mesh: &Mesh,
    start: Instant,
    f_grav: &[f64],
) -> Result<Option<Outcome>> {
    let scene = d.scene;
    let n = mesh.n_dofs;
    let steps = scene.analysis.load_steps;
    // phase 2: prescribed displacements of fixed blocks
    let presc: Vec<Point> = scene
        .blocks
        .iter()
        .map(|b| b.prescribed.unwrap_or([0.0; 2]))
        .collect();
    if presc.iter().any(|p| *p != [0.0; 2]) {
        let phase = Phase {
            base: f_grav.to_vec(),
            step: vec![0.0; n],
            presc_step: presc,
            pin_step: Vec::new(),
            record: None,
        };
        d.begin_phase("prescribed", Some(steps), 1.0);
        let (s, why) = d.run_phase(&phase, steps)?;
        if let Some(why) = why {
            return Ok(Some(fail(
                d,
                mesh,
                start,
                format!(
                    "at {:.1} % of the prescribed displacement: {why}",
                    100.0 * s
                ),
                None,
            )));
        }
    }
    Ok(None)
}

/// Displacement control of the pushed block (or its arc-length path): the outcome, with
/// the capacity curve.
fn push_phase(d: &mut Driver, mesh: &Mesh, start: Instant, push: &Push) -> Result<Outcome> {
    let scene = d.scene;
    let g = scene.model.gravity;
    let n = mesh.n_dofs;
    let steps = scene.analysis.load_steps;
    let zero_presc = vec![[0.0; 2]; mesh.blocks.len()];
    let crate::mesh::BlockDofs::Rigid { first, .. } = mesh.blocks[push.block].dofs else {
        unreachable!("the scene reader admits rigid pushed blocks only")
    };
    let f = first as usize;
    let mut pin_step = vec![(f, push.horizontal), (f + 2, 0.0)];
    if let Some(v) = push.vertical {
        pin_step.push((f + 1, v));
    }
    let phase = Phase {
        base: d.external(g, true),
        step: vec![0.0; n],
        presc_step: zero_presc.clone(),
        pin_step,
        record: Some(push.block),
    };
    d.begin_phase("push", Some(steps), 1.0);
    // the failures of the earlier phases' cut increments are not the push's
    d.failure_mode = None;
    let (s, why, increments, accepted) = match d.settings.arc {
        Some(arc) => arc_length::run(d, &phase.base, push, &arc, steps)?,
        None => {
            let (s, why) = d.run_phase(&phase, steps)?;
            (
                s,
                why,
                [0, 0, d.push_curve.len().saturating_sub(1)],
                (0, 0.0),
            )
        }
    };
    let points = std::mem::take(&mut d.push_curve);
    let (dir, _) = push.direction();
    let furthest = points.iter().fold(0.0f64, |m, p| {
        let u = [
            p.displacement[0] - points[0].displacement[0],
            p.displacement[1] - points[0].displacement[1],
        ];
        m.max(u[0] * dir[0] + u[1] * dir[1])
    });
    let curve = crate::analysis::curve::Curve {
        control_block: push.block,
        top_block: d.top_block.unwrap_or(push.block),
        points,
        path: Some(crate::analysis::curve::PushPath {
            reached: s,
            furthest,
            increments,
            accepted: accepted.0,
            accepted_residual: accepted.1,
            end: why.clone().unwrap_or_else(|| "the end of the push".into()),
        }),
    };
    // past the peak of the force along the push, the structure is giving way whatever
    // stopped the path: a mechanism (docs/decisions/0037-stall-or-mechanism.md)
    let along = |p: &crate::analysis::curve::CurvePoint| {
        p.reaction.map_or(0.0, |r| r[0] * dir[0] + r[1] * dir[1])
    };
    let peak = curve.points.iter().map(along).fold(0.0f64, f64::max);
    let past_peak = curve
        .points
        .last()
        .is_some_and(|p| along(p) < (1.0 - PEAK_DROP) * peak);
    let what = |why: &str| format!("at {:.1} % of the push displacement: {why}", 100.0 * s);
    let mut out = match (why, d.path_stall.take()) {
        (Some(why), Some(residual)) if !past_peak => {
            let status = Status::NotConverged {
                reason: format!("did not converge {}", what(&why)),
                residual,
                block: None,
            };
            finish(d, mesh, start, status, None, None)
        }
        (Some(why), _) if past_peak => fail_mechanism(d, mesh, start, what(&why), None),
        (Some(why), _) => fail(d, mesh, start, what(&why), None),
        (None, _) => finish(d, mesh, start, Status::Stable, None, None),
    };
    out.capacity_curve = Some(curve);
    Ok(out)
}

/// The lateral body force of a static analysis (`lateral` × the weight, +x): the outcome.
fn lateral_phase(d: &mut Driver, mesh: &Mesh, start: Instant) -> Result<Outcome> {
    let scene = d.scene;
    let g = scene.model.gravity;
    let steps = scene.analysis.load_steps;
    let zero_presc = vec![[0.0; 2]; mesh.blocks.len()];
    let gnorm = g[0].hypot(g[1]);
    let f_base = d.external(g, true);
    let f_lat = d.external([gnorm, 0.0], false);
    if scene.analysis.lateral != 0.0 {
        let step: Vec<f64> = f_lat.iter().map(|x| x * scene.analysis.lateral).collect();
        let phase = Phase {
            base: f_base,
            step,
            presc_step: zero_presc.clone(),
            pin_step: Vec::new(),
            record: None,
        };
        d.begin_phase("lateral", Some(steps), scene.analysis.lateral);
        let (s, why) = d.run_phase(&phase, steps)?;
        if let Some(why) = why {
            return Ok(fail(
                d,
                mesh,
                start,
                format!(
                    "at a lateral coefficient of {:.4}: {why}",
                    s * scene.analysis.lateral
                ),
                Some(s * scene.analysis.lateral),
            ));
        }
    }
    Ok(finish(d, mesh, start, Status::Stable, None, None))
}

/// The capacity search: the horizontal body force λ × the weight raised until the
/// structure fails, the bracket on λ narrowed by probes (docs/decisions/
/// 0004-capacity-probe-windows.md, 0005-capacity-bracket-retry.md): the outcome, with λ
/// and the capacity curve.
fn capacity_search(d: &mut Driver, mesh: &Mesh, start: Instant) -> Result<Outcome> {
    let scene = d.scene;
    let g = scene.model.gravity;
    let zero_presc = vec![[0.0; 2]; mesh.blocks.len()];
    let gnorm = g[0].hypot(g[1]);
    let f_base = d.external(g, true);
    let f_lat = d.external([gnorm, 0.0], false);
    let dir = scene.analysis.direction;
    let mut lambda: f64 = 0.0;
    let mut step = d.settings.initial_step;
    let mut last_fail: Option<String> = None;
    let mut upper = f64::INFINITY;
    let limit = 1e3;
    // the last converged increment (its step in λ and its unknowns' increment),
    // extrapolated to start the next one (as in `run_phase`)
    let mut last: Option<(f64, Vec<f64>)> = None;
    d.begin_phase("capacity", None, 1.0);
    let control = crate::analysis::curve::control_block(mesh);
    let curve_point = |d: &Driver, lambda: f64, block: usize| {
        let displacement =
            crate::analysis::curve::control_displacement(mesh, &d.cur, &d.committed.u, block);
        crate::analysis::curve::CurvePoint {
            load_factor: lambda,
            displacement,
            reaction: None,
            top: displacement,
        }
    };
    let mut curve: Vec<crate::analysis::curve::CurvePoint> = control
        .map(|b| curve_point(d, 0.0, b))
        .into_iter()
        .collect();
    // Raise λ in increments; an increment that fails sets the upper bound and is
    // cut. A failure from a distant state is not proof of collapse (the path of
    // slips matters), so the upper bound is retried from the closer states and
    // dropped when reached. Stops when the bracket [λ, upper] is narrow enough and
    // its upper bound failed with the full stall windows: the increments are probes
    // that give up sooner ([`Driver::stall_window`]), and where the bracket is
    // narrow but its bound failed as a probe, that bound is iterated again with the
    // full windows from λ (where it then converges, the search goes on above it).
    // `upper_full`: the failure that set `upper` had the full windows.
    let mut upper_full = false;
    // a failed probe showed a mechanism ([`Failure::mechanism`]): without one the search
    // ends as not converged, whatever its bracket
    let mut mechanism = false;
    loop {
        let narrow = upper.is_finite()
            && upper - lambda <= d.settings.bracket * lambda.max(d.settings.initial_step * 1e-3);
        if (narrow && upper_full) || step <= 1e-12 * d.settings.initial_step || lambda > limit {
            break;
        }
        // a step that ends within round-off of the upper bound retries that bound
        // itself: converging a hair below it would leave it standing as a bound
        // that only a failure from a distant state set (a zero-width bracket)
        let target = if narrow || lambda + step >= upper * (1.0 - 1e-12) {
            upper
        } else {
            lambda + step
        };
        d.probing = !narrow;
        let f: Vec<f64> = f_base
            .iter()
            .zip(&f_lat)
            .map(|(b, l)| b + dir * target * l)
            .collect();
        let guess = last
            .as_ref()
            .map(|(step, dq)| dq.iter().map(|x| x * (target - lambda) / step).collect());
        if crate::analysis::tracing() {
            eprintln!("capacity increment {lambda:.6} -> {target:.6} (upper {upper:.6})");
        }
        match d.increment(&f, &zero_presc, guess)? {
            Ok(trial) => {
                let dq = trial.dq.clone();
                d.commit(trial, &dq, &zero_presc);
                last = Some((target - lambda, dq));
                lambda = target;
                d.converged(lambda);
                if let Some(b) = control {
                    curve.push(curve_point(d, lambda, b));
                }
                if lambda >= upper {
                    // the earlier failure was the path, not the structure
                    upper = f64::INFINITY;
                }
                if upper.is_infinite() {
                    step *= 1.5;
                }
            }
            Err((why, dq)) => {
                let dq = d.failure_mode.insert(dq);
                if target < upper {
                    upper_full = !d.probing;
                } else {
                    upper_full |= !d.probing;
                }
                upper = upper.min(target);
                mechanism |= dq.mechanism;
                last_fail = Some(describe(&why, !dq.mechanism));
                step = 0.5 * (target - lambda);
            }
        }
    }
    let curve = control.map(|control_block| crate::analysis::curve::Curve {
        control_block,
        top_block: control_block,
        points: curve,
        path: None,
    });
    if lambda > limit {
        let mut out = finish(d, mesh, start, Status::Stable, Some(lambda), None);
        out.capacity_curve = curve;
        return Ok(out);
    }
    let why = last_fail.unwrap_or_default();
    let mut out = if mechanism {
        fail_mechanism(
            d,
            mesh,
            start,
            format!("at the critical load factor {lambda:.6} (bracket [{lambda:.6}, {upper:.6}]): {why}"),
            Some(lambda),
        )
    } else {
        let f = d.failure_mode.as_ref();
        let status = Status::NotConverged {
            reason: format!(
                "did not converge above the load factor {lambda:.6} (bracket [{lambda:.6}, {upper:.6}]): {why}"
            ),
            residual: f.map_or(0.0, |f| f.residual),
            block: f.and_then(|f| f.worst),
        };
        finish(d, mesh, start, status, Some(lambda), None)
    };
    out.load_factor = Some(lambda);
    out.capacity_curve = curve;
    Ok(out)
}
