//! The command line as docs/outputs.md, "Command line and exit status", describes it: run, check, example, export-matrix.

mod common;
use std::process::Command;

/// A material, a joint and a fixed base block, for the scenes written here.
const BASE: &str = r#"
[[material]]
name = "stone"
lame_lambda = 1e9
lame_mu = 1e9
unit_weight = 2e4
[[joint]]
name = "j"
normal_modulus = 1e9
shear_modulus = 1e8
band = 0.01
friction_angle = 30.0
[[block]]
name = "base"
material = "stone"
support = "fixed"
vertices = [[0.0, -1.0], [4.0, -1.0], [4.0, 0.0], [0.0, 0.0]]
"#;

/// Write BASE plus `blocks` into a fresh directory; returns the directory and the file.
fn write_scene(dir: &str, file: &str, blocks: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = common::tmp_dir(dir);
    let scene = dir.join(file);
    std::fs::write(&scene, format!("{BASE}{blocks}")).unwrap();
    (dir, scene)
}

fn dfem(args: &[&str]) -> std::process::Output {
    Command::new(common::dfem_bin())
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn example_list_names_first() {
    let out = dfem(&["example", "--list"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    for n in ["incline", "wall", "arch", "tower", "slope", "tunnel"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
}

#[test]
fn run_writes_the_summary_of_interface_md() {
    let dir = common::tmp_dir("cli_run_wall");
    let out = dfem(&[
        "run",
        "--example",
        "wall",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "stable");
    assert!(v["load_factor"].is_null());
    assert!(v["failure"].is_null());
    let blocks = v["blocks"].as_array().unwrap();
    assert!(!blocks.is_empty());
    for b in blocks {
        assert!(b["name"].is_string());
        assert_eq!(b["displacement"].as_array().unwrap().len(), 2);
        assert!(b["rotation"].is_number());
        // under gravity every block of a wall on its base goes down
        assert!(b["displacement"][1].as_f64().unwrap() < 0.0);
    }
    for k in [
        "dofs",
        "contacts",
        "iterations",
        "factorizations",
        "wall_time_s",
    ] {
        assert!(v["stats"][k].is_number(), "stats.{k}");
    }
    for f in ["results.pvd", "blocks_0000.vtu", "contacts_0000.vtu"] {
        assert!(dir.join(f).metadata().unwrap().len() > 100, "{f}");
    }
    // no temporary files left behind
    for e in std::fs::read_dir(&dir).unwrap() {
        let n = e.unwrap().file_name().into_string().unwrap();
        assert!(!n.contains(".tmp"), "{n}");
    }
}

#[test]
fn check_prints_counts_of_a_file() {
    let dir = common::tmp_dir("cli_check");
    let f = dir.join("arch.toml");
    assert!(dfem(&["example", "arch", "--out", f.to_str().unwrap()])
        .status
        .success());
    let out = dfem(&["check", f.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for k in ["blocks:", "nodes:", "triangles:", "contacts:", "dofs:"] {
        assert!(text.contains(k), "{k} missing from {text}");
    }
    let dir2 = common::tmp_dir("cli_check_nothing_written");
    assert_eq!(std::fs::read_dir(&dir2).unwrap().count(), 0);
}

#[test]
fn export_matrix_writes_matrix_market() {
    let dir = common::tmp_dir("cli_export");
    let f = dir.join("wall.toml");
    assert!(dfem(&["example", "wall", "--out", f.to_str().unwrap()])
        .status
        .success());
    let mtx = dir.join("k.mtx");
    let out = dfem(&["export-matrix", f.to_str().unwrap(), mtx.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&mtx).unwrap();
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric"));
    let k = dfem_kernels::mm::read_matrix_market(&mtx).unwrap();
    // symmetric positive diagonal
    assert!(k.diagonal().iter().all(|&d| d > 0.0));
    assert!(dir.join("k.rhs.mtx").exists());
}

#[test]
fn unknown_solver_and_example_are_errors_not_panics() {
    let dir = common::tmp_dir("cli_bad");
    let out = dfem(&[
        "run",
        "--example",
        "wall",
        "--solver",
        "nope",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8(out.stderr).unwrap();
    assert!(e.contains("--solver") && e.contains("faer-cholesky"), "{e}");
    let out = dfem(&["run", "--example", "nope", "--out", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8(out.stderr).unwrap().contains("wall"));
}

#[test]
fn a_group_of_blocks_without_support_is_a_failed_result() {
    let (dir, scene) = write_scene(
        "cli_floating",
        "floating.toml",
        r#"
[[block]]
name = "on_base"
material = "stone"
vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
[[block]]
name = "lower"
material = "stone"
vertices = [[10.0, 5.0], [11.0, 5.0], [11.0, 6.0], [10.0, 6.0]]
[[block]]
name = "upper"
material = "stone"
kind = "rigid"
vertices = [[10.0, 6.0], [11.0, 6.0], [11.0, 7.0], [10.0, 7.0]]
"#,
    );
    let out = dfem(&[
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["status"], "failed");
    assert!(
        v["message"].as_str().unwrap().contains("lower, upper"),
        "{}",
        v["message"]
    );
    let motions: Vec<(String, String)> = v["failure"]["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            (
                b["name"].as_str().unwrap().to_string(),
                b["motion"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    assert!(
        motions.contains(&("lower".into(), "falling".into()))
            && motions.contains(&("on_base".into(), "none".into())),
        "{motions:?}"
    );
}

#[test]
fn clockwise_blocks_are_reversed_with_a_warning() {
    let (dir, scene) = write_scene(
        "cli_clockwise",
        "cw.toml",
        r#"
[[block]]
name = "cw"
material = "stone"
vertices = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]
"#,
    );
    let out = dfem(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("warning:") && err.contains("block 'cw'") && err.contains("clockwise"),
        "{err}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["status"], "stable");
    assert_eq!(v["warnings"].as_array().unwrap().len(), 1);
}

/// The README's first set-up command, word for word after `cargo run --release --`, run
/// in an empty directory as on a fresh machine: it writes the default scene's summary (the
/// wall stands) and its figures.
#[test]
fn readme_quick_start_writes_the_summary_and_figures() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let line = readme
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("cargo run --release -- "))
        .expect("README.md gives the main job as `cargo run --release -- ...`");
    let args: Vec<&str> = line["cargo run --release -- ".len()..]
        .split_whitespace()
        .collect();
    let k = args.iter().position(|a| *a == "--out").expect("--out DIR");
    let dir = common::tmp_dir("cli_readme");
    let out = Command::new(common::dfem_bin())
        .args(&args)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{line}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let res = dir.join(args[k + 1]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(res.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "stable", "{v}");
    for f in [
        "figures/deformed.png",
        "figures/deformed.svg",
        "blocks_0000.vtu",
    ] {
        let len = res.join(f).metadata().map(|m| m.len()).unwrap_or(0);
        assert!(len > 1000, "{f}: {len} bytes");
    }
}
