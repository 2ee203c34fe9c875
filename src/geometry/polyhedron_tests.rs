//! Tests of the convex polyhedra and their face contacts against closed forms.

use super::face_contact::{
    block_face_contacts, clip_convex, face_contact, find_face_contacts, polygon_area,
    tangent_frame, BlockContact,
};
use super::polyhedron::{cross3, dot3, norm3, Polyhedron, PolyhedronDefect, Vec3};

const TOL: f64 = 1e-9;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

/// The prism of the counter-clockwise plane polygon `p` from z = z0 to z = z1.
fn extrude(p: &[[f64; 2]], z0: f64, z1: f64) -> Polyhedron {
    let n = p.len();
    let mut vertices: Vec<Vec3> = p.iter().map(|v| [v[0], v[1], z0]).collect();
    vertices.extend(p.iter().map(|v| [v[0], v[1], z1]));
    let mut faces = vec![(0..n).rev().collect::<Vec<_>>(), (n..2 * n).collect()];
    for i in 0..n {
        let j = (i + 1) % n;
        faces.push(vec![i, j, j + n, i + n]);
    }
    Polyhedron { vertices, faces }
}

/// The box rotated by `angle` (rad) about the vertical through (cx, cy).
fn turned_box(cx: f64, cy: f64, side: f64, angle: f64, z0: f64, z1: f64) -> Polyhedron {
    let (s, c) = angle.sin_cos();
    let h = side / 2.0;
    let corners =
        [[-h, -h], [h, -h], [h, h], [-h, h]].map(|[x, y]| [cx + c * x - s * y, cy + s * x + c * y]);
    extrude(&corners, z0, z1)
}

#[test]
fn a_box_has_the_closed_form_mass_properties() {
    let (a, b, c) = (2.0, 0.5, 0.3);
    let p = Polyhedron::from_box([1.0, -1.0, 0.2], [1.0 + a, -1.0 + b, 0.2 + c]);
    assert_eq!(p.check(TOL), Ok(()));
    let m = p.mass_properties();
    assert!(close(m.volume, a * b * c, 1e-14), "{}", m.volume);
    let centre = [1.0 + a / 2.0, -1.0 + b / 2.0, 0.2 + c / 2.0];
    for (got, want) in m.centroid.iter().zip(centre) {
        assert!((got - want).abs() < 1e-14, "{:?}", m.centroid);
    }
    // J_xx = M (b² + c²) / 12, products zero
    let rho = 2000.0;
    let mass = rho * a * b * c;
    let j = m.inertia(rho);
    assert!(
        close(j[0][0], mass * (b * b + c * c) / 12.0, 1e-12),
        "{:?}",
        j
    );
    assert!(
        close(j[1][1], mass * (a * a + c * c) / 12.0, 1e-12),
        "{:?}",
        j
    );
    assert!(
        close(j[2][2], mass * (a * a + b * b) / 12.0, 1e-12),
        "{:?}",
        j
    );
    assert!(j[0][1].abs() < 1e-12 * j[0][0], "{:?}", j);
}

#[test]
fn a_tetrahedron_has_the_closed_form_second_moments() {
    // the unit right tetrahedron: V = 1/6, centroid (1/4, 1/4, 1/4), ∫x² dV = 1/60 and
    // ∫xy dV = 1/120 about the origin, so 1/60 − V/16 = 1/160 and 1/120 − V/16 = −1/480
    // about the centroid
    let p = Polyhedron {
        vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        faces: vec![vec![0, 2, 1], vec![0, 1, 3], vec![0, 3, 2], vec![1, 2, 3]],
    };
    assert_eq!(p.check(TOL), Ok(()));
    let m = p.mass_properties();
    assert!(close(m.volume, 1.0 / 6.0, 1e-14));
    assert!(m.centroid.iter().all(|c| (c - 0.25).abs() < 1e-15));
    assert!(close(m.second_moment[0][0], 1.0 / 160.0, 1e-12));
    assert!(close(m.second_moment[0][1], -1.0 / 480.0, 1e-12));
    assert!(close(m.second_moment[1][2], -1.0 / 480.0, 1e-12));
}

