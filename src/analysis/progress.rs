//! Progress of an analysis as it runs: the driver tells a [`Progress`] when a phase starts,
//! after each iteration and after each converged increment. The library's default is
//! [`Silent`]; the command line draws a progress bar or prints JSON lines from these calls.
//! Reporting never changes the computation.

/// One converged increment.
#[derive(Debug, Clone, PartialEq)]
pub struct Increment<'a> {
    /// "gravity", "prescribed", "lateral" or "capacity".
    pub phase: &'a str,
    /// 1-based number of the increment within its phase.
    pub increment: usize,
    /// The phase's load factor reached: the fraction of the self-weight (gravity), of the
    /// prescribed displacement (prescribed), the lateral coefficient (lateral) or λ
    /// (capacity).
    pub load_factor: f64,
    /// Iterations of this increment.
    pub iterations: usize,
    /// Relative out-of-balance force ‖λF − F_int‖ / ‖λF‖ at convergence.
    pub residual: f64,
}

/// Receives the driver's reports. Every method has an empty default.
pub trait Progress {
    /// A phase starts; `increments` is its planned number of increments when known
    /// (cuts may add more), `None` for the open-ended capacity search.
    fn phase(&mut self, _name: &str, _increments: Option<usize>) {}
    /// An iteration of the current increment: its 0-based number and relative residual.
    fn iteration(&mut self, _iteration: usize, _residual: f64) {}
    /// An increment converged and was committed.
    fn increment(&mut self, _report: &Increment) {}
}

/// Reports nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}

/// Records every report (for tests and callers that want the history).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recorder {
    /// (phase, planned increments) in order.
    pub phases: Vec<(String, Option<usize>)>,
    /// (phase, increment, load factor, iterations, residual) in order.
    pub increments: Vec<(String, usize, f64, usize, f64)>,
    /// Iterations reported.
    pub iterations: usize,
}

impl Progress for Recorder {
    fn phase(&mut self, name: &str, increments: Option<usize>) {
        self.phases.push((name.to_string(), increments));
    }
    fn iteration(&mut self, _iteration: usize, _residual: f64) {
        self.iterations += 1;
    }
    fn increment(&mut self, r: &Increment) {
        self.increments.push((
            r.phase.to_string(),
            r.increment,
            r.load_factor,
            r.iterations,
            r.residual,
        ));
    }
}
