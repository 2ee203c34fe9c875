//! Growth of the run time with the size of the model (issue 6), static secant analyses of
//! three kinds of model, each at sizes of about 10³, 10⁴, 10⁵ and 10⁶ unknowns, on 1 and 2
//! threads:
//!
//! * `rigid`, `deformable`: the built-in running-bond wall (`dfem example wall`) scaled to
//!   n × n bricks, rigid or deformable (corner nodes), under gravity (one increment) and
//!   then a horizontal body force of 0.1 g (below every size's capacity) in 5 increments.
//! * `tunnel`: the built-in tunnel (`dfem example tunnel`: a 20 m × 20 m rock domain in a
//!   fixed frame, a circular opening of radius 3 m at its centre, two joint sets dipping
//!   30° and 120°, deformable corner-node blocks) with the joint spacing s scaled down at
//!   fixed geometry: s = 2 m (the example), 0.55, 0.175 and 0.055 m (the number of blocks
//!   about tenfold from one to the next). The opening, the domain and so the in-situ
//!   stress (gravity over a 20 m column) stay the same; only the rock mass is cut into
//!   finer blocks, the opening's polygon refined with them (its facets keep the example's
//!   0.29 s). Scaling the domain and the opening together at a fixed spacing would instead
//!   raise the stress with the depth of the domain (γh, thirty-fold at 10⁶ unknowns) and
//!   turn the tunnel of radius 3 m into a cavern of radius about 90 m: another problem to
//!   a rock engineer, not a finer one. The analysis is the example's: gravity alone in the
//!   default 10 increments, the opening excavated "wished-in-place" (the rock is loaded by
//!   its weight with the opening already cut; dfem has no staged excavation).
//! * `excavation`: the tunnel's scenes at 100 m depth, starting from the in-situ stress
//!   of the rock mass (`[in_situ]`: σᵥ from the overburden and the rock's weight, σₕ =
//!   σᵥ/2), of which the run releases what the opening leaves out of balance (the
//!   excavation) in the 10 increments of the gravity phase; the key blocks that fall
//!   from the roof drop out (`fallout = true`) and the rest goes on.
//!
//! Each run is a child `dfem run` process (its own peak memory); the table gives the
//! analysis time (`wall_time_s` of summary.json), iterations, numeric factorizations,
//! converged increments, cuts (halvings of a failed increment, `load_cuts`), free motions
//! (summary.json `stats`), peak memory, and for each kind and thread
//! count the exponent p of time ∝ dofs^p fitted by least squares on the logarithms (over
//! every size run, the failed analyses included: their time is the cost of the failure;
//! the fit's row says how many failed). A second table gives `dfem check` on each scene
//! (blocks, contacts, unknowns, and its time).
//!
//!     cargo bench --bench growth -- [--kind rigid|deformable|both|tunnel|excavation|all]
//!         [--min-dofs 0] [--max-dofs 2e5] [--threads 1,2]
//!
//! `both` is the two walls, `all` the four kinds. Sizes whose estimated unknowns lie
//! outside [min-dofs / 1.5, 1.5 max-dofs] are skipped. The results do not depend on the
//! thread count (checked: the block motions of the runs on each thread count are compared
//! to the bit, and the status, message, failure mode and iteration counts alike).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1).cloned())
}

/// Stop the bench with a message (bad command-line input).
fn usage(what: &str) -> ! {
    eprintln!(
        "growth: {what}\nusage: cargo bench --bench growth -- [--kind rigid|deformable|both|tunnel|excavation|all] [--min-dofs 0] [--max-dofs 2e5] [--threads 1,2]"
    );
    std::process::exit(2)
}

/// `text` with `from` replaced by `to`; `from` must occur (else the example changed and the
/// bench would silently run another model).
/// The in-situ stress of the `excavation` kind: the tunnel at 100 m depth below the
/// domain's top (y = 20 m), σᵥ = γ (120 m − y) with the example's γ = 26 kN/m³, and
/// σₕ = σᵥ / 2. The key blocks that the finer joint sets cut from the roof drop out
/// (`fallout`, inserted into `[analysis]`), and the analysis goes on without them.
const EXCAVATION: &str = "
[in_situ]
datum = 20.0
stress = [-1.3e6, -2.6e6, 0.0]
gradient = [13e3, 26e3, 0.0]
";

