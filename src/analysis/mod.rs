//! Analyses: the static driver (this module), later capacity and time integration.

pub mod config;
pub mod mechanism;
pub mod statics;
pub mod support;

use crate::assembly::{contact_gradient, cst_b, loads, System};
use crate::material::{block_elastic, ContactLaw, ContactSprings, ContactState, ElasticBand};
use crate::mesh::Mesh;
use crate::scene::{AnalysisType, Scene};
use crate::solve::LinearBackend;
use crate::{Error, Result};
use std::time::Instant;

/// Whether the structure stands.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    Stable,
    /// The structure failed; the reason says how it was detected.
    Failed {
        reason: String,
        blocks: Vec<usize>,
    },
}

/// Counters written to `summary.json` stats.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    pub dofs: usize,
    pub contacts: usize,
    pub triangles: usize,
    pub increments: usize,
    pub iterations: usize,
    pub factorizations: usize,
    pub symbolic_factorizations: usize,
    pub wall_time_s: f64,
    pub min_pivot_ratio: f64,
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
    pub stats: Stats,
    /// Capacity: the critical load factor λ (last converged).
    pub load_factor: Option<f64>,
    pub mechanism: Option<mechanism::Mechanism>,
    /// The final configuration (updated Lagrangian), when it differs from the mesh.
    pub current: Option<Mesh>,
}

impl Outcome {
    /// An outcome of a linear solve with unknowns `u`.
    pub fn linear(
        scene: &Scene,
        mesh: &Mesh,
        status: Status,
        u: Vec<f64>,
        forces: Vec<[f64; 2]>,
        stats: Stats,
    ) -> Outcome {
        let node_disp = (0..mesh.nodes.len() as u32)
            .map(|n| mesh.node_displacement(n, &u))
            .collect();
        let stress = triangle_stresses(scene, mesh, &u);
        Outcome {
            status,
            node_disp,
            stress,
            contact_states: vec![ContactState::Stick; mesh.contacts.len()],
            contact_forces: forces,
            u,
            stats,
            load_factor: None,
            mechanism: None,
            current: None,
        }
    }
}

/// Pivot ratio below which the factorization is taken as singular: a mechanism (METHOD.md
/// §4, "the global stiffness matrix becomes ill-conditioned"). Round-off on a singular
/// matrix leaves ratios near 1e-16 times the condition of the rest; stiff joints on soft
/// blocks stay far above 1e-12.
pub const SINGULAR_PIVOT_RATIO: f64 = 1e-12;

