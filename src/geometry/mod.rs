//! Geometry: polygon predicates and the touching edges between blocks; convex polyhedra
//! and their face-to-face contacts for three-dimensional blocks.

pub mod face_contact;
pub mod joints;
pub mod polygon;
pub mod polyhedron;
pub mod rotation;

pub use joints::{find_joints, overlapping_pairs, JointSegment};
pub use polygon::Point;
pub use polyhedron::{Polyhedron, PolyhedronDefect};

#[cfg(test)]
mod polyhedron_tests;
