//! Analyses: the static and capacity driver ([`statics`]) and implicit time integration
//! ([`dynamics`]).

pub mod checkpoint;
pub mod config;
pub(crate) mod correction;
pub mod curve;
pub mod dynamics;
pub mod mechanism;
pub mod progress;
pub mod solver;
pub mod statics;
pub mod support;

/// The search for new contacts during a run, now with the contacts found along the
/// joints in [`crate::mesh::contacts`]; kept under its former name.
pub use crate::mesh::contacts as contact_search;

use crate::assembly::{cst_b, loads, Ranks};
use crate::material::{block_elastic, ContactLaw, ContactSprings, ContactState, ElasticBand};
use crate::mesh::Mesh;
use crate::scene::{AnalysisType, Scene};
use crate::solve::LinearBackend;
use crate::{Error, Result};

/// Whether the structure stands.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    Stable,
    /// The structure failed; the reason says how it was detected.
    Failed {
        reason: String,
        blocks: Vec<usize>,
    },
    /// The iterations of a static or capacity run stopped converging with no mechanism
    /// in sight (docs/outputs.md, "summary.json", `"not_converged"`): `reason` says
    /// where, `residual` is the out-of-balance norm left relative to the load, `block`
    /// the free block with the largest out-of-balance force and that force (N).
    NotConverged {
        reason: String,
        residual: f64,
        block: Option<(usize, f64)>,
    },
    /// A dynamic run stopped on request (Ctrl-C) after the step that reached `time` (s);
    /// its checkpoint lets `dfem run --resume` continue it.
    Interrupted {
        time: f64,
    },
}

