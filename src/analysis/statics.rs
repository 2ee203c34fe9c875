//! Nonlinear static and capacity analysis (docs/theory.md §4, seed §4): loads in increments of
//! a load factor; in each increment, iterations in which the contacts' excess forces are
//! re-applied (the residual λF − F_int) until the out-of-balance force is below a relative
//! tolerance and no contact changes state; the geometry is updated after each converged
//! increment. Failure (a mechanism) is a non-convergence after increment cutting; the
//! capacity analysis brackets the critical load factor between the last converged and
//! the first failed increment.

use super::config::{secant_local, tangent_local, Committed, Inputs, Trial};
use super::correction::{CorrectionSolver, Held};
use super::mechanism::{classify, Mechanism};
use super::progress::{Increment, Progress};
use super::solver::{
    self, IterationControls, OpenFlips, LINE_SEARCH_STEPS, LONG_LINE_SEARCH_STEPS,
};
use super::{Outcome, Stats, Status};
use crate::assembly::{loads, LocalStiffness, Ranks, System};
use crate::geometry::polygon::Point;
use crate::material::{ContactLaw, ContactState, JointLaw, PerContact};
use crate::mesh::Mesh;
use crate::scene::{AnalysisType, Scene};
use crate::solve::LinearBackend;
use crate::Result;
use dfem_kernels::{CsrMatrix, CONSTRAINED};
use std::time::Instant;

pub mod arc_length;
mod corrections;
mod increment;
mod run;
mod search;

pub use run::run_with_progress;

pub use crate::scene::settings::{Push, StaticSettings as Settings, Strategy};

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
/// The free motion is taken when the out-of-balance norm after it is below this many
/// times the norm after the iteration's own step: the norm is not what the motion
/// lowers (see [`Driver::free_motion`]), and the next iteration, with the contact that
/// stuck now holding the group, removes what it leaves
/// (docs/decisions/0007-free-motion-constants.md).
const MODE_ACCEPT: f64 = 3.0;

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
    /// The linear algebra of the corrections: the backend, what it holds factorized,
    /// the tangent LU and the matrix buffers (the shared [`CorrectionSolver`]).
    lin: CorrectionSolver<'a>,
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
    /// The arc-length path ended on an increment whose iterations did not converge under
    /// any constraint, at this relative out-of-balance force (`arc_length::run`).
    path_stall: Option<f64>,
    /// The top-most free block ([`super::curve::control_block`]), whose displacement a
    /// push's curve records beside the pushed block's.
    top_block: Option<usize>,
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
/// nearly every trial; more would only hold memory
/// (docs/decisions/0017-trial-evaluation-overhead.md).
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

