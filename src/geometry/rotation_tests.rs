//! Tests of the finite rotations against closed forms.

use super::*;
use crate::geometry::polyhedron::norm3;

fn det(a: &Mat3) -> f64 {
    dot3(a[0], cross3(a[1], a[2]))
}

#[test]
fn a_quarter_turn_about_z_takes_x_to_y() {
    let r = rotation_matrix([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    let x = [1.0, 0.0, 0.0];
    let y: Vec<f64> = (0..3).map(|i| dot3(r[i], x)).collect();
    assert!(
        (y[0]).abs() < 1e-15 && (y[1] - 1.0).abs() < 1e-15 && y[2].abs() < 1e-15,
        "{y:?}"
    );
}

#[test]
fn rotation_matrices_are_proper_orthogonal_and_invert_to_their_vector() {
    for theta in [
        [0.3, -0.2, 0.9],
        [1e-9, 2e-9, -1e-9],
        [2.0, 1.0, -0.5],
        [0.0, 0.0, 0.0],
        [0.0, 3.1, 0.0],
        // within 10⁻⁷ rad of a half turn, about an axis with a negative component
        scale3(
            [-1.0, 2.0, 0.5],
            (std::f64::consts::PI - 1e-7) / 5.25f64.sqrt(),
        ),
    ] {
        let r = rotation_matrix(theta);
        let i = mul(&r, &transpose(r));
        for (a, row) in i.iter().enumerate() {
            for (b, v) in row.iter().enumerate() {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{theta:?}: R Rᵀ = {i:?}");
            }
        }
        assert!((det(&r) - 1.0).abs() < 1e-14);
        let back = rotation_vector(&r);
        let scale = norm3(theta).max(1e-300);
        assert!(
            norm3(sub(back, theta)) <= 1e-12 * scale.max(1e-9) + 1e-20,
            "{theta:?} → {back:?}"
        );
    }
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[test]
fn a_tiny_rotation_moves_a_point_without_cancellation() {
    // θ = 10⁻¹² rad about z moves (1, 0, 0) by (−θ²/2, θ, 0) to round-off of that motion,
    // not of the point's coordinates (a difference R x − x would keep no digit of θ²/2)
    let theta = [0.0, 0.0, 1e-12];
    let u = rotate_minus_identity(theta, [1.0, 0.0, 0.0]);
    assert!((u[1] - 1e-12).abs() <= 1e-27, "{u:?}");
    assert!((u[0] + 0.5e-24).abs() <= 1e-39, "{u:?}");
}

#[test]
fn the_point_map_is_the_derivative_of_the_finite_motion() {
    let (x, c) = ([0.7, -0.2, 1.3], [0.1, 0.4, 0.5]);
    let g = point_map(x, c);
    let h = 1e-7;
    for j in 0..6 {
        let mut q = [0.0; 6];
        q[j] = h;
        let u = point_displacement(x, c, [q[0], q[1], q[2]], [q[3], q[4], q[5]]);
        for i in 0..3 {
            // second order in h: |x − c| h² ≈ 10⁻¹⁴
            assert!(
                (u[i] / h - g[i][j]).abs() < 1e-6,
                "G[{i}][{j}] = {} against {}",
                g[i][j],
                u[i] / h
            );
        }
    }
}

#[test]
fn a_finite_rotation_keeps_distances() {
    let (c, theta) = ([0.0, 0.0, 0.0], [0.4, 1.1, -0.7]);
    let (p, q) = ([1.0, 2.0, 3.0], [-0.5, 0.3, 0.9]);
    let up = point_displacement(p, c, [0.2, 0.0, -0.1], theta);
    let uq = point_displacement(q, c, [0.2, 0.0, -0.1], theta);
    let before = norm3(sub(p, q));
    let after = norm3(sub(add3(p, up), add3(q, uq)));
    assert!((before - after).abs() < 1e-14, "{before} {after}");
}
