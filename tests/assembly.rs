//! The stiffness assembly of `System` (issue 6) against a straightforward triplet sum, and
//! its three paths bit-identical to one another on 1 and 2 threads.
//!
//! Scene: a running-bond wall of 3 courses of deformable bricks (CST triangles, 0.06 m
//! mesh) on a fixed base, under a rigid steel beam: contacts between two deformable
//! nodes, between a deformable node and the rigid beam (3 unknowns on one side), and with
//! the fixed base (constrained slots).
//!
//! Reference: K = Σ_triangles t A Bᵀ D B, the dense triple product of B and the area of
//! `cst_b` with the material's tD (docs/theory.md §2), plus Σ_contacts Σ_ab g_a k_ab g_bᵀ with
//! the gradients gₙ, gₛ of `contact_gradient` (docs/theory.md §3), every product added into a
//! hash map keyed by (row, column) with the sum of absolute values. Each entry is a sum of
//! at most ~100 rounded products, so the assembly may differ from it by at most
//! 100 · 2⁻⁵³ · Σ|terms| ≈ 1.1e-14 Σ|terms|; the test allows 1e-12 Σ|terms|, still far
//! below any single contribution, so a missed or doubled element shows.

mod common;

use dfem::assembly::{contact_gradient, cst_b, diagonal, LocalStiffness, System};
use dfem::material::ContactSprings;
use dfem::mesh::Mesh;
use dfem_kernels::{CsrMatrix, CONSTRAINED};
use std::collections::HashMap;

const SCENE: &str = r#"
[model]
plane = "stress"
thickness = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "brick"
lame_lambda = 1.389e9
lame_mu = 2.083e9
unit_weight = 18e3

[[material]]
name = "steel"
lame_lambda = 121e9
lame_mu = 81e9
unit_weight = 0.0

[[joint]]
name = "j"
normal_modulus = 8.2e8
shear_modulus = 3.6e8
band = 0.010
friction_angle = 36.87

[[generate]]
type = "wall"
material = "brick"
kind = "deformable"
mesh_size = 0.06
courses = 3
bricks_per_course = 3
brick_length = 0.4
brick_height = 0.2
joint = 0.0
base = true
top_beam = false

[[block]]
name = "beam"
material = "steel"
kind = "rigid"
vertices = [[0.0, 0.6], [1.2, 0.6], [1.2, 0.7], [0.0, 0.7]]

[contacts]
joint = "j"
tolerance = 1e-6

[analysis]
type = "static"
"#;

fn setup() -> (Mesh, System) {
    let scene = common::scene(SCENE);
    let mesh = dfem::mesh::build(&scene);
    let system = System::new(&scene, &mesh);
    (mesh, system)
}

/// Local stiffnesses: elastic, open (zero), or a Newton tangent (unsymmetric) by contact.
fn locals(nc: usize, open_every: usize, tangent_every: usize) -> Vec<LocalStiffness> {
    (0..nc)
        .map(|c| {
            let kn = 1e8 * (1.0 + 0.01 * (c % 7) as f64);
            if c % open_every == 0 {
                [[0.0; 2]; 2]
            } else if tangent_every > 0 && c % tangent_every == 0 {
                [[kn, 0.0], [0.6 * kn, 0.0]]
            } else {
                diagonal(ContactSprings { kn, ks: 0.4 * kn })
            }
        })
        .collect()
}

/// The triplet sum of the header: (row, column) → (sum, Σ|terms|).
fn triplet_sum(
    mesh: &Mesh,
    system: &System,
    local: &[LocalStiffness],
) -> HashMap<(u32, u32), (f64, f64)> {
    let mut sum: HashMap<(u32, u32), (f64, f64)> = HashMap::new();
    let mut add = |i: u32, j: u32, v: f64| {
        if i != CONSTRAINED && j != CONSTRAINED {
            let e = sum.entry((i, j)).or_default();
            e.0 += v;
            e.1 += v.abs();
        }
    };
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let (b, area) = cst_b(tri.map(|n| mesh.nodes[n as usize]));
        let d = system.tri_dt(t);
        let dofs: Vec<u32> = tri
            .iter()
            .flat_map(|&n| mesh.node_dofs[n as usize])
            .collect();
        for i in 0..6 {
            for j in 0..6 {
                let mut v = 0.0;
                for p in 0..3 {
                    for q in 0..3 {
                        v += b[p][i] * d[p][q] * b[q][j];
                    }
                }
                add(dofs[i], dofs[j], area * v);
            }
        }
    }
    for (c, con) in mesh.contacts.iter().enumerate() {
        let (ml, mm) = mesh.contact_maps(con);
        let n = con.normal;
        let g = [
            contact_gradient(&ml, &mm, n),
            contact_gradient(&ml, &mm, [-n[1], n[0]]),
        ];
        let dofs: Vec<u32> = ml.dofs[..ml.len]
            .iter()
            .chain(&mm.dofs[..mm.len])
            .copied()
            .collect();
        for i in 0..dofs.len() {
            for j in 0..dofs.len() {
                for a in 0..2 {
                    for b in 0..2 {
                        add(dofs[i], dofs[j], g[a][i] * local[c][a][b] * g[b][j]);
                    }
                }
            }
        }
    }
    sum
}

