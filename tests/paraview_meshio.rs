//! dfem's ParaView files read by an independent reader (docs/outputs.md, "ParaView
//! files"): a static scene (the `wall` example) and a dynamic one (the `sliding` example
//! with meshed blocks) are run through the `dfem` binary, then every `.vtu` that
//! `results.pvd` lists is read by meshio (Python, tests/paraview/check_vtu.py, which prints
//! JSON). Checked: the frames and times of the `.pvd`; the number of points and cells and
//! the cell types against the mesh dfem builds (triangles of the deformable blocks, one
//! polygon per rigid or fixed block, contacts as line cells); the data arrays are exactly
//! those of the table in docs/outputs.md, with its numbers of components and one value per
//! point or cell; meshio warns of nothing; and every array meshio reads (the displacements
//! among them) and the points equal those of dfem's own reader, `dfem::output::read::Vtu`,
//! bit for bit.
//!
//! The optional check of issue 8: without python3 and meshio it prints
//! "skipped: install python3-meshio" and passes (CI installs python3-meshio, .ci/run).
//! `DFEM_PYTHON` names the interpreter to use; otherwise `python3`, then `/usr/bin/python3`
//! (where Debian's python3-meshio is installed when another python3 comes first on PATH).

mod common;
use dfem::output::bench_table::Table;
use dfem::output::read::Vtu;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// A Python interpreter that imports meshio, if there is one.
fn python_with_meshio() -> Option<String> {
    let mut candidates: Vec<String> = std::env::var("DFEM_PYTHON").into_iter().collect();
    candidates.extend(["python3".to_string(), "/usr/bin/python3".to_string()]);
    candidates.into_iter().find(|py| {
        Command::new(py)
            .args(["-c", "import meshio"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn skip() {
    println!(
        "skipped: install python3-meshio (no python3 that imports meshio: tried $DFEM_PYTHON, python3, /usr/bin/python3)"
    );
}

/// The arrays docs/outputs.md documents, by file kind ("blocks", "contacts"): name →
/// (on "points" or "cells", components).
fn documented() -> BTreeMap<String, BTreeMap<String, (String, usize)>> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/outputs.md"))
            .unwrap();
    let table = Table::markdown_tables(&doc)
        .into_iter()
        .find(|t| {
            t.header
                .starts_with(&["file", "array", "on", "components"].map(String::from))
        })
        .expect("docs/outputs.md: the table of the ParaView arrays");
    let mut out: BTreeMap<String, BTreeMap<String, (String, usize)>> = BTreeMap::new();
    for r in &table.rows {
        let strip = |c: &str| c.trim_matches('`').to_string();
        let kind = strip(&r[0]).split('_').next().unwrap().to_string();
        out.entry(kind)
            .or_default()
            .insert(strip(&r[1]), (r[2].clone(), r[3].parse().unwrap()));
    }
    assert_eq!(out.len(), 2, "blocks and contacts: {out:?}");
    out
}

/// meshio's reading of every data set of `dir/results.pvd`.
fn meshio_read(py: &str, dir: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/paraview/check_vtu.py");
    let out = Command::new(py)
        .arg(&script)
        .arg(dir.join("results.pvd"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}: {}",
        script.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// What a frame must hold, from the mesh dfem builds for the scene.
struct Expected {
    points: usize,
    triangles: usize,
    /// Vertices of the polygon of each rigid or fixed block, sorted.
    polygons: Vec<usize>,
    /// Contacts of the initial configuration (`None`: a dynamic frame, whose contacts
    /// change as the blocks move).
    contacts: Option<usize>,
}

fn expected(scene_text: &str) -> Expected {
    let sc = common::scene(scene_text);
    let m = dfem::mesh::build(&sc);
    let mut polygons: Vec<usize> = m
        .blocks
        .iter()
        .filter(|b| b.dofs != dfem::mesh::BlockDofs::Deformable)
        .map(|b| b.boundary.len())
        .collect();
    polygons.sort_unstable();
    Expected {
        points: m.nodes.len(),
        triangles: m.triangles.len(),
        polygons,
        contacts: Some(m.contacts.len()),
    }
}

/// Check one data set meshio read (`ds`) against the expectations, the documented arrays
/// and dfem's own reader; returns the largest displacement (m) in it.
fn check_dataset(
    ds: &Value,
    dir: &Path,
    exp: &Expected,
    doc: &BTreeMap<String, BTreeMap<String, (String, usize)>>,
) -> f64 {
    let file = ds["file"].as_str().unwrap();
    let kind = if file.starts_with("blocks_") {
        "blocks"
    } else {
        "contacts"
    };
    let what = |s: &str| format!("{file}: {s}");
    assert_eq!(
        ds["warnings"],
        Value::Array(vec![]),
        "{}",
        what("meshio warned")
    );
    let points = ds["points"].as_u64().unwrap() as usize;
    let cells = ds["cells"].as_array().unwrap();
    let n_cells: usize = cells
        .iter()
        .map(|c| c["count"].as_u64().unwrap() as usize)
        .sum();
    if kind == "blocks" {
        assert_eq!(points, exp.points, "{}", what("points"));
        let mut triangles = 0;
        let mut polygons = Vec::new();
        for c in cells {
            let (count, nodes) = (
                c["count"].as_u64().unwrap() as usize,
                c["nodes"].as_u64().unwrap() as usize,
            );
            match c["type"].as_str().unwrap() {
                "triangle" => {
                    assert_eq!(nodes, 3);
                    triangles += count;
                }
                "polygon" => polygons.extend(std::iter::repeat_n(nodes, count)),
                t => panic!("{}", what(&format!("cell type {t}"))),
            }
        }
        polygons.sort_unstable();
        assert_eq!(triangles, exp.triangles, "{}", what("triangles"));
        assert_eq!(
            polygons,
            exp.polygons,
            "{}",
            what("polygons of the rigid and fixed blocks")
        );
    } else {
        for c in cells {
            assert_eq!(c["type"], "line", "{}", what("contact cells"));
            assert_eq!(c["nodes"], 2);
        }
        assert_eq!(points, 2 * n_cells, "{}", what("two points per contact"));
        if let Some(n) = exp.contacts {
            assert_eq!(n_cells, n, "{}", what("contacts"));
        }
        assert!(n_cells > 0, "{}", what("no contact"));
    }
    // the arrays are those documented, with their components and one value per point or cell
    let docs = &doc[kind];
    let mut found = BTreeMap::new();
    for (on, key) in [("points", "point_data"), ("cells", "cell_data")] {
        for (name, comps) in ds[key].as_object().unwrap() {
            found.insert(
                name.clone(),
                (on.to_string(), comps.as_u64().unwrap() as usize),
            );
            let rows = ds["rows"][name].as_u64().unwrap() as usize;
            let n = if on == "points" { points } else { n_cells };
            assert_eq!(rows, n, "{}", what(&format!("rows of {name}")));
        }
    }
    assert_eq!(&found, docs, "{}", what("arrays against docs/outputs.md"));
    // every array and the points: meshio's values are dfem's reader's, bit for bit (both
    // parse the same decimal strings, each to the nearest double; Python's repr gives
    // back that double exactly)
    let path = dir.join(file);
    let vtu = Vtu::read(&path).unwrap();
    let mut umax = 0.0f64;
    for (name, vals) in ds["values"].as_object().unwrap() {
        let theirs: Vec<f64> = vals
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().parse().unwrap())
            .collect();
        let ours = vtu.array(name, &path).unwrap();
        assert_eq!(theirs.len(), ours.len(), "{}", what(name));
        for (i, (a, b)) in theirs.iter().zip(ours).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "{}",
                what(&format!("{name}[{i}]: meshio {a:e}, dfem {b:e}"))
            );
        }
        if name == "displacement_m" {
            umax = ours
                .chunks(3)
                .map(|u| u[0].hypot(u[1]))
                .fold(umax, f64::max);
        }
    }
    umax
}

#[test]
fn meshio_reads_the_static_wall_as_dfem_does() {
    let Some(py) = python_with_meshio() else {
        return skip();
    };
    let dir = common::tmp_dir("paraview_meshio_wall");
    common::dfem_ok(&[
        "run",
        "--example",
        "wall",
        "--quiet",
        "--no-plots",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let read = meshio_read(&py, &dir);
    let exp = expected(dfem::scene::examples::get("wall").unwrap());
    assert!(
        exp.triangles > 0 && !exp.polygons.is_empty(),
        "deformable bricks on a fixed base"
    );
    let ds = read["datasets"].as_array().unwrap();
    // a static run: one frame at t = 0, blocks as part 0, contacts as part 1
    let listed: Vec<(&str, &str, &str)> = ds
        .iter()
        .map(|d| {
            (
                d["timestep"].as_str().unwrap(),
                d["part"].as_str().unwrap(),
                d["file"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        listed,
        [
            ("0e0", "0", "blocks_0000.vtu"),
            ("0e0", "1", "contacts_0000.vtu")
        ]
    );
    let doc = documented();
    let umax: f64 = ds
        .iter()
        .map(|d| check_dataset(d, &dir, &exp, &doc))
        .fold(0.0, f64::max);
    // under its weight the wall settles by the joints' closure: micrometres, not zero
    assert!(umax > 1e-7 && umax < 1e-3, "largest displacement {umax} m");
}

#[test]
fn meshio_reads_every_frame_of_a_dynamic_run_as_dfem_does() {
    let Some(py) = python_with_meshio() else {
        return skip();
    };
    let dir = common::tmp_dir("paraview_meshio_sliding");
    // the sliding example (dt = 0.04 s, duration 2 s, a frame every 5 steps) with the
    // block meshed, so that the blocks file holds triangles and a polygon (the incline)
    let text = dfem::scene::examples::get("sliding").unwrap().replace(
        "slope_length = 24.0",
        "slope_length = 24.0\nmesh_size = 1.0",
    );
    assert!(
        text.contains("mesh_size = 1.0")
            && text.contains("dt = 0.04")
            && text.contains("every = 5")
    );
    let scene = dir.join("sliding.toml");
    std::fs::write(&scene, &text).unwrap();
    common::dfem_ok(&[
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--no-plots",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    let out = dir.join("out");
    let read = meshio_read(&py, &out);
    let mut exp = expected(&text);
    exp.contacts = None;
    let ds = read["datasets"].as_array().unwrap();
    // frames at steps 0, 5, ..., 50 (2 s / 0.04 s = 50 steps), each with its two parts
    assert_eq!(ds.len(), 2 * 11);
    for (i, pair) in ds.chunks(2).enumerate() {
        let step = 5 * i;
        assert_eq!(pair[0]["file"], format!("blocks_{step:04}.vtu"));
        assert_eq!(pair[1]["file"], format!("contacts_{step:04}.vtu"));
        for (part, d) in pair.iter().enumerate() {
            assert_eq!(d["part"], part.to_string());
            let t: f64 = d["timestep"].as_str().unwrap().parse().unwrap();
            // t = step × dt up to the rounding of the product
            assert!(
                (t - step as f64 * 0.04).abs() <= 1e-12,
                "step {step}: t = {t}"
            );
        }
    }
    let doc = documented();
    let umax: Vec<f64> = ds
        .iter()
        .map(|d| check_dataset(d, &out, &exp, &doc))
        .collect();
    // the values compared are not trivial: the block slides g (sin 30° − cos 30° tan 25°)
    // t²/2 = 1.89 m by t = 2 s (the example's closed form); more than 1 m in the last frame
    assert!(
        umax[umax.len() - 1] > 1.0,
        "last frame: {} m",
        umax[umax.len() - 1]
    );
    // at t = 0 the block rests on the incline in its static state under its weight (the
    // joint's closure: micrometres)
    assert!(umax[0] < 1e-4, "first frame: {} m", umax[0]);
}
