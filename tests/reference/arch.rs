//! Rigid-block limit analysis of masonry arches (lower-bound, or static, theorem).
//!
//! Sources: Heyman, "The stone skeleton" (1966) and "The masonry arch" (1982) for the
//! three assumptions (no tensile strength, unlimited compressive strength, no sliding);
//! Livesley, "Limit analysis of structures formed from rigid blocks" (1978) for the
//! formulation as a linear program over the joint stress resultants. Written for dfem's
//! validation tests (BENCHMARKS V6); it uses no dfem code.
//!
//! # Formulation
//!
//! Every joint `j` is a straight segment of length `t_j` with centre `c_j`, unit normal
//! `n_j` (pointing from its "first" body into its "second" body) and unit tangent `s_j`.
//! Its unknowns are the normal force `N_j`, the shear `V_j` and the moment `M_j` about
//! `c_j`; the second body receives `N_j n_j + V_j s_j` at `c_j` and the couple `M_j`, the
//! first body the opposite. Each free body `i` with weight `W_i` (acting at its centroid
//! `g_i`) and a horizontal body force `λ W_i` (also at `g_i`) must be in equilibrium:
//! two force equations and one moment equation about `g_i`. A joint carries no tension
//! and the thrust stays within the joint:
//!
//! ```text
//!   N_j >= 0,   |M_j| <= N_j t_j / 2,   (optionally |V_j| <= mu N_j)
//! ```
//!
//! By the static theorem, a load factor λ for which such a statically admissible set of
//! joint forces exists is safe, and the largest one is the collapse load factor λ_c
//! (exactly, for the rigid, no-tension, no-sliding model: the problem is a linear
//! program, solved here with the pure-Rust `microlp` simplex). Bodies flagged `fixed`
//! (supports, the ground) have no equilibrium equations.
//!
//! Before the LP is built, lengths are divided by the size of the model and forces by
//! the largest body weight, so the coefficients stay O(1) whatever the units; λ is
//! dimensionless and unaffected. Units of the inputs are free but must be consistent
//! (e.g. metres and kN per metre of arch width); the results are dimensionless.
//!
//! # Semicircular arch, minimum thickness: which numbers and why
//!
//! The semicircular helpers use `n` voussoirs between `n + 1` radial joints (two of
//! them the springings, fixed), `R` the mean radius, each voussoir an exact annular
//! sector (weight `∝ R t Δθ`, centroid at radius `(2/3)(r_e³ − r_i³)/(r_e² − r_i²) ·
//! sin(Δθ/2)/(Δθ/2)`). With that convention the minimum thickness found by bisection
//! (see the self-check) reproduces BENCHMARKS V6: n = 5 → 0.0966, n = 9 → 0.1021,
//! n = 21 → 0.1068, and n = 101 → 0.1075 to within the bisection tolerance, the
//! continuous (Milankovitch) value 0.1075 being the limit of many voussoirs. So the
//! published numbers count voussoirs (not joints) and use the mean radius (not the
//! intrados radius). With finitely many voussoirs hinges can only form at joints, the
//! set of admissible thrust lines is larger and the minimum thickness lower; for odd n
//! the crown lies inside the key stone, which is why n = 5 is so far below the limit.
//!
//! The polygon-based [`capacity`] takes the blocks as drawn (e.g. voussoirs with straight
//! chord intrados and extrados), with weights and centroids of the actual polygons:
//! they differ slightly from annular sectors, so a chord arch has a slightly different
//! λ_c than the sector arch of the same n and t/R.

#![allow(dead_code)]

use microlp::{ComparisonOp, OptimizationDirection, Problem};

/// A rigid block given as a polygon with counter-clockwise vertices (any units of
/// length), and its weight per unit area (per unit out-of-plane width: e.g. kN/m³ ·
/// 1 m). Its weight acts at the polygon's centroid.
#[derive(Clone, Debug)]
pub struct RigidBlock {
    /// Counter-clockwise vertices `[x, y]` (y up). Clockwise input is accepted too:
    /// the area is taken in absolute value.
    pub vertices: Vec<[f64; 2]>,
    /// Weight per unit area (force / length², per unit width).
    pub unit_weight: f64,
}

