//! Assembly: maps the mesh and the materials onto `dfem_kernels::assembly`.
//!
//! Element order is fixed (the triangles, group 0; the contacts, group 1; for dynamics the
//! rigid blocks' diagonal elements, group 2), so the pattern, the scatter map and the
//! colour order are built once per contact topology and every assembly sums in the same
//! order whatever the number of threads.
//!
//! The triangles' part of the stiffness depends only on the geometry: when a geometry
//! comes back (the static driver assembles every iteration matrix of an increment on the
//! last converged geometry), it is kept, and the next assemblies on that geometry add only
//! the contacts onto it (bit-identical to a whole assembly: the plan's groups), or
//! ([`System::stiffness_update`]) only the contacts whose local stiffness changed. The
//! contacts' gradients (their point maps along the normal and the tangent) are kept with
//! it, so that a contact's kernel on a kept geometry is a few products per entry.

pub mod loads;
pub mod mass;
pub mod rigid3d;
mod rows;

pub use rows::Ranks;
use rows::RowExchange;

use crate::material::{block_elastic, ContactSprings};
use crate::mesh::{Contact, Mesh, PointMap};

use crate::geometry::polygon::Point;
use crate::scene::Scene;
use dfem_kernels::{unpack_symmetric, AssemblyPlan, Connectivity, CsrMatrix, Form, CONSTRAINED};
use rayon::prelude::*;
use std::sync::Mutex;

/// Element groups of a [`System`]'s plan.
const TRIANGLES: usize = 0;
const CONTACTS: usize = 1;

/// The assembly plan of a mesh: triangles (6 slots each) then contacts (the free unknowns
/// their l point depends on, then their m point's: 4 for two deformable nodes; see
/// [`contact_map`]).
pub struct System {
    pub plan: AssemblyPlan,
    pub n_triangles: usize,
    pub n_contacts: usize,
    /// Material of each triangle, an index into `dt` and `dv`.
    tri_material: Vec<u32>,
    /// Per material: Dₑ (Pa) times the thickness (m).
    dt: Vec<[[f64; 3]; 3]>,
    /// Per material: D_v (Pa·s, the viscous Lamé constants) times the thickness (m);
    /// empty unless the system is built for dynamics.
    dv: Vec<[[f64; 3]; 3]>,
    /// Contact c's slots are `contact_ptr[c]..contact_ptr[c + 1]` in a gradient array
    /// ([`Self::contact_gradients`]).
    contact_ptr: Vec<usize>,
    /// The triangles' part of K on the last geometry seen twice, and the contacts'
    /// gradients on the last geometry.
    blocks: Mutex<BlockCache>,
    /// In a distributed run ([`System::distributed`]): the elements this process evaluates
    /// and the exchange of the rows; `None` in a serial run.
    rows: Option<RowExchange>,
}

/// See [`System`]'s `blocks`.
#[derive(Default)]
struct BlockCache {
    /// Node positions (m) of the last geometry assembled on.
    nodes: Vec<Point>,
    /// The triangles' part of K (N/m) on that geometry, once it has been seen twice.
    values: Option<CsrMatrix>,
    /// The contacts' gradients ([`System::contact_gradients`]) on that geometry, with the
    /// rest of what they depend on ([`contact_key`]); empty when not computed yet.
    gradients: Vec<[f64; 2]>,
    key: Vec<u64>,
}

/// What the contacts' gradients depend on besides the node positions, as bits: every
/// contact's normal and position along its edge, every rigid block's centroid.
fn contact_key(mesh: &Mesh) -> impl Iterator<Item = u64> + '_ {
    let contacts = mesh.contacts.iter().flat_map(|c| {
        [
            c.normal[0].to_bits(),
            c.normal[1].to_bits(),
            c.along.map_or(u64::MAX, f64::to_bits),
        ]
    });
    let centroids = mesh.blocks.iter().flat_map(|b| match b.dofs {
        crate::mesh::BlockDofs::Rigid { centroid, .. } => {
            [centroid[0].to_bits(), centroid[1].to_bits()]
        }
        _ => [u64::MAX; 2],
    });
    contacts.chain(centroids)
}

/// Local stiffness of a contact in its (n, s) frame (N/m): row = force component,
/// column = relative displacement component. Symmetric for the secant forms, with an
/// off-diagonal friction term in Newton's tangent of a slipping contact.
pub type LocalStiffness = [[f64; 2]; 2];

/// The local stiffness of elastic springs.
pub fn diagonal(k: ContactSprings) -> LocalStiffness {
    [[k.kn, 0.0], [0.0, k.ks]]
}

fn symmetric(k: &LocalStiffness) -> bool {
    k[0][1] == k[1][0]
}

/// The same positions to the bit (a cached triangles' part is valid only for them).
fn same_nodes(a: &[Point], b: &[Point]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits())
}

impl System {
    pub fn new(scene: &Scene, mesh: &Mesh) -> System {
        Self::build(scene, mesh, false)
    }

    /// The system of a dynamic analysis: after the triangles and contacts, one 3-dof
    /// element per rigid block (its own unknowns), so that the pattern holds the diagonal
    /// the mass matrix needs even for a block that touches nothing.
    pub fn for_dynamics(scene: &Scene, mesh: &Mesh) -> System {
        Self::build(scene, mesh, true)
    }

