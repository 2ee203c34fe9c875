//! What users see (docs/outputs.md): the figures `dfem run` draws into DIR/figures/, their
//! redrawing by `dfem plot DIR`, `--no-plots`, the `--log-json` lines, the capacity curve
//! (curve.csv and its figure) and the progress reports of the library.

mod common;
use std::path::Path;
use std::process::{Command, Output};

fn dfem(args: &[&str]) -> Output {
    Command::new(common::dfem_bin())
        .args(args)
        .output()
        .unwrap()
}

fn ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// A PNG of some substance: the signature and more than `kb` kB.
fn check_png(path: &Path, kb: u64) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
    assert!(
        bytes.len() as u64 > kb * 1024,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
}

/// The size (width, height) in pixels of the capacity curve figure.
const CURVE_PX: (u32, u32) = (900, 640);

/// A PNG whose header (IHDR, right after the signature) gives `size` (width, height).
fn check_png_size(path: &Path, size: (u32, u32)) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes[..8], PNG_SIGNATURE, "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR", "{}", path.display());
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    assert_eq!((be(16), be(20)), size, "{}", path.display());
}

/// The rows of a curve.csv after its header, which must be `header`.
fn curve_rows(csv: &str, header: &str) -> Vec<Vec<f64>> {
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(header));
    lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// `dfem plot` draws the run `run`'s capacity curve into `again` from curve.csv, byte for
/// byte as the run drew it.
fn curve_redraws_the_same(run: &Path, again: &Path) {
    let (r, a) = (run.to_str().unwrap(), again.to_str().unwrap());
    ok(&dfem(&["plot", r, "--out", a]), "plot");
    for f in ["capacity_curve.png", "capacity_curve.svg"] {
        assert!(
            std::fs::read(run.join("figures").join(f)).unwrap()
                == std::fs::read(again.join(f)).unwrap(),
            "{f} differs when redrawn"
        );
    }
}

/// An SVG; returns its text.
fn read_svg(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(text.contains("<svg"), "{}", path.display());
    text
}

/// The wall example as a capacity analysis.
fn wall_capacity() -> String {
    let text = dfem::scene::examples::get("wall").unwrap();
    assert!(text.contains("type = \"static\""));
    text.replace("type = \"static\"", "type = \"capacity\"")
}

#[test]
fn every_example_draws_its_figures_and_plot_redraws_them() {
    for (name, _, text) in dfem::scene::examples::EXAMPLES {
        let dir = common::tmp_dir(&format!("figures_{name}"));
        let d = dir.to_str().unwrap();
        // the Eindhoven walls with their push shortened (`common::example_scene`)
        let scene = common::example_scene(name, text, &dir);
        let run = match &scene {
            Some(file) => vec!["run", file.to_str().unwrap()],
            None => vec!["run", "--example", name],
        };
        ok(
            &dfem(&[run.as_slice(), &["--quiet", "--out", d]].concat()),
            name,
        );
        let figs = dir.join("figures");
        check_png(&figs.join("deformed.png"), 10);
        let svg = read_svg(&figs.join("deformed.svg"));
        // every block is filled: at least one polygon per block
        let blocks = dfem::scene::parse_str(text, None).unwrap().blocks.len();
        let polygons = svg.matches("<polygon").count();
        assert!(
            polygons >= blocks,
            "{name}: {polygons} polygons, {blocks} blocks"
        );
        assert!(svg.contains("|u| (m)"), "{name}: colour bar");
        // static examples draw no capacity curve, but for a push (the Eindhoven walls)
        let push = text.contains("push_block");
        assert_eq!(figs.join("capacity_curve.png").exists(), push, "{name}");
        if push {
            check_png_size(&figs.join("capacity_curve.png"), CURVE_PX);
        }
        // dynamic ones draw the displacement histories (history.csv), static ones none
        let dynamic = text.contains("type = \"dynamic\"");
        assert_eq!(figs.join("history.png").exists(), dynamic, "{name}");
        if dynamic {
            check_png(&figs.join("history.png"), 10);
            let svg = read_svg(&figs.join("history.svg"));
            assert!(svg.contains("ux, m") && svg.contains("uy, m"), "{name}");
            assert!(svg.contains("<polyline"), "{name}: no curve drawn");
        }
        // `dfem plot` reads the files back and draws the same figures
        let again = dir.join("again");
        let out = dfem(&["plot", d, "--out", again.to_str().unwrap()]);
        ok(&out, name);
        let redrawn: &[&str] = if dynamic {
            &["deformed.png", "deformed.svg", "history.png", "history.svg"]
        } else if push {
            &[
                "deformed.png",
                "deformed.svg",
                "capacity_curve.png",
                "capacity_curve.svg",
            ]
        } else {
            &["deformed.png", "deformed.svg"]
        };
        for f in redrawn {
            assert!(
                std::fs::read(figs.join(f)).unwrap() == std::fs::read(again.join(f)).unwrap(),
                "{name}: {f} differs when redrawn from the files"
            );
        }
        // no temporary files left behind
        for e in std::fs::read_dir(&figs).unwrap() {
            let n = e.unwrap().file_name().into_string().unwrap();
            assert!(!n.contains(".tmp"), "{name}: {n}");
        }
    }
}

