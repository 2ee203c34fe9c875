//! The stream of a dynamic run to disk ([`StreamWriter`]): history rows, ParaView frames,
//! checkpoints, written in the order the run produces them, on the caller's thread or on
//! a writer thread of its own (docs/decisions/0042-output-writer-thread.md).

use super::{
    create_dir, history_line, summary, vtk, write_atomic, write_summary, CHECKPOINT_SECONDS,
    STOP_AFTER_STEP,
};
use crate::analysis::checkpoint::{self, Checkpoint};
use crate::analysis::dynamics::Monitor;
use crate::analysis::Outcome;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::{Error, Result};
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Arc;
use std::thread::{Scope, ScopedJoinHandle};
use std::time::{Duration, Instant};

/// History rows handed to the writer together (one message per this many time steps;
/// docs/decisions/0042-output-writer-thread.md).
const ROWS_PER_JOB: usize = 256;

/// Jobs the writer thread may hold before the run waits for it: a bound on the memory of
/// a writer that falls behind (docs/decisions/0042-output-writer-thread.md).
const QUEUED_JOBS: usize = 8;

/// Streams a dynamic run to `dir` as it goes: history.csv grows by one line per time step,
/// buffered and flushed in whole lines (so a run killed at any moment leaves whole rows,
/// all of them up to the last checkpoint; [`write_streamed`](super::write_streamed) keeps
/// it at the end); a ParaView frame at each step of the run's
/// [`FrameSchedule`](crate::analysis::dynamics::FrameSchedule) (each .vtu atomically),
/// the .pvd that lists them rewritten atomically whenever their number has doubled since
/// it was last written and at each checkpoint, so that its cost is linear in the frames
/// (docs/decisions/0038-frames-by-simulated-time.md); a checkpoint ([`checkpoint::FILE`])
/// and a summary with status "running" at the start and then every `[output]
/// checkpoint_every` steps (default every [`CHECKPOINT_SECONDS`] s).
///
/// [`StreamWriter::on_thread`] moves the writing to a thread of its own, which writes the
/// same files in the same order (a checkpoint only after the rows and frames before it):
/// the run hands it rows and frames and goes on. [`StreamWriter::finish`] waits for it; an
/// error of the thread is returned by the next call that hands it work, or by `finish`.
pub struct StreamWriter<'a> {
    scene: &'a Scene,
    mesh: &'a Mesh,
    /// The writing, while it is done on the caller's thread.
    files: Option<Files<'a>>,
    /// The writer thread, after [`StreamWriter::on_thread`].
    thread: Option<Writer<'a>>,
    /// Rows not yet handed to the writing, `width` values each.
    rows: Vec<f64>,
    width: usize,
    /// Where the scene came from and its fingerprint, stored with each checkpoint.
    source: String,
    fingerprint: u64,
    last_checkpoint: Instant,
    /// Set on Ctrl-C: stop after the step under way.
    stop: Arc<AtomicBool>,
    /// [`STOP_AFTER_STEP`].
    stop_after: Option<usize>,
    /// Resuming: the run before its checkpoint.
    resumed: Option<Before>,
}

/// The history rows and the frames (time s, step) of a run before its checkpoint.
struct Before {
    rows: Vec<Vec<f64>>,
    frames: Vec<(f64, usize)>,
}

/// The writer thread: where its jobs go and its end.
struct Writer<'a> {
    jobs: SyncSender<Job>,
    handle: ScopedJoinHandle<'a, Result<()>>,
}

/// What the writing does, in the order of the run.
enum Job {
    /// Create history.csv with this header line (or append to it when resuming).
    Start(String),
    /// History rows, flattened.
    Rows(Vec<f64>),
    Frame {
        step: usize,
        time: f64,
        state: Box<Outcome>,
    },
    /// The rows and frames so far on disk, then checkpoint.bin and summary.json.
    Checkpoint { bytes: Vec<u8>, summary: Value },
}

