//! A stack of blocks under gravity (docs/validation.md V9): the settlement is the sum over the
//! joints below of (weight above) · h / (Eₙ · area), plus the blocks' own elastic
//! shortening under σ_yy(z) = −γ (H_total − z) with σ_xx = 0 (free sides), plane strain:
//! ε_yy = σ_yy (1 − ν²)/E. The centroid displacement of block k is the area average of
//! v(z) over the block, compared within 0.5 %.
//!
//! Shear springs are soft (Gₛ = Eₙ/10⁴) so that the joints barely restrain the Poisson
//! expansion that the closed form leaves free (with Gₛ = Eₙ/100 the restraint alone
//! stiffens the bottom block by 0.8 %; with Eₙ/10⁴ the largest error is 0.15 %, the rest
//! being the CST's linear interpolation of a quadratic displacement).

mod common;
use dfem::analysis::Status;
use dfem::material::young_poisson;

const N: usize = 5;
const B: f64 = 1.0; // width, m
const HB: f64 = 0.5; // block height, m
const GAMMA: f64 = 25e3; // N/m³
const EN: f64 = 5e9;
const BAND: f64 = 0.01;
const LAMBDA: f64 = 2e9;
const MU: f64 = 3e9;

fn scene(kind: &str) -> String {
    let mut s = format!(
        r#"
[[material]]
name = "stone"
lame_lambda = {LAMBDA}
lame_mu = {MU}
unit_weight = {GAMMA}
[[joint]]
name = "bed"
normal_modulus = {EN}
shear_modulus = {}
band = {BAND}
friction_angle = 30.0
[[block]]
name = "ground"
material = "stone"
support = "fixed"
vertices = [[-1.0, -1.0], [2.0, -1.0], [2.0, 0.0], [-1.0, 0.0]]
"#,
        EN / 1.0e4
    );
    for k in 0..N {
        let (y0, y1) = (k as f64 * HB, (k + 1) as f64 * HB);
        s += &format!(
            "[[block]]\nname = \"s{k}\"\nmaterial = \"stone\"\nkind = \"{kind}\"\nvertices = [[0.0, {y0}], [{B}, {y0}], [{B}, {y1}], [0.0, {y1}]]\n"
        );
        if kind == "deformable" {
            s += "mesh_size = 0.1\n";
        }
    }
    s
}

/// Closed-form centroid settlement (m, positive down) of block k.
fn settlement(k: usize, rigid: bool) -> f64 {
    let (e, nu) = young_poisson(LAMBDA, MU);
    let e_eff = e / (1.0 - nu * nu);
    let htot = N as f64 * HB;
    let w = GAMMA * B; // weight per unit height, N/m
                       // joints 0..=k (joint j lies under block j and carries the blocks j..N)
    let joints: f64 = (0..=k)
        .map(|j| (N - j) as f64 * HB * w * BAND / (EN * B))
        .sum();
    if rigid {
        return joints;
    }
    // continuous shortening ∫₀^z γ(H_total − ζ)/E' dζ, averaged over the block
    let z0 = k as f64 * HB;
    let avg = |z: f64| htot * z - z * z / 2.0;
    let zm = z0 + HB / 2.0;
    let mean = htot * zm - (z0 * z0 + z0 * HB + HB * HB / 3.0) / 2.0;
    let _ = avg;
    joints + GAMMA / e_eff * mean
}

fn check(kind: &str, tol: f64) -> dfem::analysis::Outcome {
    check_with(kind, "", tol)
}

/// [`check`] with `analysis` (an `[analysis]` table) appended to the scene.
fn check_with(kind: &str, analysis: &str, tol: f64) -> dfem::analysis::Outcome {
    let sc = common::scene(&(scene(kind) + analysis));
    let (m, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable);
    for k in 0..N {
        let (d, _) = dfem::analysis::outcome_motion(&m, k + 1, &out);
        let exact = settlement(k, kind == "rigid");
        let err = common::rel_err(-d[1], exact);
        eprintln!(
            "{kind} block {k}: settlement {:.6e} m, closed form {exact:.6e} m, error {:.4} %",
            -d[1],
            100.0 * err
        );
        assert!(err < tol, "block {k}: error {err}");
    }
    out
}

#[test]
fn deformable_stack_settles_as_closed_form() {
    check("deformable", 0.005);
}

#[test]
fn rigid_stack_settles_as_joint_springs() {
    // rigid blocks: only the joints deform, exactly
    let out = check("rigid", 1e-9);
    assert_eq!(out.stats.increments, 10, "load_steps' default");
}

#[test]
fn gravity_in_one_increment_settles_the_same() {
    // `gravity_steps`: the same closed form reached in one increment (a stack that stands
    // under gravity is linear)
    let out = check_with("rigid", "[analysis]\ngravity_steps = 1\n", 1e-9);
    assert_eq!(out.stats.increments, 1);
    let out = check_with("deformable", "[analysis]\ngravity_steps = 1\n", 0.005);
    assert_eq!(out.stats.increments, 1);
}

/// MUMPS and PETSc (cargo features) give faer's displacements on both stacks.
#[cfg(any(feature = "mumps", feature = "petsc"))]
#[test]
fn ffi_backends_match_faer_on_the_stacks() {
    common::assert_ffi_backends_match_faer(&common::scene(&scene("deformable")), "");
    common::assert_ffi_backends_match_faer(&common::scene(&scene("rigid")), "");
}
