//! The current configuration of the model (updated Lagrangian, docs/theory.md §4) and the
//! internal forces of a trial increment: co-rotational CST stresses, so that a rigid
//! rotation of any size produces no strain, and contact forces returned to the strength
//! envelope by the contact law.

use crate::assembly::{cst_b, System};
use crate::geometry::polygon::{sub, Point};
use crate::material::{ContactLaws, ContactState};
use crate::mesh::{BlockDofs, Mesh};
use dfem_kernels::CONSTRAINED;

/// What is committed at the end of a converged increment.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Committed {
    /// Cauchy stress of every triangle (σxx, σyy, σxy) (Pa), in the current frame.
    pub stress: Vec<[f64; 3]>,
    /// Contact forces (normal, shear) (N) in the contact's current frame; normal > 0 in tension.
    pub force: Vec<[f64; 2]>,
    pub state: Vec<ContactState>,
    /// Total unknowns since the start (m, rad): rigid blocks' centroid displacement and
    /// rotation, deformable nodes' displacement.
    pub u: Vec<f64>,
    /// History variables of each contact's law ([`crate::material::History`]: the spent
    /// fraction ξ of the fracture energy of a softening joint and the plastic relative
    /// displacement on its compression cap, zero for a new contact). A contact past the
    /// end of this list (one a driver added without it) has zero.
    pub history: Vec<crate::material::History>,
}

impl Committed {
    /// The history variables of the first `n` contacts: [`Committed::history`], with
    /// zero for the contacts past its end.
    pub fn history_of_all(&self, n: usize) -> Vec<crate::material::History> {
        (0..n)
            .map(|k| self.history.get(k).copied().unwrap_or_default())
            .collect()
    }

    pub fn zero(mesh: &Mesh) -> Self {
        Committed {
            stress: vec![[0.0; 3]; mesh.triangles.len()],
            force: vec![[0.0; 2]; mesh.contacts.len()],
            state: vec![ContactState::Stick; mesh.contacts.len()],
            u: vec![0.0; mesh.n_dofs],
            history: vec![[0.0; 2]; mesh.contacts.len()],
        }
    }

    /// The state of the rock before an excavation (docs/theory.md, "In-situ stress"): every
    /// triangle carries the in-situ stress σ₀ at its centroid, and every contact the
    /// traction σ₀ n of the joint at its point times its area `length × thickness` (m²):
    /// Fₙ = n·σ₀n A, Fₛ = t·σ₀n A (N; n from block l into block m, t = (−n_y, n_x)). Block
    /// m's triangles then pull on its boundary nodes with −σ₀n per unit length and the
    /// contact pushes back with +σ₀n, so that where σ₀ balances gravity
    /// (∂σ₀/∂y = −ρg per component), the initial internal forces balance the self-weight
    /// everywhere but on the excavated boundary, up to the tributary lengths' quadrature.
    pub fn in_situ(mesh: &Mesh, field: &crate::scene::InSitu, thickness: f64) -> Self {
        let mut c = Committed::zero(mesh);
        for (s, tri) in c.stress.iter_mut().zip(&mesh.triangles) {
            let y = tri.iter().map(|&k| mesh.nodes[k as usize][1]).sum::<f64>() / 3.0;
            *s = field.at(y);
        }
        for (f, k) in c.force.iter_mut().zip(&mesh.contacts) {
            let [sxx, syy, sxy] = field.at(mesh.nodes[k.node_m as usize][1]);
            let n = k.normal;
            let tr = [sxx * n[0] + sxy * n[1], sxy * n[0] + syy * n[1]];
            let a = k.length * thickness;
            *f = in_contact_frame(n, tr).map(|x| a * x);
        }
        c
    }
}

/// The components (normal, shear) of `v` in the frame of a contact of unit normal `n`:
/// (n·v, t·v) with t = (−n_y, n_x).
pub(crate) fn in_contact_frame(n: Point, v: Point) -> [f64; 2] {
    [n[0] * v[0] + n[1] * v[1], -n[1] * v[0] + n[0] * v[1]]
}

