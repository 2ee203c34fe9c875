//! Tests of the friction disc against the plane law and its own derivative.

use super::*;
// the plane law of its tests: kₙ = 10¹¹ N/m, kₛ = 10¹⁰ N/m on 1 m², tan φ = 0.5
use crate::material::mohr_coulomb::tests::law;

#[test]
fn on_a_tangent_axis_the_disc_is_the_plane_law() {
    let m = law();
    for (committed, d) in [
        ([0.0, 0.0], [1e-6, 0.0]),
        ([0.0, 0.0], [-1e-6, 1e-5]),
        ([0.0, 0.0], [-1e-6, -4e-6]),
        ([-1e5, 4e4], [0.0, -1e-5]),
        ([-2e5, -9e4], [1e-7, 3e-6]),
    ] {
        let (f2, s2) = m.update(1.0, committed, d);
        for axis in [1, 2] {
            let mut c3 = [committed[0], 0.0, 0.0];
            let mut d3 = [d[0], 0.0, 0.0];
            c3[axis] = committed[1];
            d3[axis] = d[1];
            let (f3, s3, _) = m.update_disc(1.0, c3, [0.0; 2], d3);
            assert_eq!(s3, s2);
            assert!((f3[0] - f2[0]).abs() <= 1e-9 * f2[0].abs().max(1.0));
            assert!(
                (f3[axis] - f2[1]).abs() <= 1e-9 * f2[1].abs().max(1.0),
                "{f3:?} {f2:?}"
            );
            assert_eq!(f3[3 - axis], 0.0);
        }
    }
}

#[test]
fn a_slipping_shear_is_returned_onto_the_circle_along_the_trial() {
    let m = law();
    // Fₙ = −10⁵ N: limit 5·10⁴ N; trial shear (3, 4)·10⁴ N (|t| = 5·10⁴: on the circle,
    // sticks), then twice that (slips back to the circle in the same direction)
    let (f, s, _) = m.update_disc(1.0, [-1e5, 0.0, 0.0], [0.0; 2], [0.0, 3e-6, 4e-6]);
    assert_eq!(s, ContactState::Stick);
    assert!(
        (f[1] - 3e4).abs() < 1e-6 && (f[2] - 4e4).abs() < 1e-6,
        "{f:?}"
    );
    let (f, s, _) = m.update_disc(1.0, [-1e5, 0.0, 0.0], [0.0; 2], [0.0, 6e-6, 8e-6]);
    assert_eq!(s, ContactState::Slip);
    assert!((f[1].hypot(f[2]) - 5e4).abs() < 1e-6, "{f:?}");
    assert!((f[1] / f[2] - 0.75).abs() < 1e-12, "{f:?}");
    // in tension: open, no force
    let (f, s, _) = m.update_disc(1.0, [0.0; 3], [0.0; 2], [1e-6, 1e-6, 0.0]);
    assert_eq!((f, s), ([0.0; 3], ContactState::Open));
}

#[test]
fn a_bond_breaks_on_the_disc_as_on_the_plane() {
    let m = MohrCoulomb {
        cohesion: 2e6,
        ..law()
    };
    // under 1 MPa of compression the intact limit is 2.5 MPa: a shear of 3 MPa slips
    // and breaks the bond, after which the dry limit 0.5 MPa holds
    let (f, s, h) = m.update_disc(1.0, [-1e6, 0.0, 0.0], [0.0; 2], [0.0, 0.0, 3e-4]);
    assert_eq!((s, h), (ContactState::Slip, [1.0, 0.0]));
    assert!((f[2] - 2.5e6).abs() < 1e-6, "{f:?}");
    let (f, s, _) = m.update_disc(1.0, f, h, [0.0; 3]);
    assert_eq!(s, ContactState::Slip);
    assert!((f[2] - 0.5e6).abs() < 1e-6, "{f:?}");
}

#[test]
fn the_tangent_is_the_derivative_of_the_law() {
    let m = law();
    let committed = [-2e5, 3e4, -2e4];
    // slipping (trial shear |t| = 1.33·10⁵ N against a limit of 1.05·10⁵ N), sticking
    // (5·10⁴ N), open (Fₙ = +10⁵ N)
    for (d, state) in [
        ([-1e-7, 1e-5, 5e-6], ContactState::Slip),
        ([-1e-7, 1e-6, -1e-6], ContactState::Stick),
        ([3e-6, 1e-6, 0.0], ContactState::Open),
    ] {
        assert_eq!(m.update_disc(1.0, committed, [0.0; 2], d).1, state);
        let k = m.tangent_disc(1.0, committed, [0.0; 2], d);
        let h = 1e-12;
        for j in 0..3 {
            let (mut dp, mut dm) = (d, d);
            dp[j] += h;
            dm[j] -= h;
            let (fp, sp, _) = m.update_disc(1.0, committed, [0.0; 2], dp);
            let (fm, sm, _) = m.update_disc(1.0, committed, [0.0; 2], dm);
            assert_eq!(sp, sm, "a kink within ±h");
            for i in 0..3 {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                assert!(
                    (fd - k[i][j]).abs() <= 1e-5 * 1e11,
                    "d {d:?}: ∂F{i}/∂δ{j} = {} against {fd}",
                    k[i][j]
                );
            }
        }
    }
}
