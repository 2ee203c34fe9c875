//! Softening joints through the static driver under displacement control
//! (docs/theory.md, "Softening joints"; `[analysis] push_block`): a rigid block on a
//! fixed one, joined by the Eindhoven joint of docs/validation.md V8 (kₙ = 82 N/mm³,
//! kₛ = 36 N/mm³, fₜ = 0.25 N/mm², G_f^I = 0.018 N/mm, c = 0.35 N/mm², tan φ = 0.75,
//! G_f^II = 0.125 N/mm; Lourenço and Rots 1997), in SI units.
//!
//! (a) Pulled apart: the force follows fₜ A exp(−fₜ u_p / G_f^I), u_p the crack opening
//!     (the opening less the elastic part F/(kₙ A)), and the work of the pulling force
//!     is G_f^I A within 1 %, whatever the number of contacts the joint is split into.
//! (b) Sheared under a constant compression σ: the shear force falls from
//!     (c − σ tan φ) A to −σ tan φ A, and the work dissipated by the cohesion (the work
//!     of the shear force less friction × slip and the elastic energy left) is G_f^II A
//!     within 1 %.

mod common;
use dfem::analysis::{Outcome, Status};

const L: f64 = 0.2; // joint length, m
const T: f64 = 0.1; // thickness, m
const AREA: f64 = L * T;
const FT: f64 = 0.25e6;
const GF1: f64 = 18.0; // N/m
const C: f64 = 0.35e6;
const TAN_PHI: f64 = 0.75;
const GF2: f64 = 125.0;
const KN: f64 = 82e9; // N/m³
const BAND: f64 = 0.01;

/// The model, the brick and the Eindhoven mortar joint (TOML), the joint taking the
/// extra lines `joint_keys`.
fn model_and_mortar(joint_keys: &str) -> String {
    format!(
        r#"
[model]
plane = "stress"
thickness = {T}
gravity = [0.0, 0.0]
[[material]]
name = "brick"
lame_lambda = 3.1e9
lame_mu = 7.3e9
unit_weight = 0.0
[[joint]]
name = "mortar"
normal_modulus = {en}
shear_modulus = {es}
band = {BAND}
friction_angle = {phi}
cohesion = {C}
tensile_strength = {FT}
softening = "exponential"
fracture_energy_i = {GF1}
fracture_energy_ii = {GF2}
{joint_keys}"#,
        en = KN * BAND,
        es = 36e9 * BAND,
        phi = TAN_PHI.atan().to_degrees(),
    )
}

fn scene(mesh_size: Option<f64>, load: f64, push: &str, steps: usize) -> String {
    let ms = mesh_size.map_or(String::new(), |m| format!("mesh_size = {m}\n"));
    model_and_mortar("")
        + &format!(
            r#"
[[block]]
name = "base"
material = "brick"
support = "fixed"
vertices = [[0.0, -0.1], [{L}, -0.1], [{L}, 0.0], [0.0, 0.0]]
{ms}
[[block]]
name = "top"
material = "brick"
kind = "rigid"
vertices = [[0.0, 0.0], [{L}, 0.0], [{L}, 0.1], [0.0, 0.1]]
{ms}
[[load]]
block = "top"
force = [0.0, {load}]
[analysis]
type = "static"
load_steps = {steps}
push_block = "top"
push_displacement = {push}
"#
        )
}

/// The push curve: (ux, uy, Fx, Fy) per converged increment (m, N).
fn curve(out: &Outcome) -> Vec<[f64; 4]> {
    let c = out.capacity_curve.as_ref().expect("a push curve");
    c.points
        .iter()
        .map(|p| {
            let r = p.reaction.expect("push points carry the reaction");
            [p.displacement[0], p.displacement[1], r[0], r[1]]
        })
        .collect()
}