/// Counters written to `summary.json` stats.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    pub dofs: usize,
    pub contacts: usize,
    pub triangles: usize,
    pub increments: usize,
    pub iterations: usize,
    pub factorizations: usize,
    pub symbolic_factorizations: usize,
    /// Distinct contact sets a dynamic run went through (1 + the changes made by the
    /// search for new contacts, [`crate::mesh::contacts`]); each needs one symbolic
    /// analysis.
    pub contact_topologies: usize,
    /// Corrections solved with an earlier factorization as preconditioner instead of a
    /// refactorization: secant ones (few contacts changed state) by conjugate gradients,
    /// tangent ones of the secant strategy by GMRES on the secant factorization, and the
    /// dynamic driver's tangent steps (GMRES on the step's secant factorization).
    pub reused_factorizations: usize,
    /// Conjugate-gradient and GMRES iterations of those corrections.
    pub reuse_iterations: usize,
    /// Secant corrections solved with the held factorization corrected exactly for the
    /// contacts that changed state since it was computed (a low-rank change,
    /// `LinearBackend::solve_changed`), neither refactorized nor iterated; not counted in
    /// `reused_factorizations`.
    pub low_rank_corrections: usize,
    /// Largest rank of those changes (signed rank-one terms; ≤ 2 per changed contact).
    pub low_rank_max_rank: usize,
    /// Tangent corrections of the secant strategy that GMRES did not solve and whose LU
    /// factorization would have been too large (`TANGENT_LU_MAX_ENTRIES` in
    /// src/analysis/statics.rs): the secant correction was taken instead.
    pub tangent_lu_skipped: usize,
    /// Numeric LU factorizations of a tangent matrix (the static driver's Newton
    /// corrections, and its secant strategy's tangent ones that GMRES on the secant
    /// factorization did not solve; every tangent correction of the arc-length path);
    /// included in `factorizations`.
    pub tangent_factorizations: usize,
    /// Increments of the secant strategy that went on with tangent (Newton) steps after
    /// the secant iterations stalled.
    pub tangent_fallbacks: usize,
    /// Iterations of the static driver that moved groups of blocks held only by slipping
    /// and open contacts along their free motion (`Driver::free_motion`, docs/theory.md §4).
    pub free_motions: usize,
    /// Iterations of the static driver whose step length came from the slope line search
    /// (`Driver::slope_search`, docs/theory.md, "The slope line search") after no
    /// backtracked length lowered the out-of-balance norm.
    pub slope_searches: usize,
    /// Bonded contacts (cohesion or tensile strength, Mohr–Coulomb) that the static
    /// driver broke within an increment after they cycled between closed and open in its
    /// iterations (`Driver::break_cycling_bonds`, docs/theory.md, "Bonds that cannot
    /// hold"); counted again if the increment is cut and they break again.
    pub bonds_broken: usize,
    /// Blocks that fell out of the structure and were taken out of the analysis
    /// (`[analysis] fallout = true`, docs/theory.md "Fallout").
    pub fallen_blocks: usize,
    /// Halvings of a static increment after it failed (the phases of gravity, lateral
    /// load, `[[load]]` and prescribed motions, and the arc-length path's halvings of its
    /// constraints' steps; not the capacity search's retries, which narrow its bracket):
    /// a phase of `steps` increments whose every cut came in its first increment runs
    /// `steps × 2^cuts` increments.
    pub load_cuts: usize,
    /// Arc-length iterations that converged with contacts frozen by the contact-state
    /// corrector and were checked against the true laws (docs/theory.md, Eq. F2).
    pub contact_releases: usize,
    /// Converged time steps of a dynamic run cut because a contact closed by more than
    /// the band thickness within the step (an impact the step could not resolve).
    pub impact_cuts: usize,
    /// Contacts of a dynamic run held open for the rest of a time step after cycling
    /// between open and closed in its iterations.
    pub held_open: usize,
    /// Iterations of the static analysis of gravity that gave a dynamic run its start
    /// (`initial = "equilibrium"`, [`dynamics::Start::Equilibrium`]; 0 where the elastic
    /// start was already in balance). Not in `iterations`.
    pub static_start_iterations: usize,
    /// Tries of a dynamic time step given up and cut after the dynamic driver's
    /// `STALL_ITERATIONS` (20) iterations without progress (before `max_iterations`).
    pub stalled_steps: usize,
    /// Converged time steps cut because their local error exceeded
    /// `adaptive_tolerance`.
    pub error_cuts: usize,
    /// Converged time steps cut to locate a stick–slip event of a contact within them
    /// (`event_cuts`, docs/theory.md §5, "Stick–slip events").
    pub event_cuts: usize,
    /// The local error estimate of the time steps (m; `Dynamics::step_error`, the
    /// largest node displacement of h² (β − 1/6)(a₁ − a₀)): its largest value over the
    /// steps and its sum, an estimate of the error the steps accumulated.
    pub step_error_max: f64,
    pub step_error_sum: f64,
    /// Time steps of a dynamic run redone because a contact that carried force at their
    /// start let go within them (`impact_reset`, docs/theory.md §5), and the iterations
    /// of those redos (included in `iterations`): each starts from the first try's
    /// answer.
    pub release_redos: usize,
    pub release_redo_iterations: usize,
    pub wall_time_s: f64,
    pub min_pivot_ratio: f64,
    /// Stored entries of the last factor of the linear backend (its memory is 8 bytes
    /// each plus indices); 0 for iterative backends.
    pub factor_nnz: usize,
    /// MPI processes whose rows made the matrices (`mpirun -n N`: N, each assembling its
    /// own rows, [`crate::assembly::Ranks`]); 1 for a serial run.
    pub processes: usize,
    /// Peak resident memory of the process at the end of the analysis (MB, 10⁶ bytes),
    /// `None` where the operating system does not tell ([`crate::resources`]).
    pub peak_memory_mb: Option<f64>,
}

/// The state of a solved model: unknowns, node displacements, stresses, contact forces.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub status: Status,
    /// Total unknowns (m, rad).
    pub u: Vec<f64>,
    /// Total displacement of every node (m).
    pub node_disp: Vec<[f64; 2]>,
    /// Cauchy stress of every triangle (σxx, σyy, σxy) (Pa).
    pub stress: Vec<[f64; 3]>,
    /// Per contact: normal and shear force (N), normal positive in tension.
    pub contact_forces: Vec<[f64; 2]>,
    pub contact_states: Vec<ContactState>,
    /// Per contact: the history variables of its law ([`crate::material::History`]):
    /// the spent fraction ξ of a softening joint's fracture energy (0–1) and the plastic
    /// relative displacement κ₃ on its compression cap (m, docs/theory.md Eq. C2), zero
    /// for laws without history. Both only grow, so they record what a contact went
    /// through during the run (a toe that crushed and then unloaded keeps its κ₃).
    pub contact_history: Vec<crate::material::History>,
    pub stats: Stats,
    /// Capacity: the critical load factor λ (last converged).
    pub load_factor: Option<f64>,
    pub mechanism: Option<mechanism::Mechanism>,
    /// The final configuration (updated Lagrangian), when it differs from the mesh.
    pub current: Option<Mesh>,
    /// Capacity: λ against the control block's displacement, per converged increment.
    pub capacity_curve: Option<curve::Curve>,
    /// Dynamic: the time history (history.csv).
    pub history: Option<dynamics::History>,
    /// Static with `fallout = true`: the blocks that fell out of the structure, in the
    /// order they fell (docs/theory.md, "Fallout").
    pub fallen: Vec<usize>,
}

