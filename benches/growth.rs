//! Growth of the run time with the size of the model (issue 6): the built-in running-bond
//! wall (`dfem example wall`) scaled to n × n bricks, rigid or deformable (corner nodes),
//! under gravity (one increment) and then a horizontal body force of 0.1 g (below every
//! size's capacity) in 5 increments, static secant analysis, on 1 and 2 threads. Each run
//! is a child `dfem run` process (its own peak memory); the table gives the analysis time
//! (`wall_time_s` of summary.json), iterations, factorizations, peak memory, and for each
//! kind and thread count the exponent p of time ∝ dofs^p fitted by least squares on the
//! logarithms.
//!
//!     cargo bench --bench growth -- [--kind rigid|deformable|both] [--max-dofs 2e5] [--threads 1,2]
//!
//! The results do not depend on the thread count (checked: the block motions of the 1- and
//! 2-thread runs are compared to the bit).

use std::path::Path;
use std::process::Command;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1).cloned())
}

/// Sizes n (bricks per course = courses) giving about 10³, 10⁴, 10⁵, 10⁶ unknowns.
fn sizes(kind: &str) -> &'static [usize] {
    match kind {
        "rigid" => &[18, 58, 183, 577],
        _ => &[10, 30, 95, 300],
    }
}

fn scene(kind: &str, n: usize) -> String {
    let rigid = if kind == "rigid" {
        "\nkind = \"rigid\""
    } else {
        ""
    };
    dfem::scene::examples::get("wall")
        .expect("the wall example")
        .replace("courses = 10", &format!("courses = {n}"))
        .replace(
            "bricks_per_course = 5",
            &format!("bricks_per_course = {n}{rigid}"),
        )
        .replace(
            "type = \"static\"",
            "type = \"static\"\nlateral = 0.1\nload_steps = 5\ngravity_steps = 1",
        )
        + "\n[output]\nvtk = false\n"
}

struct Run {
    dofs: f64,
    time: f64,
    iterations: u64,
    factorizations: u64,
    memory_mb: f64,
    status: String,
    blocks: serde_json::Value,
}

fn run(dir: &Path, kind: &str, n: usize, threads: usize) -> Run {
    let file = dir.join(format!("{kind}_{n}.toml"));
    std::fs::write(&file, scene(kind, n)).unwrap();
    let out = dir.join(format!("{kind}_{n}_t{threads}"));
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
        "{kind} {n}: {}",
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
        memory_mb: st["peak_memory_mb"].as_f64().unwrap_or(f64::NAN),
        status: s["status"].as_str().unwrap_or("?").to_string(),
        blocks: s["blocks"].clone(),
    }
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
    let kinds: Vec<String> = match arg("--kind").as_deref() {
        None | Some("both") => vec!["rigid".into(), "deformable".into()],
        Some(k) => vec![k.to_string()],
    };
    let max_dofs: f64 = arg("--max-dofs").map_or(2e5, |v| v.parse().expect("--max-dofs"));
    let threads: Vec<usize> = arg("--threads").map_or(vec![1, 2], |v| {
        v.split(',')
            .map(|t| t.parse().expect("--threads"))
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
    println!("\n| kind | n × n | dofs | threads | status | time (s) | iterations | factorizations | peak memory (MB) |");
    println!("|---|---|---:|---:|---|---:|---:|---:|---:|");
    let mut fits = Vec::new();
    for kind in &kinds {
        let mut per_thread: Vec<Vec<(f64, f64)>> = vec![Vec::new(); threads.len()];
        for &n in sizes(kind) {
            // estimated unknowns: 3 per rigid brick, about 11 per deformable one
            let est = (n * n) as f64 * if kind == "rigid" { 3.0 } else { 11.0 };
            if est > 1.5 * max_dofs {
                continue;
            }
            let mut first: Option<serde_json::Value> = None;
            for (ti, &t) in threads.iter().enumerate() {
                let r = run(&dir, kind, n, t);
                println!(
                    "| {kind} | {n} × {n} | {} | {t} | {} | {:.3} | {} | {} | {:.0} |",
                    r.dofs, r.status, r.time, r.iterations, r.factorizations, r.memory_mb
                );
                match &first {
                    None => first = Some(r.blocks.clone()),
                    Some(b) => assert_eq!(b, &r.blocks, "results depend on the thread count"),
                }
                per_thread[ti].push((r.dofs, r.time));
            }
        }
        for (ti, &t) in threads.iter().enumerate() {
            if per_thread[ti].len() >= 2 {
                fits.push((kind.clone(), t, exponent(&per_thread[ti])));
            }
        }
    }
    println!("\n| kind | threads | time ∝ dofs^p, p |\n|---|---:|---:|");
    for (kind, t, p) in fits {
        println!("| {kind} | {t} | {p:.2} |");
    }
    println!(
        "\n# load average after: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