#[test]
fn a_prism_of_a_hexagon_has_the_volume_of_its_base_times_its_height() {
    let hex: Vec<[f64; 2]> = (0..6)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 3.0;
            [t.cos(), t.sin()]
        })
        .collect();
    let p = extrude(&hex, 0.0, 0.7);
    assert_eq!(p.check(TOL), Ok(()));
    let area = 3.0 * 3f64.sqrt() / 2.0;
    assert!(close(p.mass_properties().volume, 0.7 * area, 1e-14));
}

#[test]
fn defects_are_named() {
    let good = Polyhedron::from_box([0.0; 3], [1.0; 3]);
    // one face listed clockwise seen from outside
    let mut p = good.clone();
    p.faces[1].reverse();
    assert!(matches!(
        p.check(TOL),
        Err(PolyhedronDefect::NotClosed { .. })
    ));
    // every face clockwise
    let mut p = good.clone();
    p.faces.iter_mut().for_each(|f| f.reverse());
    assert_eq!(p.check(TOL), Err(PolyhedronDefect::Inward));
    // a face missing
    let mut p = good.clone();
    p.faces.pop();
    assert!(matches!(
        p.check(TOL),
        Err(PolyhedronDefect::NotClosed { .. })
    ));
    // a corner moved off its faces' planes by 1 mm: it, and the face's other three
    // corners, are 1/4 mm off the mean plane (to within the plane's tilt, 10⁻³ rad)
    let mut p = good.clone();
    p.vertices[7][2] += 1e-3;
    match p.check(TOL) {
        Err(PolyhedronDefect::NonPlanar { distance, .. }) => {
            assert!(close(distance, 2.5e-4, 1e-6), "{distance}")
        }
        other => panic!("{other:?}"),
    }
    // an L-shaped prism: planar faces, closed, outward, not convex
    let l = [
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
    ];
    let p = extrude(&l, 0.0, 1.0);
    match p.check(TOL) {
        Err(PolyhedronDefect::NonConvex { distance, .. }) => assert!(close(distance, 1.0, 1e-12)),
        other => panic!("{other:?}"),
    }
    let mut p = good.clone();
    p.faces[0][0] = 8;
    assert_eq!(
        p.check(TOL),
        Err(PolyhedronDefect::BadIndex { face: 0, index: 8 })
    );
    let mut p = good.clone();
    p.vertices[3][0] = f64::NAN;
    assert_eq!(p.check(TOL), Err(PolyhedronDefect::NotFinite { vertex: 3 }));
    let mut p = good;
    p.faces.truncate(3);
    assert!(matches!(
        p.check(TOL),
        Err(PolyhedronDefect::TooFew { faces: 3, .. })
    ));
    // each message says how to mend it
    let msg = PolyhedronDefect::Inward.to_string();
    assert!(msg.contains("counter-clockwise"), "{msg}");
}

#[test]
fn the_tangent_frame_is_right_handed_and_orthonormal() {
    for n in [
        [0.0, 0.0, 1.0],
        [0.0, -1.0, 0.0],
        [0.6, 0.0, 0.8],
        [0.48, -0.6, 0.64],
    ] {
        let [t1, t2] = tangent_frame(n);
        assert!((norm3(t1) - 1.0).abs() < 1e-15 && (norm3(t2) - 1.0).abs() < 1e-15);
        assert!(
            dot3(t1, n).abs() < 1e-15 && dot3(t2, n).abs() < 1e-15 && dot3(t1, t2).abs() < 1e-15
        );
        let c = cross3(t1, t2);
        assert!((0..3).all(|k| (c[k] - n[k]).abs() < 1e-15), "{c:?} {n:?}");
    }
}