impl RigidBlock {
    /// A block with unit weight per unit area 1.
    pub fn new(vertices: Vec<[f64; 2]>) -> Self {
        RigidBlock {
            vertices,
            unit_weight: 1.0,
        }
    }

    /// Signed area (shoelace formula), positive for counter-clockwise vertices. [length²]
    pub fn signed_area(&self) -> f64 {
        let v = &self.vertices;
        let n = v.len();
        let mut a = 0.0;
        for i in 0..n {
            let p = v[i];
            let q = v[(i + 1) % n];
            a += p[0] * q[1] - q[0] * p[1];
        }
        0.5 * a
    }

    /// Area of the polygon. [length²]
    pub fn area(&self) -> f64 {
        self.signed_area().abs()
    }

    /// Centroid of the polygon (standard polygon centroid formula). [length]
    pub fn centroid(&self) -> [f64; 2] {
        let v = &self.vertices;
        let n = v.len();
        let (mut cx, mut cy) = (0.0, 0.0);
        for i in 0..n {
            let p = v[i];
            let q = v[(i + 1) % n];
            let cr = p[0] * q[1] - q[0] * p[1];
            cx += (p[0] + q[0]) * cr;
            cy += (p[1] + q[1]) * cr;
        }
        let a6 = 6.0 * self.signed_area();
        [cx / a6, cy / a6]
    }

    /// Weight = unit weight · area. [force per unit width]
    pub fn weight(&self) -> f64 {
        self.unit_weight * self.area()
    }
}

/// A joint: the straight segment `p`–`q` shared by `block_a` and `block_b`
/// (indices into the block list), or by `block_a` and the rigid ground when `block_b`
/// is `None`. The thrust must stay within the segment.
#[derive(Clone, Debug)]
pub struct JointGeom {
    /// One end of the joint segment. [length]
    pub p: [f64; 2],
    /// The other end. [length]
    pub q: [f64; 2],
    /// One block at the joint.
    pub block_a: usize,
    /// The other block, or `None` for the fixed ground.
    pub block_b: Option<usize>,
}

impl JointGeom {
    /// Joint between two blocks.
    pub fn between(p: [f64; 2], q: [f64; 2], a: usize, b: usize) -> Self {
        JointGeom {
            p,
            q,
            block_a: a,
            block_b: Some(b),
        }
    }
    /// Joint between a block and the fixed ground.
    pub fn to_ground(p: [f64; 2], q: [f64; 2], a: usize) -> Self {
        JointGeom {
            p,
            q,
            block_a: a,
            block_b: None,
        }
    }
}

/// Options of the limit analysis.
#[derive(Clone, Debug)]
pub struct LimitOptions {
    /// Coulomb friction coefficient μ = tan φ on every joint (`|V| <= μ N`);
    /// `None` (the default) means no sliding (infinite friction).
    pub friction: Option<f64>,
    /// Direction of the horizontal body force λ·W: `+1.0` (the default) for +x,
    /// `-1.0` for −x.
    pub load_sign: f64,
}

impl Default for LimitOptions {
    fn default() -> Self {
        LimitOptions {
            friction: None,
            load_sign: 1.0,
        }
    }
}

/// A loaded rigid body in the low-level formulation: weight and the point where the
/// weight and the horizontal load λ·W act.
#[derive(Clone, Debug)]
pub struct Body {
    /// Weight (force per unit width), > 0 for free bodies.
    pub weight: f64,
    /// Point of application of W and λW (the centroid). [length]
    pub centroid: [f64; 2],
    /// A fixed body (support) has no equilibrium equations.
    pub fixed: bool,
}