fn replace(text: &str, from: &str, to: &str) -> String {
    assert!(
        text.contains(from),
        "the built-in example no longer contains '{from}': update benches/growth.rs"
    );
    text.replace(from, to)
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Rigid,
    Deformable,
    Tunnel,
    /// The tunnel's scenes excavated from an in-situ stress (`[in_situ]`).
    Excavation,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Rigid => "rigid",
            Kind::Deformable => "deformable",
            Kind::Tunnel => "tunnel",
            Kind::Excavation => "excavation",
        }
    }

    /// Size parameters giving about 10³, 10⁴, 10⁵, 10⁶ unknowns: bricks per course
    /// (= courses) of the walls, the joint spacing (m) of the tunnel.
    fn sizes(self) -> &'static [f64] {
        match self {
            Kind::Rigid => &[18.0, 58.0, 183.0, 577.0],
            Kind::Deformable => &[10.0, 30.0, 95.0, 300.0],
            Kind::Tunnel | Kind::Excavation => &[2.0, 0.55, 0.175, 0.055],
        }
    }

    fn label(self, size: f64) -> String {
        match self {
            Kind::Tunnel | Kind::Excavation => format!("s = {size} m"),
            _ => format!("{size} × {size}"),
        }
    }

    /// Estimated unknowns: 3 per rigid brick, about 11 per deformable one; 8 per tunnel
    /// block (four corner nodes), of which there are about (400 − 9π) m² / s².
    fn estimated_dofs(self, size: f64) -> f64 {
        match self {
            Kind::Rigid => 3.0 * size * size,
            Kind::Deformable => 11.0 * size * size,
            Kind::Tunnel | Kind::Excavation => {
                8.0 * (400.0 - 9.0 * std::f64::consts::PI) / (size * size)
            }
        }
    }

    fn scene(self, size: f64) -> String {
        let text = match self {
            Kind::Tunnel | Kind::Excavation => {
                // the example's 32 segments at s = 2 m: facets of 0.29 s
                let segments = (32.0 * 2.0 / size).round();
                let t = dfem::scene::examples::get("tunnel").expect("the tunnel example");
                let t = replace(t, "spacing = 2.0", &format!("spacing = {size}"));
                let t = replace(&t, "segments = 32", &format!("segments = {segments}"));
                if self == Kind::Excavation {
                    replace(&t, "type = \"static\"", "type = \"static\"\nfallout = true")
                        + EXCAVATION
                } else {
                    t
                }
            }
            _ => {
                let n = size as usize;
                let rigid = if self == Kind::Rigid {
                    "\nkind = \"rigid\""
                } else {
                    ""
                };
                let t = dfem::scene::examples::get("wall").expect("the wall example");
                let t = replace(t, "courses = 10", &format!("courses = {n}"));
                let t = replace(
                    &t,
                    "bricks_per_course = 5",
                    &format!("bricks_per_course = {n}{rigid}"),
                );
                replace(
                    &t,
                    "type = \"static\"",
                    "type = \"static\"\nlateral = 0.1\nload_steps = 5\ngravity_steps = 1",
                )
            }
        };
        text + "\n[output]\nvtk = false\n"
    }
}

struct Run {
    dofs: f64,
    time: f64,
    iterations: u64,
    factorizations: u64,
    increments: u64,
    cuts: usize,
    free_motions: u64,
    memory_mb: f64,
    status: String,
    /// What must not depend on the thread count: the block motions, the status, message
    /// and failure mode, and the counts of `stats` (all but times and memory). A failed
    /// analysis commits no motion (its blocks stay at zero), so there the check rests on
    /// the failure mode, the message's out-of-balance force and the counts.
    result: serde_json::Value,
}

/// Write the scene of `kind` at `size` into `dir` (once per size: `dfem check` and the
/// runs on every thread count read it).
fn write_scene(dir: &Path, kind: Kind, size: f64) -> PathBuf {
    let file = dir.join(format!("{}_{size}.toml", kind.name()));
    std::fs::write(&file, kind.scene(size)).unwrap();
    file
}

