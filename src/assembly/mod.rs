//! Assembly: maps the mesh and the materials onto `dfem_kernels::assembly`.
//!
//! Element order is fixed (all triangles, then all contacts), so the pattern and the
//! gather map are built once per contact topology and every assembly sums in the same
//! order whatever the number of threads.

pub mod loads;
pub mod mass;

use crate::material::{block_elastic, ContactSprings};
use crate::mesh::{Contact, Mesh, PointMap};

use crate::geometry::polygon::Point;
use crate::scene::Scene;
use dfem_kernels::{AssemblyPlan, Connectivity, CsrMatrix, CONSTRAINED};

/// The assembly plan of a mesh: triangles (6 slots each) then contacts (6 slots each:
/// the 3 unknowns node l depends on, then node m's).
pub struct System {
    pub plan: AssemblyPlan,
    pub n_triangles: usize,
    pub n_contacts: usize,
    /// Per triangle: Dₑ (Pa) of its block material, times the thickness (m).
    tri_dt: Vec<[[f64; 3]; 3]>,
    /// Per triangle: D_v (Pa·s) of its block material (viscous Lamé constants), times
    /// the thickness (m).
    tri_dv: Vec<[[f64; 3]; 3]>,
}

/// Local stiffness of a contact in its (n, s) frame (N/m): row = force component,
/// column = relative displacement component. Symmetric for the secant forms, with an
/// off-diagonal friction term in Newton's tangent of a slipping contact.
pub type LocalStiffness = [[f64; 2]; 2];

/// The local stiffness of elastic springs.
pub fn diagonal(k: ContactSprings) -> LocalStiffness {
    [[k.kn, 0.0], [0.0, k.ks]]
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
        for c in &mesh.contacts {
            let (ml, mm) = mesh.contact_maps(c);
            let mut dofs = [CONSTRAINED; 12];
            dofs[..ml.len].copy_from_slice(&ml.dofs[..ml.len]);
            dofs[ml.len..ml.len + mm.len].copy_from_slice(&mm.dofs[..mm.len]);
            conn.push(&dofs[..ml.len + mm.len]);
        }
        if rigid_diagonal {
            for b in &mesh.blocks {
                if let crate::mesh::BlockDofs::Rigid { first, .. } = b.dofs {
                    conn.push(&[first, first + 1, first + 2]);
                }
            }
        }
        let t = scene.model.thickness;
        let tri_dt = mesh
            .tri_block
            .iter()
            .map(|&b| {
                let m = &scene.materials[scene.blocks[b as usize].material];
                let d = block_elastic(m, scene.model.plane);
                d.map(|r| r.map(|x| x * t))
            })
            .collect();
        // viscous matrices only for a dynamic analysis (a static run does no damping work)
        let tri_dv = mesh
            .tri_block
            .iter()
            .filter(|_| rigid_diagonal)
            .map(|&b| {
                let m = &scene.materials[scene.blocks[b as usize].material];
                let d = crate::material::block_viscous(m, scene.model.plane);
                d.map(|r| r.map(|x| x * t))
            })
            .collect();
        System {
            plan: AssemblyPlan::new(mesh.n_dofs, &conn),
            n_triangles: mesh.triangles.len(),
            n_contacts: mesh.contacts.len(),
            tri_dt,
            tri_dv,
        }
    }

    /// Stiffness K (N/m) for elastic contact springs: CST blocks (METHOD.md §2,
    /// Kₑ = t A Bᵀ Dₑ B) plus contacts (METHOD.md §3, K = Tᵀ K′ T).
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
    pub fn stiffness_into(&self, mesh: &Mesh, local: &[LocalStiffness], out: &mut CsrMatrix) {
        self.assemble_with(mesh, &self.tri_dt, local, out);
    }

    /// Damping matrix C (N·s/m) of the Kelvin–Voigt viscosities (METHOD.md §2, §6), for a
    /// system built [`System::for_dynamics`]:
    /// Cₑ = t A Bᵀ D_v B for the triangles and Tᵀ C′ T for the contacts, with a local
    /// viscosity per contact (cₙ = Eₙ* A_c / h, cₛ = Gₛ* A_c / h where they act).
    pub fn damping_into(&self, mesh: &Mesh, local: &[LocalStiffness], out: &mut CsrMatrix) {
        self.assemble_with(mesh, &self.tri_dv, local, out);
    }

    fn assemble_with(
        &self,
        mesh: &Mesh,
        tri: &[[[f64; 3]; 3]],
        local: &[LocalStiffness],
        out: &mut CsrMatrix,
    ) {
        let nt = self.n_triangles;
        let nc = self.n_contacts;
        let kernel = |e: usize, ke: &mut [f64]| {
            if e < nt {
                let t = mesh.triangles[e];
                let p = t.map(|n| mesh.nodes[n as usize]);
                cst_stiffness(p, &tri[e], ke);
            } else if e < nt + nc {
                let c = e - nt;
                let con = &mesh.contacts[c];
                let (ml, mm) = mesh.contact_maps(con);
                contact_stiffness(&ml, &mm, con.normal, &local[c], ke);
            } else {
                // the rigid blocks' diagonal elements (dynamics) carry no stiffness
                ke.fill(0.0);
            }
        };
        if local.iter().all(|k| k[0][1] == k[1][0]) {
            self.plan.assemble(kernel, out);
        } else {
            self.plan.assemble_unsymmetric(kernel, out);
        }
    }

    /// tDₑ (Pa·m) of triangle `t`.
    pub fn tri_dt(&self, t: usize) -> &[[f64; 3]; 3] {
        &self.tri_dt[t]
    }
}

