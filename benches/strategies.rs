//! Benchmark (not a test) of the three iteration strategies of the nonlinear static driver
//! (`[analysis] strategy` = "initial" | "secant" | "newton") on the capacity of a rigid
//! running-bond brick wall: run time against the error in the critical load factor λ.
//!
//!     cargo bench --bench strategies -- [--quick] [--limit SECONDS] [--sizes 10,30,100]
//!                                        [--strategies initial,secant,newton]
//!                                        [--tolerances 1e-4,1e-6] [--brackets 1e-2,1e-3,1e-4]
//!                                        [--reference 1e-8,1e-5] [--reference-strategy secant]
//!                                        [--jobs 1] [--threads N]
//!                                        [--csv FILE] [--plot DIR]
//!
//! `--quick` runs the small walls only (10 × 10 and 30 × 30 blocks); the default adds the
//! 100 × 100 wall (10⁴ blocks). For each wall the reference λ_ref is the tightest run
//! (strategy secant, tolerance 1e-8, bracket 1e-5); the error of a run is
//! |λ − λ_ref| / λ_ref. Every analysis runs in a child process (this binary with `--case`)
//! so that a run longer than `--limit` seconds (default 600) is stopped and reported as
//! such rather than holding up the table. `--jobs N` runs N children at a time (the
//! reference is started first) and `--threads N` sets each child's RAYON_NUM_THREADS: on a
//! 2-core machine `--jobs 2 --threads 1` gives each run a core of its own (the results do
//! not depend on the number of threads; the factorizations are sequential anyway). The wall time is the driver's own
//! (`Outcome.stats.wall_time_s`: the analysis, without parsing and meshing).
//! Results are printed as a markdown table on stdout; progress goes to stderr. `--csv FILE`
//! also saves the table as CSV, and `--plot DIR` draws the wall time against the error, one
//! series per strategy and one panel per wall, into `DIR/strategies_time_error.png` and
//! `.svg` (`dfem::output::time_error`; `dfem plot FILE.csv` draws it again from the CSV).

use dfem::output::bench_table::{markdown_line, Table, STRATEGY_COLUMNS};
use dfem::output::figures::Format;
use dfem::output::time_error;
use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Strategies compared.
const STRATEGIES: &[&str] = &["initial", "secant", "newton"];
/// (tolerance, bracket) of the compared runs.
const TOLERANCES: &[f64] = &[1e-4, 1e-6];
const BRACKETS: &[f64] = &[1e-2, 1e-3, 1e-4];
/// The reference run: secant, tolerance 1e-8, bracket 1e-5.
const REF_STRATEGY: &str = "secant";
const REF_TOLERANCE: f64 = 1e-8;
const REF_BRACKET: f64 = 1e-5;

/// A rigid running-bond wall of `courses` courses of `bricks` bricks 0.4 m × 0.2 m (mortar
/// joint included, simplified micro-model) on a fixed foundation, 0.1 m thick, under its
/// weight and then a horizontal body force λ·g raised until failure. Brick E = 5 GPa,
/// ν = 0.2, γ = 18 kN/m³ (the blocks are rigid: only γ matters); mortar joint 10 mm thick
/// with kₙ = 82 N/mm³, kₛ = 36 N/mm³ (Lourenço), friction angle 31°, no cohesion and no
/// tensile strength (a dry-joint limit analysis).
fn scene_text(
    courses: usize,
    bricks: usize,
    strategy: &str,
    tolerance: f64,
    bracket: f64,
) -> String {
    format!(
        r#"title = "strategies benchmark: rigid running-bond wall {courses} x {bricks}"

[model]
plane = "stress"
thickness = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "brick"
lame_lambda = 1.389e9
lame_mu = 2.083e9
unit_weight = 18e3

[[joint]]
name = "mortar"
normal_modulus = 8.2e8
shear_modulus = 3.6e8
band = 0.010
friction_angle = 31.0
cohesion = 0.0
tensile_strength = 0.0

[[generate]]
type = "wall"
material = "brick"
kind = "rigid"
courses = {courses}
bricks_per_course = {bricks}
brick_length = 0.4
brick_height = 0.2

[contacts]
joint = "mortar"

[analysis]
type = "capacity"
load_steps = 2
strategy = "{strategy}"
tolerance = {tolerance:e}
bracket = {bracket:e}
initial_step = 0.05

[output]
vtk = false
"#
    )
}

