//! Contact generation on a running-bond wall (issue: foundation).
//!
//! C courses of bricks L × h, n bricks per course: odd courses (from the bottom) hold n
//! full bricks, even courses half + (n − 1) full + half = n + 1 pieces, so
//! * head joints: Σ_k (pieces_k − 1), each h long;
//! * bed joints between two courses: the breakpoints of both courses interleave
//!   ((n − 1) + n interior ones), giving 2n touching pairs, L/2 long each;
//! * the bottom course on the fixed base: n pairs.
//!
//! Every touching pair must be found once, and the tributary areas of each pair's contacts
//! must add up to its joint length × thickness.

mod common;

const C: usize = 6;
const N: usize = 5;
const L: f64 = 0.4;
const H: f64 = 0.2;
const T: f64 = 0.25;

fn scene(kind: &str) -> String {
    format!(
        r#"
[model]
thickness = {T}
[[material]]
name = "brick"
lame_lambda = 2e9
lame_mu = 2e9
unit_weight = 18e3
[[joint]]
name = "mortar"
normal_modulus = 5e9
shear_modulus = 2e9
band = 0.01
friction_angle = 31.0
[[generate]]
type = "wall"
material = "brick"
kind = "{kind}"
courses = {C}
bricks_per_course = {N}
brick_length = {L}
brick_height = {H}
"#
    )
}

fn check(kind: &str, mesh_size: Option<f64>) {
    let mut text = scene(kind);
    if let Some(h) = mesh_size {
        text = text.replace("kind = ", &format!("mesh_size = {h}\nkind = "));
    }
    let sc = common::scene(&text);
    let m = dfem::mesh::build(&sc);
    let pieces: Vec<usize> = (0..C).map(|k| if k % 2 == 0 { N } else { N + 1 }).collect();
    let heads: usize = pieces.iter().map(|p| p - 1).sum();
    let expected_pairs = heads + (C - 1) * 2 * N + N;
    let mut pairs: Vec<(u32, u32)> = m
        .segments
        .iter()
        .map(|s| (s.a as u32, s.b as u32))
        .collect();
    pairs.sort();
    pairs.dedup();
    assert_eq!(
        pairs.len(),
        m.segments.len(),
        "a pair of blocks must touch along one stretch"
    );
    assert_eq!(pairs.len(), expected_pairs, "touching pairs");
    // tributary areas add up to the joint length × thickness, pair by pair
    let mut area = vec![0.0; m.segments.len()];
    for c in &m.contacts {
        area[c.segment as usize] += c.length * sc.model.thickness;
    }
    for (k, s) in m.segments.iter().enumerate() {
        let exact = s.length() * T;
        assert!(
            (area[k] - exact).abs() < 1e-12 * exact.max(1.0),
            "segment {k}: {} vs {exact}",
            area[k]
        );
        let horizontal = s.normal[0].abs() < 1e-12;
        let l = if horizontal { L / 2.0 } else { H };
        // bed joints on the base are full bricks long
        let on_base = sc.blocks[s.a].support == dfem::scene::Support::Fixed
            || sc.blocks[s.b].support == dfem::scene::Support::Fixed;
        let l = if on_base { L } else { l };
        assert!(
            (s.length() - l).abs() < 1e-12,
            "segment {k} is {} m long, expected {l}",
            s.length()
        );
    }
    let total: f64 = area.iter().sum();
    let exact = (heads as f64 * H + C as f64 * N as f64 * L) * T;
    assert!((total - exact).abs() < 1e-12 * exact);
    // without a mesh size every contact sits at a corner of one of the two blocks: two per
    // head joint, two per bed stretch
    if mesh_size.is_none() {
        assert_eq!(m.contacts.len(), 2 * expected_pairs);
    }
}

#[test]
fn running_bond_wall_rigid() {
    check("rigid", None);
}

#[test]
fn running_bond_wall_deformable() {
    check("deformable", None);
}

