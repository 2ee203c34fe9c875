//! Fallout (`[analysis] fallout = true`, docs/theory.md "Fallout"): the blocks of a local
//! failure fall out of the structure and the static analysis goes on without them.
//!
//! Reference: the same structure with those blocks deleted from the scene before the
//! analysis. A fallen block is held where it stood and its contacts carry no force, so
//! the rest must reach the equilibrium of the structure without it, up to the path
//! dependence of friction (the fallout run first loads the key blocks' neighbours through
//! the failing increments, whose state is not committed): the largest displacement of a
//! remaining block must agree within 1 %, and the blocks that fell must be those the
//! analysis without fallout reports moving in its failure. Measured on examples/tunnel:
//! b34 and b44 fall out; the largest displacement of the rest, 1.74430 µm, is the
//! reference's to the six digits printed.

mod common;
use dfem::analysis::Status;

fn tunnel(fallout: bool) -> String {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tunnel/tunnel.toml"),
    )
    .unwrap();
    if fallout {
        text.replace("type = \"static\"", "type = \"static\"\nfallout = true")
    } else {
        text
    }
}

/// The largest displacement (m) of the free blocks not in `skip` (by name).
fn largest(
    sc: &dfem::scene::Scene,
    mesh: &dfem::mesh::Mesh,
    out: &dfem::analysis::Outcome,
    skip: &[String],
) -> f64 {
    (0..mesh.blocks.len())
        .filter(|&b| mesh.blocks[b].dofs != dfem::mesh::BlockDofs::Fixed)
        .filter(|&b| !skip.contains(&sc.blocks[b].name))
        .map(|b| {
            let d = dfem::analysis::outcome_motion(mesh, b, out).0;
            d[0].hypot(d[1])
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_key_blocks_of_the_tunnel_fall_out_and_the_rest_stands_as_without_them() {
    // without fallout: the key blocks' failure
    let sc = common::scene(&tunnel(false));
    let (_, failed) = common::solve(&sc);
    let Status::Failed { blocks, .. } = &failed.status else {
        panic!("the tunnel's key blocks fail: {:?}", failed.status)
    };
    let mut key: Vec<String> = blocks.iter().map(|&b| sc.blocks[b].name.clone()).collect();
    key.sort();
    // with fallout: they fall out, and the rest stands
    let sc = common::scene(&tunnel(true));
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let mut fell: Vec<String> = out
        .fallen
        .iter()
        .map(|&b| sc.blocks[b].name.clone())
        .collect();
    fell.sort();
    assert_eq!(fell, key);
    assert_eq!(out.stats.fallen_blocks, key.len());
    let with = largest(&sc, &mesh, &out, &key);
    // the reference: the scene without the key blocks
    let mut without = sc.clone();
    without.blocks.retain(|b| !key.contains(&b.name));
    let m2 = dfem::mesh::build(&without);
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).unwrap();
    let reference = dfem::analysis::run(&without, &m2, backend.as_mut()).unwrap();
    assert_eq!(reference.status, Status::Stable);
    let expect = largest(&without, &m2, &reference, &[]);
    eprintln!("fell out: {fell:?}; largest displacement {with:.5e} m, without them {expect:.5e} m");
    assert!(expect > 0.0);
    assert!(
        common::rel_err(with, expect) < 0.01,
        "{with} m against {expect} m"
    );
}

#[test]
fn a_toppling_slope_is_not_a_fallout() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/toppling_slope/phi35.toml"),
    )
    .unwrap()
    .replace("type = \"static\"", "type = \"static\"\nfallout = true");
    let (_, out) = common::solve(&common::scene(&text));
    let Status::Failed { blocks, .. } = &out.status else {
        panic!("the slope topples: {:?}", out.status)
    };
    // 14 columns move: more than a local failure
    assert!(blocks.len() > 8, "{blocks:?}");
    assert!(out.fallen.is_empty());
}

/// The blocks that fell under gravity stay out for the capacity search that follows: the
/// rock mass without its key blocks has a lateral capacity (measured λ = 0.1486), where
/// without fallout the analysis stops under gravity.
#[test]
fn a_capacity_search_goes_on_without_the_fallen_blocks() {
    let text = tunnel(true).replace("type = \"static\"", "type = \"capacity\"");
    let sc = common::scene(&text);
    let (_, out) = common::solve(&sc);
    let lambda = out.load_factor.expect("a critical load factor");
    let fell: Vec<&str> = out
        .fallen
        .iter()
        .map(|&b| sc.blocks[b].name.as_str())
        .collect();
    eprintln!("fell out: {fell:?}; λ = {lambda}");
    assert_eq!(fell.len(), 2, "{fell:?}");
    assert!(lambda > 0.05 && lambda < 1.0, "λ = {lambda}");
}