/// ∫ F du by the trapezoid rule over (u, F) points.
fn work(pts: impl Iterator<Item = [f64; 2]>) -> f64 {
    let pts: Vec<[f64; 2]> = pts.collect();
    pts.windows(2)
        .map(|w| 0.5 * (w[0][1] + w[1][1]) * (w[1][0] - w[0][0]))
        .sum()
}

/// Independent closed form of the pull test: the stress (Pa) at a total opening u (m),
/// σ = kₙ u up to fₜ, then the root of σ = fₜ exp(−fₜ (u − σ/kₙ)/G_f^I) (a contraction:
/// the iteration's factor fₜ² σ/(G kₙ fₜ) ≤ 0.04).
fn pull_stress(u: f64) -> f64 {
    if u <= FT / KN {
        return KN * u;
    }
    let mut s = FT;
    for _ in 0..100 {
        s = FT * (-FT * (u - s / KN) / GF1).exp();
    }
    s
}

/// Pull the top block up by 1 mm in 400 increments of 2.5 µm: (contacts, work of the
/// pulling force (J), largest deviation of the force from A σ(u) (N)).
fn pull(mesh_size: Option<f64>) -> (usize, f64, f64) {
    let steps = 400;
    let sc = common::scene(&scene(mesh_size, 0.0, "[0.0, 1e-3]", steps));
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let pts = curve(&out);
    assert_eq!(pts.len(), steps + 1);
    let dev = pts
        .iter()
        .map(|p| (p[3] - AREA * pull_stress(p[1])).abs())
        .fold(0.0, f64::max);
    (
        mesh.contacts.len(),
        work(pts.iter().map(|p| [p[1], p[3]])),
        dev,
    )
}

#[test]
fn pulled_joint_follows_the_exponential_and_dissipates_gf1_whatever_the_mesh() {
    let coarse = pull(None);
    let fine = pull(Some(0.02));
    eprintln!("pull: (contacts, work J, force error N) {coarse:?} {fine:?}");
    assert!(
        fine.0 > coarse.0,
        "the finer mesh has more contacts: {fine:?} {coarse:?}"
    );
    let g = GF1 * AREA;
    for (contacts, w, dev) in [coarse, fine] {
        // the return is exact along the path and the increments converge to 1e-6 of the
        // force: 1e-4 of the peak force fₜ A is far above both
        assert!(
            dev < 1e-4 * FT * AREA,
            "{contacts} contacts: force off by {dev} N"
        );
        // trapezoid rule with 2.5 µm steps on a decay length G/fₜ = 72 µm:
        // ~(2.5/72)²/12 = 1e-4; the tail left at 1 mm is exp(−1000/72) ≈ 1e-6
        assert!(
            (w - g).abs() < 0.01 * g,
            "{contacts} contacts: work {w} J against G_f^I A = {g} J"
        );
    }
    // mesh independence: the same energy to 0.1 %
    assert!((coarse.1 - fine.1).abs() < 1e-3 * g, "{coarse:?} {fine:?}");
}