/// One measured run.
#[derive(Debug, Clone)]
struct Run {
    blocks: usize,
    dofs: usize,
    strategy: String,
    tolerance: f64,
    bracket: f64,
    /// Critical load factor, when the run gave one.
    lambda: Option<f64>,
    iterations: usize,
    factorizations: usize,
    wall_s: f64,
    /// CPU time of the child process (user + system, s; `None` where /proc is missing): on
    /// a loaded machine the wall time grows with the load, the CPU time much less.
    cpu_s: Option<f64>,
    /// The summary's message (status reason), or why there is no result.
    message: String,
}

/// Child mode: run one case and print one `RESULT` line (tab-separated).
fn run_case(courses: usize, bricks: usize, strategy: &str, tolerance: f64, bracket: f64) {
    let text = scene_text(courses, bricks, strategy, tolerance, bracket);
    let scene = dfem::scene::parse_str(&text, None).expect("the benchmark scene parses");
    let mesh = dfem::mesh::build(&scene);
    let blocks = scene
        .blocks
        .iter()
        .filter(|b| b.support == dfem::scene::Support::Free)
        .count();
    let mut backend = dfem::solve::backend("faer-cholesky").expect("faer-cholesky backend");
    let t0 = Instant::now();
    let res = dfem::analysis::run(&scene, &mesh, backend.as_mut());
    let outer = t0.elapsed().as_secs_f64();
    match res {
        Ok(out) => {
            let message = match &out.status {
                dfem::analysis::Status::Stable => "stable".to_string(),
                dfem::analysis::Status::Failed { reason, .. }
                | dfem::analysis::Status::NotConverged { reason, .. } => reason.clone(),
                dfem::analysis::Status::Interrupted { time } => format!("interrupted at {time} s"),
            };
            let lambda = out
                .load_factor
                .map_or("none".to_string(), |l| format!("{l:.17e}"));
            let wall = if out.stats.wall_time_s > 0.0 {
                out.stats.wall_time_s
            } else {
                outer
            };
            println!(
                "RESULT\t{blocks}\t{}\t{lambda}\t{}\t{}\t{wall}\t{}\t{}",
                mesh.n_dofs,
                out.stats.iterations,
                out.stats.factorizations,
                cpu_seconds().map_or("none".to_string(), |c| c.to_string()),
                message.replace(['\t', '\n'], " ")
            );
        }
        Err(e) => {
            println!(
                "RESULT\t{blocks}\t{}\tnone\t0\t0\t{outer}\tnone\terror: {}",
                mesh.n_dofs,
                e.to_string().replace(['\t', '\n'], " ")
            );
        }
    }
}

