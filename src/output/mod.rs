//! Results: `summary.json` (INTERFACE.md, "Results") and ParaView files. Every file is
//! written to a temporary name in the same directory and renamed, so a reader never sees
//! a half-written result.

pub mod figures;
pub mod plot;
pub mod read;
pub mod time_history;
pub mod vtk;

use crate::analysis::dynamics::{History, Monitor};
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
            "contact_topologies": s.contact_topologies,
            "reused_factorizations": s.reused_factorizations,
            "reuse_iterations": s.reuse_iterations,
            "min_pivot_ratio": s.min_pivot_ratio,
            "factor_nnz": s.factor_nnz,
            "peak_memory_mb": s.peak_memory_mb,
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
    let mut s = r
        .iter()
        .map(|v| format!("{v:.9e}"))
        .collect::<Vec<_>>()
        .join(",");
    s.push('\n');
    s
}

/// Streams a dynamic run to `dir` as it goes: history.csv grows by one flushed line per
/// time step (so an interrupted run keeps its completed steps; [`write_all`] rewrites
/// it atomically at the end) and a ParaView frame is written every `[output] every`
/// steps.
pub struct StreamWriter<'a> {
    dir: std::path::PathBuf,
    scene: &'a Scene,
    mesh: &'a Mesh,
    file: Option<std::fs::File>,
    frames: Vec<(f64, usize)>,
}

impl<'a> StreamWriter<'a> {
    pub fn new(dir: &Path, scene: &'a Scene, mesh: &'a Mesh) -> Result<Self> {
        create_dir(dir)?;
        Ok(StreamWriter {
            dir: dir.to_path_buf(),
            scene,
            mesh,
            file: None,
            frames: Vec::new(),
        })
    }
    fn io(&self, e: std::io::Error) -> Error {
        Error::new(format!("cannot write the history: {e}"))
            .file(self.dir.join("history.csv"))
            .fix("check that the output directory is writable and the disk is not full")
    }
}

impl Monitor for StreamWriter<'_> {
    fn start(&mut self, columns: &[String]) -> Result<()> {
        use std::io::Write;
        let mut f = std::fs::File::create(self.dir.join("history.csv")).map_err(|e| self.io(e))?;
        writeln!(f, "{}", columns.join(",")).map_err(|e| self.io(e))?;
        self.file = Some(f);
        Ok(())
    }
    fn row(&mut self, row: &[f64]) -> Result<()> {
        use std::io::Write;
        let line = history_line(row);
        if let Some(f) = self.file.as_mut() {
            let r = f.write_all(line.as_bytes()).and_then(|_| f.flush());
            if let Err(e) = r {
                return Err(self.io(e));
            }
        }
        Ok(())
    }
    fn wants_frames(&self) -> bool {
        self.scene.output.vtk
    }
    fn frame(&mut self, step: usize, time: f64, state: &Outcome) -> Result<()> {
        vtk::write_step(&self.dir, step, time, self.scene, self.mesh, state)?;
        self.frames.push((time, step));
        vtk::write_pvd(&self.dir, &self.frames)
    }
}

/// Write every result of a run into `dir`.
pub fn write_all(dir: &Path, scene: &Scene, mesh: &Mesh, out: &Outcome) -> Result<()> {
    create_dir(dir)?;
    match &out.history {
        None => {
            if scene.output.vtk {
                vtk::write_step(dir, 0, 0.0, scene, mesh, out)?;
                vtk::write_pvd(dir, &[(0.0, 0)])?;
            }
        }
        Some(h) => {
            write_atomic(&dir.join("history.csv"), history_csv(h).as_bytes())?;
            if scene.output.vtk {
                // the frames a monitor wrote, and the final state in any case
                let last = h.frames.last().copied().unwrap_or((0.0, 0));
                vtk::write_step(dir, last.1, last.0, scene, mesh, out)?;
                let written: Vec<(f64, usize)> = h
                    .frames
                    .iter()
                    .copied()
                    .filter(|f| *f == last || dir.join(format!("blocks_{:04}.vtu", f.1)).exists())
                    .collect();
                vtk::write_pvd(dir, &written)?;
            }
        }
    }
    if let Some(c) = &out.capacity_curve {
        write_atomic(&dir.join("curve.csv"), curve_csv(c).as_bytes())?;
    }
    let mut text =
        serde_json::to_string_pretty(&summary(scene, mesh, out)).expect("JSON of plain values");
    text.push('\n');
    write_atomic(&dir.join("summary.json"), text.as_bytes())
}
