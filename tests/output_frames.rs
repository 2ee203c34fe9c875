//! The ParaView frames of a dynamic run by simulated time (docs/scene-reference.md,
//! "`[output]`"): step 0, the last step, and the first step ending at or after each frame
//! time j·I, with I = max(0.02 s, duration / 500) by default, `frame_interval`, duration /
//! N for `--frames N`; or every k-th step with `every = k`. The steps expected are
//! computed here in whole numbers: with dt = 3 ms and I = p ms, frame j falls on step
//! ⌈j p / 3⌉. The files written (.vtu and the entries of results.pvd, their times) are
//! checked against them, and a run stopped between two frames resumes to the same files.

mod common;
use std::path::Path;
use std::process::Command;

/// 0.5 s at dt = 3 ms: 167 steps, the last one cut to end at 0.5 s (step_time).
const STEPS: usize = 167;

/// A rigid box sliding on a base (tan φ = 0.2) under a sine ground motion of 0.3 g, with
/// `output` (the `[output]` table).
fn scene_text(output: &str) -> String {
    common::sliding_box(output)
}

fn dfem(
    dir: &Path,
    output: &str,
    args: &[&str],
    stop_after: Option<usize>,
) -> std::process::Output {
    let f = dir.join("scene.toml");
    std::fs::write(&f, scene_text(output)).unwrap();
    let mut c = Command::new(common::dfem_bin());
    c.arg("run")
        .arg(&f)
        .arg("--out")
        .arg(dir.join("out"))
        .args(["--no-plots", "--quiet"])
        .args(args);
    if let Some(k) = stop_after {
        c.env("DFEM_STOP_AFTER_STEP", k.to_string());
    }
    c.output().unwrap()
}

/// Steps 0, ⌈j p / 3⌉ for j = 1, 2, … (frame times j·p ms at dt = 3 ms) and the last.
fn expected(p: usize) -> Vec<usize> {
    let mut k: Vec<usize> = (0..)
        .map(|j| (j * p).div_ceil(3))
        .take_while(|&k| k < STEPS)
        .collect();
    k.push(STEPS);
    k
}

/// The steps of the .vtu files in `dir`, sorted; checks that each has its contacts file.
fn vtu_steps(dir: &Path) -> Vec<usize> {
    let mut steps: Vec<usize> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            let k = name.strip_prefix("blocks_")?.strip_suffix(".vtu")?;
            Some(k.parse().unwrap())
        })
        .collect();
    steps.sort();
    for k in &steps {
        assert!(dir.join(format!("contacts_{k:04}.vtu")).exists(), "{k}");
    }
    steps
}