/// A joint in the low-level formulation.
#[derive(Clone, Debug)]
pub struct Interface {
    /// Joint centre (the moment M is taken about it). [length]
    pub centre: [f64; 2],
    /// Unit normal pointing from `first` into `second`.
    pub normal: [f64; 2],
    /// Half the joint length t/2 (the thrust eccentricity limit). [length]
    pub half_width: f64,
    /// The body on the side the normal points away from (`None`: fixed ground).
    pub first: Option<usize>,
    /// The body on the side the normal points into (`None`: fixed ground).
    pub second: Option<usize>,
}

/// What to do with λ in the LP.
#[derive(Clone, Copy, Debug)]
enum LambdaMode {
    /// λ is a free variable to maximise.
    Maximise,
    /// λ is given; the LP is a feasibility problem.
    Given(f64),
}

/// Converts polygon blocks and segment joints to bodies and interfaces (normal
/// oriented by the blocks' centroids).
pub fn build_model(
    blocks: &[RigidBlock],
    joints: &[JointGeom],
    fixed: &[bool],
) -> (Vec<Body>, Vec<Interface>) {
    assert_eq!(blocks.len(), fixed.len(), "one `fixed` flag per block");
    let bodies: Vec<Body> = blocks
        .iter()
        .zip(fixed)
        .map(|(b, &f)| Body {
            weight: b.weight(),
            centroid: b.centroid(),
            fixed: f,
        })
        .collect();
    let interfaces = joints
        .iter()
        .map(|j| {
            let d = [j.q[0] - j.p[0], j.q[1] - j.p[1]];
            let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
            assert!(len > 0.0, "joint of zero length");
            let centre = [0.5 * (j.p[0] + j.q[0]), 0.5 * (j.p[1] + j.q[1])];
            let mut normal = [-d[1] / len, d[0] / len];
            let ga = bodies[j.block_a].centroid;
            // Orient the normal away from block_a's centroid; when there is a block_b,
            // check that block_b's centroid lies on the other side.
            let side_a = (ga[0] - centre[0]) * normal[0] + (ga[1] - centre[1]) * normal[1];
            if side_a > 0.0 {
                normal = [-normal[0], -normal[1]];
            }
            if let Some(b) = j.block_b {
                let gb = bodies[b].centroid;
                let side_b = (gb[0] - centre[0]) * normal[0] + (gb[1] - centre[1]) * normal[1];
                assert!(
                    side_b > 0.0,
                    "blocks {} and {} lie on the same side of their joint",
                    j.block_a,
                    b
                );
            }
            match j.block_b {
                // normal points from a into b
                Some(b) => Interface {
                    centre,
                    normal,
                    half_width: 0.5 * len,
                    first: Some(j.block_a),
                    second: Some(b),
                },
                // ground is "first", normal points from the ground into a
                None => Interface {
                    centre,
                    normal: [-normal[0], -normal[1]],
                    half_width: 0.5 * len,
                    first: None,
                    second: Some(j.block_a),
                },
            }
        })
        .collect();
    (bodies, interfaces)
}

/// Collapse load factor λ_c of a system of rigid blocks (static theorem, LP): the
/// largest λ such that the blocks carry their self-weight plus a horizontal body force
/// λ·W (+x) on every free block, with no tension, no sliding, and the thrust within
/// every joint. `fixed[i]` marks supports. Blocks as polygons (weights and centroids of
/// the actual polygons). Returns `f64::NEG_INFINITY` if no λ admits equilibrium (the
/// structure cannot stand) and `f64::INFINITY` if λ is unbounded. Dimensionless.
///
/// Source: Livesley (1978); Heyman (1966). See the module header.
pub fn capacity(blocks: &[RigidBlock], joints: &[JointGeom], fixed: &[bool]) -> f64 {
    capacity_with(blocks, joints, fixed, &LimitOptions::default())
}