/// Pivot ratio below which the factorization is taken as singular: a mechanism (docs/theory.md
/// §4, "the global stiffness matrix becomes ill-conditioned"). Round-off on a singular
/// matrix leaves ratios near 1e-16 times the condition of the rest; stiff joints on soft
/// blocks stay far above 1e-12.
pub const SINGULAR_PIVOT_RATIO: f64 = 1e-12;

/// Whether the backend's last factorization showed a singular matrix by its pivot ratio
/// ([`SINGULAR_PIVOT_RATIO`]). A backend that does not measure pivots reports NaN (PCG,
/// PETSc; MUMPS when its null-pivot detection found nothing): not singular by this test,
/// its factorization or solve fails instead on a mechanism.
pub fn singular_pivots(backend: &dyn crate::solve::LinearBackend) -> bool {
    backend.stats().min_pivot_ratio < SINGULAR_PIVOT_RATIO
}

/// Run the scene's analysis.
pub fn run(scene: &Scene, mesh: &Mesh, backend: &mut dyn LinearBackend) -> Result<Outcome> {
    run_with(
        scene,
        mesh,
        None,
        backend,
        &mut progress::Silent,
        &mut dynamics::NoMonitor,
    )
}

/// Run the scene's analysis, telling `progress` how a static or capacity analysis goes
/// (phases, iterations, converged increments); a dynamic one streams its history and
/// frames to `monitor`. `ranks`: this process's rows in a distributed run (from
/// [`crate::solve::configure_run`]), `None` serial. The results are those of [`run`].
pub fn run_with(
    scene: &Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &mut dyn LinearBackend,
    progress: &mut dyn progress::Progress,
    monitor: &mut dyn dynamics::Monitor,
) -> Result<Outcome> {
    if scene.analysis.kind != AnalysisType::Dynamic {
        // a free block that touches nothing at all is a modelling mistake (misplaced
        // coordinates, a tolerance too small), not a structure
        // one pass over the contacts (a search per block was quadratic: 6 s of a 10⁵-unknown
        // wall's 8.6 s run, docs/performance.md, "Growth with the size of the model")
        let mut touched = vec![false; mesh.blocks.len()];
        for c in &mesh.contacts {
            touched[c.block_l as usize] = true;
            touched[c.block_m as usize] = true;
        }
        let isolated: Vec<usize> = (0..mesh.blocks.len())
            .filter(|&b| mesh.blocks[b].dofs != crate::mesh::BlockDofs::Fixed && !touched[b])
            .collect();
        if let Some(&b) = isolated.first() {
            let names: Vec<&str> = isolated
                .iter()
                .take(5)
                .map(|&i| scene.blocks[i].name.as_str())
                .collect();
            return Err(Error::new(format!(
                "{} free block(s) touch no other block ({}{}), so a static analysis has nothing to hold them",
                isolated.len(),
                names.join(", "),
                if isolated.len() > 5 { ", ..." } else { "" }
            ))
            .line(scene.blocks[b].line)
            .place(format!("block '{}'", scene.blocks[b].name))
            .fix("place the blocks on a fixed block (support = \"fixed\"), or raise [contacts] tolerance if they should touch"));
        }
    }
    if scene.analysis.kind == AnalysisType::Dynamic {
        if let Some(joint) = scene.joints.iter().find(|j| !j.blocks.is_empty()) {
            return Err(Error::new(format!(
                "joint '{}' is given to some blocks, and the dynamic analysis gives every contact the [contacts] joint",
                joint.name
            ))
            .place(format!("joint '{}' key 'blocks'", joint.name))
            .fix("remove the key 'blocks' for a dynamic run, or run a static or capacity analysis"));
        }
        if let Some(joint) = scene.joints.iter().find(|j| j.within_unit) {
            return Err(Error::new(format!(
                "joint '{}' is given to the potential cracks of split bricks, and the dynamic analysis gives every contact the [contacts] joint",
                joint.name
            ))
            .place(format!("joint '{}' key 'within'", joint.name))
            .fix("remove the key 'within' for a dynamic run, or run a static or capacity analysis"));
        }
        let j = scene.contacts.joint;
        if let Some(joint) = scene.joints.get(j) {
            if joint.softening != crate::scene::JointSoftening::None {
                return Err(Error::new(format!(
                    "joint '{}' softens, and the dynamic analysis does not follow the softening of joints",
                    joint.name
                ))
                .place(format!("joint '{}' key 'softening'", joint.name))
                .fix("run a static or capacity analysis with this joint, or remove softening (and the fracture energies) for a dynamic run"));
            }
        }
    }
    let mut out = match scene.analysis.kind {
        AnalysisType::Static | AnalysisType::Capacity => {
            statics::run_with_progress(scene, mesh, ranks, backend, progress)
        }
        AnalysisType::Dynamic => dynamics::run(scene, mesh, ranks, backend, monitor),
    }?;
    record_resources(&mut out, ranks, backend);
    Ok(out)
}

