//! Geometry: polygon predicates and the touching edges between blocks.

pub mod joints;
pub mod polygon;

pub use joints::{find_joints, overlapping_pairs, JointSegment};
pub use polygon::Point;
