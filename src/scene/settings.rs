//! The `[analysis]` settings of each analysis type, typed and validated once when the
//! scene is read (docs/scene-reference.md, "`[analysis]`"): the drivers take them as they
//! are, and `dfem check` reports a bad key or value before any run.

use crate::geometry::polygon::Point;
use crate::Result;

/// The settings of the analysis type, next to [`super::Analysis::kind`].
#[derive(Debug, Clone, PartialEq)]
pub enum AnalysisSettings {
    /// `type = "static"` or `"capacity"`: the static driver's settings.
    Static(StaticSettings),
    /// `type = "dynamic"`: the time integration's settings.
    Dynamic(DynamicSettings),
}

impl AnalysisSettings {
    /// The static driver's settings; an error for a dynamic analysis.
    pub fn statics(&self) -> Result<&StaticSettings> {
        match self {
            AnalysisSettings::Static(s) => Ok(s),
            AnalysisSettings::Dynamic(_) => Err(crate::Error::new(
                "the static driver was given a dynamic analysis",
            )
            .fix("run a scene with [analysis] type = \"static\" or \"capacity\"")),
        }
    }

    /// The static driver's settings, to change them in a scene built in code.
    pub fn statics_mut(&mut self) -> Option<&mut StaticSettings> {
        match self {
            AnalysisSettings::Static(s) => Some(s),
            AnalysisSettings::Dynamic(_) => None,
        }
    }

    /// The time integration's settings; an error for a static or capacity analysis.
    pub fn dynamics(&self) -> Result<&DynamicSettings> {
        match self {
            AnalysisSettings::Dynamic(s) => Ok(s),
            AnalysisSettings::Static(_) => Err(crate::Error::new(
                "the dynamic driver was given a static analysis",
            )
            .fix("run a scene with [analysis] type = \"dynamic\"")),
        }
    }
}

/// The iteration strategy (`[analysis] strategy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// The elastic stiffness, factorized once: cheap solves, more iterations.
    Initial,
    /// The secant stiffness (open contacts carry nothing, slipping ones no shear),
    /// numerically refactorized each iteration with the symbolic phase reused.
    Secant,
    /// Newton with the tangent (the friction term makes it nonsymmetric: LU).
    Newton,
}

impl Strategy {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "initial" => Some(Strategy::Initial),
            "secant" => Some(Strategy::Secant),
            "newton" => Some(Strategy::Newton),
            _ => None,
        }
    }
}

/// Settings of the static driver (static and capacity analyses; `[analysis]` keys, with
/// the defaults of [`StaticSettings::default`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StaticSettings {
    pub strategy: Strategy,
    /// Relative out-of-balance tolerance ‖λF − F_int‖ / ‖λF‖.
    pub tolerance: f64,
    /// Iterations per increment before it is cut.
    pub max_iterations: usize,
    /// Halvings of an increment before the structure is declared failed.
    pub max_cuts: usize,
    /// Capacity: first step of the load factor, and the relative width of the final bracket.
    pub initial_step: f64,
    pub bracket: f64,
    pub line_search: bool,
    /// Take the blocks of a local failure out of the analysis and go on without them
    /// (`fallout`, default off).
    pub fallout: bool,
    /// Keep the held secant factorization across load increments (`reuse_across_increments`,
    /// default off): the first corrections of an increment are then solved by conjugate
    /// gradients preconditioned with it, corrected for the contacts that changed state
    /// (docs/theory.md, "Factorizations across increments"). Fewer factorizations, but
    /// no faster on the measured walls, hence off
    /// (docs/decisions/0013-reuse-across-increments-off.md).
    pub reuse_across_increments: bool,
    /// Increments of the gravity phase (`gravity_steps`); `None`: `load_steps`.
    pub gravity_steps: Option<usize>,
    /// Displacement control (`push_block`, `push_displacement`), if any.
    pub push: Option<Push>,
    /// Arc-length path following of the push (`path = "arc_length"`), if any.
    pub arc: Option<ArcLength>,
}

