//! Every scene of the top-level `examples/` directory runs, writes its figures, and its
//! summary is what its README says.
//!
//! Each `examples/DIR/README.md` states, for each scene `FILE.toml` of DIR, the command
//! that reproduces it (`dfem run examples/DIR/FILE.toml --out ...`) and a machine-readable
//! line with the expected summary, which this test reads, so the text and the test cannot
//! drift:
//!
//!     expect FILE.toml: { status = "failed", mode = "toppling", load_factor = [0.1, 0.3] }
//!
//! Keys (all but `status` optional): `status` (summary.json's), `mode` (the failure mode),
//! `load_factor` = [low, high], `motions` = { MOTION = [low, high] } (how many blocks of
//! the failure have that motion), `block` with `displacement` = [low, high] (the norm of
//! its displacement, m) and `rotation` = [low, high] (rad), `max_displacement` (m, every
//! free block). The figure the README shows, `examples/DIR/FILE.png`, must exist;
//! `DFEM_WRITE_FIGURES=1` copies the run's `figures/deformed.png` there (and, for a
//! dynamic run, `figures/history.png` to `FILE_history.png` where the README has one).

mod common;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The `expect FILE: {...}` lines of a README: (file name, table).
fn expectations(readme: &str) -> Vec<(String, toml::Table)> {
    readme
        .lines()
        .filter_map(|l| l.trim().strip_prefix("expect "))
        .map(|rest| {
            let (file, table) = rest
                .split_once(": ")
                .unwrap_or_else(|| panic!("an expect line needs 'FILE: {{...}}': {rest}"));
            let doc: toml::Table = format!("e = {table}")
                .parse()
                .unwrap_or_else(|e| panic!("expect {file}: not a TOML table: {e}"));
            (file.to_string(), doc["e"].as_table().unwrap().clone())
        })
        .collect()
}

fn range(t: &toml::Table, key: &str) -> Option<[f64; 2]> {
    t.get(key).map(|v| {
        let a = v
            .as_array()
            .unwrap_or_else(|| panic!("{key} must be [low, high]"));
        let f = |x: &toml::Value| x.as_float().or(x.as_integer().map(|i| i as f64)).unwrap();
        [f(&a[0]), f(&a[1])]
    })
}

fn within(what: &str, x: f64, r: [f64; 2]) {
    assert!(
        r[0] <= x && x <= r[1],
        "{what} = {x} is outside [{}, {}]",
        r[0],
        r[1]
    );
}

fn norm(v: &Value) -> f64 {
    v[0].as_f64().unwrap().hypot(v[1].as_f64().unwrap())
}

/// Check one summary against one expectation.
fn check(s: &Value, e: &toml::Table, what: &str) {
    let status = e["status"].as_str().expect("status");
    assert_eq!(s["status"], status, "{what}: {}", s["message"]);
    if let Some(mode) = e.get("mode") {
        assert_eq!(s["failure"]["mode"], mode.as_str().unwrap(), "{what}");
    }
    if let Some(r) = range(e, "load_factor") {
        within(
            &format!("{what}: load_factor"),
            s["load_factor"].as_f64().expect("a load factor"),
            r,
        );
    }
    if let Some(m) = e.get("motions") {
        for (motion, r) in m.as_table().unwrap() {
            let n = s["failure"]["blocks"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|b| b["motion"] == motion.as_str())
                .count();
            let t: toml::Table = [("r".to_string(), r.clone())].into_iter().collect();
            within(
                &format!("{what}: blocks {motion}"),
                n as f64,
                range(&t, "r").unwrap(),
            );
        }
    }
    let blocks = s["blocks"].as_array().unwrap();
    if let Some(name) = e.get("block") {
        let b = blocks
            .iter()
            .find(|b| b["name"] == name.as_str().unwrap())
            .unwrap_or_else(|| panic!("{what}: no block {name}"));
        if let Some(r) = range(e, "displacement") {
            within(&format!("{what}: |u|"), norm(&b["displacement"]), r);
        }
        if let Some(r) = range(e, "rotation") {
            within(
                &format!("{what}: rotation"),
                b["rotation"].as_f64().unwrap(),
                r,
            );
        }
    }
    if let Some(m) = e.get("max_displacement") {
        let m = m.as_float().unwrap();
        let worst = blocks
            .iter()
            .map(|b| norm(&b["displacement"]))
            .fold(0.0, f64::max);
        assert!(worst <= m, "{what}: largest |u| {worst} > {m}");
    }
}