#[test]
fn a_block_offset_on_another_touches_over_the_overlap() {
    let base = Polyhedron::from_box([0.0; 3], [1.0; 3]);
    let top = Polyhedron::from_box([0.5, 0.25, 1.0], [1.5, 1.25, 2.0]);
    let contacts = block_face_contacts(&base, &top, 1e-6, 1e-6);
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    let (fa, fb, c) = &contacts[0];
    assert_eq!((*fa, *fb), (1, 0)); // the base's top face on the top block's bottom
    assert_eq!(c.normal, [0.0, 0.0, 1.0]);
    // the overlap 0.5 × 0.75: four corners, a quarter of the area each
    assert_eq!(c.points.len(), 4);
    assert!(close(c.area(), 0.375, 1e-14));
    assert!(
        c.areas.iter().all(|a| close(*a, 0.375 / 4.0, 1e-13)),
        "{:?}",
        c.areas
    );
    let mut g = [0.0; 3];
    for (p, a) in c.points.iter().zip(&c.areas) {
        for k in 0..3 {
            g[k] += p[k] * a / c.area();
        }
    }
    assert!(
        (g[0] - 0.75).abs() < 1e-14 && (g[1] - 0.625).abs() < 1e-14 && (g[2] - 1.0).abs() < 1e-14
    );
    // the other way round: the normal outward from the top block's face
    let c = face_contact(&top, 0, &base, 1, 1e-6, 1e-6).expect("touching");
    assert_eq!(c.normal, [0.0, 0.0, -1.0]);
    assert!(close(c.area(), 0.375, 1e-14));
}

#[test]
fn two_squares_turned_by_45_degrees_touch_over_a_regular_octagon() {
    // the intersection of two unit squares about one centre, one turned by 45°, is the
    // regular octagon of area 2 (√2 − 1)
    let base = turned_box(0.0, 0.0, 1.0, 0.0, -1.0, 0.0);
    let top = turned_box(0.0, 0.0, 1.0, std::f64::consts::FRAC_PI_4, 0.0, 1.0);
    let c = face_contact(&base, 1, &top, 0, 1e-6, 1e-6).expect("touching");
    assert_eq!(c.points.len(), 8);
    assert!(
        close(c.area(), 2.0 * (2f64.sqrt() - 1.0), 1e-13),
        "{}",
        c.area()
    );
    let each = c.area() / 8.0;
    assert!(
        c.areas.iter().all(|a| close(*a, each, 1e-12)),
        "{:?}",
        c.areas
    );
}

#[test]
fn faces_apart_tilted_or_beside_do_not_touch() {
    let base = Polyhedron::from_box([0.0; 3], [1.0; 3]);
    // 1 mm above with a gap of 0.1 mm allowed
    let above = Polyhedron::from_box([0.0, 0.0, 1.001], [1.0, 1.0, 2.0]);
    assert!(face_contact(&base, 1, &above, 0, 1e-4, 1e-6).is_none());
    // within the gap: touching, on the plane midway
    let c = face_contact(&base, 1, &above, 0, 2e-3, 1e-6).expect("within the gap");
    assert!(c.points.iter().all(|p| (p[2] - 1.0005).abs() < 1e-12));
    // beside: the faces' planes agree but they do not overlap
    let beside = Polyhedron::from_box([1.5, 0.0, 1.0], [2.5, 1.0, 2.0]);
    assert!(face_contact(&base, 1, &beside, 0, 1e-4, 1e-6).is_none());
    // sharing an edge only: no area
    let edge = Polyhedron::from_box([1.0, 0.0, 1.0], [2.0, 1.0, 2.0]);
    assert!(face_contact(&base, 1, &edge, 0, 1e-4, 1e-6).is_none());
    // a bottom face tilted by 0.01 rad against an angle tolerance of 10⁻⁶
    let mut tilted = above.clone();
    for v in tilted.vertices.iter_mut() {
        v[2] = 1.0 + (v[2] - 1.001) + 0.01 * v[0];
    }
    assert!(face_contact(&base, 1, &tilted, 0, 0.1, 1e-6).is_none());
}

