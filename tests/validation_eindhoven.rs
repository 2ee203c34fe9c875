//! The Eindhoven shear walls (Raijmakers and Vermeltfoort 1992; docs/validation.md V8) as the
//! built-in examples `eindhoven` (J4D/J5D, 0.30 N/mm²), `eindhoven-j6d` (1.21 N/mm²) and
//! `eindhoven-j7d` (2.12 N/mm²): the micro-model of Lourenço and Rots (1997), expanded
//! bricks split at mid-length by potential cracks, softening mortar joints with the
//! compression cap, a fixed base and a rigid beam pushed 4 mm with its rotation and
//! vertical motion held.
//!
//! Where each number comes from (the search tool of this project reaches only the
//! opening pages of the sources, so most of them could not be checked against the text):
//! * wall 990 × 1000 mm, 18 courses of 210 × 52 × 100 mm bricks with 10 mm joints, top
//!   and bottom courses clamped in steel beams; pre-compressions 0.30, 1.21, 2.12 N/mm²;
//!   bricks E = 16700 N/mm², ν = 0.15; joints kₙ = 82 N/mm³, kₛ = 36 N/mm³, fₜ = 0.25
//!   N/mm², G_f^I = 0.018 N/mm, c = 0.35 N/mm², tan φ = 0.75, G_f^II = 0.125 N/mm,
//!   fₘ = 10.5 N/mm², brick cracks fₜ = 2.0 N/mm²: docs/validation.md V8 (which cites
//!   Lourenço and Rots 1997); not verified against the paper.
//! * the model itself (tension cut-off, Coulomb friction and an elliptical cap; tensile
//!   and cohesion softening, compressive hardening/softening, tension–shear coupling):
//!   confirmed by the abstracts of Lourenço, Rots and Blaauwendraad (1995, Heron 40) and
//!   Lourenço and Rots (1997, J. Eng. Mech.), and the DIANA manual's composite interface
//!   model page; the cap's C_ss = 9, G_fc = 5 N/mm, κₚ = 0.093 mm and the brick cracks'
//!   G_f^I = 0.08 N/mm: recalled from Lourenço (1996), not verified.
//! * wall names J4D/J5D (0.30), J6D (1.21), J7D (2.12): the issue and Lourenço (1996) as
//!   recalled (the former example called the 1.21 and 2.12 walls J7D and J9D).
//! * the top beam: "in a confined way, i.e. keeping the bottom and top boundaries
//!   horizontal and precluding any vertical movement" (Lourenço 1996, as recalled). The
//!   mechanics agrees: with its vertical motion free under the constant pre-compression
//!   the wall in double curvature carries at most N L/h = 29.7 kN × 0.99 m / 1.0 m =
//!   29.4 kN (dfem: 30.7 kN), far below the ≈50 kN measured, so the vertical motion was
//!   restrained and the vertical force grew as the wall dilated.
//! * the experimental peak of J4D/J5D, about 50 kN: Lourenço (1996) as the earlier
//!   version of this test cited it; not verified. The peaks of J6D and J7D could not be
//!   found with the tools at hand, and no test asserts them (docs/performance.md).
//! * the J4D experimental curve drawn in the figure ([`J4D_DIGITISED`]): a third party's
//!   digitisation, not a primary source. The public repository ameerhamza-cell/urm-wall-fem
//!   (file urm_validation_j4d.py, commit 649f4812) lists ten points "digitised from
//!   published load-displacement plots; uncertainty ≈ ±8 kN", stated as an "approximate
//!   digitisation from Lourenço 1994, Fig. 5.8" of Raijmakers and Vermeltfoort's J4D,
//!   and cites "Petracca et al. (2017, Table 2: V_max = 57 kN)" for the peak. Neither
//!   the figure nor the table could be opened to check them (the searches of 25 November
//!   2026 over the stored pages, documentation, code and issues found no copy of
//!   Lourenço 1994/1996, Lourenço and Rots 1997 or Petracca et al. 2017 beyond their
//!   opening pages), so the 57 kN is shown, not asserted: it and the 50 kN above differ
//!   by 14 %, more than the 10 % the issue asks for, and which is right is open.
//! * a second search on 25 November 2026 (23:05–23:20 UTC; the stored pages, documentation,
//!   code and issues) with other queries — "Raijmakers Vermeltfoort 1992 shear wall J4D",
//!   "Lourenço micro-model shear wall pre-compression 0.30 1.21 2.12 N/mm2 collapse load",
//!   "TU Eindhoven masonry shear wall 990 x 1000 mm", "multisurface interface model …
//!   Lourenço Rots", DEM papers that reproduce the walls (Bui, Limam and Sarhosis 2019;
//!   Pulatsu et al., 3DEC), and exact strings "Vermeltfoort", "Raijmakers", "shear wall
//!   J4D" — found again only the repository above and the abstracts or opening pages of
//!   papers (Lourenço and Rots 1997's abstract: the model "is capable of predicting the
//!   experimental collapse load and behaviour accurately", no number). No experimental
//!   number is verified.
//! * a third search on 26 November 2026 (02:15–02:25 UTC): the stored pages for
//!   "Vermeltfoort Raijmakers shear wall J4D peak load kN", "masonry shear wall 990 x 1000
//!   mm micro-modelling interface Lourenço Rots validation load displacement Eindhoven" and
//!   "Lourenço user programmer guide micro-modeling masonry shear wall example dilatancy";
//!   the code for "J4D J5D J6D J7D shear walls pre-compression 0.30 1.21 2.12";
//!   the issues for "Eindhoven shear wall micro-model validation peak load comparison";
//!   the documentation for "DIANA tutorial masonry shear wall …"; the exact string
//!   "Vermeltfoort". New: the opening page of Lourenço's "A user/programmer guide for
//!   the micro-modeling of masonry structures" (TU Delft report 03.21.1.31.35, November
//!   1996, on documents.pub), which announces "comprehensive examples" but whose examples
//!   the tool does not reach. No experimental number is verified.
//!
//! The fast test runs J4D with the bricks meshed at 0.052 m (half a brick's height, where
//! the shipped examples mesh them at 0.026 m: a run to the peak at 0.026 m takes minutes)
//! under displacement control to 1.5 mm: the peak (first maximum) within 10 % of 50 kN
//! and the failure pattern at the end. The ignored tests run each wall as shipped (bricks
//! at 0.026 m, dissipation-based arc length, 4 mm) and with the bricks meshed twice as
//! finely (0.013 m, to just past the peak): the first peaks within 3 % of each other and
//! the failure pattern; they print the rows of docs/performance.md and draw
//! docs/figures/eindhoven_walls.{png,svg} from the curves written so far:
//!
//!     cargo test --release --test validation_eindhoven -- --ignored --nocapture --test-threads=3

