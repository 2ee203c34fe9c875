//! Ground motion as the prescribed motion of the foundation (`frame = "absolute"`) and
//! horizontal and vertical components shaking together (`ground_motion = [{..}, {..}]`).
//!
//! * A box on a base shaken by a_x and a_y together (both ramped over 0.2 s to constant
//!   values): it slides relative to the ground as a rigid-plastic block with the normal
//!   force m (g + a_y) (`common::rigid_plastic_sliding`), in both frames; with a_x alone
//!   it slides 15 % further.
//! * The absolute frame under El Centro against the same reference as the relative
//!   frame: tests/validation_dynamics.rs `block_slides_on_a_base_under_el_centro`.
//! * Before the box slips, the two frames agree to round-off: the same equations.

mod common;
use common::col;

const G: f64 = 9.81;

#[test]
fn horizontal_and_vertical_components_shake_together() {
    let mu: f64 = 0.2;
    // in g, ramped over 0.2 s: a load that jumps at t = 0 meets the sticking contacts'
    // filtered start acceleration (≈ 0) and costs the trapezoidal rule h a/2 of velocity
    let (ax, ay) = (0.5, 0.2);
    let ramp = |t: f64| (t / 0.2).min(1.0);
    let t_end: f64 = 1.0;
    let mut worst: f64 = 0.0;
    let mut ends = Vec::new();
    for frame in ["relative", "absolute"] {
        for vertical in [true, false] {
            let gm = if vertical {
                format!(
                    r#"[{{ expression = "{ax}*min(1, t/0.2)", units = "g" }}, {{ expression = "{ay}*min(1, t/0.2)", units = "g", direction = "y" }}]"#
                )
            } else {
                format!(r#"{{ expression = "{ax}*min(1, t/0.2)", units = "g" }}"#)
            };
            let text = common::box_on_base(
                mu,
                &format!(
                    "[analysis]\ntype = \"dynamic\"\ndt = 0.01\nduration = {t_end}\nground_motion = {gm}\nframe = \"{frame}\"\n"
                ),
            );
            let h = common::dynamic_history(&text);
            let ux = *col(&h, "box.ux").last().unwrap();
            let uy = *col(&h, "box.uy").last().unwrap();
            let ay_of = |t: f64| if vertical { ay * G * ramp(t) } else { 0.0 };
            let want = common::rigid_plastic_sliding(|t| ax * G * ramp(t), ay_of, mu, t_end).1;
            ends.push(ux);
            let err = common::rel_err(ux, want);
            eprintln!(
                "{frame}, vertical {vertical}: slides {ux:.5} m vs {want:.5} m, {:.3} %; stays on the base: uy = {uy:.2e} m",
                100.0 * err
            );
            worst = worst.max(err);
            // the box stays on the ground (the band's extra compression only)
            assert!(uy.abs() < 1e-4, "{uy}");
        }
    }
    // 0.5 %: the contact's elastic shear (μ m g / kₛ ~ 10⁻⁸ m) and the normal force's
    // oscillation after the vertical acceleration starts at t = 0 (damped by HHT within a
    // few steps) are far below; the vertical component changes the answer by 15 %
    assert!(worst < 0.005, "{worst}");
    // the vertical component matters: 15 % less sliding with it
    assert!(ends[0] / ends[1] < 0.9, "{ends:?}");
}

#[test]
fn frames_agree_to_round_off_before_the_box_slips() {
    // El Centro, tan φ = 0.2: the box moves with the ground until t ≈ 1.75 s
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/elcentro1940_NS_g_dt0.02.csv"
    );
    let run_in = |frame: &str| {
        common::dynamic_history(&common::box_on_base(
            0.2,
            &format!(
                r#"[analysis]
type = "dynamic"
dt = 0.005
duration = 1.7
integrator = "newmark"
ground_motion = {{ file = "{file}", format = "csv", direction = "x" }}
frame = "{frame}"
"#
            ),
        ))
    };
    let (rel, abs) = (run_in("relative"), run_in("absolute"));
    let (ur, ua) = (col(&rel, "box.ux"), col(&abs, "box.ux"));
    let (ur_max, diff) = ur.iter().zip(&ua).fold((0.0f64, 0.0f64), |(m, d), (x, y)| {
        (m.max(x.abs()), d.max((x - y).abs()))
    });
    let ground = col(&abs, "ground_ux");
    let drift = ground.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!("before slip: box relative to the ground up to {ur_max:.3e} m, frames differ by {diff:.3e} m; the foundation moved up to {drift:.3e} m");
    // the foundation moved by decimetres; the box's motion relative to it (the contact's
    // shear, then the first slip near 1.7 s) is, in the absolute frame, a difference of
    // two positions hundreds of times larger, and it agrees with the relative frame's
    // to 10⁻⁶ of itself (measured: 10⁻¹¹)
    assert!(drift > 0.05, "{drift}");
    assert!(ur_max > 1e-10, "{ur_max}");
    assert!(diff < 1e-6 * ur_max, "{diff} vs {ur_max}");
}