    /// `dynamic`: add the rigid blocks' diagonal elements and the viscous matrices.
    fn build(scene: &Scene, mesh: &Mesh, dynamic: bool) -> System {
        let rigid_diagonal = dynamic;
        let mut conn = Connectivity::new();
        for t in &mesh.triangles {
            let mut dofs = [CONSTRAINED; 6];
            for (k, &n) in t.iter().enumerate() {
                let d = mesh.node_dofs[n as usize];
                dofs[2 * k] = d[0];
                dofs[2 * k + 1] = d[1];
            }
            conn.push(&dofs);
        }
        let mut contact_ptr = vec![0];
        for c in &mesh.contacts {
            let map = contact_map(mesh, c);
            conn.push(&map.dofs[..map.len]);
            contact_ptr.push(contact_ptr[contact_ptr.len() - 1] + map.len);
        }
        let mut group_ends = vec![conn.len(); 2];
        group_ends[TRIANGLES] = mesh.triangles.len();
        if rigid_diagonal {
            for b in &mesh.blocks {
                if let crate::mesh::BlockDofs::Rigid { first, .. } = b.dofs {
                    conn.push(&[first, first + 1, first + 2]);
                }
            }
            group_ends.push(conn.len());
        }
        let t = scene.model.thickness;
        let scaled = |d: [[f64; 3]; 3]| d.map(|r| r.map(|x| x * t));
        let dt = scene
            .materials
            .iter()
            .map(|m| scaled(block_elastic(m, scene.model.plane)))
            .collect();
        // viscous matrices only for a dynamic analysis (a static run does no damping work)
        let dv = scene
            .materials
            .iter()
            .filter(|_| rigid_diagonal)
            .map(|m| scaled(crate::material::block_viscous(m, scene.model.plane)))
            .collect();
        let tri_material = mesh
            .tri_block
            .iter()
            .map(|&b| scene.blocks[b as usize].material as u32)
            .collect();
        let plan = AssemblyPlan::with_groups(mesh.n_dofs, &conn, &group_ends);
        System {
            plan,
            n_triangles: mesh.triangles.len(),
            n_contacts: mesh.contacts.len(),
            tri_material,
            dt,
            dv,
            contact_ptr,
            blocks: Mutex::new(BlockCache::default()),
            rows: None,
        }
    }

    /// This system assembled by the processes of a distributed run together: each
    /// evaluates only the elements of its own rows (`ranks`, made by
    /// [`crate::solve::configure_run`]) and the rows are then exchanged. `None`, or ranks
    /// that do not fit the system (one process, another number of unknowns): serial.
    pub fn distributed(mut self, ranks: Option<&Ranks>) -> System {
        self.rows =
            ranks.and_then(|r| RowExchange::new(r, self.plan.connectivity(), self.plan.pattern()));
        self
    }

    /// The elements this process evaluates (`None`: all of them).
    fn active(&self) -> Option<&[bool]> {
        self.rows.as_ref().map(RowExchange::active)
    }

    /// In a distributed run, completes `out` with the other processes' rows.
    fn complete(&self, out: &mut CsrMatrix) {
        if let Some(rows) = &self.rows {
            rows.complete(out);
        }
    }

    /// Stiffness K (N/m) for elastic contact springs: CST blocks (docs/theory.md Eq. B4,
    /// Kₑ = t A Bᵀ Dₑ B) plus contacts (docs/theory.md Eq. K4, K = Tᵀ K′ T).
    pub fn stiffness(&self, mesh: &Mesh, springs: &[ContactSprings]) -> CsrMatrix {
        let local: Vec<LocalStiffness> = springs.iter().map(|&k| diagonal(k)).collect();
        let mut k = CsrMatrix::zeros(self.plan.pattern().clone());
        self.stiffness_into(mesh, &local, &mut k);
        k
    }

    /// Stiffness (N/m) in the configuration `mesh` (node positions, rigid centroids and
    /// contact normals as they are now: the updated Lagrangian geometry) with a local
    /// stiffness per contact.
    /// When a local stiffness is unsymmetric (Newton's tangent of a slipping contact), so
    /// is the result (for an LU backend); otherwise it is symmetric to the bit.
    ///
    /// The second time in a row that the node positions are the same (to the bit), the
    /// triangles' part is kept, and from then on, while they stay the same, only the
    /// contacts are assembled, onto a copy of it. The contacts' gradients are kept while
    /// the geometry stays the same. The result is bit-identical either way.
    pub fn stiffness_into(&self, mesh: &Mesh, local: &[LocalStiffness], out: &mut CsrMatrix) {
        self.stiffness_kept(mesh, None, local, out);
    }

    /// Stiffness (N/m) like [`Self::stiffness_into`], with the triangles in the
    /// configuration `blocks` and the contacts in `contacts` (the same mesh at other node
    /// positions: the dynamic driver's matrix keeps the blocks' interiors on the step's
    /// start geometry and takes the contacts in the trial's). The triangles' part is kept
    /// as [`Self::stiffness_into`] keeps it, for the positions of `blocks`; the contacts'
    /// gradients are computed from `contacts` at each call.
    pub fn stiffness_split_into(
        &self,
        blocks: &Mesh,
        contacts: &Mesh,
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        self.stiffness_kept(blocks, Some(contacts), local, out);
    }