mod common;
use dfem::analysis::{Outcome, Status};
use dfem::mesh::Mesh;
use dfem::scene::Scene;

/// The experimental peak of J4D/J5D (N), see the header.
const J4D_PEAK: f64 = 50e3;
/// The J4D experimental curve as digitised by a third party (header): (top displacement
/// mm, horizontal load kN), stated uncertainty ±8 kN; unverified against the source.
const J4D_DIGITISED: [(f64, f64); 10] = [
    (0.0, 0.0),
    (0.2, 18.0),
    (0.4, 34.0),
    (0.7, 48.0),
    (1.0, 57.0),
    (1.4, 54.0),
    (1.8, 48.0),
    (2.2, 42.0),
    (2.6, 38.0),
    (3.0, 35.0),
];
/// The compressive strength of the cap (Pa) and its initial yield value fₘ/3.
const FC: f64 = 10.5e6;

/// The built-in example `name` (bricks meshed at 0.026 m, `path = "dissipation"`) with
/// the bricks meshed at `mesh` (m), pushed by `push` (m) in `steps` increments along
/// `path` ("displacement", "arc_length" or "dissipation"; under displacement control
/// without the example's `accept_residual`, which the arc-length paths alone take).
fn wall(name: &str, mesh: f64, push: f64, steps: usize, path: &str) -> Scene {
    let text = dfem::scene::examples::get(name).expect("a built-in example");
    let edits = [
        ("mesh_size = 0.026\n", format!("mesh_size = {mesh}\n")),
        (
            "push_displacement = [0.004, 0.0]",
            format!("push_displacement = [{push}, 0.0]"),
        ),
        ("load_steps = 80", format!("load_steps = {steps}")),
        ("path = \"dissipation\"\n", format!("path = \"{path}\"\n")),
    ];
    let mut text = text.to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "{name}: no {from:?} in the example");
        text = text.replace(from, &to);
    }
    if path == "displacement" {
        // accepting unconverged increments belongs to the arc-length paths
        let key = "accept_residual = 1e-4\n";
        assert!(text.contains(key), "{name}: no {key:?} in the example");
        text = text.replace(key, "");
    }
    common::scene(&text)
}

/// The push curve: (top displacement m, horizontal load N, vertical force N).
fn curve(out: &Outcome) -> Vec<[f64; 3]> {
    let c = out.capacity_curve.as_ref().expect("the push curve");
    let d0 = c.points[0].displacement[0];
    c.points
        .iter()
        .map(|p| {
            let r = p.reaction.expect("push points carry the force");
            [p.displacement[0] - d0, r[0], r[1]]
        })
        .collect()
}

