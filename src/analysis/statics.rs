//! Nonlinear static and capacity analysis (METHOD.md §4, seed §4): loads in increments of
//! a load factor; in each increment, iterations in which the contacts' excess forces are
//! re-applied (the residual λF − F_int) until the out-of-balance force is below a relative
//! tolerance and no contact changes state; the geometry is updated after each converged
//! increment. Failure (a mechanism) is a non-convergence after increment cutting; the
//! capacity analysis brackets the critical load factor between the last converged and
//! the first failed increment.

use super::config::{secant_local, tangent_local, Committed, Inputs, Trial};
use super::mechanism::{classify, Mechanism};
use super::progress::{Increment, Progress};
use super::{Outcome, Stats, Status};
use crate::assembly::{loads, LocalStiffness, Ranks, System};
use crate::geometry::polygon::Point;
use crate::material::{ContactLaw, ContactState, JointLaw, PerContact};
use crate::mesh::Mesh;
use crate::scene::{AnalysisType, Scene};
use crate::solve::LinearBackend;
use crate::{Error, Result};
use dfem_kernels::CsrMatrix;
use std::time::Instant;

pub mod arc_length;

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

/// Settings of the nonlinear driver (`[analysis]` keys, with these defaults).
#[derive(Debug, Clone)]
pub struct Settings {
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
    /// (`fallout`, default off; `Driver::fall_out`).
    pub fallout: bool,
    /// Keep the held secant factorization across load increments (`reuse_across_increments`,
    /// default off): the first corrections of an increment are then solved by conjugate
    /// gradients preconditioned with it, corrected for the contacts that changed state
    /// (`Driver::reuse`, docs/theory.md "Factorizations across increments"), instead of
    /// a refactorization. Fewer factorizations, but on the walls of docs/performance.md no
    /// faster (P2) or never taken (10⁵ unknowns: hundreds of contacts change state
    /// between increments), hence off.
    pub reuse_across_increments: bool,
    /// Displacement control (`push_block`, `push_displacement`), if any.
    pub push: Option<Push>,
    /// Arc-length path following of the push (`path = "arc_length"`), if any.
    pub arc: Option<arc_length::ArcLength>,
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
    pub(super) fn direction(&self) -> (Point, f64) {
        let (h, v) = (self.horizontal, self.vertical.unwrap_or(0.0));
        let length = h.hypot(v);
        if length > 0.0 {
            ([h / length, v / length], length)
        } else {
            ([1.0, 0.0], length)
        }
    }

    fn from_scene(scene: &Scene) -> Result<Option<Push>> {
        let x = &scene.analysis.extra;
        let place = super::analysis_place;
        let (name, disp) = match (x.get("push_block"), x.get("push_displacement")) {
            (None, None) => return Ok(None),
            (Some(b), Some(d)) => (b, d),
            (Some(_), None) => {
                return Err(Error::new("push_block is given without push_displacement")
                    .place(place("push_block"))
                    .fix("add push_displacement = <m> (horizontal, vertical free) or [<m>, <m>]"))
            }
            (None, Some(_)) => {
                return Err(Error::new("push_displacement is given without push_block")
                    .place(place("push_displacement"))
                    .fix("add push_block = \"<name of the free rigid block to push>\""))
            }
        };
        let name = name.as_str().ok_or_else(|| {
            Error::new("push_block is not a block name")
                .place(place("push_block"))
                .fix("give the name of a block as a string, for example \"top\"")
        })?;
        let block = scene.block_index(name).ok_or_else(|| {
            Error::new(format!("there is no block '{name}'"))
                .place(place("push_block"))
                .fix("name a block of the scene (generated walls call their top beam \"top\")")
        })?;
        let b = &scene.blocks[block];
        if b.support != crate::scene::Support::Free || b.kind != crate::scene::BlockKind::Rigid {
            return Err(Error::new(format!("block '{name}' is not a free rigid block"))
                .place(place("push_block"))
                .line(b.line)
                .fix("push a free block of kind = \"rigid\" (a loading beam); fixed blocks move with their 'prescribed' key"));
        }
        let num = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        let bad = || {
            Error::new("push_displacement is not a displacement")
                .place(place("push_displacement"))
                .fix("give a finite number of m (horizontal; the vertical motion free) or [horizontal, vertical] in m")
        };
        let (horizontal, vertical) = match disp {
            toml::Value::Array(a) if a.len() == 2 => {
                let h = num(&a[0]).ok_or_else(bad)?;
                let v = num(&a[1]).ok_or_else(bad)?;
                (h, Some(v))
            }
            v => (num(v).ok_or_else(bad)?, None),
        };
        if !horizontal.is_finite() || !vertical.unwrap_or(0.0).is_finite() {
            return Err(bad());
        }
        if scene.analysis.kind != AnalysisType::Static {
            return Err(Error::new("displacement control belongs to a static analysis")
                .place(place("push_block"))
                .fix("set [analysis] type = \"static\" (the capacity analysis raises a load factor instead)"));
        }
        Ok(Some(Push {
            block,
            horizontal,
            vertical,
        }))
    }
}

impl Settings {
    pub fn from_scene(scene: &Scene) -> Result<Settings> {
        let x = &scene.analysis.extra;
        let place = super::analysis_place;
        let strategy = match x.get("strategy") {
            None => Strategy::Secant,
            Some(v) => v.as_str().and_then(Strategy::parse).ok_or_else(|| {
                Error::new("unknown strategy")
                    .place(place("strategy"))
                    .fix("use \"initial\", \"secant\" or \"newton\"")
            })?,
        };
        let num = |k: &str, d: f64, lo: f64, hi: f64| super::analysis_number(scene, k, d, lo, hi);
        // an `[analysis]` switch: true or false, `d` when absent
        let switch = |k: &str, d: bool| -> Result<bool> {
            match x.get(k) {
                None => Ok(d),
                Some(v) => v.as_bool().ok_or_else(|| {
                    Error::new(format!("'{k}' must be true or false"))
                        .place(place(k))
                        .fix(format!("write {k} = true or {k} = false (default {d})"))
                }),
            }
        };
        let default_iters = if strategy == Strategy::Initial {
            2000.0
        } else {
            300.0
        };
        Settings {
            strategy,
            tolerance: num("tolerance", 1e-6, 1e-14, 0.1)?,
            max_iterations: num("max_iterations", default_iters, 1.0, 1e6)? as usize,
            max_cuts: num("max_cuts", 6.0, 0.0, 30.0)? as usize,
            initial_step: num("initial_step", 0.05, 1e-9, 1e3)?,
            bracket: num("bracket", 1e-3, 1e-9, 0.5)?,
            line_search: switch("line_search", strategy != Strategy::Initial)?,
            fallout: switch("fallout", false)?,
            reuse_across_increments: switch("reuse_across_increments", false)?,
            push: Push::from_scene(scene)?,
            arc: None,
        }
        .with_arc(scene)
    }

    fn with_arc(mut self, scene: &Scene) -> Result<Settings> {
        self.arc = arc_length::ArcLength::from_scene(scene, self.push.as_ref())?;
        Ok(self)
    }
}

/// ε of the blended step K_s + ε K₀ taken when the secant matrix is singular.
const BLEND: f64 = 1e-2;

/// ε of the mechanism step K_s + ε K₀ of [`Driver::free_motion`]: small enough that the
/// step is the free motion of the blocks held only by slipping and open contacts, many
/// times the distance to where one of them sticks, which the search then finds.
const MODE_BLEND: f64 = 1e-6;
/// A singular iteration whose line search keeps more than this fraction of the
/// out-of-balance norm is followed by a [`Driver::free_motion`].
const MODE_PROGRESS: f64 = 0.9;
/// Consecutive singular iterations after which a slow one is followed by a
/// [`Driver::free_motion`].
const MODE_STREAK: usize = 8;
/// Finest step 2⁻ᵏ of the grid on which [`Driver::free_motion`] seeks its roots.
const MODE_GRID: usize = 24;
/// A block is free (held only by slipping and open contacts) when its motion in the
/// mechanism step is this many times its motion in the iteration's correction (10⁴ where
/// it is free, the ratio of the two ε, and 1 elsewhere).
const MODE_RATIO: f64 = 100.0;
/// The free motion is taken when the out-of-balance norm after it is below this many
/// times the norm after the iteration's own step: the norm is not what the motion
/// lowers (see [`Driver::free_motion`]), and the next iteration, with the contact that
/// stuck now holding the group, removes what it leaves. On the 60 × 60 wall of
/// docs/performance.md ("Growth") 3 converged in 58 iterations, 1 (only motions that
/// lower the norm) in 99 (measured with the motion after every singular iteration,
/// before [`MODE_STREAK`]).
const MODE_ACCEPT: f64 = 3.0;
/// At most this many groups of free blocks move in one iteration (those with the largest
/// out-of-balance force along their motion).
const MODE_GROUPS: usize = 8;

/// Keys of `[analysis]` read by this driver.
pub const KEYS: &[&str] = &[
    "strategy",
    "tolerance",
    "max_iterations",
    "max_cuts",
    "initial_step",
    "bracket",
    "line_search",
    "fallout",
    "reuse_across_increments",
    "push_block",
    "push_displacement",
    "gravity_steps",
    "path",
    "arc_length",
    "accept_residual",
];

/// The loads of one phase as functions of its load factor.
struct Phase {
    /// External force at factor s: base + s · step (N).
    base: Vec<f64>,
    step: Vec<f64>,
    /// Prescribed translation increment of each block per unit factor (m).
    presc_step: Vec<Point>,
    /// Prescribed increments of single unknowns per unit factor: (unknown, m or rad).
    pin_step: Vec<(usize, f64)>,
    /// Displacement control: the pushed block, whose displacement and reaction are
    /// recorded after every converged increment.
    record: Option<usize>,
}

/// The nonlinear model being analysed.
pub struct Driver<'a> {
    scene: &'a Scene,
    settings: Settings,
    system: System,
    /// The law of each contact (its joint's, `Scene::joint_of`).
    law: PerContact<JointLaw>,
    area: Vec<f64>,
    cur: Mesh,
    committed: Committed,
    kbuf: CsrMatrix,
    /// The contacts' local stiffnesses `kbuf` was last assembled with on `cur`, with no
    /// unknown pinned and nothing added since (`None`: unknown), for
    /// [`System::stiffness_update`].
    kbuf_local: Option<Vec<LocalStiffness>>,
    /// A second persistent matrix buffer, on `cur` as `kbuf`: the matrix that the held
    /// secant factorization corrected for a low-rank change solves with
    /// ([`Driver::near_into_aux`]), while `kbuf` holds the iteration matrix; with what
    /// `aux_local` says it holds, as `kbuf_local`. Its values are allocated at its first
    /// use.
    aux: CsrMatrix,
    aux_local: Option<Vec<LocalStiffness>>,
    /// Whether the secant matrix that the main backend holds factorized (`Held::Secant`;
    /// its values: [`LinearBackend::factorized_values`]) was assembled on `cur` (false
    /// once a converged increment moved the geometry, [`Driver::commit`]).
    held_current: bool,
    /// The secant matrix in the held factorization's contact states assembled on `cur`,
    /// when that factorization is of an older geometry (computed once per increment,
    /// [`Driver::near_into_aux`]; empty: not yet).
    held_on_cur: Vec<f64>,
    /// GMRES on the held secant factorization failed on a tangent step of the current
    /// increment: the increment's later tangent steps do not try it again
    /// ([`Driver::tangent_with_secant_factor`]).
    gmres_failed: bool,
    /// The elastic stiffness K₀ on `cur` (no unknowns pinned), assembled when first needed
    /// after a commit ([`Driver::elastic_on_cur`]).
    k0: Option<CsrMatrix>,
    /// The increment iterated is a capacity search's probe of the load factor, which
    /// stops at shorter stall windows ([`Driver::stall_window`]); the failure that closes
    /// the search's bracket is iterated again with the full ones.
    probing: bool,
    /// Out-of-balance norm (N) that counts as converged in the current iteration
    /// (tolerance × the force scale): a tangent correction by GMRES is solved to a tenth of
    /// it ([`Driver::tangent_with_secant_factor`]).
    converged_norm: f64,
    /// The smallest force that measures the out-of-balance force (N): the norm of the
    /// load an in-situ stress leaves out of balance (the excavation), which is what the
    /// run releases when there is no gravity; zero without an in-situ stress.
    scale_floor: f64,
    pub stats: Stats,
    backend: &'a mut dyn LinearBackend,
    lu: Option<Box<dyn LinearBackend>>,
    /// What the main backend holds factorized.
    held: Held,
    /// The last failing increment (unknowns) and the contact states of its last trial,
    /// for the mechanism.
    pub failure_mode: Option<Failure>,
    /// Prescribed translation applied so far, per block (m).
    presc_total: Vec<Point>,
    /// Where progress is reported (none: silent), and the state of the report.
    progress: Option<&'a mut dyn Progress>,
    report: Report,
    /// Unknowns whose increments are prescribed in the current increment, with the
    /// increments (m, rad): their rows and columns are taken out of the solves and their
    /// out-of-balance forces are reactions.
    pins: Vec<(usize, f64)>,
    /// The curve of the displacement-controlled phase so far.
    push_curve: Vec<super::curve::CurvePoint>,
    /// Per contact: its changes of state in the iterations of the current arc-length
    /// increment (`arc_length`; empty under displacement control).
    flips: Vec<u32>,
    /// Per contact: the linear law (a chord of its law) that it keeps for the rest of the
    /// current arc-length increment (the contact-state corrector, docs/theory.md,
    /// "Contact-state corrector", Eq. F1; empty, or all `None`, elsewhere).
    frozen: Vec<Option<Frozen>>,
    /// The bonds broken in the current increment ([`Driver::break_cycling_bonds`]): the
    /// contact and its committed history before, put back if the increment fails.
    bonds_broken_here: Vec<(usize, crate::material::History)>,
    /// The blocks that fell out ([`Driver::fall_out`]), in the order they fell.
    fallen: Vec<usize>,
    /// The contacts that touch a fallen block, which carry no force.
    fallen_contacts: Vec<usize>,
    /// The unknowns of the fallen blocks, held where the blocks fell out.
    fallen_pins: Vec<(usize, f64)>,
    /// Configurations of trials no longer needed (at most [`SPARE_MESHES`]), whose memory
    /// the next trials reuse ([`Driver::recycle`]; all of `cur`'s topology, which a static
    /// run never changes).
    spare: std::sync::Mutex<Vec<Mesh>>,
}

