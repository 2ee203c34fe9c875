//! Semicircular voussoir arch on fixed springings (docs/validation.md V6; Milankovitch 1907,
//! Heyman; Makris and Alexakis 2013). Rigid voussoirs, radial joints, high friction.
//!
//! The reference is a rigid-block limit analysis (static theorem as a linear program over
//! the joint forces: no tension, thrust inside every joint) written in
//! `tests/reference/arch.rs`, independent of dfem, applied to the very polygons of dfem's
//! arch generator. It reproduces the published t/R = 0.0966 (n = 5), 0.1021 (9), 0.1068
//! (21), 0.1075 (n → ∞) and λ_c = 0.144 / 0.284 / 0.406 / 0.518 for t/R = 0.15 … 0.30
//! (`tests/reference_self_check.rs`).
//!
//! dfem must (a) stand above the minimum thickness of its number of voussoirs and fail
//! with a hinge (toppling) mechanism below it, and (b) find the horizontal capacity within
//! 5 %, from below (elastic joints lose a little capacity).

mod common;
#[path = "reference/mod.rs"]
mod reference;

use dfem::analysis::Status;
use reference::arch::{capacity, stands, JointGeom, LimitOptions, RigidBlock};

/// R: mean radius 1 m; span at the intrados 2 R_i = 2 (R − t/2).
fn scene(t_over_r: f64, n: usize, analysis: &str) -> String {
    let t = t_over_r;
    common::stone_and_dry_joint(50e9, 20e9, 0.001, 60.0)
        + &format!(
            r#"
[[generate]]
type = "arch"
material = "stone"
kind = "rigid"
shape = "semicircular"
span = {}
thickness = {t}
voussoirs = {n}
pier_height = 0.0
[analysis]
type = "{analysis}"
load_steps = 4
"#,
            2.0 - t
        )
}

/// The limit-analysis model of the scene's own polygons: joints are the edges two blocks
/// share (found here by matching vertices, independently of dfem's contact search).
fn reference_model(t_over_r: f64, n: usize) -> (Vec<RigidBlock>, Vec<JointGeom>, Vec<bool>) {
    let sc = common::scene(&scene(t_over_r, n, "static"));
    let blocks: Vec<RigidBlock> = sc
        .blocks
        .iter()
        .map(|b| RigidBlock::new(b.vertices.clone()))
        .collect();
    let fixed: Vec<bool> = sc
        .blocks
        .iter()
        .map(|b| b.support == dfem::scene::Support::Fixed)
        .collect();
    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9;
    let mut joints = Vec::new();
    for i in 0..blocks.len() {
        for j in i + 1..blocks.len() {
            if fixed[i] && fixed[j] {
                continue;
            }
            let shared: Vec<[f64; 2]> = blocks[i]
                .vertices
                .iter()
                .filter(|p| blocks[j].vertices.iter().any(|q| close(**p, *q)))
                .copied()
                .collect();
            if shared.len() == 2 {
                let (a, b) = if fixed[i] { (j, i) } else { (i, j) };
                joints.push(if fixed[b] {
                    JointGeom::to_ground(shared[0], shared[1], a)
                } else {
                    JointGeom::between(shared[0], shared[1], a, b)
                });
            }
        }
    }
    (blocks, joints, fixed)
}

fn reference_min_thickness(n: usize) -> f64 {
    let (mut lo, mut hi) = (0.05, 0.2);
    while hi - lo > 1e-4 {
        let mid = 0.5 * (lo + hi);
        let (b, j, f) = reference_model(mid, n);
        if stands(&b, &j, &f, &LimitOptions::default()) {
            hi = mid
        } else {
            lo = mid
        }
    }
    hi
}

fn dfem_status(t_over_r: f64, n: usize) -> (bool, Option<String>) {
    let sc = common::scene(&scene(t_over_r, n, "static"));
    let (_, out) = common::solve(&sc);
    match out.status {
        Status::Stable => (true, None),
        Status::Failed { .. } => (false, out.mechanism.map(|m| m.mode)),
        Status::NotConverged { reason, .. } => panic!("not converged: {reason}"),
        Status::Interrupted { .. } => unreachable!("a static run is never interrupted"),
    }
}

#[test]
fn stands_above_and_hinges_below_the_minimum_thickness() {
    for n in [5, 9] {
        let tmin = reference_min_thickness(n);
        eprintln!("n = {n}: limit analysis t/R = {tmin:.4}");
        let (up, _) = dfem_status(1.05 * tmin, n);
        assert!(
            up,
            "n = {n}: the arch must stand at t/R = {:.4}",
            1.05 * tmin
        );
        let (up, mode) = dfem_status(0.95 * tmin, n);
        assert!(
            !up,
            "n = {n}: the arch must fail at t/R = {:.4}",
            0.95 * tmin
        );
        assert_eq!(mode.as_deref(), Some("toppling"), "a hinge mechanism");
    }
}

#[test]
fn horizontal_capacity_matches_limit_analysis() {
    for (t_over_r, n) in [(0.2, 15), (0.3, 15)] {
        let (b, j, f) = reference_model(t_over_r, n);
        let reference = capacity(&b, &j, &f);
        let sc = common::scene(&scene(t_over_r, n, "capacity"));
        let (_, out) = common::solve(&sc);
        let lam = out.load_factor.unwrap();
        let err = (lam - reference) / reference;
        eprintln!(
            "t/R = {t_over_r}, n = {n}: dfem λ = {lam:.4}, limit analysis {reference:.4}, {:+.2} %",
            100.0 * err
        );
        assert!(err.abs() < 0.05, "λ = {lam}, reference {reference}");
        assert!(
            lam <= reference * 1.001,
            "elastic joints approach the rigid limit from below"
        );
        assert_eq!(out.mechanism.unwrap().mode, "toppling");
    }
}