/// Strain–displacement matrix B (1/m) of a CST and its area (m²), METHOD.md §2:
/// B = 1/(2A) [[bᵢ,0,bⱼ,0,bₖ,0],[0,cᵢ,0,cⱼ,0,cₖ],[cᵢ,bᵢ,cⱼ,bⱼ,cₖ,bₖ]],
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

/// CST stiffness Kₑ = A Bᵀ (t Dₑ) B into `ke` (row-major 6×6, N/m).
pub fn cst_stiffness(p: [Point; 3], dt: &[[f64; 3]; 3], ke: &mut [f64]) {
    let (b, area) = cst_b(p);
    // DB = (tD) B, 3×6
    let mut db = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..6 {
            db[i][j] = dt[i][0] * b[0][j] + dt[i][1] * b[1][j] + dt[i][2] * b[2][j];
        }
    }
    for i in 0..6 {
        for j in 0..6 {
            ke[6 * i + j] = area * (b[0][i] * db[0][j] + b[1][i] * db[1][j] + b[2][i] * db[2][j]);
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

/// Call `f(dof, gₙ, gₛ)` for each free unknown of contact `c`, with the gradients of its
/// relative displacements δₙ, δₛ ([`contact_gradient`]).
fn for_contact_dofs(mesh: &Mesh, c: &Contact, mut f: impl FnMut(usize, f64, f64)) {
    let (ml, mm) = mesh.contact_maps(c);
    let gn = contact_gradient(&ml, &mm, c.normal);
    let gs = contact_gradient(&ml, &mm, [-c.normal[1], c.normal[0]]);
    for i in 0..ml.len + mm.len {
        let dof = if i < ml.len {
            ml.dofs[i]
        } else {
            mm.dofs[i - ml.len]
        };
        if dof != CONSTRAINED {
            f(dof as usize, gn[i], gs[i]);
        }
    }
}

/// Add the local force [Fₙ, Fₛ] (N) of contact `c` to the global vector `out`:
/// out += Fₙ gₙ + Fₛ gₛ (the contact's share of F_int, METHOD.md §3).
pub fn add_contact_force(mesh: &Mesh, c: &Contact, f: [f64; 2], out: &mut [f64]) {
    for_contact_dofs(mesh, c, |d, gn, gs| out[d] += f[0] * gn + f[1] * gs);
}

/// Contact stiffness (N/m) K = Tᵀ K′ T mapped to the unknowns: Σ_ab g_a k_ab g_bᵀ over
/// a, b ∈ {n, s}, with gₙ, gₛ the gradients of δₙ = n·(u_m − u_l) and
/// δₛ = s·(u_m − u_l), s = (−n_y, n_x). For elastic springs, kₙ gₙ gₙᵀ + kₛ gₛ gₛᵀ.
/// `ke` is row-major, (ml.len + mm.len)².
pub fn contact_stiffness(
    ml: &PointMap,
    mm: &PointMap,
    n: Point,
    k: &LocalStiffness,
    ke: &mut [f64],
) {
    let g = [
        contact_gradient(ml, mm, n),
        contact_gradient(ml, mm, [-n[1], n[0]]),
    ];
    let len = ml.len + mm.len;
    for i in 0..len {
        for j in 0..len {
            let mut v = 0.0;
            for a in 0..2 {
                for b in 0..2 {
                    v += g[a][i] * k[a][b] * g[b][j];
                }
            }
            ke[len * i + j] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::elastic_matrix;
    use crate::scene::Plane;

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