#[test]
fn sheared_joint_softens_to_friction_and_dissipates_gf2() {
    let sigma = -0.30e6; // the lowest Eindhoven pre-compression, Pa
                         // 4 mm in 400 increments of 10 µm: decay length G_f^II/c = 357 µm, trapezoid error
                         // ~(10/357)²/12 = 7e-5; the tail left exp(−4000/357) ≈ 1.4e-5
    let steps = 400;
    let sc = common::scene(&scene(None, sigma * AREA, "4e-3", steps));
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let pts = curve(&out);
    let n = -sigma * AREA;
    let friction = TAN_PHI * n;
    let peak = pts.iter().map(|p| p[2]).fold(0.0, f64::max);
    let end = pts.last().unwrap()[2];
    // (c − σ tan φ) A = 11.5 kN; the peak is reached within a step past the elastic limit
    // (the cohesion falls by exp(−10 µm/357 µm) = 3 % over a step at most)
    let p0 = (C + TAN_PHI * -sigma) * AREA;
    assert!(
        (peak - p0).abs() < 0.03 * p0,
        "peak {peak} N against {p0} N"
    );
    assert!(
        (end - friction).abs() < 1e-3 * friction,
        "end {end} N against {friction} N"
    );
    // the block stays on the joint: its vertical reaction is nil (the compression is a
    // load) and the contacts carry σ A
    let normal: f64 = out.contact_forces.iter().map(|f| f[0]).sum();
    assert!(
        (normal - sigma * AREA).abs() < 1e-4 * n,
        "normal force {normal}"
    );
    // energy balance: the work of the pushing force is the elastic energy left in the
    // joint, H²/(2 kₛ A), plus friction × the slip u − H/(kₛ A), plus what the cohesion
    // dissipated
    let ks = 36e9 * AREA;
    let last = pts.last().unwrap();
    let w = work(pts.iter().map(|p| [p[0], p[2]]))
        - last[2] * last[2] / (2.0 * ks)
        - friction * (last[0] - last[2] / ks);
    let g = GF2 * AREA;
    eprintln!("shear: peak {peak} N, end {end} N, cohesive work {w} J");
    assert!(
        (w - g).abs() < 0.01 * g,
        "work beyond friction {w} J against {g} J"
    );
}

/// (c) Snap-back: a rigid block `a` on the fixed base, joined by the softening joint (area
///     A = 0.2 × 0.1 m², kₙ = 82 N/mm³), and a rigid block `b` on `a`, joined by a soft
///     elastic band (k₂ = 10⁷ Pa / 0.01 m × A = 2·10⁷ N/m; strengths 10⁹ Pa, never
///     reached); `a` is kept from rotating by two fixed guides with frictionless, cohesionless
///     contacts (no vertical force), so the two contacts of the softening joint open
///     alike. `b` is pulled up with its rotation and horizontal motion held. Past the peak
///     F = fₜ A = 5 kN the joint's compliance falls as its softening compliance
///     G_f^I/(fₜ F) grows; the pull's displacement
///
///         u(F) = F (1/(kₙ A) + 1/k₂) + (G_f^I/fₜ) ln(fₜ A / F)        (after the peak)
///
///     is smallest at F = G_f^I k₂' / fₜ ≈ 1.44 kN (k₂' the series stiffness), 0.162 mm,
///     after 0.253 mm at the peak: the path snaps back. Arc length
///     (`path = "arc_length"`) follows it; every converged point lies on u(F), and the
///     displacement falls by a third after the peak. Displacement control jumps from the
///     peak to the far branch: no point of it lies on the falling part.
///
///     `path`: the `[analysis]` path ("displacement", "arc_length" or "dissipation").
fn snap_back_scene(path: &str) -> String {
    model_and_mortar("blocks = [\"base\"]\n")
        + &format!(
            r#"
[[joint]]
name = "guide"
normal_modulus = {en}
shear_modulus = 1.0
band = {BAND}
friction_angle = 0.0
blocks = ["left", "right"]
[[joint]]
name = "spring"
normal_modulus = {SPRING_MODULUS}
shear_modulus = {SPRING_MODULUS}
band = {BAND}
friction_angle = 30.0
cohesion = 1e9
tensile_strength = 1e9
[[block]]
name = "base"
material = "brick"
support = "fixed"
vertices = [[0.0, -0.1], [{L}, -0.1], [{L}, 0.0], [0.0, 0.0]]
[[block]]
name = "left"
material = "brick"
support = "fixed"
vertices = [[-0.1, 0.0], [0.0, 0.0], [0.0, 0.1], [-0.1, 0.1]]
[[block]]
name = "right"
material = "brick"
support = "fixed"
vertices = [[{L}, 0.0], [0.3, 0.0], [0.3, 0.1], [{L}, 0.1]]
[[block]]
name = "a"
material = "brick"
kind = "rigid"
vertices = [[0.0, 0.0], [{L}, 0.0], [{L}, 0.1], [0.0, 0.1]]
[[block]]
name = "b"
material = "brick"
kind = "rigid"
vertices = [[0.0, 0.1], [{L}, 0.1], [{L}, 0.2], [0.0, 0.2]]
[contacts]
joint = "spring"
[analysis]
type = "static"
load_steps = 200
push_block = "b"
push_displacement = [0.0, 1e-3]
path = "{path}"
"#,
            en = KN * BAND,
        )
}

