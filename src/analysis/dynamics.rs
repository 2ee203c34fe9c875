//! Implicit dynamic analysis (METHOD.md §6): M ü + C u̇ + F_int(u) = F(t), seed Eq. 12,
//! in the frame of the ground, F = gravity + `[[load]]` forces − M ι a_g(t); or, with
//! `frame = "absolute"`, in a fixed frame with F = gravity + loads and the fixed blocks
//! (the foundation) moved by the ground's displacement, integrated from a_g(t) with the
//! scheme's own Newmark relations (docs/theory.md §5, "Ground motion").
//!
//! Time integration by the generalized-α family (Chung and Hulbert 1993), which holds
//! Newmark's average acceleration (α_m = α_f = 0, β = ¼, γ = ½), HHT-α (Hilber, Hughes
//! and Taylor 1977: α_m = 0, α_f = α, γ = ½ + α, β = (1 + α)²/4) and generalized-α from
//! the spectral radius ρ∞ (α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1),
//! γ = ½ − α_m + α_f, β = ¼ (1 − α_m + α_f)²). With a nonlinear internal force the
//! balance of a step is taken between the forces at its two ends (the form of OpenSees'
//! HHT):
//!
//!   (1−α_m) M a₁ + α_m M a₀ + (1−α_f)(C v₁ + F_int(u₁)) + α_f (C v₀ + F_int(u₀))
//!       = (1−α_f) F(t₁) + α_f F(t₀)
//!
//! with Newmark's a₁ = (Δu − h v₀ − h²(½ − β) a₀)/(β h²), v₁ = v₀ + h((1−γ) a₀ + γ a₁).
//! The unknown of a step is its increment Δu, evaluated by the same co-rotational CST
//! and contact return map as the static driver ([`Inputs::evaluate`]); the contact states are
//! iterated within the step with the secant stiffness (METHOD.md §4), the effective
//! matrix being (1−α_m)/(βh²) M + (1−α_f) γ/(βh) C + (1−α_f) K_s — positive definite
//! even when blocks separate, thanks to the mass. The geometry is updated after every
//! converged step (updated Lagrangian); a step that does not converge is halved.
//!
//! `inertia = false` (the seed's pseudo-dynamic analysis, its §4.2 end and §4.3): M is
//! dropped, C u̇ + F_int(u) = F(t) with F = gravity + loads − M ι a_g(t) (the ground motion
//! as a body-force history), integrated by backward Euler (v₁ = Δu/h, balance at t₁,
//! effective matrix C/h + K_s). A step with no solution even when cut means the loads
//! exceed what the contacts hold: the run ends "failed" (a mechanism), as the seed's
//! computations end (its §4).
//!
//! Damping C: the Kelvin–Voigt viscosities of the blocks (D_v from λ*, μ*) and of the
//! contacts (cₙ = Eₙ* A_c / h, cₛ = Gₛ* A_c / h, both while a contact is closed, sticking
//! or slipping: the band's dashpots act in parallel with its friction slider, so that the
//! shear force is continuous at the onset of slip; none when it is open, nor over a step
//! at whose start the contact carried no force, `DASHPOT_FORCE`), plus the optional
//! Rayleigh a₀ M + a₁ K_s (K_s in the contact states at the step's start).
//!
//! Energy audit (J, all in the ground's frame): kinetic ½ vᵀMv; elastic energy of the
//! blocks ½ ∫ σᵀ Dₑ⁻¹ σ and of the contacts ½ (Fₙ²/kₙ + Fₛ²/kₛ); viscous dissipation
//! Σ Δuᵀ (C v)ₘ; friction dissipation Σ F̄ₛ · (Δδₛ − ΔFₛ/kₛ) per contact (the normal
//! band, with its opening remembered, is elastic); work of gravity and loads Σ Δuᵀ F_static; work
//! of the ground motion Σ Δuᵀ (−M ι a_g)ₘ, with (·)ₘ the mean over the step. The balance
//! error is kinetic + elastic + dissipated − work: zero up to the iteration tolerance
//! for Newmark's average acceleration (which conserves energy); HHT and generalized-α
//! add their numerical dissipation to it.
//!
//! Contacts are first those found in the initial geometry ([`Mesh::contacts`]). After
//! each converged step the driver looks for new ones and drops far-separated ones
//! (`Dynamics::update_contacts`, [`crate::mesh::contacts`]); only when the set changed
//! does it rebuild [`System`], the pattern and the buffers, and with them the symbolic
//! factorization at the next solve (`contact_topologies` in the summary).

use super::checkpoint::Checkpoint;
use super::config::{secant_local, tangent_local, Committed, Inputs, Trial};
use super::statics::OpenFlips;
use super::{fit_motion, Outcome, Stats, Status};
use crate::assembly::{loads, mass, LocalStiffness, Ranks, System};
use crate::geometry::polygon::Point;
use crate::material::{block_elastic, ContactLaw, ContactSprings, ContactState, MohrCoulomb};
use crate::mesh::{contacts, BlockDofs, Mesh};
use crate::scene::ground_motion::{self, Frame};
use crate::scene::Scene;
use crate::solve::LinearBackend;
use crate::{Error, Result};
use dfem_kernels::CsrMatrix;
use std::time::Instant;

/// Keys of `[analysis]` read by this driver (besides `dt`, `duration`, `ground_motion`).
pub const KEYS: &[&str] = &[
    "integrator",
    "alpha",
    "rho_inf",
    "rayleigh",
    "tolerance",
    "max_iterations",
    "max_cuts",
    "initial",
    "impact_reset",
    "inertia",
    "adaptive_tolerance",
];

/// Open/closed changes of a contact within a step after which its normal spring stays
/// in the matrix (see [`Dynamics::step`]).
const FLIPS_BEFORE_ELASTIC: u32 = 2;
/// GMRES iterations of a tangent step preconditioned with the step's secant
/// factorization ([`Dynamics::step`]) after which the secant step is taken instead.
const TANGENT_MAX_ITERATIONS: usize = 30;
/// A step's iterations switch to tangent steps (once the contact states settle) only
/// where the secant iteration contracts the out-of-balance norm by less than this
/// factor an iteration, and then keep to them until a state changes. Always switching
/// (factor 0) converged the rocking drums of docs/performance.md in 10,742 iterations
/// instead of 11,202, but in the collapse of the seed's arch under Acc. No. 2
/// (examples/seed_arch/acc2_inertia.toml) it led the blocks through contact sequences
/// that needed 727,493 iterations instead of the secant driver's 24,365 (31,169 with
/// this rule; over the two records at dt = 0.009, 0.01, 0.011 and 0.0125 s, 173,513
/// iterations with it against the secant driver's 526,101).
const TANGENT_SLOW: f64 = 0.5;
/// Iterations of a try of a step (not of the smallest length) without progress after
/// which it is given up and the step cut, as it would be after `max_iterations`:
/// progress is an out-of-balance norm below [`STALL_PROGRESS`] of the try's best so
/// far. In the traces of the seed arch's collapse under Acc. No. 1 and No. 2 at
/// Δt = 0.009, 0.01, 0.011 and 0.0125 s (docs/performance.md, "Giving up a stalled
/// step"), 11,407 of the 12,029 tries that converged did so within 10 iterations and 10
/// went 20 iterations without halving their best norm, while 1,051 tries ran to the 100
/// iterations and failed, cycling for most of them (periods of 2–6 iterations among the
/// states of a few contacts at their kinks): 44 % of all the iterations.
const STALL_ITERATIONS: usize = 20;
/// See [`STALL_ITERATIONS`].
const STALL_PROGRESS: f64 = 0.5;
/// Largest turn (rad) of a deformable block within a step for which its triangles stay
/// on the step's start geometry in the iteration matrix ([`Dynamics::effective_into`]):
/// the rocking drums of the `column` example turn by at most 4·10⁻⁴ rad in a step of
/// 5 ms, the voussoirs of the seed's arch by up to 10⁻² rad a step as they fall, where a
/// matrix on the start geometry slowed the iterations (tries of 12 iterations and more:
/// 870 against 56 under Acc. No. 1).
const START_GEOMETRY_TURN: f64 = 1e-3;
/// Factor on that spring per iteration the contact stays open.
const OPEN_WEIGHT_DECAY: f64 = 0.1;
/// Default halvings of a time step before the run is declared failed: impacts in a
/// collapse need steps of Δt/2⁶–Δt/2¹⁰ (the arch of examples/seed_arch at Δt = 0.01 s:
/// voussoirs landing at 6 m/s on a band of 5 mm, see `Dynamics::too_fast`), reached only
/// while they last (the step doubles back after each converged one).
const MAX_CUTS: f64 = 12.0;
/// Open/closed changes of a contact within a try of a step after which it is held open
/// for the rest of the try's iterations: in a try of the smallest length (`max_cuts`
/// halvings) whatever its force, in any other where it never carried more than
/// [`HOLD_OPEN_FORCE`] of the step's force scale while closed. A contact at the kink of
/// its law (touching with a force near zero) can make the iterations cycle whatever its
/// spring in the matrix: closed, the step carries it open; open, the step carries it
/// closed. Held open, the step's problem is smooth and converges; the contact ends the
/// step with the normal gap it reached (a penetration of at most a tenth of the band,
/// else the step is cut, `Dynamics::too_fast`), which the next step starts from with its
/// state re-evaluated.
const FREEZE_FLIPS: u32 = 6;
/// The largest force (fraction of the step's force scale, `Balance::scale`) a contact
/// may have carried closed within a try for [`FREEZE_FLIPS`] to hold it open at a step
/// length above the smallest. Held open only at the smallest length, such contacts
/// (0.1–1 N on voussoirs of tens of kN in the seed arch's collapse) stalled try after
/// try, each halving the step down to it and the step doubling back after: on the
/// arch's eight runs under Acc. No. 1 and No. 2 (docs/performance.md, "The release redo
/// from the first try, and chattering contacts held open") up to 1,402 tries given up in
/// one run, and with the redo from the first try 19,538 in one at `tolerance` 1.25·10⁻⁶
/// (72 s instead of 1). Held open at any length
/// whatever their force, a box landing on its base was launched (the held contact's
/// penetration, up to a tenth of the band, returned as elastic energy): a contact that
/// carries a force that matters is never held open above the smallest length.
const HOLD_OPEN_FORCE: f64 = 1e-3;
/// The least force (fraction of the step's force scale at its start, as
/// [`HOLD_OPEN_FORCE`]) a contact closed at a step's start must carry there for its
/// dashpots, and its share of Rayleigh's a₁ K ([`Dynamics::rayleigh_local`]), to act over
/// the step. A contact that touches with no force (the head joints
/// of a running-bond wall under gravity) sits at the kink of its law: with its dashpots
/// engaged while the trial is closed, the force jumps by cₙ δ̇ₙ and cₛ δ̇ₛ each time the
/// iterations carry it across δₙ = 0, a law with no solution there that the iterations
/// cycle around, whatever the step (with the joints' dashpots of
/// docs/performance.md, "Dashpots of contacts that carry no force", a rigid 30 × 30 wall
/// under El Centro took 5,692 iterations and 60 stalled tries for 1 s, against 816
/// without dashpots). Such a contact damps nothing that matters; it takes its dashpots
/// back at the first step it starts carrying a force.
const DASHPOT_FORCE: f64 = 1e-3;
/// Penetration (fraction of the band thickness) a contact held open may end a step with
/// before the step is cut, and the most a new contact starts with.
const HELD_PENETRATION: f64 = 0.1;
/// Step lengths tried by the line search of a step's iterations: 1, 1/2, …, 1/8.
const LINE_SEARCH_STEPS: usize = 4;

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