/// The largest load of [`J4D_DIGITISED`] (kN).
fn digitised_peak() -> f64 {
    J4D_DIGITISED.iter().map(|p| p.1).fold(0.0, f64::max)
}

/// The first maximum of the load: the largest load before it falls by 0.2 % (N), its
/// index. The held beam's vertical force grows as the wall dilates, and past the peak
/// the load rises again with it (docs/performance.md); the arc-length curves are smooth
/// to 10⁻⁵ of the load, far below the 0.2 %.
fn first_peak(pts: &[[f64; 3]]) -> (usize, f64) {
    let mut best = (0, 0.0);
    for (i, p) in pts.iter().enumerate() {
        if p[1] > best.1 {
            best = (i, p[1]);
        } else if p[1] < 0.998 * best.1 {
            break;
        }
    }
    best
}

/// The midpoint (m) of every contact in the final configuration, with its joint name.
fn contacts(sc: &Scene, mesh: &Mesh, out: &Outcome) -> Vec<([f64; 2], String)> {
    let cur = out.current.as_ref().unwrap_or(mesh);
    cur.contacts
        .iter()
        .map(|c| {
            let j = sc.joint_of(c.block_l as usize, c.block_m as usize);
            (cur.nodes[c.node_m as usize], sc.joints[j].name.clone())
        })
        .collect()
}

/// Pearson's correlation of x and y over the points.
fn correlation(p: &[[f64; 2]]) -> f64 {
    let n = p.len() as f64;
    let (mx, my) = (
        p.iter().map(|q| q[0]).sum::<f64>() / n,
        p.iter().map(|q| q[1]).sum::<f64>() / n,
    );
    let sxy: f64 = p.iter().map(|q| (q[0] - mx) * (q[1] - my)).sum();
    let sxx: f64 = p.iter().map(|q| (q[0] - mx).powi(2)).sum();
    let syy: f64 = p.iter().map(|q| (q[1] - my).powi(2)).sum();
    sxy / (sxx * syy).sqrt()
}

/// The failure pattern at the end of a run: the open contacts inside the wall (not on
/// the bed joints to the base and the beam), the x–y correlation of their midpoints
/// (negative: a band falling from the top left to the bottom right, the diagonal
/// stepped crack), how many of them are brick cracks, the largest compression (Pa,
/// negative) at the bottom-right and top-left toes, and the open fraction of the length
/// of the bed joints to the base and to the beam (rocking opens most of them at the
/// heels).
struct Pattern {
    open: usize,
    rho: f64,
    through_bricks: usize,
    bottom_right: f64,
    top_left: f64,
    /// Contacts at the bottom-right and top-left toes whose cap yielded during the run
    /// (κ₃ > 0: at some point σ² + C_ss τ² reached (fₘ/3)², the cap's initial yield
    /// surface). κ₃ never decreases, so a toe that crushed and then unloaded, as the
    /// walls do down their softening branches, still counts.
    crushed: [usize; 2],
    /// The largest cap strength σ̄(κ₃) (Eq. C2, Pa) any contact at the bottom-right and
    /// top-left toe reached during the run: fₘ/3 where no cap yielded, fₘ at κₚ, and
    /// below fₘ again past it (softening), where the largest κ₃ is reported as fₘ.
    reached: [f64; 2],
    bed_open: [f64; 2],
}

