//! Resource limits (issue 9): the peak memory goes into summary.json, the up-front
//! estimate (`dfem check`, src/resources.rs) covers the measured peak without
//! overstating it much, and a scene whose estimate exceeds the limit is refused before
//! the analysis with the estimate in the message.

mod common;
use std::process::Command;

fn dfem(args: &[&str]) -> std::process::Output {
    Command::new(common::dfem_bin())
        .args(args)
        .output()
        .unwrap()
}

/// The built-in wall example with `n` courses of `n` bricks of the given kind.
fn wall(n: usize, kind: &str, mesh_size: Option<f64>) -> String {
    let text = String::from_utf8(dfem(&["example", "wall"]).stdout).unwrap();
    let mut extra = format!("kind = \"{kind}\"\n");
    if let Some(h) = mesh_size {
        extra.push_str(&format!("mesh_size = {h}\n"));
    }
    text.replace("courses = 10", &format!("courses = {n}"))
        .replace("bricks_per_course = 5", &format!("bricks_per_course = {n}"))
        .replace("joint = 0.0\n", &format!("joint = 0.0\n{extra}"))
}

/// `dfem check`'s estimate (MB) and `dfem run`'s measured peak (MB) of a scene.
fn estimate_and_peak(name: &str, text: &str) -> (f64, f64) {
    let dir = common::tmp_dir(name);
    let file = dir.join("scene.toml");
    std::fs::write(&file, text).unwrap();
    let check = dfem(&["check", file.to_str().unwrap()]);
    assert!(check.status.success());
    let stdout = String::from_utf8(check.stdout).unwrap();
    let line = stdout
        .lines()
        .find(|l| l.starts_with("estimated memory"))
        .expect("dfem check prints the estimate");
    let est: f64 = line
        .split(": ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("a number of MB");
    let out = dir.join("out");
    let run = dfem(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--no-plots",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let peak = v["stats"]["peak_memory_mb"]
        .as_f64()
        .expect("peak_memory_mb in the summary (Linux)");
    assert!(v["stats"]["factor_nnz"].as_u64().unwrap() > 0);
    (est, peak)
}

#[test]
fn memory_estimate_covers_the_measured_peak() {
    // The estimate must not be below the peak (a refused scene would then be one that
    // fits, an accepted one could be killed), and should not overstate it by more than
    // 3× (the factor's fill is the uncertain part: FILL = 8 against 3.3–6.4 measured).
    for (name, text) in [
        ("memory_rigid", wall(30, "rigid", None)),
        ("memory_deformable", wall(12, "deformable", Some(0.1))),
    ] {
        let (est, peak) = estimate_and_peak(name, &text);
        eprintln!("{name}: estimate {est:.0} MB, measured peak {peak:.1} MB");
        // `dfem check` does not start PETSc/MPI, whose initialisation (shared-memory
        // segments, libraries touched) `dfem run` pays in the builds with those backends:
        // there the check's estimate may fall short of the run's peak by that much
        let slack = if cfg!(any(feature = "petsc", feature = "mpi")) {
            15.0
        } else {
            0.0
        };
        assert!(
            est + slack >= peak && est <= 3.0 * peak,
            "{name}: {est} against {peak}"
        );
    }
}

#[test]
fn a_scene_over_the_memory_limit_is_refused_with_the_estimate() {
    let dir = common::tmp_dir("memory_refused");
    let file = dir.join("wall.toml");
    std::fs::write(&file, wall(30, "rigid", None)).unwrap();
    let out = dir.join("out");
    let run = dfem(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--memory-limit",
        "5",
    ]);
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(err.contains("would need about"), "{err}");
    assert!(err.contains("wall.toml"), "names the file: {err}");
    assert!(err.contains("rigid"), "gives a fix: {err}");
    assert!(!err.contains("panicked"), "{err}");
    // refused before anything was written
    assert!(!out.join("summary.json").exists());
    // a limit that is not a number of MB is an error too
    let bad = dfem(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--memory-limit",
        "-1",
    ]);
    assert_eq!(bad.status.code(), Some(2));
}