impl Default for StaticSettings {
    /// The secant strategy with the defaults of docs/scene-reference.md.
    fn default() -> Self {
        StaticSettings::with_strategy(Strategy::Secant)
    }
}

impl StaticSettings {
    /// The defaults of a strategy: 2,000 iterations per increment and no line search for
    /// the initial stiffness, 300 and a line search otherwise.
    pub fn with_strategy(strategy: Strategy) -> Self {
        StaticSettings {
            strategy,
            tolerance: 1e-6,
            max_iterations: if strategy == Strategy::Initial {
                2000
            } else {
                300
            },
            max_cuts: 6,
            initial_step: 0.05,
            bracket: 1e-3,
            line_search: strategy != Strategy::Initial,
            fallout: false,
            reuse_across_increments: false,
            gravity_steps: None,
            push: None,
            arc: None,
        }
    }
}

/// Displacement control of a static analysis: after gravity and the loads, the rigid
/// block `block` is moved by `displacement` in `load_steps` equal increments with its
/// rotation held (its top stays horizontal); its vertical motion is prescribed too when
/// `vertical` is given, else free under the loads (a constant pre-compression). The force
/// that holds the block on this path (N) is the load of the capacity curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    pub block: usize,
    /// Horizontal displacement (m).
    pub horizontal: f64,
    /// Vertical displacement (m); `None`: free.
    pub vertical: Option<f64>,
}

impl Push {
    /// The unit direction of the push in the plane and its length (m): the end of the
    /// path along it ([1, 0] for a zero push).
    pub fn direction(&self) -> (Point, f64) {
        let (h, v) = (self.horizontal, self.vertical.unwrap_or(0.0));
        let length = h.hypot(v);
        if length > 0.0 {
            ([h / length, v / length], length)
        } else {
            ([1.0, 0.0], length)
        }
    }
}

/// `[analysis] path = "arc_length"` or `"dissipation"`, and `arc_length` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcLength {
    /// Δl (m), the root-mean-square increment of the free unknowns; `None`: the length
    /// whose elastic predictor moves the block by `push_displacement / load_steps` at the
    /// first increment.
    pub length: Option<f64>,
    /// `path = "dissipation"`: the cylinder of theory.md Eq. A1 until the contacts start
    /// to dissipate, then the energy dissipated per increment (Eq. A2).
    pub dissipation: bool,
    /// `accept_residual`: an increment that fails every constraint at its least step is
    /// taken at its best iterate with the true laws when that iterate's relative
    /// out-of-balance force is at most this (0: never, the default). The force left is
    /// carried into the next increment, whose iterations remove it (the out-of-balance
    /// force is always that of the total state); `summary.json` counts such increments
    /// and their largest force (`curve.path.accepted`).
    pub accept: f64,
}

/// Parameters of a member of the generalized-α family (docs/theory.md §5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scheme {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl Scheme {
    /// Newmark's average acceleration (trapezoidal rule): no numerical damping.
    pub fn newmark() -> Scheme {
        Scheme {
            alpha_m: 0.0,
            alpha_f: 0.0,
            beta: 0.25,
            gamma: 0.5,
        }
    }
    /// HHT-α, 0 ≤ α ≤ ⅓ (Hilber's α with the opposite sign).
    pub fn hht(alpha: f64) -> Scheme {
        Scheme {
            alpha_m: 0.0,
            alpha_f: alpha,
            beta: 0.25 * (1.0 + alpha).powi(2),
            gamma: 0.5 + alpha,
        }
    }
    /// Generalized-α with spectral radius ρ∞ ∈ [0, 1] at infinite frequency.
    pub fn generalized_alpha(rho_inf: f64) -> Scheme {
        let am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let af = rho_inf / (rho_inf + 1.0);
        Scheme {
            alpha_m: am,
            alpha_f: af,
            beta: 0.25 * (1.0 - am + af).powi(2),
            gamma: 0.5 - am + af,
        }
    }
}