/// A trial increment evaluated: positions, stresses, contact forces and the internal force
/// vector (N).
#[derive(Debug, Clone)]
pub struct Trial {
    pub mesh: Mesh,
    pub stress: Vec<[f64; 3]>,
    pub force: Vec<[f64; 2]>,
    pub state: Vec<ContactState>,
    pub f_int: Vec<f64>,
    /// The increment of unknowns evaluated (m, rad).
    pub dq: Vec<f64>,
    /// Per contact: the increment of relative displacement (Δδₙ, Δδₛ) (m) in the
    /// contact's frame at the start of the increment (the energy audit's slip).
    pub rel: Vec<[f64; 2]>,
    /// Per contact: the history variables after the increment ([`Committed::history`]).
    pub history: Vec<crate::material::History>,
}

/// The secant local stiffness (N/m) of a contact in a state (docs/theory.md §4, step 1): the
/// elastic springs when it sticks, no shear when it slips (the friction force is carried
/// as a force, not a stiffness), nothing when it is open. The same rule gives the
/// contacts' viscosities (N·s/m) from (cₙ, cₛ).
pub fn secant_local(k: crate::material::ContactSprings, state: ContactState) -> [[f64; 2]; 2] {
    match state {
        ContactState::Stick => [[k.kn, 0.0], [0.0, k.ks]],
        ContactState::Slip => [[k.kn, 0.0], [0.0, 0.0]],
        ContactState::Open => [[0.0, 0.0], [0.0, 0.0]],
    }
}

/// The tangent local stiffness (N/m) of a contact in a state: the secant one
/// ([`secant_local`]) but for a slipping contact, whose friction force
/// Fₛ = ±(cA − Fₙ tan φ) depends on the normal displacement, ∂Fₛ/∂δₙ = ∓ tan φ kₙ (the sign
/// of `shear`, the contact's shear force in N). Unsymmetric where a contact slips.
pub fn tangent_local(
    k: crate::material::ContactSprings,
    state: ContactState,
    shear: f64,
    tan_phi: f64,
) -> [[f64; 2]; 2] {
    match state {
        ContactState::Slip => [[k.kn, 0.0], [-shear.signum() * tan_phi * k.kn, 0.0]],
        s => secant_local(k, s),
    }
}

/// Move the configuration `cur` by the increment `dq` (unknowns) and `presc` (prescribed
/// translation of each fixed block, m): exact rotation for rigid blocks. Returns the moved
/// configuration and every node's displacement increment (m), computed directly rather
/// than as a difference of positions, which would lose the small relative displacements
/// of stiff contacts to round-off.
pub fn moved(cur: &Mesh, dq: &[f64], presc: &[Point]) -> (Mesh, Vec<Point>) {
    moved_reusing(cur, dq, presc, None)
}

