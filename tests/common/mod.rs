//! Helpers shared by the integration tests.
#![allow(dead_code)]

use dfem::analysis::{self, Outcome};
use dfem::mesh::{self, Mesh};
use dfem::scene::{self, Scene};
use std::path::PathBuf;

pub fn scene(text: &str) -> Scene {
    scene::parse_str(text, None).unwrap_or_else(|e| panic!("scene does not parse: {e}"))
}

pub fn solve(sc: &Scene) -> (Mesh, Outcome) {
    let m = mesh::build(sc);
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).unwrap();
    let out = analysis::run(sc, &m, backend.as_mut()).unwrap();
    (m, out)
}

/// The `dfem` binary built by cargo for the integration tests.
pub fn dfem_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_dfem"))
}

/// Run the `dfem` binary with `args`; panics with its stderr unless it succeeds. Returns
/// its output.
pub fn dfem_ok(args: &[&str]) -> std::process::Output {
    let out = std::process::Command::new(dfem_bin())
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "dfem {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A fresh empty directory under the target directory.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// TOML of the rock (λ = 56 GPa, μ = 21 GPa, γ = 25 kN/m³) and the dry joint "j"
/// (Eₙ = 50 GPa, Gₛ = 5 GPa, band 1 cm, friction angle `phi` in degrees, no cohesion) of
/// the dynamic tests.
pub fn rock_and_joint(phi: f64) -> String {
    format!(
        r#"
[[material]]
name = "rock"
lame_lambda = 56e9
lame_mu = 21e9
unit_weight = 25e3
[[joint]]
name = "j"
normal_modulus = 50e9
shear_modulus = 5e9
band = 0.01
friction_angle = {phi}
"#
    )
}

/// A 1 m × 1 m rock block (`kind`) on an incline α (degrees) with joint friction φ
/// (degrees), then `analysis` (the `[analysis]` table and anything after it).
pub fn incline(alpha: f64, phi: f64, kind: &str, analysis: &str) -> String {
    format!(
        r#"{}
[[generate]]
type = "incline"
material = "rock"
kind = "{kind}"
slope_angle = {alpha}
breadth = 1.0
height = 1.0
slope_length = 12.0
{analysis}"#,
        rock_and_joint(phi)
    )
}

/// Blocks "base" (fixed, 3 m × 0.5 m, top at y = 0) and "box" (1 m × 1 m rock, `kind`,
/// its bottom `h0` (m) above the base).
pub fn box_above_base(kind: &str, h0: f64) -> String {
    let h1 = h0 + 1.0;
    on_fixed_base(
        [[-1.0, -0.5], [2.0, -0.5], [2.0, 0.0], [-1.0, 0.0]],
        "box",
        kind,
        [[0.0, h0], [1.0, h0], [1.0, h1], [0.0, h1]],
    )
}

/// The `[[block]]` tables of a fixed block "base" with the vertices `base` (m) and a rock
/// block `name` of `kind` with the vertices `block` (m): the test scenes of one block on a
/// foundation.
pub fn on_fixed_base(base: [[f64; 2]; 4], name: &str, kind: &str, block: [[f64; 2]; 4]) -> String {
    format!(
        r#"
[[block]]
name = "base"
material = "rock"
support = "fixed"
vertices = {base:?}
[[block]]
name = "{name}"
material = "rock"
kind = "{kind}"
vertices = {block:?}
"#
    )
}

/// The column `name` of a dynamic run's history.
pub fn col(h: &dfem::analysis::dynamics::History, name: &str) -> Vec<f64> {
    let k = h
        .columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", h.columns));
    h.rows.iter().map(|r| r[k]).collect()
}

pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// TOML of a stone (λ = μ = 5 GPa, γ = 20 kN/m³) and a dry joint "dry" with normal and
/// shear moduli `en`, `gs` (Pa), band thickness `band` (m) and friction angle `phi`
/// (degrees), no cohesion: the material pair of the tilting, arch and stress tests.
pub fn stone_and_dry_joint(en: f64, gs: f64, band: f64, phi: f64) -> String {
    format!(
        r#"
[[material]]
name = "stone"
lame_lambda = 5e9
lame_mu = 5e9
unit_weight = 20e3
[[joint]]
name = "dry"
normal_modulus = {en:e}
shear_modulus = {gs:e}
band = {band:e}
friction_angle = {phi}
"#
    )
}

/// Solve a scene with the backend `name` (its near-null space set to the blocks' rigid-body
/// modes, as `dfem run` does).
pub fn solve_with(sc: &Scene, name: &str) -> (Mesh, Outcome) {
    solve_with_options(sc, name, "")
}

/// [`solve_with`] with PETSc options (`--petsc-options`).
pub fn solve_with_options(sc: &Scene, name: &str, petsc_options: &str) -> (Mesh, Outcome) {
    let m = mesh::build(sc);
    let opts = dfem::solve::BackendOptions {
        petsc_options: petsc_options.to_string(),
        ..Default::default()
    };
    let mut backend =
        dfem::solve::backend_with(name, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    dfem::solve::configure(backend.as_mut(), &m).unwrap();
    let out = analysis::run(sc, &m, backend.as_mut()).unwrap_or_else(|e| panic!("{name}: {e}"));
    (m, out)
}

/// Every backend of dfem-ffi compiled in (MUMPS, PETSc) gives the unknowns of faer's
/// Cholesky to `1e-8` relative (max norm over the max of faer's), with the same status.
/// 1e-8: the direct solvers differ by round-off times the condition number (the stiff
/// joints of the validation scenes make it ~1e6–1e8 in the worst case), PETSc's CG stops at
/// a relative residual of 1e-12 (its default here); the out-of-balance tolerance of the
/// secant iterations (1e-8 and below) bounds what can differ after them. `petsc_options`
/// go to the PETSc backend (empty: its default CG + GAMG).
pub fn assert_ffi_backends_match_faer(sc: &Scene, petsc_options: &str) {
    let (_, reference) = solve(sc);
    let umax = reference.u.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(umax > 0.0);
    for name in dfem_ffi::BACKENDS {
        let (_, out) = solve_with_options(sc, name, petsc_options);
        assert_eq!(out.status, reference.status, "{name}");
        let err = out
            .u
            .iter()
            .zip(&reference.u)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{name}: max |u - u_faer| / max |u_faer| = {:.2e}",
            err / umax
        );
        assert!(
            err <= 1e-8 * umax,
            "{name}: relative difference {:e}",
            err / umax
        );
    }
}

/// El Centro 1940 N-S (tests/data, in g at 0.02 s), read independently of dfem's parser:
/// its file, times (s) and accelerations (m/s²).
#[allow(dead_code)]
pub fn el_centro_record() -> (&'static str, Vec<f64>, Vec<f64>) {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/elcentro1940_NS_g_dt0.02.csv"
    );
    let csv = std::fs::read_to_string(file).unwrap();
    let (mut t, mut a) = (vec![], vec![]);
    for l in csv.lines().skip(1) {
        let mut it = l.split(',');
        t.push(it.next().unwrap().parse::<f64>().unwrap());
        a.push(it.next().unwrap().parse::<f64>().unwrap() * 9.81);
    }
    (file, t, a)
}

