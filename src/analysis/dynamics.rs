//! Implicit dynamic analysis (docs/theory.md §5): M ü + C u̇ + F_int(u) = F(t), seed Eq. 12,
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
//! iterated within the step with the secant stiffness (docs/theory.md §4), the effective
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
use super::correction::CorrectionSolver;
use super::solver::{self, IterationControls, OpenFlips, LINE_SEARCH_STEPS};
use super::{fit_motion, Outcome, Stats, Status};
use crate::assembly::{loads, mass, LocalStiffness, Ranks, System};
use crate::geometry::polygon::Point;
use crate::material::{block_elastic, ContactLaw, ContactSprings, ContactState, MohrCoulomb};
use crate::mesh::{contacts, BlockDofs, Mesh};
use crate::scene::ground_motion;
use crate::scene::{AnalysisSettings, Scene, StaticSettings};
use crate::solve::LinearBackend;
use crate::Result;
use dfem_kernels::CsrMatrix;
use std::time::Instant;

mod advance;
mod run;
mod step;
mod step_try;

pub use run::{
    run, run_from, step_count, step_time, tracked, FrameSchedule, FRAME_INTERVAL, MAX_FRAMES,
};

/// Open/closed changes of a contact within a step after which its normal spring stays
/// in the matrix (see [`Dynamics::step`]).
const FLIPS_BEFORE_ELASTIC: u32 = 2;
/// A step's iterations switch to tangent steps (once the contact states settle) only
/// where the secant iteration contracts the out-of-balance norm by less than this
/// factor an iteration, and then keep to them until a state changes. Always switching
/// (factor 0) led the seed arch's collapse through contact sequences that cost 30 times
/// the iterations (docs/decisions/0019-dynamic-tangent-steps.md).
const TANGENT_SLOW: f64 = 0.5;
/// Iterations of a try of a step (not of the smallest length) without progress after
/// which it is given up and the step cut, as it would be after `max_iterations`:
/// progress is an out-of-balance norm below [`STALL_PROGRESS`] of the try's best so
/// far. Tries that converge nearly all do so within 10 iterations; those that cycle
/// among the states of a few contacts at their kinks held 44 % of the iterations
/// (docs/decisions/0020-dynamic-stall-rule.md).
const STALL_ITERATIONS: usize = 20;
/// See [`STALL_ITERATIONS`].
const STALL_PROGRESS: f64 = 0.5;
/// Largest turn (rad) of a deformable block within a step for which its triangles stay
/// on the step's start geometry in the iteration matrix ([`Dynamics::effective_into`]):
/// rocking drums turn less, a falling voussoir more
/// (docs/decisions/0021-start-geometry-interiors.md).
const START_GEOMETRY_TURN: f64 = 1e-3;
/// Factor on that spring per iteration the contact stays open.
const OPEN_WEIGHT_DECAY: f64 = 0.1;
/// Open/closed changes of a contact within a try of a step after which it is held open
/// for the rest of the try (at the smallest step length whatever its force, above it
/// only below [`HOLD_OPEN_FORCE`]): a contact at the kink of its law makes the iterations
/// cycle whatever its spring; held open, the step converges
/// (docs/decisions/0022-release-redo-and-held-open-contacts.md).
const FREEZE_FLIPS: u32 = 6;
/// The largest force (fraction of the step's force scale) a contact may have carried
/// closed within a try for [`FREEZE_FLIPS`] to hold it open above the smallest step
/// length: a contact whose force matters is never held open there
/// (docs/decisions/0022-release-redo-and-held-open-contacts.md).
const HOLD_OPEN_FORCE: f64 = 1e-3;
/// The least force (fraction of the step's force scale at its start) a contact closed at
/// a step's start must carry for its dashpots and its share of Rayleigh's a₁ K to act over
/// the step: a contact touching with no force sits at the kink of its law, where damping
/// makes the iterations cycle (docs/decisions/0023-dashpots-and-rayleigh.md).
const DASHPOT_FORCE: f64 = 1e-3;
/// Penetration (fraction of the band thickness) a contact held open may end a step with
/// before the step is cut, and the most a new contact starts with.
const HELD_PENETRATION: f64 = 0.1;

pub use crate::scene::settings::{DynamicSettings as Settings, Scheme, Start};

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
    /// The full state at a frame (at the steps of [`FrameSchedule`]), the monitor's to
    /// keep (the output writer hands it to its thread).
    fn frame(&mut self, _step: usize, _time: f64, _state: Outcome) -> Result<()> {
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
    /// The effective matrices' buffers (`kbuf` the secant's, `aux` the tangent's, at its
    /// first use) and the backend: the shared correction solver.
    lin: CorrectionSolver<'a>,
    /// C of the last trial balanced, on its geometry (the viscous force C v₁).
    cbuf: Option<CsrMatrix>,
    /// C on the step's start geometry, in the states of the matrix being built
    /// ([`Dynamics::effective_into`]).
    cmat: Option<CsrMatrix>,
    diag: Vec<usize>,
    /// Dₑ⁻¹ (1/Pa) of each triangle's material (elastic energy).
    compliance: Vec<[[f64; 3]; 3]>,
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
/// viscosities (cₙ, cₛ) = (Eₙ*, Gₛ*) A_c / h (N·s/m), docs/theory.md §3.
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
        let settings = scene.analysis.settings.dynamics()?.clone();
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
            lin: CorrectionSolver::new(backend, pattern),
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
            .stiffness_into(&self.cur, &local, &mut self.lin.kbuf);
        self.lin
            .kbuf
            .values
            .iter_mut()
            .for_each(|k| *k *= beta * h * h);
        for (i, &p) in self.diag.iter().enumerate() {
            self.lin.kbuf.values[p] += self.mass[i];
        }
        let mut x = r;
        if self.lin.factorize(false) && self.lin.solve(&mut x) {
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
        scene.analysis.settings = AnalysisSettings::Static(StaticSettings {
            tolerance: self.settings.tolerance,
            ..StaticSettings::default()
        });
        for b in &mut scene.blocks {
            b.prescribed = None;
        }
        let silent = &mut super::progress::Silent;
        let run = super::statics::run_with_progress(
            &scene,
            initial,
            self.ranks,
            &mut *self.lin.backend,
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
            .stiffness_into(&self.cur, &local, &mut self.lin.kbuf);
        let r: Vec<f64> = self
            .f_static
            .iter()
            .zip(&self.f_int)
            .map(|(f, g)| f - g)
            .collect();
        let load = norm(&r);
        let x = self.lin.factor_solve(false, &r)?;
        let (Some(x), false) = (x, load == 0.0) else {
            return Ok(());
        };
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
        self.lin.new_pattern(pattern.clone());
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

#[cfg(test)]
mod tests;
