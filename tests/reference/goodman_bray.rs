//! Limit-equilibrium analysis of block toppling (Goodman and Bray 1976; as presented in
//! Hoek and Bray, "Rock Slope Engineering", 3rd ed. 1981, chapter on toppling, and in
//! Wyllie and Mah, 4th ed. 2004, chapter 9). Written for dfem's validation tests
//! (BENCHMARKS V7); it uses no dfem code.
//!
//! # Geometry (the "regular" system of blocks)
//!
//! Work in a frame rotated so that the base planes (dip ψ toward the slope face) are
//! horizontal: every column is a rectangle of width Δx (along the base planes) and
//! height y_n (along the column faces, i.e. along the joints dipping 90° − ψ into the
//! slope). Blocks are numbered 1 (the toe) to N (the top). In that frame:
//!
//! * the stepped base line (overall dip ψ_b) rises by `b = Δx tan(ψ_b − ψ)` per block,
//!   so the base of block n is at height `n b` (from a common origin);
//! * below the crest the slope face (dip ψ_f) rises by `a₁ = Δx tan(ψ_f − ψ)` per block,
//!   so the top of block n is at `n a₁` and `y_n = n (a₁ − b)`;
//! * above the crest the upper slope (dip ψ_s) falls by `a₂ = Δx tan(ψ − ψ_s)` per block,
//!   so `y_n = y_{n−1} − a₂ − b`.
//!
//! With the V7 example (ψ_f = 56.6°, ψ_s = 4°, ψ_b = 35.8°, ψ = 30°, Δx = 10 m):
//! a₁ = 5.008, a₂ = 4.877, b = 1.016 m, rounded in the source to 5.0, 4.9, 1.0 m, which
//! give the heights 4, 8, …, 40 (crest, block 10), 34.1, …, 4.6 m.
//!
//! # Where the inter-column forces act
//!
//! P_n is the normal force on the upper (uphill) face of block n, from block n + 1;
//! P_{n−1} the one on its lower face, from block n − 1. For a toppling block the force
//! from its neighbour acts at the top corner of the shorter of the two columns in
//! contact (the corner about which the contact opens). Measured along the face from the
//! base of block n (at height n b):
//!
//! * upper face, below the crest: block n + 1 (base at (n+1) b) leans on the top corner
//!   of block n, at n a₁: `M_n = n a₁ − n b = y_n`;
//! * upper face, at and above the crest: block n + 1 is lower, its top at
//!   top_n − a₂: `M_n = y_n − a₂`;
//! * lower face, below and at the crest: the top corner of block n − 1, at (n−1) a₁:
//!   `L_n = (n−1) a₁ − n b = y_n − a₁`;
//! * lower face, above the crest: block n is the shorter, its own top: `L_n = y_n`.
//!
//! These are the expressions tabulated by Hoek and Bray.
//!
//! # Recursion (from the top block down)
//!
//! Friction φ on the faces (Q = P tan φ) and on the bases; W_n = γ Δx y_n.
//! Moments about the toe of block n give the force P_{n−1} needed to prevent toppling:
//!
//! ```text
//! P_{n−1,t} = [P_n (M_n − Δx tan φ) + (W_n/2)(y_n sin ψ − Δx cos ψ)] / L_n
//! ```
//!
//! and forces along and normal to the base with limiting friction on the base and on
//! both faces give the force needed to prevent sliding:
//!
//! ```text
//! P_{n−1,s} = P_n − W_n (tan φ cos ψ − sin ψ) / (1 − tan² φ)
//! ```
//!
//! Block n is stable if both are ≤ 0 (then P_{n−1} = 0), toppling if P_{n−1,t} is the
//! larger, sliding if P_{n−1,s} is the larger; P_{n−1} = max(P_{n−1,t}, P_{n−1,s}, 0).
//! The slope stands when the force P_0 needed below the toe block is ≤ 0; the limit
//! friction angle is the φ at which P_0 = 0 (found here by bisection on the unclamped
//! max(P_{0,t}, P_{0,s}), which decreases with φ).
//!
//! One detail the formula leaves open: if `L_n <= 0` the block below does not reach
//! above block n's base (for the toe block, L_1 = y_1 − a₁ = −1 m: there is no block
//! below at all), so no inter-column force can hold block n against toppling and the
//! toppling expression is meaningless (its sign flips). For such blocks only the sliding
//! force is used. In the V7 example this concerns the toe block only, which slides at
//! the limit anyway (see the self-check, which prints the modes).
//!
//! # Result for the worked example
//!
//! With the rounded constants of the source (a₁ = 5.0, a₂ = 4.9, b = 1.0 m) the limit
//! is φ = 38.160°; with the unrounded ones (5.008, 4.877, 1.016 m, from the angles) it
//! is 38.147°. The published 38.15° lies between: at φ = 38.15° the rounded geometry
//! leaves P₀ ≈ +10 kN/m on the toe block, against P₁ ≈ 480 kN/m and forces of up to
//! 4850 kN/m higher up (P₀ changes by about 1000 kN/m per degree near the limit), so
//! the difference is the rounding of a hand calculation, not a different method. The
//! modes agree with the source: blocks 16–14 stable, 13–4 toppling, 3–1 sliding.

#![allow(dead_code, clippy::too_many_arguments)]