/// Eₙ of the soft band in series with the softening joint (Pa): k₂ = Eₙ A / h.
const SPRING_MODULUS: f64 = 1.0e7;

/// The closed form of (c): the pull's displacement (m) at the force `f` (N), before or
/// after the peak.
fn snap_back_displacement(f: f64, after_peak: bool) -> f64 {
    let k2 = SPRING_MODULUS * AREA / BAND;
    let elastic = f * (1.0 / (KN * AREA) + 1.0 / k2);
    if after_peak {
        elastic + GF1 / FT * (FT * AREA / f).ln()
    } else {
        elastic
    }
}

/// The checks (c) and (d) share on a path `pts` that `path` followed to its end: the peak
/// fₜ A, every converged point on the closed form, the snap-back to the closed form's
/// least displacement, the end of the push. Returns the closed form's least displacement after the
/// peak, the displacement at the peak and the series stiffness k₂' (m, m, N/m).
fn check_snap_back(path: &str, pts: &[[f64; 4]]) -> (f64, f64, f64) {
    let peak = (0..pts.len())
        .max_by(|&i, &j| pts[i][3].total_cmp(&pts[j][3]))
        .unwrap();
    let (u_peak, f_peak) = (pts[peak][1], pts[peak][3]);
    // the peak fₜ A = 5 kN is met within an increment (Δu ≈ 5 µm on the elastic branch:
    // kₛₑᵣᵢₑₛ Δu ≈ 100 N, 2 %)
    assert!(
        (f_peak - FT * AREA).abs() < 0.02 * FT * AREA,
        "{path}: peak {f_peak} N"
    );
    // every converged point on the closed form: the increments converge to 10⁻⁶ of the
    // load, which moves u by at most 10⁻⁶ × 5 kN × the softening compliance
    // G_f^I/(fₜ F) ≤ 7·10⁻⁵/F m/N: < 10⁻⁶ relative at the smallest forces of the path
    let mut worst: f64 = 0.0;
    for (i, p) in pts.iter().enumerate().skip(1) {
        let u = snap_back_displacement(p[3], i > peak);
        worst = worst.max((p[1] - u).abs() / p[1].abs());
    }
    eprintln!(
        "{path}: {} points, peak {f_peak} N at {u_peak} m, worst relative deviation {worst:.2e}",
        pts.len()
    );
    assert!(worst < 1e-5, "{path}: off the closed form by {worst}");
    // it snaps back: after the peak the displacement falls to the closed form's least
    // value, then grows to the end of the push
    let least = pts[peak..]
        .iter()
        .map(|p| p[1])
        .fold(f64::INFINITY, f64::min);
    let k2s = 1.0 / (1.0 / (KN * AREA) + 1.0 / (SPRING_MODULUS * AREA / BAND));
    let f_min = GF1 * k2s / FT;
    let u_min = snap_back_displacement(f_min, true);
    assert!(
        (least - u_min).abs() < 0.01 * u_min,
        "{path}: least displacement {least} m against {u_min} m"
    );
    assert!(least < 0.7 * u_peak, "{least} {u_peak}");
    // the path ends with the increment that passes the end of the push
    let (before, end) = (pts[pts.len() - 2][1], pts[pts.len() - 1][1]);
    assert!(before < 1e-3 && end >= 1e-3, "{path}: ended at {end} m");
    (u_min, u_peak, k2s)
}

