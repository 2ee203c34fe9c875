//! Updated Lagrangian geometry with co-rotational CSTs (docs/theory.md §4: "rotate, don't
//! stretch"): a rigid rotation of a deformable block, however large, produces no strain,
//! and a block carrying a stress that is rotated rigidly carries the same stress rotated
//! (σ' = R σ Rᵀ). And a prescribed displacement of a fixed block is followed by the block
//! it carries.

mod common;
use dfem::analysis::config::{evaluate, Committed};
use dfem::assembly::System;
use dfem::material::MohrCoulomb;

const SCENE: &str = r#"
[[material]]
name = "stone"
lame_lambda = 3e9
lame_mu = 2e9
unit_weight = 0.0
[[joint]]
name = "j"
normal_modulus = 1e9
shear_modulus = 1e8
band = 0.01
friction_angle = 30.0
[[block]]
name = "b"
material = "stone"
vertices = [[0.0, 0.0], [2.0, 0.0], [2.5, 1.0], [0.7, 1.6]]
mesh_size = 0.3
"#;

/// Unknowns that rotate every node of block 0 rigidly by `theta` about (x0, y0).
fn rigid_rotation(m: &dfem::mesh::Mesh, theta: f64) -> Vec<f64> {
    let (s, c) = theta.sin_cos();
    let mut dq = vec![0.0; m.n_dofs];
    for (n, p) in m.nodes.iter().enumerate() {
        let (x, y) = (p[0] - 0.3, p[1] - 0.2);
        let d = m.node_dofs[n];
        dq[d[0] as usize] = c * x - s * y - x;
        dq[d[1] as usize] = s * x + c * y - y;
    }
    dq
}

#[test]
fn large_rigid_rotation_produces_no_strain() {
    let sc = common::scene(SCENE);
    let m = dfem::mesh::build(&sc);
    assert!(m.triangles.len() > 20);
    let sys = System::new(&sc, &m);
    let law = MohrCoulomb::from_joint(&sc.joints[0]);
    let presc = vec![[0.0; 2]; m.blocks.len()];
    for theta in [0.01, 0.5, 1.5, 3.0] {
        let dq = rigid_rotation(&m, theta);
        let t = evaluate(&sys, &m, &Committed::zero(&m), &law, &[], 1.0, &dq, &presc);
        let smax = t
            .stress
            .iter()
            .flatten()
            .fold(0.0f64, |a, s| a.max(s.abs()));
        let fmax = t.f_int.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        // E·(round-off) ≈ 1e9 × 1e-15
        assert!(smax < 1e-4, "θ = {theta}: spurious stress {smax} Pa");
        assert!(fmax < 1e-4, "θ = {theta}: spurious internal force {fmax} N");
    }
}

#[test]
fn rigid_rotation_rotates_the_stress() {
    let sc = common::scene(SCENE);
    let m = dfem::mesh::build(&sc);
    let sys = System::new(&sc, &m);
    let law = MohrCoulomb::from_joint(&sc.joints[0]);
    let presc = vec![[0.0; 2]; m.blocks.len()];
    let s0 = [-2.0e6, 0.5e6, 0.3e6];
    let mut committed = Committed::zero(&m);
    committed.stress.iter_mut().for_each(|s| *s = s0);
    let theta: f64 = 1.1;
    let (s, c) = theta.sin_cos();
    let expect = [
        c * c * s0[0] - 2.0 * s * c * s0[2] + s * s * s0[1],
        s * s * s0[0] + 2.0 * s * c * s0[2] + c * c * s0[1],
        s * c * (s0[0] - s0[1]) + (c * c - s * s) * s0[2],
    ];
    let t = evaluate(
        &sys,
        &m,
        &committed,
        &law,
        &[],
        1.0,
        &rigid_rotation(&m, theta),
        &presc,
    );
    for st in &t.stress {
        for i in 0..3 {
            assert!(
                (st[i] - expect[i]).abs() < 1e-6 * 2e6,
                "{st:?} vs {expect:?}"
            );
        }
    }
}

#[test]
fn prescribed_displacement_of_a_fixed_block_carries_the_block_on_it() {
    for (kind, d) in [
        ("rigid", [0.02, 0.0]),
        ("deformable", [0.0, 0.005]),
        ("rigid", [0.01, -0.003]),
    ] {
        let text = format!(
            r#"
[[material]]
name = "stone"
lame_lambda = 1e9
lame_mu = 1e9
unit_weight = 2e4
[[joint]]
name = "j"
normal_modulus = 1e9
shear_modulus = 1e8
band = 0.01
friction_angle = 30.0
[[block]]
name = "base"
material = "stone"
support = "fixed"
prescribed = [{}, {}]
vertices = [[0.0, -1.0], [4.0, -1.0], [4.0, 0.0], [0.0, 0.0]]
[[block]]
name = "top"
material = "stone"
kind = "{kind}"
vertices = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]]
[analysis]
load_steps = 4
"#,
            d[0], d[1]
        );
        let sc = common::scene(&text);
        let (m, out) = common::solve(&sc);
        assert_eq!(out.status, dfem::analysis::Status::Stable);
        // the block also settles under its own weight on the elastic joint: remove that part
        let settle = 2e4 * 1.0 * 0.01 / 1e9;
        let (u, rot) = dfem::analysis::outcome_motion(&m, 1, &out);
        // rigid: exact; deformable: within its own elastic deformation under its weight,
        // γ h² / E = 2e-5 m
        let tol = if kind == "rigid" { 1e-9 } else { 2e-5 };
        assert!((u[0] - d[0]).abs() < tol, "{kind}: ux {} vs {}", u[0], d[0]);
        assert!(
            (u[1] - (d[1] - settle)).abs() < tol,
            "{kind}: uy {} vs {}",
            u[1],
            d[1] - settle
        );
        assert!(rot.abs() < tol);
    }
}