/// Geometry and unit weight of a regular Goodman–Bray toppling slope.
#[derive(Clone, Debug)]
pub struct ToppleSlope {
    /// Column width Δx (along the base planes). [m]
    pub dx: f64,
    /// Column heights y_n from the toe (index 0 = block 1) to the top. [m]
    pub heights: Vec<f64>,
    /// Index (0-based) of the crest block.
    pub crest: usize,
    /// Dip ψ of the base planes (toward the face). [degrees]
    pub psi_deg: f64,
    /// Geometric constant a₁ = Δx tan(ψ_f − ψ) (face step). [m]
    pub a1: f64,
    /// Geometric constant a₂ = Δx tan(ψ − ψ_s) (upper-slope step). [m]
    pub a2: f64,
    /// Geometric constant b = Δx tan(ψ_b − ψ) (base step). [m]
    pub b: f64,
    /// Unit weight γ. [kN/m³] (the limit friction angle does not depend on it)
    pub gamma: f64,
}

/// Mode of a block at the given friction angle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockMode {
    /// Needs no force from below.
    Stable,
    /// P_{n−1,t} governs.
    Toppling,
    /// P_{n−1,s} governs.
    Sliding,
}

/// One line of the limit-equilibrium table (block n, from the top down).
#[derive(Clone, Debug)]
pub struct ToppleRow {
    /// Block number n (1 = toe).
    pub n: usize,
    /// Height y_n. [m]
    pub y: f64,
    /// Height of P_n above the base of block n. [m]
    pub m: f64,
    /// Height of P_{n−1} above the base of block n. [m]
    pub l: f64,
    /// Force on the upper face P_n. [kN/m]
    pub p_n: f64,
    /// Force needed on the lower face against toppling (NaN where L_n <= 0). [kN/m]
    pub p_t: f64,
    /// Force needed on the lower face against sliding. [kN/m]
    pub p_s: f64,
    /// The block's mode.
    pub mode: BlockMode,
}

impl ToppleSlope {
    /// The worked example of Goodman and Bray (1976) as in Hoek and Bray (BENCHMARKS
    /// V7): Δx = 10 m, 16 columns (4, 8, …, 40 m to the crest, block 10, then 34.1,
    /// 28.2, 22.3, 16.4, 10.5, 4.6 m), ψ = 30°, a₁ = 5.0, a₂ = 4.9, b = 1.0 m,
    /// γ = 25 kN/m³.
    pub fn worked_example() -> Self {
        ToppleSlope::regular(10.0, 10, 16, 30.0, 5.0, 4.9, 1.0, 25.0)
    }

    /// A regular system of `n_blocks` columns with the crest at block `crest_block`
    /// (1-based): y_n = n (a₁ − b) up to the crest, then y_n = y_{n−1} − a₂ − b.
    pub fn regular(
        dx: f64,
        crest_block: usize,
        n_blocks: usize,
        psi_deg: f64,
        a1: f64,
        a2: f64,
        b: f64,
        gamma: f64,
    ) -> Self {
        let mut heights = Vec::with_capacity(n_blocks);
        for n in 1..=n_blocks {
            let y = if n <= crest_block {
                n as f64 * (a1 - b)
            } else {
                heights[n - 2] - a2 - b
            };
            heights.push(y);
        }
        ToppleSlope {
            dx,
            heights,
            crest: crest_block - 1,
            psi_deg,
            a1,
            a2,
            b,
            gamma,
        }
    }

    /// The table of the recursion at friction angle `phi_deg` (faces and bases), from
    /// the top block down, and the unclamped force needed below the toe,
    /// max(P_{0,t}, P_{0,s}) [kN/m]. Source: Hoek and Bray (1981), Goodman and Bray (1976).
    pub fn table(&self, phi_deg: f64) -> (Vec<ToppleRow>, f64) {
        let tf = phi_deg.to_radians().tan();
        let (sp, cp) = self.psi_deg.to_radians().sin_cos();
        let dx = self.dx;
        let mut p = 0.0; // P_n on the top block
        let mut rows = Vec::new();
        let mut p0 = 0.0;
        for i in (0..self.heights.len()).rev() {
            let y = self.heights[i];
            let w = self.gamma * dx * y;
            let m = if i < self.crest { y } else { y - self.a2 };
            let l = if i <= self.crest { y - self.a1 } else { y };
            let p_t = if l > 0.0 {
                (p * (m - dx * tf) + 0.5 * w * (y * sp - dx * cp)) / l
            } else {
                f64::NAN
            };
            let p_s = p - w * (tf * cp - sp) / (1.0 - tf * tf);
            let need = if p_t.is_nan() { p_s } else { p_t.max(p_s) };
            let mode = if need <= 0.0 {
                BlockMode::Stable
            } else if !p_t.is_nan() && p_t >= p_s {
                BlockMode::Toppling
            } else {
                BlockMode::Sliding
            };
            rows.push(ToppleRow {
                n: i + 1,
                y,
                m,
                l,
                p_n: p,
                p_t,
                p_s,
                mode,
            });
            if i == 0 {
                p0 = need;
            }
            p = need.max(0.0);
        }
        (rows, p0)
    }
}

/// Friction angle φ (degrees; the same on the column faces and the bases) at which the
/// force needed below the toe block is just zero: the limiting friction angle of the
/// slope by the Goodman–Bray limit-equilibrium recursion. Bisection to 1e-6 degree
/// between 1° and 89° (also requires tan² φ < 1 in the sliding formula, so it searches
/// below 45°). Source: Goodman and Bray (1976); Hoek and Bray (1981).
pub fn goodman_bray_limit_friction(geometry: &ToppleSlope) -> f64 {
    let f = |phi: f64| geometry.table(phi).1;
    let (mut lo, mut hi) = (1.0, 44.999);
    assert!(f(lo) > 0.0, "slope stands even with φ = 1°");
    assert!(f(hi) <= 0.0, "slope does not stand with φ = 45°");
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