fn pattern(sc: &Scene, mesh: &Mesh, out: &Outcome) -> Pattern {
    let cs = contacts(sc, mesh, out);
    let t = sc.model.thickness;
    let is_open = |s: &dfem::material::ContactState| *s == dfem::material::ContactState::Open;
    let open: Vec<[f64; 2]> = cs
        .iter()
        .zip(&out.contact_states)
        .filter(|((p, _), s)| is_open(s) && p[1] > 0.07 && p[1] < 0.92)
        .map(|((p, _), _)| *p)
        .collect();
    let through_bricks = cs
        .iter()
        .zip(&out.contact_states)
        .filter(|((_, j), s)| j == "brick" && is_open(s))
        .count();
    let stress = |k: usize| {
        let c = &mesh.contacts[k];
        out.contact_forces[k][0] / (c.length * t)
    };
    let in_toe = |k: usize, bottom: bool| {
        let p = cs[k].0;
        if bottom {
            p[0] >= 0.8 && p[1] <= 0.07
        } else {
            p[0] <= 0.2 && p[1] >= 0.92
        }
    };
    let toe = |bottom: bool| {
        (0..cs.len())
            .filter(|&k| in_toe(k, bottom))
            .map(stress)
            .fold(0.0f64, f64::min)
    };
    let cap = sc
        .joints
        .iter()
        .find_map(|j| j.cap)
        .expect("the mortar's cap");
    let law = dfem::material::cap::Cap::new(
        cap.compressive_strength,
        cap.shear_factor,
        cap.fracture_energy.map(|g| (g, cap.peak_displacement)),
    );
    let kappa = |k: usize| out.contact_history[k][1];
    let crushed = [true, false].map(|bottom| {
        (0..cs.len())
            .filter(|&k| in_toe(k, bottom) && kappa(k) > 0.0)
            .count()
    });
    // σ̄ rises to fₘ at κₚ and falls past it: a toe past its peak reached fₘ
    let reached = [true, false].map(|bottom| {
        let most = (0..cs.len())
            .filter(|&k| in_toe(k, bottom))
            .map(kappa)
            .fold(0.0f64, f64::max);
        if most > 0.0 && most >= cap.peak_displacement {
            cap.compressive_strength
        } else if most > 0.0 {
            law.yield_value(most)
        } else {
            cap.compressive_strength / 3.0
        }
    });
    // the bed joints to the base (y = 0) and to the beam (y = 0.992 m)
    let bed_open = [0.0, 0.992].map(|y: f64| {
        let on = |k: &usize| (cs[*k].0[1] - y).abs() < 1e-3;
        let total: f64 = (0..cs.len())
            .filter(on)
            .map(|k| mesh.contacts[k].length)
            .sum();
        let opened: f64 = (0..cs.len())
            .filter(on)
            .filter(|&k| is_open(&out.contact_states[k]))
            .map(|k| mesh.contacts[k].length)
            .sum();
        opened / total.max(1e-300)
    });
    let p = Pattern {
        bed_open,
        open: open.len(),
        rho: if open.len() > 1 {
            correlation(&open)
        } else {
            0.0
        },
        through_bricks,
        bottom_right: toe(true),
        top_left: toe(false),
        crushed,
        reached,
    };
    eprintln!(
        "{} open contacts inside, x–y correlation {:.2}; {} open brick cracks; toes at {:.2} and {:.2} MPa, {} and {} contacts whose cap yielded, cap strengths reached {:.2} and {:.2} MPa; bed joints to the base and the beam {:.0} % and {:.0} % open",
        p.open,
        p.rho,
        p.through_bricks,
        p.bottom_right / 1e6,
        p.top_left / 1e6,
        p.crushed[0],
        p.crushed[1],
        p.reached[0] / 1e6,
        p.reached[1] / 1e6,
        100.0 * p.bed_open[0],
        100.0 * p.bed_open[1]
    );
    p
}