/// The most trial configurations [`Driver::recycle`] keeps: the line search evaluates
/// one trial at a time and keeps the best, the iteration one, so that two spares serve
/// nearly every trial; more would only hold memory (a mesh is 1.5 MB on the rigid P2 wall
/// of docs/performance.md, 9,480 contacts, and grows with the contacts).
const SPARE_MESHES: usize = 2;

/// A contact held in one state of its law for the rest of an arc-length increment: a
/// fixed linear law through its force at the iterate where it was frozen,
/// F(Δδ) = F* + T (Δδ − Δδ*) (docs/theory.md, Eq. F1: T the chord from the committed
/// force), smooth where the law has a kink.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Frozen {
    /// Δδ* (m): the relative displacement increment where the law was linearized.
    pub d: [f64; 2],
    /// F* (N): the law's force there (normal, shear).
    pub f: [f64; 2],
    /// T (N/m): the frozen law's slope (rows Fₙ, Fₛ; columns δₙ, δₛ), the chord of
    /// `arc_length::chord_law`.
    pub t: LocalStiffness,
    /// The law's state there, which the contact keeps.
    pub state: ContactState,
}

impl Frozen {
    /// The force (N) of the frozen law at the increment of relative displacement `d` (m).
    pub fn force(&self, d: [f64; 2]) -> [f64; 2] {
        let dd = [d[0] - self.d[0], d[1] - self.d[1]];
        [
            self.f[0] + self.t[0][0] * dd[0] + self.t[0][1] * dd[1],
            self.f[1] + self.t[1][0] * dd[0] + self.t[1][1] * dd[1],
        ]
    }
}

/// What the progress report needs between calls.
#[derive(Debug, Clone, Default)]
struct Report {
    phase: &'static str,
    /// Load factor of the phase per unit of the phase's factor.
    scale: f64,
    /// Converged increments of the phase so far.
    increments: usize,
    /// Iterations and relative residual of the last converged increment.
    iterations: usize,
    residual: f64,
}

/// The matrix whose factorization the main backend holds.
#[derive(Debug, Clone, PartialEq)]
enum Held {
    Nothing,
    /// The elastic stiffness of the initial configuration.
    K0,
    /// A secant stiffness, with the contact states it was assembled for.
    Secant(Vec<ContactState>),
}

/// The external force along a line search ([`Driver::line_search_along`]) at the step
/// length α.
enum Load<'v> {
    /// Fixed (N): the static driver's increments.
    Fixed(&'v [f64]),
    /// `base` + (`lam` + α `dlam`) `p` (N): the arc-length corrector, whose load factor
    /// λ moves by δλ = `dlam` along the full step (docs/theory.md, "Arc length").
    Along {
        base: &'v [f64],
        p: &'v [f64],
        lam: f64,
        dlam: f64,
    },
}

impl Load<'_> {
    /// The external force (N) at the step length `alpha`.
    fn at(&self, alpha: f64) -> std::borrow::Cow<'_, [f64]> {
        match self {
            Load::Fixed(f) => std::borrow::Cow::Borrowed(f),
            Load::Along { base, p, lam, dlam } => base
                .iter()
                .zip(p.iter())
                .map(|(b, q)| b + (lam + alpha * dlam) * q)
                .collect(),
        }
    }
}

/// A secant correction reuses the held factorization as a preconditioner when at most this
/// many contacts changed state since it was computed. Each changed contact is a rank-1 or
/// rank-2 change of K, and conjugate gradients need about one iteration per unit of rank
/// plus three for the change of geometry (measured on the 30×30 wall of
/// docs/performance.md: 0 changes → 3 iterations, 5–9 → 6–10, 20–24 → 18–25), while one
/// iteration (a solve pair and a product with K) costs a tenth to a twentieth of a numeric
/// factorization on the walls of docs/performance.md. Since the low-rank path
/// ([`Driver::changed`]) takes the changes on an unchanged geometry, this applies to the
/// first correction of an increment (a new geometry: the held factorization is then a
/// preconditioner only) and to changes the backend refused; on the P2 walls the other
/// first corrections come after 8–2,500 changes (5 of the deformable wall's 35 take
/// conjugate gradients, none of the rigid wall's), so the limit was left as it was.
const REUSE_MAX_CHANGES: usize = 4;
/// The iteration matrix is updated ([`System::stiffness_update`]) rather than assembled
/// again when at most 1/`UPDATE_MAX_SHARE` of the contacts changed their local stiffness:
/// the update finds the entries and elements a changed contact touches one by one, which
/// on the rigid P2 wall of docs/performance.md costs more than assembling all contacts
/// once 1/8 of them changed (a tangent step after a secant one changes every slipping
/// contact's).
const UPDATE_MAX_SHARE: usize = 32;
/// GMRES iterations of a tangent correction preconditioned with the held secant
/// factorization ([`Driver::tangent_with_secant_factor`]) after which the tangent matrix is
/// factorized with LU instead: an LU factorization of the tangent costs about 4–5
/// Cholesky factorizations of the secant matrix, or 40 preconditioned iterations, on the
/// P2 wall of docs/performance.md.
const TANGENT_MAX_ITERATIONS: usize = 30;
/// A tangent correction of the secant strategy that GMRES on the secant factorization did
/// not solve is solved with an LU factorization of the tangent only when the held Cholesky
/// factor has at most this many entries; above, the secant correction is taken instead.
/// On the rigid 10⁶-unknown wall of docs/performance.md (Cholesky factor 1.66·10⁸
/// entries, 1.3 GB) the LU raised the resident memory from 5.6 to 11.6 GB and failed; on
/// the 10⁵-unknown wall (1.28·10⁷ entries) it fits in well under 1 GB. 5·10⁷ Cholesky
/// entries (0.4 GB) lets an LU of up to about 4× that (2.4 GB with its indices) through.
const TANGENT_LU_MAX_ENTRIES: usize = 50_000_000;
/// The loosest relative residual of a tangent correction by GMRES.
const TANGENT_TOLERANCE: f64 = 1e-3;
/// Conjugate-gradient iterations after which the reused factorization stops paying and the
/// secant matrix is refactorized.
const REUSE_MAX_ITERATIONS: usize = 8;
/// On the rigid P2 wall a secant correction is solved with the held factorization
/// corrected for the change ([`Driver::changed`]) when at most this many contacts changed
/// state since it was computed (each a change of rank ≤ 2); larger models allow more
/// ([`Driver::low_rank_limit`]). Measured on the rigid P2 wall of docs/performance.md (each correction timed
/// in the driver, one window): with 64 (and rank 128) the corrections change a median 22
/// contacts and cost 0.45 of a refactorization; with 128 (and rank 256) the held factor
/// is kept longer, the corrections change a median 55 contacts and cost 0.80 of one,
/// for 39 factorizations instead of 47.
const LOW_RANK_MAX_CHANGES: usize = 64;
/// Unknowns of the rigid P2 wall, where [`LOW_RANK_MAX_CHANGES`] was measured. The
/// break-even rank of the correction grows with the model ([`Driver::low_rank_limit`]).
const LOW_RANK_REFERENCE_DOFS: f64 = 4860.0;
/// The most contacts a low-rank correction takes on any model: the backend refuses ranks
/// above its own limit (`dfem_kernels::faer_backend::CHANGED_MAX_RANK` = 256), and a
/// contact that changed state is a change of rank 1 or 2.
const LOW_RANK_CAP: usize = 256;
/// Relative residual of a correction computed with a reused factorization: far below the
/// out-of-balance tolerances (≥ 1e-8), so the iterations see no difference.
const REUSE_TOLERANCE: f64 = 1e-10;

/// An increment stops as not converged when its out-of-balance norm has not fallen below
/// [`STALL_PROGRESS`] times its best value for this many iterations. Past the limit load
/// the secant iterations stagnate at a fixed residual (a toppling block: 9 % of the load,
/// for all 300 iterations), while converging increments near the limit, where contacts
/// open and slip in waves, still gain 10 % within 60 iterations (the 30×30 wall of
/// docs/performance.md: its slowest increment improves by that in at most 25).
const STALL_ITERATIONS: usize = 60;
/// The stall windows of a capacity search's probes ([`Driver::stall_window`]): secant
/// iterations, then tangent steps. Half the secant window still covers the slowest
/// converging increment measured near the limit (10 % gained within 25 iterations, the
/// 30×30 wall above); a probe that fails within them only narrows the bracket, and the
/// failure that closes it is confirmed with the full windows.
const PROBE_STALL_ITERATIONS: usize = 30;
const PROBE_TANGENT_STALL_ITERATIONS: usize = 10;
/// A bonded contact that has changed between closed and open this many times in an
/// increment's iterations breaks ([`Driver::break_cycling_bonds`]): closed → open →
/// closed → open. The dynamic driver breaks them likewise where a try stalls
/// (`Dynamics::break_cycling_bonds`).
const BOND_BREAK_FLIPS: u32 = 3;
/// Step lengths 1, ½, ¼, ⅛ of the line search on the out-of-balance norm.
const LINE_SEARCH_STEPS: usize = 4;
/// Step lengths 1 … 2⁻¹¹ of the line search along the tangent step that replaces a secant
/// step which does not lower the out-of-balance norm.
const SAFEGUARD_STEPS: usize = 12;
/// Fallout ([`Driver::fall_out`]): a failure mode that moves at most this many blocks, or
/// [`FALLOUT_MAX_SHARE`] of the free blocks if that is more, is a local failure (key
/// blocks falling out of a tunnel's roof: 6, then 6 behind them, of the 1,348 blocks of
/// the growth bench's excavation at s = 0.55 m, docs/performance.md); a larger one is the
/// structure's.
const FALLOUT_MAX_BLOCKS: usize = 8;
/// See [`FALLOUT_MAX_BLOCKS`].
const FALLOUT_MAX_SHARE: f64 = 0.01;
/// Fraction of the best residual an iteration must reach to count as progress.
const STALL_PROGRESS: f64 = 0.9;

