//! Results that are never lost (issue 9, item 5): a dynamic run stopped by Ctrl-C
//! (SIGINT, or `DFEM_STOP_AFTER_STEP`, which takes the same path) or killed (SIGKILL)
//! leaves valid results up to its last completed step, and `dfem run --resume DIR`
//! continues it to the same results as an uninterrupted run, to the bit.
//!
//! The scene: a rigid box dropped 5 mm onto a fixed base (the contact set changes when it
//! lands: the checkpoint must carry it) and shaken by El Centro 1940 N-S with tan φ = 0.1,
//! so that it slides back and forth (slip and stick states, friction dissipation, all in
//! the state a checkpoint holds). 20 s at dt = 5 ms: 4000 steps, about a second.
//!
//! "The same results" is the strictest test there is: history.csv byte for byte (every
//! value written with 10 significant digits, of every step) and the summary's block
//! displacements and rotations as the same f64. No tolerance: the resumed run does the
//! same floating-point operations in the same order, or it is wrong.

mod common;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

const DT: f64 = 0.005;

fn scene_text(duration: f64) -> String {
    let record = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/elcentro1940_NS_g_dt0.02.csv"
    );
    format!(
        r#"title = "box dropped on a base under El Centro"
{}[[block]]
name = "base"
material = "rock"
support = "fixed"
vertices = [[-2.0, -1.0], [3.0, -1.0], [3.0, 0.0], [-2.0, 0.0]]
[[block]]
name = "box"
material = "rock"
kind = "rigid"
vertices = [[0.0, 0.005], [1.0, 0.005], [1.0, 0.5], [0.0, 0.5]]
[analysis]
type = "dynamic"
dt = {DT}
duration = {duration}
integrator = "hht"
ground_motion = {{ file = "{record}", format = "csv", direction = "x" }}
# the foundation moves (its displacement and velocity are part of the checkpoint)
frame = "absolute"
[output]
every = 40
checkpoint_every = 50
"#,
        common::rock_and_joint(5.71)
    )
}

/// The scene file, written once into `dir`.
fn scene_file(dir: &Path) -> PathBuf {
    let f = dir.join("scene.toml");
    std::fs::write(&f, scene_text(20.0)).unwrap();
    f
}

fn dfem(args: &[&str], stop_after: Option<usize>) -> Output {
    let mut c = Command::new(common::dfem_bin());
    c.args(args).arg("--no-plots").arg("--quiet");
    if let Some(k) = stop_after {
        c.env("DFEM_STOP_AFTER_STEP", k.to_string());
    }
    c.output().unwrap()
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(dir, "summary.json")).unwrap()
}

/// The uninterrupted run (once for all tests): its directory.
fn reference() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = common::tmp_dir("resume_reference");
        let scene = scene_file(&dir);
        let out = dir.join("out");
        let o = dfem(
            &[
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            None,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = summary(&out);
        assert_eq!(s["status"], "completed");
        // the box lands (a second contact set) and slides: a state worth checkpointing
        assert!(
            s["stats"]["contact_topologies"].as_u64().unwrap() >= 2,
            "{s}"
        );
        let ux = s["blocks"][0]["displacement"][0].as_f64().unwrap();
        assert!(ux.abs() > 1e-3, "the box must slide: {ux}");
        assert!(
            !out.join("checkpoint.bin").exists(),
            "a completed run leaves no checkpoint"
        );
        out
    })
}