/// CPU time of this process so far (user + system, s), from /proc/self/stat (Linux;
/// `None` elsewhere). The clock tick is taken as 1/100 s, the value on Linux.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the fields after the command name, which is in parentheses and may hold spaces
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Parent mode: run one case in a child process, stopped after `limit`.
fn measure(
    courses: usize,
    bricks: usize,
    strategy: &str,
    tolerance: f64,
    bracket: f64,
    limit: Duration,
    threads: Option<usize>,
) -> Run {
    let exe = std::env::current_exe().expect("path of the bench binary");
    let mut command = Command::new(exe);
    if let Some(t) = threads {
        // results do not depend on the number of threads; only the wall time does
        command.env("RAYON_NUM_THREADS", t.to_string());
    }
    let mut child = command
        .args([
            "--case",
            &courses.to_string(),
            &bricks.to_string(),
            strategy,
            &format!("{tolerance:e}"),
            &format!("{bracket:e}"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start the child run");
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for the child run") {
            break Some(s);
        }
        if start.elapsed() > limit {
            // the child was started here: stop it by its own handle
            let _ = child.kill();
            let _ = child.wait();
            timed_out = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut stdout = String::new();
    if let Some(mut o) = child.stdout.take() {
        let _ = o.read_to_string(&mut stdout);
    }
    let elapsed = start.elapsed().as_secs_f64();
    let mut run = Run {
        blocks: 0,
        dofs: 0,
        strategy: strategy.to_string(),
        tolerance,
        bracket,
        lambda: None,
        iterations: 0,
        factorizations: 0,
        wall_s: elapsed,
        cpu_s: None,
        message: String::new(),
    };
    if let Some(line) = stdout.lines().find(|l| l.starts_with("RESULT\t")) {
        let f: Vec<&str> = line.splitn(10, '\t').collect();
        run.blocks = f[1].parse().unwrap_or(0);
        run.dofs = f[2].parse().unwrap_or(0);
        run.lambda = f[3].parse().ok();
        run.iterations = f[4].parse().unwrap_or(0);
        run.factorizations = f[5].parse().unwrap_or(0);
        run.wall_s = f[6].parse().unwrap_or(elapsed);
        run.cpu_s = f.get(7).and_then(|c| c.parse().ok());
        run.message = f.get(8).unwrap_or(&"").to_string();
    } else if timed_out {
        run.message = format!("stopped after {:.0} s (limit)", limit.as_secs_f64());
    } else {
        run.message = format!("the run ended without a result ({status:?})");
    }
    run
}

fn fmt_sci(x: f64) -> String {
    format!("{x:.0e}")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--case") {
        let a = &args[1..];
        assert!(
            a.len() >= 5,
            "--case COURSES BRICKS STRATEGY TOLERANCE BRACKET"
        );
        run_case(
            a[0].parse().expect("courses"),
            a[1].parse().expect("bricks"),
            &a[2],
            a[3].parse().expect("tolerance"),
            a[4].parse().expect("bracket"),
        );
        return;
    }
    let mut quick = false;
    let mut limit = 600.0;
    let mut sizes: Option<Vec<usize>> = None;
    let mut strategies: Vec<String> = STRATEGIES.iter().map(|s| s.to_string()).collect();
    let mut tolerances: Vec<f64> = TOLERANCES.to_vec();
    let mut brackets: Vec<f64> = BRACKETS.to_vec();
    let list = |v: Option<&String>, what: &str| -> Vec<f64> {
        v.unwrap_or_else(|| panic!("{what} needs a comma-separated list"))
            .split(',')
            .map(|s| {
                s.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{what}: not a number: {s}"))
            })
            .collect()
    };
    let count = |v: Option<&String>, what: &str| -> usize {
        v.and_then(|v| v.parse().ok())
            .filter(|&n| n >= 1)
            .unwrap_or_else(|| panic!("{what} needs a whole number >= 1"))
    };
    let (mut ref_tolerance, mut ref_bracket) = (REF_TOLERANCE, REF_BRACKET);
    let mut ref_strategy = REF_STRATEGY.to_string();
    let mut jobs = 1usize;
    let mut threads: Option<usize> = None;
    let (mut csv, mut plot): (Option<String>, Option<String>) = (None, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            // cargo bench passes --bench to harness = false binaries
            "--bench" => {}
            "--limit" => {
                limit = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--limit SECONDS")
            }
            "--sizes" => {
                sizes = Some(
                    it.next()
                        .expect("--sizes 10,30,100")
                        .split(',')
                        .map(|s| s.trim().parse().expect("a wall size"))
                        .collect(),
                )
            }
            "--tolerances" => tolerances = list(it.next(), "--tolerances"),
            "--reference" => {
                let r = list(it.next(), "--reference");
                assert_eq!(r.len(), 2, "--reference TOLERANCE,BRACKET");
                (ref_tolerance, ref_bracket) = (r[0], r[1]);
            }
            "--reference-strategy" => {
                ref_strategy = it
                    .next()
                    .expect("--reference-strategy initial|secant|newton")
                    .clone()
            }
            "--jobs" => jobs = count(it.next(), "--jobs"),
            "--threads" => threads = Some(count(it.next(), "--threads")),
            "--brackets" => brackets = list(it.next(), "--brackets"),
            "--csv" => csv = Some(it.next().expect("--csv FILE").clone()),
            "--plot" => plot = Some(it.next().expect("--plot DIR").clone()),
            "--strategies" => {
                strategies = it
                    .next()
                    .expect("--strategies initial,secant,newton")
                    .split(',')
                    .map(|s| s.trim().to_string())
                    .collect()
            }
            other => eprintln!("strategies bench: ignoring argument '{other}'"),
        }
    }
    let sizes = sizes.unwrap_or(if quick {
        vec![10, 30]
    } else {
        vec![10, 30, 100]
    });
    let limit = Duration::from_secs_f64(limit);
    println!(
        "Capacity of rigid running-bond walls (n courses x n bricks of 0.4 m x 0.2 m, friction 31 deg, no cohesion), backend faer-cholesky."
    );
    println!(
        "Reference lambda_ref of each wall: the tightest run (strategy {ref_strategy}, tolerance {ref_tolerance:e}, bracket {ref_bracket:e}); error = |lambda - lambda_ref| / lambda_ref."
    );
    println!(
        "Each run is stopped after {:.0} s; wall time is the analysis only (no parsing/meshing); {jobs} run(s) at a time, {} thread(s) each.\n",
        limit.as_secs_f64(),
        threads.map_or("the default number of".to_string(), |t| t.to_string())
    );
    let mut table = Table::new(&STRATEGY_COLUMNS);
    print!(
        "{}",
        table.markdown_header(&[true, true, false, true, true, true, true, true, true, true])
    );
    let mut notes = Vec::new();
    for &n in &sizes {
        // the reference first, then the grid; `jobs` child processes at a time
        let mut cases = vec![(ref_strategy.clone(), ref_tolerance, ref_bracket)];
        for s in &strategies {
            for &tol in &tolerances {
                for &br in &brackets {
                    cases.push((s.clone(), tol, br));
                }
            }
        }
        let done = run_cases(n, &cases, limit, jobs, threads);
        let lref = done[0].lambda;
        let runs: Vec<(Run, bool)> = done
            .into_iter()
            .enumerate()
            .map(|(i, r)| (r, i == 0))
            .collect();
        for (r, is_ref) in &runs {
            table.rows.push(print_row(r, lref, *is_ref));
        }
        for (r, is_ref) in &runs {
            let ok = r.message.starts_with("critical load factor");
            if !ok || r.lambda.is_none() {
                notes.push(format!(
                    "{} blocks, {}{}, tolerance {}, bracket {}: {}",
                    r.blocks,
                    r.strategy,
                    if *is_ref { " (reference)" } else { "" },
                    fmt_sci(r.tolerance),
                    fmt_sci(r.bracket),
                    r.message
                ));
            }
        }
        eprintln!("wall {n} x {n}: summary messages:");
        for (r, _) in &runs {
            eprintln!(
                "  {} tol {} bracket {}: {}",
                r.strategy,
                fmt_sci(r.tolerance),
                fmt_sci(r.bracket),
                r.message
            );
        }
    }
    if !notes.is_empty() {
        println!("\nRuns without a critical load factor:\n");
        for n in notes {
            println!("* {n}");
        }
    }
    if let Some(f) = csv {
        table
            .write_csv(std::path::Path::new(&f))
            .unwrap_or_else(|e| panic!("{e}"));
        eprintln!("table saved in {f}");
    }
    if let Some(d) = plot {
        let fig =
            time_error::Plot::new(&table, time_error::STRATEGIES).expect("the table's columns");
        for f in time_error::write(
            std::path::Path::new(&d),
            None,
            &fig,
            &[Format::Png, Format::Svg],
        )
        .unwrap_or_else(|e| panic!("{e}"))
        {
            eprintln!("figure written: {}", f.display());
        }
    }
}

/// Run the `cases` (strategy, tolerance, bracket) of the n × n wall, `jobs` child processes
/// at a time, and return their results in the order of `cases`.
fn run_cases(
    n: usize,
    cases: &[(String, f64, f64)],
    limit: Duration,
    jobs: usize,
    threads: Option<usize>,
) -> Vec<Run> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<std::sync::Mutex<Option<Run>>> =
        cases.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(cases.len()) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some((s, tol, br)) = cases.get(i) else {
                    break;
                };
                eprintln!("wall {n} x {n}: {s}, tol {tol:e}, bracket {br:e}: started");
                let r = measure(n, n, s, *tol, *br, limit, threads);
                eprintln!(
                    "wall {n} x {n}: {s}, tol {tol:e}, bracket {br:e}: {:.1} s wall, {} s CPU, {}",
                    r.wall_s,
                    r.cpu_s.map_or("?".to_string(), |c| format!("{c:.1}")),
                    r.message
                );
                *results[i].lock().expect("a result slot") = Some(r);
            });
        }
    });
    results
        .into_iter()
        .map(|m| {
            m.into_inner()
                .expect("a result slot")
                .expect("every case was run")
        })
        .collect()
}

/// Print the row of a run (markdown, as it comes) and return its cells.
fn print_row(r: &Run, lref: Option<f64>, is_ref: bool) -> Vec<String> {
    let lam = r.lambda.map_or("–".to_string(), |l| format!("{l:.6}"));
    let err = if is_ref {
        "(reference)".to_string()
    } else {
        match (r.lambda, lref) {
            (Some(l), Some(lr)) => format!("{:.1e}", (l - lr).abs() / lr),
            _ => "–".to_string(),
        }
    };
    let wall = if r.lambda.is_none() && !r.message.starts_with("critical") {
        format!("{:.2} ({})", r.wall_s, short(&r.message))
    } else {
        format!("{:.2}", r.wall_s)
    };
    let cells = vec![
        r.blocks.to_string(),
        r.dofs.to_string(),
        r.strategy.clone(),
        fmt_sci(r.tolerance),
        fmt_sci(r.bracket),
        lam,
        err,
        r.iterations.to_string(),
        r.factorizations.to_string(),
        wall,
    ];
    println!("{}", markdown_line(&cells));
    cells
}

fn short(m: &str) -> String {
    let s: String = m.chars().take(60).collect();
    if s.len() < m.len() {
        format!("{s}…")
    } else {
        s
    }
}
