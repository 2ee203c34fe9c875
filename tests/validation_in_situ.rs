//! The in-situ stress (`[in_situ]`, docs/theory.md "In-situ stress"): a static run starts
//! from the rock's stress before the excavation and releases only what the excavation
//! leaves out of balance.
//!
//! * A stack of deformable blocks on a fixed base, its in-situ stress the self-weight's
//!   own (σyy = −γ (H − y), σxx = σxy = 0: in equilibrium with gravity, no traction on
//!   the free sides and top): nothing is out of balance, so nothing moves. Reference: the
//!   settlement of the same stack loaded by gravity from zero stress (closed form of
//!   docs/validation.md V9, checked in tests/validation_stack.rs); the in-situ run must move
//!   less than 10⁻⁹ of it (round-off: the horizontal joints carry a constant traction,
//!   which the node-to-node contacts integrate exactly).
//! * A circular opening of radius a in a glued block mass under a hydrostatic in-situ
//!   stress p, no gravity: the excavation unloads the opening's wall by p, which moves
//!   inward by u = p a / (2μ) in an infinite plane-strain medium (Kirsch; Jaeger, Cook and
//!   Zimmerman, Fundamentals of Rock Mechanics, §8.6). The domain is a 60 m square held
//!   by a fixed frame: a thick cylinder a < r < b with u(b) = 0 moves by
//!   p a/(2μ) (1 − a²/b²)/(1 + (λ + μ) a²/(μ b²)), 0.971 of the infinite medium's
//!   displacement for the inscribed circle (b = 30 m) and 0.985 for the circumscribed one
//!   (b = 42.4 m); the reference is their mean, 0.978, and the mean radial displacement of
//!   the opening's 32 corners must be within 3 % of it (the outer boundary's ±0.7 %,
//!   and the constant-strain triangles' and polygonal opening's discretisation error,
//!   measured at −2.5 %, falling to −1.1 % with finer triangles: the ignored test).
//! * Dynamic runs start from the same state: the stack started at rest stays at rest, and
//!   the excavated tunnel comes to rest, in a damped run, where the static run stands.

mod common;
use dfem::analysis::Status;

/// Five deformable 1 m blocks stacked on a fixed base (top at y = 0), γ = 25 kN/m³;
/// `in_situ`: the `[in_situ]` table, or "".
fn stack(in_situ: &str) -> String {
    let mut s = format!(
        "[model]\nplane = \"strain\"\ngravity = [0.0, -9.81]\n{}\n[contacts]\njoint = \"j\"\n\
         [analysis]\ntype = \"static\"\n\
         [[block]]\nname = \"base\"\nmaterial = \"rock\"\nsupport = \"fixed\"\n\
         vertices = [[-1.0, -1.0], [2.0, -1.0], [2.0, 0.0], [-1.0, 0.0]]\n",
        common::rock_and_joint(30.0)
    );
    for i in 0..5 {
        let (y0, y1) = (i as f64, i as f64 + 1.0);
        s += &format!(
            "[[block]]\nname = \"s{i}\"\nmaterial = \"rock\"\nmesh_size = 0.3\n\
             vertices = [[0.0, {y0}], [1.0, {y0}], [1.0, {y1}], [0.0, {y1}]]\n"
        );
    }
    s + in_situ
}

