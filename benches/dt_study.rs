//! Time-step study of a dynamic scene (docs/performance.md, "Time-step study"): the
//! scene run at its `dt`, dt/2 and dt/4 (or the divisors of `--halvings N`: dt/2⁰ …
//! dt/2ᴺ), each run's largest displacement of a tracked block (m, the largest over the
//! history of √(u_x² + u_y²)) and its change from the run at the step before, the run's
//! error estimate (`step_error_sum` of summary.json: the sum over the steps of their local
//! error h² (β − 1/6)(a₁ − a₀), docs/theory.md §5), and the run time (the driver's
//! `wall_time_s`, and as a ratio to the first run's).
//!
//!     cargo bench --bench dt_study -- SCENE.toml [--halvings 2]
//!     cargo bench --bench dt_study -- --example seed_arch
//!
//! A change larger than the estimate of the coarser run says that the estimate does not
//! bound the error of that scene at that step. Prints a markdown table on stdout.

use dfem::analysis::{self, Status};
use dfem::scene::{self, AnalysisSettings, Scene};
use std::path::Path;

fn usage(what: &str) -> ! {
    eprintln!(
        "dt_study: {what}\nusage: cargo bench --bench dt_study -- SCENE.toml|--example NAME [--halvings 2]"
    );
    std::process::exit(2)
}

/// The scene with its time step divided by `div`.
fn with_step(sc: &Scene, div: f64) -> Scene {
    let mut s = sc.clone();
    let dt = match &mut s.analysis.settings {
        AnalysisSettings::Dynamic(d) => {
            d.dt /= div;
            d.dt
        }
        AnalysisSettings::Static(_) => usage("the scene's analysis is not dynamic"),
    };
    s.analysis.dt = Some(dt);
    s
}

/// One run: (dt s, largest displacement m, step_error_sum m, wall time s, status).
fn run(sc: &Scene) -> (f64, f64, f64, f64, Status) {
    let mesh = dfem::mesh::build(sc);
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).expect("the default backend");
    let out = analysis::run(sc, &mesh, backend.as_mut()).unwrap_or_else(|e| usage(&e.to_string()));
    let h = out.history.as_ref().expect("a dynamic run has a history");
    let mut umax = 0.0f64;
    for c in 0..h.columns.len() {
        if let Some(name) = h.columns[c].strip_suffix(".ux") {
            let y = h.columns.iter().position(|n| *n == format!("{name}.uy"));
            for r in &h.rows {
                let uy = y.map_or(0.0, |y| r[y]);
                umax = umax.max(r[c].hypot(uy));
            }
        }
    }
    let dt = sc.analysis.settings.dynamics().expect("dynamic").dt;
    (
        dt,
        umax,
        out.stats.step_error_sum,
        out.stats.wall_time_s,
        out.status,
    )
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let value = |name: &str| {
        args.iter().position(|a| a == name).map(|k| {
            args.get(k + 1)
                .cloned()
                .unwrap_or_else(|| usage(&format!("{name} needs a value")))
        })
    };
    let halvings: i32 = value("--halvings").map_or(2, |h| {
        h.parse()
            .unwrap_or_else(|_| usage("--halvings: not an integer"))
    });
    let sc = match value("--example") {
        Some(name) => {
            let text = scene::examples::get(&name)
                .unwrap_or_else(|| usage(&format!("no built-in example '{name}'")));
            scene::parse_str(text, Some(Path::new(&format!("example:{name}"))))
        }
        None => match args
            .iter()
            .find(|a| !a.starts_with("--") && Some(*a) != value("--halvings").as_ref())
        {
            Some(f) => scene::load(Path::new(f)),
            None => usage("no scene given"),
        },
    }
    .unwrap_or_else(|e| usage(&e.to_string()));
    println!("| dt (s) | largest displacement (m) | change from the step before (m) | error estimate (m) | status | run time (s) | time ratio |");
    println!("|---|---|---|---|---|---|---|");
    let mut before: Option<(f64, f64)> = None;
    for k in 0..=halvings {
        let (dt, u, estimate, time, status) = run(&with_step(&sc, 2f64.powi(k)));
        let change = before.map_or("–".into(), |(u0, _)| format!("{:.3e}", u - u0));
        let ratio = before.map_or(1.0, |(_, t0)| time / t0);
        let t0 = before.map_or(time, |(_, t0)| t0);
        let status = match status {
            Status::Stable => "completed".to_string(),
            s => format!("{s:?}"),
        };
        println!("| {dt:.3e} | {u:.6e} | {change} | {estimate:.3e} | {status} | {time:.2} | {ratio:.2} |");
        before = Some((u, t0));
    }
}
