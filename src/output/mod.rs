//! Results: `summary.json` (INTERFACE.md, "Results") and ParaView files. Every file is
//! written to a temporary name in the same directory and renamed, so a reader never sees
//! a half-written result.

pub mod figures;
pub mod plot;
pub mod read;
pub mod vtk;

use crate::analysis::{outcome_motion, Outcome, Status};
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::{AnalysisType, Scene};
use crate::{Error, Result};
use serde_json::{json, Value};
use std::path::Path;

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
    let (status, failure, message) = match &out.status {
        Status::Stable => (
            if scene.analysis.kind == AnalysisType::Dynamic {
                "completed"
            } else {
                "stable"
            },
            Value::Null,
            Value::Null,
        ),
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
        "load_factor": out.load_factor,
        "failure": failure,
        "blocks": blocks,
        "stats": {
            "dofs": s.dofs,
            "contacts": s.contacts,
            "triangles": s.triangles,
            "increments": s.increments,
            "iterations": s.iterations,
            "factorizations": s.factorizations,
            "symbolic_factorizations": s.symbolic_factorizations,
            "reused_factorizations": s.reused_factorizations,
            "reuse_iterations": s.reuse_iterations,
            "min_pivot_ratio": s.min_pivot_ratio,
            "wall_time_s": s.wall_time_s,
        },
        "warnings": scene.warnings,
        "curve": out.capacity_curve.as_ref().map(|c| json!({
            "file": "curve.csv",
            "control_block": scene.blocks[c.control_block].name,
        })),
    })
}

/// The text of `curve.csv`: header `load_factor,ux_m,uy_m`, one row per converged state of
/// the capacity search (the first one after gravity, at λ = 0).
pub fn curve_csv(curve: &crate::analysis::curve::Curve) -> String {
    let mut s = String::from("load_factor,ux_m,uy_m\n");
    for p in &curve.points {
        s.push_str(&format!(
            "{},{:e},{:e}\n",
            p.load_factor, p.displacement[0], p.displacement[1]
        ));
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
    let rows: Option<Vec<[f64; 3]>> = out.capacity_curve.as_ref().map(|c| {
        c.points
            .iter()
            .map(|p| [p.load_factor, p.displacement[0], p.displacement[1]])
            .collect()
    });
    let control = out
        .capacity_curve
        .as_ref()
        .map(|c| scene.blocks[c.control_block].name.as_str())
        .unwrap_or("");
    figures::write_figures(
        dir,
        &fig,
        rows.as_deref().map(|r| (r, control)),
        amplification,
        formats,
    )
}

/// Write every result of a run into `dir`.
pub fn write_all(dir: &Path, scene: &Scene, mesh: &Mesh, out: &Outcome) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::new(format!("cannot create the output directory: {e}"))
            .file(dir)
            .fix("choose a writable --out directory")
    })?;
    if scene.output.vtk {
        vtk::write_step(dir, 0, 0.0, scene, mesh, out)?;
        vtk::write_pvd(dir, &[(0.0, 0)])?;
    }
    if let Some(c) = &out.capacity_curve {
        write_atomic(&dir.join("curve.csv"), curve_csv(c).as_bytes())?;
    }
    let mut text =
        serde_json::to_string_pretty(&summary(scene, mesh, out)).expect("JSON of plain values");
    text.push('\n');
    write_atomic(&dir.join("summary.json"), text.as_bytes())
}