fn nonempty(p: &Path, min: u64) {
    let len = std::fs::metadata(p)
        .unwrap_or_else(|_| panic!("{} is missing", p.display()))
        .len();
    assert!(len > min, "{} has {len} bytes", p.display());
}

#[test]
fn every_example_reproduces_its_readme() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    let index = std::fs::read_to_string(root.join("examples/README.md")).unwrap();
    let mut runs = 0;
    for dir in dirs {
        let dname = dir.file_name().unwrap().to_string_lossy().to_string();
        assert!(
            index.contains(&format!("({dname}/)")),
            "examples/README.md does not link {dname}/"
        );
        let readme = std::fs::read_to_string(dir.join("README.md"))
            .unwrap_or_else(|_| panic!("examples/{dname} has no README.md"));
        let expect = expectations(&readme);
        let mut scenes: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        scenes.sort();
        assert!(!scenes.is_empty(), "examples/{dname} has no scene");
        for scene in &scenes {
            let what = format!("examples/{dname}/{scene}");
            let e = &expect
                .iter()
                .find(|x| &x.0 == scene)
                .unwrap_or_else(|| panic!("{dname}/README.md has no 'expect {scene}: ...' line"))
                .1;
            assert!(
                readme.contains(&format!("dfem run {what} --out")),
                "{dname}/README.md does not give the command `dfem run {what} --out ...`"
            );
            let out = common::tmp_dir(&format!("examples_dir_{dname}_{scene}"));
            let t0 = std::time::Instant::now();
            let run = Command::new(common::dfem_bin())
                .current_dir(root)
                .args(["run", &what, "--quiet", "--out"])
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "{what}: {}",
                String::from_utf8_lossy(&run.stderr)
            );
            let s: Value =
                serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                    .unwrap();
            check(&s, e, &what);
            // a figure is at least a few kB (an empty plotters PNG of this size is ~ 5 kB)
            let figs = out.join("figures");
            nonempty(&figs.join("deformed.png"), 10_000);
            nonempty(&figs.join("deformed.svg"), 1_000);
            if s["analysis"] == "capacity" {
                nonempty(&figs.join("capacity_curve.png"), 10_000);
            }
            let stem = scene.trim_end_matches(".toml");
            // dynamic runs draw their displacement histories; a README may show them as
            // STEM_history.png, refreshed with the deformed figure
            if s["analysis"] == "dynamic" {
                nonempty(&figs.join("history.png"), 10_000);
                let shown = dir.join(format!("{stem}_history.png"));
                if std::env::var_os("DFEM_WRITE_FIGURES").is_some() && shown.exists() {
                    std::fs::copy(figs.join("history.png"), &shown).unwrap();
                }
            }
            let shown = dir.join(format!("{stem}.png"));
            if std::env::var_os("DFEM_WRITE_FIGURES").is_some() {
                std::fs::copy(figs.join("deformed.png"), &shown).unwrap();
            }
            nonempty(&shown, 10_000);
            assert!(
                readme.contains(&format!("({stem}.png)")),
                "{dname}/README.md does not show {stem}.png"
            );
            eprintln!(
                "{what}: {} {} ({:.1} s)",
                s["status"],
                s["message"],
                t0.elapsed().as_secs_f64()
            );
            runs += 1;
        }
        for (file, _) in &expect {
            assert!(
                scenes.contains(file),
                "{dname}/README.md expects {file}, which is not there"
            );
        }
    }
    assert!(runs >= 8, "only {runs} example scenes");
}
