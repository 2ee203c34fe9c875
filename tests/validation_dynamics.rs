//! Implicit dynamics (docs/theory.md §5) against closed forms and an independent integration.
//!
//! * A rigid block released on an incline α > φ slides s(t) = ½ g (sin α − cos α tan φ) t²
//!   (docs/theory.md §5); with α < φ it stays.
//! * A rigid block on a flat base under El Centro 1940 N-S, tan φ = 0.2: the largest
//!   sliding displacement against a rigid-plastic sliding-block integration written
//!   here (two-way sliding, Newmark 1965's model, time step 10⁻⁴ s).
//! * A slender block (b/d = 0.25) under a ground-acceleration ramp starts rocking when the
//!   acceleration passes g b/d (Housner 1963): its heel contact opens within one step.
//! * A free-rocking block loses, at its impact, the angular velocity Housner's
//!   1 − (3/2) sin²α predicts (from the amplitudes on either side, within 5 %).
//! * The seed's arch on piers (§4.3): pseudo-dynamic (`inertia = false`) it fails just
//!   past the collapse load factor of the static capacity driver; with inertia it
//!   collapses and the run goes on.
//! * The energy audit closes to 1 % of the external work in the sliding and rocking runs.
//! * A block put on its base without contact force: Newmark's average acceleration keeps
//!   the contact's chatter, HHT-α damps it.

mod common;
use dfem::analysis::dynamics::History;
use dfem::analysis::Status;

const G: f64 = 9.81;

fn run(text: &str) -> History {
    common::dynamic_history(text)
}

use common::col;

/// Energy balance error relative to the external work (absolute values summed).
fn energy_error(h: &History) -> f64 {
    let e = col(h, "E_error");
    let w: Vec<f64> = col(h, "W_gravity")
        .iter()
        .zip(col(h, "W_ground"))
        .map(|(a, b)| a.abs() + b.abs())
        .collect();
    let wmax = w.iter().fold(0.0f64, |m, x| m.max(*x));
    e.iter().fold(0.0f64, |m, x| m.max(x.abs())) / wmax
}

fn incline(alpha: f64, phi: f64, integrator: &str, kind: &str) -> String {
    common::incline(
        alpha,
        phi,
        kind,
        &format!(
            "[analysis]\ntype = \"dynamic\"\ndt = 0.01\nduration = 1.0\nintegrator = \"{integrator}\"\n[output]\ntrack = [\"block\"]\n"
        ),
    )
}

#[test]
fn block_slides_down_an_incline() {
    let (alpha, phi) = (30.0f64, 20.0f64);
    let (a, p) = (alpha.to_radians(), phi.to_radians());
    let exact = 0.5 * G * (a.sin() - a.cos() * p.tan());
    for (integ, kind) in [
        ("newmark", "rigid"),
        ("hht", "rigid"),
        ("generalized-alpha", "rigid"),
        ("hht", "deformable"),
    ] {
        let h = run(&incline(alpha, phi, integ, kind));
        let (ux, uy) = (col(&h, "block.ux"), col(&h, "block.uy"));
        let t = *col(&h, "t").last().unwrap();
        let s = ux.last().unwrap().hypot(*uy.last().unwrap());
        let err = common::rel_err(s, exact * t * t);
        let eerr = energy_error(&h);
        eprintln!(
            "{integ} {kind}: s(1 s) = {s:.6} m vs {:.6} m closed form, {:.4} %; energy error {:.2e} of the work",
            exact * t * t,
            100.0 * err,
            eerr
        );
        // 0.5 %: the block's elastic settlement (~10⁻⁷ m) and the contact's shear
        // compliance are far below it; a wrong friction force or a lost initial
        // acceleration (an O(dt) error, 1 % here) is not
        assert!(err < 0.005, "{integ} {kind}: {s} vs {}", exact * t * t);
        // the block moves down the slope (towards −x)
        assert!(*ux.last().unwrap() < 0.0);
        // Newmark conserves energy: the audit closes to the iteration tolerance; HHT and
        // generalized-α dissipate only the start-up transient of the stiff contacts
        assert!(eerr < 0.01, "{integ} {kind}: energy error {eerr}");
    }
}

#[test]
fn block_stays_on_an_incline_below_the_friction_angle() {
    let h = run(&incline(20.0, 30.0, "hht", "rigid"));
    let (ux, uy) = (col(&h, "block.ux"), col(&h, "block.uy"));
    let umax = ux
        .iter()
        .zip(&uy)
        .fold(0.0f64, |m, (x, y)| m.max(x.hypot(*y)));
    eprintln!("α < φ: largest displacement {umax:.3e} m");
    // the elastic settlement under the weight is ~10⁻⁸ m; sliding at the rate of the
    // other test would be 0.3 m
    assert!(umax < 1e-6, "{umax}");
    assert!(col(&h, "slipping_contacts").iter().all(|&s| s == 0.0));
}

#[test]
fn block_slides_on_a_base_under_el_centro() {
    // the record, read independently
    let (file, t, a) = common::el_centro_record();
    let duration = 15.0;
    let record = |x: f64| common::interpolate(&t, &a, x);
    // the relative frame, and the ground motion as the foundation's prescribed motion
    // (`frame = "absolute"`, tests/ground_frames.rs) for tan φ = 0.2
    for (mu, frame) in [(0.2f64, "relative"), (0.2, "absolute"), (0.1, "relative")] {
        let text = common::box_on_base(
            mu,
            &format!(
                r#"[analysis]
type = "dynamic"
dt = 0.005
duration = {duration}
integrator = "hht"
ground_motion = {{ file = "{file}", format = "csv", direction = "x" }}
frame = "{frame}"
"#
            ),
        );
        let h = run(&text);
        let ux = col(&h, "box.ux");
        let umax = ux.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        // the ground acceleration column is the record (PGA 0.319 g at t = 2.02 s)
        let ag = col(&h, "ground_ax");
        let tt = col(&h, "t");
        let k = tt.iter().position(|&x| (x - 2.02).abs() < 1e-9).unwrap();
        assert!((ag[k] - a[101]).abs() < 1e-9, "{} vs {}", ag[k], a[101]);
        let reference = common::rigid_plastic_sliding(record, |_| 0.0, mu, duration).0;
        let err = common::rel_err(umax, reference);
        let eerr = energy_error(&h);
        eprintln!(
            "El Centro, tan φ = {mu}, {frame} frame: largest sliding {umax:.5} m vs {reference:.5} m (rigid-plastic integration), {:.3} %; energy error {eerr:.2e} of the work",
            100.0 * err
        );
        // 2 %: the elastic shear of the contact (~μW/kₛ ≈ 10⁻⁸ m) and the O(dt²) error
        // of the slip reversals are well below it; a friction force off by 2 % is not
        assert!(err < 0.02, "{umax} vs {reference}");
        assert!(eerr < 0.01, "energy error {eerr}");
    }
}

