//! The contact element between two rigid blocks in space (docs/theory.md §7, Eq. R2): a
//! contact point x with its frame (n, t₁, t₂) joins block a (centroid cₐ) to block b
//! (centroid c_b), each with six unknowns q = (Δc, θ). The relative displacement of b
//! against a in the contact's frame is
//!
//!   d = Tᵀ (G(x, c_b) q_b − G(x, cₐ) qₐ) = B [qₐ; q_b],   T = [n t₁ t₂]   (R2)
//!
//! with G the point map of src/geometry/rotation.rs, and the element stiffness is Bᵀ K B
//! (12 × 12) with K the law's 3 × 3 local stiffness (diagonal sticking, the friction
//! disc's tangent (K7) slipping).

use crate::geometry::polyhedron::{dot3, Vec3};
use crate::geometry::rotation::point_map;

/// B of (R2): the 3 × 12 map from the two blocks' unknowns (a's six, then b's) to the
/// relative displacement (normal, tangent 1, tangent 2; m) of b against a at `x`.
pub fn contact_b(x: Vec3, ca: Vec3, cb: Vec3, frame: [Vec3; 3]) -> [[f64; 12]; 3] {
    let (ga, gb) = (point_map(x, ca), point_map(x, cb));
    let mut b = [[0.0; 12]; 3];
    for (row, axis) in b.iter_mut().zip(frame) {
        for j in 0..6 {
            let column = |g: &[[f64; 6]; 3]| dot3(axis, [g[0][j], g[1][j], g[2][j]]);
            row[j] = -column(&ga);
            row[6 + j] = column(&gb);
        }
    }
    b
}

/// The element stiffness Bᵀ K B (N/m, N, N·m: rows and columns a's six unknowns then
/// b's) of a contact with local stiffness `k` (N/m; rows normal, tangent 1, tangent 2).
pub fn contact_stiffness(b: &[[f64; 12]; 3], k: &[[f64; 3]; 3]) -> [[f64; 12]; 12] {
    let mut kb = [[0.0; 12]; 3];
    for i in 0..3 {
        for j in 0..12 {
            kb[i][j] = (0..3).map(|m| k[i][m] * b[m][j]).sum();
        }
    }
    let mut out = [[0.0; 12]; 12];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|m| b[m][i] * kb[m][j]).sum();
        }
    }
    out
}

#[cfg(test)]
#[path = "rigid3d_tests.rs"]
mod tests;