/// Continue a dynamic run from a checkpoint of the same scene ([`dynamics::run_from`]).
pub fn resume_with(
    scene: &Scene,
    mesh: &Mesh,
    ranks: Option<&Ranks>,
    backend: &mut dyn LinearBackend,
    monitor: &mut dyn dynamics::Monitor,
    from: checkpoint::Checkpoint,
) -> Result<Outcome> {
    let mut out = dynamics::run_from(scene, mesh, ranks, backend, monitor, Some(from))?;
    record_resources(&mut out, ranks, backend);
    Ok(out)
}

/// The factor size and the peak memory of the process, into the outcome's stats.
fn record_resources(out: &mut Outcome, ranks: Option<&Ranks>, backend: &dyn LinearBackend) {
    out.stats.processes = ranks.map_or(1, |r| r.size as usize);
    out.stats.factor_nnz = backend.stats().factor_nnz;
    out.stats.peak_memory_mb = crate::resources::peak_resident_bytes().map(|b| b as f64 / 1e6);
}

/// Whether the drivers print their iterations to stderr (`DFEM_TRACE` set), read once.
pub(crate) fn tracing() -> bool {
    static TRACE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *TRACE.get_or_init(|| std::env::var_os("DFEM_TRACE").is_some())
}

/// Springs of every contact under the elastic band law.
pub fn elastic_springs(scene: &Scene, mesh: &Mesh) -> Vec<ContactSprings> {
    if mesh.contacts.is_empty() {
        return Vec::new();
    }
    let law = ElasticBand::from_joint(&scene.joints[scene.contacts.joint]);
    let t = scene.model.thickness;
    mesh.contacts
        .iter()
        .map(|c| law.springs(c.length * t))
        .collect()
}

/// External load (N): gravity, the `lateral` body force (a fraction of the weight, +x),
/// and the `[[load]]` forces.
pub fn external_load(scene: &Scene, mesh: &Mesh) -> Vec<f64> {
    let g = scene.model.gravity;
    let gnorm = g[0].hypot(g[1]);
    let mut f = loads::body_force(scene, mesh, [g[0] + scene.analysis.lateral * gnorm, g[1]]);
    for (a, b) in f.iter_mut().zip(loads::applied(scene, mesh)) {
        *a += b;
    }
    f
}

/// Stress (σxx, σyy, σxy) (Pa) of every triangle: σ = Dₑ B uₑ.
pub fn triangle_stresses(scene: &Scene, mesh: &Mesh, u: &[f64]) -> Vec<[f64; 3]> {
    mesh.triangles
        .iter()
        .zip(&mesh.tri_block)
        .map(|(t, &b)| {
            let d = block_elastic(
                &scene.materials[scene.blocks[b as usize].material],
                scene.model.plane,
            );
            let (bm, _) = cst_b(t.map(|n| mesh.nodes[n as usize]));
            let mut ue = [0.0; 6];
            for (k, &n) in t.iter().enumerate() {
                let dn = mesh.node_displacement(n, u);
                ue[2 * k] = dn[0];
                ue[2 * k + 1] = dn[1];
            }
            let eps: [f64; 3] = std::array::from_fn(|i| (0..6).map(|j| bm[i][j] * ue[j]).sum());
            std::array::from_fn(|i| (0..3).map(|j| d[i][j] * eps[j]).sum())
        })
        .collect()
}