#[test]
fn a_stack_in_its_own_in_situ_stress_does_not_move() {
    let (_, gravity) = common::solve(&common::scene(&stack("")));
    assert_eq!(gravity.status, Status::Stable);
    let settled = common::largest_displacement(&gravity);
    let (_, in_situ) = common::solve(&common::scene(&stack(
        "[in_situ]\ndatum = 5.0\nstress = [0.0, 0.0, 0.0]\ngradient = [0.0, 25e3, 0.0]\n",
    )));
    assert_eq!(in_situ.status, Status::Stable);
    let moved = common::largest_displacement(&in_situ);
    eprintln!("gravity alone: {settled:.4e} m; from the in-situ stress: {moved:.4e} m");
    assert!(settled > 1e-6, "the stack settles under gravity: {settled}");
    assert!(
        moved < 1e-9 * settled,
        "the stack moved {moved} m (gravity alone: {settled} m)"
    );
    // the stresses are the in-situ ones: σyy = −γ (5 − y) at the bottom block's centroids
    let max_err = in_situ
        .stress
        .iter()
        .map(|s| s[0].abs().max(s[2].abs()))
        .fold(0.0, f64::max);
    assert!(max_err < 1e-6, "σxx, σxy up to {max_err} Pa");
}

/// The opening's mean closure (m) and the thick cylinder's reference (m), the blocks
/// meshed at `mesh_size` (m).
fn opening_closure(mesh_size: f64) -> (f64, f64) {
    let (lambda, mu, p, a) = (10e9, 10e9, 10e6, 3.0);
    let text = format!(
        r#"
[model]
plane = "strain"
gravity = [0.0, 0.0]
[[material]]
name = "rock"
lame_lambda = {lambda}
lame_mu = {mu}
unit_weight = 26e3
[[joint]]
name = "glued"
normal_modulus = 1e12
shear_modulus = 1e12
band = 0.01
friction_angle = 35.0
cohesion = 1e9
tensile_strength = 1e9
[[generate]]
type = "tunnel"
material = "rock"
width = 60.0
height = 60.0
mesh_size = {mesh_size}
joint_sets = [{{ dip = 30.0, spacing = 6.0 }}, {{ dip = 120.0, spacing = 6.0 }}]
opening = {{ shape = "circle", radius = {a}, segments = 32 }}
[contacts]
joint = "glued"
[analysis]
type = "static"
[in_situ]
stress = [{s}, {s}, 0.0]
"#,
        s = -p
    );
    let sc = common::scene(&text);
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable);
    let c = [30.0, 30.0];
    let mut radial = Vec::new();
    for (x, d) in mesh.nodes.iter().zip(&out.node_disp) {
        let r = [x[0] - c[0], x[1] - c[1]];
        let rn = r[0].hypot(r[1]);
        if (rn - a).abs() < 1e-6 {
            radial.push(-(d[0] * r[0] + d[1] * r[1]) / rn);
        }
    }
    assert_eq!(radial.len(), 32, "the opening's corners");
    let mean = radial.iter().sum::<f64>() / radial.len() as f64;
    let infinite = p * a / (2.0 * mu);
    let cyl = |b: f64| {
        let q = a * a / (b * b);
        infinite * (1.0 - q) / (1.0 + (lambda + mu) / mu * q)
    };
    let reference = 0.5 * (cyl(30.0) + cyl(30.0 * 2f64.sqrt()));
    let spread = radial.iter().fold(0.0f64, |m, u| m.max((u - mean).abs())) / mean;
    eprintln!(
        "opening closes by {mean:.5e} m (spread {spread:.2e}); reference {reference:.5e} m \
         (error {:+.2} %), infinite medium {infinite:.5e} m",
        100.0 * (mean / reference - 1.0)
    );
    (mean, reference)
}

#[test]
fn an_opening_under_hydrostatic_in_situ_stress_closes_as_kirsch_says() {
    let (mean, reference) = opening_closure(0.75);
    assert!(
        common::rel_err(mean, reference) < 0.03,
        "closure {mean} m against {reference} m"
    );
}

/// The discretisation error falls with the triangles' size (cargo test --release --test
/// validation_in_situ -- --ignored).
#[test]
#[ignore]
fn the_closure_converges_as_the_blocks_are_meshed_finer() {
    let errors: Vec<f64> = [0.75, 0.375, 0.1875]
        .iter()
        .map(|&h| {
            let (mean, reference) = opening_closure(h);
            (mean / reference - 1.0).abs()
        })
        .collect();
    eprintln!("errors {errors:?}");
    assert!(errors[1] < errors[0] && errors[2] < errors[1], "{errors:?}");
}