/// The record (t_i, a_i) linearly interpolated at x, zero after its end.
pub fn interpolate(t: &[f64], a: &[f64], x: f64) -> f64 {
    if x >= t[t.len() - 1] {
        return 0.0;
    }
    let k = t.partition_point(|&s| s <= x).clamp(1, t.len() - 1);
    let w = (x - t[k - 1]) / (t[k] - t[k - 1]);
    a[k - 1] + w * (a[k] - a[k - 1])
}

/// Rigid-plastic sliding block on a moving base (two-way, Coulomb μ; Newmark 1965's
/// model) under the ground accelerations `ax(t)` and `ay(t)` (m/s², y up, gravity 9.81
/// m/s² down): the normal force is m (g + a_y) and the block slides relative to the
/// ground when |a_x| exceeds μ (g + a_y). Explicit integration with a step of 10⁻⁴ s and
/// the exact stick test. Returns the largest |x| and the final x (m) of the block
/// relative to the ground.
pub fn rigid_plastic_sliding(
    ax: impl Fn(f64) -> f64,
    ay: impl Fn(f64) -> f64,
    mu: f64,
    duration: f64,
) -> (f64, f64) {
    rigid_plastic_sliding_step(ax, ay, mu, duration, 1e-4)
}

/// [`rigid_plastic_sliding`] with a step `dt` (s): the slip converges as O(dt) (the
/// stick and slip events are located to within a step).
pub fn rigid_plastic_sliding_step(
    ax: impl Fn(f64) -> f64,
    ay: impl Fn(f64) -> f64,
    mu: f64,
    duration: f64,
    dt: f64,
) -> (f64, f64) {
    let g = 9.81;
    let (mut x, mut v, mut xmax) = (0.0f64, 0.0f64, 0.0f64);
    let steps = (duration / dt).round() as usize;
    for k in 0..steps {
        let tm = (k as f64 + 0.5) * dt;
        let a = ax(tm);
        let limit = mu * (g + ay(tm));
        // relative frame: inertial force −m a_g; friction μ N against the sliding
        let dv = if v == 0.0 {
            if a.abs() <= limit {
                0.0
            } else {
                (-a - limit * (-a).signum()) * dt
            }
        } else {
            let nv = v + (-a - limit * v.signum()) * dt;
            if nv * v < 0.0 {
                // the block stops within the step
                -v
            } else {
                nv - v
            }
        };
        let v0 = v;
        v += dv;
        x += 0.5 * (v0 + v) * dt;
        xmax = xmax.max(x.abs());
    }
    (xmax, x)
}