/// Parameters of a member of the generalized-α family.
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

/// Settings of the dynamic driver (`[analysis]` keys).
#[derive(Debug, Clone)]
pub struct Settings {
    pub scheme: Scheme,
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
    /// `[analysis] frame = "absolute"`: the fixed blocks move with the ground (the
    /// prescribed motion of the foundation) instead of the ground-motion load on the free
    /// blocks ([`Frame`]).
    pub absolute: bool,
}

impl Settings {
    pub fn from_scene(scene: &Scene) -> Result<Settings> {
        let x = &scene.analysis.extra;
        let place = super::analysis_place;
        let num = |k: &str, d: f64, lo: f64, hi: f64| super::analysis_number(scene, k, d, lo, hi);
        let scheme = match x.get("integrator").map(|v| v.as_str()) {
            None | Some(Some("hht")) => Scheme::hht(num("alpha", 0.05, 0.0, 1.0 / 3.0)?),
            Some(Some("newmark")) => Scheme::newmark(),
            Some(Some("generalized-alpha")) => {
                Scheme::generalized_alpha(num("rho_inf", 0.8, 0.0, 1.0)?)
            }
            _ => {
                return Err(Error::new("unknown integrator")
                    .place(place("integrator"))
                    .fix("use \"newmark\", \"hht\" or \"generalized-alpha\""))
            }
        };
        let rayleigh = match x.get("rayleigh") {
            None => [0.0, 0.0],
            Some(v) => {
                let r: Option<Vec<f64>> = v.as_array().map(|a| {
                    a.iter()
                        .map(|v| {
                            v.as_float()
                                .or_else(|| v.as_integer().map(|i| i as f64))
                                .unwrap_or(f64::NAN)
                        })
                        .collect()
                });
                match r {
                    Some(r) if r.len() == 2 && r.iter().all(|c| c.is_finite() && *c >= 0.0) => {
                        [r[0], r[1]]
                    }
                    _ => {
                        return Err(Error::new(
                            "'rayleigh' must be two non-negative numbers [a0, a1]",
                        )
                        .place(place("rayleigh"))
                        .fix("for example rayleigh = [0.1, 0.001] (C = a0 M + a1 K)"))
                    }
                }
            }
        };
        let inertia = match x.get("inertia") {
            None => true,
            Some(v) => v.as_bool().ok_or_else(|| {
                Error::new("'inertia' must be true or false")
                    .place(place("inertia"))
                    .fix("inertia = true (default: M ü kept) or false (pseudo-dynamic: C u̇ + F_int = F(t))")
            })?,
        };
        // (without inertia refused by the scene reader)
        let absolute = scene.analysis.frame == Frame::Absolute;
        Ok(Settings {
            scheme,
            dt: scene.analysis.dt.unwrap_or(0.01),
            duration: scene.analysis.duration.unwrap_or(0.0),
            rayleigh,
            tolerance: num("tolerance", 1e-6, 1e-14, 0.1)?,
            max_iterations: num("max_iterations", 100.0, 1.0, 1e6)? as usize,
            max_cuts: num("max_cuts", MAX_CUTS, 0.0, 30.0)? as usize,
            inertia,
            absolute,
            adaptive: match x.get("adaptive_tolerance") {
                None => None,
                Some(_) => Some(num("adaptive_tolerance", 1e-6, 1e-15, 1.0)?),
            },
            reset_on_impact: match x.get("impact_reset") {
                None => true,
                Some(v) => v.as_bool().ok_or_else(|| {
                    Error::new("'impact_reset' must be true or false")
                        .place(place("impact_reset"))
                        .fix("impact_reset = true (default) or false")
                })?,
            },
            start: match x.get("initial").map(|v| v.as_str()) {
                None | Some(Some("static")) => Start::Elastic,
                Some(Some("equilibrium")) => Start::Equilibrium,
                Some(Some("rest")) => Start::Rest,
                _ => {
                    return Err(Error::new("unknown initial state")
                        .place(place("initial"))
                        .fix("use \"static\" (elastic equilibrium of gravity returned to the joints' strength, default), \"equilibrium\" (static equilibrium of gravity under the joints' law) or \"rest\" (no contact force at t = 0)"))
                }
            },
        })
    }
}

/// The time history of a dynamic run: `columns` names each value of a row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    /// ParaView frames due: (time s, step number).
    pub frames: Vec<(f64, usize)>,
}

/// Receives the results of a run as they are computed (the output writer streams them
/// to disk, so that an interrupted run keeps its completed steps).
pub trait Monitor {
    /// The history columns, before the first row.
    fn start(&mut self, _columns: &[String]) -> Result<()> {
        Ok(())
    }
    /// One history row (the initial state, then every completed time step).
    fn row(&mut self, _row: &[f64]) -> Result<()> {
        Ok(())
    }
    /// Whether [`Monitor::frame`] wants full states (building them costs a copy).
    fn wants_frames(&self) -> bool {
        false
    }
    /// The full state at a frame (every `[output] every` steps).
    fn frame(&mut self, _step: usize, _time: f64, _state: &Outcome) -> Result<()> {
        Ok(())
    }
    /// Whether the run should stop after step `step` (Ctrl-C): the driver then writes a
    /// checkpoint and returns [`Status::Interrupted`].
    fn stop_requested(&mut self, _step: usize) -> bool {
        false
    }
    /// Whether a checkpoint is due after step `step` (0: the initial state).
    fn checkpoint_due(&mut self, _step: usize) -> bool {
        false
    }
    /// A checkpoint ([`Dynamics::checkpoint`]) and the state it holds.
    fn checkpoint(&mut self, _c: &Checkpoint, _state: &Outcome) -> Result<()> {
        Ok(())
    }
}

/// A monitor that keeps nothing (the history is also in the outcome).
pub struct NoMonitor;
impl Monitor for NoMonitor {}