#[test]
fn eindhoven_j4d_peak_and_failure_pattern() {
    let sc = wall("eindhoven", 0.052, 1.5e-3, 30, "displacement");
    let (mesh, out) = common::solve(&sc);
    let pts = curve(&out);
    let (ip, peak) = first_peak(&pts);
    eprintln!(
        "J4D, bricks at 0.052 m: peak {:.2} kN at {:.3} mm, {} points to {:.3} mm ({:?})",
        peak / 1e3,
        pts[ip][0] * 1e3,
        pts.len(),
        pts.last().unwrap()[0] * 1e3,
        out.status
    );
    // the potential cracks: exactly the contacts between the two halves of a brick take
    // the brick's joint
    for c in &mesh.contacts {
        let (l, m) = (c.block_l as usize, c.block_m as usize);
        let same = sc.blocks[l].unit.is_some() && sc.blocks[l].unit == sc.blocks[m].unit;
        assert_eq!(sc.joints[sc.joint_of(l, m)].name == "brick", same);
    }
    // how the push went (summary.json's curve.path): under displacement control one
    // increment per point of the curve after the first, the fraction reached that of the
    // curve's last point, the furthest point the curve's largest displacement
    let path = out.capacity_curve.as_ref().unwrap().path.clone().unwrap();
    let last = pts.last().unwrap()[0];
    let furthest = pts.iter().fold(0.0f64, |m, p| m.max(p[0]));
    assert_eq!(path.increments, [0, 0, pts.len() - 1], "{path:?}");
    assert!((path.reached * 1.5e-3 - last).abs() < 1e-9, "{path:?}");
    assert!((path.furthest - furthest).abs() < 1e-12, "{path:?}");
    match &out.status {
        Status::Failed { reason, .. } => assert!(reason.ends_with(&path.end), "{reason}"),
        _ => assert_eq!(path.end, "the end of the push"),
    }
    // the beam's rotation is held, so its top stays horizontal
    let beam = sc.block_index("beam").unwrap();
    let (_, rot) = dfem::analysis::outcome_motion(&mesh, beam, &out);
    assert!(rot.abs() < 1e-7, "the beam rotated by {rot}");
    // the load is followed past its peak (the run may stop later, where the path snaps
    // back under displacement control: docs/performance.md)
    assert!(ip + 1 < pts.len(), "no peak within the push");
    assert!(
        matches!(out.status, Status::Stable) || pts.last().unwrap()[0] > 1.2e-3,
        "{:?}",
        out.status
    );
    eprintln!(
        "J4D peak against the candidate references (header): {:+.1} % against 50 kN, {:+.1} % against the digitised 57 kN",
        100.0 * (peak - J4D_PEAK) / J4D_PEAK,
        100.0 * (peak / 1e3 - digitised_peak()) / digitised_peak()
    );
    // the peak against the experiment (header): 10 %
    assert!(
        (peak - J4D_PEAK).abs() < 0.1 * J4D_PEAK,
        "peak {peak} N against the experimental {J4D_PEAK} N"
    );
    // the held beam takes a growing vertical force as the wall dilates (its
    // compression, negative), of the order of the pre-compression at the peak
    let fy = pts[ip][2];
    assert!(
        fy < -0.3 * 29.7e3 && fy > -3.0 * 29.7e3,
        "vertical force {fy} N"
    );

    // failure pattern at the end: the open contacts inside the wall (not on the bed
    // joints to the base and the beam) form a band from the top left to the bottom
    // right (the diagonal stepped crack across joints and bricks), and the toes (bottom
    // right, top left) are on the compression cap (|σ| ≥ fₘ/3 where it starts to yield)
    let Pattern {
        open,
        rho,
        bottom_right,
        top_left,
        through_bricks,
        bed_open,
        ..
    } = pattern(&sc, &mesh, &out);
    // through bricks as well as joints, and rocking at this low pre-compression: the bed
    // joints to the base and the beam open at the heels (23 % of their length measured)
    assert!(through_bricks >= 1, "no brick crack open");
    assert!(bed_open.iter().all(|&f| f > 0.05), "heels {bed_open:?}");
    assert!(open >= 10, "{open} open contacts");
    assert!(
        rho < -0.5,
        "the open contacts do not form a falling diagonal: {rho}"
    );
    assert!(
        bottom_right < -FC / 3.0,
        "bottom-right toe at {bottom_right} Pa"
    );
    assert!(top_left < -FC / 3.0, "top-left toe at {top_left} Pa");
}

/// One run of a sweep: its mesh (m), the curve, the first peak and the outcome.
struct Run {
    mesh: f64,
    pts: Vec<[f64; 3]>,
    peak: (usize, f64),
    out: Outcome,
    pattern: Pattern,
}

/// The walls of the sweep: example, label, the push (m) of the twice-finer mesh (past
/// the first peak of the example's mesh: 1.1, 1.4 and 2.1 mm, docs/performance.md).
const WALLS: [(&str, &str, f64); 3] = [
    ("eindhoven", "J4D/J5D, 0.30 N/mm²", 1.6e-3),
    ("eindhoven-j6d", "J6D, 1.21 N/mm²", 2.0e-3),
    ("eindhoven-j7d", "J7D, 2.12 N/mm²", 2.6e-3),
];

/// The curves of the sweeps, one CSV per wall and mesh (top displacement mm, load kN,
/// vertical force kN), kept between the tests so that the last one draws them all.
fn curve_file(name: &str, mesh: f64) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("eindhoven_{name}_{}mm.csv", mesh * 1e3))
}

