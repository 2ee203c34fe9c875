//! Results: `summary.json` (docs/outputs.md, "summary.json") and ParaView files. Every file is
//! written to a temporary name in the same directory and renamed, so a reader never sees
//! a half-written result.

pub mod bench_table;
pub mod figures;
pub mod plot;
pub mod read;
mod stream;
pub mod time_error;
pub mod time_history;
pub mod vtk;

pub use stream::{read_checkpoint, StreamWriter};

use crate::analysis::dynamics::History;
use crate::analysis::{outcome_motion, Outcome, Status};
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::{AnalysisType, Scene};
use crate::{Error, Result};
use serde_json::{json, Value};
use std::path::Path;

/// Wall time (s) between the checkpoints of a dynamic run without `[output]
/// checkpoint_every`.
pub const CHECKPOINT_SECONDS: u64 = 30;

/// Environment variable that stops a dynamic run after the step it names, as Ctrl-C
/// would (for tests of the interruption).
pub const STOP_AFTER_STEP: &str = "DFEM_STOP_AFTER_STEP";

/// Write `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let io = |e: std::io::Error| {
        Error::new(format!("cannot write the result: {e}"))
            .file(path)
            .fix("check that the output directory is writable and the disk is not full")
    };
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// The summary document.
pub fn summary(scene: &Scene, mesh: &Mesh, out: &Outcome) -> Value {
    let blocks: Vec<Value> = mesh
        .blocks
        .iter()
        .enumerate()
        .filter(|(_, b)| b.dofs != BlockDofs::Fixed)
        .map(|(i, _)| {
            let (d, r) = outcome_motion(mesh, i, out);
            json!({"name": scene.blocks[i].name, "displacement": d, "rotation": r})
        })
        .collect();
    let fallen: Vec<&str> = out
        .fallen
        .iter()
        .map(|&b| scene.blocks[b].name.as_str())
        .collect();
    let (status, failure, message) = match &out.status {
        Status::Stable => (
            if scene.analysis.kind == AnalysisType::Dynamic {
                "completed"
            } else {
                "stable"
            },
            Value::Null,
            if fallen.is_empty() {
                Value::Null
            } else {
                Value::String(format!(
                    "stands after {} block(s) fell out: {}{}",
                    fallen.len(),
                    fallen[..fallen.len().min(10)].join(", "),
                    if fallen.len() > 10 { ", ..." } else { "" }
                ))
            },
        ),
        Status::Interrupted { time } => (
            "interrupted",
            Value::Null,
            Value::String(format!(
                "interrupted at t = {time} s; the results up to then are written; continue with `dfem run --resume DIR`"
            )),
        ),
        Status::NotConverged { reason, .. } => {
            ("not_converged", Value::Null, Value::String(reason.clone()))
        }
        Status::Failed { reason, .. } => (
            "failed",
            match &out.mechanism {
                Some(m) => json!({
                    "mode": m.mode,
                    "blocks": m.blocks.iter().map(|&(b, motion)| json!({"name": scene.blocks[b].name, "motion": motion.as_str()})).collect::<Vec<_>>(),
                }),
                None => json!({"mode": "mixed", "blocks": []}),
            },
            Value::String(reason.clone()),
        ),
    };
    let s = &out.stats;
    json!({
        "title": scene.title,
        "analysis": match scene.analysis.kind { AnalysisType::Static => "static", AnalysisType::Capacity => "capacity", AnalysisType::Dynamic => "dynamic" },
        "status": status,
        "message": message,
        "time": match &out.status {
            Status::Interrupted { time } => Some(*time),
            _ => out.history.as_ref().and_then(|h| h.rows.last()).map(|r| r[0]),
        },
        "load_factor": out.load_factor,
        "failure": failure,
        "out_of_balance": match &out.status {
            Status::NotConverged { residual, block, .. } => json!({
                "relative": residual.is_finite().then_some(*residual),
                "block": block.map(|b| scene.blocks[b.0].name.as_str()),
                "largest_N": block.map(|b| b.1),
            }),
            _ => Value::Null,
        },
        "fallen": fallen,
        "blocks": blocks,
        "stats": {
            "dofs": s.dofs,
            "contacts": s.contacts,
            "triangles": s.triangles,
            "increments": s.increments,
            "iterations": s.iterations,
            "factorizations": s.factorizations,
            "symbolic_factorizations": s.symbolic_factorizations,
            "contact_topologies": s.contact_topologies,
            "reused_factorizations": s.reused_factorizations,
            "reuse_iterations": s.reuse_iterations,
            "low_rank_corrections": s.low_rank_corrections,
            "low_rank_max_rank": s.low_rank_max_rank,
            "tangent_lu_skipped": s.tangent_lu_skipped,
            "tangent_factorizations": s.tangent_factorizations,
            "tangent_fallbacks": s.tangent_fallbacks,
            "free_motions": s.free_motions,
            "slope_searches": s.slope_searches,
            "bonds_broken": s.bonds_broken,
            "fallen_blocks": s.fallen_blocks,
            "load_cuts": s.load_cuts,
            "contact_releases": s.contact_releases,
            "impact_cuts": s.impact_cuts,
            "held_open": s.held_open,
            "stalled_steps": s.stalled_steps,
            "static_start_iterations": s.static_start_iterations,
            "error_cuts": s.error_cuts,
            "event_cuts": s.event_cuts,
            "step_error_max": s.step_error_max,
            "step_error_sum": s.step_error_sum,
            "release_redos": s.release_redos,
            "release_redo_iterations": s.release_redo_iterations,
            "min_pivot_ratio": s.min_pivot_ratio,
            "factor_nnz": s.factor_nnz,
            "peak_memory_mb": s.peak_memory_mb,
            "processes": s.processes,
            "wall_time_s": s.wall_time_s,
        },
        "warnings": scene.warnings,
        "curve": out.capacity_curve.as_ref().map(|c| json!({
            "file": "curve.csv",
            "control_block": scene.blocks[c.control_block].name,
            "top_block": scene.blocks[c.top_block].name,
            "path": c.path.as_ref().map(|p| json!({
                "reached": p.reached,
                "furthest_m": p.furthest,
                "increments": {
                    "cylinder": p.increments[0],
                    "dissipation": p.increments[1],
                    "displacement": p.increments[2],
                },
                "accepted": {
                    "increments": p.accepted,
                    "largest_residual": p.accepted_residual,
                },
                "end": p.end,
            })),
        })),
    })
}