fn run(dir: &Path, file: &Path, kind: Kind, size: f64, threads: usize) -> Run {
    let out = dir.join(format!("{}_{size}_t{threads}", kind.name()));
    let o = Command::new(env!("CARGO_BIN_EXE_dfem"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--threads", &threads.to_string(), "--no-plots", "--quiet"])
        .output()
        .expect("run dfem");
    assert!(
        o.status.success(),
        "{} {size}: {}",
        kind.name(),
        String::from_utf8_lossy(&o.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let st = &s["stats"];
    Run {
        dofs: st["dofs"].as_f64().unwrap(),
        time: st["wall_time_s"].as_f64().unwrap(),
        iterations: st["iterations"].as_u64().unwrap(),
        factorizations: st["factorizations"].as_u64().unwrap(),
        increments: st["increments"].as_u64().unwrap(),
        cuts: st["load_cuts"].as_u64().unwrap() as usize,
        free_motions: st["free_motions"].as_u64().unwrap(),
        memory_mb: st["peak_memory_mb"].as_f64().unwrap_or(f64::NAN),
        status: s["status"].as_str().unwrap_or("?").to_string(),
        result: {
            let mut stats = st.clone();
            if let Some(m) = stats.as_object_mut() {
                for timing in ["wall_time_s", "peak_memory_mb"] {
                    m.remove(timing);
                }
            }
            serde_json::json!([s["blocks"], s["status"], s["message"], s["failure"], stats])
        },
    }
}

/// `dfem check` on the scene: its lines `blocks: N (...)`, `contacts: N`, `dofs: N` and
/// `time: T s` (its own time from reading the scene to the memory estimate), and the
/// child process's wall time (s).
fn check(file: &Path, kind: Kind, size: f64) -> String {
    let t0 = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_dfem"))
        .args(["check", file.to_str().unwrap()])
        .output()
        .expect("run dfem check");
    let wall = t0.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "check {} {size}: {}",
        kind.name(),
        String::from_utf8_lossy(&o.stderr)
    );
    let field = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.split_whitespace().next())
            .unwrap_or("?")
            .to_string()
    };
    format!(
        "| {} | {} | {} | {} | {} | {} | {wall:.2} |",
        kind.name(),
        kind.label(size),
        field("blocks: "),
        field("contacts: "),
        field("dofs: "),
        field("time: ")
    )
}

/// Least-squares slope of ln(time) against ln(dofs).
fn exponent(runs: &[(f64, f64)]) -> f64 {
    let n = runs.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = runs.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn main() {
    let kinds: Vec<Kind> = match arg("--kind").as_deref() {
        None | Some("both") => vec![Kind::Rigid, Kind::Deformable],
        Some("all") => vec![
            Kind::Rigid,
            Kind::Deformable,
            Kind::Tunnel,
            Kind::Excavation,
        ],
        Some("rigid") => vec![Kind::Rigid],
        Some("deformable") => vec![Kind::Deformable],
        Some("tunnel") => vec![Kind::Tunnel],
        Some("excavation") => vec![Kind::Excavation],
        Some(k) => usage(&format!("unknown --kind '{k}'")),
    };
    let number = |name: &str, default: f64| {
        arg(name).map_or(default, |v| {
            v.parse()
                .unwrap_or_else(|_| usage(&format!("{name} '{v}' is not a number")))
        })
    };
    let min_dofs = number("--min-dofs", 0.0);
    let max_dofs = number("--max-dofs", 2e5);
    let threads: Vec<usize> = arg("--threads").map_or(vec![1, 2], |v| {
        v.split(',')
            .map(|t| match t.parse() {
                Ok(n) if n > 0 => n,
                _ => usage(&format!("--threads '{v}': give counts like 1,2")),
            })
            .collect()
    });
    let dir = std::env::temp_dir().join("dfem-growth");
    std::fs::create_dir_all(&dir).unwrap();
    println!(
        "# load average before: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    println!("\n| kind | size | dofs | threads | status | time (s) | iterations | factorizations | increments | cuts | free motions | peak memory (MB) |");
    println!("|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    let mut fits = Vec::new();
    let mut checks = Vec::new();
    for &kind in &kinds {
        let mut per_thread: Vec<Vec<(f64, f64)>> = vec![Vec::new(); threads.len()];
        let mut failed = 0;
        for &size in kind.sizes() {
            let est = kind.estimated_dofs(size);
            if est > 1.5 * max_dofs || 1.5 * est < min_dofs {
                continue;
            }
            let file = write_scene(&dir, kind, size);
            checks.push(check(&file, kind, size));
            let mut first: Option<serde_json::Value> = None;
            for (ti, &t) in threads.iter().enumerate() {
                let r = run(&dir, &file, kind, size, t);
                println!(
                    "| {} | {} | {} | {t} | {} | {:.3} | {} | {} | {} | {} | {} | {:.0} |",
                    kind.name(),
                    kind.label(size),
                    r.dofs,
                    r.status,
                    r.time,
                    r.iterations,
                    r.factorizations,
                    r.increments,
                    r.cuts,
                    r.free_motions,
                    r.memory_mb
                );
                match &first {
                    None => first = Some(r.result.clone()),
                    Some(b) => assert_eq!(b, &r.result, "results depend on the thread count"),
                }
                per_thread[ti].push((r.dofs, r.time));
                failed += usize::from(ti == 0 && r.status == "failed");
            }
        }
        for (ti, &t) in threads.iter().enumerate() {
            if per_thread[ti].len() >= 2 {
                let sizes = per_thread[ti].len();
                fits.push((kind.name(), t, sizes, failed, exponent(&per_thread[ti])));
            }
        }
    }
    println!("\n| kind | threads | sizes | of which failed | time ∝ dofs^p, p |\n|---|---:|---:|---:|---:|");
    for (kind, t, sizes, failed, p) in fits {
        println!("| {kind} | {t} | {sizes} | {failed} | {p:.2} |");
    }
    println!("\n| kind | size | blocks | contacts | dofs | `dfem check` (s) | check process (s) |");
    println!("|---|---|---:|---:|---:|---:|---:|");
    for c in checks {
        println!("{c}");
    }
    println!(
        "\n# load average after: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