/// Results in `dir` are valid up to the last row of history.csv: every row whole and
/// finite, consecutive time steps from t = 0, and results.pvd lists only complete .vtu
/// files up to that time. Returns the number of completed steps.
fn check_partial(dir: &Path) -> usize {
    let h = read(dir, "history.csv");
    assert!(h.ends_with('\n'), "history.csv ends with a partial row");
    let mut lines = h.lines();
    let width = lines.next().unwrap().split(',').count();
    let mut steps = 0;
    for (k, l) in lines.enumerate() {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), width, "row {k}: {l}");
        assert!(v.iter().all(|x| x.is_finite()), "row {k}: {l}");
        // t = k dt to the 10 digits written
        assert!(
            (v[0] - k as f64 * DT).abs() <= 1e-9 * (1.0 + v[0]),
            "row {k}: {l}"
        );
        steps = k;
    }
    let pvd = read(dir, "results.pvd");
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "{pvd}");
    let mut listed = 0;
    for part in pvd.split("file=\"").skip(1) {
        let name = &part[..part.find('"').unwrap()];
        let vtu = dfem::output::read::Vtu::read(&dir.join(name))
            .unwrap_or_else(|e| panic!("{name} listed in results.pvd: {e}"));
        assert!(!vtu.points(&dir.join(name)).unwrap().is_empty());
        let step: usize = name[name.find('_').unwrap() + 1..name.find('.').unwrap()]
            .parse()
            .unwrap();
        assert!(step <= steps, "{name} is past the last row, step {steps}");
        listed += 1;
    }
    assert!(listed >= 2, "{pvd}");
    steps
}

/// After `--resume`, the results are those of the uninterrupted run.
fn check_same_as_reference(dir: &Path) {
    let r = reference();
    assert!(
        read(dir, "history.csv") == read(r, "history.csv"),
        "history.csv differs from the uninterrupted run's"
    );
    let (a, b) = (summary(dir), summary(r));
    assert_eq!(a["status"], "completed");
    // serde_json reads back the f64 it wrote: equal values are equal bits
    assert_eq!(a["blocks"], b["blocks"]);
    assert_eq!(a["time"], b["time"]);
    assert_eq!(read(dir, "results.pvd"), read(r, "results.pvd"));
    assert!(!dir.join("checkpoint.bin").exists());
}

fn resume(dir: &Path) -> Output {
    dfem(&["run", "--resume", dir.to_str().unwrap()], None)
}