/// The failing increment: its unknowns (the mode), the states and forces of its last
/// trial, and the external force resultant on every block (N).
#[derive(Debug, Clone)]
pub struct Failure {
    pub mode: Vec<f64>,
    pub states: Vec<ContactState>,
    pub forces: Vec<[f64; 2]>,
    pub loads: Vec<[f64; 2]>,
}

/// Why an increment did not converge.
#[derive(Debug, Clone)]
enum IncrementFailure {
    NoConvergence { residual: f64 },
    Divergence,
}

impl<'a> Driver<'a> {
    pub fn new(
        scene: &'a Scene,
        mesh: &Mesh,
        ranks: Option<&Ranks>,
        backend: &'a mut dyn LinearBackend,
    ) -> Result<Driver<'a>> {
        let settings = Settings::from_scene(scene)?;
        let system = System::new(scene, mesh).distributed(ranks);
        // a failed factorization only says "singular" here: no LDLᵀ for its pivot's value
        backend.set_failed_pivot_value(false);
        let law = PerContact::of_scene(scene, mesh);
        let t = scene.model.thickness;
        let area = mesh.contacts.iter().map(|c| c.length * t).collect();
        let kbuf = CsrMatrix::zeros(system.plan.pattern().clone());
        // no values until the first correction across a change of state needs them
        // (`near_into_aux`): most runs never do, and on the 10⁶-unknown wall they are
        // as large as the matrix's
        let aux = CsrMatrix {
            pattern: kbuf.pattern.clone(),
            values: Vec::new(),
        };
        Ok(Driver {
            scene,
            settings,
            system,
            law,
            area,
            cur: mesh.clone(),
            committed: match &scene.in_situ {
                Some(f) => Committed::in_situ(mesh, f, scene.model.thickness),
                None => Committed::zero(mesh),
            },
            kbuf,
            kbuf_local: None,
            aux,
            aux_local: None,
            held_current: false,
            held_on_cur: Vec::new(),
            gmres_failed: false,
            k0: None,
            probing: false,
            converged_norm: 0.0,
            scale_floor: 0.0,
            stats: Stats {
                dofs: mesh.n_dofs,
                contacts: mesh.contacts.len(),
                triangles: mesh.triangles.len(),
                ..Default::default()
            },
            backend,
            lu: None,
            held: Held::Nothing,
            failure_mode: None,
            presc_total: vec![[0.0; 2]; mesh.blocks.len()],
            progress: None,
            report: Report::default(),
            pins: Vec::new(),
            push_curve: Vec::new(),
            flips: Vec::new(),
            frozen: Vec::new(),
            fallen: Vec::new(),
            fallen_contacts: Vec::new(),
            bonds_broken_here: Vec::new(),
            fallen_pins: Vec::new(),
            spare: std::sync::Mutex::new(Vec::new()),
        })
    }

    /// Give back a trial no longer needed: its configuration is kept (up to
    /// [`SPARE_MESHES`]) for the next trial to be written into
    /// ([`super::config::moved_reusing`]) instead of a copy of `cur`.
    fn recycle(&self, t: Trial) {
        self.keep_spare(t.mesh);
    }

    /// [`Driver::recycle`] for a configuration of `cur`'s topology.
    fn keep_spare(&self, mesh: Mesh) {
        let mut spare = self.spare.lock().unwrap_or_else(|e| e.into_inner());
        if spare.len() < SPARE_MESHES {
            spare.push(mesh);
        }
    }

    /// Evaluate the increment `dq` (and the prescribed translations `presc`) from the
    /// committed state; the contacts held by the contact-state corrector
    /// ([`Driver::frozen`]) take the force of their frozen law (Eq. F1), the difference
    /// from the true law's force mapped into the internal forces.
    fn trial(&self, dq: &[f64], presc: &[Point]) -> Trial {
        let spare = self.spare.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut t = self.inputs().evaluate_reusing(dq, presc, spare);
        self.held_contacts(
            &t.mesh,
            Some,
            &mut t.force,
            &t.rel,
            Some(&mut t.state),
            &mut t.f_int,
        );
        t
    }

    /// What a trial of this driver evaluates against ([`Inputs`]): its model, the last
    /// converged configuration and state, the contacts' laws and areas.
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

    /// The contacts held by the contact-state corrector take the force of their frozen law
    /// and the fallen ones none, the differences mapped into `f_int` (on `mesh`): the
    /// frozen contacts in ascending order, then the fallen ones. `slot(k)`: where contact
    /// k's force, relative displacement and state are in `force`, `rel` and `state`
    /// (`None`: not evaluated, left alone).
    fn held_contacts(
        &self,
        mesh: &Mesh,
        slot: impl Fn(usize) -> Option<usize>,
        force: &mut [[f64; 2]],
        rel: &[[f64; 2]],
        state: Option<&mut [ContactState]>,
        f_int: &mut [f64],
    ) {
        // contact k (slot i) now carries `f` in state `s`, the change of its force mapped
        // into f_int
        let mut state = state;
        let mut hold =
            |i: usize, k: usize, f: [f64; 2], s: ContactState, force: &mut [[f64; 2]]| {
                let delta = [f[0] - force[i][0], f[1] - force[i][1]];
                if delta != [0.0, 0.0] {
                    let map = crate::assembly::contact_map(mesh, &mesh.contacts[k]);
                    crate::assembly::add_mapped_force(&map, delta, f_int);
                }
                force[i] = f;
                if let Some(st) = state.as_deref_mut() {
                    st[i] = s;
                }
            };
        for (k, fr) in self.frozen.iter().enumerate() {
            if let (Some(fr), Some(i)) = (fr, slot(k)) {
                hold(i, k, fr.force(rel[i]), fr.state, force);
            }
        }
        for &k in &self.fallen_contacts {
            if let Some(i) = slot(k) {
                hold(i, k, [0.0, 0.0], ContactState::Open, force);
            }
        }
    }

    /// The internal forces (N) of [`Driver::trial`] for the increment `dq`, computed from
    /// the elements of `part` only ([`Inputs::evaluate_part`]; the frozen and
    /// fallen contacts of the part adjusted as in `trial`): at the unknowns of the blocks
    /// `part` was made for ([`super::config::Part::of_blocks`]) `trial`'s F_int to the
    /// bit, at the cost of the part's elements.
    fn f_int_of_part(&self, dq: &[f64], presc: &[Point], part: &super::config::Part) -> Vec<f64> {
        let spare = self.spare.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut t = self.inputs().evaluate_part(dq, presc, spare, part);
        self.held_contacts(
            &t.mesh,
            |k| part.contacts.binary_search(&k).ok(),
            &mut t.force,
            &t.rel,
            None,
            &mut t.f_int,
        );
        self.keep_spare(t.mesh);
        t.f_int
    }

    /// The contacts' local stiffness matrices (N/m) in the given states; `newton` adds the
    /// slip contacts' friction–normal coupling, with the sign of the shear force in `trial`.
    fn local_stiffness(
        &self,
        trial: &Trial,
        states: &[ContactState],
        newton: bool,
    ) -> Vec<LocalStiffness> {
        self.local_of(&trial.force, states, newton)
    }

    /// The contacts' secant local stiffness matrices (N/m) in the given states (those of
    /// [`Driver::local_stiffness`] without `newton`, which need no trial).
    fn secant_local(&self, states: &[ContactState]) -> Vec<LocalStiffness> {
        self.local_of(&[], states, false)
    }

    /// [`Driver::local_stiffness`] with the contact forces `force` (N; read for the sign of
    /// the shear force when `newton`).
    fn local_of(
        &self,
        force: &[[f64; 2]],
        states: &[ContactState],
        newton: bool,
    ) -> Vec<LocalStiffness> {
        (0..self.area.len())
            .map(|k| {
                let law = self.law.get(k);
                let s = law.springs(self.area[k]);
                if self
                    .flips
                    .get(k)
                    .is_some_and(|&n| n >= arc_length::FLIP_LIMIT)
                {
                    // a contact that keeps changing state at the kink of its law keeps its
                    // elastic springs: they bound every tangent of the law, so the
                    // iterations contract to the state at the kink instead of cycling
                    return [[s.kn, 0.0], [0.0, s.ks]];
                }
                if newton {
                    tangent_local(s, states[k], force[k][1], law.tan_phi())
                } else {
                    secant_local(s, states[k])
                }
            })
            .collect()
    }

    fn elastic_local(&self) -> Vec<LocalStiffness> {
        self.area
            .iter()
            .enumerate()
            .map(|(k, &a)| crate::assembly::diagonal(self.law.get(k).springs(a)))
            .collect()
    }

    /// Take the pinned unknowns out of `k`: their rows and columns are zeroed but for the
    /// diagonal (kept, or the mean diagonal where it is not positive), so that a solve
    /// leaves them unchanged when their right-hand side is zero.
    fn pin_rows(pins: &[(usize, f64)], k: &mut CsrMatrix) {
        if pins.is_empty() {
            return;
        }
        let n = k.pattern.n();
        let mut pinned = vec![false; n];
        for &(d, _) in pins {
            pinned[d] = true;
        }
        let pattern = k.pattern.clone();
        let rp = pattern.row_ptr();
        // row of every stored entry, in storage order
        let rows: Vec<usize> = (0..n)
            .flat_map(|i| std::iter::repeat_n(i, rp[i + 1] - rp[i]))
            .collect();
        let ci = pattern.col_idx();
        let diag_sum: f64 = rows
            .iter()
            .zip(ci)
            .zip(&k.values)
            .filter(|((i, j), _)| **i == **j as usize)
            .map(|(_, v)| v.abs())
            .sum();
        let mean = (diag_sum / n.max(1) as f64).max(1e-300);
        for ((&i, &j), v) in rows.iter().zip(ci).zip(k.values.iter_mut()) {
            let j = j as usize;
            if i == j {
                if pinned[i] && *v <= 0.0 {
                    *v = mean;
                }
            } else if pinned[i] || pinned[j] {
                *v = 0.0;
            }
        }
    }

    /// The out-of-balance force f_ext − f_int (N), zero at pinned unknowns (where it is
    /// the reaction).
    fn out_of_balance(&self, f_ext: &[f64], f_int: &[f64]) -> Vec<f64> {
        let mut r: Vec<f64> = f_ext.iter().zip(f_int).map(|(a, b)| a - b).collect();
        for &(d, _) in &self.pins {
            r[d] = 0.0;
        }
        r
    }

    /// The force that measures the out-of-balance force: the external force on the free
    /// unknowns and the reactions at the pinned ones (N).
    fn force_scale(&self, f_ext: &[f64], f_int: &[f64]) -> f64 {
        let mut s2: f64 = f_ext.iter().map(|x| x * x).sum();
        for &(d, _) in &self.pins {
            s2 += f_int[d] * f_int[d] - f_ext[d] * f_ext[d];
        }
        s2.max(0.0).sqrt().max(self.scale_floor).max(1e-300)
    }

    /// The elastic stiffness K₀ (N/m) on the geometry of the last converged increment,
    /// no unknowns pinned: assembled once per increment, when first asked for (the
    /// blended steps of a singular secant matrix ask for it at every iteration).
    fn elastic_on_cur(&mut self) -> &CsrMatrix {
        if self.k0.is_none() {
            let local = self.elastic_local();
            let mut k = CsrMatrix::zeros(self.system.plan.pattern().clone());
            self.system.stiffness_into(&self.cur, &local, &mut k);
            self.k0 = Some(k);
        }
        self.k0.as_ref().expect("assembled above")
    }

    /// Solve with the elastic stiffness of the initial configuration (factorized once).
    fn solve_k0(&mut self, rhs: &mut [f64]) -> Result<bool> {
        if self.held != Held::K0 {
            let mut k = self.elastic_on_cur().clone();
            Self::pin_rows(&self.pins, &mut k);
            let ok = self.backend.factorize(&k).is_ok() && !super::singular_pivots(&*self.backend);
            self.held = Held::K0;
            if !ok {
                return Ok(false);
            }
        }
        Ok(self.backend.solve(rhs).is_ok())
    }

    /// One correction δ = K⁻¹ r with the strategy's matrix; `None` when that matrix is
    /// singular (a mechanism in the current contact states).
    /// `states`: the contact states the matrix is built in (the trial's, or at the first
    /// iteration of an increment those of the last converged one).
    ///
    /// The matrix is assembled on the geometry of the last converged increment, not the
    /// trial's: the out-of-balance force, which decides convergence, is always that of the
    /// trial geometry (the updated Lagrangian scheme of METHOD.md §4), so the converged
    /// state is the same, while the iteration matrix stays fixed within an increment but
    /// for the contacts that change state. An iteration in which no contact changed then
    /// finds the matrix bit-identical and skips the factorization (only a solve), and one
    /// in which a few changed is a low-rank change of the held factorization, which
    /// [`Driver::reuse`] exploits.
    fn correction(
        &mut self,
        trial: &Trial,
        states: &[ContactState],
        r: &[f64],
        tangent: bool,
    ) -> Result<Option<Vec<f64>>> {
        let mut x = r.to_vec();
        match self.settings.strategy {
            Strategy::Initial => Ok(self.solve_k0(&mut x)?.then_some(x)),
            Strategy::Secant | Strategy::Newton => {
                let mut newton = self.settings.strategy == Strategy::Newton || tangent;
                if newton && self.settings.strategy == Strategy::Secant {
                    if let Some(x) = self.tangent_with_secant_factor(trial, states, r) {
                        return Ok(Some(x));
                    }
                    // no LU of the tangent where its factor would not fit: the secant
                    // correction instead (the safeguard's alternative step)
                    newton = !self.tangent_lu_too_large();
                    if !newton {
                        self.stats.tangent_lu_skipped += 1;
                    }
                }
                let local = self.local_stiffness(trial, states, newton);
                self.assemble_kbuf(local);
                if !newton {
                    if let Some(x) = self.changed(states, r) {
                        return Ok(Some(x));
                    }
                    if let Some(x) = self.reuse(states, r) {
                        return Ok(Some(x));
                    }
                    self.hold_secant(states);
                }
                let backend: &mut dyn LinearBackend = if newton {
                    if self.lu.is_none() {
                        self.lu = Some(crate::solve::backend("faer-lu")?);
                    }
                    self.lu.as_mut().unwrap().as_mut()
                } else {
                    &mut *self.backend
                };
                let ok = backend.factorize(&self.kbuf).is_ok()
                    && (newton || !super::singular_pivots(&*backend))
                    && backend.solve(&mut x).is_ok()
                    && x.iter().all(|v| v.is_finite());
                // LU has no pivot measure: a matrix singular up to round-off shows as a
                // step of the size of the model
                let size = self.model_size();
                let huge = newton && x.iter().any(|v| v.abs() > 0.1 * size);
                Ok((ok && !huge).then_some(x))
            }
        }
    }

    /// Whether an LU factorization of the tangent would exceed
    /// [`TANGENT_LU_MAX_ENTRIES`], estimated from the held Cholesky factor's entries
    /// (`SolverStats::factor_nnz`; an LU of the same matrix holds L and U with pivoting's
    /// extra fill, several times as many) or, for a backend that does not report them
    /// (iterative ones), from the matrix's stored entries × 8 (the ratio of the
    /// Cholesky factor's entries to the matrix's on the walls of docs/performance.md).
    /// The size of the model alone decides, never the machine's free memory, so that the
    /// results do not depend on the machine.
    fn tangent_lu_too_large(&self) -> bool {
        let factor = match self.backend.stats().factor_nnz {
            0 => 8 * self.kbuf.values.len(),
            f => f,
        };
        factor > TANGENT_LU_MAX_ENTRIES
    }

    /// Assemble the iteration matrix for the contacts' local stiffnesses `local` into
    /// `kbuf`, on the geometry of the last converged increment, with the pinned unknowns
    /// taken out. When `kbuf` holds the matrix of the same geometry for other local
    /// stiffnesses, only the contacts whose local stiffness changed are assembled again
    /// ([`System::stiffness_update`]: bit-identical to a whole assembly).
    fn assemble_kbuf(&mut self, local: Vec<LocalStiffness>) {
        Self::assemble(
            &self.system,
            &self.cur,
            &self.pins,
            local,
            &mut self.kbuf,
            &mut self.kbuf_local,
        );
    }

    /// [`Driver::assemble_kbuf`] into `aux` (the second buffer, tracked by `aux_local`).
    fn assemble_aux(&mut self, local: Vec<LocalStiffness>) {
        Self::assemble(
            &self.system,
            &self.cur,
            &self.pins,
            local,
            &mut self.aux,
            &mut self.aux_local,
        );
    }

    /// Assemble the matrix of the local stiffnesses `local` on `mesh` into `out`, with the
    /// unknowns `pins` taken out; `out_local`: what `out` holds (`None`: unknown), for
    /// the update of only the contacts that changed.
    fn assemble(
        system: &System,
        mesh: &Mesh,
        pins: &[(usize, f64)],
        local: Vec<LocalStiffness>,
        out: &mut CsrMatrix,
        out_local: &mut Option<Vec<LocalStiffness>>,
    ) {
        let few = |prev: &[LocalStiffness]| {
            let changed = prev.iter().zip(&local).filter(|(a, b)| a != b).count();
            UPDATE_MAX_SHARE * changed <= local.len()
        };
        match out_local.take() {
            Some(prev) if pins.is_empty() && few(&prev) => {
                system.stiffness_update(mesh, &prev, &local, out)
            }
            _ => system.stiffness_into(mesh, &local, out),
        }
        if pins.is_empty() {
            *out_local = Some(local);
        } else {
            Self::pin_rows(pins, out);
        }
    }

    /// Record that the main backend holds (or is about to hold) the factorization of
    /// `kbuf`, the secant matrix in `states` on `cur`.
    fn hold_secant(&mut self, states: &[ContactState]) {
        self.held = Held::Secant(states.to_vec());
        self.held_current = true;
        self.held_on_cur.clear();
    }

    /// `aux` ← the matrix that the held secant factorization, of H = K_s(held states) on
    /// its own geometry, is to be corrected to ([`LinearBackend::solve_changed`]) for the
    /// secant matrix K_s(`states`) on `cur`: K_s(`states`) itself when the factorization
    /// is of `cur`; on an older geometry, H plus the change of state on `cur`,
    ///
    ///   N = H + K_s(`states`) − K_s(held states)   (entry by entry; H where the two agree),
    ///
    /// a change of H on the contacts that changed state only (rank ≤ 2 each), which the
    /// backend's low-rank correction accepts, and near K_s(`states`): the two differ by
    /// the geometry's change over the increments since the factorization (mm on m-sized
    /// blocks), which the conjugate gradients of [`Driver::reuse`] or the GMRES of
    /// [`Driver::tangent_with_secant_factor`] iterate on. `in_kbuf`: `kbuf` holds
    /// K_s(`states`) (else it is assembled into `aux`). `false` when no secant
    /// factorization is held, or the backend does not give its values (then it offers no
    /// `solve_changed` either).
    fn near_into_aux(&mut self, states: &[ContactState], in_kbuf: bool) -> bool {
        let Held::Secant(held_states) = &self.held else {
            return false;
        };
        if self.backend.factorized_values().is_none() {
            return false;
        }
        if self.aux.values.is_empty() {
            self.aux.values = vec![0.0; self.kbuf.values.len()];
        }
        if !self.held_current && self.held_on_cur.is_empty() {
            let local = self.secant_local(&held_states.clone());
            self.assemble_aux(local);
            self.held_on_cur.clone_from(&self.aux.values);
        }
        if in_kbuf {
            self.aux.values.copy_from_slice(&self.kbuf.values);
            self.aux_local.clone_from(&self.kbuf_local);
        } else {
            let local = self.secant_local(states);
            self.assemble_aux(local);
        }
        if !self.held_current {
            // exactly H where the contact states agree, so that the change read by the
            // backend is the changed contacts' alone
            let held = self
                .backend
                .factorized_values()
                .expect("checked above; nothing factorized since");
            for ((a, h), b) in self.aux.values.iter_mut().zip(held).zip(&self.held_on_cur) {
                *a = if *a == *b { *h } else { h + (*a - b) };
            }
            self.aux_local = None;
        }
        true
    }

    /// The tangent correction K_t⁻¹ r of the secant strategy (a symmetric secant matrix
    /// plus the slipping contacts' friction–normal coupling) by GMRES preconditioned with
    /// the held secant factorization (factorized first, in `states`, when none is held),
    /// instead of an LU factorization of K_t, which costs several Cholesky
    /// factorizations. `None`: the caller factorizes K_t (GMRES did not converge within
    /// [`TANGENT_MAX_ITERATIONS`], or the secant matrix is singular).
    fn tangent_with_secant_factor(
        &mut self,
        trial: &Trial,
        states: &[ContactState],
        r: &[f64],
    ) -> Option<Vec<f64>> {
        if self.gmres_failed {
            // it failed earlier in this increment: on the 10⁶-unknown wall of
            // docs/performance.md it then failed at every later tangent step of the
            // increment (31 in a row, 30 iterations each)
            return None;
        }
        if !matches!(self.held, Held::Secant(_)) {
            let local = self.local_stiffness(trial, states, false);
            self.assemble_kbuf(local);
            self.held = Held::Nothing;
            let ok = self.backend.factorize(&self.kbuf).is_ok()
                && !super::singular_pivots(&*self.backend);
            if !ok {
                return None;
            }
            self.hold_secant(states);
        }
        // the secant matrix in `states` (in `aux`), when the held factorization is of a
        // few contacts in other states (on this geometry or, corrected for the change of
        // state, an older one: `near_into_aux`): GMRES is then preconditioned with the
        // factorization corrected for them (`LinearBackend::solve_changed`), which leaves
        // the friction–normal coupling of the slipping contacts alone to iterate on (and
        // the geometry's change)
        let near = match self.changed_since_factor(states) {
            Some(c) if c > 0 && c <= self.low_rank_limit() => self.near_into_aux(states, false),
            _ => false,
        };
        let local = self.local_stiffness(trial, states, true);
        self.assemble_kbuf(local);
        // an inexact Newton step: the linear residual left is a tenth of what counts as
        // converged (relative to ‖r‖: between REUSE_TOLERANCE and TANGENT_TOLERANCE), so
        // that the step converges the increment as the exact one does, up to the
        // nonlinearity, which the next iteration corrects either way
        let rn = Self::norm(r);
        let tolerance =
            (0.1 * self.converged_norm / rn.max(1e-300)).clamp(REUSE_TOLERANCE, TANGENT_TOLERANCE);
        let (out, corrected) = match near {
            true => crate::solve::reuse::gmres_with_changed_factor(
                &self.kbuf,
                &self.aux,
                &mut *self.backend,
                r,
                tolerance,
                TANGENT_MAX_ITERATIONS,
            ),
            false => (
                crate::solve::reuse::gmres_with_factor(
                    &self.kbuf,
                    &mut *self.backend,
                    r,
                    tolerance,
                    TANGENT_MAX_ITERATIONS,
                ),
                false,
            ),
        };
        let Some(out) = out else {
            self.gmres_failed = true;
            if super::tracing() {
                eprintln!("  tangent by GMRES failed (corrected preconditioner: {corrected})");
            }
            return None;
        };
        // a step of the size of the model: K_t singular up to round-off, as in `correction`
        let size = self.model_size();
        if out.x.iter().any(|v| v.abs() > 0.1 * size) {
            return None;
        }
        self.stats.reused_factorizations += 1;
        self.stats.reuse_iterations += out.iterations;
        if super::tracing() {
            eprintln!(
                "  tangent by GMRES: {} iterations (corrected preconditioner: {corrected})",
                out.iterations
            );
        }
        Some(out.x)
    }

    /// Iterations without a gain of [`STALL_PROGRESS`] after which an increment's secant
    /// iterations (`tangent = false`) go on with tangent steps, or its tangent steps stop
    /// as not converged: [`STALL_ITERATIONS`] for both, or in a capacity search's probes
    /// ([`Driver::probing`]) [`PROBE_STALL_ITERATIONS`] and
    /// [`PROBE_TANGENT_STALL_ITERATIONS`].
    fn stall_window(&self, tangent: bool) -> usize {
        match (self.probing, tangent) {
            (false, _) => STALL_ITERATIONS,
            (true, false) => PROBE_STALL_ITERATIONS,
            (true, true) => PROBE_TANGENT_STALL_ITERATIONS,
        }
    }

    /// Contacts whose state in `now` differs from that of the held secant factorization;
    /// `None` when no secant factorization is held.
    fn changed_since_factor(&self, now: &[ContactState]) -> Option<usize> {
        let Held::Secant(states) = &self.held else {
            return None;
        };
        Some(states.iter().zip(now).filter(|(a, b)| a != b).count())
    }

    /// The most contacts changed state since the held factorization for which the
    /// low-rank correction ([`Driver::changed`], and across increments [`Driver::reuse`])
    /// is tried instead of a refactorization: [`LOW_RANK_MAX_CHANGES`] × √(n / n_P2), n the
    /// unknowns, between [`LOW_RANK_MAX_CHANGES`] and [`LOW_RANK_CAP`]. A correction of
    /// rank r costs about r solves restricted to the paths of the changed unknowns to the
    /// root of the elimination tree, whose top separators (√n unknowns on a wall, dense)
    /// make a path cost ∝ n, while a nested-dissection factorization of a wall costs
    /// ∝ n^1.5: the break-even rank grows as √n. Measured (docs/performance.md, "The
    /// low-rank correction in the static driver"): a correction at 0.45 of a
    /// refactorization for a median 22 changed contacts on the rigid P2 wall (4,860
    /// unknowns), at 0.13–0.17 for 39 on the 10⁵-unknown wall. The size of the model alone
    /// decides (no timing), so that the results do not depend on the machine.
    fn low_rank_limit(&self) -> usize {
        let n = self.kbuf.pattern.n() as f64;
        let scaled = LOW_RANK_MAX_CHANGES as f64 * (n / LOW_RANK_REFERENCE_DOFS).sqrt();
        (scaled as usize).clamp(LOW_RANK_MAX_CHANGES, LOW_RANK_CAP)
    }

    /// The secant correction K_s⁻¹ r by the held secant factorization corrected exactly
    /// for the contacts that changed state since it was computed
    /// ([`LinearBackend::solve_changed`]: the Woodbury identity inside the factor, no
    /// iteration), when between 1 and [`Driver::low_rank_limit`] did (`kbuf` holds the new
    /// K_s). Within an increment the iteration matrix changes only by those contacts'
    /// stiffness (it is assembled on the last converged geometry, see
    /// [`Driver::correction`]); across increments every entry changes and the backend
    /// refuses after reading a few of them. `None`: the backend refused (unsupported, a
    /// rank above its limit, a new geometry, K_s not positive definite) or the result's
    /// true residual is above 10 × [`REUSE_TOLERANCE`]; then [`Driver::reuse`] or a
    /// refactorization.
    fn changed(&mut self, now: &[ContactState], r: &[f64]) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        if changed == 0 || changed > self.low_rank_limit() || !self.held_current {
            return None;
        }
        let start = std::time::Instant::now();
        let out = crate::solve::reuse::solve_changed(
            &self.kbuf,
            &mut *self.backend,
            r,
            10.0 * REUSE_TOLERANCE,
        )?;
        self.stats.low_rank_corrections += 1;
        let rank = self.backend.stats().last_changed_rank;
        if super::tracing() {
            eprintln!(
                "  low-rank correction: {changed} contacts changed, rank {rank}, {:.3e} s",
                start.elapsed().as_secs_f64()
            );
        }
        self.stats.low_rank_max_rank = self.stats.low_rank_max_rank.max(rank);
        Some(out.x)
    }

    /// The secant correction K_s⁻¹ r computed with the held secant factorization as a
    /// preconditioner, when few contacts changed state since it was computed (`kbuf` holds
    /// the new K_s). `None`: refactorize.
    fn reuse(&mut self, now: &[ContactState], r: &[f64]) -> Option<Vec<f64>> {
        let changed = self.changed_since_factor(now)?;
        // across increments (the factorization of an older geometry) the held factor
        // corrected for the change of state (`near_into_aux`) preconditions, up to the
        // low-rank path's limit of changed contacts
        let across = !self.held_current && changed > 0 && self.settings.reuse_across_increments;
        let limit = if across {
            self.low_rank_limit()
        } else {
            REUSE_MAX_CHANGES
        };
        if changed > limit {
            if super::tracing() {
                eprintln!("  refactorization: {changed} contacts changed");
            }
            return None;
        }
        let out = if across {
            if !self.near_into_aux(now, true) {
                // the backend gives no corrected factor: refactorize
                return None;
            }
            crate::solve::reuse::solve_with_changed_factor(
                &self.kbuf,
                &self.aux,
                &mut *self.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        } else {
            crate::solve::reuse::solve_with_factor(
                &self.kbuf,
                &mut *self.backend,
                r,
                REUSE_TOLERANCE,
                REUSE_MAX_ITERATIONS,
            )
        };
        if super::tracing() {
            eprintln!(
                "  PCG on the held factor: {changed} contacts changed, {} geometry, {:?} iterations",
                if self.held_current { "same" } else { "older" },
                out.as_ref().map(|o| o.iterations)
            );
        }
        let out = out?;
        self.stats.reused_factorizations += 1;
        self.stats.reuse_iterations += out.iterations;
        Some(out.x)
    }

    /// The mechanism of a singular secant matrix K_s: the solution of (K_s + ε K₀) x = r,
    /// ε = 10⁻⁸, is dominated by the part of r that K_s cannot resist, i.e. by K_s's null
    /// space (the blocks' free motions).
    fn mechanism_mode(&mut self, trial: &Trial, r: &[f64]) -> Result<Vec<f64>> {
        Ok(self
            .blended_step(trial, r, 1e-8)?
            .unwrap_or_else(|| vec![0.0; r.len()]))
    }

    /// Solve (K_s + ε K₀) x = r, both in the configuration of the last converged
    /// increment (as every iteration matrix: see [`Driver::correction`]).
    fn blended_step(&mut self, trial: &Trial, r: &[f64], eps: f64) -> Result<Option<Vec<f64>>> {
        let local = self.local_stiffness(trial, &trial.state, false);
        if self.pins.is_empty() {
            // K_s: where `kbuf` holds the secant matrix of these or nearby states (the
            // correction that found K_s singular assembled it), only the contacts whose
            // stiffness differs are assembled again (bit-identical to a whole assembly)
            self.assemble_kbuf(local);
        } else {
            // (pinned rows are pinned once, after the blend)
            self.system
                .stiffness_into(&self.cur, &local, &mut self.kbuf);
        }
        self.kbuf_local = None;
        self.elastic_on_cur();
        let k0 = self.k0.as_ref().expect("assembled above");
        for (a, b) in self.kbuf.values.iter_mut().zip(&k0.values) {
            *a += eps * b;
        }
        Self::pin_rows(&self.pins, &mut self.kbuf);
        self.held = Held::Nothing;
        let mut x = r.to_vec();
        let ok = self.backend.factorize(&self.kbuf).is_ok()
            && self.backend.solve(&mut x).is_ok()
            && x.iter().all(|v| v.is_finite());
        Ok(ok.then_some(x))
    }

    fn norm(v: &[f64]) -> f64 {
        v.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// Iterate one increment to the external force `f_ext` and prescribed increments.
    /// `guess`: where the iterations start (the last increment of the phase extrapolated),
    /// or `None` to start from zero.
    fn increment(
        &mut self,
        f_ext: &[f64],
        presc: &[Point],
        guess: Option<Vec<f64>>,
    ) -> Result<std::result::Result<Trial, (IncrementFailure, Failure)>> {
        self.bonds_broken_here.clear();
        let out = self.iterate(f_ext, presc, guess);
        if !matches!(out, Ok(Ok(_))) {
            // the retry (a cut increment, the capacity search's next bracket) starts from
            // the committed state as it was
            OpenFlips::give_back(&mut self.committed.history, &mut self.bonds_broken_here);
        }
        out
    }

    /// The iterations of [`Driver::increment`].
    fn iterate(
        &mut self,
        f_ext: &[f64],
        presc: &[Point],
        guess: Option<Vec<f64>>,
    ) -> Result<std::result::Result<Trial, (IncrementFailure, Failure)>> {
        let n = self.cur.n_dofs;
        let extrapolated = guess.is_some();
        let mut dq = guess.unwrap_or_else(|| vec![0.0; n]);
        for &(d, v) in &self.pins {
            dq[d] = v;
        }
        if !extrapolated
            && (presc.iter().any(|p| *p != [0.0, 0.0]) || self.pins.iter().any(|p| p.1 != 0.0))
        {
            // elastic predictor of a prescribed motion: the free blocks' elastic response to
            // it, so that the iterations start near the answer rather than from the
            // friction limit of slipping contacts
            let elastic = PerContact {
                laws: self.law.laws.iter().map(JointLaw::elastic).collect(),
                of: self.law.of.clone(),
            };
            let t = Inputs {
                law: &elastic,
                ..self.inputs()
            }
            .evaluate(&dq, presc);
            let mut x = self.out_of_balance(f_ext, &t.f_int);
            if self.solve_k0(&mut x)? {
                for (a, b) in dq.iter_mut().zip(&x) {
                    *a += b;
                }
            }
        }
        let mut trial = self.trial(&dq, presc);
        let mut scale = self.force_scale(f_ext, &trial.f_int);
        let size = self.model_size();
        let mut prev_state = trial.state.clone();
        let mut prev_force = trial.force.clone();
        let mut singular_streak = 0;
        // the best out-of-balance norm so far and the iteration that set it
        let mut best_rn = f64::INFINITY;
        let mut best_it = 0;
        let mut tangent_only = false;
        // the closed ↔ open changes that break bonds, counted only where a joint has a
        // bond to break ([`Driver::break_cycling_bonds`])
        let bonded = self
            .law
            .laws
            .iter()
            .any(|l| l.broken_bond([0.0; 2]).is_some());
        let mut open_flips = OpenFlips::new(bonded, trial.state.len());
        let mut bonds_broken = false;
        self.gmres_failed = false;
        for it in 0..self.settings.max_iterations {
            self.stats.iterations += 1;
            let negligible = self.settings.tolerance * scale;
            open_flips.count(it, &trial, (&prev_state, &prev_force), negligible);
            let r = self.out_of_balance(f_ext, &trial.f_int);
            if !self.pins.is_empty() {
                scale = self.force_scale(f_ext, &trial.f_int);
            }
            let rn = Self::norm(&r);
            if let Some(p) = self.progress.as_deref_mut() {
                p.iteration(it, rn / scale);
            }
            if super::tracing() {
                eprintln!(
                    "it {it} residual {:.3e} open {} slip {}",
                    rn / scale,
                    trial
                        .state
                        .iter()
                        .filter(|s| **s == ContactState::Open)
                        .count(),
                    trial
                        .state
                        .iter()
                        .filter(|s| **s == ContactState::Slip)
                        .count()
                );
            }
            // a state change counts only where the contact carries a force that matters at
            // the tolerance: contacts with no force (head joints under gravity) flip with
            // round-off
            let negligible = self.settings.tolerance * scale;
            self.converged_norm = negligible;
            let matters = |k: usize| {
                trial.force[k][0].hypot(trial.force[k][1]) > negligible
                    || prev_force[k][0].hypot(prev_force[k][1]) > negligible
            };
            let changed = trial
                .state
                .iter()
                .zip(&prev_state)
                .enumerate()
                .any(|(k, (a, b))| a != b && matters(k));
            if super::tracing() {
                // changes of state of the contacts that carry a force: stick→slip,
                // slip→stick, closed→open, open→closed
                let mut tr = [0usize; 4];
                for (k, (a, b)) in trial.state.iter().zip(&prev_state).enumerate() {
                    if a != b && matters(k) {
                        tr[match (b, a) {
                            (ContactState::Stick, ContactState::Slip) => 0,
                            (ContactState::Slip, ContactState::Stick) => 1,
                            (_, ContactState::Open) => 2,
                            _ => 3,
                        }] += 1;
                    }
                }
                eprintln!(
                    "  changes stick>slip {} slip>stick {} >open {} open> {}",
                    tr[0], tr[1], tr[2], tr[3]
                );
            }
            if (it > 0 || extrapolated) && rn <= self.settings.tolerance * scale && !changed {
                self.report.iterations = it;
                self.report.residual = rn / scale;
                return Ok(Ok(trial));
            }
            if rn < STALL_PROGRESS * best_rn {
                best_rn = rn;
                best_it = it;
            } else if it - best_it >= self.stall_window(tangent_only) {
                if self.settings.strategy == Strategy::Secant && !tangent_only {
                    // the secant iterations stagnate, which on large walls they do below
                    // the limit load, a little above the tolerance (docs/performance.md,
                    // "60×60 and 100×100 walls"): go on with tangent steps, which take the
                    // friction's dependence on the normal force into account, before
                    // declaring the load beyond what the contacts can hold
                    tangent_only = true;
                    self.stats.tangent_fallbacks += 1;
                    if super::tracing() {
                        eprintln!(
                            "  secant stalled at it {it}: best {:.3e}, now {:.3e}: tangent steps",
                            best_rn / scale,
                            rn / scale
                        );
                    }
                    best_it = it;
                } else if !bonds_broken && self.break_cycling_bonds(&open_flips) {
                    // the iterations cycled on bonds that cannot hold: go on with them
                    // broken (once an increment: where they still stall the load is beyond
                    // what the contacts can hold)
                    bonds_broken = true;
                    let t = self.trial(&dq, presc);
                    self.recycle(std::mem::replace(&mut trial, t));
                    (best_rn, best_it) = (f64::INFINITY, it);
                    prev_state = trial.state.clone();
                    prev_force = trial.force.clone();
                    continue;
                } else {
                    // stagnation: the load is beyond what the contacts can hold from here
                    if super::tracing() {
                        eprintln!(
                            "  stalled at it {it}: best {:.3e}, now {:.3e} (tangent steps: {tangent_only})",
                            best_rn / scale,
                            rn / scale
                        );
                    }
                    break;
                }
            }
            prev_state = trial.state.clone();
            prev_force = trial.force.clone();
            // the secant strategy takes a tangent step once the contact states have settled:
            // with the states fixed the problem is linear but for the friction limit's
            // dependence on the normal force, which the secant matrix leaves out (the
            // secant iterations then contract by a constant factor, ~0.7 on the walls of
            // docs/performance.md; the tangent step closes them in one or two)
            let tangent = self.settings.strategy == Strategy::Newton
                || tangent_only
                || (self.settings.strategy == Strategy::Secant
                    && it > 1
                    && !changed
                    && trial.state.contains(&ContactState::Slip));
            // the first correction of an increment is built in the states the last increment
            // converged in: at dq = 0 every contact reports its committed force, which reads
            // as sticking even where it was open or slipping, and an all-sticking (elastic)
            // predictor overshoots where the joints had opened
            let states =
                if it == 0 && !extrapolated && self.committed.state.len() == trial.state.len() {
                    self.committed.state.clone()
                } else {
                    trial.state.clone()
                };
            // a correction of the size of the model comes from a matrix singular but for
            // round-off (whether the factorization flags it depends on the backend's pivot
            // threshold): treated as singular, so that the backends agree
            let correction = self
                .correction(&trial, &states, &r, tangent)?
                .filter(|d| d.iter().all(|v| v.abs() <= 0.5 * size));
            let delta = match correction {
                Some(d) => {
                    singular_streak = 0;
                    d
                }
                None => {
                    // the secant matrix is singular in the current states (a mechanism,
                    // or a transient set of open contacts): step with K_s + ε K₀, stiffer
                    // than the secant (so the iteration contracts, as the seed's
                    // excess-force iteration with K₀ does) but much closer to it
                    singular_streak += 1;
                    match self.blended_step(&trial, &r, BLEND)? {
                        Some(x) => x,
                        None => {
                            let mut x = r.clone();
                            if !self.solve_k0(&mut x)? {
                                return Ok(Err((
                                    IncrementFailure::Divergence,
                                    self.failure(dq, &trial, f_ext),
                                )));
                            }
                            x
                        }
                    }
                }
            };
            // line search on the out-of-balance norm
            let mut best = self.line_search(&dq, &delta, rn, f_ext, presc, LINE_SEARCH_STEPS);
            if super::tracing() {
                eprintln!(
                    "  step tangent {tangent} singular {singular_streak} ratio {:.3}",
                    best.0 / rn
                );
            }
            if tangent && best.0 >= rn {
                // safeguarded Newton: where the tangent step does not reduce the
                // out-of-balance force (slip/open cycling at a lightly loaded contact),
                // take the secant step instead
                let local = self.local_stiffness(&trial, &trial.state, false);
                self.assemble_kbuf(local);
                let mut x = r.clone();
                let ok = self.backend.factorize(&self.kbuf).is_ok()
                    && !super::singular_pivots(&*self.backend)
                    && self.backend.solve(&mut x).is_ok()
                    && x.iter().all(|v| v.is_finite());
                self.hold_secant(&trial.state);
                let x = if ok {
                    Some(x)
                } else {
                    self.blended_step(&trial, &r, BLEND)?
                };
                if let Some(x) = x {
                    let alt = self.line_search(&dq, &x, rn, f_ext, presc, LINE_SEARCH_STEPS);
                    if alt.0 < best.0 {
                        best = alt;
                    }
                }
            } else if self.settings.strategy == Strategy::Secant
                && singular_streak == 0
                && best.0 >= rn
            {
                // safeguarded secant: a regular secant step that no step length makes
                // reduce the out-of-balance force is not a descent direction (with many
                // contacts slipping K_s is far from the Jacobian, which couples the
                // friction to the normal force); take the tangent step where it does
                if let Some(x) = self
                    .correction(&trial, &states, &r, true)?
                    .filter(|d| d.iter().all(|v| v.abs() <= 0.5 * size))
                {
                    // the tangent of the current states is the Jacobian where no contact
                    // sits at a kink of its law, so a short enough step along it lowers
                    // the norm: backtrack further than for the secant step
                    let alt = self.line_search(&dq, &x, rn, f_ext, presc, SAFEGUARD_STEPS);
                    if super::tracing() {
                        eprintln!("  safeguard tangent ratio {:.3}", alt.0 / rn);
                    }
                    if alt.0 < best.0 {
                        best = alt;
                    }
                }
            }
            if self.settings.line_search && best.0 >= rn {
                // no step length lowered the norm, nor did the safeguards' other steps:
                // the step length where the out-of-balance force stops working along the
                // correction (see `slope_search`), taken whatever its norm
                if let Some(alt) = self.slope_search(&dq, &delta, &r, &best.1.history, f_ext, presc)
                {
                    if super::tracing() {
                        eprintln!(
                            "  slope search: norm {:.3e} -> {:.3e}",
                            best.0 / scale,
                            alt.0 / scale
                        );
                    }
                    self.recycle(std::mem::replace(&mut best, alt).1);
                    self.stats.slope_searches += 1;
                }
            }
            if singular_streak >= MODE_STREAK
                && self.settings.strategy != Strategy::Initial
                && best.0 > MODE_PROGRESS * rn
            {
                // the step moved little: blocks held only by slipping and open contacts
                // carry an out-of-balance force that no contact of theirs resists (K_s is
                // singular there) and the residual's norm does not fall along their free
                // motion until one of those contacts sticks: search along that motion
                if let Some(m) = self.blended_step(&trial, &r, MODE_BLEND)? {
                    if let Some(moves) =
                        self.free_motion(&best.2, &best.1.state, &m, &delta, f_ext, presc)
                    {
                        let mut cand = best.2.clone();
                        for (i, v) in moves.into_iter().flatten() {
                            cand[i] += v;
                        }
                        let t = self.trial(&cand, presc);
                        let rn2 = Self::norm(&self.out_of_balance(f_ext, &t.f_int));
                        if super::tracing() {
                            eprintln!(
                                "  free motion: norm {:.3e} -> {:.3e}",
                                best.0 / scale,
                                rn2 / scale
                            );
                        }
                        if rn2 < MODE_ACCEPT * best.0 {
                            best = (rn2, t, cand);
                            self.stats.free_motions += 1;
                        }
                    }
                }
            }
            let (_, t, cand) = best;
            self.recycle(std::mem::replace(&mut trial, t));
            dq = cand;
            let dmax = dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if !dmax.is_finite() || dmax > 0.5 * size {
                return Ok(Err((
                    IncrementFailure::Divergence,
                    self.failure(dq, &trial, f_ext),
                )));
            }
        }
        let r = self.out_of_balance(f_ext, &trial.f_int);
        let residual = Self::norm(&r) / scale;
        // the mechanism: the null space of the secant matrix when it is singular, else
        // the increment itself
        let mode = if singular_streak > 0 && self.settings.strategy != Strategy::Initial {
            self.mechanism_mode(&trial, &r)?
        } else {
            dq
        };
        Ok(Err((
            IncrementFailure::NoConvergence { residual },
            self.failure(mode, &trial, f_ext),
        )))
    }

    fn failure(&self, mode: Vec<f64>, trial: &Trial, f_ext: &[f64]) -> Failure {
        let loads = self
            .cur
            .blocks
            .iter()
            .map(|b| match b.dofs {
                crate::mesh::BlockDofs::Rigid { first, .. } => {
                    [f_ext[first as usize], f_ext[first as usize + 1]]
                }
                crate::mesh::BlockDofs::Deformable => b.nodes.clone().fold([0.0, 0.0], |a, n| {
                    let d = self.cur.node_dofs[n as usize];
                    [a[0] + f_ext[d[0] as usize], a[1] + f_ext[d[1] as usize]]
                }),
                crate::mesh::BlockDofs::Fixed => [0.0, 0.0],
            })
            .collect();
        Failure {
            mode,
            states: trial.state.clone(),
            forces: trial.force.clone(),
            loads,
        }
    }

    /// Breaks the bonds that cannot hold, where an increment's iterations stalled: every
    /// bonded contact (cohesion or tensile strength, intact) that went closed → open →
    /// closed → open ([`BOND_BREAK_FLIPS`], `open_flips`: [`OpenFlips`]) in them
    /// has its bond broken for good from there on (docs/theory.md, "Bonds that cannot
    /// hold"). Such a contact sits at the jump of its law: closed it carries a cohesive
    /// shear that its equilibrium holds only with the contact in tension, past its
    /// strength, and open it carries nothing, and its equilibrium closes it again. No
    /// intact state is consistent, so the iterations cycle until the stall rule fails the
    /// increment (a false collapse: the free-surface tunnel of docs/performance.md),
    /// where the brittle law says the bond has broken. Only where the increment would
    /// otherwise fail, so that a run whose increments converge is not changed. Returns
    /// whether a bond broke (the trial must then be evaluated again).
    fn break_cycling_bonds(&mut self, open_flips: &OpenFlips) -> bool {
        let before = self.bonds_broken_here.len();
        let law = &self.law;
        let broke = open_flips.break_bonds(
            &mut self.committed.history,
            |k, h| law.get(k).broken_bond(h),
            |_| false,
            &mut self.bonds_broken_here,
        );
        self.stats.bonds_broken += self.bonds_broken_here.len() - before;
        broke
    }

    /// The slope line search: the step length α* along the correction `delta` from `dq`
    /// where the out-of-balance force r(α) = f_ext − f_int(dq + α δ) stops doing work along
    /// δ, the root of s(α) = r(α)·δ (N·m), sought on the grid α = 2⁻ᵏ, k = 0 …
    /// [`MODE_GRID`], from the largest step down, and interpolated linearly between the
    /// first grid point where s > 0 and the one before it (docs/theory.md, "The slope line
    /// search"). Where the contact laws derive from a potential (frozen normal forces, or
    /// no friction) s is minus the derivative of the total potential energy along δ, so
    /// α* is its minimum on the line: the step a mechanism's blocks make until a contact
    /// of theirs closes or sticks, which the norm of r cannot find, because it rises as
    /// soon as they touch however far they fall before. `None` when δ is not a descent
    /// direction (s(0) ≤ 0), when s > 0 at α = 1 (the full step already lowers the
    /// energy everywhere along it), and when the contacts' history at α* is not
    /// `history`, that of the backtracked step it would replace: a root far along δ may
    /// carry cohesive joints past their strength, which they do not regain when the next
    /// iterations correct the step (taken regardless, it cracked the wall over the fault
    /// of examples/fault_offset, which then followed the drop by 17 mm instead of
    /// bridging it), and a root short of the backtracked step may spare joints that the
    /// path cracks. So the search changes where the iterate goes, never which contacts
    /// have cracked or softened there.
    fn slope_search(
        &self,
        dq: &[f64],
        delta: &[f64],
        r0: &[f64],
        history: &[crate::material::History],
        f_ext: &[f64],
        presc: &[Point],
    ) -> Option<(f64, Trial, Vec<f64>)> {
        let slope = |r: &[f64]| r.iter().zip(delta).map(|(x, y)| x * y).sum::<f64>();
        let s0 = slope(r0);
        if s0 <= 0.0 || !s0.is_finite() {
            return None;
        }
        let at =
            |alpha: f64| -> Vec<f64> { dq.iter().zip(delta).map(|(a, b)| a + alpha * b).collect() };
        // (α, s) at the last grid point where the slope was not positive, and at the
        // first one below it where it is
        let mut above: Option<(f64, f64)> = None;
        let mut below = (0.0, s0);
        let mut alpha = 1.0f64;
        for _ in 0..=MODE_GRID {
            let t = self.trial(&at(alpha), presc);
            let s = slope(&self.out_of_balance(f_ext, &t.f_int));
            self.recycle(t);
            if s > 0.0 {
                below = (alpha, s);
                break;
            }
            above = Some((alpha, s));
            alpha *= 0.5;
        }
        let (ah, sh) = above?;
        let (al, sl) = below;
        let root = al + (ah - al) * sl / (sl - sh);
        let cand = at(root);
        let t = self.trial(&cand, presc);
        if t.history != history {
            self.recycle(t);
            return None;
        }
        let rn = Self::norm(&self.out_of_balance(f_ext, &t.f_int));
        Some((rn, t, cand))
    }

    /// Backtracking on the out-of-balance norm along `delta` from `dq` over the step
    /// lengths 1, ½, … 2^(1 − `steps`) (one step without `line_search`), the external
    /// force `f_ext` fixed: the best of the tried steps (norm, trial, increment).
    fn line_search(
        &self,
        dq: &[f64],
        delta: &[f64],
        rn: f64,
        f_ext: &[f64],
        presc: &[Point],
        steps: usize,
    ) -> (f64, Trial, Vec<f64>) {
        let steps = if self.settings.line_search { steps } else { 1 };
        let (rn2, t, cand, _) =
            self.line_search_along(dq, delta, rn, &Load::Fixed(f_ext), presc, steps);
        (rn2, t, cand)
    }

    /// Backtracking on the out-of-balance norm along `delta` from `dq` over the step
    /// lengths α = 1, ½, … 2^(1 − `steps`), the external force moving with α as `load`
    /// says (the static driver's [`Driver::line_search`], the arc-length corrector's
    /// backtracking): the first step that does not raise the norm above `rn` (N), else
    /// the best of them, as (its norm, its trial, the increment, α).
    fn line_search_along(
        &self,
        dq: &[f64],
        delta: &[f64],
        rn: f64,
        load: &Load,
        presc: &[Point],
        steps: usize,
    ) -> (f64, Trial, Vec<f64>, f64) {
        let mut alpha = 1.0;
        let mut best: Option<(f64, Trial, Vec<f64>, f64)> = None;
        for _ in 0..steps {
            let cand: Vec<f64> = dq.iter().zip(delta).map(|(a, b)| a + alpha * b).collect();
            let t = self.trial(&cand, presc);
            let rn2 = Self::norm(&self.out_of_balance(&load.at(alpha), &t.f_int));
            if best.as_ref().is_none_or(|b| rn2 < b.0) {
                if let Some(worse) = best.replace((rn2, t, cand, alpha)) {
                    self.recycle(worse.1);
                }
            } else {
                self.recycle(t);
            }
            if rn2 <= rn {
                break;
            }
            alpha *= 0.5;
        }
        best.expect("at least one step is tried")
    }

    /// The unknowns of each block (m, rad): a rigid block's three, a deformable block's
    /// nodes' two each, none for a fixed block.
    fn block_dofs(&self) -> Vec<Vec<usize>> {
        (0..self.cur.blocks.len())
            .map(|b| self.cur.block_unknowns(b))
            .collect()
    }

    /// The free motion of the blocks that only slipping and open contacts hold, and the
    /// distance each group of them must travel for one of its contacts to stick.
    ///
    /// `m` = (K_s + ε K₀)⁻¹ r with ε = [`MODE_BLEND`] and `step` the correction of the
    /// iteration, (K_s + 10⁻² K₀)⁻¹ r: where K_s is regular the two agree, where it is
    /// singular (a block whose contacts all slip or are open, in the direction they slip)
    /// `m` is 10⁴ times larger. Those blocks, grouped by their closed contacts, each move
    /// along their part of `m` to the root of their slope s_g(α) = Σ_{i ∈ g} rᵢ(α) mᵢ, where
    /// r(α) is the out-of-balance force at `from` + α m (an energy line search: with the
    /// normal forces frozen the contact laws derive from a convex potential and s_g is
    /// minus its derivative along the group's motion). Along that motion the slope stays
    /// at the group's out-of-balance force until one of its contacts sticks or reverses,
    /// while the norm of r stays flat: the norm cannot find the distance, the slope's root
    /// can. The roots are found on the grid α = 2⁻ᵏ, k = 0 … [`MODE_GRID`], interpolated
    /// linearly. Returns each group's motion α_g m as (unknown, increment) pairs, or `None`
    /// when no block is free or no group finds a root.
    #[allow(clippy::too_many_arguments)]
    fn free_motion(
        &self,
        from: &[f64],
        from_state: &[ContactState],
        m: &[f64],
        step: &[f64],
        f_ext: &[f64],
        presc: &[Point],
    ) -> Option<Vec<Vec<(usize, f64)>>> {
        let dofs = self.block_dofs();
        let amax = |v: &[f64], d: &[usize]| d.iter().fold(0.0f64, |a, &i| a.max(v[i].abs()));
        let free: Vec<bool> = dofs
            .iter()
            .map(|d| !d.is_empty() && amax(m, d) > MODE_RATIO * amax(step, d))
            .collect();
        if !free.contains(&true) {
            return None;
        }
        // groups: free blocks joined by closed contacts
        let nb = dofs.len();
        let mut parent: Vec<usize> = (0..nb).collect();
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for (k, c) in self.cur.contacts.iter().enumerate() {
            let (l, n) = (c.block_l as usize, c.block_m as usize);
            if free[l] && free[n] && from_state[k] != ContactState::Open {
                let (a, b) = (root(&mut parent, l), root(&mut parent, n));
                parent[a] = b;
            }
        }
        let group: Vec<Option<usize>> = (0..nb)
            .map(|b| free[b].then(|| root(&mut parent, b)))
            .collect();
        let mut mf = vec![0.0; m.len()];
        for (b, d) in dofs.iter().enumerate() {
            if free[b] {
                for &i in d {
                    mf[i] = m[i];
                }
            }
        }
        for &(d, _) in &self.pins {
            mf[d] = 0.0;
        }
        let size = self.model_size();
        let slopes = |r: &[f64]| {
            let mut s = vec![0.0; nb];
            for (b, d) in dofs.iter().enumerate() {
                if let Some(g) = group[b] {
                    s[g] += d.iter().map(|&i| r[i] * mf[i]).sum::<f64>();
                }
            }
            s
        };
        let at = |a: f64| -> Vec<f64> { from.iter().zip(&mf).map(|(x, y)| x + a * y).collect() };
        // the slopes read the out-of-balance force at the free blocks' unknowns only: the
        // elements of those blocks give it, at a fraction of a whole trial's cost
        let part = super::config::Part::of_blocks(&self.cur, &free);
        let slope_at =
            |a: f64| slopes(&self.out_of_balance(f_ext, &self.f_int_of_part(&at(a), presc, &part)));
        let mmax = mf.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut prev = (0.0, slope_at(0.0));
        let s0 = prev.1.clone();
        let mut alpha: Vec<Option<f64>> = vec![None; nb];
        for k in (0..=MODE_GRID).rev() {
            let a = 0.5f64.powi(k as i32);
            if a * mmax > 0.1 * size {
                break;
            }
            let s = slope_at(a);
            for g in 0..nb {
                if group[g] == Some(g) && alpha[g].is_none() && prev.1[g] > 0.0 && s[g] <= 0.0 {
                    let (a0, s0) = (prev.0, prev.1[g]);
                    alpha[g] = Some(a0 + (a - a0) * s0 / (s0 - s[g]));
                }
            }
            prev = (a, s);
            if (0..nb).all(|g| group[g] != Some(g) || alpha[g].is_some()) {
                break;
            }
        }
        // each group's motion, the groups whose out-of-balance force is largest first
        let mut groups: Vec<usize> = (0..nb).filter(|&g| alpha[g].is_some()).collect();
        groups.sort_by(|a, b| s0[*b].total_cmp(&s0[*a]));
        groups.truncate(MODE_GROUPS);
        let moves: Vec<Vec<(usize, f64)>> = groups
            .iter()
            .map(|&g| {
                let a = alpha[g].unwrap_or(0.0);
                (0..nb)
                    .filter(|&b| group[b] == Some(g))
                    .flat_map(|b| dofs[b].iter().map(|&i| (i, a * mf[i])))
                    .collect()
            })
            .collect();
        if super::tracing() {
            let nf = free.iter().filter(|f| **f).count();
            eprintln!(
                "  free motion: {nf} free blocks, {} groups with a root",
                moves.len()
            );
        }
        (!moves.is_empty()).then_some(moves)
    }

    fn model_size(&self) -> f64 {
        let b = crate::geometry::polygon::bbox(&self.cur.nodes);
        (b[2] - b[0]).hypot(b[3] - b[1]).max(1e-9)
    }

    fn commit(&mut self, trial: Trial, dq: &[f64], presc: &[Point]) {
        for (u, d) in self.committed.u.iter_mut().zip(dq) {
            *u += d;
        }
        self.committed.stress = trial.stress;
        self.committed.force = trial.force;
        self.committed.state = trial.state;
        self.committed.history = trial.history;
        let old = std::mem::replace(&mut self.cur, trial.mesh);
        self.keep_spare(old);
        self.k0 = None;
        self.kbuf_local = None;
        self.aux_local = None;
        // a held secant factorization is now of an older geometry: across increments it
        // preconditions (Driver::reuse) with the change of state corrected
        self.held_current = false;
        self.held_on_cur.clear();
        self.gmres_failed = false;
        for (t, p) in self.presc_total.iter_mut().zip(presc) {
            t[0] += p[0];
            t[1] += p[1];
        }
        self.stats.increments += 1;
    }

    /// A phase starts: `name` for the progress report, `increments` planned (if known),
    /// `scale` its load factor per unit of the phase's factor.
    fn begin_phase(&mut self, name: &'static str, increments: Option<usize>, scale: f64) {
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
    fn converged(&mut self, factor: f64) {
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
    fn run_phase(&mut self, phase: &Phase, steps: usize) -> Result<(f64, Option<String>)> {
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
            self.held = Held::Nothing;
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
                        return Ok((s, Some(describe(&why))));
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
    /// [`super::mechanism::classify`]) fall out of the structure when they are few: at
    /// most [`FALLOUT_MAX_BLOCKS`] or [`FALLOUT_MAX_SHARE`] of the free blocks at a time.
    /// Each is held where it stood at the last converged increment (its unknowns pinned),
    /// and its contacts carry no force from then on; the committed state keeps the rest.
    /// Returns whether any block fell; a larger mechanism is the structure's failure.
    fn fall_out(&mut self) -> bool {
        let Some(f) = self.failure_mode.as_ref() else {
            return false;
        };
        let mech = super::mechanism::classify(
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
        if super::tracing() {
            eprintln!("fallout: blocks {moving:?} fall out");
        }
        self.stats.fallen_blocks += moving.len();
        self.fallen.extend(moving);
        self.held = Held::Nothing;
        self.failure_mode = None;
        true
    }

    /// The forces (N, horizontal and vertical) and moment (N·m) that hold the rigid block
    /// `block` on its prescribed path: the internal minus the external force at its
    /// unknowns (the vertical one is zero up to the tolerance when it moves freely).
    fn reaction(&self, block: usize, f_int: &[f64], f_ext: &[f64]) -> [f64; 3] {
        match self.cur.blocks[block].dofs {
            crate::mesh::BlockDofs::Rigid { first, .. } => {
                let f = first as usize;
                [0, 1, 2].map(|i| f_int[f + i] - f_ext[f + i])
            }
            _ => [0.0; 3],
        }
    }

    /// A point of the displacement-controlled curve at the phase's factor `s`.
    fn push_point(
        &self,
        block: usize,
        s: f64,
        reaction: Option<[f64; 3]>,
    ) -> super::curve::CurvePoint {
        super::curve::CurvePoint {
            load_factor: s,
            displacement: super::curve::control_displacement(
                &self.cur,
                &self.cur,
                &self.committed.u,
                block,
            ),
            reaction: Some(reaction.unwrap_or([0.0; 3])),
        }
    }

    fn external(&self, acc: Point, with_loads: bool) -> Vec<f64> {
        let mut f = loads::body_force(self.scene, &self.cur, acc);
        if with_loads {
            for (a, b) in f.iter_mut().zip(loads::applied(self.scene, &self.cur)) {
                *a += b;
            }
        }
        f
    }

    fn outcome(
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

fn describe(why: &IncrementFailure) -> String {
    match why {
        IncrementFailure::NoConvergence { residual } => format!("the out-of-balance force stays at {residual:.2e} of the load: the contacts cannot hold it"),
        IncrementFailure::Divergence => "the displacements grow without bound: the blocks move without restraint".to_string(),
    }
}

/// Run a static or capacity analysis.
pub fn run(scene: &Scene, mesh: &Mesh, backend: &mut dyn LinearBackend) -> Result<Outcome> {
    run_with_progress(scene, mesh, None, backend, &mut super::progress::Silent)
}

/// [`run`], reporting phases, iterations and converged increments to `progress`;
/// `ranks`: this process's rows in a distributed run ([`System::distributed`]).
pub fn run_with_progress<'a>(
    scene: &'a Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &'a mut dyn LinearBackend,
    progress: &'a mut dyn Progress,
) -> Result<Outcome> {
    let start = Instant::now();
    let mut d = Driver::new(scene, mesh, ranks, backend)?;
    d.progress = Some(progress);
    let steps = scene.analysis.load_steps;
    // increments of the gravity phase (`gravity_steps`, default `load_steps`): gravity on
    // a structure that stands is nearly linear and needs few
    let gravity_steps =
        super::analysis_number(scene, "gravity_steps", steps as f64, 1.0, 1e6)?.round() as usize;
    let g = scene.model.gravity;
    let gnorm = g[0].hypot(g[1]);
    let n = mesh.n_dofs;
    let zero_presc = vec![[0.0; 2]; mesh.blocks.len()];
    let finish = |d: &mut Driver, status: Status, lf: Option<f64>, mech: Option<Mechanism>| {
        let bs = d.backend.stats();
        d.stats.factorizations = bs.numeric_factorizations
            + d.lu
                .as_ref()
                .map_or(0, |l| l.stats().numeric_factorizations);
        d.stats.tangent_factorizations =
            d.lu.as_ref()
                .map_or(0, |l| l.stats().numeric_factorizations);
        d.stats.symbolic_factorizations = bs.symbolic_factorizations
            + d.lu
                .as_ref()
                .map_or(0, |l| l.stats().symbolic_factorizations);
        d.stats.min_pivot_ratio = bs.min_pivot_ratio;
        d.stats.wall_time_s = start.elapsed().as_secs_f64();
        if super::tracing() {
            eprintln!("solver {bs:?}");
            if let Some(l) = d.lu.as_ref() {
                eprintln!("solver (tangent LU) {:?}", l.stats());
            }
            eprintln!("analysis {} s", d.stats.wall_time_s);
        }
        d.outcome(status, mesh, lf, mech)
    };
    let fail = |d: &mut Driver, what: String, lf: Option<f64>| -> Outcome {
        let mech = d
            .failure_mode
            .as_ref()
            .map(|f| classify(scene, &d.cur, &f.mode, &f.states, &f.forces, &f.loads));
        let blocks = mech.as_ref().map(|m| m.moving()).unwrap_or_default();
        finish(
            d,
            Status::Failed {
                reason: what,
                blocks,
            },
            lf,
            mech,
        )
    };

    // groups of blocks with no chain of contacts down to a fixed block fall: a result
    let floating = super::support::unsupported_blocks(mesh);
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
                        super::mechanism::Motion::Falling
                    } else {
                        super::mechanism::Motion::None
                    },
                )
            })
            .collect();
        let mech = Mechanism {
            blocks,
            mode: "mixed".into(),
        };
        return Ok(finish(
            &mut d,
            Status::Failed {
                reason,
                blocks: floating,
            },
            None,
            Some(mech),
        ));
    }

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
        return Ok(fail(
            &mut d,
            format!("failed under gravity at {:.1} % {of}: {why}", 100.0 * s),
            None,
        ));
    }
    // phase 2: prescribed displacements of fixed blocks
    let presc: Vec<Point> = scene
        .blocks
        .iter()
        .map(|b| b.prescribed.unwrap_or([0.0; 2]))
        .collect();
    if presc.iter().any(|p| *p != [0.0; 2]) {
        let phase = Phase {
            base: f_grav.clone(),
            step: vec![0.0; n],
            presc_step: presc,
            pin_step: Vec::new(),
            record: None,
        };
        d.begin_phase("prescribed", Some(steps), 1.0);
        let (s, why) = d.run_phase(&phase, steps)?;
        if let Some(why) = why {
            return Ok(fail(
                &mut d,
                format!(
                    "failed at {:.1} % of the prescribed displacement: {why}",
                    100.0 * s
                ),
                None,
            ));
        }
    }
    // phase 3: displacement control
    if let Some(push) = d.settings.push {
        let crate::mesh::BlockDofs::Rigid { first, .. } = mesh.blocks[push.block].dofs else {
            unreachable!("Push::from_scene admits rigid blocks only")
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
        let (s, why, increments, accepted) = match d.settings.arc {
            Some(arc) => arc_length::run(&mut d, &phase.base, &push, &arc, steps)?,
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
        let curve = super::curve::Curve {
            control_block: push.block,
            points,
            path: Some(super::curve::PushPath {
                reached: s,
                furthest,
                increments,
                accepted: accepted.0,
                accepted_residual: accepted.1,
                end: why.clone().unwrap_or_else(|| "the end of the push".into()),
            }),
        };
        let mut out = match why {
            Some(why) => fail(
                &mut d,
                format!(
                    "failed at {:.1} % of the push displacement: {why}",
                    100.0 * s
                ),
                None,
            ),
            None => finish(&mut d, Status::Stable, None, None),
        };
        out.capacity_curve = Some(curve);
        return Ok(out);
    }
    let f_base = d.external(g, true);
    let f_lat = d.external([gnorm, 0.0], false);
    match scene.analysis.kind {
        AnalysisType::Static => {
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
                        &mut d,
                        format!(
                            "failed at a lateral coefficient of {:.4}: {why}",
                            s * scene.analysis.lateral
                        ),
                        Some(s * scene.analysis.lateral),
                    ));
                }
            }
            Ok(finish(&mut d, Status::Stable, None, None))
        }
        AnalysisType::Capacity => {
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
            let control = super::curve::control_block(mesh);
            let curve_point = |d: &Driver, lambda: f64, block: usize| super::curve::CurvePoint {
                load_factor: lambda,
                displacement: super::curve::control_displacement(
                    mesh,
                    &d.cur,
                    &d.committed.u,
                    block,
                ),
                reaction: None,
            };
            let mut curve: Vec<super::curve::CurvePoint> = control
                .map(|b| curve_point(&d, 0.0, b))
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
            loop {
                let narrow = upper.is_finite()
                    && upper - lambda
                        <= d.settings.bracket * lambda.max(d.settings.initial_step * 1e-3);
                if (narrow && upper_full)
                    || step <= 1e-12 * d.settings.initial_step
                    || lambda > limit
                {
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
                if super::tracing() {
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
                            curve.push(curve_point(&d, lambda, b));
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
                        d.failure_mode = Some(dq);
                        if target < upper {
                            upper_full = !d.probing;
                        } else {
                            upper_full |= !d.probing;
                        }
                        upper = upper.min(target);
                        last_fail = Some(describe(&why));
                        step = 0.5 * (target - lambda);
                    }
                }
            }
            let curve = control.map(|control_block| super::curve::Curve {
                control_block,
                points: curve,
                path: None,
            });
            if lambda > limit {
                let mut out = finish(&mut d, Status::Stable, Some(lambda), None);
                out.capacity_curve = curve;
                return Ok(out);
            }
            let mut out = fail(
                &mut d,
                format!(
                    "critical load factor {lambda:.6} (bracket [{lambda:.6}, {upper:.6}]): {}",
                    last_fail.unwrap_or_default()
                ),
                Some(lambda),
            );
            out.load_factor = Some(lambda);
            out.capacity_curve = curve;
            Ok(out)
        }
        AnalysisType::Dynamic => unreachable!("the dynamic driver runs elsewhere"),
    }
}