/// Run the scene's analysis.
pub fn run(scene: &Scene, mesh: &Mesh, backend: &mut dyn LinearBackend) -> Result<Outcome> {
    if scene.analysis.kind != AnalysisType::Dynamic {
        let floating = support::unsupported_blocks(mesh);
        if let Some(&b) = floating.first() {
            let names: Vec<&str> = floating
                .iter()
                .take(5)
                .map(|&i| scene.blocks[i].name.as_str())
                .collect();
            return Err(Error::new(format!(
                "{} free block(s) have no path of contacts to a fixed block ({}{}), so a static analysis has nothing to hold them",
                floating.len(),
                names.join(", "),
                if floating.len() > 5 { ", ..." } else { "" }
            ))
            .line(scene.blocks[b].line)
            .place(format!("block '{}'", scene.blocks[b].name))
            .fix("place the blocks on a fixed block (support = \"fixed\"), or raise [contacts] tolerance if they should touch"));
        }
    }
    match scene.analysis.kind {
        AnalysisType::Static | AnalysisType::Capacity => statics::run(scene, mesh, backend),
        AnalysisType::Dynamic => Err(Error::new(
            "analysis type 'dynamic' is not available in this version",
        )
        .place("[analysis] key 'type'")
        .fix("use type = \"static\" or \"capacity\"")),
    }
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

/// Linear elastic static solve K u = f with elastic contacts that carry tension: the
/// reference for solver comparisons and `export-matrix` (the `static` analysis itself is
/// the nonlinear driver of [`statics`]).
pub fn linear_static(scene: &Scene, mesh: &Mesh, backend: &mut dyn LinearBackend) -> Outcome {
    let start = Instant::now();
    let mut stats = Stats {
        dofs: mesh.n_dofs,
        contacts: mesh.contacts.len(),
        triangles: mesh.triangles.len(),
        ..Default::default()
    };
    let springs = elastic_springs(scene, mesh);
    let failed = |reason: String, blocks: Vec<usize>, stats: Stats| {
        Outcome::linear(
            scene,
            mesh,
            Status::Failed { reason, blocks },
            vec![0.0; mesh.n_dofs],
            vec![[0.0; 2]; mesh.contacts.len()],
            stats,
        )
    };
    let floating = support::unsupported_blocks(mesh);
    if !floating.is_empty() {
        stats.wall_time_s = start.elapsed().as_secs_f64();
        let names: Vec<&str> = floating
            .iter()
            .take(5)
            .map(|&b| scene.blocks[b].name.as_str())
            .collect();
        return failed(
            format!(
                "{} block(s) have no path of contacts to a fixed block: {}{}",
                floating.len(),
                names.join(", "),
                if floating.len() > 5 { ", ..." } else { "" }
            ),
            floating,
            stats,
        );
    }
    if mesh.n_dofs == 0 {
        stats.wall_time_s = start.elapsed().as_secs_f64();
        return Outcome::linear(
            scene,
            mesh,
            Status::Stable,
            vec![],
            vec![[0.0; 2]; mesh.contacts.len()],
            stats,
        );
    }
    let system = System::new(scene, mesh);
    let k = system.stiffness(mesh, &springs);
    let mut u = external_load(scene, mesh);
    stats.increments = 1;
    stats.iterations = 1;
    let result = backend.factorize(&k).and_then(|_| backend.solve(&mut u));
    let s = backend.stats();
    stats.factorizations = s.numeric_factorizations;
    stats.symbolic_factorizations = s.symbolic_factorizations;
    stats.min_pivot_ratio = s.min_pivot_ratio;
    stats.wall_time_s = start.elapsed().as_secs_f64();
    if let Err(e) = result {
        return failed(
            format!("the stiffness matrix is singular ({e}): part of the structure is a mechanism"),
            vec![],
            stats,
        );
    }
    if s.min_pivot_ratio < SINGULAR_PIVOT_RATIO || u.iter().any(|x| !x.is_finite()) {
        return failed(format!("the stiffness matrix is singular (pivot ratio {:.1e}): part of the structure is a mechanism", s.min_pivot_ratio), vec![], stats);
    }
    let (contact_forces, _) = contact_forces(scene, mesh, &springs, &u);
    Outcome::linear(scene, mesh, Status::Stable, u, contact_forces, stats)
}

/// Relative displacement (δₙ, δₛ) (m) of a contact (METHOD.md §3: δ = u_m − u_l).
pub fn contact_opening(mesh: &Mesh, c: usize, u: &[f64]) -> (f64, f64) {
    let con = &mesh.contacts[c];
    let (ml, mm) = (mesh.node_map(con.node_l), mesh.node_map(con.node_m));
    let n = con.normal;
    let gn = contact_gradient(&ml, &mm, n);
    let gs = contact_gradient(&ml, &mm, [-n[1], n[0]]);
    let mut q = [0.0; 6];
    for k in 0..3 {
        for (slot, m) in [(k, &ml), (3 + k, &mm)] {
            let d = m.dofs[k];
            if d != dfem_kernels::CONSTRAINED {
                q[slot] = u[d as usize];
            }
        }
    }
    let dot = |g: &[f64; 6]| g.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>();
    (dot(&gn), dot(&gs))
}

/// Forces (N) and states of all contacts for springs and unknowns.
pub fn contact_forces(
    scene: &Scene,
    mesh: &Mesh,
    springs: &[ContactSprings],
    u: &[f64],
) -> (Vec<[f64; 2]>, Vec<ContactState>) {
    let _ = scene;
    let f = (0..mesh.contacts.len())
        .map(|c| {
            let (dn, ds) = contact_opening(mesh, c, u);
            [springs[c].kn * dn, springs[c].ks * ds]
        })
        .collect();
    (f, vec![ContactState::Stick; mesh.contacts.len()])
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