#[test]
fn no_plots_draws_nothing_and_plot_draws_later() {
    let dir = common::tmp_dir("figures_no_plots");
    let d = dir.to_str().unwrap();
    ok(
        &dfem(&[
            "run",
            "--example",
            "arch",
            "--quiet",
            "--no-plots",
            "--out",
            d,
        ]),
        "run",
    );
    assert!(dir.join("summary.json").is_file());
    assert!(!dir.join("figures").exists());
    // one format, a given amplification, shown in the title
    let out = dfem(&["plot", d, "--format", "svg", "--amplification", "123"]);
    ok(&out, "plot");
    let svg = read_svg(&dir.join("figures/deformed.svg"));
    assert!(
        svg.contains("× 123"),
        "amplification missing from the title"
    );
    assert!(!dir.join("figures/deformed.png").exists());
}

#[test]
fn plot_errors_name_the_file_and_the_fix() {
    let dir = common::tmp_dir("figures_plot_errors");
    let d = dir.to_str().unwrap();
    let check = |out: Output, needle: &str| {
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "'{needle}' missing from: {err}");
        assert!(err.contains("fix:"), "{err}");
        assert!(
            !err.contains("panicked") && !err.contains("internal error"),
            "{err}"
        );
    };
    // an empty directory
    check(dfem(&["plot", d]), "summary.json");
    // a run without ParaView files
    let scene = dir.join("novtk.toml");
    let text = dfem::scene::examples::get("arch").unwrap();
    std::fs::write(&scene, format!("{text}\n[output]\nvtk = false\n")).unwrap();
    let run = dir.join("run");
    ok(
        &dfem(&[
            "run",
            scene.to_str().unwrap(),
            "--quiet",
            "--no-plots",
            "--out",
            run.to_str().unwrap(),
        ]),
        "run",
    );
    check(dfem(&["plot", run.to_str().unwrap()]), "blocks_NNNN.vtu");
    // a damaged result file
    let run2 = dir.join("run2");
    ok(
        &dfem(&[
            "run",
            "--example",
            "arch",
            "--quiet",
            "--no-plots",
            "--out",
            run2.to_str().unwrap(),
        ]),
        "run",
    );
    let vtu = run2.join("blocks_0000.vtu");
    let t = std::fs::read_to_string(&vtu).unwrap();
    std::fs::write(&vtu, t.replace("</DataArray>", "")).unwrap();
    check(dfem(&["plot", run2.to_str().unwrap()]), "blocks_0000.vtu");
    // a bad amplification
    check(
        dfem(&["plot", run2.to_str().unwrap(), "--amplification=0"]),
        "--amplification",
    );
}