#[test]
fn running_bond_wall_refined_keeps_pairs_and_areas() {
    check("deformable", Some(0.05));
}

/// Blocks `[x0, y0, x1, y1]` (rigid, m) on a fixed base 3 m wide, with the rock of
/// [`common::rock_and_joint`] (band h = 0.01 m).
fn blocks_on_base(boxes: &[[f64; 4]]) -> dfem::mesh::Mesh {
    let mut text = common::rock_and_joint(30.0);
    text += r#"
[[block]]
name = "base"
material = "rock"
support = "fixed"
vertices = [[-0.5, -0.5], [2.5, -0.5], [2.5, 0.0], [-0.5, 0.0]]
"#;
    for (k, b) in boxes.iter().enumerate() {
        text += &format!(
            "[[block]]\nname = \"b{k}\"\nmaterial = \"rock\"\nkind = \"rigid\"\nvertices = [[{0}, {1}], [{2}, {1}], [{2}, {3}], [{0}, {3}]]\n",
            b[0], b[1], b[2], b[3]
        );
    }
    text += "[contacts]\njoint = \"j\"\ntolerance = 1e-6\n[analysis]\ntype = \"static\"\n";
    dfem::mesh::build(&common::scene(&text))
}

/// The dynamic driver's search for new contacts (`mesh::contacts::search`)
/// finds none where joints cross: in a stack-bond 2 × 2 group of blocks, the blocks
/// diagonal to each other touch only at the crossing, where their neighbours' contacts
/// already hold them apart (a corner-to-corner contact there has no side along the
/// edge, so no tributary length, and its normal is whichever edge came nearest: in the
/// jointed rock of the `tunnel` example, 184 such contacts at the first step opened and
/// closed as the rock shook). Before the rule the search returned the two diagonal
/// pairs, one contact each.
#[test]
fn no_new_contact_between_blocks_that_meet_only_where_joints_cross() {
    let m = blocks_on_base(&[
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 0.0, 2.0, 1.0],
        [0.0, 1.0, 1.0, 2.0],
        [1.0, 1.0, 2.0, 2.0],
    ]);
    let still = vec![[0.0; 2]; m.nodes.len()];
    let found = dfem::mesh::contacts::search(&m, &still, 0.01, 0.01);
    let pairs: Vec<(u32, u32)> = found
        .iter()
        .map(|f| (f.contact.block_l, f.contact.block_m))
        .collect();
    assert!(pairs.is_empty(), "new contacts between {pairs:?}");
}

/// The rule keeps the corners that land square on a block of the same width: a box
/// 1 mm above a block whose top edge ends where the box's bottom does, falling at
/// 1 m/s, is found at both bottom corners, each with half of the bottom side (0.5 m),
/// 1 mm open.
#[test]
fn a_block_landing_square_on_another_is_found_at_both_corners() {
    let m = blocks_on_base(&[[0.0, 0.0, 1.0, 1.0], [0.0, 1.001, 1.0, 2.001]]);
    let top = 2; // the base is block 0
    let vel: Vec<[f64; 2]> = (0..m.nodes.len())
        .map(|n| {
            let on_top = m.blocks[top].nodes.contains(&(n as u32));
            if on_top {
                [0.0, -1.0]
            } else {
                [0.0, 0.0]
            }
        })
        .collect();
    let found = dfem::mesh::contacts::search(&m, &vel, 0.01, 0.01 + 2.0 * 0.01);
    let between: Vec<_> = found
        .iter()
        .filter(|f| {
            let (l, b) = (f.contact.block_l, f.contact.block_m);
            (l.min(b), l.max(b)) == (1, 2)
        })
        .collect();
    assert_eq!(between.len(), 2, "{found:?}");
    for f in between {
        assert!((f.contact.length - 0.5).abs() < 1e-9, "{f:?}");
        assert!((f.gap - 0.001).abs() < 1e-9, "{f:?}");
    }
}