/// [`moved`], written into `spare` when one is given: a mesh of the same topology as `cur`
/// (the same nodes, triangles, blocks and contacts, in other positions: a configuration
/// moved from `cur` or from one it was moved from, as every trial of a static run is),
/// whose memory it reuses instead of a copy of `cur` (about 1.5 MB on the 40 × 40 wall of
/// docs/decisions/0017-trial-evaluation-overhead.md, at every trial). Only what moves is written: every node's
/// position, every block's unknowns and centroid, every contact's normal; the result is
/// [`moved`]'s to the bit. A spare whose sizes are not `cur`'s is dropped for a copy.
pub fn moved_reusing(
    cur: &Mesh,
    dq: &[f64],
    presc: &[Point],
    spare: Option<Mesh>,
) -> (Mesh, Vec<Point>) {
    let sizes = |m: &Mesh| {
        [
            m.nodes.len(),
            m.triangles.len(),
            m.blocks.len(),
            m.contacts.len(),
            m.segments.len(),
            m.n_dofs,
        ]
    };
    let (mut m, copied) = match spare {
        Some(s) if sizes(&s) == sizes(cur) => (s, false),
        _ => (cur.clone(), true),
    };
    let mut du = vec![[0.0; 2]; cur.nodes.len()];
    for (bi, b) in cur.blocks.iter().enumerate() {
        match b.dofs {
            BlockDofs::Fixed => {
                let d = presc[bi];
                for n in b.nodes.clone() {
                    du[n as usize] = d;
                }
            }
            BlockDofs::Deformable => {
                for n in b.nodes.clone() {
                    let d = cur.node_dofs[n as usize];
                    du[n as usize] = [dq[d[0] as usize], dq[d[1] as usize]];
                }
            }
            BlockDofs::Rigid { first, centroid } => {
                let f = first as usize;
                let s = dq[f + 2].sin();
                // (R(Δθ) − I) r with c − 1 = −2 sin²(Δθ/2), accurate for small angles
                let cm1 = -2.0 * (0.5 * dq[f + 2]).sin().powi(2);
                for n in b.nodes.clone() {
                    let r = sub(cur.nodes[n as usize], centroid);
                    du[n as usize] = [
                        dq[f] + cm1 * r[0] - s * r[1],
                        dq[f + 1] + s * r[0] + cm1 * r[1],
                    ];
                }
                let cn = [centroid[0] + dq[f], centroid[1] + dq[f + 1]];
                m.blocks[bi].dofs = BlockDofs::Rigid {
                    first,
                    centroid: cn,
                };
                m.blocks[bi].centroid = cn;
                continue;
            }
        }
        if !copied {
            // a fixed or deformable block keeps its unknowns and its reference centroid
            m.blocks[bi].dofs = b.dofs;
            m.blocks[bi].centroid = b.centroid;
        }
    }
    for ((p, c), d) in m.nodes.iter_mut().zip(&cur.nodes).zip(&du) {
        *p = [c[0] + d[0], c[1] + d[1]];
    }
    m.update_normals();
    (m, du)
}

/// Evaluate the increment `dq` from the configuration `cur` and the committed state
/// ([`Inputs::evaluate`]).
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    system: &System,
    cur: &Mesh,
    committed: &Committed,
    law: &dyn ContactLaws,
    area: &[f64],
    thickness: f64,
    dq: &[f64],
    presc: &[Point],
) -> Trial {
    Inputs {
        system,
        cur,
        committed,
        law,
        area,
        thickness,
    }
    .evaluate(dq, presc)
}

/// What the evaluation of a trial increment reads besides the increment: the model, the
/// configuration it moves from and its committed state, the contacts' laws and areas
/// (m²) and the plane thickness (m).
#[derive(Clone, Copy)]
pub struct Inputs<'a> {
    pub system: &'a System,
    pub cur: &'a Mesh,
    pub committed: &'a Committed,
    pub law: &'a dyn ContactLaws,
    pub area: &'a [f64],
    pub thickness: f64,
}