    /// [`Self::stiffness_into`] on `mesh`, the contacts' gradients from `contacts` when
    /// given (then not kept: the kept ones, which [`Self::stiffness_update`] reads, are
    /// always those of the kept node positions).
    fn stiffness_kept(
        &self,
        mesh: &Mesh,
        contacts: Option<&Mesh>,
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        let mut guard = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        let same = same_nodes(&guard.nodes, &mesh.nodes);
        if !same {
            guard.nodes.clear();
            guard.nodes.extend_from_slice(&mesh.nodes);
            guard.values = None;
            guard.gradients.clear();
        }
        if contacts.is_none() {
            self.keep_gradients(mesh, &mut guard);
        }
        let own = contacts.map(|c| self.contact_gradients(c));
        let cache = &mut *guard;
        let g = own.as_deref().unwrap_or(cache.gradients.as_slice());
        if !same {
            return self.assemble_all(mesh, &self.dt, g, local, out);
        }
        if cache.values.is_none() {
            let mut b = CsrMatrix::zeros(self.plan.pattern().clone());
            self.plan.assemble_groups_of(
                Form::Packed,
                0..CONTACTS,
                None,
                self.active(),
                // inlined into the plan's loop: a triangle's values stay in registers
                #[inline(always)]
                |e: usize, ke: &mut [f64]| {
                    self.element(mesh, &self.dt, g, local, Form::Packed, e, ke)
                },
                &mut b,
            );
            cache.values = Some(b);
        }
        let form = self.form(local);
        let kernel = |e: usize, ke: &mut [f64]| self.element(mesh, &self.dt, g, local, form, e, ke);
        let base = cache.values.as_ref();
        let groups = CONTACTS..self.plan.n_groups();
        self.plan
            .assemble_groups_of(form, groups, base, self.active(), kernel, out);
        self.complete(out);
    }

    /// Makes `cache.gradients` those of `mesh` (the caller has cleared them if the node
    /// positions changed): recomputed when empty or when a normal, a position along an edge
    /// or a rigid centroid changed.
    fn keep_gradients(&self, mesh: &Mesh, cache: &mut BlockCache) {
        if cache.gradients.is_empty() || !cache.key.iter().copied().eq(contact_key(mesh)) {
            cache.gradients = self.contact_gradients(mesh);
            cache.key.clear();
            cache.key.extend(contact_key(mesh));
        }
    }

    /// Stiffness (N/m) like [`Self::stiffness_into`], every element assembled and every
    /// contact's gradients computed (no kept triangles' part or gradients, which it neither
    /// uses nor changes).
    pub fn stiffness_full_into(&self, mesh: &Mesh, local: &[LocalStiffness], out: &mut CsrMatrix) {
        self.assemble_split(mesh, mesh, &self.dt, local, out);
    }

    /// The gradients gₙ, gₛ of every contact's relative displacements with respect to its
    /// free unknowns ([`contact_map`]; 1, or m for a rigid block's rotation), contact c's
    /// at `contact_ptr[c]..contact_ptr[c + 1]`, as [gₙ, gₛ] per unknown.
    fn contact_gradients(&self, mesh: &Mesh) -> Vec<[f64; 2]> {
        let g: Vec<[f64; 2]> = mesh
            .contacts
            .par_iter()
            .flat_map_iter(|c| {
                let map = contact_map(mesh, c);
                map.g.into_iter().take(map.len)
            })
            .collect();
        assert_eq!(
            g.len(),
            self.contact_ptr[self.n_contacts],
            "the system's mesh"
        );
        g
    }

    /// Every element assembled, the triangles with the material matrices `d` (`dt` for
    /// stiffness, `dv` for damping), the contacts with the gradients `g`.
    fn assemble_all(
        &self,
        mesh: &Mesh,
        d: &[[[f64; 3]; 3]],
        g: &[[f64; 2]],
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        self.assemble_own(mesh, d, g, local, out);
        self.complete(out);
    }

    /// [`Self::assemble_all`] without the exchange: in a distributed run, only this
    /// process's rows are right.
    fn assemble_own(
        &self,
        mesh: &Mesh,
        d: &[[[f64; 3]; 3]],
        g: &[[f64; 2]],
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        let form = self.form(local);
        let groups = 0..self.plan.n_groups();
        self.plan.assemble_groups_of(
            form,
            groups,
            None,
            self.active(),
            // inlined into the plan's loop: a triangle's values stay in registers
            #[inline(always)]
            |e: usize, ke: &mut [f64]| self.element(mesh, d, g, local, form, e, ke),
            out,
        );
    }

