//! CST patch test (docs/validation.md V9): on an irregular mesh of a non-convex block, a linear
//! displacement field imposed on the boundary nodes is reproduced exactly (to round-off)
//! at every interior node, and every triangle carries the same uniform stress σ = Dₑ ε.
//! Reference: the closed form itself (a CST represents any linear field exactly).

#![allow(clippy::needless_range_loop)]
mod common;
use dfem::assembly::System;
use dfem::material::{block_elastic, elastic_matrix};
use dfem::scene::Plane;
use std::collections::HashSet;

const SCENE: &str = r#"
[model]
plane = "PLANE"
[[material]]
name = "stone"
lame_lambda = 3.1e9
lame_mu = 1.7e9
unit_weight = 0.0
[[block]]
name = "l"
material = "stone"
vertices = [[0.0, 0.0], [2.0, 0.0], [2.3, 0.9], [1.1, 1.0], [0.9, 2.1], [-0.2, 1.6]]
mesh_size = 0.23
"#;

fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap();
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x
}

fn patch(plane: Plane) {
    let sc = common::scene(&SCENE.replace(
        "PLANE",
        if plane == Plane::Strain {
            "strain"
        } else {
            "stress"
        },
    ));
    let m = dfem::mesh::build(&sc);
    assert!(
        m.triangles.len() > 40,
        "the mesh should be refined: {}",
        m.triangles.len()
    );
    let sys = System::new(&sc, &m);
    let k = sys.stiffness(&m, &[]);
    // linear field u = a + E x
    let field = |p: [f64; 2]| {
        [
            1e-3 + 2e-4 * p[0] - 1e-4 * p[1],
            -5e-4 + 0.7e-4 * p[0] + 3e-4 * p[1],
        ]
    };
    let boundary: HashSet<u32> = m.blocks[0].boundary.iter().copied().collect();
    let n = m.n_dofs;
    let mut fixed = vec![None; n];
    for &b in &boundary {
        let d = m.node_dofs[b as usize];
        let v = field(m.nodes[b as usize]);
        fixed[d[0] as usize] = Some(v[0]);
        fixed[d[1] as usize] = Some(v[1]);
    }
    let free: Vec<usize> = (0..n).filter(|&i| fixed[i].is_none()).collect();
    assert!(free.len() >= 10, "there must be interior nodes");
    let pos: Vec<Option<usize>> = {
        let mut p = vec![None; n];
        for (k, &i) in free.iter().enumerate() {
            p[i] = Some(k);
        }
        p
    };
    let mut a = vec![vec![0.0; free.len()]; free.len()];
    let mut rhs = vec![0.0; free.len()];
    let (rp, ci) = (k.pattern.row_ptr(), k.pattern.col_idx());
    for i in 0..n {
        let Some(r) = pos[i] else { continue };
        for idx in rp[i]..rp[i + 1] {
            let j = ci[idx] as usize;
            match (pos[j], fixed[j]) {
                (Some(c), _) => a[r][c] += k.values[idx],
                (None, Some(v)) => rhs[r] -= k.values[idx] * v,
                _ => unreachable!(),
            }
        }
    }
    #[cfg(any(feature = "mumps", feature = "petsc"))]
    ffi_backends_reproduce_the_field(&a, &rhs, &free, &m, &boundary, &field);
    let x = dense_solve(a, rhs);
    let mut worst: f64 = 0.0;
    for (node, p) in m.nodes.iter().enumerate() {
        if boundary.contains(&(node as u32)) {
            continue;
        }
        let d = m.node_dofs[node];
        let exact = field(*p);
        worst = worst.max((x[pos[d[0] as usize].unwrap()] - exact[0]).abs());
        worst = worst.max((x[pos[d[1] as usize].unwrap()] - exact[1]).abs());
    }
    assert!(worst < 1e-13, "interior displacement error {worst:e} m");
    // uniform stress everywhere
    let mut u = vec![0.0; n];
    for i in 0..n {
        u[i] = fixed[i].unwrap_or_else(|| x[pos[i].unwrap()]);
    }
    let eps = [2e-4, 3e-4, -1e-4 + 0.7e-4];
    let d = elastic_matrix(3.1e9, 1.7e9, plane);
    assert_eq!(d, block_elastic(&sc.materials[0], plane));
    let sigma: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|j| d[i][j] * eps[j]).sum())
        .collect();
    for s in dfem::analysis::triangle_stresses(&sc, &m, &u) {
        for i in 0..3 {
            assert!(
                (s[i] - sigma[i]).abs() < 1e-9 * 1e6,
                "stress {s:?} vs {sigma:?}"
            );
        }
    }
}

/// The same interior problem (the free rows and columns of K, as a sparse matrix) solved by
/// every backend of dfem-ffi compiled in (MUMPS, PETSc): the interior nodes follow the linear
/// field to 1e-8 relative to the largest displacement (the direct solvers reach round-off,
/// ~1e-15; PETSc's CG stops at a relative residual of 1e-12 and cond(K_free) ~ 1e2 here).
#[cfg(any(feature = "mumps", feature = "petsc"))]
fn ffi_backends_reproduce_the_field(
    a: &[Vec<f64>],
    rhs: &[f64],
    free: &[usize],
    m: &dfem::mesh::Mesh,
    boundary: &HashSet<u32>,
    field: &dyn Fn([f64; 2]) -> [f64; 2],
) {
    use dfem_kernels::{CsrMatrix, CsrPattern};
    let nf = free.len();
    let entries = (0..nf).flat_map(|i| {
        (0..nf)
            .filter(move |&j| a[i][j] != 0.0)
            .map(move |j| (i, j))
    });
    let mut k = CsrMatrix::zeros(std::sync::Arc::new(CsrPattern::from_entries(nf, entries)));
    for i in 0..nf {
        for j in 0..nf {
            if a[i][j] != 0.0 {
                k.add(i, j, a[i][j]);
            }
        }
    }
    let umax = m
        .nodes
        .iter()
        .map(|&p| field(p)[0].abs().max(field(p)[1].abs()))
        .fold(0.0, f64::max);
    for name in dfem_ffi::BACKENDS {
        let mut b = dfem::solve::backend(name).unwrap();
        b.factorize(&k).unwrap();
        let mut x = rhs.to_vec();
        b.solve(&mut x).unwrap();
        let pos = |dof: u32| free.binary_search(&(dof as usize)).unwrap();
        let mut worst: f64 = 0.0;
        for (node, p) in m.nodes.iter().enumerate() {
            if boundary.contains(&(node as u32)) {
                continue;
            }
            let d = m.node_dofs[node];
            let exact = field(*p);
            worst = worst.max((x[pos(d[0])] - exact[0]).abs());
            worst = worst.max((x[pos(d[1])] - exact[1]).abs());
        }
        eprintln!("{name}: interior error / max |u| = {:.2e}", worst / umax);
        assert!(
            worst <= 1e-8 * umax,
            "{name}: interior displacement error {worst:e} m"
        );
    }
}

#[test]
fn cst_patch_test_plane_strain() {
    patch(Plane::Strain);
}

#[test]
fn cst_patch_test_plane_stress() {
    patch(Plane::Stress);
}