#[test]
fn log_json_prints_one_parsable_line_per_increment() {
    let dir = common::tmp_dir("figures_log_json");
    let out = dfem(&[
        "run",
        "--example",
        "wall",
        "--quiet",
        "--no-plots",
        "--log-json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    ok(&out, "run");
    let err = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<serde_json::Value> = err
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        lines.len() as u64,
        summary["stats"]["increments"].as_u64().unwrap(),
        "one line per converged increment"
    );
    let mut prev_elapsed = 0.0;
    for (k, v) in lines.iter().enumerate() {
        assert_eq!(v["phase"], "gravity", "{v}");
        assert_eq!(v["increment"].as_u64(), Some(k as u64 + 1), "{v}");
        assert!(v["iterations"].as_u64().is_some(), "{v}");
        let r = v["residual"].as_f64().unwrap();
        assert!((0.0..=1e-6).contains(&r), "{v}");
        let e = v["elapsed_s"].as_f64().unwrap();
        assert!(e >= prev_elapsed, "{v}");
        prev_elapsed = e;
    }
    // gravity in equal increments up to the full self-weight
    assert_eq!(lines.last().unwrap()["load_factor"].as_f64(), Some(1.0));
    assert!((lines[0]["load_factor"].as_f64().unwrap() - 1.0 / lines.len() as f64).abs() < 1e-12);
}

#[test]
fn capacity_curve_ends_at_the_critical_load_factor() {
    let dir = common::tmp_dir("figures_capacity");
    let scene = dir.join("wall_capacity.toml");
    std::fs::write(&scene, wall_capacity()).unwrap();
    let run = dir.join("run");
    let out = dfem(&[
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--log-json",
        "--out",
        run.to_str().unwrap(),
    ]);
    ok(&out, "run");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let lambda = summary["load_factor"].as_f64().unwrap();
    assert!(lambda > 0.1, "{lambda}");
    let csv = std::fs::read_to_string(run.join("curve.csv")).unwrap();
    let rows = curve_rows(&csv, "load_factor,ux_m,uy_m,top_ux_m,top_uy_m");
    assert!(rows.len() >= 3, "{csv}");
    // the control block is the top block: its displacement twice
    assert_eq!(
        summary["curve"]["top_block"],
        summary["curve"]["control_block"]
    );
    assert!(rows.iter().all(|r| r[3..] == r[1..3]), "{csv}");
    assert_eq!(rows[0][0], 0.0, "the curve starts after gravity");
    for w in rows.windows(2) {
        assert!(w[1][0] > w[0][0], "λ increases: {csv}");
    }
    // (serde_json's default float parsing may differ from the exact value by an ulp)
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-14 * b.abs();
    let last = rows.last().unwrap()[0];
    assert!(
        same(last, lambda),
        "last λ of the curve {last} against {lambda}"
    );
    // the control block (top of the wall) moves with the lateral force (+x)
    assert!(rows.last().unwrap()[1] > rows[0][1] + 1e-7, "{csv}");
    let control = summary["curve"]["control_block"].as_str().unwrap();
    assert!(summary["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .any(|b| b["name"] == control));
    assert_eq!(summary["curve"]["file"], "curve.csv");
    // the capacity log lines: λ of each converged increment, the last one λ_c
    let err = String::from_utf8(out.stderr).unwrap();
    let cap: Vec<serde_json::Value> = err
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v["phase"] == "capacity")
        .collect();
    assert_eq!(cap.len(), rows.len() - 1);
    assert!(same(
        cap.last().unwrap()["load_factor"].as_f64().unwrap(),
        lambda
    ));
    // figures: the deformed shape shows open contacts (red) and the curve is drawn
    let figs = run.join("figures");
    check_png(&figs.join("capacity_curve.png"), 10);
    check_png_size(&figs.join("capacity_curve.png"), CURVE_PX);
    let svg = read_svg(&figs.join("capacity_curve.svg"));
    assert!(svg.contains("λ = "), "legend with the critical λ");
    assert!(
        svg.contains("(control and top)"),
        "one block, control and top"
    );
    let deformed = read_svg(&figs.join("deformed.svg"));
    assert!(
        deformed.matches("fill=\"#DC1414\"").count() > 1,
        "open contacts"
    );
    assert!(
        deformed.contains(&format!("λ = {lambda:.4}")),
        "title with λ"
    );
    // the failed wall's mechanism is outlined and counted in the legend
    assert!(
        deformed.matches("stroke=\"#C800A0\"").count() >= 2,
        "mechanism outline"
    );
    assert!(!deformed.contains("mechanism (0 blocks)"));
    // and `dfem plot` redraws the curve from curve.csv
    curve_redraws_the_same(&run, &dir.join("again"));
}

#[test]
fn progress_reports_do_not_change_the_results() {
    use dfem::analysis::progress::Recorder;
    let sc = common::scene(&wall_capacity());
    let m = dfem::mesh::build(&sc);
    let (_, silent) = common::solve(&sc);
    let mut rec = Recorder::default();
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).unwrap();
    let out = dfem::analysis::run_with(
        &sc,
        &m,
        None,
        backend.as_mut(),
        &mut rec,
        &mut dfem::analysis::dynamics::NoMonitor,
    )
    .unwrap();
    assert_eq!(out.u, silent.u);
    assert_eq!(out.load_factor, silent.load_factor);
    assert_eq!(out.capacity_curve, silent.capacity_curve);
    let phases: Vec<&str> = rec.phases.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(phases, ["gravity", "capacity"]);
    assert_eq!(rec.phases[0].1, Some(sc.analysis.load_steps));
    assert_eq!(rec.increments.len(), out.stats.increments);
    assert_eq!(rec.iterations, out.stats.iterations);
    let curve = out.capacity_curve.unwrap();
    let lambdas: Vec<f64> = rec
        .increments
        .iter()
        .filter(|i| i.0 == "capacity")
        .map(|i| i.2)
        .collect();
    let from_curve: Vec<f64> = curve.points[1..].iter().map(|p| p.load_factor).collect();
    assert_eq!(lambdas, from_curve);
    // the control block is the top-most free block
    let top = m
        .blocks
        .iter()
        .filter(|b| b.dofs != dfem::mesh::BlockDofs::Fixed)
        .map(|b| b.centroid[1])
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(m.blocks[curve.control_block].centroid[1], top);
}

/// A push draws its capacity curve too: the horizontal force on the pushed block against
/// its displacement and the top block's. The middle block of a stack of three (rigid,
/// rigid, deformable; φ = 30°) pushed 2 mm slides on the block below under the weight of
/// two blocks, W = 2 × 0.5 m² × 25 kN/m³, and carries the top block with it: the force
/// levels off at W tan φ, the top block's displacement
/// follows the pushed one's once the push slides, and `dfem plot` draws the same figure
/// from curve.csv.
#[test]
fn a_push_draws_its_capacity_curve_with_the_top_block() {
    let dir = common::tmp_dir("figures_push_curve");
    let mut scene = String::from("title = \"push\"\n");
    scene += &common::rock_and_joint(30.0);
    scene += "[[block]]\nname = \"ground\"\nmaterial = \"rock\"\nsupport = \"fixed\"\nvertices = [[-1.0, -1.0], [2.0, -1.0], [2.0, 0.0], [-1.0, 0.0]]\n";
    for (k, kind) in ["rigid", "rigid", "deformable"].iter().enumerate() {
        let (y0, y1) = (0.5 * k as f64, 0.5 * (k + 1) as f64);
        scene += &format!("[[block]]\nname = \"b{k}\"\nmaterial = \"rock\"\nkind = \"{kind}\"\nvertices = [[0.0, {y0:?}], [1.0, {y0:?}], [1.0, {y1:?}], [0.0, {y1:?}]]\n");
    }
    scene += "[analysis]\ntype = \"static\"\nload_steps = 20\npush_block = \"b1\"\npush_displacement = 2e-3\n";
    let file = dir.join("push.toml");
    std::fs::write(&file, scene).unwrap();
    let run = dir.join("run");
    ok(
        &dfem(&[
            "run",
            file.to_str().unwrap(),
            "--quiet",
            "--out",
            run.to_str().unwrap(),
        ]),
        "run",
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "stable");
    assert_eq!(summary["curve"]["control_block"], "b1");
    assert_eq!(summary["curve"]["top_block"], "b2");
    let csv = std::fs::read_to_string(run.join("curve.csv")).unwrap();
    let rows = curve_rows(
        &csv,
        "load_factor,ux_m,uy_m,force_x_N,force_y_N,moment_Nm,top_ux_m,top_uy_m",
    );
    // one row after gravity, one per increment of the push (none cut), the last at its end
    assert_eq!(summary["stats"]["load_cuts"], 0);
    assert_eq!(rows.len(), 21);
    assert_eq!(rows.last().unwrap()[0], 1.0);
    assert!((rows.last().unwrap()[1] - 2e-3).abs() < 1e-12, "{csv}");
    let w = 2.0 * 0.5 * 25e3;
    let limit = w * 30f64.to_radians().tan();
    let last = rows.last().unwrap();
    // (within the tolerance: 10⁻⁶ of a force scale, the weight and the reactions, a few
    // times the push force)
    assert!(
        common::rel_err(last[3], limit) < 1e-5,
        "{} against {limit}",
        last[3]
    );
    // the top block rides on the pushed one: the same slip, within its elastic shear
    assert!(
        (last[6] - last[1]).abs() < 1e-6 && last[6] > 1.9e-3,
        "{csv}"
    );
    let figs = run.join("figures");
    check_png_size(&figs.join("capacity_curve.png"), CURVE_PX);
    let svg = read_svg(&figs.join("capacity_curve.svg"));
    assert!(
        svg.contains("peak force") && svg.contains("(top)"),
        "legend"
    );
    curve_redraws_the_same(&run, &dir.join("again"));
}