/// A rigid 1 m × 0.5 m box on a fixed base 40 m wide (the base moves with the ground in
/// the absolute frame), friction tan φ = `mu`.
pub fn box_on_base(mu: f64, analysis: &str) -> String {
    box_on_base_with(mu, "[output]\ntrack = [\"box\"]\nvtk = false\n", analysis)
}

/// [`box_on_base`] with `output` (the `[output]` table, or nothing) in place of its
/// history-only output.
pub fn box_on_base_with(mu: f64, output: &str, analysis: &str) -> String {
    format!(
        "{}{}{output}\n{analysis}",
        rock_and_joint(mu.atan().to_degrees()),
        on_fixed_base(
            [[-20.0, -1.0], [20.0, -1.0], [20.0, 0.0], [-20.0, 0.0]],
            "box",
            "rigid",
            [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.5]],
        )
    )
}

/// Run a dynamic scene that must complete; its history.
pub fn dynamic_history(text: &str) -> dfem::analysis::dynamics::History {
    let sc = scene(text);
    let (_, out) = solve(&sc);
    assert_eq!(
        out.status,
        dfem::analysis::Status::Stable,
        "{:?}",
        out.status
    );
    out.history.expect("a dynamic run has a history")
}

/// The scene file `dfem run` is given for built-in example `name` in the tests that run
/// every example, written into `dir`: the example itself (`None`: run `--example name`),
/// except the Eindhoven walls (`eindhoven*`, 12–35 minutes each along their whole 4 mm
/// push), whose push is shortened to its first 0.4 mm in 4 increments, still by their
/// dissipation-based arc length: their whole paths are the ignored sweeps of
/// tests/validation_eindhoven.rs (docs/performance.md).
#[allow(dead_code)]
pub fn example_scene(name: &str, text: &str, dir: &std::path::Path) -> Option<PathBuf> {
    if !name.starts_with("eindhoven") {
        return None;
    }
    let short = text
        .replace(
            "push_displacement = [0.004, 0.0]",
            "push_displacement = [0.0004, 0.0]",
        )
        .replace("load_steps = 80", "load_steps = 4");
    assert_ne!(
        short, text,
        "{name}: the push to shorten is not in the example"
    );
    let file = dir.join("scene.toml");
    std::fs::write(&file, short).unwrap();
    Some(file)
}

/// The largest displacement of a node (m).
pub fn largest_displacement(out: &Outcome) -> f64 {
    out.node_disp
        .iter()
        .map(|d| d[0].hypot(d[1]))
        .fold(0.0, f64::max)
}