impl Inputs<'_> {
    /// Evaluate the increment `dq` (m, rad) with the prescribed translations `presc` (m)
    /// of the fixed blocks.
    pub fn evaluate(&self, dq: &[f64], presc: &[Point]) -> Trial {
        self.evaluate_reusing(dq, presc, None)
    }

    /// [`Inputs::evaluate`], the moved configuration written into `spare` if given
    /// ([`moved_reusing`]).
    pub fn evaluate_reusing(&self, dq: &[f64], presc: &[Point], spare: Option<Mesh>) -> Trial {
        use rayon::prelude::*;
        let inputs = self;
        let cur = inputs.cur;
        let (mesh, du) = moved_reusing(cur, dq, presc, spare);
        let n = cur.n_dofs;
        // triangles: co-rotational CST
        let stress: Vec<[f64; 3]> = (0..cur.triangles.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|t| triangle_stress(inputs, &du, t))
            .collect();
        // internal force vector, serial in element order (deterministic): the triangles
        let mut f_int = vec![0.0; n];
        for (t, s) in stress.iter().enumerate() {
            add_triangle_force(&mesh, inputs.thickness, t, s, &mut f_int);
        }
        // the contacts: their laws, and their shares of F_int (docs/theory.md §3: Fₙ gₙ + Fₛ gₛ on
        // each free unknown, with the map of the moved configuration), computed in parallel
        // into place, a slice of contacts at a time (1.2 MB of shares whatever the model's
        // size); the shares added serially in contact order after the triangles: the same
        // sums as adding them one contact at a time, bit for bit, for any number of threads
        const SLICE: usize = 8192;
        use crate::assembly::ContactShare;
        let nc = cur.contacts.len();
        let mut force = vec![[0.0; 2]; nc];
        let mut state = vec![ContactState::Stick; nc];
        let mut rel = vec![[0.0; 2]; nc];
        let mut history: Vec<crate::material::History> = vec![[0.0; 2]; nc];
        let mut shares = vec![ContactShare::NONE; SLICE.min(nc)];
        for start in (0..nc).step_by(SLICE) {
            let end = (start + SLICE).min(nc);
            let part = &mut shares[..end - start];
            part.par_iter_mut()
                .zip(&mut force[start..end])
                .zip(&mut state[start..end])
                .zip(&mut rel[start..end])
                .zip(&mut history[start..end])
                .with_min_len(256)
                .enumerate()
                .for_each(|(i, ((((share, f), st), d), h))| {
                    (*f, *st, *d, *h) = contact_update(inputs, &mesh, &du, start + i, share);
                });
            for share in part.iter() {
                share.add_to(&mut f_int);
            }
        }
        Trial {
            mesh,
            stress,
            force,
            state,
            f_int,
            dq: dq.to_vec(),
            rel,
            history,
        }
    }
}

/// The Cauchy stress (σxx, σyy, σxy) (Pa) of triangle `t` after the nodes' displacement
/// increments `du` (m) from the configuration `inputs.cur`: the co-rotational CST of
/// [`evaluate`].
fn triangle_stress(inputs: &Inputs, du: &[Point], t: usize) -> [f64; 3] {
    let Inputs {
        system,
        cur,
        committed,
        thickness,
        ..
    } = *inputs;
    let tri = cur.triangles[t];
    let x0 = tri.map(|k| cur.nodes[k as usize]);
    let (b0, _) = cst_b(x0);
    // H = ∇Δu (constant over a CST), F = ∂x/∂X = I + H
    let mut h = [[0.0, 0.0], [0.0, 0.0]];
    for k in 0..3 {
        let d = du[tri[k] as usize];
        for i in 0..2 {
            h[i][0] += d[i] * b0[0][2 * k];
            h[i][1] += d[i] * b0[1][2 * k + 1];
        }
    }
    // polar decomposition in 2D: R = rotation by θ
    let th = (h[1][0] - h[0][1]).atan2(2.0 + h[0][0] + h[1][1]);
    let (s, c) = th.sin_cos();
    // the strain U − I = Rᵀ F − I = (Rᵀ − I) + Rᵀ H, with c − 1 = −2 sin²(θ/2): formed
    // from H, never as a difference from 1, whose round-off (10⁻¹⁶ of a strain, times the
    // modulus) is an out-of-balance force no correction removes on blocks far stiffer
    // than their joints (docs/decisions/0037-stall-or-mechanism.md)
    let cm1 = -2.0 * (0.5 * th).sin().powi(2);
    let eps = [
        cm1 + c * h[0][0] + s * h[1][0],
        cm1 + c * h[1][1] - s * h[0][1],
        c * (h[0][1] + h[1][0]) + s * (h[1][1] - h[0][0]),
    ];
    let dt = system.tri_dt(t);
    let s0 = committed.stress[t];
    let mut sl = [0.0; 3];
    for i in 0..3 {
        sl[i] = s0[i] + (dt[i][0] * eps[0] + dt[i][1] * eps[1] + dt[i][2] * eps[2]) / thickness;
    }
    // σ = R σ_l Rᵀ
    let (sxx, syy, sxy) = (sl[0], sl[1], sl[2]);
    [
        c * c * sxx - 2.0 * s * c * sxy + s * s * syy,
        s * s * sxx + 2.0 * s * c * sxy + c * c * syy,
        s * c * (sxx - syy) + (c * c - s * s) * sxy,
    ]
}