/// The files of the stream and what they hold so far.
struct Files<'a> {
    dir: PathBuf,
    scene: &'a Scene,
    mesh: &'a Mesh,
    file: Option<std::io::BufWriter<std::fs::File>>,
    /// Values of a history row.
    width: usize,
    /// Appending to the history.csv of a resumed run.
    append: bool,
    frames: Vec<(f64, usize)>,
    /// The number of frames results.pvd lists.
    listed: usize,
}

fn history_error(dir: &Path, e: std::io::Error) -> Error {
    Error::new(format!("cannot write the history: {e}"))
        .file(dir.join("history.csv"))
        .fix("check that the output directory is writable and the disk is not full")
}

impl Files<'_> {
    fn io(&self, e: std::io::Error) -> Error {
        history_error(&self.dir, e)
    }

    fn run(&mut self, job: Job) -> Result<()> {
        match job {
            Job::Start(header) => {
                let path = self.dir.join("history.csv");
                let f = if self.append {
                    std::fs::OpenOptions::new().append(true).open(&path)
                } else {
                    std::fs::File::create(&path)
                }
                .map_err(|e| self.io(e))?;
                let mut f = std::io::BufWriter::new(f);
                if !self.append {
                    writeln!(f, "{header}").map_err(|e| self.io(e))?;
                }
                self.width = header.split(',').count();
                self.file = Some(f);
            }
            Job::Rows(values) => {
                if let Some(f) = self.file.as_mut() {
                    for r in values.chunks(self.width.max(1)) {
                        // whole lines into the buffer, which writes only whole lines: a
                        // killed run leaves whole rows
                        if let Err(e) = f.write_all(history_line(r).as_bytes()) {
                            return Err(history_error(&self.dir, e));
                        }
                    }
                }
            }
            Job::Frame { step, time, state } => {
                vtk::write_step(&self.dir, step, time, self.scene, self.mesh, &state)?;
                self.frames.push((time, step));
                if self.frames.len() >= 2 * self.listed {
                    self.list_frames()?;
                }
            }
            Job::Checkpoint { bytes, summary } => {
                // the rows and frames up to the checkpoint's step on disk before it
                self.flush()?;
                self.list_frames()?;
                write_atomic(&self.dir.join(checkpoint::FILE), &bytes)?;
                write_summary(&self.dir, &summary)?;
            }
        }
        Ok(())
    }

    /// Write results.pvd with every frame written so far, unless it lists them already.
    fn list_frames(&mut self) -> Result<()> {
        if self.listed < self.frames.len() {
            vtk::write_pvd(&self.dir, &self.frames)?;
            self.listed = self.frames.len();
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<()> {
        match self.file.as_mut().map(|f| f.flush()) {
            Some(Err(e)) => Err(self.io(e)),
            _ => Ok(()),
        }
    }
}

/// Where a scene came from, as a checkpoint records it: the absolute path of its file, or
/// `example:NAME`.
fn scene_source(scene: &Scene) -> String {
    match &scene.file {
        Some(f) => std::fs::canonicalize(f)
            .unwrap_or_else(|_| f.clone())
            .to_string_lossy()
            .into_owned(),
        None => String::new(),
    }
}

/// The checkpoint in `dir`; a clear error when there is none.
pub fn read_checkpoint(dir: &Path) -> Result<checkpoint::Saved> {
    let path = dir.join(checkpoint::FILE);
    let bytes = std::fs::read(&path).map_err(|e| {
        Error::new(format!("no checkpoint to resume from ({e})"))
            .file(&path)
            .fix("--resume continues a dynamic run that was interrupted (Ctrl-C) or killed in DIR; a run that completed or failed leaves none: run the scene again without --resume")
    })?;
    checkpoint::decode(&bytes, &path)
}

impl<'a> StreamWriter<'a> {
    pub fn new(dir: &Path, scene: &'a Scene, mesh: &'a Mesh) -> Result<Self> {
        create_dir(dir)?;
        let stop_after = std::env::var(STOP_AFTER_STEP)
            .ok()
            .and_then(|s| s.trim().parse().ok());
        Ok(StreamWriter {
            scene,
            mesh,
            files: Some(Files {
                dir: dir.to_path_buf(),
                scene,
                mesh,
                file: None,
                width: 0,
                append: false,
                frames: Vec::new(),
                listed: 0,
            }),
            thread: None,
            rows: Vec::new(),
            width: 0,
            source: scene_source(scene),
            fingerprint: checkpoint::fingerprint(scene),
            last_checkpoint: Instant::now(),
            stop: Arc::new(AtomicBool::new(false)),
            stop_after,
            resumed: None,
        })
    }

    /// Stop after the step under way when `flag` is set (by a Ctrl-C handler).
    pub fn stop_on(mut self, flag: Arc<AtomicBool>) -> Self {
        self.stop = flag;
        self
    }

    /// Write on a thread of `scope` from now on (the same files as on the caller's
    /// thread); [`StreamWriter::finish`] waits for it.
    pub fn on_thread<'env>(mut self, scope: &'a Scope<'a, 'env>) -> Result<Self> {
        if let Some(mut files) = self.files.take() {
            let (jobs, queue) = sync_channel::<Job>(QUEUED_JOBS);
            let spawned = std::thread::Builder::new()
                .name("dfem-output".into())
                .spawn_scoped(scope, move || {
                    for job in queue {
                        files.run(job)?;
                    }
                    files.flush()
                });
            let handle = spawned.map_err(|e| {
                Error::new(format!("cannot start the output writer thread: {e}"))
                    .fix("free memory or processes and run again")
            })?;
            self.thread = Some(Writer { jobs, handle });
        }
        Ok(self)
    }

    /// A writer that continues the results in `dir` from checkpoint `c` of this scene:
    /// history.csv is cut after the checkpoint's row (the rows a killed run wrote after
    /// it are computed again) and the frames up to it are kept.
    pub fn resuming(dir: &Path, scene: &'a Scene, mesh: &'a Mesh, c: &Checkpoint) -> Result<Self> {
        let mut w = Self::new(dir, scene, mesh)?;
        let path = dir.join("history.csv");
        let text = std::fs::read_to_string(&path).map_err(|e| history_error(dir, e))?;
        let mut lines = text.lines();
        let header = lines.next().unwrap_or_default().to_string();
        let rows: Vec<Vec<f64>> = lines
            .take(c.step + 1)
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        let width = header.split(',').count();
        if rows.len() != c.step + 1 || rows.iter().any(|r| r.len() != width) {
            return Err(Error::new(format!(
                "history.csv holds {} whole rows, fewer than the {} of the checkpoint",
                rows.iter().filter(|r| r.len() == width).count(),
                c.step + 1
            ))
            .file(&path)
            .fix("the results in DIR do not belong to its checkpoint: run the scene again without --resume"));
        }
        let mut kept = header;
        kept.push('\n');
        for r in &rows {
            kept.push_str(&history_line(r));
        }
        write_atomic(&path, kept.as_bytes())?;
        let settings = scene.analysis.settings.dynamics()?.clone();
        let schedule =
            crate::analysis::dynamics::FrameSchedule::new(&settings, scene.output.frames);
        if !schedule.due(c.step) {
            // the final state an interrupted run wrote between two frames
            for part in ["blocks", "contacts"] {
                let _ = std::fs::remove_file(dir.join(format!("{part}_{:04}.vtu", c.step)));
            }
        }
        let frames: Vec<(f64, usize)> = (0..=c.step)
            .filter(|&k| schedule.due(k) && dir.join(format!("blocks_{k:04}.vtu")).exists())
            .map(|k| (crate::analysis::dynamics::step_time(&settings, k), k))
            .collect();
        if let Some(f) = w.files.as_mut() {
            f.frames = frames.clone();
            f.append = true;
        }
        w.resumed = Some(Before { rows, frames });
        Ok(w)
    }

    /// Put the history rows and frames of the run before the checkpoint in front of the
    /// outcome's (which holds those after it).
    pub fn complete(&self, out: &mut Outcome) {
        if let (Some(b), Some(h)) = (&self.resumed, out.history.as_mut()) {
            h.rows.splice(0..0, b.rows.iter().cloned());
            h.frames.splice(0..0, b.frames.iter().copied());
        }
    }

    /// Hand `job` to the writing: done at once on the caller's thread, queued on the
    /// writer thread (whose error, if it stopped on one, is returned here).
    fn send(&mut self, job: Job) -> Result<()> {
        if let Some(f) = self.files.as_mut() {
            return f.run(job);
        }
        let Some(w) = self.thread.as_ref() else {
            return Ok(());
        };
        if w.jobs.send(job).is_ok() {
            return Ok(());
        }
        // the thread stopped: on an error, which its end holds
        self.join()
            .and(Err(Error::new("the output writer thread stopped")))
    }

    /// The rows not yet handed to the writing, handed.
    fn send_rows(&mut self) -> Result<()> {
        if self.rows.is_empty() {
            return Ok(());
        }
        let rows = std::mem::take(&mut self.rows);
        self.send(Job::Rows(rows))
    }

    /// Wait for the writer thread to write what it holds and end; its error, if any.
    fn join(&mut self) -> Result<()> {
        match self.thread.take() {
            None => Ok(()),
            Some(Writer { jobs, handle }) => {
                drop(jobs);
                handle.join().unwrap_or_else(|_| {
                    Err(Error::new("the output writer thread panicked")
                        .fix("please report this as a bug, with the scene"))
                })
            }
        }
    }

    /// Flush history.csv (and wait for the writer thread): after a run that ended
    /// (completed, failed or interrupted) it then holds every row of the outcome's
    /// history, which [`write_streamed`](super::write_streamed) keeps.
    pub fn finish(&mut self) -> Result<()> {
        self.send_rows()?;
        if let Some(f) = self.files.as_mut() {
            return f.flush();
        }
        self.join()
    }
}