#[test]
fn arc_length_follows_the_snap_back_of_a_softening_joint() {
    let sc = common::scene(&snap_back_scene("arc_length"));
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let (u_min, u_peak, k2s) = check_snap_back("arc_length", &curve(&out));
    let f_min = GF1 * k2s / FT;

    // displacement control on the same scene: no point on the falling part of the path
    let sc = common::scene(&snap_back_scene("displacement"));
    let (_, out) = common::solve(&sc);
    let pts = curve(&out);
    let on_snap_back = pts
        .iter()
        .filter(|p| p[1] > u_min * 1.01 && p[1] < u_peak * 0.99 && p[3] > f_min * 1.01)
        .filter(|p| {
            // a point of the falling part: u above the closed form's rising branch
            (p[1] - snap_back_displacement(p[3], true)).abs() < 1e-3 * p[1]
        })
        .count();
    assert_eq!(
        on_snap_back, 0,
        "displacement control followed the snap-back?"
    );
}

/// (d) The snap-back of (c) under the dissipation-based arc length (`path =
///     "dissipation"`; Gutiérrez 2004, Verhoosel et al. 2009; docs/theory.md, Eq. A2):
///     the cylinder up to the peak, then increments that each dissipate the energy Δτ.
///     Every converged point lies on the closed form u(F) as in (c); the displacement
///     falls after the peak to its least value; and the energy balance holds: the work of
///     the pull less the elastic energy left, F²/(2 k₂'), is the energy the joint
///     dissipated, G_f^I A (1 − F/(fₜ A)) at the end force F (the exponential's integral
///     to the opening where the force is F).
#[test]
fn dissipation_arc_length_follows_the_snap_back_and_dissipates_gf1() {
    let sc = common::scene(&snap_back_scene("dissipation"));
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let pts = curve(&out);
    let (_, _, k2s) = check_snap_back("dissipation", &pts);
    // how the pull was followed (summary.json's curve.path): to its end, one increment
    // per point of the curve after the first, some of them on the dissipation (Eq. A2)
    let path = out.capacity_curve.as_ref().unwrap().path.clone().unwrap();
    assert_eq!(path.end, "the end of the push");
    assert!((path.reached - 1.0).abs() < 1e-9, "{path:?}");
    assert_eq!(
        path.increments.iter().sum::<usize>() + 1,
        pts.len(),
        "{path:?}"
    );
    assert!(path.increments[1] > 0, "{path:?}");
    let last = *pts.last().unwrap();
    let w = work(pts.iter().map(|p| [p[1], p[3]])) - last[3] * last[3] / (2.0 * k2s);
    let g = GF1 * AREA * (1.0 - last[3] / (FT * AREA));
    eprintln!("dissipation: dissipated {w} J against {g} J");
    // the trapezoidal rule on a path whose points lie on the closed form: 1 % covers
    // its error over the increments past the peak (the force falls by less than 10 %
    // in most of them)
    assert!((w - g).abs() < 0.01 * g, "dissipated {w} J against {g} J");
}