#[test]
fn slender_block_starts_rocking_at_g_b_over_d() {
    // b = 0.5 m, d = 2 m: rocking at a_g = g b/d = 0.25 g; ramp a_g = 0.2 g/s · t,
    // so t_c = 1.25 s
    let (b, d, rate) = (0.5, 2.0, 0.2);
    let dt = 0.005;
    let text = format!(
        r#"{}
[[block]]
name = "base"
material = "rock"
support = "fixed"
vertices = [[-1.0, -0.5], [1.5, -0.5], [1.5, 0.0], [-1.0, 0.0]]
[[block]]
name = "pillar"
material = "rock"
kind = "rigid"
vertices = [[0.0, 0.0], [{b}, 0.0], [{b}, {d}], [0.0, {d}]]
[analysis]
type = "dynamic"
dt = {dt}
duration = 1.45
integrator = "generalized-alpha"
rho_inf = 0.5
ground_motion = {{ expression = "{rate}*t", units = "g" }}
"#,
        common::rock_and_joint(40.0)
    );
    let h = run(&text);
    let t = col(&h, "t");
    let open = col(&h, "open_contacts");
    let k = open
        .iter()
        .position(|&o| o >= 1.0)
        .expect("the block must rock");
    let tc = b / d / rate;
    eprintln!(
        "rocking starts at t = {:.4} s (heel contact open), expected {tc:.4} s (a_g = g b/d)",
        t[k]
    );
    // within one time step: the heel opens at the first step whose end is past t_c
    assert!(
        t[k] >= tc - 1e-9 && t[k] <= tc + dt + 1e-9,
        "{} vs {tc}",
        t[k]
    );
    let rz = col(&h, "pillar.rz");
    let th = rz.last().unwrap().abs();
    assert!(th > 1e-4, "the block rocks: θ = {th}");
    let eerr = energy_error(&h);
    eprintln!("rocking: final rotation {th:.3e} rad, energy error {eerr:.2e} of the work");
    assert!(eerr < 0.01, "energy error {eerr}");
}

fn resting_block(integrator: &str) -> Vec<f64> {
    let text = format!(
        r#"{}{}[analysis]
type = "dynamic"
dt = 0.01
duration = 0.5
integrator = "{integrator}"
alpha = 0.1
initial = "rest"
"#,
        common::rock_and_joint(30.0),
        common::box_above_base("rigid", 0.0)
    );
    col(&run(&text), "box.uy")
}

#[test]
fn hht_damps_contact_chatter_newmark_does_not() {
    // static settlement of the box on its two contacts: W / (2 kₙ)
    let w = 25e3 * 1.0;
    let kn = 50e9 * 0.5 / 0.01;
    let settle = w / (2.0 * kn);
    let chatter = |uy: &[f64]| -> f64 {
        // step-to-step oscillation over the last 10 steps, relative to the settlement
        let n = uy.len();
        (n - 10..n)
            .map(|k| (uy[k] - uy[k - 1]).abs())
            .fold(0.0f64, f64::max)
            / settle
    };
    let newmark = chatter(&resting_block("newmark"));
    let hht = chatter(&resting_block("hht"));
    eprintln!("chatter after 0.5 s (step-to-step jump / settlement): Newmark {newmark:.3}, HHT-α (α = 0.1) {hht:.2e}");
    // Newmark's average acceleration has no numerical damping: the contact released
    // without force keeps bouncing at the Nyquist frequency by about its settlement;
    // HHT-α (spectral radius 0.82 at infinite frequency) damps it by 0.82⁵⁰ ≈ 10⁻⁴
    assert!(newmark > 0.5, "{newmark}");
    assert!(hht < 0.01, "{hht}");
}

#[test]
fn at2_record_is_read() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/synthetic.AT2");
    let text = format!(
        r#"{}{}[analysis]
type = "dynamic"
dt = 0.01
duration = 0.1
ground_motion = {{ file = "{file}", scale = 2.0, direction = "y" }}
"#,
        common::rock_and_joint(30.0),
        common::box_above_base("rigid", 0.0)
    );
    let sc = common::scene(&text);
    let gm = &sc.analysis.ground_motion[0];
    // sample 7 (t = 0.07 s) of the file: 0.1 sin(2π 1.5 t) · min(1, k/50), in g
    let t: f64 = 0.07;
    let want = 2.0 * G * 0.1 * (2.0 * std::f64::consts::PI * 1.5 * t).sin() * 7.0 / 50.0;
    assert!(
        (gm.vector(t)[1] - want).abs() < 1e-7,
        "{:?} vs {want}",
        gm.vector(t)
    );
    assert_eq!(gm.vector(t)[0], 0.0);
}