impl Monitor for StreamWriter<'_> {
    fn start(&mut self, columns: &[String]) -> Result<()> {
        self.width = columns.len();
        self.send(Job::Start(columns.join(",")))
    }
    fn row(&mut self, row: &[f64]) -> Result<()> {
        self.rows.extend_from_slice(row);
        if self.rows.len() >= ROWS_PER_JOB * self.width.max(1) {
            self.send_rows()?;
        }
        Ok(())
    }
    fn stop_requested(&mut self, step: usize) -> bool {
        self.stop.load(Ordering::SeqCst) || self.stop_after == Some(step)
    }
    fn checkpoint_due(&mut self, step: usize) -> bool {
        step == 0
            || match self.scene.output.checkpoint_every {
                Some(n) => step.is_multiple_of(n),
                None => self.last_checkpoint.elapsed() >= Duration::from_secs(CHECKPOINT_SECONDS),
            }
    }
    fn checkpoint(&mut self, c: &Checkpoint, state: &Outcome) -> Result<()> {
        self.send_rows()?;
        let bytes = checkpoint::encode(&self.source, self.fingerprint, c);
        let mut s = summary(self.scene, self.mesh, state);
        s["status"] = json!("running");
        s["time"] = json!(c.time);
        s["message"] = json!(format!(
            "running, or killed: the results reach t = {} s at the last checkpoint; a run that no longer runs continues with `dfem run --resume DIR`",
            c.time
        ));
        self.send(Job::Checkpoint { bytes, summary: s })?;
        self.last_checkpoint = Instant::now();
        Ok(())
    }
    fn wants_frames(&self) -> bool {
        self.scene.output.vtk
    }
    fn frame(&mut self, step: usize, time: f64, state: Outcome) -> Result<()> {
        self.send(Job::Frame {
            step,
            time,
            state: Box::new(state),
        })
    }
}