    /// The update path: `out` holds [`Self::stiffness_into`]`(mesh, prev, out)` (and has
    /// not been changed since); this makes it `stiffness_into(mesh, local, out)`, bit for
    /// bit, re-assembling only the entries of the contacts whose local stiffness differs
    /// from `prev` (with the kept triangles' part and gradients). When the geometry is not
    /// that of the kept triangles' part, or more than 1/8 of the contacts changed, it
    /// assembles all the contacts (or everything) instead; with none changed, it does
    /// nothing.
    pub fn stiffness_update(
        &self,
        mesh: &Mesh,
        prev: &[LocalStiffness],
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        let changed: Vec<usize> = (0..self.n_contacts)
            .filter(|&c| {
                let (a, b) = (prev[c].as_flattened(), local[c].as_flattened());
                a.iter().zip(b).any(|(x, y)| x.to_bits() != y.to_bits())
            })
            .map(|c| self.n_triangles + c)
            .collect();
        if changed.is_empty() {
            return;
        }
        if self.rows.is_some() {
            // distributed: the kept triangles' part holds only this process's rows
            return self.stiffness_into(mesh, local, out);
        }
        let cache = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
        let kept = same_nodes(&cache.nodes, &mesh.nodes)
            && cache.values.is_some()
            && !cache.gradients.is_empty()
            && cache.key.iter().copied().eq(contact_key(mesh));
        if !kept || 8 * changed.len() > self.n_contacts {
            drop(cache);
            return self.stiffness_into(mesh, local, out);
        }
        // an unsymmetric element adds the same values in either form, so the entries left
        // as they are stay those of the new form
        let form = if self.form(prev) == Form::Packed {
            self.form(local)
        } else {
            Form::Unsymmetric
        };
        let g = &cache.gradients;
        let kernel = |e: usize, ke: &mut [f64]| self.element(mesh, &self.dt, g, local, form, e, ke);
        self.plan
            .reassemble(form, &changed, cache.values.as_ref(), kernel, out);
    }

    /// Damping matrix C (N·s/m) of the Kelvin–Voigt viscosities (docs/theory.md §2, §5), for a
    /// system built [`System::for_dynamics`]:
    /// Cₑ = t A Bᵀ D_v B for the triangles and Tᵀ C′ T for the contacts, with a local
    /// viscosity per contact (cₙ = Eₙ* A_c / h, cₛ = Gₛ* A_c / h where they act).
    pub fn damping_into(&self, mesh: &Mesh, local: &[LocalStiffness], out: &mut CsrMatrix) {
        self.damping_split_into(mesh, mesh, local, out);
    }

    /// Damping (N·s/m) like [`Self::damping_into`], split between two configurations
    /// as [`Self::stiffness_split_into`] (every element assembled at each call).
    pub fn damping_split_into(
        &self,
        blocks: &Mesh,
        contacts: &Mesh,
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        self.assemble_split(blocks, contacts, &self.dv, local, out);
    }

    /// [`Self::assemble_all`] with the triangles in `blocks` and the contacts' gradients
    /// from `contacts`.
    fn assemble_split(
        &self,
        blocks: &Mesh,
        contacts: &Mesh,
        d: &[[[f64; 3]; 3]],
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        let g = self.contact_gradients(contacts);
        self.assemble_all(blocks, d, &g, local, out);
    }

    /// Packed when every contact's local matrix is symmetric, else unsymmetric.
    fn form(&self, local: &[LocalStiffness]) -> Form {
        if local.iter().all(symmetric) {
            Form::Packed
        } else {
            Form::Unsymmetric
        }
    }

    /// Element `e`'s matrix in `form` ([`Form::Packed`] or [`Form::Unsymmetric`]): a
    /// triangle with the material matrices `d` (per material), a contact with its
    /// gradients in `g` ([`Self::contact_gradients`]) and its local matrix. A symmetric
    /// element matrix is computed packed in either form, so that an element adds the same
    /// values whatever the form.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn element(
        &self,
        mesh: &Mesh,
        d: &[[[f64; 3]; 3]],
        g: &[[f64; 2]],
        local: &[LocalStiffness],
        form: Form,
        e: usize,
        ke: &mut [f64],
    ) {
        let (nt, nc) = (self.n_triangles, self.n_contacts);
        if e < nt {
            let t = mesh.triangles[e];
            let p = t.map(|n| mesh.nodes[n as usize]);
            let d = &d[self.tri_material[e] as usize];
            if form == Form::Packed {
                cst_stiffness_packed(p, d, ke);
            } else {
                cst_stiffness(p, d, ke);
            }
        } else if e < nt + nc {
            let c = e - nt;
            let g = &g[self.contact_ptr[c]..self.contact_ptr[c + 1]];
            contact_element(g, &local[c], form, ke);
        }
        // else: the rigid blocks' diagonal elements (dynamics) carry no stiffness (`ke`
        // is zeroed by the plan)
    }

    /// tDₑ (Pa·m) of triangle `t`.
    pub fn tri_dt(&self, t: usize) -> &[[f64; 3]; 3] {
        &self.dt[self.tri_material[t] as usize]
    }
}

/// A contact's matrix in `form` from its gradients ([`System::element`]).
#[inline(never)]
fn contact_element(g: &[[f64; 2]], k: &LocalStiffness, form: Form, ke: &mut [f64]) {
    match (form, symmetric(k)) {
        (Form::Packed, _) => contact_stiffness_packed(g, k, ke),
        (_, true) => {
            let mut packed = [0.0; 78];
            contact_stiffness_packed(g, k, &mut packed);
            unpack_symmetric(g.len(), &packed, ke);
        }
        _ => contact_stiffness(g, k, ke),
    }
}

