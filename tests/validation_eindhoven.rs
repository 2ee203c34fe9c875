//! The Eindhoven shear wall J4D (Raijmakers and Vermeltfoort 1992; BENCHMARKS.md V8), the
//! built-in example `eindhoven`: 990 × 992 mm of expanded bricks (210 × 52 mm bricks,
//! 10 mm joints, 16 free courses between a fixed base and a rigid steel beam), softening
//! joints with the Lourenço and Rots (1997) data of BENCHMARKS.md V8 (kₙ = 82 N/mm³,
//! kₛ = 36 N/mm³, fₜ = 0.25 N/mm², G_f^I = 0.018 N/mm, c = 0.35 N/mm², tan φ = 0.75,
//! G_f^II = 0.125 N/mm; the numbers could not be checked against the papers with the
//! tools at hand, they are taken from BENCHMARKS.md as given), pre-compression
//! 0.30 N/mm² (29.7 kN), the beam pushed 4 mm with its rotation and vertical motion held.
//!
//! What is checked:
//! * the load is followed through a peak and down the softening branch;
//! * at the end the wall slides along a bed joint whose cohesion is spent: the load is
//!   tan φ × the normal force on that joint, i.e. tan φ (P + R) with R the vertical force
//!   the beam adds (the reaction of the held vertical motion), up to the weight of the
//!   bricks above the sliding joint (at most the whole wall's 1.77 kN, × tan φ = 1.3 kN);
//! * the peak against the experiment: Lourenço (1996) reports about 50 kN for J4D and
//!   J5D. This model, with corner nodes only, no compression cap and no potential cracks
//!   in the bricks, peaks at 60.7 kN (+21 %); the bound below (25 %) guards that figure,
//!   it does not meet the 10 % (docs/performance.md, "Eindhoven walls").

mod common;
use dfem::analysis::Status;

#[test]
fn eindhoven_wall_030_peaks_softens_and_ends_in_friction() {
    let text = dfem::scene::examples::get("eindhoven").expect("the built-in example");
    let sc = common::scene(text);
    let (mesh, out) = common::solve(&sc);
    assert_eq!(out.status, Status::Stable, "{:?}", out.status);
    let c = out.capacity_curve.as_ref().expect("the push curve");
    assert_eq!(sc.blocks[c.control_block].name, "beam");
    let pts: Vec<([f64; 2], [f64; 3])> = c
        .points
        .iter()
        .map(|p| (p.displacement, p.reaction.unwrap()))
        .collect();
    // the beam follows its path: 4 mm across, vertical motion held after the
    // pre-compression, no rotation
    let (d0, _) = pts[0];
    let (d_end, r_end) = *pts.last().unwrap();
    assert!((d_end[0] - d0[0] - 0.004).abs() < 1e-9, "{d_end:?}");
    assert!((d_end[1] - d0[1]).abs() < 1e-12, "{d_end:?} {d0:?}");
    let beam = sc.block_index("beam").unwrap();
    let (_, rot) = dfem::analysis::outcome_motion(&mesh, beam, &out);
    // it rotates only elastically under the pre-compression (5e-9 rad) and is then held;
    // the bricks turn by ~1e-3 rad
    assert!(rot.abs() < 1e-7, "the beam rotated by {rot}");

    let (imax, peak) = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.1[0]))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let end = r_end[0];
    eprintln!(
        "peak {:.2} kN at {:.3} mm; end {:.2} kN, vertical reaction {:.2} kN",
        peak / 1e3,
        (pts[imax].0[0] - d0[0]) * 1e3,
        end / 1e3,
        r_end[1] / 1e3
    );
    assert!(imax + 1 < pts.len(), "no peak within 4 mm");
    assert!(
        end < 0.9 * peak,
        "no softening branch: {end} N after {peak} N"
    );

    // residual friction on the sliding bed joint
    let p = 0.30e6 * 0.99 * 0.1;
    let normal = p - r_end[1];
    let wall_weight = 18e3 * 0.99 * 0.992 * 0.1;
    let friction = 0.75 * normal;
    assert!(
        (end - friction).abs() <= 0.75 * wall_weight + 1e-3 * friction,
        "end load {end} N against tan φ × {normal} N = {friction} N"
    );

    // the experiment: about 50 kN (Lourenço 1996, J4D/J5D)
    assert!(
        (peak - 50e3).abs() < 0.25 * 50e3,
        "peak {peak} N against the experimental 50 kN"
    );
}