/// As [`capacity`], with options (friction, load direction).
pub fn capacity_with(
    blocks: &[RigidBlock],
    joints: &[JointGeom],
    fixed: &[bool],
    opts: &LimitOptions,
) -> f64 {
    let (bodies, ifs) = build_model(blocks, joints, fixed);
    max_load_factor(&bodies, &ifs, opts)
}

/// Whether the blocks stand under self-weight alone (LP feasibility at λ = 0).
pub fn stands(
    blocks: &[RigidBlock],
    joints: &[JointGeom],
    fixed: &[bool],
    opts: &LimitOptions,
) -> bool {
    let (bodies, ifs) = build_model(blocks, joints, fixed);
    feasible_at(&bodies, &ifs, opts, 0.0)
}

/// Low-level: maximum λ for bodies and interfaces (see [`capacity`]).
pub fn max_load_factor(bodies: &[Body], ifs: &[Interface], opts: &LimitOptions) -> f64 {
    match solve_lp(bodies, ifs, opts, LambdaMode::Maximise) {
        LpResult::Optimal(l) => l,
        LpResult::Infeasible => f64::NEG_INFINITY,
        LpResult::Unbounded => f64::INFINITY,
    }
}

/// Low-level: is there a statically admissible set of joint forces at the given λ?
pub fn feasible_at(bodies: &[Body], ifs: &[Interface], opts: &LimitOptions, lambda: f64) -> bool {
    matches!(
        solve_lp(bodies, ifs, opts, LambdaMode::Given(lambda)),
        LpResult::Optimal(_)
    )
}

enum LpResult {
    Optimal(f64),
    Infeasible,
    Unbounded,
}

fn solve_lp(bodies: &[Body], ifs: &[Interface], opts: &LimitOptions, mode: LambdaMode) -> LpResult {
    // Scales: lengths by the extent of the model, forces by the largest free weight.
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut grow = |p: [f64; 2]| {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    };
    for b in bodies {
        grow(b.centroid);
    }
    for j in ifs {
        grow(j.centre);
    }
    let ls = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let ws = bodies
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| b.weight)
        .fold(0.0f64, f64::max)
        .max(1e-300);
    let origin = lo;
    let sc = |p: [f64; 2]| [(p[0] - origin[0]) / ls, (p[1] - origin[1]) / ls];

    let dir = match mode {
        LambdaMode::Maximise => OptimizationDirection::Maximize,
        LambdaMode::Given(_) => OptimizationDirection::Minimize,
    };
    let mut lp = Problem::new(dir);
    let inf = f64::INFINITY;
    let lam = match mode {
        LambdaMode::Maximise => Some(lp.add_var(1.0, (-inf, inf))),
        LambdaMode::Given(_) => None,
    };
    let given = match mode {
        LambdaMode::Given(l) => l,
        LambdaMode::Maximise => 0.0,
    };
    // Joint variables: N >= 0, V free, M free (scaled: forces / ws, moments / (ws ls)).
    let mut vars = Vec::with_capacity(ifs.len());
    for j in ifs {
        let n = lp.add_var(0.0, (0.0, inf));
        let v = lp.add_var(0.0, (-inf, inf));
        let m = lp.add_var(0.0, (-inf, inf));
        let h = j.half_width / ls;
        lp.add_constraint([(m, 1.0), (n, -h)], ComparisonOp::Le, 0.0);
        lp.add_constraint([(m, -1.0), (n, -h)], ComparisonOp::Le, 0.0);
        if let Some(mu) = opts.friction {
            lp.add_constraint([(v, 1.0), (n, -mu)], ComparisonOp::Le, 0.0);
            lp.add_constraint([(v, -1.0), (n, -mu)], ComparisonOp::Le, 0.0);
        }
        vars.push((n, v, m));
    }
    // Equilibrium of every free body.
    for (i, b) in bodies.iter().enumerate() {
        if b.fixed {
            continue;
        }
        let g = sc(b.centroid);
        let w = b.weight / ws;
        let mut fx = Vec::new();
        let mut fy = Vec::new();
        let mut mz = Vec::new();
        for (j, itf) in ifs.iter().enumerate() {
            let sign = if itf.second == Some(i) {
                1.0
            } else if itf.first == Some(i) {
                -1.0
            } else {
                continue;
            };
            let (n, v, m) = vars[j];
            let nn = itf.normal;
            let tt = [-nn[1], nn[0]];
            let c = sc(itf.centre);
            let d = [c[0] - g[0], c[1] - g[1]];
            fx.push((n, sign * nn[0]));
            fx.push((v, sign * tt[0]));
            fy.push((n, sign * nn[1]));
            fy.push((v, sign * tt[1]));
            mz.push((n, sign * (d[0] * nn[1] - d[1] * nn[0])));
            mz.push((v, sign * (d[0] * tt[1] - d[1] * tt[0])));
            mz.push((m, sign));
        }
        // Σ joint forces + (λ s W, −W) = 0
        fx.retain(|(_, c)| c.abs() > 1e-12);
        match lam {
            Some(l) => {
                fx.push((l, opts.load_sign * w));
                lp.add_constraint(&fx[..], ComparisonOp::Eq, 0.0);
            }
            None => {
                lp.add_constraint(&fx[..], ComparisonOp::Eq, -given * opts.load_sign * w);
            }
        }
        // lever arms that vanish up to round-off (a joint through a centroid) give
        // coefficients of 1e-17 next to O(1) ones, which the simplex cannot take: zero
        let clean = |v: &mut Vec<(microlp::Variable, f64)>| v.retain(|(_, c)| c.abs() > 1e-12);
        clean(&mut fy);
        clean(&mut mz);
        lp.add_constraint(&fy[..], ComparisonOp::Eq, w);
        lp.add_constraint(&mz[..], ComparisonOp::Eq, 0.0);
    }
    match lp.solve() {
        Ok(out) => match out.into_solution() {
            Ok(sol) => LpResult::Optimal(match lam {
                Some(l) => sol.var_value(l),
                None => given,
            }),
            Err(e) => panic!("LP interrupted: {e:?}"),
        },
        Err(microlp::Error::Infeasible) => LpResult::Infeasible,
        Err(microlp::Error::Unbounded) => LpResult::Unbounded,
        Err(e) => panic!("LP failed: {e}"),
    }
}