/// The laws' history in the outcome (`Outcome::contact_history`, written to
/// contacts_NNNN.vtu as `fracture_energy_spent` and `cap_plastic_displacement_m`):
/// (a) pulled open by 50 µm, the joint's spent fraction of G_f^I is ξ = 1 − σ/fₜ at
/// every contact (pure mode I: ds = −s fₜ du_p / G_f^I, σ = s fₜ), with σ the closed
/// form of [`pull_stress`]; (b) pressed down past the cap's first yield with the top
/// block's motion prescribed (the base fixed, so every contact closes by the push δ), the
/// plastic relative displacement on the cap is the root κ₃ of kₙ (δ − κ₃) = σ̄(κ₃), the
/// hardening branch of Eq. C2 written out here: σ̄ = fₘ/3 + (2fₘ/3) √(2x − x²),
/// x = κ₃/κₚ ≤ 1.
#[test]
fn the_outcome_records_each_contacts_spent_energy_and_cap_plastic_displacement() {
    // (a) 50 µm in 20 increments: the opening is well past fₜ/kₙ = 3 µm
    let u = 50e-6;
    let sc = common::scene(&scene(None, 0.0, &format!("[0.0, {u}]"), 20));
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let s = pull_stress(u);
    assert!(s < 0.9 * FT, "still near the peak: {s} Pa");
    for (k, c) in mesh.contacts.iter().enumerate() {
        let xi = out.contact_history[k][0];
        let sigma = out.contact_forces[k][0] / (c.length * T);
        // the increments converge to 1e-6 of the force: 1e-4 of fₜ is far above it
        assert!(
            (xi - (1.0 - sigma / FT)).abs() < 1e-4 && (xi - (1.0 - s / FT)).abs() < 1e-4,
            "contact {k}: ξ = {xi}, σ = {sigma} Pa, closed form {s} Pa"
        );
        assert_eq!(out.contact_history[k][1], 0.0, "no compression, no cap");
    }

    // (b) the Eindhoven cap (fₘ = 10.5 N/mm², C_ss = 9, G_fc = 5 N/mm, κₚ = 0.093 mm)
    let (fm, kp) = (10.5e6, 0.093e-3);
    let cap = format!(
        "compressive_strength = {fm}\ncap_shear_factor = 9.0\ncompressive_fracture_energy = 5000.0\ncap_peak_displacement = {kp}\n"
    );
    let sigma_bar = |k: f64| {
        let x = k / kp;
        fm / 3.0 + 2.0 * fm / 3.0 * (2.0 * x - x * x).sqrt()
    };
    // κ₃ = κₚ/2 at the end: δ = κ₃ + σ̄(κ₃)/kₙ
    let delta = 0.5 * kp + sigma_bar(0.5 * kp) / KN;
    let text = scene(None, 0.0, &format!("[0.0, {}]", -delta), 20).replacen(
        "[[block]]",
        &format!("{cap}\n[[block]]"),
        1,
    );
    let (mesh, out) = common::solve(&common::scene(&text));
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    // the root of kₙ (δ − κ) = σ̄(κ) by bisection on [0, κₚ] (the left side falls, the
    // right rises)
    let (mut lo, mut hi) = (0.0, kp);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if KN * (delta - mid) > sigma_bar(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let kappa = 0.5 * (lo + hi);
    assert!((kappa - 0.5 * kp).abs() < 1e-9 * kp, "{kappa}");
    assert!(!mesh.contacts.is_empty());
    eprintln!(
        "cap: κ₃ {:?} m against {kappa} m",
        out.contact_history.iter().map(|h| h[1]).collect::<Vec<_>>()
    );
    for (k, c) in mesh.contacts.iter().enumerate() {
        let [xi, k3] = out.contact_history[k];
        let sigma = out.contact_forces[k][0] / (c.length * T);
        // the force converges to 1e-6 of itself; dσ̄/dκ at κₚ/2 is 4.3e10 Pa/m, so κ₃
        // is within ~2e-10 m (5e-6 of it): 1e-4 is far above both
        assert!(
            (k3 - kappa).abs() < 1e-4 * kappa,
            "contact {k}: κ₃ = {k3} m, closed form {kappa} m"
        );
        assert!(
            (sigma + sigma_bar(kappa)).abs() < 1e-4 * fm,
            "contact {k}: σ = {sigma} Pa"
        );
        assert!(xi.abs() < 1e-9, "no tension or slip, nothing spent: {xi}");
    }
}

/// (d) Dilatancy (docs/theory.md, Eq. D1): the block pressed by σ₀ = −0.3 MPa, then
///     pushed 0.4 mm sideways in 800 increments with its height and rotation held, the
///     joint dilating with tan ψ₀ = 0.5 up to σᵤ = 2 MPa. On the shear surface the held
///     height takes back the plastic opening, so whatever the cohesion does
///
///         σ(u_p) = −σᵤ + (σ₀ + σᵤ) exp(−kₙ tan ψ₀ u_p / σᵤ),   u_p = u − H/(kₛ A)
///
///     (the plastic slip: the push less the joint's elastic shear). The beam's vertical
///     reaction is the compression built up: σ A = F_y − |σ₀| A. Backward Euler over
///     increments of ≤ 0.5 µm of slip against the decay length σᵤ/(kₙ tan ψ₀) = 49 µm
///     lags by ≤ 0.5/98 of σ + σᵤ ≤ 1.7 MPa, 8.7 kPa: the tolerance is 0.5 % of σᵤ.
///     Without the dilatancy (the same push) the compression stays σ₀.
#[test]
fn a_held_dilating_joint_builds_up_compression_to_the_dilatancy_stress() {
    let (s0, su, tpsi): (f64, f64, f64) = (-0.3e6, 2e6, 0.5);
    let ks = 36e9;
    let mut ends = Vec::new();
    for dilates in [true, false] {
        let keys = if dilates {
            format!(
                "dilatancy_angle = {}\ndilatancy_stress = {su}\n",
                tpsi.atan().to_degrees()
            )
        } else {
            String::new()
        };
        let text = scene(None, s0 * AREA, "[4e-4, 0.0]", 800).replacen(
            "[[block]]",
            &format!("{keys}\n[[block]]"),
            1,
        );
        let (_, out) = common::solve(&common::scene(&text));
        assert_eq!(out.status, Status::Stable, "{:?}", out.status);
        let pts = curve(&out);
        assert_eq!(pts.len(), 801);
        let mut worst = 0.0_f64;
        let mut slipping = 0;
        for p in &pts {
            // the compression carried: the load plus the beam's reaction
            let sigma = s0 + p[3] / AREA;
            let up = p[0] - p[2] / (ks * AREA);
            if up < 1e-9 {
                // elastic: the held height keeps σ₀
                assert!((sigma - s0).abs() < 1e-6 * su, "σ = {sigma} Pa before slip");
                continue;
            }
            slipping += 1;
            let exact = if dilates {
                -su + (s0 + su) * (-KN * tpsi * up / su).exp()
            } else {
                s0
            };
            worst = worst.max((sigma - exact).abs());
        }
        eprintln!("dilatancy {dilates}: {slipping} slipping points, σ off the closed form by ≤ {worst:.1} Pa, end σ {:.0} Pa", s0 + pts[800][3] / AREA);
        assert!(slipping > 700, "{slipping} slipping points");
        assert!(worst < 5e-3 * su, "σ off the closed form by {worst} Pa");
        ends.push(s0 + pts[800][3] / AREA);
    }
    // 0.4 mm of slip is 8 decay lengths: the dilating joint is within 0.1 % of σᵤ
    assert!((ends[0] + su).abs() < 2e-3 * su, "{ends:?}");
    assert!((ends[1] - s0).abs() < 1e-6 * su, "{ends:?}");
}

/// (e) `accept_residual` acts only where an increment would end the path: on the
///     snap-back of (d), whose increments all converge, the option changes nothing —
///     the same points to the last bit, and no increment counted as accepted.
#[test]
fn accept_residual_leaves_a_converging_path_alone() {
    let run = |extra: &str| {
        let text = snap_back_scene("dissipation").replace(
            "path = \"dissipation\"\n",
            &format!("path = \"dissipation\"\n{extra}"),
        );
        let (_, out) = common::solve(&common::scene(&text));
        let path = out.capacity_curve.as_ref().unwrap().path.clone().unwrap();
        (curve(&out), path)
    };
    let (strict, strict_path) = run("");
    let (lenient, path) = run("accept_residual = 1e-3\n");
    assert_eq!(path.end, "the end of the push");
    assert_eq!(
        (path.accepted, path.accepted_residual),
        (0, 0.0),
        "{path:?}"
    );
    assert_eq!(path.increments, strict_path.increments);
    assert_eq!(strict, lenient);
}