/// The seed's dynamic incline examples (section 4.2, Fig. 4): on a 30° incline a 4 m × 4 m
/// block with φ = 25° slides (Δt = 0.04 s) and a block 4 m along the slope and 12 m high
/// with φ = 35° topples (Δt = 0.01 s), as the kinematic conditions of Hoek and Bray say
/// (docs/validation.md). Seed Table 1 is not legible in the source; the Hoek–Bray properties of
/// docs/validation.md are used. Deformable CST blocks, as in the seed.
#[test]
fn seed_incline_examples_slide_and_topple() {
    let scene = |b: f64, d: f64, phi: f64, dt: f64, duration: f64| {
        format!(
            r#"{}
[[generate]]
type = "incline"
material = "rock"
slope_angle = 30.0
breadth = {b}
height = {d}
slope_length = {}
[analysis]
type = "dynamic"
dt = {dt}
duration = {duration}
"#,
            common::rock_and_joint(phi),
            6.0 * b.max(d)
        )
    };
    // square block: slides with s = ½ g (sin α − cos α tan φ) t², hardly rotates
    let h = run(&scene(4.0, 4.0, 25.0, 0.04, 2.0));
    let (ux, uy, rz) = (
        col(&h, "block.ux"),
        col(&h, "block.uy"),
        col(&h, "block.rz"),
    );
    let s = ux.last().unwrap().hypot(*uy.last().unwrap());
    let (a, p) = (30f64.to_radians(), 25f64.to_radians());
    let exact = 0.5 * G * (a.sin() - a.cos() * p.tan()) * 4.0;
    let th = rz.last().unwrap().abs();
    eprintln!("4 m x 4 m, φ = 25°: slides {s:.4} m in 2 s (closed form {exact:.4} m), rotation {th:.2e} rad");
    assert!(common::rel_err(s, exact) < 0.005, "{s} vs {exact}");
    assert!(th < 1e-3, "{th}");
    // tall block: topples about its downhill toe; its base hardly slides (φ > α)
    let h = run(&scene(4.0, 12.0, 35.0, 0.01, 1.5));
    let rz = col(&h, "block.rz");
    let th = *rz.last().unwrap();
    let (ux, uy) = (col(&h, "block.ux"), col(&h, "block.uy"));
    let u = ux.last().unwrap().hypot(*uy.last().unwrap());
    let open = *col(&h, "open_contacts").last().unwrap();
    eprintln!("4 m x 12 m, φ = 35°: rotation {th:.4} rad after 1.5 s, centroid moved {u:.3} m, {open} open contacts");
    // toppling down the slope (towards −x) is a counter-clockwise rotation: θ > 0,
    // and by 1.5 s it is well under way (a 0.05 rad tilt moves the top by 0.6 m)
    assert!(th > 0.05, "θ = {th}");
    assert!(open >= 1.0);
}

/// A slender block (b/d = 0.25) thrown into rocking by a ground pulse (0.5 g for 0.25 s)
/// lifts its heel, falls back and lands on it, rocking onto the other corner: an open
/// contact must remember its opening (it closes where it lifted off, not at the first
/// downward step). At the impact the angular velocity drops; Housner (1963) gives the
/// ratio 1 − (3/2) sin²α for a rigid plastic impact (α = atan(b/d)). Here the impact is
/// resolved by the penalty contacts and the numerical dissipation of generalized-α
/// (ρ∞ = 0) over a few steps; measured from the rocking amplitudes before and after
/// the impact, within 5 %.
#[test]
fn rocking_block_lands_back_on_its_heel() {
    let h = run(&common::rocking_block(
        0.002,
        "integrator = \"generalized-alpha\"\nrho_inf = 0.0",
    ));
    let r = common::rocking_impact(&h);
    let alpha = 0.25f64.atan();
    assert!(r.p0 > 0.05 && r.p0 < alpha, "peak tilt {}", r.p0);
    assert!(r.landed, "the block must fall back onto its heel");
    // the amplitude after the impact is reached within the run (not cut by its end)
    assert!(
        r.reached,
        "the run ends before the amplitude after the impact"
    );
    eprintln!(
        "rocking: peak {:.4} rad, lands at t = {:.3} s, rocks on to {:.4} rad: θ̇ ratio {:.4} (Housner {:.4}, {:+.1} %)",
        r.p0,
        r.t_land,
        r.p1,
        r.ratio,
        r.housner,
        100.0 * (r.ratio / r.housner - 1.0)
    );
    assert!(r.rocks_on, "it rocks on, onto the other corner");
    // Housner's ratio assumes an instantaneous impact about the new corner; here the
    // penalty band spreads it over a few steps and generalized-α (ρ∞ = 0) damps the
    // contact's stiff modes: 5 % (the issue's tolerance; measured −0.9 % with Δt = 2 ms,
    // −0.7 % before the steps in which a contact lets go were redone without its force;
    // 0.0 % with 0.5 ms; the second impact, −0.1 %)
    assert!(
        (r.ratio / r.housner - 1.0).abs() < 0.05,
        "{} vs {}",
        r.ratio,
        r.housner
    );
}