/// Strain–displacement matrix B (1/m) of a CST and its area (m²), docs/theory.md Eq. B3:
/// B = 1/(2A) `[[bᵢ,0,bⱼ,0,bₖ,0],[0,cᵢ,0,cⱼ,0,cₖ],[cᵢ,bᵢ,cⱼ,bⱼ,cₖ,bₖ]]`,
/// bᵢ = yⱼ − yₖ, cᵢ = xₖ − xⱼ (cyclic).
pub fn cst_b(p: [Point; 3]) -> ([[f64; 6]; 3], f64) {
    let b = [p[1][1] - p[2][1], p[2][1] - p[0][1], p[0][1] - p[1][1]];
    let c = [p[2][0] - p[1][0], p[0][0] - p[2][0], p[1][0] - p[0][0]];
    let two_a = b[0] * c[1] - b[1] * c[0];
    let inv = 1.0 / two_a;
    let mut m = [[0.0; 6]; 3];
    for i in 0..3 {
        m[0][2 * i] = b[i] * inv;
        m[1][2 * i + 1] = c[i] * inv;
        m[2][2 * i] = c[i] * inv;
        m[2][2 * i + 1] = b[i] * inv;
    }
    (m, 0.5 * two_a)
}

/// CST stiffness Kₑ = A Bᵀ (t Dₑ) B into `ke` (row-major 6×6, N/m): the packed upper
/// triangle of [`cst_stiffness_packed`], mirrored.
pub fn cst_stiffness(p: [Point; 3], dt: &[[f64; 3]; 3], ke: &mut [f64]) {
    let mut packed = [0.0; 21];
    cst_stiffness_packed(p, dt, &mut packed);
    unpack_symmetric(6, &packed, ke);
}

/// CST stiffness Kₑ = A Bᵀ (t Dₑ) B (N/m, docs/theory.md Eq. B4), its upper triangle packed by rows
/// into `ke` (21 values (0,0), (0,1), …, (0,5), (1,1), …, (5,5); slots 2i and 2i + 1 are
/// node i's x and y). B is sparse: node j's block of B is 1/(2A) `[[bⱼ,0],[0,cⱼ],[cⱼ,bⱼ]]`
/// ([`cst_b`]), so K_ij = 1/(4A) `[[bᵢ,0,cᵢ],[0,cᵢ,bᵢ]]` (tDₑ) `[[bⱼ,0],[0,cⱼ],[cⱼ,bⱼ]]`: 14
/// products per node for (tDₑ)Bⱼ/(4A), then 2 per entry, 84 in all (the dense triple
/// product of [`cst_b`]'s matrices takes 324), and the lower triangle is not computed.
#[inline(always)]
pub fn cst_stiffness_packed(p: [Point; 3], dt: &[[f64; 3]; 3], ke: &mut [f64]) {
    let ke: &mut [f64; 21] = (&mut ke[..21]).try_into().expect("21 values");
    let b = [p[1][1] - p[2][1], p[2][1] - p[0][1], p[0][1] - p[1][1]];
    let c = [p[2][0] - p[1][0], p[0][0] - p[2][0], p[1][0] - p[0][0]];
    // 1/(4A), A the signed area: applied last, so that the division's latency overlaps
    // the products (nothing else waits for it)
    let f = 0.5 / (b[0] * c[1] - b[1] * c[0]);
    // (tDₑ) Bⱼ 2A: its x column and its y column, per node j
    let db: [[[f64; 3]; 2]; 3] = std::array::from_fn(|j| {
        let (bj, cj) = (b[j], c[j]);
        [
            std::array::from_fn(|r| dt[r][0] * bj + dt[r][2] * cj),
            std::array::from_fn(|r| dt[r][1] * cj + dt[r][2] * bj),
        ]
    });
    let mut t = 0;
    for i in 0..3 {
        let (bi, ci) = (b[i], c[i]);
        // row x of node i: [bᵢ, 0, cᵢ] · column; row y: [0, cᵢ, bᵢ] · column; times 1/(4A)
        let rx = |d: &[f64; 3]| f * (bi * d[0] + ci * d[2]);
        let ry = |d: &[f64; 3]| f * (ci * d[1] + bi * d[2]);
        for d in &db[i..] {
            ke[t] = rx(&d[0]);
            ke[t + 1] = rx(&d[1]);
            t += 2;
        }
        ke[t] = ry(&db[i][1]);
        t += 1;
        for d in &db[i + 1..] {
            ke[t] = ry(&d[0]);
            ke[t + 1] = ry(&d[1]);
            t += 2;
        }
    }
}

/// Gradient of a relative displacement component along `dir` with respect to the
/// contact's unknowns (the l point's `ml.len` slots, then the m point's):
/// (u_m − u_l)·dir = g · [q_l, q_m]. 6 entries for a node-to-node contact.
pub fn contact_gradient(ml: &PointMap, mm: &PointMap, dir: Point) -> [f64; 12] {
    let mut g = [0.0; 12];
    let (gl, gm) = g.split_at_mut(ml.len);
    for (k, x) in gl.iter_mut().enumerate() {
        *x = -(dir[0] * ml.g[0][k] + dir[1] * ml.g[1][k]);
    }
    for (k, x) in gm.iter_mut().take(mm.len).enumerate() {
        *x = dir[0] * mm.g[0][k] + dir[1] * mm.g[1][k];
    }
    g
}

