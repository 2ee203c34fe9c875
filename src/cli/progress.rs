//! What `dfem run` shows while it works: a progress bar on stderr (only when stderr is a
//! terminal, not with `--quiet`, and only once the run has lasted about a second), and with
//! `--log-json` one JSON line per converged increment on stderr, for pipelines.

use crate::analysis::progress::{Increment, Progress};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// The bar appears only for runs longer than this.
const DELAY: Duration = Duration::from_secs(1);

/// The command line's [`Progress`].
pub struct CliProgress {
    start: Instant,
    /// Draw a bar (stderr is a terminal, no --quiet, no --log-json).
    want_bar: bool,
    bar: Option<ProgressBar>,
    json: bool,
    phase: String,
    planned: Option<usize>,
    increment: usize,
    load_factor: Option<f64>,
}

impl CliProgress {
    pub fn new(quiet: bool, json: bool) -> CliProgress {
        CliProgress {
            start: Instant::now(),
            want_bar: !quiet && !json && std::io::stderr().is_terminal(),
            bar: None,
            json,
            phase: String::new(),
            planned: None,
            increment: 0,
            load_factor: None,
        }
    }

    /// A stage outside the analysis ("meshing", "writing results", "drawing figures").
    pub fn stage(&mut self, name: &str) {
        self.phase = name.to_string();
        self.planned = None;
        self.increment = 0;
        self.refresh(None);
    }

    /// Remove the bar (before the final line is printed).
    pub fn finish(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }

    fn style(&self) -> ProgressStyle {
        let template = if self.planned.is_some() {
            "{spinner} {prefix:<10} [{bar:28}] {pos}/{len} {msg}  {elapsed_precise} (ETA {eta})"
        } else {
            "{spinner} {prefix:<10} {msg}  {elapsed_precise}"
        };
        ProgressStyle::with_template(template)
            .unwrap_or_else(|_| ProgressStyle::default_spinner())
            .progress_chars("=> ")
    }

    /// Show the bar once the run has lasted long enough, and update it.
    fn refresh(&mut self, detail: Option<String>) {
        if !self.want_bar {
            return;
        }
        if self.bar.is_none() {
            if self.start.elapsed() < DELAY {
                return;
            }
            let b = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            b.enable_steady_tick(Duration::from_millis(200));
            self.bar = Some(b);
        }
        let style = self.style();
        let bar = self.bar.as_ref().expect("created above");
        bar.set_style(style);
        bar.set_prefix(self.phase.clone());
        match self.planned {
            Some(n) => {
                bar.set_length(n.max(self.increment) as u64);
                bar.set_position(self.increment as u64);
            }
            None => bar.unset_length(),
        }
        let mut msg = String::new();
        if self.planned.is_none() && self.increment > 0 {
            msg.push_str(&format!("increment {}", self.increment));
        }
        if let Some(l) = self.load_factor.filter(|_| self.phase == "capacity") {
            msg.push_str(&format!("  λ = {l:.4}"));
        }
        if let Some(d) = detail {
            msg.push_str("  ");
            msg.push_str(&d);
        }
        bar.set_message(msg.trim().to_string());
    }
}

impl Progress for CliProgress {
    fn phase(&mut self, name: &str, increments: Option<usize>) {
        self.phase = name.to_string();
        self.planned = increments;
        self.increment = 0;
        self.load_factor = None;
        self.refresh(None);
    }

    fn iteration(&mut self, iteration: usize, residual: f64) {
        if self.want_bar {
            self.refresh(Some(format!(
                "iteration {} residual {residual:.1e}",
                iteration + 1
            )));
        }
    }

    fn increment(&mut self, r: &Increment) {
        self.increment = r.increment;
        self.load_factor = Some(r.load_factor);
        if self.json {
            let line = serde_json::json!({
                "phase": r.phase,
                "increment": r.increment,
                "load_factor": r.load_factor,
                "iterations": r.iterations,
                "residual": r.residual,
                "elapsed_s": self.start.elapsed().as_secs_f64(),
            });
            eprintln!("{line}");
        }
        self.refresh(Some(format!(
            "{} iterations, residual {:.1e}",
            r.iterations, r.residual
        )));
    }
}

impl Drop for CliProgress {
    fn drop(&mut self) {
        self.finish();
    }
}