/// `dfem run` on the built-in dynamic example: history.csv (header: docs/scene-reference.md, "Dynamic results"), frames
/// every `[output] every` steps in results.pvd, summary status "completed", and the same
/// bytes whatever the number of threads.
#[test]
fn cli_dynamic_run_writes_history_and_frames() {
    let mut histories = Vec::new();
    for threads in ["1", "2"] {
        let dir = common::tmp_dir(&format!("dyn_cli_{threads}"));
        let out = std::process::Command::new(common::dfem_bin())
            .args([
                "run",
                "--example",
                "sliding",
                "--quiet",
                "--threads",
                threads,
                "--out",
            ])
            .arg(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let h = std::fs::read_to_string(dir.join("history.csv")).unwrap();
        let header = h.lines().next().unwrap();
        assert!(
            header.starts_with("t,block.ux,block.uy,block.rz,"),
            "{header}"
        );
        // dt = 0.04 s over 2 s: the initial row and 50 steps
        assert_eq!(h.lines().count(), 1 + 51);
        let pvd = std::fs::read_to_string(dir.join("results.pvd")).unwrap();
        // every = 5: steps 0, 5, ..., 50, two parts each
        assert_eq!(pvd.matches("<DataSet").count(), 2 * 11, "{pvd}");
        assert!(dir.join("blocks_0050.vtu").exists());
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(v["status"], "completed");
        assert_eq!(v["analysis"], "dynamic");
        assert_eq!(v["stats"]["symbolic_factorizations"], 1);
        histories.push(h);
    }
    assert_eq!(
        histories[0], histories[1],
        "results depend on the thread count"
    );
}

/// A rigid 1 m box released 0.2 m above a fixed base: no contact exists at the start (the
/// mesh has none); the search for new contacts (docs/theory.md §5) finds the base under the
/// falling corners. The box falls freely (−½ g t²), lands at √(2h/g) within one step,
/// never passes into the base, and comes to rest on its two corner contacts at the
/// static settlement W / (2 kₙ), kₙ = Eₙ (b/2) t / h_band. Generalized-α with ρ∞ = 0
/// makes the impact plastic (no numerical bounce).
#[test]
fn dropped_block_lands_and_settles_on_new_contacts() {
    let (h0, dt) = (0.2, 0.005);
    let text = format!(
        r#"{}{}[analysis]
type = "dynamic"
dt = {dt}
duration = 1.0
integrator = "generalized-alpha"
rho_inf = 0.0
"#,
        common::rock_and_joint(30.0),
        common::box_above_base("rigid", h0)
    );
    let sc = common::scene(&text);
    let (mesh, out) = common::solve(&sc);
    assert!(
        mesh.contacts.is_empty(),
        "the box starts apart from the base"
    );
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let h = out.history.expect("history");
    let (t, uy, el) = (col(&h, "t"), col(&h, "box.uy"), col(&h, "E_elastic"));
    let k = el.iter().position(|&e| e > 0.0).expect("the box must land");
    let t_land = (2.0 * h0 / G).sqrt();
    eprintln!(
        "drop: lands at t = {:.4} s (free fall {t_land:.4} s), lowest uy {:.9} m",
        t[k],
        uy.iter().fold(f64::INFINITY, |m, x| m.min(*x))
    );
    // free fall before the landing: −½ g t², exact for the constant acceleration
    for i in 0..k {
        assert!(
            (uy[i] + 0.5 * G * t[i] * t[i]).abs() < 1e-9,
            "{} {}",
            t[i],
            uy[i]
        );
    }
    // the first step whose end is past the free-fall time carries the contact force
    assert!(
        t[k] >= t_land - 1e-9 && t[k] <= t_land + dt + 1e-9,
        "{}",
        t[k]
    );
    // never into the base: a missed contact would fall on through (0.5 m in 1 s); the
    // band allows at most its elastic compression under the impact (~10⁻⁶ m here)
    let lowest = uy.iter().fold(f64::INFINITY, |m, x| m.min(*x));
    assert!(lowest > -h0 - 1e-4, "{lowest}");
    // at rest at the static settlement: W / (2 kₙ), each corner with half the side
    let w = 25e3 * 1.0;
    let kn = 50e9 * 0.5 / 0.01;
    let settle = w / (2.0 * kn);
    let end = -uy.last().unwrap() - h0;
    eprintln!("drop: final settlement {end:.4e} m vs W/(2 kn) = {settle:.4e} m");
    // 1 %: the contact forces balance the weight to the iteration tolerance (10⁻⁶)
    assert!(common::rel_err(end, settle) < 0.01, "{end} vs {settle}");
    let ke = *col(&h, "E_kinetic").last().unwrap();
    assert!(ke < 1e-9 * w * h0, "still moving: {ke} J");
    // one pattern without contacts, one with the two landing corners: one symbolic
    // factorization each
    assert_eq!(out.stats.contact_topologies, 2);
    assert_eq!(
        out.stats.symbolic_factorizations,
        out.stats.contact_topologies
    );
}

/// A post 0.4 m × 2 m standing with its centre of gravity 5 cm beyond the edge of a
/// fixed 1 m pedestal topples about the pedestal's corner, falls and must land on the
/// ground beside the pedestal (found by the search for new contacts) rather than pass
/// through it: it ends lying on its long side (θ = −π/2, centroid 0.2 m above the
/// ground, wholly beyond the pedestal) and at rest. Its corners never go below the
/// ground by more than the band at any step.
#[test]
fn toppling_post_lands_beside_its_pedestal() {
    let dt = 0.005;
    let text = format!(
        r#"{}
[[block]]
name = "ground"
material = "rock"
support = "fixed"
vertices = [[-1.0, -0.5], [4.0, -0.5], [4.0, 0.0], [-1.0, 0.0]]
[[block]]
name = "pedestal"
material = "rock"
support = "fixed"
vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
[[block]]
name = "post"
material = "rock"
kind = "rigid"
vertices = [[0.85, 1.0], [1.25, 1.0], [1.25, 3.0], [0.85, 3.0]]
[analysis]
type = "dynamic"
dt = {dt}
duration = 3.0
integrator = "generalized-alpha"
rho_inf = 0.0
"#,
        common::rock_and_joint(30.0)
    );
    let sc = common::scene(&text);
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let h = out.history.expect("history");
    let (ux, uy, rz) = (col(&h, "post.ux"), col(&h, "post.uy"), col(&h, "post.rz"));
    let c0 = [1.05, 2.0];
    let corners = [[-0.2, -1.0], [0.2, -1.0], [0.2, 1.0], [-0.2, 1.0]];
    let mut lowest = f64::INFINITY;
    for i in 0..ux.len() {
        let (s, c) = rz[i].sin_cos();
        for p in corners {
            lowest = lowest.min(c0[1] + uy[i] + s * p[0] + c * p[1]);
        }
    }
    let n = ux.len() - 1;
    let (xc, yc) = (c0[0] + ux[n], c0[1] + uy[n]);
    eprintln!(
        "post: ends at θ = {:.5} rad, centroid ({xc:.4}, {yc:.5}) m, lowest corner ever {lowest:.2e} m; {} contact sets",
        rz[n], out.stats.contact_topologies
    );
    // lying on its side: θ = −π/2 and the centroid half the width above the ground
    // (1 mrad and 1 mm: the penalty settlement is ~10⁻⁸ m)
    assert!(
        (rz[n] + std::f64::consts::FRAC_PI_2).abs() < 1e-3,
        "{}",
        rz[n]
    );
    assert!((yc - 0.2).abs() < 1e-3, "{yc}");
    // beside the pedestal (x ≤ 1): its near end, 1 m from the centroid, beyond it
    assert!(xc - 1.0 > 1.0, "{xc}");
    // never through the ground (by more than the 1 cm band)
    assert!(lowest > -0.01, "{lowest}");
    assert!(*col(&h, "E_kinetic").last().unwrap() < 1e-6);
    assert!(out.stats.contact_topologies > 2);
    assert_eq!(
        out.stats.symbolic_factorizations,
        out.stats.contact_topologies
    );
}

/// The seed's arch on piers (its §4.3, Table 2; `examples/seed_arch/`).
fn seed_arch(name: &str) -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(root.join("examples/seed_arch").join(name)).unwrap()
}

/// The seed's Acc. No. 1 (ω = 1 rad/s) and No. 2 (ω = 3 rad/s), in g.
fn seed_acc(t: f64, omega: f64) -> f64 {
    0.8 * t * (-0.5 * t).exp() * (omega * t).sin()
}