/// Per contact, the changes between closed and open in the iterations of an increment
/// (or of a try of a time step), counted where the contact carries a force that matters
/// on one side: what breaks the bonds that cannot hold ([`BOND_BREAK_FLIPS`],
/// [`Driver::break_cycling_bonds`] and the dynamic driver's
/// `Dynamics::break_cycling_bonds`). Empty, counting nothing, where no joint has a bond
/// to break.
pub(super) struct OpenFlips(Vec<u32>);

impl OpenFlips {
    pub(super) fn new(bonded: bool, contacts: usize) -> Self {
        OpenFlips(vec![0; if bonded { contacts } else { 0 }])
    }

    /// Count the changes from the last iteration's states `prev_state` (forces
    /// `prev_force`) to `trial`'s, where the contact carries a force above `negligible`
    /// (N) on one side; nothing at the first iteration (`it` = 0).
    pub(super) fn count(
        &mut self,
        it: usize,
        trial: &Trial,
        (prev_state, prev_force): (&[ContactState], &[[f64; 2]]),
        negligible: f64,
    ) {
        if it == 0 {
            return;
        }
        let matters = |f: [f64; 2]| f[0].hypot(f[1]) > negligible;
        for (k, flips) in self.0.iter_mut().enumerate() {
            let open = trial.state[k] == ContactState::Open;
            if open != (prev_state[k] == ContactState::Open)
                && (matters(trial.force[k]) || matters(prev_force[k]))
            {
                *flips += 1;
            }
        }
    }