/// Bodies and interfaces of a semicircular arch of `n` equal voussoirs, exact annular
/// sectors of mean radius 1 and thickness `t_over_r`, between `n + 1` radial joints,
/// on fixed springings (bodies `n` and `n + 1` are the fixed supports). Voussoir `k`
/// spans polar angles `[kπ/n, (k+1)π/n]`, from the right springing (+x) to the left.
pub fn semicircular_sector_model(t_over_r: f64, n: usize) -> (Vec<Body>, Vec<Interface>) {
    assert!(n >= 1 && t_over_r > 0.0 && t_over_r < 2.0);
    let ri = 1.0 - 0.5 * t_over_r;
    let re = 1.0 + 0.5 * t_over_r;
    let dth = std::f64::consts::PI / n as f64;
    let half = 0.5 * dth;
    // annular sector: area = (Δθ/2)(re² − ri²); centroid radius
    // (2/3)(re³ − ri³)/(re² − ri²) · sin(Δθ/2)/(Δθ/2)
    let area = half * (re * re - ri * ri);
    let rg = 2.0 / 3.0 * (re.powi(3) - ri.powi(3)) / (re * re - ri * ri) * half.sin() / half;
    let mut bodies: Vec<Body> = (0..n)
        .map(|k| {
            let th = (k as f64 + 0.5) * dth;
            Body {
                weight: area,
                centroid: [rg * th.cos(), rg * th.sin()],
                fixed: false,
            }
        })
        .collect();
    // supports: positions only matter for scaling
    bodies.push(Body {
        weight: 0.0,
        centroid: [1.0, -0.5 * t_over_r],
        fixed: true,
    });
    bodies.push(Body {
        weight: 0.0,
        centroid: [-1.0, -0.5 * t_over_r],
        fixed: true,
    });
    let ifs = (0..=n)
        .map(|k| {
            let th = k as f64 * dth;
            Interface {
                centre: [th.cos(), th.sin()],
                normal: [-th.sin(), th.cos()],
                half_width: 0.5 * t_over_r,
                first: Some(if k == 0 { n } else { k - 1 }),
                second: Some(if k == n { n + 1 } else { k }),
            }
        })
        .collect();
    (bodies, ifs)
}