/// Pseudo-dynamic (`inertia = false`, seed §4.3): the arch under Acc. No. 1 and No. 2
/// ends as a mechanism once the ground acceleration passes the arch's collapse load
/// factor λ_c, computed independently by the static capacity driver on the same scene
/// (the lateral body force λ W raised until no equilibrium). It cannot fail below λ_c (a
/// balanced state exists, which the Kelvin–Voigt system relaxes to), and the dashpots
/// (relaxation time Eₙ*/Eₙ = 0.1 s) carry part of the load while it rises, so it fails a
/// little above: at the last whole step, measured 1.02 λ_c (Acc. 1, t = 0.6 s) and
/// 1.25 λ_c (Acc. 2, t = 0.4 s, a faster rise); asked within
/// [λ_c, 1.6 λ_c]. Up to then the displacements stay small beside the blocks (below 2 cm,
/// gravity's settlement of the crown, 6.1 mm, included), as the seed's Fig. 6b reports.
#[test]
fn pseudo_dynamic_arch_fails_past_its_static_collapse_load() {
    let text = seed_arch("acc1.toml");
    let cap =
        text.split("[analysis]").next().unwrap().to_string() + "[analysis]\ntype = \"capacity\"\n";
    let (_, out) = common::solve(&common::scene(&cap));
    let lc = out.load_factor.expect("a capacity run gives λ");
    assert!(lc > 0.1 && lc < 0.3, "λ_c = {lc}");
    let mut fail_at = vec![];
    for (file, omega) in [("acc1.toml", 1.0), ("acc2.toml", 3.0)] {
        let (_, out) = common::solve(&common::scene(&seed_arch(file)));
        assert!(
            matches!(out.status, Status::Failed { .. }),
            "{file}: {:?}",
            out.status
        );
        let h = out.history.expect("history");
        let t = *col(&h, "t").last().unwrap();
        let a = seed_acc(t, omega);
        eprintln!(
            "{file}: last converged t = {t:.4} s, a_g = {a:.4} g = {:.3} λ_c (λ_c = {lc:.4})",
            a / lc
        );
        assert!(
            a >= lc && a <= 1.6 * lc,
            "{file}: a_g(t) = {a} g, λ_c = {lc}"
        );
        let umax = out
            .node_disp
            .iter()
            .map(|d| d[0].hypot(d[1]))
            .fold(0.0, f64::max);
        assert!(umax < 0.02, "{file}: |u| = {umax} m");
        fail_at.push(t);
    }
    // Acc. No. 2 rises faster (0.8 t e^(−t/2) sin 3t): it reaches λ_c first
    assert!(fail_at[1] < fail_at[0], "{fail_at:?}");
}

/// With inertia, the seed's arch under Acc. No. 1 and No. 2 (HHT-α, Δt = 0.01 s, 10 s as
/// in the seed's Fig. 6; the examples `examples/seed_arch/acc{1,2}_inertia.toml`, on a
/// 30 m base) runs through its collapse to the end:
/// * the arching action is lost: the crown block falls by more than a metre;
/// * the falling voussoirs and pier blocks land on the base and on each other instead of
///   passing through: no node ends more than two band thicknesses (2 × 5 mm) inside the
///   base, none beyond its ends;
/// * they come to rest: the kinetic energy at 10 s is below 10⁻³ of its peak;
/// * the energy audit never shows energy made (E_error at most 2 % of the work of gravity
///   and the ground motion done so far, at every step: measured ≤ 0.9 % with Δt = 0.005
///   and 0.01 s) and the impacts dissipate less than 30 % of it by the end (measured
///   −9.5 % and −24 %: the HHT-α scheme's loss at impacts resolved by step cuts).
///
/// * the seed's Fig. 6b: the right pier's top moves much more under Acc. No. 1 than under
///   No. 2 in the first seconds (largest |ux| over 0–3 s more than twice; measured 2.04
///   against 0.55 m), though in the first 1.5 s the order is the other way (13 against
///   50 mm at t = 1.5 s).
#[test]
fn arch_with_inertia_collapses_and_lands_under_acc_1_and_2() {
    // the largest sideways motion of the right pier's top block in the first 3 s
    let mut pier_top = Vec::new();
    for file in ["acc1_inertia.toml", "acc2_inertia.toml"] {
        let sc = common::scene(&seed_arch(file));
        let (m, out) = common::solve(&sc);
        assert_eq!(out.status, Status::Stable, "{file}: {:?}", out.status);
        let h = out.history.expect("history");
        let t = col(&h, "t");
        assert!(
            (t.last().unwrap() - 10.0).abs() < 1e-9,
            "{file}: ends at {:?}",
            t.last()
        );
        let last = |c: &str| *col(&h, c).last().unwrap();
        assert!(last("v7.uy") < -1.0, "{file}: crown uy = {}", last("v7.uy"));
        let ux = col(&h, "pier_r_4.ux");
        pier_top.push(
            (0..t.len())
                .filter(|&k| t[k] <= 3.0 + 1e-9)
                .fold(0.0f64, |m, k| m.max(ux[k].abs())),
        );
        let band = 0.005;
        for (b, block) in m.blocks.iter().enumerate() {
            if block.dofs == dfem::mesh::BlockDofs::Fixed {
                continue;
            }
            for n in block.nodes.clone() {
                let (x, u) = (m.nodes[n as usize], out.node_disp[n as usize]);
                let (xe, ye) = (x[0] + u[0], x[1] + u[1]);
                assert!(
                    ye > -2.0 * band && xe.abs() < 15.0,
                    "{file}: block {b} node {n} ends at ({xe}, {ye})"
                );
            }
        }
        let ek = col(&h, "E_kinetic");
        let peak = ek.iter().cloned().fold(0.0, f64::max);
        assert!(
            last("E_kinetic") < 1e-3 * peak,
            "{file}: E_k {} of {peak}",
            last("E_kinetic")
        );
        let (wg, wgr, err) = (
            col(&h, "W_gravity"),
            col(&h, "W_ground"),
            col(&h, "E_error"),
        );
        for k in 0..t.len() {
            let work = wg[k] + wgr[k];
            assert!(
                work < 1e3 || err[k] < 0.02 * work,
                "{file}: at t = {} E_error {} of {work} J",
                t[k],
                err[k]
            );
        }
        let work = last("W_gravity") + last("W_ground");
        assert!(
            last("E_error") > -0.3 * work,
            "{file}: E_error {} of {work} J",
            last("E_error")
        );
    }
    // the seed's Fig. 6b: the side column moves "much more severe[ly] under Acc. No. 1 as
    // compared with Acc. No. 2, especially in the early stage": the long pulse of Acc. No. 1
    // (one-sided for π s) carries the right pier 2.0 m within 3 s, the alternating
    // Acc. No. 2 0.55 m (measured). Before t ≈ 2 s the order is the other way (13 against
    // 50 mm at 1.5 s), as Acc. No. 2's faster rise shakes the piers loose first.
    eprintln!(
        "right pier's top, largest |ux| in 0–3 s: {:.3} m (Acc. No. 1), {:.3} m (Acc. No. 2)",
        pier_top[0], pier_top[1]
    );
    assert!(pier_top[0] > 2.0 * pier_top[1], "{pier_top:?}");
}