    /// Break the bond of every contact that changed [`BOND_BREAK_FLIPS`] times, is not
    /// `skip`ped and whose bond `broken_bond(k, history)` breaks: its `history` set to
    /// broken, the history it had pushed onto `broken` (to give back if the iterations
    /// still fail). Whether any broke.
    pub(super) fn break_bonds(
        &self,
        history: &mut [crate::material::History],
        broken_bond: impl Fn(usize, crate::material::History) -> Option<crate::material::History>,
        skip: impl Fn(usize) -> bool,
        broken: &mut Vec<(usize, crate::material::History)>,
    ) -> bool {
        let mut broke = false;
        for (k, &flips) in self.0.iter().enumerate() {
            if flips < BOND_BREAK_FLIPS || k >= history.len() || skip(k) {
                continue;
            }
            if let Some(b) = broken_bond(k, history[k]) {
                if super::tracing() {
                    eprintln!("  bond broken: contact {k} after {flips} changes");
                }
                broken.push((k, history[k]));
                history[k] = b;
                broke = true;
            }
        }
        broke
    }

    /// Give the bonds broken by [`OpenFlips::break_bonds`] back to `history` (`broken`
    /// emptied): the iterations they were broken in did not lead to a committed state.
    pub(super) fn give_back(
        history: &mut [crate::material::History],
        broken: &mut Vec<(usize, crate::material::History)>,
    ) {
        for (k, h) in broken.drain(..) {
            history[k] = h;
        }
    }
}
