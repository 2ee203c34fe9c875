//! Tests of the rigid contact element in space against closed forms.

use super::*;
use crate::geometry::face_contact::tangent_frame;

/// The frame (n, t₁, t₂) of the normal n.
fn frame(n: Vec3) -> [Vec3; 3] {
    let [t1, t2] = tangent_frame(n);
    [n, t1, t2]
}

fn apply(k: &[[f64; 12]; 12], q: &[f64; 12]) -> [f64; 12] {
    let mut f = [0.0; 12];
    for (fi, row) in f.iter_mut().zip(k) {
        *fi = row.iter().zip(q).map(|(a, b)| a * b).sum();
    }
    f
}

#[test]
fn a_common_rigid_motion_strains_no_contact() {
    let (x, ca, cb) = ([0.3, 0.2, 1.0], [0.5, 0.5, 0.5], [0.4, 0.6, 1.5]);
    let b = contact_b(x, ca, cb, frame([0.0, 0.0, 1.0]));
    // the same translation and (small) rotation of both blocks about one point: each
    // block's unknowns about its own centroid, q = (v + w × (c − p), w)
    let (v, w, p) = ([0.1, -0.3, 0.2], [0.02, -0.01, 0.03], [0.0, 0.0, 0.0]);
    let about = |c: Vec3| {
        let r = [c[0] - p[0], c[1] - p[1], c[2] - p[2]];
        let wr = crate::geometry::polyhedron::cross3(w, r);
        [v[0] + wr[0], v[1] + wr[1], v[2] + wr[2], w[0], w[1], w[2]]
    };
    let mut q = [0.0; 12];
    q[..6].copy_from_slice(&about(ca));
    q[6..].copy_from_slice(&about(cb));
    for row in &b {
        let d: f64 = row.iter().zip(&q).map(|(a, b)| a * b).sum();
        assert!(d.abs() < 1e-15, "{d}");
    }
}

#[test]
fn a_block_on_four_corner_springs_has_the_closed_form_stiffness() {
    // a block 2a × 2b in plan on a fixed base, its centroid h above the contact plane,
    // kₙ at each of the four corners and kₛ in both tangents:
    // vertical 4kₙ, rocking about x 4kₙ b², about y 4kₙ a², twisting 4kₛ (a² + b²),
    // horizontal 4kₛ, with the coupling of a horizontal force at height h
    let (a, bb, h, kn, ks) = (0.5, 0.25, 0.4, 1e9, 4e8);
    let (ca, cb) = ([0.0, 0.0, -1.0], [0.0, 0.0, h]);
    let mut k = [[0.0; 12]; 12];
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let b = contact_b([sx * a, sy * bb, 0.0], ca, cb, frame([0.0, 0.0, 1.0]));
        let local = [[kn, 0.0, 0.0], [0.0, ks, 0.0], [0.0, 0.0, ks]];
        let e = contact_stiffness(&b, &local);
        for (row, erow) in k.iter_mut().zip(&e) {
            for (v, ev) in row.iter_mut().zip(erow) {
                *v += ev;
            }
        }
    }
    // block b's own 6 × 6 (block a is the base)
    let kb = |i: usize, j: usize| k[6 + i][6 + j];
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * y.abs().max(1.0);
    assert!(close(kb(2, 2), 4.0 * kn));
    assert!(close(kb(0, 0), 4.0 * ks) && close(kb(1, 1), 4.0 * ks));
    assert!(
        close(kb(3, 3), 4.0 * kn * bb * bb + 4.0 * ks * h * h),
        "{}",
        kb(3, 3)
    );
    assert!(
        close(kb(4, 4), 4.0 * kn * a * a + 4.0 * ks * h * h),
        "{}",
        kb(4, 4)
    );
    assert!(close(kb(5, 5), 4.0 * ks * (a * a + bb * bb)));
    // a translation along x and a rotation about y couple through the shear springs at
    // the lever h below the centroid
    assert!(close(kb(0, 4).abs(), 4.0 * ks * h), "{}", kb(0, 4));
    // symmetric for a symmetric local stiffness; the base's rows balance block b's
    for (i, row) in k.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert!((v - k[j][i]).abs() <= 1e-6 * kn, "{i} {j}");
        }
    }
    let mut q = [0.0; 12];
    q[8] = 1e-3; // b moves up 1 mm: the springs pull it back by 4 kₙ 10⁻³
    let f = apply(&k, &q);
    assert!(
        close(f[8], 4.0 * kn * 1e-3) && close(f[2], -4.0 * kn * 1e-3),
        "{f:?}"
    );
}
