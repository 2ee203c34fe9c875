//! One block on an incline under gravity (Hoek and Bray 1977; seed §4.1, Fig. 3;
//! docs/validation.md V1). With α the slope angle, φ the friction angle, b the breadth (along
//! the slope) and d the height:
//!
//! | mode                 | condition                      |
//! |----------------------|--------------------------------|
//! | stable               | α < φ and b/d > tan α          |
//! | sliding              | α > φ and b/d > tan α          |
//! | toppling             | α < φ and b/d < tan α          |
//! | sliding and toppling | α > φ and b/d < tan α          |
//!
//! Seed properties: λ = 56 GPa, μ = 21 GPa, γ = 25 kN/m³, Eₙ = 50 GPa, Gₛ = 0.5 GPa,
//! φ = 20°, h = 10 mm. The sweep covers α from 2° to 60° and b/d from 0.1 to 2.0 and leaves
//! out the points within 1° (in α) or 2 % (in b/d) of a boundary.

mod common;
use dfem::analysis::Status;
use rayon::prelude::*;

const PHI: f64 = 20.0;

pub fn incline_scene(alpha_deg: f64, b: f64, d: f64, kind: &str) -> String {
    let a = alpha_deg.to_radians();
    let (e, n) = ([a.cos(), a.sin()], [-a.sin(), a.cos()]);
    let s0 = 1.0;
    let l = s0 + b + 1.0;
    let p = |s: f64, h: f64| [s * e[0] + h * n[0], s * e[1] + h * n[1]];
    let box_ = [p(s0, 0.0), p(s0 + b, 0.0), p(s0 + b, d), p(s0, d)];
    let top = p(l, 0.0);
    let v = |q: [f64; 2]| format!("[{:.15e}, {:.15e}]", q[0], q[1]);
    format!(
        r#"
[[material]]
name = "rock"
lame_lambda = 56e9
lame_mu = 21e9
unit_weight = 25e3
[[joint]]
name = "rock-rock"
normal_modulus = 50e9
shear_modulus = 0.5e9
band = 0.010
friction_angle = {PHI}
[[block]]
name = "slope"
material = "rock"
support = "fixed"
vertices = [[0.0, 0.0], {}, {}]
[[block]]
name = "box"
material = "rock"
kind = "{kind}"
vertices = [{}, {}, {}, {}]
[analysis]
type = "static"
load_steps = 4
"#,
        v([top[0], 0.0]),
        v(top),
        v(box_[0]),
        v(box_[1]),
        v(box_[2]),
        v(box_[3])
    )
}

fn expected(alpha: f64, ratio: f64) -> &'static str {
    let slides = alpha > PHI;
    let topples = ratio < alpha.to_radians().tan();
    match (slides, topples) {
        (false, false) => "stable",
        (true, false) => "sliding",
        (false, true) => "toppling",
        (true, true) => "sliding+toppling",
    }
}

fn computed(alpha: f64, ratio: f64, kind: &str) -> String {
    let sc = common::scene(&incline_scene(alpha, ratio, 1.0, kind));
    let (_, out) = common::solve(&sc);
    match out.status {
        Status::Stable => "stable".to_string(),
        Status::Failed { .. } => {
            let m = out.mechanism.expect("a failure names its mechanism");
            let b = m.blocks.iter().find(|b| b.0 == 1).unwrap();
            assert_eq!(m.mode, b.1.as_str());
            m.mode
        }
        Status::NotConverged { reason, .. } => panic!("not converged: {reason}"),
        Status::Interrupted { .. } => unreachable!("a static run is never interrupted"),
    }
}

fn sweep(kind: &str) -> Vec<(f64, f64, &'static str, String)> {
    let mut pts = Vec::new();
    for i in 1..=30 {
        let alpha = 2.0 * i as f64;
        for j in 2..=40 {
            let ratio = 0.05 * j as f64;
            let near_phi = (alpha - PHI).abs() < 1.0;
            let tb = alpha.to_radians().tan();
            let near_topple = (ratio - tb).abs() < 0.02 * tb;
            if !near_phi && !near_topple {
                pts.push((alpha, ratio));
            }
        }
    }
    assert!(pts.len() >= 150);
    pts.par_iter()
        .map(|&(a, r)| (a, r, expected(a, r), computed(a, r, kind)))
        .collect()
}

fn check(kind: &str) {
    let res = sweep(kind);
    // the sweep as a figure (the seed's Fig. 3); DFEM_WRITE_FIGURES=1 also writes it to
    // docs/figures/
    let pts: Vec<dfem::output::plot::ModePoint> = res
        .iter()
        .map(|r| dfem::output::plot::ModePoint {
            alpha: r.0,
            ratio: r.1,
            mode: r.3.clone(),
        })
        .collect();
    let mut dirs = vec![common::tmp_dir(&format!("hoek_bray_{kind}"))];
    if std::env::var_os("DFEM_WRITE_FIGURES").is_some() {
        dirs.push(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures"));
    }
    for dir in dirs {
        for ext in ["svg", "png"] {
            let f = dir.join(format!("hoek_bray_{kind}.{ext}"));
            dfem::output::plot::hoek_bray_chart(&f, PHI, &pts).unwrap();
            assert!(
                std::fs::metadata(&f).unwrap().len() > 10_000,
                "{} is too small",
                f.display()
            );
        }
    }
    let wrong: Vec<_> = res.iter().filter(|r| r.2 != r.3).collect();
    let counts = ["stable", "sliding", "toppling", "sliding+toppling"]
        .map(|m| res.iter().filter(|r| r.2 == m).count());
    eprintln!(
        "{kind}: {} points, expected modes {counts:?}, {} wrong",
        res.len(),
        wrong.len()
    );
    assert!(
        counts.iter().all(|&c| c >= 15),
        "every mode must be sampled: {counts:?}"
    );
    assert!(
        wrong.is_empty(),
        "{} of {} points wrong, e.g. {:?}",
        wrong.len(),
        res.len(),
        &wrong[..wrong.len().min(10)]
    );
}

#[test]
fn hoek_bray_chart_deformable_block() {
    check("deformable");
}

#[test]
fn hoek_bray_chart_rigid_block() {
    check("rigid");
}