/// The error-controlled step (`adaptive_tolerance`): a rigid box set on its base with no
/// contact force (`initial = "rest"`) oscillates on the two contact springs as
/// u(t) = −δ (1 − cos ωt), δ = W/Σkₙ, ω = √(Σkₙ/m) (no damping, the contacts stay
/// closed). With Newmark at Δt = 0.05 s, half the period T = 0.1 s, the fixed step misses
/// the oscillation entirely (at ωΔt = π the trapezoidal rule stretches the period
/// several times: measured error 1.96 δ); with a local error of 10⁻⁸ m per step the
/// steps shrink to about 0.5 ms (1108 steps, ωh ≈ 0.03) and the response follows the
/// closed form to 1 % of δ over five periods (measured 3.2·10⁻⁴ δ).
#[test]
fn adaptive_step_follows_a_contact_oscillation_the_fixed_step_misses() {
    // the rock of the other tests on a joint 5·10⁵ times softer
    let rock = common::rock_and_joint(30.0)
        .replace("normal_modulus = 50e9", "normal_modulus = 1e5")
        .replace("shear_modulus = 5e9", "shear_modulus = 1e5");
    let scene = |adaptive: &str| {
        format!(
            r#"{rock}{}[analysis]
type = "dynamic"
dt = 0.05
duration = 0.5
integrator = "newmark"
initial = "rest"
{adaptive}
"#,
            common::box_above_base("rigid", 0.0)
        )
    };
    // two contacts of 0.5 m each: Σkₙ = Eₙ/h × 1 m × 1 m
    let (w, sum_kn) = (25e3, 1e5 / 0.01);
    let m = w / G;
    let (delta, omega) = (w / sum_kn, (sum_kn / m).sqrt());
    let worst = |adaptive: &str| {
        let sc = common::scene(&scene(adaptive));
        let (_, out) = common::solve(&sc);
        assert_eq!(out.status, Status::Stable, "{:?}", out.status);
        let h = out.history.expect("history");
        let (t, uy) = (col(&h, "t"), col(&h, "box.uy"));
        let err = t
            .iter()
            .zip(&uy)
            .map(|(t, u)| (u + delta * (1.0 - (omega * t).cos())).abs())
            .fold(0.0, f64::max);
        (err / delta, out.stats.increments, out.stats.error_cuts)
    };
    let (fixed, n_fixed, _) = worst("");
    let (adaptive, n_adaptive, cuts) = worst("adaptive_tolerance = 1e-8");
    eprintln!(
        "largest error / δ: fixed Δt {fixed:.3} ({n_fixed} steps), adaptive {adaptive:.2e} \
         ({n_adaptive} steps, {cuts} cut for their error)"
    );
    assert!(fixed > 0.5, "{fixed}");
    assert!(adaptive < 0.01, "{adaptive}");
    assert!(cuts > 0 && n_adaptive > 10 * n_fixed, "{n_adaptive} {cuts}");
}

/// The rocking drums of the `column` example (six deformable marble drums on dry joints,
/// φ = 35°) under a 0.15 g, 5 Hz sine for 0.3 s: its joints open and close, and the
/// contacts on either side of each rocking joint slip, with friction forces that follow
/// their normal forces. The secant iteration alone contracts there by a constant factor
/// (0.79 an iteration over 46 iterations at t = 0.14 s): 3,236 iterations for 74 steps and
/// cuts (44 a step) on f3b80a7. The dynamic driver's tangent steps (docs/theory.md §5, by
/// GMRES on the secant factorization) close such steps in two once the states settle:
/// 1,804 iterations for 67 (27 a step). Its tries that stall at an impact (the
/// out-of-balance force not below half its best for 20 iterations) are given up and
/// the step cut then, not after 100 iterations: 1,519 iterations for 68 (22 a step);
/// with the drums' triangles on the step's start geometry in the iteration matrix, 1,302
/// for 65 (20 a step). The bound of 25 a step fails without the tangent steps and the
/// stall rule; that the tangent is the law's derivative is checked in
/// `analysis::config`'s unit tests. The bound is on the steps of `dt` and their cuts, with
/// the stick–slip events not located (`event_cuts = 0`): located, the steps around them
/// are 84 more and the harder ones, 4,204 iterations for 155 steps (27 a step; 1,370
/// for 71 without,
/// docs/decisions/0036-stick-slip-events.md).
#[test]
fn rocking_drums_converge_with_tangent_steps() {
    let text = dfem::scene::examples::drum_column(
        0.05,
        "[analysis]\ntype = \"dynamic\"\ndt = 0.005\nduration = 0.3\nevent_cuts = 0\n\
         ground_motion = { expression = \"0.15*sin(31.4*t)\", units = \"g\" }\n",
    );
    let sc = common::scene(&text);
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let s = &out.stats;
    let per_step = s.iterations as f64 / s.increments as f64;
    eprintln!(
        "rocking drums: {} iterations for {} steps ({per_step:.1} a step), {} tangent steps by GMRES ({} iterations), {} stalled tries",
        s.iterations, s.increments, s.reused_factorizations, s.reuse_iterations, s.stalled_steps
    );
    assert!(s.reused_factorizations > 0, "no tangent step taken");
    assert!(s.stalled_steps > 0, "no stalled try given up");
    assert!(per_step < 25.0, "{per_step} iterations a step");
    // the drums rock: joints open (the column does not slide off its base)
    let open = col(out.history.as_ref().unwrap(), "open_contacts");
    assert!(open.iter().any(|&n| n > 0.0));
}

/// The built-in `wall` example (dry joints, φ = 36.87°) made rigid, `courses` ×
/// `bricks` bricks, under the first `duration` s of El Centro 1940 N-S (dt = 0.01 s);
/// `joint`: more keys for its joint.
fn rigid_wall_under_el_centro(courses: usize, bricks: usize, duration: f64, joint: &str) -> String {
    let record = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/elcentro1940_NS_g_dt0.02.csv"
    );
    let wall = dfem::scene::examples::get("wall").expect("the wall example");
    let text = wall
        .replace("courses = 10", &format!("courses = {courses}"))
        .replace(
            "bricks_per_course = 5",
            &format!("bricks_per_course = {bricks}\nkind = \"rigid\""),
        )
        .replace("cohesion = 0.0", &format!("cohesion = 0.0\n{joint}"))
        .replace(
            "type = \"static\"",
            &format!(
                "type = \"dynamic\"\ndt = 0.01\nduration = {duration}\n\
                 ground_motion = {{ file = \"{record}\", units = \"g\" }}"
            ),
        );
    assert!(
        text.contains(&format!("bricks_per_course = {bricks}")) && text.contains("ground_motion")
    );
    text
}