/// The (time, step) of the blocks entries of results.pvd, in order.
fn pvd_frames(dir: &Path) -> Vec<(f64, usize)> {
    let pvd = std::fs::read_to_string(dir.join("results.pvd")).unwrap();
    pvd.lines()
        .filter(|l| l.contains("part=\"0\""))
        .map(|l| {
            let t = l
                .split("timestep=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            let f = l
                .split("file=\"blocks_")
                .nth(1)
                .unwrap()
                .split('.')
                .next()
                .unwrap();
            (t.parse().unwrap(), f.parse().unwrap())
        })
        .collect()
}

/// The run writes exactly the frames of `steps`, listed in results.pvd at t = k dt (the
/// last one at the duration).
fn check_frames(dir: &Path, steps: &[usize]) {
    let out = dir.join("out");
    assert_eq!(vtu_steps(&out), steps);
    let listed = pvd_frames(&out);
    assert_eq!(listed.iter().map(|f| f.1).collect::<Vec<_>>(), steps);
    for &(t, k) in &listed {
        let tk = (k as f64 * 0.003).min(0.5);
        assert!((t - tk).abs() <= 1e-12, "step {k} listed at t = {t}");
    }
    let pvd = std::fs::read_to_string(out.join("results.pvd")).unwrap();
    assert_eq!(pvd.matches("part=\"1\"").count(), steps.len());
}

fn run_ok(name: &str, output: &str, args: &[&str]) -> std::path::PathBuf {
    let dir = common::tmp_dir(name);
    let o = dfem(&dir, output, args, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir
}

#[test]
fn default_frames_every_20_ms_of_simulated_time() {
    // I = max(0.02, 0.5 / 500) = 20 ms: 25 frame times after t = 0, none on a step
    // end but the last (20 j / 3 is whole only for j a multiple of 3, 60 ms = step 20)
    let dir = run_ok("frames_default", "", &[]);
    let steps = expected(20);
    assert_eq!(steps.len(), 26);
    assert_eq!(&steps[..4], &[0, 7, 14, 20]);
    check_frames(&dir, &steps);
}

#[test]
fn frame_interval_and_frames_flag_and_every() {
    // frame_interval = 0.1 s: 5 frames after t = 0
    let dir = run_ok("frames_interval", "[output]\nframe_interval = 0.1", &[]);
    check_frames(&dir, &expected(100));
    assert_eq!(expected(100), [0, 34, 67, 100, 134, 167]);
    // --frames 10: I = 50 ms, over the scene's frame_interval
    let dir = run_ok(
        "frames_flag",
        "[output]\nframe_interval = 0.1",
        &["--frames", "10"],
    );
    assert_eq!(expected(50).len(), 11);
    check_frames(&dir, &expected(50));
    // --frames finer than the steps: every step
    let dir = run_ok("frames_flag_fine", "", &["--frames", "1000"]);
    check_frames(&dir, &(0..=STEPS).collect::<Vec<_>>());
    // every = 40 (steps), as before frames by simulated time
    let dir = run_ok("frames_every", "[output]\nevery = 40", &[]);
    check_frames(&dir, &[0, 40, 80, 120, 160, STEPS]);
}

#[test]
fn default_interval_is_capped_at_500_frames() {
    // 12 s at dt = 10 ms: I = max(0.02, 12 / 500) = 24 ms, frame j on step ⌈12 j / 5⌉
    let text = scene_text("")
        .replace("duration = 0.5", "duration = 12.0")
        .replace("dt = 0.003", "dt = 0.01");
    let sc = common::scene(&text);
    let settings = sc.analysis.settings.dynamics().unwrap();
    let s = dfem::analysis::dynamics::FrameSchedule::new(settings, sc.output.frames);
    let due: Vec<usize> = (0..=1200).filter(|&k| s.due(k)).collect();
    let mut want: Vec<usize> = (0..=500).map(|j: usize| (12 * j).div_ceil(5)).collect();
    want.dedup();
    assert_eq!(due, want);
    assert_eq!(due.len(), 501);
}

#[test]
fn stopped_between_frames_resumes_to_the_same_frames() {
    let reference = run_ok("frames_resume_reference", "", &[]);
    let r = reference.join("out");
    // step 50: between the frames of steps 47 and 54
    let dir = common::tmp_dir("frames_resume");
    let o = dfem(&dir, "", &[], Some(50));
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = dir.join("out");
    let steps = expected(20);
    let before: Vec<usize> = steps.iter().copied().filter(|&k| k < 50).collect();
    // the frames up to the stop and the state reached
    assert_eq!(vtu_steps(&out), [before.clone(), vec![50]].concat());
    assert_eq!(
        pvd_frames(&out).iter().map(|f| f.1).collect::<Vec<_>>(),
        [before, vec![50]].concat()
    );
    let o = Command::new(common::dfem_bin())
        .args([
            "run",
            "--resume",
            out.to_str().unwrap(),
            "--no-plots",
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_frames(&dir, &steps);
    for f in ["results.pvd", "history.csv"] {
        assert!(
            std::fs::read(out.join(f)).unwrap() == std::fs::read(r.join(f)).unwrap(),
            "{f} differs from the uninterrupted run's"
        );
    }
}

#[test]
fn bad_frame_interval_is_an_error_at_its_line() {
    for (output, says) in [
        (
            "frame_interval = 0.0",
            "frame_interval must be a time > 0 s, not 0",
        ),
        (
            "frame_interval = -0.1",
            "frame_interval must be a time > 0 s, not -0.1",
        ),
        (
            "frame_interval = \"fast\"",
            "invalid type: string \"fast\", expected f64",
        ),
        (
            "every = 10\nframe_interval = 0.1",
            "every and frame_interval both set",
        ),
    ] {
        let dir = common::tmp_dir("frames_bad");
        let f = dir.join("scene.toml");
        let text = scene_text(&format!("[output]\n{output}"));
        std::fs::write(&f, &text).unwrap();
        let line = text
            .lines()
            .position(|l| l.starts_with("frame_interval"))
            .unwrap()
            + 1;
        let o = Command::new(common::dfem_bin())
            .args(["check", f.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{output}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        let place = format!("{}:{line}", f.display());
        assert!(stderr.contains(&place), "{output}: {place} not in {stderr}");
        assert!(stderr.contains(says), "{output}: «{says}» not in {stderr}");
        assert!(stderr.contains("fix: "), "{stderr}");
    }
}