/// A slender rigid block 0.5 m × 2 m (b/d = 0.25) on a fixed base, thrown into rocking by a
/// ground pulse of 0.5 g for 0.25 s, 2.4 s at the step `dt` (s) with the `[analysis]`
/// lines `integrator` (tests/validation_dynamics.rs, `rocking_block_lands_back_on_its_heel`).
pub fn rocking_block(dt: f64, integrator: &str) -> String {
    format!(
        r#"{}{}[analysis]
type = "dynamic"
dt = {dt}
duration = 2.4
{integrator}
ground_motion = {{ expression = "0.5*step(0.25-t)", units = "g" }}
"#,
        rock_and_joint(45.0),
        on_fixed_base(
            [[-1.0, -0.5], [1.5, -0.5], [1.5, 0.0], [-1.0, 0.0]],
            "p",
            "rigid",
            [[0.0, 0.0], [0.5, 0.0], [0.5, 2.0], [0.0, 2.0]],
        )
    )
}

/// The first impact of [`rocking_block`]'s block back on its heel.
pub struct RockingImpact {
    /// The tilt (rad) before the impact and after it.
    pub p0: f64,
    pub p1: f64,
    /// The time of the impact (s), whether it landed, and whether the amplitude after
    /// it is reached within the run.
    pub t_land: f64,
    pub landed: bool,
    pub reached: bool,
    /// Whether it rocks on onto the other corner (the opposite way).
    pub rocks_on: bool,
    /// The ratio of the angular velocities after and before the impact, and Housner's
    /// (1963) 1 − (3/2) sin²α.
    pub ratio: f64,
    pub housner: f64,
}

/// The first impact of a [`rocking_block`] run. The angular velocity at the impact,
/// before and after, from the amplitudes on either side: a rigid rectangle rocking about
/// a corner (I_O = 4/3 m R², R the half-diagonal) keeps ½ I_O θ̇² + m g R cos(α − |θ|)
/// between impacts, so that θ̇² at θ = 0 is (3g/2R)(cos(α − θ_peak) − cos α). (A finite
/// difference of θ a few steps on each side also counts gravity's deceleration of the
/// new rotation over those steps, ≈ p² sin α × 0.01 s ≈ 3 % of θ̇: it measured −7.5 %.)
pub fn rocking_impact(h: &dfem::analysis::dynamics::History) -> RockingImpact {
    let (t, th) = (col(h, "t"), col(h, "p.rz"));
    let alpha = 0.25f64.atan();
    let amplitude = |s: &[f64]| s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    // first return through θ = 0 after the pulse
    let first = (1..th.len()).find(|&k| t[k] > 0.3 && th[k - 1] * th[k] < 0.0);
    let k = first.unwrap_or(th.len() - 1);
    // the next return, or the end of the run
    let k2 = (k + 1..th.len())
        .find(|&j| th[j - 1] * th[j] < 0.0)
        .unwrap_or(th.len());
    let p0 = amplitude(&th[..k]);
    let p1 = amplitude(&th[k..k2]);
    let drop = |p: f64| (alpha - p).cos() - alpha.cos();
    let after = th[k..k2]
        .iter()
        .fold(0.0f64, |m, x| if x.abs() > m.abs() { *x } else { m });
    RockingImpact {
        p0,
        p1,
        t_land: t[k],
        landed: first.is_some(),
        reached: th[k2 - 1].abs() < p1,
        rocks_on: th[k - 1] > 0.0 && after < 0.0,
        ratio: (drop(p1) / drop(p0)).sqrt(),
        housner: 1.0 - 1.5 * alpha.sin().powi(2),
    }
}

/// 0.5 s at dt = 3 ms (167 steps, the last one cut to end at 0.5 s) of a rigid box sliding
/// on a base (tan φ = 0.2) under a sine ground motion of 0.3 g, with `output` (the
/// `[output]` table): the scene of the output tests.
pub fn sliding_box(output: &str) -> String {
    box_on_base_with(
        0.2,
        output,
        r#"[analysis]
type = "dynamic"
dt = 0.003
duration = 0.5
ground_motion = { expression = "0.3*sin(10*t)", units = "g" }
"#,
    )
}
