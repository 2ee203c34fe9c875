//! The command line (docs/outputs.md, "Command line and exit status"). Depends on everything; nothing depends
//! on it.

mod progress;

use crate::output::figures::Format;
use crate::{analysis, mesh, output, scene, solve, Error, Result};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "dfem",
    version,
    about = "Discrete finite element analysis of masonry and blocky rock structures"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the scene's analysis and write the results into DIR.
    Run {
        /// Scene file (TOML); omit it with --example.
        scene: Option<PathBuf>,
        /// Run a built-in example scene instead of a file (`dfem example --list`).
        #[arg(long, conflicts_with = "scene")]
        example: Option<String>,
        /// Output directory.
        #[arg(long, required_unless_present = "resume", conflicts_with = "resume")]
        out: Option<PathBuf>,
        /// Continue the interrupted (Ctrl-C) or killed dynamic run in DIR from its
        /// checkpoint; the scene is the one it ran (or SCENE, which must be the same).
        #[arg(long, value_name = "DIR")]
        resume: Option<PathBuf>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Linear backend: faer-condensed (default: faer's Cholesky with the deformable
        /// blocks' interiors condensed out where that pays), faer-cholesky, faer-ldlt,
        /// faer-lu, faer-substructured (subdomains of blocks factorized in parallel), pcg,
        /// ..., and with
        /// the cargo features of the same name mumps, mumps-spd, mumps-lu, petsc.
        #[arg(long, default_value = solve::DEFAULT)]
        solver: String,
        /// Number of subdomains of --solver faer-substructured (default 2, one per core on
        /// a two-core machine): the movable blocks split by METIS into K parts, each
        /// factorized on its own task.
        #[arg(long, value_name = "K")]
        subdomains: Option<usize>,
        /// Options for PETSc's database when --solver petsc, as on PETSc's command line
        /// (default: -ksp_type cg -pc_type gamg, rtol 1e-12).
        #[arg(long, value_name = "OPTIONS", allow_hyphen_values = true)]
        petsc_options: Option<String>,
        /// Print nothing but errors (and the --log-json lines, when asked for).
        #[arg(long)]
        quiet: bool,
        /// Do not draw the figures (DIR/figures/).
        #[arg(long)]
        no_plots: bool,
        /// Displacement amplification of the deformed figure (default: automatic, the
        /// largest displacement drawn as about 5 % of the model's size).
        #[arg(long, value_name = "X")]
        amplification: Option<f64>,
        /// Print one JSON line per converged increment on stderr (phase, increment,
        /// load_factor, iterations, residual, elapsed_s) instead of a progress bar.
        #[arg(long)]
        log_json: bool,
        /// Refuse the scene when its estimated memory exceeds this many MB (default: the
        /// memory the machine has available).
        #[arg(long, value_name = "MB")]
        memory_limit: Option<f64>,
        /// Dynamic: write N ParaView frames after the one at t = 0, at t = j duration / N,
        /// instead of the scene's `[output]` rule (a run resumed with --resume takes the
        /// same N).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
        frames: Option<u32>,
    },
    /// Draw the figures of a finished run again from the files in DIR, or the run time
    /// against error of a benchmark table saved with --csv (DIR is then FILE.csv).
    Plot {
        /// The directory `dfem run --out DIR` wrote, or a benchmark's FILE.csv.
        dir: PathBuf,
        /// Displacement amplification of the deformed figure (default: automatic).
        #[arg(long, value_name = "X")]
        amplification: Option<f64>,
        /// Image format (default: both png and svg).
        #[arg(long, value_parser = ["png", "svg"])]
        format: Option<String>,
        /// Where to write the figures (default: DIR/figures; for FILE.csv, its directory).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Parse, mesh and find contacts; print counts; no solve.
    Check {
        scene: PathBuf,
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Write a built-in example scene (list them with --list).
    Example {
        name: Option<String>,
        /// Write to FILE instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long)]
        list: bool,
    },
    /// Run every linear backend of this build on the scene's stiffness matrix (the elastic
    /// one of the first solve) and print one table: setup, factorization or preconditioner
    /// set-up, solve, iterations, memory, true residual.
    BenchSolvers {
        scene: PathBuf,
        /// Comma-separated backends to run (default: every one compiled in).
        #[arg(long, value_delimiter = ',')]
        solvers: Vec<String>,
        /// Options for PETSc's database (as for `run`).
        #[arg(long, value_name = "OPTIONS", allow_hyphen_values = true)]
        petsc_options: Option<String>,
        /// Number of subdomains of faer-substructured (as for `run`).
        #[arg(long, value_name = "K")]
        subdomains: Option<usize>,
        #[arg(long)]
        threads: Option<usize>,
        /// Also draw the run time against the true residual, one marker per backend, into
        /// DIR/solvers_time_error.png and .svg.
        #[arg(long, value_name = "DIR")]
        plot: Option<PathBuf>,
        /// Also save the table as CSV (redraw it with `dfem plot FILE.csv`).
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
    },
    /// Write the stiffness matrix at the first solve (and the load vector) in Matrix Market.
    ExportMatrix {
        scene: PathBuf,
        file: PathBuf,
        #[arg(long)]
        threads: Option<usize>,
    },
}

/// Refuse a scene whose estimated memory ([`crate::resources::estimate`]) exceeds `limit`
/// MB, or the memory available on the machine when no limit is given.
fn check_memory(sc: &scene::Scene, m: &mesh::Mesh, limit: Option<f64>) -> Result<()> {
    let e = crate::resources::estimate(m);
    let (limit_b, what) = match limit {
        Some(mb) if mb.is_finite() && mb > 0.0 => (mb * 1e6, "the --memory-limit"),
        Some(mb) => {
            return Err(Error::new(format!(
                "--memory-limit {mb} is not a positive number of MB"
            ))
            .fix("give the limit in MB, for example --memory-limit 4000"))
        }
        None => match crate::resources::available_bytes() {
            Some(b) => (b as f64, "the memory this machine has available"),
            None => return Ok(()),
        },
    };
    if e.total() <= limit_b {
        return Ok(());
    }
    let mb = |b: f64| b / 1e6;
    let mut err = Error::new(format!(
        "the analysis would need about {:.0} MB (elements {:.0}, factor {:.0}, vectors {:.0}, program {:.0}), more than {what} ({:.0} MB)",
        mb(e.total()), mb(e.elements), mb(e.factor), mb(e.vectors), mb(e.base), mb(limit_b)
    ))
    .fix("use rigid blocks (kind = \"rigid\") where deformation does not matter, a coarser mesh_size, fewer blocks, or a machine with more memory");
    if let Some(f) = &sc.file {
        err = err.file(f);
    }
    Err(err)
}

/// Entry point of the `dfem` binary.
pub fn main() -> ExitCode {
    std::panic::set_hook(Box::new(|info| {
        // stdout closed by the reader (`dfem check scene.toml | head`): not a bug; end as
        // a program killed by SIGPIPE would (Rust ignores the signal, and `println!`
        // panics on the write error instead)
        let text = info.to_string();
        if text.contains("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(141);
        }
        eprintln!("dfem: internal error ({info}); this is a bug, please report it with the scene that caused it");
    }));
    let cli = Cli::parse();
    let mut code = 0;
    let r = dispatch(cli, &mut code);
    // every backend is dropped by now: end PETSc/MPI if they were started
    dfem_ffi::finalize();
    match r {
        Ok(()) => ExitCode::from(code),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Start the global thread pool with `n` threads (default: rayon's, all cores), the
/// calling (main) thread one of them: the analyses run on it and call parallel loops by
/// the thousand (every trial of the static driver, every matrix product), which then start
/// on it and hand only their split halves to the other threads. Without it every loop is
/// handed from the main thread to a worker and back (a wake-up, a futex wait and a
/// worker's idle spinning each time): on the rigid 40 × 40 wall of docs/decisions/0017-trial-evaluation-overhead.md,
/// 3,852 futex calls and 16,588 yields of the idle worker in a run, and most of its
/// system time.
fn threads(n: Option<usize>) -> Result<()> {
    if n == Some(0) {
        return Err(Error::new("--threads must be at least 1")
            .place("option --threads")
            .fix("give a positive number of threads"));
    }
    let started = rayon::ThreadPoolBuilder::new()
        .num_threads(n.unwrap_or(0))
        .use_current_thread()
        .build_global();
    match (started, n) {
        (Err(e), Some(n)) => {
            Err(Error::new(format!("cannot start {n} threads: {e}")).place("option --threads"))
        }
        // without --threads, a pool started already (another command in this process)
        // serves as it is
        _ => Ok(()),
    }
}

fn check_amplification(a: Option<f64>) -> Result<()> {
    match a {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(Error::new(format!(
            "--amplification must be a positive number, not {x}"
        ))
        .place("option --amplification")
        .fix("give for example --amplification 100, or leave it out for the automatic one")),
        _ => Ok(()),
    }
}

/// Read a scene from a file or a built-in example.
pub fn read_scene(file: Option<&Path>, example: Option<&str>) -> Result<scene::Scene> {
    match (file, example) {
        (Some(f), _) => scene::load(f),
        (None, Some(name)) => {
            let text = scene::examples::get(name).ok_or_else(|| unknown_example(name))?;
            scene::parse_str(text, Some(Path::new(&format!("example:{name}"))))
        }
        (None, None) => {
            Err(Error::new("no scene given").fix("give a scene file, or --example NAME"))
        }
    }
}

fn unknown_example(name: &str) -> Error {
    let names: Vec<&str> = scene::examples::EXAMPLES.iter().map(|e| e.0).collect();
    Error::new(format!("there is no built-in example '{name}'"))
        .fix(format!("use one of: {}", names.join(", ")))
}

/// Exit status of a dynamic run stopped by Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Exit status of a static or capacity run whose iterations stopped converging with no
/// mechanism in sight (summary.json `"not_converged"`, docs/outputs.md): its results are
/// written, but they answer nothing.
pub const EXIT_NOT_CONVERGED: u8 = 3;

/// What a run that did not converge tells the user (stderr): the out-of-balance force
/// left (`residual`, relative to the load), where it is largest (`block`: the block and
/// the force, N), and what to try.
pub fn not_converged_advice(
    sc: &scene::Scene,
    residual: f64,
    block: Option<(usize, f64)>,
) -> String {
    let at = block.map_or(String::new(), |(b, f)| {
        format!(", largest at block '{}' ({f:.3e} N)", sc.blocks[b].name)
    });
    format!(
        "not converged: the iterations stopped with an out-of-balance force of {residual:.2e} of the load{at} \
         (tolerance {:.0e}) and no mechanism in sight; this is not a collapse. Try, in [analysis]: \
         more iterations (max_iterations), a looser tolerance (tolerance), strategy = \"newton\", \
         smaller load steps (load_steps, gravity_steps); or joints whose stiffness is closer to \
         the blocks' (normal_modulus, shear_modulus)",
        sc.analysis.settings.statics().map_or(1e-6, |s| s.tolerance)
    )
}

/// The scene of `dfem run`: `file` or the built-in `example`, its frames those of
/// `--frames N` when given.
fn run_scene(
    file: Option<&Path>,
    example: Option<&str>,
    frames: Option<u32>,
) -> Result<scene::Scene> {
    let mut sc = read_scene(file, example)?;
    if let Some(n) = frames {
        sc.output.frames = scene::Frames::Count(n as usize);
    }
    Ok(sc)
}

/// The scene a checkpoint was run with: `given` when there is one (it must be the same),
/// otherwise the file (or built-in example) the checkpoint names; with `--frames N` as it
/// was run.
fn resumed_scene(
    dir: &Path,
    saved: &crate::analysis::checkpoint::Saved,
    file: Option<&Path>,
    example: Option<&str>,
    frames: Option<u32>,
) -> Result<scene::Scene> {
    use crate::analysis::checkpoint;
    let sc = if file.is_some() || example.is_some() {
        run_scene(file, example, frames)?
    } else if let Some(name) = saved.source.strip_prefix("example:") {
        run_scene(None, Some(name), frames)?
    } else {
        run_scene(Some(Path::new(&saved.source)), None, frames)?
    };
    if checkpoint::fingerprint(&sc) != saved.fingerprint {
        return Err(Error::new(format!(
            "the checkpoint belongs to another scene ({}), or the scene was changed since",
            saved.source
        ))
        .file(dir.join(checkpoint::FILE))
        .fix("resume with the scene (and --frames N) as it was run, or run this scene without --resume (into another --out directory to keep these results)"));
    }
    Ok(sc)
}

fn dispatch(cli: Cli, code: &mut u8) -> Result<()> {
    match cli.command {
        Command::Run {
            scene: file,
            example,
            out,
            resume,
            threads: n,
            solver,
            subdomains,
            petsc_options,
            quiet,
            no_plots,
            amplification,
            log_json,
            memory_limit,
            frames,
        } => {
            threads(n)?;
            check_amplification(amplification)?;
            // under mpirun (feature `mpi`) every rank runs the analysis, its linear solves
            // together; rank 0 alone reports and writes the results
            let (rank, _) = dfem_ffi::process_rank();
            let quiet = quiet || rank != 0;
            let mut prog = progress::CliProgress::new(quiet, log_json && rank == 0);
            let opts = solve::BackendOptions {
                petsc_options: petsc_options.unwrap_or_default(),
                subdomains,
            };
            let mut backend = solve::backend_with(&solver, &opts)?;
            let saved = resume.as_deref().map(output::read_checkpoint).transpose()?;
            let out = out.or(resume).expect("clap requires --out or --resume");
            let sc = match &saved {
                Some(s) => resumed_scene(&out, s, file.as_deref(), example.as_deref(), frames)?,
                None => run_scene(file.as_deref(), example.as_deref(), frames)?,
            };
            if !quiet {
                for w in &sc.warnings {
                    eprintln!("warning: {w}");
                }
            }
            prog.stage("meshing");
            let m = mesh::build(&sc);
            check_memory(&sc, &m, memory_limit)?;
            let ranks = solve::configure_run(backend.as_mut(), &m)
                .map_err(|e| Error::new(e.to_string()).place("option --solver"))?;
            let ranks = ranks.as_ref();
            if rank != 0 {
                analysis::run_with(
                    &sc,
                    &m,
                    ranks,
                    backend.as_mut(),
                    &mut prog,
                    &mut analysis::dynamics::NoMonitor,
                )
                .map_err(|e| e.in_file(sc.file.as_deref().unwrap_or(Path::new("scene"))))?;
                return Ok(());
            }
            let outcome = if sc.analysis.kind == scene::AnalysisType::Dynamic {
                let stop = Arc::new(AtomicBool::new(false));
                let flag = stop.clone();
                // the first Ctrl-C stops after the step under way, the second at once
                let _ = ctrlc::set_handler(move || {
                    if flag.swap(true, Ordering::SeqCst) {
                        std::process::exit(i32::from(EXIT_INTERRUPTED));
                    }
                    eprintln!("\ninterrupted: stopping after this time step (Ctrl-C again to stop at once; the results up to the last checkpoint are kept)");
                });
                // the files written on a thread of their own beside the run
                // (docs/decisions/0042-output-writer-thread.md)
                std::thread::scope(|scope| match saved {
                    Some(s) => {
                        let mut w = output::StreamWriter::resuming(&out, &sc, &m, &s.state)?
                            .stop_on(stop)
                            .on_thread(scope)?;
                        analysis::resume_with(&sc, &m, ranks, backend.as_mut(), &mut w, s.state)
                            .and_then(|mut o| {
                                w.complete(&mut o);
                                w.finish()?;
                                Ok(o)
                            })
                    }
                    None => {
                        let mut w = output::StreamWriter::new(&out, &sc, &m)?
                            .stop_on(stop)
                            .on_thread(scope)?;
                        analysis::run_with(&sc, &m, ranks, backend.as_mut(), &mut prog, &mut w)
                            .and_then(|o| {
                                w.finish()?;
                                Ok(o)
                            })
                    }
                })
            } else {
                analysis::run_with(
                    &sc,
                    &m,
                    ranks,
                    backend.as_mut(),
                    &mut prog,
                    &mut analysis::dynamics::NoMonitor,
                )
            }
            .map_err(|e| e.in_file(sc.file.as_deref().unwrap_or(Path::new("scene"))))?;
            prog.stage("writing");
            if sc.analysis.kind == scene::AnalysisType::Dynamic {
                // history.csv is the stream's, every row written
                output::write_streamed(&out, &sc, &m, &outcome)?;
            } else {
                output::write_all(&out, &sc, &m, &outcome)?;
            }
            if !matches!(outcome.status, analysis::Status::Interrupted { .. }) {
                // a run that reached its end has nothing to resume
                let _ = std::fs::remove_file(out.join(analysis::checkpoint::FILE));
            }
            if !no_plots {
                prog.stage("figures");
                output::write_figures(
                    &out.join("figures"),
                    &sc,
                    &m,
                    &outcome,
                    amplification,
                    &[Format::Png, Format::Svg],
                )
                .map_err(|mut e| {
                    let fix = e.fix.take().unwrap_or_default();
                    e.fix(format!("{fix} (the results are written: draw the figures later with `dfem plot DIR`, or run with --no-plots)"))
                })?;
            }
            prog.finish();
            if !quiet {
                match &outcome.status {
                    analysis::Status::Stable => println!(
                        "{}: {} dofs, {} contacts, {:.3} s; results in {}",
                        if sc.analysis.kind == scene::AnalysisType::Dynamic {
                            "completed"
                        } else {
                            "stable"
                        },
                        outcome.stats.dofs,
                        outcome.stats.contacts,
                        outcome.stats.wall_time_s,
                        out.display()
                    ),
                    analysis::Status::Failed { reason, .. } => {
                        println!("failed: {reason}; results in {}", out.display())
                    }
                    analysis::Status::NotConverged { reason, .. } => {
                        println!("not converged: {reason}; results in {}", out.display())
                    }
                    analysis::Status::Interrupted { .. } => {}
                }
            }
            if let analysis::Status::NotConverged {
                residual, block, ..
            } = &outcome.status
            {
                // on stderr even with --quiet: no mechanism was found, so the result is no
                // answer, and the user has something to try
                eprintln!("{}", not_converged_advice(&sc, *residual, *block));
                *code = EXIT_NOT_CONVERGED;
            }
            if let analysis::Status::Interrupted { time } = outcome.status {
                // on stderr even with --quiet: the exit status alone does not say how to go on
                eprintln!(
                    "interrupted at t = {time} s; the results up to then are in {dir}; continue with: dfem run --resume {dir}",
                    dir = out.display()
                );
                *code = EXIT_INTERRUPTED;
            }
            Ok(())
        }
        Command::Plot {
            dir,
            amplification,
            format,
            out,
        } => {
            check_amplification(amplification)?;
            let formats = match format.as_deref().and_then(Format::parse) {
                Some(f) => vec![f],
                None => vec![Format::Png, Format::Svg],
            };
            if dir.is_file() && dir.extension().is_some_and(|e| e == "csv") {
                let fig_dir = out.unwrap_or_else(|| {
                    dir.parent()
                        .filter(|p| !p.as_os_str().is_empty())
                        .unwrap_or(Path::new("."))
                        .to_path_buf()
                });
                for w in output::time_error::redraw(&dir, &fig_dir, &formats)? {
                    println!("{}", w.display());
                }
                return Ok(());
            }
            let fig = output::figures::Deformed::from_dir(&dir)?;
            let curve = output::read::curve(&dir)?;
            let history = output::read::history(&dir)?;
            let summary = output::read::summary(&dir)?;
            let name = |key: &str| summary["curve"][key].as_str().map(String::from);
            let control = name("control_block").unwrap_or_else(|| "control".into());
            let top = name("top_block").unwrap_or_else(|| control.clone());
            let curve = curve.and_then(|c| {
                output::figures::CurveFigure::from_columns(&c.columns, &c.rows, &control, &top)
            });
            let fig_dir = out.unwrap_or_else(|| dir.join("figures"));
            let written = output::figures::write_figures(
                &fig_dir,
                &fig,
                curve.as_ref(),
                history.as_ref().filter(|h| !h.rows.is_empty()),
                amplification,
                &formats,
            )?;
            for w in written {
                println!("{}", w.display());
            }
            Ok(())
        }
        Command::Check {
            scene: file,
            threads: n,
        } => {
            threads(n)?;
            let t0 = std::time::Instant::now();
            let sc = scene::load(&file)?;
            for w in &sc.warnings {
                eprintln!("warning: {w}");
            }
            let m = mesh::build(&sc);
            let fixed = sc
                .blocks
                .iter()
                .filter(|b| b.support == scene::Support::Fixed)
                .count();
            let rigid = sc
                .blocks
                .iter()
                .filter(|b| b.support == scene::Support::Free && b.kind == scene::BlockKind::Rigid)
                .count();
            println!("scene: {}", file.display());
            println!(
                "blocks: {} ({} fixed, {} rigid, {} deformable)",
                sc.blocks.len(),
                fixed,
                rigid,
                sc.blocks.len() - fixed - rigid
            );
            println!("nodes: {}", m.nodes.len());
            println!("triangles: {}", m.triangles.len());
            println!("joints: {}", m.segments.len());
            println!("contacts: {}", m.contacts.len());
            println!("dofs: {}", m.n_dofs);
            let mut blocks: Vec<u32> = solve::interior_groups(&m)
                .into_iter()
                .filter(|&g| g != u32::MAX)
                .collect();
            let interior = blocks.len();
            if interior > 0 {
                blocks.sort_unstable();
                blocks.dedup();
                println!(
                    "interior dofs: {interior} in {} deformable blocks (no contact on their \
                     nodes; the default solver condenses them out where that pays)",
                    blocks.len()
                );
            }
            let e = crate::resources::estimate(&m);
            println!(
                "estimated memory of the analysis: {:.0} MB (factor {:.0} MB)",
                e.total() / 1e6,
                e.factor / 1e6
            );
            println!("time: {:.3} s", t0.elapsed().as_secs_f64());
            Ok(())
        }
        Command::Example { name, out, list } => {
            if list || name.is_none() {
                for (n, d, _) in scene::examples::EXAMPLES {
                    println!("{n}\t{d}");
                }
                return Ok(());
            }
            let name = name.unwrap();
            let text = scene::examples::get(&name).ok_or_else(|| unknown_example(&name))?;
            match out {
                Some(f) => output::write_atomic(&f, text.as_bytes()),
                None => {
                    print!("{text}");
                    Ok(())
                }
            }
        }
        Command::BenchSolvers {
            scene: file,
            solvers,
            petsc_options,
            subdomains,
            threads: n,
            plot,
            csv,
        } => {
            threads(n)?;
            subdomains.map(solve::check_subdomains).transpose()?;
            let t0 = std::time::Instant::now();
            let sc = scene::load(&file)?;
            let m = mesh::build(&sc);
            let system = crate::assembly::System::new(&sc, &m);
            let k = system.stiffness(&m, &analysis::elastic_springs(&sc, &m));
            let f = analysis::external_load(&sc, &m);
            let t_model = t0.elapsed().as_secs_f64();
            let available = solve::available_names();
            let names: Vec<&str> = if solvers.is_empty() {
                available.clone()
            } else {
                solvers.iter().map(String::as_str).collect()
            };
            for name in &names {
                if !solve::all_names().contains(name) {
                    return Err(Error::new(format!("unknown linear backend '{name}'"))
                        .place("option --solvers")
                        .fix(format!("use some of: {}", available.join(", "))));
                }
            }
            let opts = solve::BackendOptions {
                petsc_options: petsc_options.unwrap_or_default(),
                subdomains,
            };
            let rows = solve::bench::bench(&k, &f, &m, &names, &opts);
            println!(
                "{}: {} unknowns, {} stored entries, {} blocks, {} contacts; model built in {:.2} s; {} threads\n",
                file.display(),
                k.pattern.n(),
                k.pattern.nnz(),
                m.blocks.len(),
                m.contacts.len(),
                t_model,
                rayon::current_num_threads()
            );
            let table = output::bench_table::solvers(&rows);
            print!("{}", table.markdown());
            if let Some(f) = csv {
                table.write_csv(&f)?;
            }
            if let Some(d) = plot {
                let fig = output::time_error::Plot::new(&table, output::time_error::SOLVERS)?;
                output::time_error::write(&d, None, &fig, &[Format::Png, Format::Svg])?;
            }
            Ok(())
        }
        Command::ExportMatrix {
            scene: file,
            file: mtx,
            threads: n,
        } => {
            threads(n)?;
            let sc = scene::load(&file)?;
            let m = mesh::build(&sc);
            let system = crate::assembly::System::new(&sc, &m);
            let k = system.stiffness(&m, &analysis::elastic_springs(&sc, &m));
            let f = analysis::external_load(&sc, &m);
            let io = |e: std::io::Error| {
                Error::new(format!("cannot write: {e}"))
                    .file(&mtx)
                    .fix("check the path")
            };
            dfem_kernels::mm::write_matrix_market(&mtx, &k).map_err(io)?;
            let rhs = mtx.with_extension("rhs.mtx");
            dfem_kernels::mm::write_vector_market(&rhs, &f).map_err(io)?;
            println!(
                "wrote {} ({} unknowns, {} non-zeros) and {}",
                mtx.display(),
                k.pattern.n(),
                k.pattern.nnz(),
                rhs.display()
            );
            Ok(())
        }
    }
}