/// A contact's free unknowns and the gradients of its relative displacements with respect
/// to them ([`contact_map`]).
#[derive(Debug, Clone, Copy)]
pub struct ContactMap {
    /// Number of free unknowns (4 for two deformable nodes, at most 9).
    pub len: usize,
    /// The free unknowns: the l point's, then the m point's, without the constrained
    /// slots of [`Mesh::contact_maps`] (a deformable node's rotation, a fixed block's).
    pub dofs: [u32; 12],
    /// [gₙ, gₛ] per free unknown: the gradients of δₙ = n·(u_m − u_l) and
    /// δₛ = s·(u_m − u_l), s = (−n_y, n_x) ([`contact_gradient`]; 1, or m for a rotation).
    pub g: [[f64; 2]; 12],
}

/// Contact `c`'s free unknowns and gradients ([`ContactMap`]; docs/theory.md §3, the rows of
/// T that give δₙ, δₛ).
///
/// A node-to-node contact (no `along`, every contact of the static driver) takes a direct
/// route (`node_to_node_map`), bit-identical to the general one through
/// [`Mesh::contact_maps`] and [`contact_gradient`]: the static driver computes the map of
/// every contact that carries a force at every trial of its iterations.
pub fn contact_map(mesh: &Mesh, c: &Contact) -> ContactMap {
    match c.along {
        None => node_to_node_map(mesh, c),
        Some(_) => combined_map(mesh, c),
    }
}

/// [`contact_map`] by the general route: the points' maps ([`Mesh::contact_maps`], a
/// vertex-to-edge contact's l point combining its edge's two ends) and their gradients
/// along n and s ([`contact_gradient`]), without the constrained slots.
fn combined_map(mesh: &Mesh, c: &Contact) -> ContactMap {
    let (ml, mm) = mesh.contact_maps(c);
    let n = c.normal;
    let gn = contact_gradient(&ml, &mm, n);
    let gs = contact_gradient(&ml, &mm, [-n[1], n[0]]);
    let mut map = ContactMap {
        len: 0,
        dofs: [CONSTRAINED; 12],
        g: [[0.0; 2]; 12],
    };
    let dofs = ml.dofs[..ml.len].iter().chain(&mm.dofs[..mm.len]);
    for (i, &dof) in dofs.enumerate() {
        if dof != CONSTRAINED {
            map.dofs[map.len] = dof;
            map.g[map.len] = [gn[i], gs[i]];
            map.len += 1;
        }
    }
    map
}

/// [`contact_map`] of a node-to-node contact: each point is one node, u = G q with G its
/// [`crate::mesh::NodeMap`] (dimensionless, or m for a rigid block's rotation), and the
/// gradients of δₙ = n·(u_m − u_l), δₛ = s·(u_m − u_l) are gₙ = ± n·G, gₛ = ± s·G (− on
/// the l side). The same floating-point operations as the general route, whose one-node
/// point map holds 0 + 1·G (the sum of its weighted parts: −0 becomes +0), without its
/// arrays of combined points and gradients.
fn node_to_node_map(mesh: &Mesh, c: &Contact) -> ContactMap {
    let n = c.normal;
    let s = [-n[1], n[0]];
    let mut map = ContactMap {
        len: 0,
        dofs: [CONSTRAINED; 12],
        g: [[0.0; 2]; 12],
    };
    for (node, side) in [(c.node_l, -1.0), (c.node_m, 1.0)] {
        let nm = mesh.node_map(node);
        for k in 0..3 {
            if nm.dofs[k] == CONSTRAINED {
                continue;
            }
            let (g0, g1) = (0.0 + nm.g[0][k], 0.0 + nm.g[1][k]);
            let (gn, gs) = (n[0] * g0 + n[1] * g1, s[0] * g0 + s[1] * g1);
            map.dofs[map.len] = nm.dofs[k];
            // a sign flip is exact: −(a) as the general route's negation
            map.g[map.len] = if side < 0.0 { [-gn, -gs] } else { [gn, gs] };
            map.len += 1;
        }
    }
    map
}

/// Add the local force [Fₙ, Fₛ] (N) of contact `c` to the global vector `out`:
/// out += Fₙ gₙ + Fₛ gₛ (the contact's share of F_int, docs/theory.md §3).
pub fn add_contact_force(mesh: &Mesh, c: &Contact, f: [f64; 2], out: &mut [f64]) {
    add_mapped_force(&contact_map(mesh, c), f, out);
}

/// [`add_contact_force`] with the contact's map computed already.
pub fn add_mapped_force(map: &ContactMap, f: [f64; 2], out: &mut [f64]) {
    let mut share = ContactShare::NONE;
    share.set(map, f);
    share.add_to(out);
}

/// A contact's share of F_int (N): Fₙ gₙ + Fₛ gₛ on each of its free unknowns
/// ([`ContactMap`]), computed apart from its addition into the global vector (in
/// parallel, then added in contact order: [`add_mapped_force`]'s sums to the bit).
#[derive(Debug, Clone, Copy)]
pub struct ContactShare {
    len: usize,
    dofs: [u32; 12],
    values: [f64; 12],
}

impl ContactShare {
    /// No share (a contact that carries no force).
    pub const NONE: ContactShare = ContactShare {
        len: 0,
        dofs: [CONSTRAINED; 12],
        values: [0.0; 12],
    };