/// Runs `name` as shipped (bricks at 0.026 m, dissipation-based arc length, 4 mm) and
/// with the bricks meshed twice as finely (0.013 m) to `fine_push`, prints the rows of
/// docs/performance.md ("Eindhoven walls") and the failure patterns, writes the curves
/// and draws docs/figures/eindhoven_walls.{png,svg} from every wall's curves written so
/// far. Returns the two runs.
fn sweep(name: &str, fine_push: f64) -> [Run; 2] {
    let runs = [(0.026, 4e-3, 80), (0.013, fine_push, 80)].map(|(m, push, steps)| {
        let sc = wall(name, m, push, steps, "dissipation");
        let (mesh, out) = common::solve(&sc);
        eprint!("{name} at {m} m, at the end: ");
        let pattern = pattern(&sc, &mesh, &out);
        let pts = curve(&out);
        let peak = first_peak(&pts);
        let far = pts.iter().fold(pts[0], |a, p| if p[0] > a[0] { *p } else { a });
        let last = pts.last().unwrap();
        let path = out.capacity_curve.as_ref().unwrap().path.clone().unwrap();
        eprintln!(
            "| {name} | {m} | {} / {} | {:.1} s | {:.2} kN at {:.2} mm | {:.1} kN at {:.2} mm ({:.0} %) | {:.1} kN at {:.2} mm, vertical {:.1} kN | increments on the cylinder / dissipation / displacement {:?} | {} |",
            out.stats.dofs,
            out.stats.contacts,
            out.stats.wall_time_s,
            peak.1 / 1e3,
            pts[peak.0][0] * 1e3,
            far[1] / 1e3,
            far[0] * 1e3,
            100.0 * far[0] / push,
            last[1] / 1e3,
            last[0] * 1e3,
            last[2] / 1e3,
            path.increments,
            path.end
        );
        let csv: String = pts
            .iter()
            .map(|p| format!("{},{},{}\n", p[0] * 1e3, p[1] / 1e3, p[2] / 1e3))
            .collect();
        std::fs::write(curve_file(name, m), csv).unwrap();
        Run {
            mesh: m,
            pts,
            peak,
            out,
            pattern,
        }
    });
    let [a, b] = &runs;
    eprintln!(
        "{name}: first peaks {:.2} kN ({} m) and {:.2} kN ({} m): {:+.2} %",
        a.peak.1 / 1e3,
        a.mesh,
        b.peak.1 / 1e3,
        b.mesh,
        100.0 * (b.peak.1 - a.peak.1) / a.peak.1
    );
    figure();
    for r in &runs {
        assert!(r.pts.len() > 10, "{name} {}: {:?}", r.mesh, r.out.status);
        // the first peak is a maximum inside the run, not its last point
        assert!(r.peak.0 + 1 < r.pts.len(), "{name} {}: no peak", r.mesh);
    }
    // mesh independence: bricks meshed twice as finely change the first peak by < 3 %
    assert!(
        (b.peak.1 - a.peak.1).abs() < 0.03 * a.peak.1,
        "{name}: first peak {} N at 0.026 m, {} N at 0.013 m",
        a.peak.1,
        b.peak.1
    );
    runs
}

/// docs/figures/eindhoven_walls.{png,svg} from the curves the sweeps wrote: the walls as
/// shipped (bricks at 26 mm) solid, the twice-finer meshes dashed, the J4D/J5D peak of
/// about 50 kN ± 10 % and the third party's digitised J4D curve (header).
fn figure() {
    let mut curves = Vec::new();
    for (c, (name, label, _)) in WALLS.iter().enumerate() {
        for (m, dashed) in [(0.026, false), (0.013, true)] {
            let Ok(text) = std::fs::read_to_string(curve_file(name, m)) else {
                continue;
            };
            let points = text
                .lines()
                .map(|l| {
                    let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                    (v[0], v[1])
                })
                .collect();
            curves.push(dfem::output::plot::CurveSeries {
                label: format!("dfem {label}, bricks at {} mm", m * 1e3),
                points,
                color: c,
                dashed,
                markers: false,
            });
        }
    }
    curves.push(dfem::output::plot::CurveSeries {
        label: "J4D experiment, third-party digitisation (± 8 kN; unverified)".into(),
        points: J4D_DIGITISED.to_vec(),
        color: 0,
        dashed: false,
        markers: true,
    });
    let bands = [dfem::output::plot::Band {
        label: "J4D/J5D peak, about 50 kN (Lourenço 1996, unverified), ± 10 %".into(),
        load: J4D_PEAK / 1e3,
        width: 0.1,
        color: 0,
    }];
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures");
    for ext in ["png", "svg"] {
        dfem::output::plot::load_displacement_chart(
            &dir.join(format!("eindhoven_walls.{ext}")),
            "Eindhoven shear walls: horizontal load against top displacement (held beam)",
            &curves,
            &bands,
        )
        .unwrap();
    }
}