#[test]
fn stopped_run_is_valid_and_resumes_to_the_same_history() {
    // step 1234: between checkpoints (every 50) and between frames (every 40); step 0:
    // stopped before the first step, resumed from the initial checkpoint
    for k in [1234, 0] {
        let dir = common::tmp_dir(&format!("resume_stop_{k}"));
        let scene = scene_file(&dir);
        let out = dir.join("out");
        let o = dfem(
            &[
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            Some(k),
        );
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{stderr}");
        assert!(stderr.contains("dfem run --resume"), "{stderr}");
        assert_eq!(check_partial(&out), k);
        let s = summary(&out);
        assert_eq!(s["status"], "interrupted");
        assert!(
            (s["time"].as_f64().unwrap() - k as f64 * DT).abs() < 1e-12,
            "{s}"
        );
        assert!(
            out.join(format!("blocks_{k:04}.vtu")).exists(),
            "the state reached"
        );
        assert!(out.join("checkpoint.bin").exists());
        // the partial history is the beginning of the uninterrupted one
        let partial = read(&out, "history.csv");
        assert!(read(reference(), "history.csv").starts_with(&partial));

        let o = resume(&out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        check_same_as_reference(&out);
    }
}

/// Start the run as a child process and wait until history.csv holds the row of
/// step `step` (rows 0..=step after the header).
fn start_and_wait(scene: &Path, out: &Path, step: usize) -> std::process::Child {
    let mut child = Command::new(common::dfem_bin())
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--no-plots", "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        let n = std::fs::read_to_string(out.join("history.csv"))
            .map(|h| h.matches('\n').count())
            .unwrap_or(0);
        // complete lines only: the header and the rows of steps 0..=step
        if n > step + 1 {
            return child;
        }
        if t0.elapsed() > Duration::from_secs(120) || child.try_wait().unwrap().is_some() {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!(
                "the run did not reach step {step}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn ctrl_c_stops_after_a_step_and_resumes_to_the_same_history() {
    let dir = common::tmp_dir("resume_sigint");
    let scene = scene_file(&dir);
    let out = dir.join("out");
    let child = start_and_wait(&scene, &out, 300);
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    let k = check_partial(&out);
    assert!((300..4000).contains(&k), "stopped at step {k}");
    let s = summary(&out);
    assert_eq!(s["status"], "interrupted", "{s}");
    assert!(
        (s["time"].as_f64().unwrap() - k as f64 * DT).abs() < 1e-9,
        "{s}"
    );

    let o = resume(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_same_as_reference(&out);
}

#[test]
fn killed_run_leaves_valid_results_and_resumes_to_the_same_history() {
    let dir = common::tmp_dir("resume_sigkill");
    let scene = scene_file(&dir);
    let out = dir.join("out");
    let mut child = start_and_wait(&scene, &out, 300);
    child.kill().unwrap(); // SIGKILL: nothing of dfem runs after it
    let status = child.wait().unwrap();
    assert!(!status.success());
    let k = check_partial(&out);
    assert!((300..4000).contains(&k), "killed at step {k}");
    // the summary of the last checkpoint: status "running", the time it reached
    let s = summary(&out);
    assert_eq!(s["status"], "running", "{s}");
    let t = s["time"].as_f64().unwrap();
    let at = (t / DT).round() as usize;
    // the last checkpoint: at most 50 steps back (at k itself when killed after it)
    assert!(
        at.is_multiple_of(50) && at <= k && at + 50 >= k,
        "checkpoint at step {at}, rows {k}"
    );

    let o = resume(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_same_as_reference(&out);
}

fn assert_clear_error(o: &Output, says: &[&str]) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for s in says {
        assert!(stderr.contains(s), "'{s}' not in: {stderr}");
    }
}

#[test]
fn resume_without_a_checkpoint_or_of_another_scene_is_a_clear_error() {
    let dir = common::tmp_dir("resume_errors");
    // nothing to resume in an empty directory, nor after a completed run
    let o = resume(&dir);
    assert_clear_error(&o, &["checkpoint.bin", "no checkpoint", "without --resume"]);
    let o = resume(reference());
    assert_clear_error(&o, &["checkpoint.bin", "without --resume"]);

    // a checkpoint of a 2 s run, resumed with the 20 s scene or after the file changed
    let short = dir.join("short.toml");
    std::fs::write(&short, scene_text(2.0)).unwrap();
    let out = dir.join("out");
    let o = dfem(
        &[
            "run",
            short.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        Some(10),
    );
    assert_eq!(o.status.code(), Some(130));
    let long = scene_file(&dir);
    let o = dfem(
        &[
            "run",
            long.to_str().unwrap(),
            "--resume",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert_clear_error(&o, &["checkpoint.bin", "another scene", "without --resume"]);
    std::fs::write(&short, scene_text(2.5)).unwrap();
    let o = resume(&out);
    assert_clear_error(&o, &["checkpoint.bin", "changed", "without --resume"]);

    // a damaged checkpoint
    std::fs::write(&short, scene_text(2.0)).unwrap();
    let ck = out.join("checkpoint.bin");
    let mut bytes = std::fs::read(&ck).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&ck, &bytes).unwrap();
    let o = resume(&out);
    assert_clear_error(&o, &["checkpoint.bin", "damaged"]);
    std::fs::write(&ck, b"not a checkpoint").unwrap();
    let o = resume(&out);
    assert_clear_error(&o, &["checkpoint.bin", "not a dfem checkpoint"]);
}

/// A scene given by a relative path, with its record beside it by a relative name,
/// resumes from the same directory (the checkpoint stores the scene's absolute path;
/// the record's path, as read, differs but its samples do not).
#[test]
fn a_scene_given_by_a_relative_path_resumes() {
    let dir = common::tmp_dir("resume_relative");
    std::fs::copy(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/elcentro1940_NS_g_dt0.02.csv"
        ),
        dir.join("record.csv"),
    )
    .unwrap();
    let text = scene_text(1.0).replace(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/elcentro1940_NS_g_dt0.02.csv"
        ),
        "record.csv",
    );
    assert!(text.contains("file = \"record.csv\""));
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let run = |args: &[&str], stop: Option<usize>| {
        let mut c = Command::new(common::dfem_bin());
        c.current_dir(&dir)
            .args(args)
            .arg("--no-plots")
            .arg("--quiet");
        if let Some(k) = stop {
            c.env("DFEM_STOP_AFTER_STEP", k.to_string());
        }
        c.output().unwrap()
    };
    let o = run(&["run", "scene.toml", "--out", "out"], Some(120));
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&["run", "--resume", "out"], None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&dir.join("out"));
    assert_eq!(s["status"], "completed");
    assert!((s["time"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{s}");
}