#[test]
fn clipping_keeps_a_polygon_inside_and_drops_one_outside() {
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let inner = [[0.2, 0.2], [0.4, 0.2], [0.3, 0.5]];
    let kept = clip_convex(&inner, &square);
    assert_eq!(kept, inner.to_vec());
    let outer = [[2.0, 2.0], [3.0, 2.0], [2.5, 3.0]];
    assert!(clip_convex(&outer, &square).len() < 3);
    // the triangle (0.5, −0.5), (1.5, 0.5), (0.5, 0.5) has its hypotenuse y = x − 1 below
    // the square, so its part inside is the rectangle [0.5, 1] × [0, 0.5]
    let half = [[0.5, -0.5], [1.5, 0.5], [0.5, 0.5]];
    let cut = clip_convex(&half, &square);
    assert_eq!(cut.len(), 4, "{cut:?}");
    assert!(close(polygon_area(&cut), 0.25, 1e-14), "{cut:?}");
}

#[test]
fn a_stack_of_boxes_touches_at_every_shared_face() {
    // 4 × 3 × 2 unit boxes: (n−1)ml + n(m−1)l + nm(l−1) = 18 + 16 + 12 = 46 shared faces
    // of 1 m² each, however the blocks are listed
    let (n, m, l) = (4, 3, 2);
    let mut blocks = Vec::new();
    for k in 0..l {
        for j in 0..m {
            for i in 0..n {
                let lo = [i as f64, j as f64, k as f64];
                blocks.push(Polyhedron::from_box(
                    lo,
                    [lo[0] + 1.0, lo[1] + 1.0, lo[2] + 1.0],
                ));
            }
        }
    }
    let contacts = find_face_contacts(&blocks, 1e-6, 1e-6);
    assert_eq!(contacts.len(), 46);
    assert!(contacts.iter().all(|c| close(c.contact.area(), 1.0, 1e-12)));
    assert!(contacts.iter().all(|c| c.blocks.0 < c.blocks.1));
    // listed the other way round: the same pairs of blocks
    let reversed: Vec<Polyhedron> = blocks.iter().rev().cloned().collect();
    let mut pairs: Vec<(usize, usize)> = find_face_contacts(&reversed, 1e-6, 1e-6)
        .iter()
        .map(|c| {
            let last = blocks.len() - 1;
            let (a, b) = (last - c.blocks.0, last - c.blocks.1);
            (a.min(b), a.max(b))
        })
        .collect();
    pairs.sort();
    let expected: Vec<(usize, usize)> = contacts.iter().map(|c| c.blocks).collect();
    assert_eq!(pairs, expected);
    // a running-bond course on top, shifted by half a box: each top box on two below
    let top: Vec<Polyhedron> = (0..n - 1)
        .map(|i| {
            let x = i as f64 + 0.5;
            Polyhedron::from_box([x, 0.0, 2.0], [x + 1.0, 1.0, 3.0])
        })
        .collect();
    let mut all = blocks.clone();
    all.extend(top);
    let found = find_face_contacts(&all, 1e-6, 1e-6);
    let on_top: Vec<&BlockContact> = found
        .iter()
        .filter(|c| c.blocks.1 >= blocks.len())
        .collect();
    // 3 top boxes each on 2 boxes below (half their area each), and 2 between themselves
    let below = on_top.iter().filter(|c| c.blocks.0 < blocks.len()).count();
    assert_eq!(below, 6);
    assert!(on_top
        .iter()
        .filter(|c| c.blocks.0 < blocks.len())
        .all(|c| close(c.contact.area(), 0.5, 1e-12)));
    assert_eq!(on_top.len() - below, 2);
}