// The failure patterns at the end of each wall's run with the bricks at 0.026 m
// (`pattern`): the experiments (Raijmakers and Vermeltfoort 1992, as described by
// Lourenço 1996; docs/validation.md V8) open horizontal cracks at the heels first (rocking),
// then a diagonal stepped crack through joints and bricks, with the toes crushing, more so
// at the higher pre-compressions. The open cracks are read at the end of the run; the
// toes from the caps' history (κ₃, `Outcome::contact_history`), since J4D and J6D
// unload down their softening branches (from 52.4 to 38.5 kN, from 84.0 to 49.3 kN) and
// the compressed zone at each toe shrinks: at 4 mm their end stresses are 0.78–0.90 fₘ
// with 9–12 contacts on the yield surface, where 21 at each toe yielded on the way.
// Measured on 66fab1d + the history (docs/performance.md, "Eindhoven
// walls"): J4D at 4 mm (the end of the push) x–y correlation of the open contacts
// −0.51, 30 brick cracks open, 21 and 21 toe contacts whose cap yielded, both toes past
// fₘ (κ₃ ≥ κₚ: crushed), heels 2 % and 2 % open; J6D at 4 mm −0.83, 41, 21 and 21, both
// past fₘ, 1 % and 2 %; J7D at 2.07 mm (its end, in its snap-back) −0.92, 14, 20 and
// 21, the caps at 0.95 fₘ (9.99 and 10.03 MPa), 0 % and 0 %. (The heels open on the way
// down J4D's snap-backs, 12–14 % of the bed joints at the foot of the first, and close
// again as it reloads, so the end reads them closed: no check reads them for J4D.)

/// Contacts at a toe whose cap yielded during the run (κ₃ > 0) from which the toe counts
/// as crushing: 10, half the 20–21 of every wall at its end (above); a toe whose cap
/// never yielded, or yielded at a few contacts only, is not crushing.
const CRUSHED: usize = 10;

/// What a wall's failure pattern must show: the open contacts' x–y correlation below
/// `rho` (a band falling from the top left to the bottom right: −1 along the diagonal,
/// 0 for no trend), at least `bricks` brick cracks open, the heels open (rocking: more
/// than 5 % of the bed joints to the base and to the beam open) or closed (less than
/// 5 %), and the toes crushing (at each at least [`CRUSHED`] contacts whose cap yielded
/// during the run and a cap strength σ̄(κ₃) reached of at least 0.8 fₘ: the
/// compression at the toe went past 0.8 fₘ) or only starting to (1 to `CRUSHED` − 1
/// contacts).
struct Expect {
    rho: f64,
    bricks: usize,
    rocking: Option<bool>,
    crushing: bool,
}

fn check_pattern(p: &Pattern, wall: &str, e: Expect) {
    eprintln!(
        "{wall}: correlation {:.2}, {} brick cracks, heels {:?}, toes {:?} yielded, cap strengths reached {:.2} and {:.2} MPa",
        p.rho,
        p.through_bricks,
        p.bed_open,
        p.crushed,
        p.reached[0] / 1e6,
        p.reached[1] / 1e6
    );
    assert!(p.rho < e.rho, "{wall}: no falling diagonal");
    assert!(p.through_bricks >= e.bricks, "{wall}: too few brick cracks");
    if let Some(rocking) = e.rocking {
        assert!(
            p.bed_open.iter().all(|&f| (f > 0.05) == rocking),
            "{wall}: heels"
        );
    }
    let toes = if e.crushing {
        CRUSHED..usize::MAX
    } else {
        1..CRUSHED
    };
    assert!(p.crushed.iter().all(|n| toes.contains(n)), "{wall}: toes");
    if e.crushing {
        assert!(
            p.reached.iter().all(|&r| r >= 0.8 * FC),
            "{wall}: toes' caps"
        );
    }
}

/// The sweep of wall `WALLS[k]` (its two meshes) with the failure pattern of the
/// example's mesh checked against `e`; returns that mesh's run.
fn sweep_and_check(k: usize, wall: &str, e: Expect) -> Run {
    let (name, _, push) = WALLS[k];
    let [a, _] = sweep(name, push);
    check_pattern(&a.pattern, wall, e);
    a
}

/// Draws docs/figures/eindhoven_walls.{png,svg} again from the curves the sweeps last
/// wrote (in the test target's temporary directory), without running the walls.
#[test]
#[ignore = "draws from the sweeps' curves: run the sweeps first"]
fn eindhoven_figure_from_the_sweeps_curves() {
    figure();
}

#[test]
#[ignore = "two runs of several minutes: run it with --ignored"]
fn eindhoven_j4d_sweep() {
    // the diagonal stepped crack through joints and bricks, and the toes crushing, as in
    // the experiment's last stage (as recalled from Lourenço 1996, not verified:
    // horizontal cracks at the base and the top first, then the diagonal crack, then the
    // toes). The heels are not checked: they open on the way down the first snap-back
    // (12–14 % of the bed joints at its foot) and close again as the wall reloads, so at
    // the end of the push they read closed (measured at the 26 mm mesh, 4 mm: correlation
    // −0.51, 30 brick cracks, heels 2 % and 2 %, 21 and 21 toe contacts whose cap
    // yielded, both toes' caps past fₘ)
    let e = Expect {
        rho: -0.5,
        bricks: 1,
        rocking: None,
        crushing: true,
    };
    let a = sweep_and_check(0, "J4D", e);
    assert!(
        (a.peak.1 - J4D_PEAK).abs() < 0.1 * J4D_PEAK,
        "J4D {}",
        a.peak.1
    );
}