fn bits(k: &CsrMatrix) -> Vec<u64> {
    k.values.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn stiffness_matches_a_triplet_sum() {
    let (mesh, system) = setup();
    let nc = mesh.contacts.len();
    assert!(mesh.triangles.len() > 100 && nc > 50);
    // contacts with 2 + 2, 2 + 3 and 2 + 0 unknowns
    let sizes: Vec<usize> = mesh
        .contacts
        .iter()
        .map(|c| {
            let (ml, mm) = mesh.contact_maps(c);
            (0..ml.len).filter(|&k| ml.dofs[k] != CONSTRAINED).count()
                + (0..mm.len).filter(|&k| mm.dofs[k] != CONSTRAINED).count()
        })
        .collect();
    for s in [2, 4, 5] {
        assert!(sizes.contains(&s), "a contact with {s} unknowns");
    }
    for (what, local) in [("secant", locals(nc, 5, 0)), ("tangent", locals(nc, 5, 3))] {
        let reference = triplet_sum(&mesh, &system, &local);
        let mut k = CsrMatrix::zeros(system.plan.pattern().clone());
        k.values.fill(f64::NAN);
        system.stiffness_into(&mesh, &local, &mut k);
        let p = k.pattern.clone();
        for i in 0..p.n() {
            for q in p.row_ptr()[i]..p.row_ptr()[i + 1] {
                let j = p.col_idx()[q];
                let (sum, scale) = reference.get(&(i as u32, j)).copied().unwrap_or_default();
                let v = k.values[q];
                assert!(
                    (v - sum).abs() <= 1e-12 * scale,
                    "{what} ({i}, {j}): {v:e} against {sum:e} (scale {scale:e})"
                );
            }
        }
        for &(i, j) in reference.keys() {
            assert!(
                p.find(i as usize, j as usize).is_some(),
                "({i}, {j}) in the pattern"
            );
        }
        let symmetric = (0..p.n()).all(|i| {
            (p.row_ptr()[i]..p.row_ptr()[i + 1]).all(|q| {
                let t = p.find(p.col_idx()[q] as usize, i).unwrap();
                k.values[q].to_bits() == k.values[t].to_bits()
            })
        });
        assert_eq!(
            symmetric,
            what == "secant",
            "{what}: symmetric to the bit or not"
        );
    }
}

#[test]
fn kept_blocks_and_update_paths_give_the_whole_assembly_to_the_bit() {
    let (mesh, system) = setup();
    let nc = mesh.contacts.len();
    let a = locals(nc, 5, 0);
    // about 1 in 20 contacts changes: opens, closes, or takes a Newton tangent
    let b: Vec<LocalStiffness> = (0..nc)
        .map(|c| if c % 20 == 1 { [[0.0; 2]; 2] } else { a[c] })
        .collect();
    let t: Vec<LocalStiffness> = (0..nc)
        .map(|c| {
            if c % 23 == 2 {
                [[2e8, 0.0], [1e8, 0.0]]
            } else {
                b[c]
            }
        })
        .collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let full = |local: &[LocalStiffness]| {
                let mut k = CsrMatrix::zeros(system.plan.pattern().clone());
                system.stiffness_full_into(&mesh, local, &mut k);
                bits(&k)
            };
            let mut k = CsrMatrix::zeros(system.plan.pattern().clone());
            // the first call assembles everything, the second keeps the triangles' part,
            // the third uses it
            for _ in 0..3 {
                system.stiffness_into(&mesh, &a, &mut k);
                assert_eq!(bits(&k), full(&a), "kept blocks + contacts");
            }
            let mut out = vec![bits(&k)];
            for (prev, next) in [(&a, &b), (&b, &t), (&t, &a), (&a, &a)] {
                system.stiffness_update(&mesh, prev, next, &mut k);
                assert_eq!(bits(&k), full(next), "update");
                out.push(bits(&k));
            }
            // another geometry: the kept part is not used for it
            let mut moved = mesh.clone();
            for p in &mut moved.nodes {
                p[0] *= 1.0 + 1e-3;
            }
            let mut k2 = k.clone();
            system.stiffness_update(&moved, &a, &b, &mut k2);
            let mut k3 = CsrMatrix::zeros(system.plan.pattern().clone());
            system.stiffness_full_into(&moved, &b, &mut k3);
            assert_eq!(bits(&k2), bits(&k3), "update on a new geometry");
            assert_ne!(bits(&k2), full(&b));
            out
        })
    };
    assert!(run(1) == run(2), "1 and 2 threads differ");
}