    /// The share of the force `f` = [Fₙ, Fₛ] (N) of the contact of `map`, written in place.
    pub fn set(&mut self, map: &ContactMap, f: [f64; 2]) {
        self.len = map.len;
        for (i, (&d, g)) in map.dofs.iter().zip(&map.g).take(map.len).enumerate() {
            self.dofs[i] = d;
            self.values[i] = f[0] * g[0] + f[1] * g[1];
        }
    }

    /// No share any more.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// out += the share.
    pub fn add_to(&self, out: &mut [f64]) {
        for (&d, v) in self.dofs.iter().zip(&self.values).take(self.len) {
            out[d as usize] += v;
        }
    }
}

/// Contact stiffness (N/m) K = Tᵀ K′ T mapped to the contact's free unknowns:
/// Σ_ab g_a k_ab g_bᵀ over a, b ∈ {n, s}, with `g` the [gₙ, gₛ] of each unknown
/// ([`ContactMap::g`]). For elastic springs, kₙ gₙ gₙᵀ + kₛ gₛ gₛᵀ. `ke` is row-major,
/// len².
pub fn contact_stiffness(g: &[[f64; 2]], k: &LocalStiffness, ke: &mut [f64]) {
    let len = g.len();
    for i in 0..len {
        for j in 0..len {
            ke[len * i + j] = contact_entry(g, k, i, j);
        }
    }
}

/// [`contact_stiffness`] for a symmetric `k`: the upper triangle packed by rows
/// (len (len + 1)/2 values), half the work and symmetric by construction.
pub fn contact_stiffness_packed(g: &[[f64; 2]], k: &LocalStiffness, ke: &mut [f64]) {
    let len = g.len();
    let mut t = 0;
    for i in 0..len {
        for j in i..len {
            ke[t] = contact_entry(g, k, i, j);
            t += 1;
        }
    }
}

