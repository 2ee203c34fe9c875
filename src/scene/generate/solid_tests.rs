//! Tests of the solid blocks: each a valid convex polyhedron, their volume the plane
//! blocks' area times the depth, and their face contacts those of the plane blocks in
//! every ring plus one between each block and its neighbour in the next ring.

use super::super::common::signed_area;
use super::super::testutil::run;
use super::*;
use crate::geometry::face_contact::find_face_contacts;
use crate::geometry::find_joints;

/// Every solid block passes the checks; the volumes add up to the plane area times the
/// depth; and the face contacts are, in each ring, the plane blocks' touching edges
/// (found by the two-dimensional search), and between rings one per block.
fn check(blocks: &[GeneratedBlock], depth: f64, rings: usize) {
    let solid = extrude(blocks, depth, rings);
    let area: f64 = blocks.iter().map(|b| signed_area(&b.vertices)).sum();
    let mut volume = 0.0;
    for s in &solid {
        let size = s.block.size();
        assert_eq!(s.block.check(1e-9 * size), Ok(()), "{}", s.name);
        volume += s.block.mass_properties().volume;
    }
    assert!(
        (volume / (area * depth) - 1.0).abs() < 1e-12,
        "{volume} vs {}",
        area * depth
    );
    let plane: Vec<Vec<[f64; 2]>> = blocks.iter().map(|b| b.vertices.clone()).collect();
    // touching pairs of plane blocks (a pair may touch along several edges)
    let joints = find_joints(&plane, 1e-6);
    let fixed = blocks.iter().filter(|b| b.fixed).count();
    let free = blocks.len() - fixed;
    let contacts = find_face_contacts(
        &solid.iter().map(|s| s.block.clone()).collect::<Vec<_>>(),
        1e-6,
        1e-6,
    );
    // a joint between two free blocks is in every ring; one with a fixed block (one prism
    // through the depth) is met by each ring of the free block
    let per_ring = joints.len();
    let between = if rings > 1 { (rings - 1) * free } else { 0 };
    eprintln!(
        "{} plane blocks ({fixed} fixed), {} joints; {} solid blocks, {} face contacts",
        blocks.len(),
        per_ring,
        solid.len(),
        contacts.len()
    );
    assert_eq!(
        contacts.len(),
        per_ring * rings + between,
        "{} blocks, {rings} rings",
        blocks.len()
    );
}

#[test]
fn a_wall_made_solid_is_its_bricks_through_its_thickness() {
    let wall = run("wall", "courses = 6\nbricks_per_course = 4");
    check(&wall, 0.25, 1);
}

#[test]
fn a_barrel_vault_is_the_arch_in_rings() {
    let arch = run("arch", "voussoirs = 9\npier_courses = 2");
    check(&arch, 1.5, 3);
}