/// The columns and rows of `curve.csv` (docs/outputs.md, "The capacity curve"): per
/// converged state, λ and the control block's displacement (m), a push's forces (N) and
/// moment (N·m), then the top block's displacement (m).
pub fn curve_table(curve: &crate::analysis::curve::Curve) -> (Vec<String>, Vec<Vec<f64>>) {
    let push = curve.points.iter().any(|p| p.reaction.is_some());
    let mut columns = vec!["load_factor", "ux_m", "uy_m"];
    if push {
        columns.extend(["force_x_N", "force_y_N", "moment_Nm"]);
    }
    columns.extend(["top_ux_m", "top_uy_m"]);
    let rows = curve
        .points
        .iter()
        .map(|p| {
            let mut r = vec![p.load_factor, p.displacement[0], p.displacement[1]];
            if push {
                r.extend(p.reaction.unwrap_or([0.0; 3]));
            }
            r.extend(p.top);
            r
        })
        .collect();
    (columns.into_iter().map(String::from).collect(), rows)
}

/// The text of `curve.csv` ([`curve_table`]): λ as written by `{}`, the rest in `{:e}`,
/// both the shortest text that reads back to the same number.
pub fn curve_csv(curve: &crate::analysis::curve::Curve) -> String {
    let (columns, rows) = curve_table(curve);
    let mut s = columns.join(",");
    s.push('\n');
    for r in rows {
        let cells: Vec<String> = r
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if i == 0 {
                    format!("{v}")
                } else {
                    format!("{v:e}")
                }
            })
            .collect();
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