/// f_int += the nodal forces (N) of triangle `t` of the moved configuration `mesh` under
/// the stress `s` (Pa).
fn add_triangle_force(mesh: &Mesh, thickness: f64, t: usize, s: &[f64; 3], f_int: &mut [f64]) {
    let tri = mesh.triangles[t];
    let x = tri.map(|k| mesh.nodes[k as usize]);
    let (b, area_t) = cst_b(x);
    for k in 0..6 {
        let v = thickness * area_t * (b[0][k] * s[0] + b[1][k] * s[1] + b[2][k] * s[2]);
        let dof = mesh.node_dofs[tri[k / 2] as usize][k % 2];
        if dof != CONSTRAINED {
            f_int[dof as usize] += v;
        }
    }
}

/// Contact `k`'s law after the nodes' displacement increments `du` (m) from
/// `inputs.cur`: its force (N), state, relative displacement increment in its frame (m)
/// and history, its share of F_int on the moved configuration `mesh` written into `share`.
fn contact_update(
    inputs: &Inputs,
    mesh: &Mesh,
    du: &[Point],
    k: usize,
    share: &mut crate::assembly::ContactShare,
) -> ([f64; 2], ContactState, [f64; 2], crate::material::History) {
    let committed = inputs.committed;
    let c = &inputs.cur.contacts[k];
    let r = sub(du[c.node_m as usize], c.at_l(|n| du[n as usize]));
    let d = in_contact_frame(c.normal, r);
    let h0 = committed.history.get(k).copied().unwrap_or([0.0; 2]);
    let (f, st, h) = inputs
        .law
        .law(k)
        .update_history(inputs.area[k], committed.force[k], h0, d);
    if f != [0.0, 0.0] {
        share.set(&crate::assembly::contact_map(mesh, &mesh.contacts[k]), f);
    } else {
        share.clear();
    }
    (f, st, d, h)
}

/// Which elements an [`Inputs::evaluate_part`] evaluates: triangles and contacts, ascending.
#[derive(Debug, Clone, Default)]
pub struct Part {
    pub triangles: Vec<usize>,
    pub contacts: Vec<usize>,
}

impl Part {
    /// The triangles of the blocks flagged in `blocks` and the contacts that touch one of
    /// them: every element that adds to those blocks' unknowns.
    pub fn of_blocks(mesh: &Mesh, blocks: &[bool]) -> Self {
        let triangles = (0..mesh.triangles.len())
            .filter(|&t| blocks[mesh.tri_block[t] as usize])
            .collect();
        let contacts = (0..mesh.contacts.len())
            .filter(|&k| {
                let c = &mesh.contacts[k];
                blocks[c.block_l as usize] || blocks[c.block_m as usize]
            })
            .collect();
        Part {
            triangles,
            contacts,
        }
    }
}

/// A trial increment evaluated on a [`Part`]'s elements ([`Inputs::evaluate_part`]).
pub struct PartTrial {
    pub mesh: Mesh,
    /// The part's contacts' forces (N) and relative displacement increments (m), in the
    /// order of `Part::contacts`.
    pub force: Vec<[f64; 2]>,
    pub rel: Vec<[f64; 2]>,
    /// The internal force vector of the part's elements (N).
    pub f_int: Vec<f64>,
}

