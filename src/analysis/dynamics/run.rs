//! A dynamic run: the drivers' entry points, from the start or from a checkpoint, the
//! steps of the record, the history rows, frames and checkpoints handed to the monitor.

use super::*;
use crate::scene::Frames;

/// Blocks written to the history: `[output] track`, or every free block.
pub fn tracked(scene: &Scene, mesh: &Mesh) -> Vec<usize> {
    if scene.output.track.is_empty() {
        (0..mesh.blocks.len())
            .filter(|&b| mesh.blocks[b].dofs != BlockDofs::Fixed)
            .collect()
    } else {
        scene
            .output
            .track
            .iter()
            .filter_map(|n| scene.block_index(n))
            .collect()
    }
}

/// The time (s) at the end of step `k` of a run with time step `dt` lasting `duration`.
pub fn step_time(settings: &Settings, k: usize) -> f64 {
    (k as f64 * settings.dt).min(settings.duration.max(settings.dt))
}

/// The number of time steps of a run.
pub fn step_count(settings: &Settings) -> usize {
    (settings.duration / settings.dt - 1e-9).ceil().max(1.0) as usize
}

/// Default interval (s of simulated time) between ParaView frames
/// (docs/decisions/0038-frames-by-simulated-time.md).
pub const FRAME_INTERVAL: f64 = 0.02;

/// Most frames after t = 0 that the default interval gives: a longer run widens it to
/// duration / MAX_FRAMES (docs/decisions/0038-frames-by-simulated-time.md).
pub const MAX_FRAMES: usize = 500;

/// The steps of a run at which a ParaView frame is written (docs/scene-reference.md,
/// "`[output]`"): step 0, the last step, and in between every k-th step (`every = k`) or
/// the first step ending at or after each frame time j·I (j = 1, 2, …; to within
/// 10⁻⁶ I, so that j·I computed in floating point is not missed by a rounding).
#[derive(Debug, Clone, Copy)]
pub struct FrameSchedule {
    /// `every = k`: k; otherwise `None` and `interval` rules.
    every: Option<usize>,
    /// I (s).
    interval: f64,
    steps: usize,
    dt: f64,
    duration: f64,
}

impl FrameSchedule {
    /// The schedule of `frames` for a run with `settings`: I = `frame_interval`,
    /// duration / N (`--frames N`), or by default max([`FRAME_INTERVAL`], duration /
    /// [`MAX_FRAMES`]).
    pub fn new(settings: &Settings, frames: Frames) -> Self {
        let duration = settings.duration.max(settings.dt);
        let (every, interval) = match frames {
            Frames::Steps(k) => (Some(k.max(1)), 0.0),
            Frames::Interval(i) => (None, i),
            Frames::Count(n) => (None, duration / n.max(1) as f64),
            Frames::Default => (None, FRAME_INTERVAL.max(duration / MAX_FRAMES as f64)),
        };
        FrameSchedule {
            every,
            interval,
            steps: step_count(settings),
            dt: settings.dt,
            duration,
        }
    }

    /// The index j of the last frame time j·I reached at time `t`.
    fn index(&self, t: f64) -> f64 {
        (t / self.interval + 1e-6).floor()
    }

    /// Whether step `k` ends with a frame.
    pub fn due(&self, k: usize) -> bool {
        if k == 0 || k >= self.steps {
            return true;
        }
        let t = |k: usize| (k as f64 * self.dt).min(self.duration);
        match self.every {
            Some(e) => k.is_multiple_of(e),
            None => self.index(t(k)) > self.index(t(k - 1)),
        }
    }
}

/// Run a dynamic analysis, streaming the history and frames to `monitor`.
pub fn run(
    scene: &Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &mut dyn LinearBackend,
    monitor: &mut dyn Monitor,
) -> Result<Outcome> {
    run_from(scene, mesh, ranks, backend, monitor, None)
}