#[test]
#[ignore = "two runs of several minutes: run it with --ignored"]
fn eindhoven_j6d_sweep() {
    // the diagonal stepped crack, through more bricks than J4D's; toe crushing, no
    // rocking (measured at the 26 mm mesh, 4 mm: correlation −0.83, 41 brick cracks,
    // heels 1 % and 2 %, 21 and 21 toe contacts whose cap yielded, both past fₘ)
    let e = Expect {
        rho: -0.4,
        bricks: 5,
        rocking: Some(false),
        crushing: true,
    };
    sweep_and_check(1, "J6D", e);
}

#[test]
#[ignore = "two runs of several minutes: run it with --ignored"]
fn eindhoven_j7d_sweep() {
    // toe crushing under the highest pre-compression, and the diagonal stepped crack
    // through joints and bricks (measured at the 26 mm mesh at the run's end, 2.07 mm in
    // its snap-back: correlation −0.92, 14 brick cracks, heels 0 % and 0 %, 20 and 21 toe
    // contacts whose cap yielded, the caps at 0.95 fₘ; when the run stopped at its first
    // peak the diagonal had only begun, −0.33 with 6 brick cracks, which the thresholds
    // of J4D and J6D, −0.5 or −0.4 and 5, would not have passed)
    let e = Expect {
        rho: -0.5,
        bricks: 5,
        rocking: None,
        crushing: true,
    };
    sweep_and_check(2, "J7D", e);
}

/// The contact-state corrector (docs/theory.md, Eq. F1–F2) carries J7D, as shipped,
/// through the state where it stopped without it: before the corrector the run stopped at
/// 2.088 mm, 117.9 kN, 0.3 % below its first peak of 118.3 kN, its iterations cycling
/// between the states of 4–8 contacts at the kinks of their laws (docs/decisions/
/// 0026-eindhoven-mesh-and-path.md). With it the path goes on
/// past that point and down the wall's softening branch: the load must fall by more
/// than 3 % below the first peak (ten times the old 0.3 %) before the run ends.
///
/// With `accept_residual = 1e-4` (the examples' setting since 27 November 2026) the
/// path also passes the stop at 2.078 mm, 94.4 kN, where every constraint's iterations
/// stalled a little above the tolerance 10⁻⁵, and reaches the end of the 4 mm push:
/// each increment taken unconverged was left within 10⁻⁴ of the load (by the option's
/// definition), and such increments are few (11 of 618 on 27 November 2026): the
/// increments after one converge again.
#[test]
#[ignore = "a run of several minutes: run it with --ignored"]
fn eindhoven_j7d_corrector_passes_the_old_stop() {
    let sc = wall("eindhoven-j7d", 0.026, 4e-3, 80, "dissipation");
    let (_, out) = common::solve(&sc);
    let pts = curve(&out);
    let peak = first_peak(&pts);
    let least = pts[peak.0..]
        .iter()
        .map(|p| p[1])
        .fold(f64::INFINITY, f64::min);
    let far = pts.iter().map(|p| p[0]).fold(0.0, f64::max);
    let path = out.capacity_curve.as_ref().unwrap().path.clone().unwrap();
    eprintln!(
        "J7D: first peak {:.2} kN, least load after it {:.2} kN ({:+.1} %), furthest {:.3} mm, reached {:.1} %, increments {:?}, {} contact-state checks, end: {}",
        peak.1 / 1e3,
        least / 1e3,
        100.0 * (least - peak.1) / peak.1,
        far * 1e3,
        100.0 * path.reached,
        path.increments,
        out.stats.contact_releases,
        path.end
    );
    assert!(
        least < 0.97 * peak.1,
        "J7D: the load fell to {least} N after the first peak of {} N",
        peak.1
    );
    eprintln!(
        "J7D: {} increments accepted unconverged, the largest at {:.2e} of the load",
        path.accepted, path.accepted_residual
    );
    assert_eq!(path.end, "the end of the push", "{path:?}");
    assert!(path.accepted_residual <= 1e-4, "{path:?}");
    let taken: usize = path.increments.iter().sum();
    assert!(20 * path.accepted < taken, "{path:?}");
}
