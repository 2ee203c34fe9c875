//! `[[import]]`: blocks read from a Gmsh mesh or a DXF drawing are the polygons drawn there,
//! and a scene that imports them gives the same analysis as the same blocks written in
//! TOML.
//!
//! The files (tests/data/import/) are written by hand, so the expected polygons are known
//! exactly: two squares stacked, the unit square "base" (meshed with five triangles around
//! its centre, one of them clockwise, and a node in the middle of its top edge) and the
//! square "top" of side 0.5 resting on it from x = 0.25 to 0.75 (one quadrangle).

mod common;
use dfem::scene::{self, Support};
use std::path::Path;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/import")
        .join(name)
}

const BASE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
const TOP: [[f64; 2]; 4] = [[0.25, 1.0], [0.75, 1.0], [0.75, 1.5], [0.25, 1.5]];

/// `got` is `want` up to a cyclic shift, every coordinate within 1e-12 m (the files hold
/// these decimal values; only parsing rounds them, to 1 ulp).
fn same_polygon(got: &[[f64; 2]], want: &[[f64; 2]]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    let found = (0..got.len()).any(|k| {
        (0..got.len()).all(|i| {
            let (g, w) = (got[(i + k) % got.len()], want[i]);
            (g[0] - w[0]).abs() < 1e-12 && (g[1] - w[1]).abs() < 1e-12
        })
    });
    assert!(found, "{got:?} is not {want:?}");
}

fn area(v: &[[f64; 2]]) -> f64 {
    dfem::geometry::polygon::signed_area(v)
}

fn stone() -> String {
    common::stone_and_dry_joint(1e9, 1e8, 0.01, 30.0)
}

#[test]
fn gmsh_4_1_and_2_2_give_the_two_squares() {
    for f in ["two_squares.msh", "two_squares_v22.msh"] {
        let b = scene::import::read(&data(f), "gmsh").unwrap();
        assert_eq!(b.len(), 2, "{f}");
        assert_eq!(
            (b[0].name.as_str(), b[0].group.as_str()),
            ("base_1", "base")
        );
        assert_eq!((b[1].name.as_str(), b[1].group.as_str()), ("top_1", "top"));
        same_polygon(&b[0].vertices, &BASE);
        same_polygon(&b[1].vertices, &TOP);
        // areas 1 and 0.25 m², counter-clockwise (positive)
        assert!((area(&b[0].vertices) - 1.0).abs() < 1e-12, "{f}");
        assert!((area(&b[1].vertices) - 0.25).abs() < 1e-12, "{f}");
    }
}

/// The scene with the import and the one with the same blocks in TOML: identical blocks,
/// and identical results (the same polygons in the same order give the same mesh and the
/// same arithmetic, so the displacements agree to the last bit; 1e-12 of the settlement
/// leaves room for nothing but rounding).
fn same_analysis(import: &str, explicit_blocks: &str) {
    let tail = "[analysis]\ntype = \"static\"\nload_steps = 2\n";
    let a = common::scene(&format!("{}{import}\n{tail}", stone()));
    let b = common::scene(&format!("{}{explicit_blocks}\n{tail}", stone()));
    assert_eq!(a.blocks.len(), b.blocks.len());
    for (x, y) in a.blocks.iter().zip(&b.blocks) {
        assert_eq!(
            (&x.name, x.support, x.material),
            (&y.name, y.support, y.material)
        );
        same_polygon(&x.vertices, &y.vertices);
    }
    let (ma, oa) = common::solve(&a);
    let (mb, ob) = common::solve(&b);
    assert_eq!(oa.status, dfem::analysis::Status::Stable);
    assert_eq!(oa.status, ob.status);
    let (ua, ra) = dfem::analysis::outcome_motion(&ma, 1, &oa);
    let (ub, rb) = dfem::analysis::outcome_motion(&mb, 1, &ob);
    // the top block settles on the joint: γ h / Eₙ × band ≈ 2e4 × 0.5 × 0.01 / 1e9 = 1e-7 m
    assert!(ua[1] < -1e-8, "{ua:?}");
    let tol = 1e-12 * ua[1].abs();
    assert!(
        (ua[0] - ub[0]).abs() <= tol && (ua[1] - ub[1]).abs() <= tol && (ra - rb).abs() <= 1e-12
    );
}

const EXPLICIT: &str = r#"
[[block]]
name = "base_1"
material = "stone"
support = "fixed"
vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
[[block]]
name = "top_1"
material = "stone"
vertices = [[0.25, 1.0], [0.75, 1.0], [0.75, 1.5], [0.25, 1.5]]
"#;

#[test]
fn an_imported_gmsh_mesh_analyses_as_the_same_blocks_in_toml() {
    let file = data("two_squares.msh");
    same_analysis(
        &format!(
            "[[import]]\nfile = \"{}\"\nmaterial = \"stone\"\nfixed = [\"base\"]\n",
            file.display()
        ),
        EXPLICIT,
    );
}

#[test]
fn group_mapping_prefix_and_kind() {
    let dir = data("two_squares_v22.msh");
    let text = format!(
        "{}[[material]]\nname = \"concrete\"\nlame_lambda = 1e10\nlame_mu = 1e10\nunit_weight = 24e3\n\
         [[import]]\nfile = \"{}\"\nname = \"w\"\nmaterial = \"stone\"\nmaterials = {{ base = \"concrete\" }}\n\
         fixed = [\"base\"]\nkind = \"rigid\"\n",
        stone(),
        dir.display()
    );
    let sc = common::scene(&text);
    let names: Vec<&str> = sc.blocks.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["w_base_1", "w_top_1"]);
    assert_eq!(sc.materials[sc.blocks[0].material].name, "concrete");
    assert_eq!(sc.materials[sc.blocks[1].material].name, "stone");
    assert_eq!(sc.blocks[0].support, Support::Fixed);
    assert_eq!(sc.blocks[1].support, Support::Free);
    assert_eq!(sc.blocks[1].kind, scene::BlockKind::Rigid);
}

#[test]
fn dxf_closed_polylines_give_the_two_squares() {
    // base: a closed LWPOLYLINE with a vertex in the middle of its bottom edge; top: a
    // POLYLINE whose last vertex repeats the first; an open LWPOLYLINE and a LINE on layer
    // "notes" are skipped
    let b = scene::import::read(&data("two_squares.dxf"), "dxf").unwrap();
    assert_eq!(b.len(), 2);
    assert_eq!(
        (b[0].name.as_str(), b[0].group.as_str()),
        ("base_1", "base")
    );
    assert_eq!((b[1].name.as_str(), b[1].group.as_str()), ("top_1", "top"));
    same_polygon(&b[0].vertices, &BASE);
    same_polygon(&b[1].vertices, &TOP);
    assert!((area(&b[0].vertices) - 1.0).abs() < 1e-12);
    assert!((area(&b[1].vertices) - 0.25).abs() < 1e-12);
}

#[test]
fn an_imported_dxf_drawing_analyses_as_the_same_blocks_in_toml() {
    let file = data("two_squares.dxf");
    same_analysis(
        &format!(
            "[[import]]\nfile = \"{}\"\nmaterial = \"stone\"\nfixed = [\"base\"]\n",
            file.display()
        ),
        EXPLICIT,
    );
}
