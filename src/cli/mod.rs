//! The command line (INTERFACE.md, "Command line"). Depends on everything; nothing depends
//! on it.

use crate::{analysis, mesh, output, scene, solve, Error, Result};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
        #[arg(long)]
        out: PathBuf,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Linear backend.
        #[arg(long, default_value = solve::DEFAULT)]
        solver: String,
        /// Print nothing but errors.
        #[arg(long)]
        quiet: bool,
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
    /// Write the stiffness matrix at the first solve (and the load vector) in Matrix Market.
    ExportMatrix {
        scene: PathBuf,
        file: PathBuf,
        #[arg(long)]
        threads: Option<usize>,
    },
}

/// Entry point of the `dfem` binary.
pub fn main() -> ExitCode {
    std::panic::set_hook(Box::new(|info| {
        eprintln!("dfem: internal error ({info}); this is a bug, please report it with the scene that caused it");
    }));
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn threads(n: Option<usize>) -> Result<()> {
    if let Some(n) = n {
        if n == 0 {
            return Err(Error::new("--threads must be at least 1")
                .place("option --threads")
                .fix("give a positive number of threads"));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| {
                Error::new(format!("cannot start {n} threads: {e}")).place("option --threads")
            })?;
    }
    Ok(())
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

fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run {
            scene: file,
            example,
            out,
            threads: n,
            solver,
            quiet,
        } => {
            threads(n)?;
            let mut backend = solve::backend(&solver)?;
            let sc = read_scene(file.as_deref(), example.as_deref())?;
            if !quiet {
                for w in &sc.warnings {
                    eprintln!("warning: {w}");
                }
            }
            let m = mesh::build(&sc);
            let outcome = if sc.analysis.kind == scene::AnalysisType::Dynamic {
                let mut w = output::StreamWriter::new(&out, &sc, &m)?;
                analysis::run_with(&sc, &m, backend.as_mut(), &mut w)
            } else {
                analysis::run(&sc, &m, backend.as_mut())
            }
            .map_err(|e| e.in_file(sc.file.as_deref().unwrap_or(Path::new("scene"))))?;
            output::write_all(&out, &sc, &m, &outcome)?;
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
                }
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