/// An increment stops as not converged when its out-of-balance norm has not fallen below
/// [`STALL_PROGRESS`] times its best value for this many iterations. Past the limit load
/// the secant iterations stagnate at a fixed residual, while converging increments near
/// the limit still gain 10 % within at most 25 iterations
/// (docs/decisions/0003-stall-window-and-tangent-fallback.md).
const STALL_ITERATIONS: usize = 60;
/// The stall windows of a capacity search's probes ([`Driver::stall_window`]): secant
/// iterations, then tangent steps. Half the secant window still covers the slowest
/// converging increment measured near the limit (10 % gained within 25 iterations, the
/// 30×30 wall above); a probe that fails within them only narrows the bracket, and the
/// failure that closes it is confirmed with the full windows
/// (docs/decisions/0004-capacity-probe-windows.md).
const PROBE_STALL_ITERATIONS: usize = 30;
const PROBE_TANGENT_STALL_ITERATIONS: usize = 10;
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
    /// The out-of-balance norm of the last trial relative to the force scale (as the
    /// tolerance measures it).
    pub residual: f64,
    /// The free block that carries the largest out-of-balance force of the last trial
    /// (at one node, or a rigid block's centroid) and that force (N).
    pub worst: Option<(usize, f64)>,
    /// Whether the failure shows a mechanism (docs/outputs.md, "summary.json"): the
    /// increment diverged or its secant matrix was singular (a free mode), or a contact
    /// of its last trial slips or is open. With every contact sticking the blocks are held
    /// elastically and no mechanism can form: the iterations stopped converging.
    pub mechanism: bool,
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
        let settings = scene.analysis.settings.statics()?.clone();
        let system = System::new(scene, mesh).distributed(ranks);
        let pattern = system.plan.pattern().clone();
        // a failed factorization only says "singular" here: no LDLᵀ for its pivot's value
        backend.set_failed_pivot_value(false);
        let law = PerContact::of_scene(scene, mesh);
        let t = scene.model.thickness;
        let area = mesh.contacts.iter().map(|c| c.length * t).collect();
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
            lin: CorrectionSolver::new(backend, pattern),
            probing: false,
            converged_norm: 0.0,
            scale_floor: 0.0,
            stats: Stats {
                dofs: mesh.n_dofs,
                contacts: mesh.contacts.len(),
                triangles: mesh.triangles.len(),
                ..Default::default()
            },
            failure_mode: None,
            presc_total: vec![[0.0; 2]; mesh.blocks.len()],
            progress: None,
            report: Report::default(),
            pins: Vec::new(),
            push_curve: Vec::new(),
            path_stall: None,
            top_block: super::curve::control_block(mesh),
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

    /// [`Driver::local_stiffness`] with the contact forces `force` (N; read for the sign of
    /// the shear force when `newton`).
    fn local_of(
        &self,
        force: &[[f64; 2]],
        states: &[ContactState],
        newton: bool,
    ) -> Vec<LocalStiffness> {
        corrections::contact_local(&self.law, &self.area, &self.flips, force, states, newton)
    }

    fn elastic_local(&self) -> Vec<LocalStiffness> {
        self.area
            .iter()
            .enumerate()
            .map(|(k, &a)| crate::assembly::diagonal(self.law.get(k).springs(a)))
            .collect()
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
        let trial = self.trial(&dq, presc);
        let scale = self.force_scale(f_ext, &trial.f_int);
        let size = self.model_size();
        self.lin.gmres_failed = false;
        let controls = IterationControls {
            tolerance: self.settings.tolerance,
            max_iterations: self.settings.max_iterations,
            stall_progress: STALL_PROGRESS,
        };
        let mut increment = increment::Increment {
            d: self,
            f_ext,
            presc,
            extrapolated,
            dq,
            trial,
            r: Vec::new(),
            scale,
            size,
            singular_streak: 0,
            tangent_only: false,
        };
        let end = solver::iterate(&mut increment, &controls)?;
        increment.finish(end)
    }

    /// The failure of an increment whose last trial is `trial` under `f_ext` (N), `mode`
    /// its failure mode; `free_mode`: it diverged or its secant matrix was singular.
    fn failure(&self, mode: Vec<f64>, trial: &Trial, f_ext: &[f64], free_mode: bool) -> Failure {
        let r = self.out_of_balance(f_ext, &trial.f_int);
        let at = |d: u32| if d == CONSTRAINED { 0.0 } else { r[d as usize] };
        let mut worst: Option<(usize, f64)> = None;
        for (bi, b) in self.cur.blocks.iter().enumerate() {
            let f = match b.dofs {
                crate::mesh::BlockDofs::Rigid { first, .. } => at(first).hypot(at(first + 1)),
                crate::mesh::BlockDofs::Deformable => b.nodes.clone().fold(0.0f64, |m, n| {
                    let d = self.cur.node_dofs[n as usize];
                    m.max(at(d[0]).hypot(at(d[1])))
                }),
                crate::mesh::BlockDofs::Fixed => continue,
            };
            if worst.is_none_or(|w| f > w.1) {
                worst = Some((bi, f));
            }
        }
        let residual = Driver::norm(&r) / self.force_scale(f_ext, &trial.f_int);
        let mechanism = free_mode || trial.state.iter().any(|s| *s != ContactState::Stick);
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
            residual,
            worst,
            mechanism,
        }
    }

    /// Breaks the bonds that cannot hold, where an increment's iterations stalled: every
    /// bonded contact (cohesion or tensile strength, intact) that went closed → open →
    /// closed → open ([`solver::BOND_BREAK_FLIPS`], `open_flips`: [`OpenFlips`]) in them
    /// has its bond broken for good from there on (docs/theory.md, "Bonds that cannot
    /// hold"). Such a contact sits at the jump of its law: closed it carries a cohesive
    /// shear that its equilibrium holds only with the contact in tension, past its
    /// strength, and open it carries nothing, and its equilibrium closes it again. No
    /// intact state is consistent, so the iterations cycle until the stall rule fails the
    /// increment (a false collapse: the free-surface tunnel of docs/decisions/0009-breaking-cycling-bonds.md),
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
        self.lin.moved();
        for (t, p) in self.presc_total.iter_mut().zip(presc) {
            t[0] += p[0];
            t[1] += p[1];
        }
        self.stats.increments += 1;
    }
}

/// Run a static or capacity analysis.
pub fn run(scene: &Scene, mesh: &Mesh, backend: &mut dyn LinearBackend) -> Result<Outcome> {
    run_with_progress(scene, mesh, None, backend, &mut super::progress::Silent)
}