#[test]
fn a_stack_in_its_own_in_situ_stress_stays_at_rest_in_a_dynamic_run() {
    let text =
        stack("[in_situ]\ndatum = 5.0\nstress = [0.0, 0.0, 0.0]\ngradient = [0.0, 25e3, 0.0]\n")
            .replace(
                "type = \"static\"",
                "type = \"dynamic\"\ndt = 0.001\nduration = 0.02\ninitial = \"rest\"",
            );
    let (_, out) = common::solve(&common::scene(&text));
    assert_eq!(out.status, Status::Stable);
    let moved = common::largest_displacement(&out);
    eprintln!("from rest in the in-situ stress: {moved:.4e} m");
    // gravity alone settles the stack by 4.7 µm (the first test): 10⁻¹⁵ m is 2·10⁻¹⁰ of
    // it, round-off (measured 8·10⁻²⁰ m)
    assert!(moved < 1e-15, "the stack moved {moved} m");
}

/// The excavation of the 2 m-jointed tunnel (the growth bench's `excavation` kind at its
/// smallest size) run statically and as a damped dynamic run from the in-situ stress
/// (elastic start, then 0.5 s with mass-proportional damping a₀ = 20/s, about 2.5 times
/// the critical damping of the rock mass's first mode): both come to rest at the same
/// state, up to the path dependence of friction. Measured: largest block displacement
/// 0.3133 mm (static, 10 increments) and 0.3130 mm (dynamic), 0.08 % apart; 2 % allowed.
#[test]
fn the_excavated_tunnel_comes_to_rest_where_the_static_run_stands() {
    let text = dfem::scene::examples::get("tunnel").unwrap().to_string()
        + "[in_situ]\ndatum = 20.0\nstress = [-1.3e6, -2.6e6, 0.0]\ngradient = [13e3, 26e3, 0.0]\n";
    let largest = |out: &dfem::analysis::Outcome, mesh: &dfem::mesh::Mesh| {
        (0..mesh.blocks.len())
            .map(|b| {
                let d = dfem::analysis::outcome_motion(mesh, b, out).0;
                d[0].hypot(d[1])
            })
            .fold(0.0, f64::max)
    };
    let (mesh, stat) = common::solve(&common::scene(&text));
    assert_eq!(stat.status, Status::Stable);
    let dyn_text = text.replace(
        "type = \"static\"",
        "type = \"dynamic\"\ndt = 0.005\nduration = 0.5\nrayleigh = [20.0, 0.0]",
    );
    let (_, dynamic) = common::solve(&common::scene(&dyn_text));
    assert_eq!(dynamic.status, Status::Stable);
    let (s, d) = (largest(&stat, &mesh), largest(&dynamic, &mesh));
    eprintln!("largest block displacement: static {s:.5e} m, dynamic {d:.5e} m");
    assert!(s > 1e-4, "the opening closes: {s} m");
    assert!(common::rel_err(d, s) < 0.02, "static {s} m, dynamic {d} m");
}

/// An in-situ stress whose gradient does not balance the rock's weight is read with a
/// warning that names the material and the balancing gradient; one that does, without.
#[test]
fn an_in_situ_stress_out_of_equilibrium_with_gravity_is_warned_about() {
    let with = |g: &str| {
        common::scene(&(stack("") + &format!("[in_situ]\ndatum = 5.0\nstress = [0.0, 0.0, 0.0]\ngradient = [0.0, {g}, 0.0]\n")))
            .warnings
    };
    assert!(with("25e3").is_empty(), "{:?}", with("25e3"));
    let w = with("20e3");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("material 'rock'") && w[0].contains("(25000, 0 Pa/m)"),
        "{w:?}"
    );
}