/// Draw the default figures of a run into `dir` (deformed configuration; capacity curve
/// for a capacity analysis) in each of `formats`; `amplification` `None`: automatic.
pub fn write_figures(
    dir: &Path,
    scene: &Scene,
    mesh: &Mesh,
    out: &Outcome,
    amplification: Option<f64>,
    formats: &[figures::Format],
) -> Result<Vec<std::path::PathBuf>> {
    let fig = figures::Deformed::from_run(scene, mesh, out);
    // the figure drawn from what curve.csv holds, so that `dfem plot` draws the same
    let curve = out.capacity_curve.as_ref().and_then(|c| {
        let (columns, rows) = curve_table(c);
        figures::CurveFigure::from_columns(
            &columns,
            &rows,
            &scene.blocks[c.control_block].name,
            &scene.blocks[c.top_block].name,
        )
    });
    figures::write_figures(
        dir,
        &fig,
        curve.as_ref(),
        out.history.as_ref().filter(|h| !h.rows.is_empty()),
        amplification,
        formats,
    )
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::new(format!("cannot create the output directory: {e}"))
            .file(dir)
            .fix("choose a writable --out directory")
    })
}

/// The text of history.csv: the header line, then one line per row.
pub fn history_csv(h: &History) -> String {
    let mut s = h.columns.join(",");
    s.push('\n');
    for r in &h.rows {
        s.push_str(&history_line(r));
    }
    s
}

fn history_line(r: &[f64]) -> String {
    use std::fmt::Write;
    // one string for the row (not one per value): the history is written at every step
    let mut s = String::with_capacity(17 * r.len());
    for (i, v) in r.iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        let _ = write!(s, "{v:.9e}");
    }
    s.push('\n');
    s
}

/// Write every result of a run into `dir`.
pub fn write_all(dir: &Path, scene: &Scene, mesh: &Mesh, out: &Outcome) -> Result<()> {
    write_results(dir, scene, mesh, out, false)
}

/// [`write_all`] after a dynamic run streamed by a [`StreamWriter`] and its
/// [`StreamWriter::finish`]: history.csv, whole, is not formatted and written again.
pub fn write_streamed(dir: &Path, scene: &Scene, mesh: &Mesh, out: &Outcome) -> Result<()> {
    write_results(dir, scene, mesh, out, true)
}

fn write_results(
    dir: &Path,
    scene: &Scene,
    mesh: &Mesh,
    out: &Outcome,
    streamed: bool,
) -> Result<()> {
    create_dir(dir)?;
    match &out.history {
        None => {
            if scene.output.vtk {
                vtk::write_step(dir, 0, 0.0, scene, mesh, out)?;
                vtk::write_pvd(dir, &[(0.0, 0)])?;
            }
        }
        Some(h) => {
            if !streamed {
                write_atomic(&dir.join("history.csv"), history_csv(h).as_bytes())?;
            }
            if scene.output.vtk {
                // the frames a monitor wrote, and the final state in any case (at the
                // step it reached: a failed or interrupted run may end between frames)
                let last = match h.rows.last() {
                    Some(r) => (r[0], h.rows.len() - 1),
                    None => h.frames.last().copied().unwrap_or((0.0, 0)),
                };
                vtk::write_step(dir, last.1, last.0, scene, mesh, out)?;
                let mut written: Vec<(f64, usize)> = h
                    .frames
                    .iter()
                    .copied()
                    .filter(|f| f.1 < last.1 && dir.join(format!("blocks_{:04}.vtu", f.1)).exists())
                    .collect();
                written.push(last);
                vtk::write_pvd(dir, &written)?;
            }
        }
    }
    if let Some(c) = &out.capacity_curve {
        write_atomic(&dir.join("curve.csv"), curve_csv(c).as_bytes())?;
    }
    write_summary(dir, &summary(scene, mesh, out))
}

fn write_summary(dir: &Path, s: &Value) -> Result<()> {
    let mut text = serde_json::to_string_pretty(s).expect("JSON of plain values");
    text.push('\n');
    write_atomic(&dir.join("summary.json"), text.as_bytes())
}
