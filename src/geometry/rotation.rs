//! Finite rotations of rigid blocks in space (docs/theory.md §7, Eq. R1): a block's six
//! unknowns are its centroid's translation and a rotation vector θ (rad, the axis times
//! the angle); a point x of the block moves by u = Δc + (R(θ) − I)(x − c).

use super::polyhedron::{add3, cross3, dot3, scale3, Vec3};

/// A 3 × 3 matrix, rows first.
pub type Mat3 = [[f64; 3]; 3];

/// sin θ / θ and (1 − cos θ)/θ², the coefficients of Rodrigues' formula, with their
/// series below θ = 10⁻⁴ rad (where the closed forms lose digits to cancellation).
fn coefficients(theta: f64) -> (f64, f64) {
    if theta < 1e-4 {
        let t2 = theta * theta;
        (1.0 - t2 / 6.0, 0.5 - t2 / 24.0)
    } else {
        let h = (theta / 2.0).sin() / theta;
        (theta.sin() / theta, 2.0 * h * h)
    }
}

/// Rodrigues' formula: R(θ) = I + a \[θ\]ₓ + b \[θ\]ₓ², a = sin θ/θ, b = (1 − cos θ)/θ²,
/// θ = |θ| (R1).
pub fn rotation_matrix(theta: Vec3) -> Mat3 {
    let (a, b) = coefficients(dot3(theta, theta).sqrt());
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        let mut e = [0.0; 3];
        e[i] = 1.0;
        // column i of R is R eᵢ; this is row i of Rᵀ, transposed below
        let col = add3(e, rotate_minus_identity_ab(theta, e, a, b));
        *row = col;
    }
    transpose(r)
}

/// (R(θ) − I) v (m) without forming R: a θ × v + b θ × (θ × v), exact to round-off even
/// where the rotation is tiny (no difference of nearly equal positions).
pub fn rotate_minus_identity(theta: Vec3, v: Vec3) -> Vec3 {
    let (a, b) = coefficients(dot3(theta, theta).sqrt());
    rotate_minus_identity_ab(theta, v, a, b)
}

fn rotate_minus_identity_ab(theta: Vec3, v: Vec3, a: f64, b: f64) -> Vec3 {
    let tv = cross3(theta, v);
    add3(scale3(tv, a), scale3(cross3(theta, tv), b))
}

/// The rotation vector of a rotation matrix (the inverse of [`rotation_matrix`] for
/// angles below π): angle from the trace, axis from the skew part (near π from the
/// symmetric part).
pub fn rotation_vector(r: &Mat3) -> Vec3 {
    let w = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let cos = ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0).clamp(-1.0, 1.0);
    let sin = dot3(w, w).sqrt() / 2.0;
    let theta = sin.atan2(cos);
    if theta < 1e-4 {
        // w = 2 sin θ · axis: θ axis = w/2 · θ/sin θ ≈ w/2 (1 + θ²/6)
        return scale3(w, 0.5 * (1.0 + theta * theta / 6.0));
    }
    if std::f64::consts::PI - theta > 1e-6 {
        return scale3(w, theta / (2.0 * sin));
    }
    // near π, from the symmetric part: (R + Rᵀ)/2 = cos θ I + (1 − cos θ) n nᵀ, whose
    // column k (the largest diagonal) is nₖ n
    let k = (0..3)
        .max_by(|&i, &j| r[i][i].total_cmp(&r[j][j]))
        .unwrap_or(0);
    let mut n: Vec3 = [0.0; 3];
    for (i, v) in n.iter_mut().enumerate() {
        *v = (r[i][k] + r[k][i]) / 2.0 - if i == k { cos } else { 0.0 };
    }
    // the axis's sign from the skew part (2 sin θ n), while it still has one
    let len = dot3(n, n).sqrt() * if dot3(n, w) < 0.0 { -1.0 } else { 1.0 };
    scale3(n, theta / len)
}

/// The product a b.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// The transpose.
pub fn transpose(a: Mat3) -> Mat3 {
    let mut t = [[0.0; 3]; 3];
    for (i, row) in a.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            t[j][i] = v;
        }
    }
    t
}

/// The linearized map of a block's six unknowns (Δc, θ) to the displacement of its point
/// x about its centroid c: u ≈ G q with G = [I | −[x − c]ₓ] (3 × 6), the derivative of
/// (R1) at q = 0.
pub fn point_map(x: Vec3, c: Vec3) -> [[f64; 6]; 3] {
    let r = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    // θ × r = −r × θ = −[r]ₓ θ
    [
        [1.0, 0.0, 0.0, 0.0, r[2], -r[1]],
        [0.0, 1.0, 0.0, -r[2], 0.0, r[0]],
        [0.0, 0.0, 1.0, r[1], -r[0], 0.0],
    ]
}

/// The displacement (m) of the point x of a block whose centroid c moves by `dc` (m) and
/// which turns by `theta` (rad) about it: u = Δc + (R(θ) − I)(x − c) (R1).
pub fn point_displacement(x: Vec3, c: Vec3, dc: Vec3, theta: Vec3) -> Vec3 {
    let r = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    add3(dc, rotate_minus_identity(theta, r))
}

#[cfg(test)]
#[path = "rotation_tests.rs"]
mod tests;
