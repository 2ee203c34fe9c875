//! Unit tests of the dynamic driver's helpers.

use super::*;

#[test]
#[allow(clippy::needless_range_loop)]
fn inverse_of_the_elastic_matrix() {
    let d = crate::material::elastic_matrix(56e9, 21e9, crate::scene::Plane::Strain);
    let c = invert3(d);
    for i in 0..3 {
        for j in 0..3 {
            let p: f64 = (0..3).map(|k| d[i][k] * c[k][j]).sum();
            assert!(
                (p - f64::from(u8::from(i == j))).abs() < 1e-12,
                "{i} {j} {p}"
            );
        }
    }
}

#[test]
fn family_members() {
    assert_eq!(Scheme::hht(0.0), Scheme::newmark());
    // generalized-α with ρ∞ = 1 is the trapezoidal rule at the mid-point
    let g = Scheme::generalized_alpha(1.0);
    assert!((g.alpha_m - 0.5).abs() < 1e-15 && (g.alpha_f - 0.5).abs() < 1e-15);
    assert!((g.gamma - 0.5).abs() < 1e-15 && (g.beta - 0.25).abs() < 1e-15);
    // ρ∞ = 0: asymptotic annihilation, γ = 3/2, β = 1
    let g = Scheme::generalized_alpha(0.0);
    assert!((g.gamma - 1.5).abs() < 1e-15 && (g.beta - 1.0).abs() < 1e-15);
}