/// Energy terms (J), see the module documentation.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energy {
    pub kinetic: f64,
    pub elastic: f64,
    pub viscous: f64,
    pub contact: f64,
    pub work_static: f64,
    pub work_ground: f64,
    /// Elastic energy of the initial state (the gravity pre-load).
    pub elastic0: f64,
}

impl Energy {
    /// kinetic + elastic + dissipated − external work.
    pub fn error(&self) -> f64 {
        self.kinetic + self.elastic - self.elastic0 + self.viscous + self.contact
            - self.work_static
            - self.work_ground
    }
}

/// The dynamic model being integrated.
pub struct Dynamics<'a> {
    scene: &'a Scene,
    mesh0: &'a Mesh,
    /// This process's rows in a distributed run ([`System::distributed`]).
    ranks: Option<&'a Ranks>,
    pub settings: Settings,
    system: System,
    law: MohrCoulomb,
    springs: Vec<ContactSprings>,
    /// Contact viscosities (cₙ, cₛ) (N·s/m).
    visc: Vec<ContactSprings>,
    /// The least force (N) a contact carries at a step's start for its damping to act in
    /// that step ([`DASHPOT_FORCE`] of the step's force scale; set by [`Dynamics::step`]).
    dashpot_floor: f64,
    area: Vec<f64>,
    cur: Mesh,
    committed: Committed,
    /// The bonds broken in the tries of the step being taken
    /// ([`Dynamics::break_cycling_bonds`]), with the history each had: given back when
    /// the step fails or is cut ([`OpenFlips::give_back`], in [`Dynamics::advance_to`]),
    /// so that its retry starts from the committed state as it was; kept when it is
    /// committed.
    bonds_broken_here: Vec<(usize, crate::material::History)>,
    /// Velocity (m/s, rad/s) and acceleration (m/s², rad/s²) of the unknowns.
    v: Vec<f64>,
    a: Vec<f64>,
    /// Internal and damping forces (N) at the last converged state.
    f_int: Vec<f64>,
    f_visc: Vec<f64>,
    mass: Vec<f64>,
    iota: [Vec<f64>; 2],
    f_static: Vec<f64>,
    kbuf: CsrMatrix,
    /// The tangent effective matrix of [`Dynamics::step`] (allocated at its first use).
    tbuf: Option<CsrMatrix>,
    /// C of the last trial balanced, on its geometry (the viscous force C v₁).
    cbuf: Option<CsrMatrix>,
    /// C on the step's start geometry, in the states of the matrix being built
    /// ([`Dynamics::effective_into`]).
    cmat: Option<CsrMatrix>,
    diag: Vec<usize>,
    /// Dₑ⁻¹ (1/Pa) of each triangle's material (elastic energy).
    compliance: Vec<[[f64; 3]; 3]>,
    backend: &'a mut dyn LinearBackend,
    pub stats: Stats,
    pub energy: Energy,
    pub time: f64,
    /// The ground's displacement (m) and velocity (m/s) at `time` in the absolute frame,
    /// integrated from a_g along the steps taken by the scheme's own Newmark relations
    /// (zero in the relative frame).
    ground_u: [f64; 2],
    ground_v: [f64; 2],
}

/// Open the contacts `frozen` in a trial: no force (taken out of F_int), state open.
fn hold_open(trial: &mut Trial, frozen: &[bool]) {
    for (k, &f) in frozen.iter().enumerate() {
        if f && trial.state[k] != ContactState::Open {
            let [fnn, fs] = trial.force[k];
            crate::assembly::add_contact_force(
                &trial.mesh,
                &trial.mesh.contacts[k],
                [-fnn, -fs],
                &mut trial.f_int,
            );
            trial.force[k] = [0.0, 0.0];
            trial.state[k] = ContactState::Open;
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let (a0, a1) = ((j + 1) % 3, (j + 2) % 3);
            let (b0, b1) = ((i + 1) % 3, (i + 2) % 3);
            (m[a0][b0] * m[a1][b1] - m[a0][b1] * m[a1][b0]) / det
        })
    })
}

/// Per contact: area A_c = length × thickness (m²), springs (kₙ, kₛ) (N/m) and
/// viscosities (cₙ, cₛ) = (Eₙ*, Gₛ*) A_c / h (N·s/m), METHOD.md §3.
fn contact_coefficients(
    scene: &Scene,
    law: &MohrCoulomb,
    contacts: &[crate::mesh::Contact],
) -> (Vec<f64>, Vec<ContactSprings>, Vec<ContactSprings>) {
    let joint = scene.joints.get(scene.contacts.joint);
    let t = scene.model.thickness;
    let area: Vec<f64> = contacts.iter().map(|c| c.length * t).collect();
    let springs = area.iter().map(|&a| law.springs(a)).collect();
    let visc = area
        .iter()
        .map(|&a| match joint {
            Some(j) => ContactSprings {
                kn: j.normal_viscosity * a / j.band,
                ks: j.shear_viscosity * a / j.band,
            },
            None => ContactSprings { kn: 0.0, ks: 0.0 },
        })
        .collect();
    (area, springs, visc)
}

/// A converged step, ready to commit.
/// The constants of one step: the scheme's parameters (with α_m = α_f = 0, β = γ = 1
/// for the pseudo-dynamic backward Euler), c₀ = 1/(β h²) (0 without inertia), the step h
/// (s) and the external force F_ext at t + (1 − α_f) h (N).
struct StepTerms {
    am: f64,
    af: f64,
    beta: f64,
    gamma: f64,
    c0: f64,
    h: f64,
    fe: Vec<f64>,
    /// The ground's velocity at the step's end (m/s; zero in the relative frame): the
    /// damping acts on the velocity relative to it.
    vg1: [f64; 2],
}

/// The balance of a trial increment ([`Dynamics::balance`]): out-of-balance force `r`
/// (N), its norm and the force scale it is measured against, and the step's end
/// velocity, acceleration and viscous force.
struct Balance {
    r: Vec<f64>,
    rn: f64,
    scale: f64,
    v1: Vec<f64>,
    a1: Vec<f64>,
    fv1: Vec<f64>,
}

struct Accepted {
    trial: Trial,
    v: Vec<f64>,
    a: Vec<f64>,
    f_visc: Vec<f64>,
    h: f64,
    ground: [f64; 2],
    /// The ground's displacement over the step (m) and velocity at its end (m/s) in the
    /// absolute frame (zero in the relative frame).
    ground_du: [f64; 2],
    ground_v1: [f64; 2],
    /// Contacts held open for the rest of the step after cycling (see [`FREEZE_FLIPS`]).
    frozen: Vec<bool>,
}

/// How far each deformable block of `to` turned from `from` (the same mesh at other node
/// positions): the largest distance of a node's displacement from the block's mean one
/// over the largest distance of a node of `from` from their mean (rad for a rigid turn;
/// a strain for a deformation). Other blocks: 0.
fn turns(from: &Mesh, to: &Mesh) -> Vec<f64> {
    from.blocks
        .iter()
        .map(|b| {
            if b.dofs != BlockDofs::Deformable || b.nodes.is_empty() {
                return 0.0;
            }
            let ids = b.nodes.start as usize..b.nodes.end as usize;
            let d: Vec<Point> = ids
                .clone()
                .map(|i| {
                    [
                        to.nodes[i][0] - from.nodes[i][0],
                        to.nodes[i][1] - from.nodes[i][1],
                    ]
                })
                .collect();
            let k = d.len() as f64;
            let m = d
                .iter()
                .fold([0.0, 0.0], |m, v| [m[0] + v[0] / k, m[1] + v[1] / k]);
            let spread = d
                .iter()
                .map(|v| (v[0] - m[0]).hypot(v[1] - m[1]))
                .fold(0.0, f64::max);
            let c = ids.clone().fold([0.0, 0.0], |c, i| {
                [c[0] + from.nodes[i][0] / k, c[1] + from.nodes[i][1] / k]
            });
            let radius = ids
                .map(|i| (from.nodes[i][0] - c[0]).hypot(from.nodes[i][1] - c[1]))
                .fold(0.0, f64::max);
            if radius > 0.0 {
                spread / radius
            } else {
                0.0
            }
        })
        .collect()
}