/// A rigid running-bond wall of 10 × 10 bricks (the `wall` example's) under the first
/// 0.5 s of El Centro 1940 N-S: in half its steps some joint that carried force opens,
/// and the step is redone from the start's acceleration and internal force without it
/// (`impact_reset`, docs/theory.md §5). The redo differs from the first try only by the
/// released contacts' share of the start, so it starts from the first try's answer: 2.48
/// iterations a redo against 5.42 a first try from rest (measured; a redo from rest costs
/// about what the first try did, 5.46 against 5.16 on the strategies bench's wall). The
/// wall stands: its bricks move by less than a millimetre.
#[test]
fn a_release_redo_starts_from_the_first_try() {
    let text = rigid_wall_under_el_centro(10, 10, 0.5, "");
    let sc = common::scene(&text);
    let (_, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let s = &out.stats;
    let first = (s.iterations - s.release_redo_iterations) as f64 / s.increments as f64;
    let redo = s.release_redo_iterations as f64 / s.release_redos.max(1) as f64;
    eprintln!(
        "{} steps, {} redone; iterations: {first:.2} a first try, {redo:.2} a redo",
        s.increments, s.release_redos
    );
    assert!(s.release_redos >= 10, "{} redos", s.release_redos);
    assert!(
        redo < 0.6 * first,
        "{redo} a redo against {first} a first try"
    );
    // the bricks move by less than a millimetre: the wall stands in its joints
    let umax = common::largest_displacement(&out);
    assert!(umax < 1e-3, "{umax} m");
}

/// The built-in wall made rigid, 15 × 15 bricks, under the first 0.3 s of El Centro
/// 1940 N-S: dry, with dashpots on its joints (Eₙ* = 5·10⁵, Gₛ* = 2.5·10⁵ Pa·s), and with
/// stiffness-proportional Rayleigh damping (a₁ = 0.002 s). Its head joints touch with no
/// force under gravity, and other joints sit at their friction limit. With their damping
/// taken in the trial's states, the force jumped by cₛ δ̇ₛ (or a₁ kₙ δ̇ₙ, a₁ kₛ δ̇ₛ) each time
/// an iteration carried a contact across a kink of its law, and the steps cycled: with
/// dashpots 507 iterations, 3 stalled tries and 25 contacts held open, against 227 dry;
/// with Rayleigh damping the run failed in its first steps (measured). A contact's damping is
/// now taken in its state at the step's start, none where it carried no force there
/// (`DASHPOT_FORCE`, docs/theory.md §5): the damped walls cost about what the dry one does
/// (222 and 212 iterations, measured), and their loaded joints still dissipate.
#[test]
fn damping_of_contacts_at_their_kinks_does_not_stall_the_steps() {
    let solve = |text: String| {
        let (_, out) = common::solve(&common::scene(&text));
        assert_eq!(out.status, Status::Stable, "{:?}", out.status);
        out
    };
    let wall = |joint: &str| rigid_wall_under_el_centro(15, 15, 0.3, joint);
    let dry = solve(wall(""));
    let dashpots = solve(wall("normal_viscosity = 5e5\nshear_viscosity = 2.5e5"));
    // stiffness-proportional Rayleigh damping on the states at the step's start
    let rayleigh =
        solve(wall("").replace("duration = 0.3", "duration = 0.3\nrayleigh = [0.0, 0.002]"));
    let d = &dry.stats;
    for (what, out) in [("dashpots", &dashpots), ("Rayleigh", &rayleigh)] {
        let w = &out.stats;
        eprintln!(
            "iterations: {} dry, {} with {what} ({} stalled tries, {} held open)",
            d.iterations, w.iterations, w.stalled_steps, w.held_open
        );
        assert_eq!(w.stalled_steps, 0, "{what}");
        assert!(
            w.iterations as f64 <= 1.1 * d.iterations as f64,
            "{} iterations with {what} against {} dry",
            w.iterations,
            d.iterations
        );
        // the loaded joints still damp
        let viscous = col(out.history.as_ref().unwrap(), "W_viscous");
        assert!(
            viscous.last().is_some_and(|&x| x > 0.0),
            "{what}: {viscous:?}"
        );
    }
}

/// Stiffness-proportional Rayleigh damping (C = a₁ K) of a rigid box resting on a soft
/// band (Eₙ = 1 MPa, h = 10 mm: two contacts of kₙ = 5·10⁷ N/m under 25 kN), released
/// from rest at first touch (`initial = "rest"`): it oscillates about its settlement
/// W / (2 kₙ) = 0.25 mm at ω = √(2 kₙ / m) = 198 rad/s, and a₁ = 2 ζ / ω damps it at
/// ζ = 0.05: each cycle's amplitude is exp(−2π ζ / √(1 − ζ²)) of the one before (a
/// single-degree-of-freedom oscillator; Newmark's average acceleration adds no damping of
/// its own, and at ω Δt = 0.12 its error in ζ is of order (ω Δt)² / 12 ≈ 0.1 %; measured:
/// ζ = 0.04996). The band never opens after the first touch (the first rebound leaves it
/// compressed by 27 % of the settlement, measured).
#[test]
fn rayleigh_stiffness_damping_of_a_box_on_its_band_has_its_closed_form_ratio() {
    // a soft band of `rock_and_joint`'s thickness; the box's weight (1 m² at 25 kN/m³)
    let (en, band, w) = (1e6, 0.01, 25e3);
    let k = 2.0 * en * 0.5 / band;
    let omega = (k / (w / G)).sqrt();
    let zeta = 0.05;
    // the rock and joint of the other box tests, the band made soft
    let rock = common::rock_and_joint(30.0)
        .replace("normal_modulus = 50e9", &format!("normal_modulus = {en}"))
        .replace("shear_modulus = 5e9", &format!("shear_modulus = {en}"));
    assert!(
        rock.contains(&format!("normal_modulus = {en}")) && rock.contains("unit_weight = 25e3")
    );
    let text = format!(
        r#"[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]
{rock}{}[contacts]
joint = "j"
[analysis]
type = "dynamic"
dt = 0.0006
duration = 0.2
integrator = "newmark"
initial = "rest"
rayleigh = [0.0, {a1}]
"#,
        common::box_above_base("rigid", 0.0),
        a1 = 2.0 * zeta / omega
    );
    let h = run(&text);
    let settle = -w / k;
    let uy: Vec<f64> = col(&h, "box.uy").iter().map(|u| u - settle).collect();
    // the extremes of the oscillation about the settlement
    let peaks: Vec<f64> = (1..uy.len() - 1)
        .filter(|&i| (uy[i] - uy[i - 1]) * (uy[i + 1] - uy[i]) <= 0.0)
        .map(|i| uy[i].abs())
        .collect();
    assert!(peaks.len() >= 10, "{} extremes", peaks.len());
    let ratio = (-2.0 * std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    for p in peaks.windows(3).take(8) {
        let r = p[2] / p[0];
        eprintln!("cycle ratio {r:.5} (closed form {ratio:.5})");
        // 5 % on ζ: exp(-2π ζ) moves by 2π ζ × 5 % = 1.6 % of the ratio
        assert!((r - ratio).abs() < 0.016 * ratio, "{r} against {ratio}");
    }
    let open = col(&h, "open_contacts");
    assert!(open[5..].iter().all(|&n| n == 0.0), "the band opened");
}

/// The largest change (m) of any block's ux or uy in a dynamic run's history from
/// t = 0 to its end, and the largest displacement (m) at t = 0.
fn drift_from_start(h: &History) -> (f64, f64) {
    let (first, last) = (&h.rows[0], h.rows.last().unwrap());
    let mut drift: f64 = 0.0;
    let mut at_start: f64 = 0.0;
    for (k, c) in h.columns.iter().enumerate() {
        if c.ends_with(".ux") || c.ends_with(".uy") {
            drift = drift.max((last[k] - first[k]).abs());
            at_start = at_start.max(first[k].abs());
        }
    }
    (drift, at_start)
}

/// `initial = "equilibrium"` starts a dynamic run from the static equilibrium of gravity
/// under the joints' law, so a structure that stands and is not shaken stays where it
/// is. The `tunnel` example (jointed rock around a circular opening, cohesion 50 kPa,
/// φ = 35°) run for 0.2 s with no ground motion:
/// * from the equilibrium start the blocks move by at most 10⁻⁶ of their settlement at
///   t = 0 (each step converges to the tolerance 10⁻⁶ of the force; measured
///   1.8·10⁻¹² m against 1.8·10⁻⁴ m, 10⁻⁸);
/// * from the default start (`initial = "static"`: the elastic equilibrium with its
///   contact forces returned to the joints' strength) the contacts in tension and past
///   their friction let their forces go at t = 0 and the rock settles dynamically:
///   measured 2.2·10⁻⁴ m in 0.2 s, seven times its displacement at t = 0 (and under
///   1 s of El Centro, 241 stalled tries against the equilibrium start's 1).
#[test]
fn a_standing_structure_starts_from_its_static_equilibrium_and_stays_there() {
    let text = dfem::scene::examples::get("tunnel").unwrap();
    let head = &text[..text.find("[analysis]").unwrap()];
    let run = |initial: &str| {
        let sc = common::scene(&format!(
            "{head}[analysis]\ntype = \"dynamic\"\ndt = 0.01\nduration = 0.2\ninitial = \"{initial}\"\n"
        ));
        common::solve(&sc).1
    };
    let settled = run("equilibrium");
    assert_eq!(settled.status, Status::Stable, "{:?}", settled.status);
    assert!(settled.stats.static_start_iterations > 0);
    let (drift, u0) = drift_from_start(settled.history.as_ref().unwrap());
    let elastic = run("static");
    assert_eq!(elastic.stats.static_start_iterations, 0);
    let (drift_el, u0_el) = drift_from_start(elastic.history.as_ref().unwrap());
    eprintln!(
        "equilibrium start: drift {drift:.3e} m of {u0:.3e} m; elastic start: {drift_el:.3e} m of {u0_el:.3e} m"
    );
    assert!(drift <= 1e-6 * u0, "{drift} m against {u0} m");
    assert!(drift_el > 0.1 * u0_el.max(u0), "{drift_el} m");
}

/// Bonds that cannot hold break within a dynamic step as they do within a static
/// increment (`Dynamics::break_cycling_bonds`, docs/theory.md §5, "Bonds that cannot
/// hold"). The `tunnel` example (cohesion 50 kPa, no tensile strength) from the default
/// start, whose contact forces around the opening let go at t = 0, for 0.2 s with no
/// ground motion: joints at zero normal force cycle between closed, carrying their
/// cohesive shear, and open, carrying nothing (the jump of the brittle bond's law), and
/// the tries stall there. A try that stalls breaks the bonds that changed between
/// closed and open at least three times and goes on, once a try.
/// * bonds break (measured 146), and the tries given up as stalled fall from 210 (when
///   they were all cut, commit 5e0a125) to 43: asserted below 100;
/// * the rock settles as it did when those tries were cut instead: the largest change of
///   a block's displacement over the 0.2 s is 2.23·10⁻⁴ m against 2.21·10⁻⁴ m then,
///   asserted within 10 % (the two paths break different bonds at different times).
#[test]
fn bonds_that_cycle_within_a_dynamic_step_break_instead_of_stalling_it() {
    let text = dfem::scene::examples::get("tunnel").unwrap();
    let head = &text[..text.find("[analysis]").unwrap()];
    let sc = common::scene(&format!(
        "{head}[analysis]\ntype = \"dynamic\"\ndt = 0.01\nduration = 0.2\n"
    ));
    let out = common::solve(&sc).1;
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let (drift, _) = drift_from_start(out.history.as_ref().unwrap());
    eprintln!(
        "bonds broken {}, stalled tries {}, iterations {}, drift {drift:.4e} m",
        out.stats.bonds_broken, out.stats.stalled_steps, out.stats.iterations
    );
    assert!(out.stats.bonds_broken > 0);
    assert!(out.stats.stalled_steps < 100, "{}", out.stats.stalled_steps);
    let cut = 2.2088e-4;
    assert!((drift - cut).abs() < 0.1 * cut, "{drift} m against {cut} m");
}