/// [`run()`], or its continuation from a checkpoint `from` of the same scene: the rows and
/// frames up to the checkpoint's step are neither computed nor sent to `monitor` again,
/// and the outcome's history holds only the rows after it.
pub fn run_from(
    scene: &Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &mut dyn LinearBackend,
    monitor: &mut dyn Monitor,
    from: Option<Checkpoint>,
) -> Result<Outcome> {
    let start = Instant::now();
    let mut d = Dynamics::new(scene, mesh, ranks, backend)?;
    // counters of the part of the run before the checkpoint
    let mut before = Stats::default();
    let resumed = from.is_some();
    let first = match from {
        Some(c) => {
            before = c.stats.clone();
            d.restore(c)
        }
        None => {
            d.start()?;
            d.update_contacts();
            0
        }
    };
    let counted = |d: &Dynamics| -> Stats {
        let bs = d.lin.backend.stats();
        let mut s = d.stats.clone();
        s.factorizations = before.factorizations + bs.numeric_factorizations;
        s.symbolic_factorizations = before.symbolic_factorizations + bs.symbolic_factorizations;
        s.min_pivot_ratio = if resumed {
            bs.min_pivot_ratio.min(before.min_pivot_ratio)
        } else {
            bs.min_pivot_ratio
        };
        s.wall_time_s = before.wall_time_s + start.elapsed().as_secs_f64();
        s
    };
    // after step k: a checkpoint when due or asked to stop; whether to stop
    let save = |d: &Dynamics, monitor: &mut dyn Monitor, k: usize| -> Result<bool> {
        let stop = monitor.stop_requested(k);
        if stop || monitor.checkpoint_due(k) {
            let mut c = d.checkpoint(k);
            c.stats = counted(d);
            let mut state = d.outcome(Status::Stable);
            state.stats = c.stats.clone();
            monitor.checkpoint(&c, &state)?;
        }
        Ok(stop)
    };
    let blocks = tracked(scene, mesh);
    let mut columns = vec!["t".to_string()];
    for &b in &blocks {
        let name = &scene.blocks[b].name;
        for c in ["ux", "uy", "rz"] {
            columns.push(format!("{name}.{c}"));
        }
    }
    columns.extend(EXTRA_COLUMNS.iter().map(|s| s.to_string()));
    if d.settings.absolute {
        columns.extend(ABSOLUTE_COLUMNS.iter().map(|s| s.to_string()));
    }
    monitor.start(&columns)?;
    let mut history = History {
        columns,
        ..Default::default()
    };
    let row = |d: &Dynamics| -> Vec<f64> {
        let mut r = vec![d.time];
        for &b in &blocks {
            let (u, th) = d.block_motion(b);
            r.extend([u[0], u[1], th]);
        }
        let g = d.ground(d.time);
        let count = |s: ContactState| d.committed.state.iter().filter(|x| **x == s).count() as f64;
        let e = d.energy;
        r.extend([
            g[0],
            g[1],
            count(ContactState::Open),
            count(ContactState::Slip),
            e.kinetic,
            e.elastic,
            e.viscous,
            e.contact,
            e.work_static,
            e.work_ground,
            e.error(),
        ]);
        if d.settings.absolute {
            r.extend(d.ground_u);
        }
        r
    };
    let steps = step_count(&d.settings);
    let schedule = FrameSchedule::new(&d.settings, scene.output.frames);
    let frames = scene.output.vtk;
    let mut status = Status::Stable;
    if !resumed {
        let r0 = row(&d);
        monitor.row(&r0)?;
        history.rows.push(r0);
        if frames {
            history.frames.push((0.0, 0));
            if monitor.wants_frames() {
                monitor.frame(0, 0.0, d.outcome(Status::Stable))?;
            }
        }
        if save(&d, monitor, 0)? {
            status = Status::Interrupted { time: d.time };
        }
    }
    for k in first + 1..=steps {
        if status != Status::Stable {
            break;
        }
        let target = step_time(&d.settings, k);
        let ok = d.advance_to(target)?;
        if !ok {
            status = Status::Failed {
                reason: if d.settings.inertia {
                    format!(
                        "the time step from t = {:.4} s did not converge even when cut to dt/2^{}: the contacts cannot be resolved (try a smaller dt)",
                        d.time, d.settings.max_cuts
                    )
                } else {
                    // without inertia a step has no solution once the loads exceed what
                    // the contacts can hold: the seed's end of a computation (its §4)
                    format!(
                        "at t = {:.4} s the structure became a mechanism: without inertia (pseudo-dynamic, inertia = false) no state after it balances the loads",
                        d.time
                    )
                },
                blocks: vec![],
            };
            break;
        }
        let r = row(&d);
        monitor.row(&r)?;
        history.rows.push(r);
        if frames && schedule.due(k) {
            history.frames.push((d.time, k));
            if monitor.wants_frames() {
                monitor.frame(k, d.time, d.outcome(Status::Stable))?;
            }
        }
        if k < steps && save(&d, monitor, k)? {
            status = Status::Interrupted { time: d.time };
        }
    }
    d.stats = counted(&d);
    let mut out = d.outcome(status);
    out.history = Some(history);
    Ok(out)
}