/// The state a dynamic run starts from at t = 0 (`[analysis] initial`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// `"static"` (default): the elastic equilibrium of gravity and the loads (every
    /// contact sticking) with the contact forces returned to their strength
    /// (`Dynamics::preload`): what is out of balance after the return acts at t = 0.
    Elastic,
    /// `"equilibrium"`: the static equilibrium of gravity and the loads under the
    /// joints' law, as a static analysis finds it (`Dynamics::settle`); where the
    /// structure cannot stand, the elastic start above (the blocks that cannot stand
    /// start moving).
    Equilibrium,
    /// `"rest"`: no contact force; gravity applied at t = 0.
    Rest,
}

/// Default halvings of a time step before the run is declared failed: impacts in a
/// collapse need steps of Δt/2⁶–Δt/2¹⁰ (the arch of examples/seed_arch at Δt = 0.01 s:
/// voussoirs landing at 6 m/s on a band of 5 mm), reached only while they last (the step
/// doubles back after each converged one).
pub const DYNAMIC_MAX_CUTS: usize = 12;

/// Default halvings of a time step to locate a stick–slip event of a contact within it:
/// the event is then placed to within dt/2⁴ (docs/decisions/0036-stick-slip-events.md).
pub const DYNAMIC_EVENT_CUTS: usize = 4;

/// Settings of the dynamic driver (`[analysis]` keys of `type = "dynamic"`).
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicSettings {
    pub scheme: Scheme,
    /// Time step and duration (s).
    pub dt: f64,
    pub duration: f64,
    /// Rayleigh coefficients a₀ (1/s) and a₁ (s).
    pub rayleigh: [f64; 2],
    pub tolerance: f64,
    pub max_iterations: usize,
    pub max_cuts: usize,
    /// The state at t = 0 (`initial`): the elastic equilibrium of gravity returned to the
    /// strength (default), the static equilibrium under the joints' law, or zero contact
    /// forces.
    pub start: Start,
    /// Recompute the acceleration after a step in which a contact opened or closed
    /// (`Dynamics::filtered_acceleration`), and redo a step in which a loaded contact
    /// lets go without its force at the start (`Dynamics::release`, docs/theory.md
    /// "Impacts"); `impact_reset = false` turns both off.
    pub reset_on_impact: bool,
    /// Keep the inertia M ü (default). `inertia = false`: the seed's pseudo-dynamic
    /// analysis (its §4.2 end, §4.3): C u̇ + F_int(u) = F(t), integrated by backward
    /// Euler, the ground motion entering only through the body force −M ι a_g(t).
    pub inertia: bool,
    /// Error-controlled step (`adaptive_tolerance`, m): the largest local error of a
    /// step's node displacements allowed (`Dynamics::step_error`); `None`: steps of
    /// `dt` cut only when they do not converge or jump over an impact.
    pub adaptive: Option<f64>,
    /// Halvings of a time step allowed to locate a change of a closed contact between
    /// sticking and slipping, or a reversal of its slip (`event_cuts`;
    /// `Dynamics::slip_event`, docs/theory.md §5, "Stick–slip events"); 0: none.
    pub event_cuts: usize,
    /// `[analysis] frame = "absolute"`: the fixed blocks move with the ground (the
    /// prescribed motion of the foundation) instead of the ground-motion load on the free
    /// blocks ([`super::ground_motion::Frame`]).
    pub absolute: bool,
}

impl DynamicSettings {
    /// HHT-α with α = 0.05 and the other defaults of docs/scene-reference.md, for a step
    /// `dt` over `duration` (s).
    pub fn new(dt: f64, duration: f64) -> Self {
        DynamicSettings {
            scheme: Scheme::hht(0.05),
            dt,
            duration,
            rayleigh: [0.0, 0.0],
            tolerance: 1e-6,
            max_iterations: 100,
            max_cuts: DYNAMIC_MAX_CUTS,
            start: Start::Elastic,
            reset_on_impact: true,
            inertia: true,
            adaptive: None,
            event_cuts: DYNAMIC_EVENT_CUTS,
            absolute: false,
        }
    }
}