impl<'a> Dynamics<'a> {
    /// The driver of the scene's dynamic analysis, its state still all zero: a run
    /// starts it with [`Dynamics::start`] or restores a checkpoint
    /// ([`Dynamics::restore`]).
    pub fn new(
        scene: &'a Scene,
        mesh: &'a Mesh,
        ranks: Option<&'a Ranks>,
        backend: &'a mut dyn LinearBackend,
    ) -> Result<Dynamics<'a>> {
        let settings = Settings::from_scene(scene)?;
        let system = System::for_dynamics(scene, mesh).distributed(ranks);
        // a failed factorization only says "singular" here: no LDLᵀ for its pivot's value
        backend.set_failed_pivot_value(false);
        let joint = scene.joints.get(scene.contacts.joint);
        let law = joint.map(MohrCoulomb::from_joint).unwrap_or(MohrCoulomb {
            elastic: crate::material::ElasticBand {
                normal_modulus: 0.0,
                shear_modulus: 0.0,
                band: 1.0,
            },
            tan_phi: 0.0,
            cohesion: 0.0,
            tensile_strength: 0.0,
        });
        let (area, springs, visc) = contact_coefficients(scene, &law, &mesh.contacts);
        let mass = mass::lumped(scene, mesh);
        let iota = mass::influence(mesh);
        let g = scene.model.gravity;
        let mut f_static: Vec<f64> = (0..mesh.n_dofs)
            .map(|i| mass[i] * (iota[0][i] * g[0] + iota[1][i] * g[1]))
            .collect();
        for (f, l) in f_static.iter_mut().zip(loads::applied(scene, mesh)) {
            *f += l;
        }
        let viscous_blocks = mesh.tri_block.iter().any(|&b| {
            let m = &scene.materials[scene.blocks[b as usize].material];
            m.viscous_lambda > 0.0 || m.viscous_mu > 0.0
        });
        // from the joint, not the contacts: a run may start with none and find some
        let viscous_contacts =
            joint.is_some_and(|j| j.normal_viscosity > 0.0 || j.shear_viscosity > 0.0);
        let pattern = system.plan.pattern().clone();
        let cbuf = (viscous_blocks || viscous_contacts).then(|| CsrMatrix::zeros(pattern.clone()));
        let compliance = mesh
            .tri_block
            .iter()
            .map(|&b| {
                invert3(block_elastic(
                    &scene.materials[scene.blocks[b as usize].material],
                    scene.model.plane,
                ))
            })
            .collect();
        let n = mesh.n_dofs;
        Ok(Dynamics {
            scene,
            mesh0: mesh,
            ranks,
            settings,
            diag: pattern.diagonal_positions(),
            kbuf: CsrMatrix::zeros(pattern),
            tbuf: None,
            cmat: cbuf.clone(),
            cbuf,
            system,
            law,
            springs,
            visc,
            dashpot_floor: 0.0,
            area,
            cur: mesh.clone(),
            committed: match &scene.in_situ {
                Some(f) => Committed::in_situ(mesh, f, scene.model.thickness),
                None => Committed::zero(mesh),
            },
            bonds_broken_here: Vec::new(),
            v: vec![0.0; n],
            a: vec![0.0; n],
            f_int: vec![0.0; n],
            f_visc: vec![0.0; n],
            mass,
            iota,
            f_static,
            compliance,
            backend,
            stats: Stats {
                dofs: n,
                contacts: mesh.contacts.len(),
                contact_topologies: 1,
                triangles: mesh.triangles.len(),
                ..Default::default()
            },
            energy: Energy::default(),
            time: 0.0,
            ground_u: [0.0; 2],
            ground_v: [0.0; 2],
        })
    }

    /// The state at t = 0 (`initial`, [`Start`]): the in-situ state, the elastic or
    /// static equilibrium of gravity, and the initial acceleration. Not needed by a run
    /// resumed from a checkpoint, which [`Dynamics::restore`] sets whole (a static start
    /// would be computed for nothing).
    pub fn start(&mut self) -> Result<()> {
        let n = self.cur.n_dofs;
        if self.scene.in_situ.is_some() {
            self.start_from_committed();
        }
        if self.settings.start != Start::Rest {
            // the geometry before the elastic predictor, only where a static analysis
            // may start from it
            let initial = (self.settings.start == Start::Equilibrium).then(|| self.cur.clone());
            self.preload()?;
            if let Some(initial) = initial {
                self.settle(&initial);
            }
        }
        let f0 = self.f_ext(0.0);
        if self.settings.inertia {
            self.a = (0..n)
                .map(|i| (f0[i] - self.f_int[i]) / self.mass[i])
                .collect();
            self.a = self.absolute_from_relative(&self.a, self.ground(0.0));
        }
        if self.settings.start != Start::Rest && self.settings.inertia {
            self.filtered_acceleration();
        }
        Ok(())
    }

    /// The acceleration of the committed state seen by the next step:
    /// (M + β h² K_s) a = F(t) − F_int − C v. The soft motions (a sliding block) get
    /// M⁻¹ r; the stiff ones (a contact pressed by an out-of-balance force) get ≈ 0, as the
    /// contacts adjust within the step. Used at the start, and after a step in which a
    /// contact opened or closed: the acceleration of an impact is an impulse spread over
    /// one step, which the next steps would otherwise carry on (through the a₀ terms of
    /// the update) after the contact has let go, feeding energy into the free motion.
    fn filtered_acceleration(&mut self) {
        let states = self.committed.state.clone();
        self.filtered_acceleration_with(&states);
    }

    /// [`Dynamics::filtered_acceleration`] with the contact states `states` in K_s.
    fn filtered_acceleration_with(&mut self, states: &[ContactState]) {
        let f = self.f_ext(self.time);
        let r: Vec<f64> = (0..f.len())
            .map(|i| f[i] - self.f_int[i] - self.f_visc[i])
            .collect();
        let h = self.settings.dt;
        let beta = self.settings.scheme.beta;
        let local: Vec<LocalStiffness> = (0..self.springs.len())
            .map(|k| secant_local(self.springs[k], states[k]))
            .collect();
        self.system
            .stiffness_into(&self.cur, &local, &mut self.kbuf);
        self.kbuf.values.iter_mut().for_each(|k| *k *= beta * h * h);
        for (i, &p) in self.diag.iter().enumerate() {
            self.kbuf.values[p] += self.mass[i];
        }
        let mut x = r;
        if self.backend.factorize(&self.kbuf).is_ok()
            && self.backend.solve(&mut x).is_ok()
            && x.iter().all(|v| v.is_finite())
        {
            // the filtered acceleration is the one relative to the ground
            self.a = self.absolute_from_relative(&x, self.ground(self.time));
        }
    }

    /// The committed state returned to the contacts' strength envelope, its internal
    /// forces, and its elastic energy as the energy audit's origin: the start of a run,
    /// from the in-situ state (docs/theory.md, "In-situ stress": the stresses and contact
    /// forces of Eq. I1; from rest, `initial = "rest"`, the out-of-balance force of the
    /// excavation then acts at t = 0, a sudden excavation) or from the elastic
    /// equilibrium of [`Dynamics::preload`].
    fn start_from_committed(&mut self) {
        let back = self.trial(&vec![0.0; self.cur.n_dofs]);
        self.committed.force = back.force;
        self.committed.state = back.state;
        self.committed.stress = back.stress;
        self.f_int = back.f_int;
        self.energy.elastic =
            self.elastic_energy(&self.cur, &self.committed.stress, &self.committed.force);
        self.energy.elastic0 = self.energy.elastic;
    }

    /// The static equilibrium of gravity and the loads as the start (`initial =
    /// "equilibrium"`):
    /// when the elastic start of [`Dynamics::preload`] leaves an out-of-balance force
    /// above the tolerance (contacts in tension opened, others slipped: jointed rock
    /// around an opening, a wall's head joints), the static driver applies gravity (and
    /// the in-situ state's release) to the `initial` geometry in its increments with the
    /// joints' law, and the run starts from its converged state. Where it fails (a block
    /// that cannot stand) the elastic start stays, and the blocks that cannot stand
    /// start moving from it, and so it does where the static analysis cannot be run (its
    /// error is not the dynamic run's). The static driver's iterations are counted in
    /// `static_start_iterations`.
    ///
    /// Why: from the elastic start returned to the strength the first steps must find
    /// the equilibrium through inertia under the full out-of-balance force, a sudden
    /// release that shakes the contacts open and shut (the `tunnel` example under El
    /// Centro: an out-of-balance force of 1.05 times the load scale at t = 0, its first
    /// step stalled at 0.95 of it, 241 stalled tries in 1 s).
    fn settle(&mut self, initial: &Mesh) {
        let r: Vec<f64> = self
            .f_static
            .iter()
            .zip(&self.f_int)
            .map(|(f, g)| f - g)
            .collect();
        let load = norm(&self.f_static);
        if load == 0.0 || norm(&r) <= self.settings.tolerance * load {
            return;
        }
        let mut scene = self.scene.clone();
        scene.analysis.kind = crate::scene::AnalysisType::Static;
        scene.analysis.lateral = 0.0;
        scene.analysis.ground_motion.clear();
        scene.analysis.extra.retain(|k, _| k == "tolerance");
        for b in &mut scene.blocks {
            b.prescribed = None;
        }
        let silent = &mut super::progress::Silent;
        let run = super::statics::run_with_progress(
            &scene,
            initial,
            self.ranks,
            &mut *self.backend,
            silent,
        );
        let Ok(out) = run else {
            return;
        };
        self.stats.static_start_iterations = out.stats.iterations;
        if out.status != Status::Stable || out.contact_forces.len() != self.cur.contacts.len() {
            return;
        }
        self.committed.u = out.u;
        self.committed.stress = out.stress;
        self.committed.force = out.contact_forces;
        self.committed.state = out.contact_states;
        self.committed.history = out.contact_history;
        self.cur = out.current.unwrap_or_else(|| initial.clone());
        self.start_from_committed();
    }

    /// The initial state: the elastic equilibrium K₀ u₀ = F_static − F_int of gravity and
    /// loads (F_int: the in-situ state's internal forces, zero without one; every contact
    /// sticking, no strength limit), then the contact forces returned to their strength.
    /// Contacts that carry the weight from t = 0 do not bounce (the
    /// chatter of stiff contacts started without force), and a block whose friction
    /// cannot hold it starts sliding with the right acceleration. Skipped when K₀ is
    /// singular (a block that touches nothing).
    fn preload(&mut self) -> Result<()> {
        let local: Vec<LocalStiffness> = self
            .springs
            .iter()
            .map(|&k| crate::assembly::diagonal(k))
            .collect();
        self.system
            .stiffness_into(&self.cur, &local, &mut self.kbuf);
        let mut x: Vec<f64> = self
            .f_static
            .iter()
            .zip(&self.f_int)
            .map(|(f, g)| f - g)
            .collect();
        let load = norm(&x);
        let ok = self.backend.factorize(&self.kbuf).is_ok()
            && !super::singular_pivots(&*self.backend)
            && self.backend.solve(&mut x).is_ok()
            && x.iter().all(|v| v.is_finite());
        if !ok || load == 0.0 {
            return Ok(());
        }
        let presc = vec![[0.0; 2]; self.cur.blocks.len()];
        let el = Inputs {
            law: &self.law.elastic,
            ..self.inputs()
        }
        .evaluate(&x, &presc);
        self.committed.u = x;
        self.committed.stress = el.stress;
        self.committed.force = el.force;
        self.cur = el.mesh;
        // the same state returned to the strength envelope
        self.start_from_committed();
        Ok(())
    }

    /// Look for new contacts and drop far-separated ones in the current configuration
    /// ([`contacts`]); rebuild the system (pattern, and with it the symbolic
    /// factorization at the next solve) only when the set changed. The committed forces
    /// and states of the contacts kept are carried over; a new contact starts with the
    /// band's force at its gap, Fₙ = kₙ × gap: open with its opening remembered (as in
    /// [`Dynamics::commit`]) when the gap is positive, compressed otherwise.
    /// Returns whether the contact set changed.
    fn update_contacts(&mut self) -> bool {
        let band = self.law.elastic.band;
        let t = self.scene.model.thickness;
        let v_rel = self.relative(&self.v, self.ground_v);
        let vel: Vec<Point> = (0..self.cur.nodes.len() as u32)
            .map(|n| self.cur.node_displacement(n, &v_rel))
            .collect();
        let vmax = vel.iter().fold(0.0f64, |m, v| m.max(v[0].hypot(v[1])));
        let reach = band + 2.0 * vmax * self.settings.dt;
        let state = &self.committed.state;
        let open: Vec<bool> = state.iter().map(|s| *s == ContactState::Open).collect();
        let keep = contacts::kept(&self.cur, &open, band, reach);
        let dropped = keep.iter().filter(|k| !**k).count();
        if dropped > 0 {
            let mut it = keep.iter();
            self.cur.contacts.retain(|_| *it.next().unwrap());
            let mut it = keep.iter();
            self.committed.force.retain(|_| *it.next().unwrap());
            let mut it = keep.iter();
            self.committed.state.retain(|_| *it.next().unwrap());
        }
        let found = contacts::search(&self.cur, &vel, band, reach);
        let added = found.len();
        for f in found {
            if super::tracing() {
                eprintln!(
                    "  new contact {}-{} node {} gap {:.4e} length {:.4e} along {:.4}",
                    f.contact.block_l,
                    f.contact.block_m,
                    f.contact.node_m,
                    f.gap,
                    f.contact.length,
                    f.contact.along.unwrap_or(f64::NAN)
                );
            }
            // the band's force at the gap: the remembered opening of an open contact, or
            // the elastic compression of one found already within the band, at most that
            // of a tenth of the band: a vertex found deeper (it came past the end of an
            // edge, or out of the shadow of a contact dropped since) would start with
            // the elastic energy ½ kₙ gap² that no work paid for (the arch: 1.8 MJ from
            // a vertex found 4 cm inside its neighbour); the rest of the overlap is
            // left, and the contact resists any further approach
            let kn = self.law.springs(f.contact.length * t).kn;
            let gap = f.gap.max(-HELD_PENETRATION * band);
            self.committed.force.push([kn * gap, 0.0]);
            self.committed.state.push(if f.gap > 0.0 {
                ContactState::Open
            } else {
                ContactState::Stick
            });
            self.cur.contacts.push(f.contact);
        }
        // the tributary lengths of open vertex-to-edge contacts follow the geometry (a
        // corner that turns onto its side before it lands gets half of that side); a
        // closed contact keeps its length, and with it its spring, while it carries force:
        // its force kept with a spring 40 times softer (a side that rocks back onto its
        // corner, h against half the side) would hold 40 times the elastic energy, made
        // from nothing (the arch of examples/seed_arch: 10⁵–10⁶ J jumps before this rule)
        let lengths: Vec<f64> = self
            .cur
            .contacts
            .iter()
            .zip(&self.committed.state)
            .map(|(c, s)| match c.along {
                Some(_) if *s == ContactState::Open => {
                    contacts::current_length(&self.cur, c, band, reach)
                }
                _ => c.length,
            })
            .collect();
        for (k, (c, l)) in self.cur.contacts.iter_mut().zip(lengths).enumerate() {
            // an open contact keeps its gap (Fₙ/kₙ) when its spring changes with the length
            if l != c.length && self.committed.state[k] == ContactState::Open {
                self.committed.force[k][0] *= l / c.length;
            }
            c.length = l;
        }
        let (area, springs, visc) = contact_coefficients(self.scene, &self.law, &self.cur.contacts);
        self.area = area;
        self.springs = springs;
        self.visc = visc;
        if dropped + added == 0 {
            return false;
        }
        self.rebuild_system();
        // the internal force of the committed state with the new contact set
        let now = self.trial(&vec![0.0; self.cur.n_dofs]);
        self.f_int = now.f_int;
        self.stats.contact_topologies += 1;
        true
    }

    /// The system, its pattern and the matrix buffers for the contact set of `cur`.
    fn rebuild_system(&mut self) {
        self.system = System::for_dynamics(self.scene, &self.cur).distributed(self.ranks);
        let pattern = self.system.plan.pattern().clone();
        self.diag = pattern.diagonal_positions();
        self.kbuf = CsrMatrix::zeros(pattern.clone());
        self.tbuf = None;
        if self.cbuf.is_some() {
            self.cbuf = Some(CsrMatrix::zeros(pattern.clone()));
            self.cmat = Some(CsrMatrix::zeros(pattern));
        }
    }

    /// The state after `step` completed time steps, for `dfem run --resume`
    /// ([`super::checkpoint`]).
    pub fn checkpoint(&self, step: usize) -> Checkpoint {
        Checkpoint {
            step,
            time: self.time,
            mesh: self.cur.clone(),
            committed: self.committed.clone(),
            v: self.v.clone(),
            a: self.a.clone(),
            f_int: self.f_int.clone(),
            f_visc: self.f_visc.clone(),
            energy: self.energy,
            stats: self.stats.clone(),
            ground: [self.ground_u, self.ground_v],
        }
    }

    /// Continue from a checkpoint of the same scene: the state is taken as saved, the
    /// contact coefficients, the system and its buffers are rebuilt for its contact set.
    /// Returns the number of completed steps.
    pub fn restore(&mut self, c: Checkpoint) -> usize {
        self.time = c.time;
        self.cur = c.mesh;
        self.committed = c.committed;
        self.v = c.v;
        self.a = c.a;
        self.f_int = c.f_int;
        self.f_visc = c.f_visc;
        self.energy = c.energy;
        self.stats = c.stats;
        [self.ground_u, self.ground_v] = c.ground;
        let (area, springs, visc) = contact_coefficients(self.scene, &self.law, &self.cur.contacts);
        self.area = area;
        self.springs = springs;
        self.visc = visc;
        self.rebuild_system();
        c.step
    }

    /// The ground acceleration vector (m/s²) at time t.
    pub fn ground(&self, t: f64) -> [f64; 2] {
        ground_motion::vector(&self.scene.analysis.ground_motion, t)
    }

    /// x − ι g: a velocity or acceleration of the unknowns relative to the ground's `g`
    /// (the unknowns' own in the relative frame, where it is returned unchanged).
    fn relative(&self, x: &[f64], g: [f64; 2]) -> Vec<f64> {
        self.shifted(x, g, -1.0)
    }

    /// x + ι g in the absolute frame (unchanged in the relative frame).
    fn absolute_from_relative(&self, x: &[f64], g: [f64; 2]) -> Vec<f64> {
        self.shifted(x, g, 1.0)
    }

    fn shifted(&self, x: &[f64], g: [f64; 2], sign: f64) -> Vec<f64> {
        if !self.settings.absolute {
            return x.to_vec();
        }
        (0..x.len())
            .map(|i| x[i] + sign * (self.iota[0][i] * g[0] + self.iota[1][i] * g[1]))
            .collect()
    }

    /// ιᵀ f: the x and y resultants (N) of a force on the unknowns (the rotations of
    /// rigid blocks left out).
    fn resultant(&self, f: &[f64]) -> [f64; 2] {
        [dot(&self.iota[0], f), dot(&self.iota[1], f)]
    }

    /// Ground-motion load −M ι a_g(t) (N).
    fn f_ground(&self, ag: [f64; 2]) -> Vec<f64> {
        (0..self.mass.len())
            .map(|i| -self.mass[i] * (self.iota[0][i] * ag[0] + self.iota[1][i] * ag[1]))
            .collect()
    }

    /// External force F(t) (N): gravity and loads, and the ground-motion load.
    fn f_ext(&self, t: f64) -> Vec<f64> {
        let fg = self.f_ground(self.ground(t));
        self.f_static.iter().zip(&fg).map(|(a, b)| a + b).collect()
    }

    fn trial(&self, dq: &[f64]) -> Trial {
        self.trial_moving(dq, [0.0; 2])
    }

    /// A trial increment `dq` of the free unknowns with the fixed blocks moved by `dug`
    /// (m): the ground's motion over a step in the absolute frame.
    fn trial_moving(&self, dq: &[f64], dug: [f64; 2]) -> Trial {
        let presc: Vec<Point> = self
            .cur
            .blocks
            .iter()
            .map(|b| match b.dofs {
                BlockDofs::Fixed => dug,
                _ => [0.0; 2],
            })
            .collect();
        self.inputs().evaluate(dq, &presc)
    }

    /// What a trial of this driver evaluates against ([`Inputs`]): its model, the
    /// configuration at the step's start and its committed state, the contacts' laws and
    /// areas.
    fn inputs(&self) -> Inputs<'_> {
        Inputs {
            system: &self.system,
            cur: &self.cur,
            committed: &self.committed,
            law: &self.law,
            area: &self.area,
            thickness: self.scene.model.thickness,
        }
    }

    /// The out-of-balance force of a trial increment `dq` of a step (METHOD.md §6, the
    /// generalized-α balance): r = F_ext − M a_{1−α_m} − (1−α_f)(C v₁ + F_int(q₁)) −
    /// α_f (C v₀ + F_int(q₀)) (N), with the Newmark kinematics of `k` for a₁ and v₁; the
    /// viscous forces C v₁ of the trial states (the dashpots of closed contacts, the
    /// blocks' Kelvin–Voigt viscosity, Rayleigh damping).
    fn balance(&mut self, k: &StepTerms, dq: &[f64], trial: &Trial) -> Balance {
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
            // it (a rigid wall under El Centro failed within 0.02 s: docs/performance.md,
            // "Rayleigh damping on the step's start states"); none from a contact with no
            // force at the start (`DASHPOT_FORCE`), nor across one open in the trial (no
            // damping force across an open band, as for the dashpots)
            let local: Vec<LocalStiffness> = (0..self.springs.len())
                .map(|c| self.rayleigh_local(c, trial.state[c]))
                .collect();
            self.system
                .stiffness_into(&trial.mesh, &local, &mut self.kbuf);
            let mut kv = vec![0.0; n];
            self.kbuf.mul_vec(&v1r, &mut kv);
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

    /// Breaks the bonds of the contacts that changed between closed and open at least
    /// `BOND_BREAK_FLIPS` (3) times in a try's iterations, counted where they carried a
    /// force that matters on one side (`flips`, [`OpenFlips`]), not held open
    /// (`frozen`), whose bond is intact: the try stalled cycling between a closed
    /// contact with its cohesion and an open one without, which is the jump of the
    /// brittle bond's law at zero normal force (the bond cannot hold there, as in the
    /// static driver's `Driver::break_cycling_bonds`). Whether any broke.
    fn break_cycling_bonds(&mut self, flips: &OpenFlips, frozen: &[bool]) -> bool {
        let law = &self.law;
        flips.break_bonds(
            &mut self.committed.history,
            |_, h| law.broken_bond(h),
            |k| frozen[k],
            &mut self.bonds_broken_here,
        )
    }

    /// Try one step of length h from the committed state; `None` when it does not
    /// converge (the caller cuts it). `last_resort`: the step cannot be cut further, and
    /// contacts that cycle are held open ([`FREEZE_FLIPS`]). `start`: the increment of
    /// the unknowns the iterations start from, in the trial's own contact states (the
    /// answer of a first try of the same step, which [`Dynamics::advance_to`] redoes);
    /// `None`: the committed state carried along by the ground, in the committed states.
    fn step(
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
        let mut dq: Vec<f64> = match start {
            Some(s) => s.to_vec(),
            None => self.absolute_from_relative(&vec![0.0; n], dug),
        };
        let mut trial = self.trial_moving(&dq, dug);
        let mut prev_state = trial.state.clone();
        let mut prev_force = trial.force.clone();
        let mut flips = vec![0u32; trial.state.len()];
        let mut slip_flips = vec![0u32; trial.state.len()];
        let mut weight = vec![1.0f64; trial.state.len()];
        let mut frozen = vec![false; trial.state.len()];
        let size = {
            let b = crate::geometry::polygon::bbox(&self.cur.nodes);
            (b[2] - b[0]).hypot(b[3] - b[1]).max(1e-9)
        };
        let mut bal = self.balance(&terms, &dq, &trial);
        // per contact, the largest force (N) it carried closed in this try's iterations
        let mut closed_max = vec![0.0f64; trial.state.len()];
        // the out-of-balance norm of the last iteration (N), and whether its step was a
        // tangent one
        let mut last_rn = f64::INFINITY;
        let mut last_tangent = false;
        // the best out-of-balance norm so far (N) and the iteration that set it
        let (mut best_rn, mut best_it) = (f64::INFINITY, 0);
        let mut bonds_broken = false;
        // the closed ↔ open changes that break bonds, counted only where the joints have a
        // bond to break and the contact carries a force that matters on one side
        let bonded = self.law.broken_bond([0.0; 2]).is_some();
        let mut open_flips = OpenFlips::new(bonded, trial.state.len());
        for it in 0..self.settings.max_iterations {
            self.stats.iterations += 1;
            let negligible = self.settings.tolerance * bal.scale;
            open_flips.count(it, &trial, (&prev_state, &prev_force), negligible);
            // secant stiffness and damping of the trial states (the contacts in the trial
            // geometry, the blocks as `effective_into` says). A contact that keeps opening
            // and closing within the step sits at the kink of its law (touching with no
            // force: the chatter of a stiff contact), where the secant iteration cycles
            // between the open and the closed linearization; its normal spring then stays
            // in the matrix, weakened by a factor w that drops while the contact stays open
            // (so that a contact that really separates is soon left free) and returns to 1
            // when it closes.
            for k in 0..flips.len() {
                let open = trial.state[k] == ContactState::Open;
                if it > 0 && open != (prev_state[k] == ContactState::Open) {
                    flips[k] += 1;
                }
                let pair = [trial.state[k], prev_state[k]];
                if it > 0
                    && pair.contains(&ContactState::Stick)
                    && pair.contains(&ContactState::Slip)
                {
                    slip_flips[k] += 1;
                }
                if flips[k] >= FLIPS_BEFORE_ELASTIC {
                    weight[k] = if open {
                        weight[k] * OPEN_WEIGHT_DECAY
                    } else {
                        1.0
                    };
                }
                if !open {
                    closed_max[k] = closed_max[k].max(trial.force[k][0].hypot(trial.force[k][1]));
                }
                if (last_resort || closed_max[k] <= HOLD_OPEN_FORCE * bal.scale)
                    && flips[k] >= FREEZE_FLIPS
                    && !frozen[k]
                {
                    if super::tracing() {
                        eprintln!("  hold open: contact {k}");
                    }
                    frozen[k] = true;
                    self.stats.held_open += 1;
                }
            }
            if frozen
                .iter()
                .zip(&trial.state)
                .any(|(f, s)| *f && *s != ContactState::Open)
            {
                hold_open(&mut trial, &frozen);
                bal = self.balance(&terms, &dq, &trial);
            }
            let negligible = self.settings.tolerance * bal.scale;
            let changed = trial
                .state
                .iter()
                .zip(&prev_state)
                .enumerate()
                .any(|(k, (x, y))| {
                    x != y
                        && (trial.force[k][0].hypot(trial.force[k][1]) > negligible
                            || prev_force[k][0].hypot(prev_force[k][1]) > negligible)
                });
            if super::tracing() {
                eprintln!(
                    "t {t0:.4} h {h:.3e} it {it} residual {:.3e}",
                    bal.rn / bal.scale
                );
                for k in 0..trial.state.len() {
                    if trial.state[k] != prev_state[k] {
                        let c = &trial.mesh.contacts[k];
                        eprintln!(
                            "  contact {k} ({}-{}) {:?} -> {:?} force {:?} flips {} w {}",
                            c.block_l,
                            c.block_m,
                            prev_state[k],
                            trial.state[k],
                            trial.force[k],
                            flips[k],
                            weight[k]
                        );
                    }
                }
            }
            if it > 0 && bal.rn <= self.settings.tolerance * bal.scale && !changed {
                return Ok(Some(Accepted {
                    trial,
                    v: bal.v1,
                    a: bal.a1,
                    f_visc: bal.fv1,
                    h,
                    ground: g1,
                    ground_du: dug,
                    ground_v1: vg1,
                    frozen,
                }));
            }
            if bal.rn < STALL_PROGRESS * best_rn {
                (best_rn, best_it) = (bal.rn, it);
            } else if !last_resort && it - best_it >= STALL_ITERATIONS {
                if !bonds_broken && self.break_cycling_bonds(&open_flips, &frozen) {
                    // the iterations cycled on bonds that cannot hold: go on with them
                    // broken (once a try, as the static driver does)
                    bonds_broken = true;
                    trial = self.trial_moving(&dq, dug);
                    if frozen.iter().any(|&f| f) {
                        hold_open(&mut trial, &frozen);
                    }
                    bal = self.balance(&terms, &dq, &trial);
                    (best_rn, best_it) = (f64::INFINITY, it);
                    prev_state = trial.state.clone();
                    prev_force = trial.force.clone();
                    continue;
                }
                if super::tracing() {
                    eprintln!("  stalled: no progress since iteration {best_it}");
                }
                self.stats.stalled_steps += 1;
                return Ok(None);
            }
            prev_state = trial.state.clone();
            prev_force = trial.force.clone();
            // at the first iteration, the states of the last step (a contact exactly at
            // its friction limit evaluates as sticking, but it was slipping)
            let states = if it == 0 && start.is_none() {
                &self.committed.state
            } else {
                &trial.state
            };
            // the contacts' local stiffness in the matrix: secant, but for the anti-chatter
            // rules above
            let secant: Vec<LocalStiffness> = (0..self.springs.len())
                .map(|k| {
                    if frozen[k] {
                        return [[0.0; 2]; 2];
                    }
                    let mut l = secant_local(self.springs[k], states[k]);
                    if flips[k] >= FLIPS_BEFORE_ELASTIC {
                        l[0][0] = weight[k] * self.springs[k].kn;
                    }
                    if slip_flips[k] >= FLIPS_BEFORE_ELASTIC && states[k] != ContactState::Open {
                        l[1][1] = self.springs[k].ks;
                    }
                    l
                })
                .collect();
            // once no contact changes state, the step's problem is smooth but for the
            // slipping contacts' friction, which depends on their normal force: the secant
            // matrix leaves that out (and keeps kₛ on contacts that flipped between stick
            // and slip), so its iterations may contract slowly (0.79 an iteration on the
            // rocking drums of docs/performance.md, "Tangent steps in the dynamic driver");
            // a tangent step closes them in one or two. Taken only where the secant
            // iteration is slow ([`TANGENT_SLOW`]), and then until a state changes.
            let tangent = it > 1
                && !changed
                && (last_tangent || bal.rn > TANGENT_SLOW * last_rn)
                && (0..trial.state.len())
                    .any(|k| !frozen[k] && trial.state[k] == ContactState::Slip);
            last_rn = bal.rn;
            let geometry = self.blocks_geometry(&trial.mesh);
            let blocks = geometry.as_ref().map(|m| m.as_ref().unwrap_or(&trial.mesh));
            self.effective_into(blocks, &trial.mesh, &secant, &trial.state, &terms, false);
            if self.backend.factorize(&self.kbuf).is_err() {
                return Ok(None);
            }
            // the tangent step where it lowers the out-of-balance force; else the secant step
            let tangent_step = match tangent {
                true => self
                    .tangent_step(
                        &trial, blocks, &secant, &frozen, &terms, &dq, &bal, it, dug, size,
                    )
                    .filter(|s| s.2.rn < bal.rn),
                false => None,
            };
            last_tangent = tangent_step.is_some();
            let found = match tangent_step {
                Some(step) => Some(step),
                None => {
                    let mut x = bal.r.clone();
                    if self.backend.solve(&mut x).is_err() || !x.iter().all(|v| v.is_finite()) {
                        return Ok(None);
                    }
                    self.search(&terms, &dq, &x, &bal, it, &frozen, dug, size)
                }
            };
            let Some((cand, t, b, last)) = found else {
                return Ok(None);
            };
            dq = cand;
            trial = t;
            bal = if last {
                b
            } else {
                // `cbuf` holds C of the last candidate tried: assemble it for the one kept
                self.balance(&terms, &dq, &trial)
            };
        }
        Ok(None)
    }

    /// The tangent step of [`Dynamics::step`] from `dq` and the line search along it: the
    /// effective matrix with the contacts' tangent stiffness in the trial's states (the
    /// slipping contacts' friction–normal coupling, [`tangent_local`]; the normal springs
    /// of `secant`, which carry the anti-chatter weights), solved by GMRES preconditioned
    /// with the backend's factorization of the secant effective matrix (an inexact Newton
    /// step, to a tenth of the tolerance, as the static driver's). `None` when GMRES does
    /// not converge within [`TANGENT_MAX_ITERATIONS`] or the step leaves the model.
    #[allow(clippy::too_many_arguments)]
    fn tangent_step(
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
        let out = crate::solve::reuse::gmres_with_factor(
            self.tbuf.as_ref().expect("assembled above"),
            &mut *self.backend,
            &bal.r,
            tolerance,
            TANGENT_MAX_ITERATIONS,
        )?;
        self.stats.reused_factorizations += 1;
        self.stats.reuse_iterations += out.iterations;
        let step = self.search(terms, dq, &out.x, bal, it, frozen, dug, size);
        if super::tracing() {
            eprintln!(
                "  tangent step: GMRES {} iterations, ratio {:.3}",
                out.iterations,
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
    fn blocks_geometry(&self, trial: &Mesh) -> Option<Option<Mesh>> {
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
    fn damped_state(&self, c: usize) -> ContactState {
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
    fn rayleigh_local(&self, c: usize, state: ContactState) -> LocalStiffness {
        match state {
            ContactState::Open => [[0.0; 2]; 2],
            _ => secant_local(self.springs[c], self.damped_state(c)),
        }
    }

    /// The contacts' local dashpot matrices for the trial states `state`.
    fn dashpots(&self, state: &[ContactState]) -> Vec<LocalStiffness> {
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
    /// (1−α_f) c₁ a₁ K) and C of the dashpots in the trial states `state`, into `kbuf`;
    /// into `tbuf` when `second` (the tangent's, with the C of the `kbuf` built before
    /// it in the same iteration).
    ///
    /// The contacts in the trial's geometry `contacts`, the blocks' triangles (and their
    /// Kelvin–Voigt viscosity) in `blocks` (`None`: the step's start geometry;
    /// [`Dynamics::blocks_geometry`]), as the static driver's iteration matrix is on the
    /// last converged geometry (the out-of-balance force, which decides convergence, is
    /// always the trial geometry's). The interior rows of a block on the start geometry
    /// then stay the same within a step, and the condensed backend does not refactorize
    /// its interior after the step's first iteration (on the rocking drums of
    /// docs/performance.md, "The blocks' interiors on the step's start geometry", those
    /// refactorizations had taken a third of the run). The contacts stay in the trial's
    /// geometry: with them on the start's too, the seed arch's voussoirs, which turn by
    /// up to 10⁻² rad within a step of the collapse, took 2–11 times the iterations.
    fn effective_into(
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
            self.tbuf
                .get_or_insert_with(|| CsrMatrix::zeros(self.kbuf.pattern.clone()))
        } else {
            &mut self.kbuf
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
            self.tbuf.as_mut().expect("allocated above")
        } else {
            &mut self.kbuf
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

    /// Backtracking along the correction `x` from `dq` on the out-of-balance norm: where
    /// the full step overshoots (a contact cycling between its open and closed
    /// linearizations, each of which carries the iterate past the kink of the law), a
    /// shorter one lands near the kink. Returns the best of the tried steps: its unknowns,
    /// trial and balance, and whether it was the last one evaluated (then `cbuf` holds its
    /// C); `None` when even the full step leaves the model (a step larger than half its
    /// size, `size` in m, or not finite).
    #[allow(clippy::too_many_arguments)]
    fn search(
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
        let mut best: Option<(Vec<f64>, Trial, Balance)> = None;
        let mut best_is_last = false;
        let mut alpha = 1.0;
        for _ in 0..LINE_SEARCH_STEPS {
            let cand: Vec<f64> = dq.iter().zip(x).map(|(d, x)| d + alpha * x).collect();
            let dmax = cand.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if !dmax.is_finite() || dmax > 0.5 * size {
                break;
            }
            let mut t = self.trial_moving(&cand, dug);
            hold_open(&mut t, frozen);
            let b = self.balance(terms, &cand, &t);
            let decreased = b.rn <= bal.rn;
            best_is_last = best.as_ref().is_none_or(|(_, _, bb)| b.rn < bb.rn);
            if best_is_last {
                best = Some((cand, t, b));
            }
            // the first iteration's residual is that of the committed state, before any
            // inertia: its full step is the linearized step, always taken
            if decreased || it == 0 {
                break;
            }
            alpha *= 0.5;
        }
        best.map(|(c, t, b)| (c, t, b, best_is_last))
    }

    /// Elastic energy (J) of a state: blocks ½ ∫ σᵀ Dₑ⁻¹ σ, contacts ½ (Fₙ²/kₙ + Fₛ²/kₛ).
    fn elastic_energy(&self, mesh: &Mesh, stress: &[[f64; 3]], force: &[[f64; 2]]) -> f64 {
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

    fn commit(&mut self, acc: Accepted) {
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
    fn too_fast(&self, acc: &Accepted) -> bool {
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
    fn step_error(&self, acc: &Accepted, h: f64) -> f64 {
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
    fn advance_to(&mut self, target: f64) -> Result<bool> {
        let hmin = self.settings.dt / 2f64.powi(self.settings.max_cuts as i32);
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
                if super::tracing() {
                    let k: Vec<usize> = (0..released.len()).filter(|&k| released[k]).collect();
                    eprintln!("  release redo: contacts {k:?}");
                }
                // the redo starts from the first try's answer, which differs from the
                // redo's by the released contacts' small share of the start: 2–3
                // iterations instead of the 5–7 of a start from rest (docs/performance.md,
                // "The release redo from the first try")
                let first = accepted.as_ref().map(|acc| acc.trial.dq.clone());
                self.release(&released);
                let before = self.stats.iterations;
                accepted = self.step(h, last_resort, first.as_deref())?;
                self.stats.release_redos += 1;
                self.stats.release_redo_iterations += self.stats.iterations - before;
                saved = Some(start);
            }
            // the local error of an error-controlled step, computed once for the cut and
            // for the growth of the next step
            let error = match (&accepted, self.settings.adaptive) {
                (Some(acc), Some(_)) => self.step_error(acc, h),
                _ => 0.0,
            };
            let cut = match &accepted {
                None => true,
                // an impact the step cannot resolve: cut it (see `too_fast`)
                Some(acc) if h > hmin * (1.0 + 1e-9) && self.too_fast(acc) => {
                    if super::tracing() {
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
                    self.bonds_broken_here.clear();
                    self.commit(acc);
                    if super::tracing() {
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

    /// The contacts a converged step opens that were closed at its start, if any (with
    /// `impact_reset` and inertia: the steps [`Dynamics::advance_to`] redoes).
    fn released(&self, acc: &Accepted) -> Option<Vec<bool>> {
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
    fn release(&mut self, released: &[bool]) {
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
    fn true_force(&self, k: usize) -> [f64; 2] {
        if self.committed.state[k] == ContactState::Open {
            [0.0, 0.0]
        } else {
            self.committed.force[k]
        }
    }

    /// Centroid displacement (m) and rotation (rad) of a block, relative to the ground.
    pub fn block_motion(&self, b: usize) -> ([f64; 2], f64) {
        match self.mesh0.blocks[b].dofs {
            BlockDofs::Rigid { first, .. } => {
                let f = first as usize;
                let u = &self.committed.u;
                let g = self.ground_u;
                ([u[f] - g[0], u[f + 1] - g[1]], u[f + 2])
            }
            _ => {
                let blk = &self.mesh0.blocks[b];
                let disp: Vec<Point> = blk
                    .nodes
                    .clone()
                    .map(|n| self.node_displacement(n as usize))
                    .collect();
                fit_motion(self.mesh0, b, &disp)
            }
        }
    }

    /// Displacement (m) of node `n` relative to the ground (in the absolute frame, its
    /// motion less the foundation's).
    fn node_displacement(&self, n: usize) -> Point {
        let (p, q, g) = (self.cur.nodes[n], self.mesh0.nodes[n], self.ground_u);
        [p[0] - q[0] - g[0], p[1] - q[1] - g[1]]
    }

    fn outcome(&self, status: Status) -> Outcome {
        let node_disp = (0..self.cur.nodes.len())
            .map(|n| self.node_displacement(n))
            .collect();
        Outcome {
            status,
            u: self.committed.u.clone(),
            node_disp,
            stress: self.committed.stress.clone(),
            contact_forces: (0..self.committed.force.len())
                .map(|k| self.true_force(k))
                .collect(),
            contact_states: self.committed.state.clone(),
            contact_history: self.committed.history_of_all(self.committed.state.len()),
            stats: self.stats.clone(),
            load_factor: None,
            mechanism: None,
            current: Some(self.cur.clone()),
            history: None,
            capacity_curve: None,
            fallen: Vec::new(),
        }
    }
}

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

/// Names of the columns after the blocks' (documented in docs/scene-reference.md).
pub const EXTRA_COLUMNS: &[&str] = &[
    "ground_ax",
    "ground_ay",
    "open_contacts",
    "slipping_contacts",
    "E_kinetic",
    "E_elastic",
    "W_viscous",
    "W_contact",
    "W_gravity",
    "W_ground",
    "E_error",
];

/// Columns added in the absolute frame (`frame = "absolute"`): the ground's displacement
/// (m), integrated from a_g along the steps.
pub const ABSOLUTE_COLUMNS: &[&str] = &["ground_ux", "ground_uy"];

/// The time (s) at the end of step `k` of a run with time step `dt` lasting `duration`.
pub fn step_time(settings: &Settings, k: usize) -> f64 {
    (k as f64 * settings.dt).min(settings.duration.max(settings.dt))
}

/// The number of time steps of a run.
pub fn step_count(settings: &Settings) -> usize {
    (settings.duration / settings.dt - 1e-9).ceil().max(1.0) as usize
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

/// [`run`], or its continuation from a checkpoint `from` of the same scene: the rows and
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
        let bs = d.backend.stats();
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
    let every = scene.output.every.max(1);
    let frames = scene.output.vtk;
    let mut status = Status::Stable;
    if !resumed {
        let r0 = row(&d);
        monitor.row(&r0)?;
        history.rows.push(r0);
        if frames {
            history.frames.push((0.0, 0));
            if monitor.wants_frames() {
                monitor.frame(0, 0.0, &d.outcome(Status::Stable))?;
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
        if frames && (k % every == 0 || k == steps) {
            history.frames.push((d.time, k));
            if monitor.wants_frames() {
                monitor.frame(k, d.time, &d.outcome(Status::Stable))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn inverse_of_the_elastic_matrix() {
        let d = crate::material::elastic_matrix(56e9, 21e9, crate::scene::Plane::Strain);
        let c = invert3(d);
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| d[i][k] * c[k][j]).sum();
                assert!(
                    (p - f64::from(u8::from(i == j))).abs() < 1e-12,
                    "{i} {j} {p}"
                );
            }
        }
    }

    #[test]
    fn family_members() {
        assert_eq!(Scheme::hht(0.0), Scheme::newmark());
        // generalized-α with ρ∞ = 1 is the trapezoidal rule at the mid-point
        let g = Scheme::generalized_alpha(1.0);
        assert!((g.alpha_m - 0.5).abs() < 1e-15 && (g.alpha_f - 0.5).abs() < 1e-15);
        assert!((g.gamma - 0.5).abs() < 1e-15 && (g.beta - 0.25).abs() < 1e-15);
        // ρ∞ = 0: asymptotic annihilation, γ = 3/2, β = 1
        let g = Scheme::generalized_alpha(0.0);
        assert!((g.gamma - 1.5).abs() < 1e-15 && (g.beta - 1.0).abs() < 1e-15);
    }
}