/// Entry (i, j) of Σ_ab g_a k_ab g_bᵀ.
#[inline(always)]
fn contact_entry(g: &[[f64; 2]], k: &LocalStiffness, i: usize, j: usize) -> f64 {
    let mut v = 0.0;
    for a in 0..2 {
        for b in 0..2 {
            v += g[i][a] * k[a][b] * g[j][b];
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::elastic_matrix;
    use crate::scene::Plane;
    use dfem_kernels::same_bits;

    /// The built-in wall example of deformable bricks, meshed at 0.1 m.
    fn meshed_wall() -> (crate::scene::Scene, Mesh) {
        let text = crate::scene::examples::get("wall")
            .unwrap()
            .replace("joint = 0.0\n", "joint = 0.0\nmesh_size = 0.1\n");
        let scene = crate::scene::parse_str(&text, None).unwrap();
        let mesh = crate::mesh::build(&scene);
        (scene, mesh)
    }

    /// The rows of a distributed assembly, simulated in one process: each of 3 ranks
    /// evaluates only the elements touching its own unknowns (block partition), and its
    /// rows, exchanged, rebuild the whole stiffness matrix bit for bit (the same additions
    /// in the same order as the serial assembly; an independent evaluation of every
    /// element). Deformable bricks (triangles and node-to-node contacts) with distinct
    /// spring stiffnesses per contact, so that a missing or doubled element shows.
    #[test]
    fn distributed_rows_rebuild_the_serial_matrix() {
        let (scene, mesh) = meshed_wall();
        assert!(mesh.triangles.len() > 500 && mesh.contacts.len() > 100);
        let local: Vec<LocalStiffness> = (0..mesh.contacts.len())
            .map(|c| [[1e9 * (1.0 + c as f64 / 7.0), 0.0], [0.0, 3e8 + c as f64]])
            .collect();
        let serial = System::new(&scene, &mesh);
        assert!(serial.rows.is_none());
        let mut k = CsrMatrix::zeros(serial.plan.pattern().clone());
        serial.stiffness_full_into(&mesh, &local, &mut k);
        let size = 3u32;
        // whole blocks to each rank, a third of the blocks (courses of the wall) each
        let mut part = vec![0u32; mesh.n_dofs];
        let n_blocks = mesh.blocks.len();
        for b in 0..n_blocks {
            for i in mesh.block_unknowns(b) {
                part[i] = (b * size as usize / n_blocks) as u32;
            }
        }
        let mut all = Vec::new();
        let mut last = None;
        for rank in 0..size {
            let ranks = Ranks {
                part: part.clone(),
                rank,
                size,
            };
            let sys = System::new(&scene, &mesh).distributed(Some(&ranks));
            let rows = sys.rows.as_ref().expect("distributed");
            let evaluated = rows.active().iter().filter(|&&a| a).count();
            // a third of the elements plus the contacts along the cuts
            assert!(
                evaluated < sys.plan.n_elements() / 2,
                "{evaluated} of {}",
                sys.plan.n_elements()
            );
            let mut own = CsrMatrix::zeros(sys.plan.pattern().clone());
            own.values.fill(f64::NAN);
            let g = sys.contact_gradients(&mesh);
            sys.assemble_own(&mesh, &sys.dt, &g, &local, &mut own);
            all.extend(rows.pack(&own));
            last = Some((sys, own));
        }
        let (sys, mut out) = last.unwrap();
        assert_eq!(all.len(), k.values.len());
        sys.rows.as_ref().unwrap().unpack(&all, &mut out);
        assert_eq!(out.pattern.col_idx(), k.pattern.col_idx());
        assert!(same_bits(&out.values, &k.values));
    }

    /// The contacts' gradients kept with the geometry follow it: with the node positions
    /// unchanged but every contact normal turned by 0.1 rad, the kept path (triangles'
    /// part and gradients kept from the calls before) gives the matrix of a full
    /// assembly on the turned normals, to the bit, and not the one of the old normals.
    #[test]
    fn kept_gradients_follow_the_normals() {
        let (scene, mesh) = meshed_wall();
        let sys = System::new(&scene, &mesh);
        let springs = crate::material::ContactSprings { kn: 1e9, ks: 3e8 };
        let local = vec![diagonal(springs); mesh.contacts.len()];
        let zeros = || CsrMatrix::zeros(sys.plan.pattern().clone());
        let mut before = zeros();
        for _ in 0..2 {
            sys.stiffness_into(&mesh, &local, &mut before);
        }
        let mut turned = mesh.clone();
        let (sin, cos) = 0.1f64.sin_cos();
        for c in &mut turned.contacts {
            let n = c.normal;
            c.normal = [cos * n[0] - sin * n[1], sin * n[0] + cos * n[1]];
        }
        let mut kept = zeros();
        sys.stiffness_into(&turned, &local, &mut kept);
        let mut full = zeros();
        sys.stiffness_full_into(&turned, &local, &mut full);
        assert!(same_bits(&kept.values, &full.values));
        assert!(!same_bits(&kept.values, &before.values));
    }

    /// The direct map of a node-to-node contact is the general route's ([`combined_map`],
    /// an independent composition of the points' maps and gradients) to the bit, on
    /// rigid bricks (3 slots a side), deformable ones (2) and the fixed base (none), in a
    /// moved configuration (every node shifted and every normal turned, so that no
    /// gradient is a round number), and with the signed zeros the general route makes
    /// (a node level with its block's centroid: G's −(y − y_c) is −0, which its sum
    /// 0 + 1·G turns into +0). A rotation's gradient is also checked against its closed
    /// form: ∂δₙ/∂θ_l = −n·(−(y − y_c), x − x_c).
    #[test]
    fn node_to_node_maps_are_the_general_route() {
        let rigid =
            crate::scene::parse_str(&crate::scene::examples::scaled_wall(4, true), None).unwrap();
        let rigid = crate::mesh::build(&rigid);
        let (_, deformable) = meshed_wall();
        let (sin, cos) = 0.07f64.sin_cos();
        let mut checked_rotation = 0;
        for (mesh, lens) in [(rigid, [3, 6]), (deformable, [2, 4])] {
            let mut moved = mesh.clone();
            for (i, p) in moved.nodes.iter_mut().enumerate() {
                p[0] += 1e-3 * (i as f64 * 0.37).sin();
                p[1] += 1e-3 * (i as f64 * 0.23).cos();
            }
            for c in &mut moved.contacts {
                let n = c.normal;
                c.normal = [cos * n[0] - sin * n[1], sin * n[0] + cos * n[1]];
            }
            // a node level with its rigid block's centroid, a normal with a −0 component
            let c0 = moved.contacts[0].clone();
            if let crate::mesh::BlockDofs::Rigid { centroid, .. } =
                moved.blocks[c0.block_l as usize].dofs
            {
                moved.nodes[c0.node_l as usize][1] = centroid[1];
            }
            moved.contacts[1].normal = [-0.0, 1.0];
            let mut seen = std::collections::BTreeSet::new();
            for m in [&mesh, &moved] {
                for c in &m.contacts {
                    assert!(c.along.is_none());
                    let (a, b) = (node_to_node_map(m, c), combined_map(m, c));
                    assert_eq!(a.len, b.len);
                    seen.insert(a.len);
                    assert_eq!(a.dofs, b.dofs);
                    let bits = |g: &[[f64; 2]; 12]| g.map(|x| x.map(f64::to_bits));
                    assert_eq!(bits(&a.g), bits(&b.g));
                    if let crate::mesh::BlockDofs::Rigid { centroid, .. } =
                        m.blocks[c.block_l as usize].dofs
                    {
                        let (p, n) = (m.nodes[c.node_l as usize], c.normal);
                        let want = -(n[0] * -(p[1] - centroid[1]) + n[1] * (p[0] - centroid[0]));
                        assert!((a.g[2][0] - want).abs() <= 1e-15 * (1.0 + want.abs()));
                        checked_rotation += 1;
                    }
                }
            }
            // two bricks, and a brick on the fixed base
            assert!(seen.into_iter().eq(lens));
        }
        assert!(checked_rotation > 10);
    }

    #[test]
    fn cst_rigid_modes_have_no_energy() {
        let p = [[0.1, 0.2], [1.3, 0.1], [0.4, 0.9]];
        let d = elastic_matrix(2.0, 1.0, Plane::Strain);
        let mut k = [0.0; 36];
        cst_stiffness(p, &d, &mut k);
        let modes = [
            [1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
            p.iter()
                .flat_map(|q| [-q[1], q[0]])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
        ];
        for m in modes {
            for i in 0..6 {
                let r: f64 = (0..6).map(|j| k[6 * i + j] * m[j]).sum();
                assert!(r.abs() < 1e-12, "{r}");
            }
        }
    }
}