/// Polygons and joints of a semicircular arch of `n` voussoirs with straight chord
/// intrados and extrados (quadrilaterals between radial joints), mean radius 1,
/// thickness `t_over_r`, on the fixed ground: the same geometry as a polygon-based
/// arch generator. All blocks free; the springing joints go to the ground.
pub fn semicircular_chord_blocks(t_over_r: f64, n: usize) -> (Vec<RigidBlock>, Vec<JointGeom>) {
    let ri = 1.0 - 0.5 * t_over_r;
    let re = 1.0 + 0.5 * t_over_r;
    let dth = std::f64::consts::PI / n as f64;
    let pt = |r: f64, th: f64| [r * th.cos(), r * th.sin()];
    let blocks = (0..n)
        .map(|k| {
            let a = k as f64 * dth;
            let b = a + dth;
            RigidBlock::new(vec![pt(ri, a), pt(re, a), pt(re, b), pt(ri, b)])
        })
        .collect();
    let joints = (0..=n)
        .map(|k| {
            let th = k as f64 * dth;
            let (p, q) = (pt(ri, th), pt(re, th));
            if k == 0 {
                JointGeom::to_ground(p, q, 0)
            } else if k == n {
                JointGeom::to_ground(p, q, n - 1)
            } else {
                JointGeom::between(p, q, k - 1, k)
            }
        })
        .collect();
    (blocks, joints)
}

/// Minimum thickness ratio t/R (R the mean radius) of a semicircular arch of
/// `n_voussoirs` equal voussoirs (annular sectors, radial joints) on fixed springings
/// that stands under self-weight with no tension and no sliding. Bisection on t/R with
/// an LP feasibility test, to a relative precision of 1e-4. Dimensionless.
///
/// Source: static theorem (Heyman 1966); published values in BENCHMARKS V6
/// (0.0966, 0.1021, 0.1068 for n = 5, 9, 21; 0.1075 as n grows, Milankovitch 1907).
pub fn semicircular_min_thickness(n_voussoirs: usize) -> f64 {
    let opts = LimitOptions::default();
    let ok = |t: f64| {
        let (b, i) = semicircular_sector_model(t, n_voussoirs);
        feasible_at(&b, &i, &opts, 0.0)
    };
    let (mut lo, mut hi) = (0.01, 0.5);
    assert!(!ok(lo) && ok(hi), "bracket of the minimum thickness");
    while hi - lo > 1e-4 * 0.5 * (hi + lo) * 0.5 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Horizontal collapse load factor λ_c (body force λ·W in +x on every voussoir) of a
/// semicircular arch of thickness `t_over_r` (R the mean radius) and `n_voussoirs`
/// annular-sector voussoirs between radial joints, on fixed springings, no sliding.
/// LP maximising λ. Dimensionless.
///
/// Source: static theorem; published values in BENCHMARKS V6 (λ_c = 0.144, 0.284,
/// 0.406, 0.518 for t/R = 0.15, 0.20, 0.25, 0.30, many voussoirs).
pub fn semicircular_horizontal_capacity(t_over_r: f64, n_voussoirs: usize) -> f64 {
    let (b, i) = semicircular_sector_model(t_over_r, n_voussoirs);
    max_load_factor(&b, &i, &LimitOptions::default())
}
