//! The same scene gives bit-identical results with `--threads 1` and `--threads 2`, and
//! across repeated runs (docs/outputs.md, "Command line and exit status": "Results do not depend on it").

mod common;
use std::process::Command;

fn run(example: &str, threads: usize, tag: &str) -> std::path::PathBuf {
    let dir = common::tmp_dir(&format!("det_{example}_{tag}"));
    let st = Command::new(common::dfem_bin())
        .args([
            "run",
            "--example",
            example,
            "--quiet",
            "--threads",
            &threads.to_string(),
            "--out",
        ])
        .arg(&dir)
        .status()
        .unwrap();
    assert!(st.success());
    dir
}

/// summary.json without the wall time and the peak memory, the things allowed to differ.
fn summary(dir: &std::path::Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    v["stats"]["wall_time_s"] = serde_json::Value::Null;
    v["stats"]["peak_memory_mb"] = serde_json::Value::Null;
    v
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    // column: deformable drums whose interiors the default solver condenses out
    for example in ["wall", "arch", "tunnel", "column"] {
        let a = run(example, 1, "t1");
        let b = run(example, 2, "t2");
        let c = run(example, 2, "t2again");
        assert_eq!(
            summary(&a),
            summary(&b),
            "{example}: summary differs between 1 and 2 threads"
        );
        assert_eq!(
            summary(&b),
            summary(&c),
            "{example}: summary differs between runs"
        );
        for f in ["blocks_0000.vtu", "contacts_0000.vtu", "results.pvd"] {
            let (x, y) = (
                std::fs::read(a.join(f)).unwrap(),
                std::fs::read(b.join(f)).unwrap(),
            );
            assert!(x == y, "{example}: {f} differs between 1 and 2 threads");
        }
    }
}

/// A dynamic run whose steps take tangent steps (GMRES on the secant factorization,
/// docs/theory.md §5) on the condensed drums of the `column` example: 0.2 s of a 0.15 g,
/// 5 Hz sine, through the drums' first rocking impact. Its history and summary are the same
/// bits on 1 and 2 threads.
#[test]
fn a_dynamic_run_with_tangent_steps_gives_the_same_bits() {
    let dir = common::tmp_dir("det_column_dynamic");
    let scene = dir.join("column_dynamic.toml");
    std::fs::write(
        &scene,
        dfem::scene::examples::drum_column(
            0.05,
            "[analysis]\ntype = \"dynamic\"\ndt = 0.005\nduration = 0.2\n\
             ground_motion = { expression = \"0.15*sin(31.4*t)\", units = \"g\" }\n",
        ),
    )
    .unwrap();
    let run_scene = |threads: usize| {
        let out = dir.join(format!("t{threads}"));
        let st = Command::new(common::dfem_bin())
            .args([
                "run",
                "--quiet",
                "--no-plots",
                "--threads",
                &threads.to_string(),
            ])
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success());
        out
    };
    let (a, b) = (run_scene(1), run_scene(2));
    let s = summary(&a);
    assert!(
        s["stats"]["reused_factorizations"].as_u64().unwrap() > 0,
        "no tangent step taken"
    );
    assert_eq!(s, summary(&b), "summary differs between 1 and 2 threads");
    assert!(
        std::fs::read(a.join("history.csv")).unwrap()
            == std::fs::read(b.join("history.csv")).unwrap(),
        "history.csv differs between 1 and 2 threads"
    );
}