/// Displacement of the centroid (m) and rotation (rad, counter-clockwise) of a block for
/// the unknowns `u` (linear map of the unknowns to the nodes).
pub fn block_motion(mesh: &Mesh, block: usize, u: &[f64]) -> ([f64; 2], f64) {
    if let crate::mesh::BlockDofs::Rigid { first, .. } = mesh.blocks[block].dofs {
        let f = first as usize;
        return ([u[f], u[f + 1]], u[f + 2]);
    }
    let disp: Vec<[f64; 2]> = mesh.blocks[block]
        .nodes
        .clone()
        .map(|n| mesh.node_displacement(n, u))
        .collect();
    fit_motion(mesh, block, &disp)
}

/// The least-squares rigid motion of a block's nodes (weights: lumped areas) from their
/// displacements `disp` (m), in node order of the block: centroid displacement (m) and
/// rotation θ = atan2(Σ w r × d, Σ w r · d) (rad), valid for rotations of any size.
pub fn fit_motion(mesh: &Mesh, block: usize, disp: &[[f64; 2]]) -> ([f64; 2], f64) {
    let b = &mesh.blocks[block];
    let mut w = vec![0.0; (b.nodes.end - b.nodes.start) as usize];
    if b.triangles.is_empty() {
        w.iter_mut().for_each(|x| *x = 1.0);
    }
    for t in b.triangles.clone() {
        let a = mesh.triangle_area(t as usize) / 3.0;
        for &n in &mesh.triangles[t as usize] {
            w[(n - b.nodes.start) as usize] += a;
        }
    }
    let (mut sw, mut xc, mut uc) = (0.0, [0.0; 2], [0.0; 2]);
    for (k, n) in b.nodes.clone().enumerate() {
        let p = mesh.nodes[n as usize];
        sw += w[k];
        for i in 0..2 {
            xc[i] += w[k] * p[i];
            uc[i] += w[k] * disp[k][i];
        }
    }
    xc = xc.map(|x| x / sw);
    uc = uc.map(|x| x / sw);
    let (mut s, mut c) = (0.0, 0.0);
    for (k, n) in b.nodes.clone().enumerate() {
        let p = mesh.nodes[n as usize];
        let r = [p[0] - xc[0], p[1] - xc[1]];
        let d = [r[0] + disp[k][0] - uc[0], r[1] + disp[k][1] - uc[1]];
        s += w[k] * (r[0] * d[1] - r[1] * d[0]);
        c += w[k] * (r[0] * d[0] + r[1] * d[1]);
    }
    // displacement of the polygon centroid (equal to the weighted node centroid for
    // triangulated blocks; for node sets it follows from the rigid motion)
    let th = s.atan2(c);
    let (sn, cs) = th.sin_cos();
    let r = [b.centroid[0] - xc[0], b.centroid[1] - xc[1]];
    let moved = [
        xc[0] + uc[0] + cs * r[0] - sn * r[1],
        xc[1] + uc[1] + sn * r[0] + cs * r[1],
    ];
    ([moved[0] - b.centroid[0], moved[1] - b.centroid[1]], th)
}

/// Block motion from an outcome: rigid blocks from their unknowns (rotation accumulated
/// over the increments), deformable ones fitted to their total node displacements.
pub fn outcome_motion(mesh: &Mesh, block: usize, out: &Outcome) -> ([f64; 2], f64) {
    if let crate::mesh::BlockDofs::Rigid { first, .. } = mesh.blocks[block].dofs {
        let f = first as usize;
        return ([out.u[f], out.u[f + 1]], out.u[f + 2]);
    }
    let b = &mesh.blocks[block];
    fit_motion(
        mesh,
        block,
        &out.node_disp[b.nodes.start as usize..b.nodes.end as usize],
    )
}
