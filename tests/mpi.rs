//! Distributed runs (cargo feature `mpi`): `mpirun -n 2 dfem run SCENE --solver petsc` on a
//! wall of 1.46 × 10⁵ unknowns, and `--solver mumps` (MUMPS' distributed input) on a wall
//! of 2.7 × 10⁴, give the serial result; each rank assembles its own rows
//! (`dfem::assembly::Ranks`). Needs `mpirun` (OpenMPI) on PATH.
#![cfg(feature = "mpi")]

mod common;
use std::path::Path;
use std::process::Command;

/// A `courses` × `bricks` running-bond wall of deformable bricks (`mesh_size` in m) under
/// its own weight, in one load step (secant iterations until the contact states settle)
/// to keep the test short.
fn wall(courses: usize, bricks: usize, mesh_size: f64) -> String {
    let text = dfem::scene::examples::get("wall").unwrap();
    assert!(text.contains("type = \"static\"\n"));
    text.replace("type = \"static\"\n", "type = \"static\"\nload_steps = 1\n")
        .replace("courses = 10", &format!("courses = {courses}"))
        .replace(
            "bricks_per_course = 5",
            &format!("bricks_per_course = {bricks}"),
        )
        .replace(
            "joint = 0.0\n",
            &format!("joint = 0.0\nmesh_size = {mesh_size}\n"),
        )
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// (displacement x, y, rotation) of every free block, from summary.json.
fn motions(v: &serde_json::Value) -> Vec<[f64; 3]> {
    v["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let d = &b["displacement"];
            [
                d[0].as_f64().unwrap(),
                d[1].as_f64().unwrap(),
                b["rotation"].as_f64().unwrap(),
            ]
        })
        .collect()
}

/// Runs `scene` serially and on 2 ranks with `solver`; checks that they agree and returns
/// the number of unknowns.
fn serial_and_two_ranks(name: &str, scene_text: &str, solver: &str) -> u64 {
    let dir = common::tmp_dir(name);
    let scene = dir.join("wall.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let bin = common::dfem_bin();
    let args = |out: &str| {
        vec![
            "run".to_string(),
            scene.to_str().unwrap().to_string(),
            "--solver".into(),
            solver.into(),
            "--no-plots".into(),
            "--quiet".into(),
            "--out".into(),
            dir.join(out).to_str().unwrap().to_string(),
        ]
    };
    let serial = Command::new(&bin).args(args("serial")).output().unwrap();
    assert!(
        serial.status.success(),
        "{}",
        String::from_utf8_lossy(&serial.stderr)
    );
    // one program per rank (MPMD), each with its own output directory, so that anything
    // rank 1 wrote would show
    let par = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", "1"])
        .arg(&bin)
        .args(args("two"))
        .args([":", "-n", "1"])
        .arg(&bin)
        .args(args("rank1"))
        .output()
        .expect("mpirun (OpenMPI) must be on PATH for the mpi tests");
    assert!(
        par.status.success(),
        "{}",
        String::from_utf8_lossy(&par.stderr)
    );
    let (s, p) = (summary(&dir.join("serial")), summary(&dir.join("two")));
    assert_eq!(s["status"], p["status"]);
    let (ms, mp) = (motions(&s), motions(&p));
    assert_eq!(ms.len(), mp.len());
    // Both runs stop their linear solves at round-off (MUMPS) or at a relative residual
    // of 1e-12 (PETSc CG; different partitions give different round-off and GAMG
    // hierarchies, so the iterates differ); the secant iterations then converge to their
    // out-of-balance tolerance from slightly different points. 1e-6 of the largest motion
    // is far above both and far below any physical difference (a brick that slides or
    // rocks moves by 1e-4 of the largest or more).
    let scale = ms.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
    let diff = ms
        .iter()
        .zip(&mp)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0, f64::max);
    eprintln!(
        "{solver}: max |serial - 2 ranks| / max |motion| = {:.2e}",
        diff / scale
    );
    assert!(diff <= 1e-6 * scale, "difference {:e} of {scale:e}", diff);
    assert_eq!(s["stats"]["processes"], 1);
    assert_eq!(p["stats"]["processes"], 2, "the run did not go on 2 ranks");
    // rank 1 reports and writes nothing: rank 0 alone writes the results
    let rank1 = dir.join("rank1");
    let written: Vec<_> = std::fs::read_dir(&rank1)
        .map(|d| d.flatten().map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert!(
        written.is_empty(),
        "rank 1 wrote {written:?} in {}",
        rank1.display()
    );
    s["stats"]["dofs"].as_u64().unwrap()
}

/// PETSc (CG + GAMG on an MPIAIJ matrix, each rank setting its own rows) on a 30 × 30
/// wall: 915 bricks, 146,384 unknowns, 17,502 dry contacts.
#[test]
fn two_ranks_give_the_serial_result() {
    let dofs = serial_and_two_ranks("mpi_wall", &wall(30, 30, 0.04), "petsc");
    assert_eq!(dofs, 146_384);
}

/// MUMPS with its distributed input (ICNTL(18) = 3: each rank gives the entries of its own
/// rows) on a 20 × 12 wall of 27,374 unknowns (a direct solve: kept smaller for CI).
#[cfg(feature = "mumps")]
#[test]
fn two_ranks_with_mumps_distributed_input_give_the_serial_result() {
    let dofs = serial_and_two_ranks("mpi_wall_mumps", &wall(20, 12, 0.05), "mumps");
    assert_eq!(dofs, 27_374);
}