/// [`Inputs::evaluate_reusing`] for the elements of `part` only: the moved configuration,
/// the part's contacts' forces and the internal force vector of the part's elements. At
/// the unknowns of blocks whose elements are all in the part ([`Part::of_blocks`]) it is
/// [`evaluate`]'s F_int to the bit: the same terms, added in the same order (triangles,
/// then contacts, each ascending).
impl Inputs<'_> {
    pub fn evaluate_part(
        &self,
        dq: &[f64],
        presc: &[Point],
        spare: Option<Mesh>,
        part: &Part,
    ) -> PartTrial {
        let inputs = self;
        let (mesh, du) = moved_reusing(inputs.cur, dq, presc, spare);
        let mut f_int = vec![0.0; inputs.cur.n_dofs];
        for &t in &part.triangles {
            let s = triangle_stress(inputs, &du, t);
            add_triangle_force(&mesh, inputs.thickness, t, &s, &mut f_int);
        }
        let mut share = crate::assembly::ContactShare::NONE;
        let (force, rel) = part
            .contacts
            .iter()
            .map(|&k| {
                let (f, _, d, _) = contact_update(inputs, &mesh, &du, k, &mut share);
                share.add_to(&mut f_int);
                (f, d)
            })
            .unzip();
        PartTrial {
            mesh,
            force,
            rel,
            f_int,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tangent of every state is the law's derivative: a central difference of the
    /// Mohr–Coulomb return map (`ContactLaw::update`) from states well inside each regime,
    /// slipping either way, with cohesion (the friction's dependence on the normal
    /// displacement is −sign(Fₛ) tan φ kₙ), sticking and open.
    #[test]
    fn tangent_local_is_the_derivative_of_the_law() {
        use crate::material::{ContactLaw, ElasticBand, MohrCoulomb};
        let law = MohrCoulomb {
            elastic: ElasticBand {
                normal_modulus: 1e9,
                shear_modulus: 4e8,
                band: 0.01,
            },
            tan_phi: 0.6,
            cohesion: 2e4,
            tensile_strength: 1e4,
        };
        let area = 0.05;
        let k = law.springs(area);
        let committed = [-2e4, 3e3];
        // (Δδₙ, Δδₛ) in m: slip forward, slip backward, stick, open
        for d in [[-1e-6, 4e-5], [-1e-6, -4e-5], [-1e-6, 1e-7], [2e-4, 0.0]] {
            let (f, state) = law.update(area, committed, d);
            let t = tangent_local(k, state, f[1], law.tan_phi);
            let h = 1e-10;
            for j in 0..2 {
                let (mut a, mut b) = (d, d);
                a[j] += h;
                b[j] -= h;
                let (fa, sa) = law.update(area, committed, a);
                let (fb, sb) = law.update(area, committed, b);
                assert_eq!((sa, sb), (state, state), "{d:?} stays in its regime");
                for i in 0..2 {
                    let fd = (fa[i] - fb[i]) / (2.0 * h);
                    assert!(
                        (fd - t[i][j]).abs() <= 1e-6 * k.kn,
                        "{state:?} {d:?}: ∂F{i}/∂δ{j} = {fd:e} by differences, tangent {:e}",
                        t[i][j]
                    );
                }
            }
        }
    }

    /// [`evaluate_part`] on the elements of a few blocks gives [`evaluate`]'s internal
    /// forces at those blocks' unknowns to the bit, for rigid bricks and deformable ones
    /// (triangles and contacts), from a committed state with forces and stresses in it,
    /// with increments large enough that contacts open, slip and stick; and its contacts'
    /// forces are `evaluate`'s.
    #[test]
    fn a_part_gives_the_whole_evaluation_at_its_blocks() {
        use crate::material::PerContact;
        for rigid in [true, false] {
            let text = crate::scene::examples::scaled_wall(4, rigid);
            let text = if rigid {
                text
            } else {
                text.replace("joint = 0.0\n", "joint = 0.0\nmesh_size = 0.1\n")
            };
            let scene = crate::scene::parse_str(&text, None).unwrap();
            let mesh = crate::mesh::build(&scene);
            let system = System::new(&scene, &mesh);
            let law = PerContact::of_scene(&scene, &mesh);
            let t = scene.model.thickness;
            let area: Vec<f64> = mesh.contacts.iter().map(|c| c.length * t).collect();
            let n = mesh.n_dofs;
            let presc: Vec<Point> = mesh.blocks.iter().map(|_| [0.0, 0.0]).collect();
            // a committed state: the wall moved once, its forces and stresses kept
            let first = evaluate(
                &system,
                &mesh,
                &Committed::zero(&mesh),
                &law,
                &area,
                t,
                &pattern(n, -2e-5),
                &presc,
            );
            let committed = Committed {
                stress: first.stress,
                force: first.force,
                state: first.state,
                u: vec![0.0; n],
                history: first.history,
            };
            let dq = pattern(n, 3e-4);
            let whole = evaluate(&system, &mesh, &committed, &law, &area, t, &dq, &presc);
            let states = |s: ContactState| whole.state.iter().filter(|&&x| x == s).count();
            assert!(states(ContactState::Open) > 0 && states(ContactState::Slip) > 0);
            let blocks: Vec<bool> = (0..mesh.blocks.len()).map(|b| b % 3 == 1).collect();
            let part = Part::of_blocks(&mesh, &blocks);
            assert!(!part.contacts.is_empty() && part.contacts.len() < mesh.contacts.len());
            assert_eq!(rigid, part.triangles.is_empty());
            let inputs = Inputs {
                system: &system,
                cur: &mesh,
                committed: &committed,
                law: &law,
                area: &area,
                thickness: t,
            };
            let got = inputs.evaluate_part(&dq, &presc, None, &part);
            let mut checked = 0;
            for b in (0..mesh.blocks.len()).filter(|&b| blocks[b]) {
                let dofs = mesh.block_unknowns(b);
                for d in dofs {
                    assert_eq!(
                        got.f_int[d].to_bits(),
                        whole.f_int[d].to_bits(),
                        "unknown {d}"
                    );
                    checked += 1;
                }
            }
            assert!(checked > 10);
            for (i, &k) in part.contacts.iter().enumerate() {
                assert_eq!(got.force[i], whole.force[k]);
                assert_eq!(got.rel[i], whole.rel[k]);
            }
        }
    }

    /// Unknowns (m, rad) that differ from unknown to unknown: `scale` × a fixed pattern.
    fn pattern(n: usize, scale: f64) -> Vec<f64> {
        (0..n)
            .map(|i| scale * (0.3 + (i as f64 * 0.7).sin()))
            .collect()
    }

    /// A configuration written into a spare is the copied one to the bit: every field of
    /// the mesh (compared through its serialized form, which spells every float and its
    /// sign in full), for rigid bricks and deformable ones on a fixed base moved by a
    /// prescribed translation, the spare being another configuration of the same mesh
    /// (moved by other unknowns, another base translation), and for a spare of another
    /// mesh (dropped for a copy).
    #[test]
    fn moved_into_a_spare_is_the_copy() {
        let scene = |rigid| {
            let text = crate::scene::examples::scaled_wall(3, rigid);
            let text = if rigid {
                text
            } else {
                text.replace("joint = 0.0\n", "joint = 0.0\nmesh_size = 0.1\n")
            };
            crate::mesh::build(&crate::scene::parse_str(&text, None).unwrap())
        };
        let (rigid, deformable) = (scene(true), scene(false));
        assert!(deformable.triangles.len() > 50);
        for (mesh, other) in [(&rigid, &deformable), (&deformable, &rigid)] {
            let n = mesh.n_dofs;
            let presc =
                |s: f64| -> Vec<Point> { mesh.blocks.iter().map(|_| [s, -0.5 * s]).collect() };
            // the current configuration: moved once already
            let (cur, _) = moved(mesh, &pattern(n, 1e-3), &presc(1e-4));
            let (spare, _) = moved(&cur, &pattern(n, -2e-2), &presc(3e-3));
            let (dq, pr) = (pattern(n, 5e-3), presc(-2e-4));
            let (want, du) = moved(&cur, &dq, &pr);
            let json = |m: &Mesh| serde_json::to_string(m).unwrap();
            for spare in [spare, other.clone()] {
                let (got, du2) = moved_reusing(&cur, &dq, &pr, Some(spare));
                assert_eq!(json(&got), json(&want));
                assert_eq!(format!("{du2:?}"), format!("{du:?}"));
            }
            assert_ne!(json(&want), json(&cur));
        }
    }
}
