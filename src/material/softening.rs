//! The softening joint (docs/theory.md §3, "Softening joints" and
//! "Compression cap"): tension cut-off and Mohr–Coulomb strength whose tensile strength
//! and cohesion soften exponentially with the fracture energies G_f^I and G_f^II,
//! friction remaining, and optionally the elliptic compression cap of [`super::cap`],
//! after the composite interface model of Lourenço and Rots (1997).
//!
//! Stresses per unit contact area (Pa), compression negative; relative displacements
//! (m). With the elastic trial stresses σ* = σ₀ + kₙ Δδₙ, τ* = τ₀ + kₛ Δδₛ (kₙ = Eₙ/h,
//! kₛ = Gₛ/h in N/m³) and the history ξ (the spent fraction of the fracture energy,
//! 0 ≤ ξ ≤ 1; s = 1 − ξ the remaining fraction of the strengths):
//! * tension surface f₁ = σ − s fₜ, associated flow: plastic opening Δλ₁;
//! * shear surface f₂ = |τ| + σ tan φ − s c: plastic slip Δλ₂, and with a dilatancy
//!   ([`Dilatancy`], docs/theory.md Eq. D1) the plastic opening Δλ₂ tan ψ(σ) with
//!   tan ψ(σ) = tan ψ₀ ⟨1 + σ/σᵤ⟩ (σ ≤ 0; tan ψ₀ in tension): the joint dilates as it
//!   slips, less under compression, not at all beyond σᵤ (after Lourenço 1996 and Van
//!   Zijl 2004, as recalled, unchecked). Without it the flow is along τ alone (no
//!   dilatancy);
//! * softening: dξ = (s fₜ dλ₁)/G_f^I + (s c dλ₂)/G_f^II, the work spent against the
//!   tensile strength and against the cohesion, each over its own fracture energy (the
//!   linear mixed-mode energy criterion). Within an increment s′ = s exp(−fₜ Δλ₁/G_f^I −
//!   c Δλ₂/G_f^II), exact along a radial plastic path. Under pure tension this is
//!   σ = fₜ exp(−fₜ u_p/G_f^I) with ∫σ du_p = G_f^I; under shear at constant σ,
//!   τ = c exp(−c u_p/G_f^II) − σ tan φ with ∫(τ + σ tan φ) du_p = G_f^II;
//! * cap surface f₃ = σ² + C_ss τ² − σ̄(κ₃)², associated flow, its own history κ₃ (m),
//!   uncoupled from ξ (Lourenço and Rots 1997 couple tension and shear only).
//!
//! Everything is per unit area and per unit relative displacement, so the dissipated
//! energy of a joint is G_f × its area whatever the number of contacts it is split
//! into: the regularisation that keeps the response independent of the mesh.

use super::cap::{bisect, decreasing_root, Cap};
use super::{ContactLaw, ContactSprings, ContactState, ElasticBand, History};
use crate::scene::Joint;

/// Mode-I and mode-II exponential softening of a Mohr–Coulomb band with tension cut-off,
/// and an optional compression cap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Softening {
    pub elastic: ElasticBand,
    /// tan φ (the friction that remains when the cohesion is spent).
    pub tan_phi: f64,
    /// Initial cohesion c (Pa).
    pub cohesion: f64,
    /// Initial tensile strength fₜ (Pa), fₜ tan φ ≤ c.
    pub tensile_strength: f64,
    /// Mode-I fracture energy G_f^I (N/m = J/m²), > 0.
    pub fracture_energy_i: f64,
    /// Mode-II fracture energy G_f^II (N/m), > 0.
    pub fracture_energy_ii: f64,
    /// The compression cap, if any.
    pub cap: Option<Cap>,
    /// The dilatancy of the shear surface, if any (none: slip without opening).
    pub dilatancy: Option<Dilatancy>,
}

/// The dilatancy of a slipping joint (docs/theory.md, Eq. D1): the plastic opening per
/// unit plastic slip, tan ψ(σ) = tan ψ₀ ⟨1 + σ/σᵤ⟩ under compression (σ < 0) and tan ψ₀
/// in tension, so that a joint pressed by σᵤ or more slips without opening. Held between
/// stiff supports, a dilating joint presses them harder as it slips; the compression it
/// builds up that way stops at σᵤ (the closed form of the test
/// `confined_slip_builds_compression_up_to_the_dilatancy_stress`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dilatancy {
    /// tan ψ₀, the dilatancy at zero normal stress (≥ 0).
    pub tan_psi: f64,
    /// σᵤ (Pa, > 0): the compression at which the dilatancy vanishes.
    pub stress: f64,
}

impl Dilatancy {
    /// tan ψ(σ) at the normal stress `sig` (Pa, compression negative).
    pub fn tan_at(&self, sig: f64) -> f64 {
        self.tan_psi * (1.0 + sig / self.stress).clamp(0.0, 1.0)
    }
}

/// Which surfaces of tension and shear are active in a return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Active {
    Tension,
    Shear,
    Both,
}

/// Bisection steps of the scalar return equation: the bracket [0, s] shrinks to 2⁻⁶⁰ s.
const BISECTIONS: usize = 60;

/// The root of an increasing `f` on [lo, hi] with f(lo) ≤ 0 < f(hi) = `f_hi`, by the
/// Illinois variant of regula falsi (superlinear on smooth pieces, the bracket kept),
/// to 10⁻¹⁴ of the bracket's scale or at most 200 steps.
fn increasing_root(mut lo: f64, mut hi: f64, mut f_hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let mut f_lo = f(lo);
    if f_lo >= 0.0 {
        return lo;
    }
    let tol = 1e-14 * (lo.abs() + hi.abs());
    let mut side = 0;
    for _ in 0..200 {
        let x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let x = if x > lo && x < hi { x } else { 0.5 * (lo + hi) };
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if fx < 0.0 {
            (lo, f_lo) = (x, fx);
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            (hi, f_hi) = (x, fx);
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
        if hi - lo <= tol {
            break;
        }
    }
    if f_hi.abs() < f_lo.abs() {
        hi
    } else {
        lo
    }
}

/// The result of a return: stresses (Pa), remaining fraction s′ and the cap's history κ₃
/// (m).
#[derive(Debug, Clone, Copy)]
struct Returned {
    sig: f64,
    tau: f64,
    s: f64,
    kappa: f64,
}

impl Softening {
    pub fn from_joint(j: &Joint) -> Self {
        Softening {
            elastic: ElasticBand::from_joint(j),
            tan_phi: j.friction_angle.to_radians().tan(),
            cohesion: j.cohesion,
            tensile_strength: j.tensile_strength,
            fracture_energy_i: j.fracture_energy_i,
            fracture_energy_ii: j.fracture_energy_ii,
            cap: j.cap.map(|c| {
                Cap::new(
                    c.compressive_strength,
                    c.shear_factor,
                    c.fracture_energy.map(|g| (g, c.peak_displacement)),
                )
            }),
            dilatancy: (j.dilatancy_angle > 0.0).then(|| Dilatancy {
                tan_psi: j.dilatancy_angle.to_radians().tan(),
                stress: j.dilatancy_stress,
            }),
        }
    }

    /// The normal stress σ (Pa) after a slip return at the remaining fraction `r` from
    /// the trial (σ*, |τ*|), with the normal stiffness `kn` (N/m³) and the shear
    /// stiffness `ks`: the root of σ − σ* + kₙ tan ψ(σ) Δλ₂(σ) = 0, Δλ₂ = ⟨|τ*| − t(σ)⟩/kₛ,
    /// t(σ) = ⟨r c − σ tan φ⟩ (Eq. D1, backward Euler). The left side increases with σ
    /// (a more compressed joint resists more slip and dilates less), is ≥ 0 at σ* and
    /// ≤ 0 at min(σ*, −σᵤ): the Illinois variant of regula falsi (this return runs inside
    /// the bisections on s′ and on the cap's multiplier, so plain bisection here would
    /// multiply their 60–80 evaluations by another 60). σ* itself without a dilatancy.
    fn slip_normal(&self, sig: f64, tau: f64, r: f64, kn: f64, ks: f64) -> f64 {
        let Some(d) = self.dilatancy else {
            return sig;
        };
        let (c, tp) = (self.cohesion, self.tan_phi);
        let h = |sg: f64| {
            let t = (r * c - sg * tp).max(0.0);
            sg - sig + kn * d.tan_at(sg) * ((tau - t) / ks).max(0.0)
        };
        let hi = h(sig);
        if hi <= 0.0 {
            return sig;
        }
        increasing_root(sig.min(-d.stress), sig, hi, h)
    }

    /// kₙ = Eₙ/h and kₛ = Gₛ/h (N/m³).
    fn stiffness(&self) -> (f64, f64) {
        (
            self.elastic.normal_modulus / self.elastic.band,
            self.elastic.shear_modulus / self.elastic.band,
        )
    }

    /// The return of the trial stresses (σ*, |τ*|) (Pa) onto the tension and shear
    /// surfaces `active` from the remaining fraction `s`, with the stiffnesses (kₙ, kₛ)
    /// (N/m³): (σ, |τ|, s′). The unknown is s′ ∈ [0, s]: the plastic multipliers follow
    /// from it linearly (the stresses on the active surfaces at strength s′), and
    /// s′ = s exp(−a Δλ₁ − b Δλ₂) is solved by bisection (its left side minus right side
    /// increases from −s·e^… < 0 at s′ = 0 to ≥ 0 at s′ = s).
    fn ret(&self, sig: f64, tau: f64, s: f64, k: (f64, f64), active: Active) -> (f64, f64, f64) {
        let (kn, ks) = k;
        let (ft, c, tp) = (self.tensile_strength, self.cohesion, self.tan_phi);
        let a = ft / self.fracture_energy_i;
        let b = c / self.fracture_energy_ii;
        // stresses and multipliers at a remaining fraction r
        let at = |r: f64| -> (f64, f64, f64, f64) {
            match active {
                Active::Tension => {
                    let s1 = r * ft;
                    (s1, tau, (sig - s1) / kn, 0.0)
                }
                Active::Shear => {
                    let sg = self.slip_normal(sig, tau, r, kn, ks);
                    let t = (r * c - sg * tp).max(0.0);
                    (sg, t, 0.0, (tau - t) / ks)
                }
                Active::Both => {
                    let s1 = r * ft;
                    let t = (r * c - s1 * tp).max(0.0);
                    // on the tension cut-off the joint's faces part: it opens by the whole
                    // opening past the strength and does not dilate (Eq. D1 rides the faces
                    // on each other, which needs them in contact); at the edge of this
                    // return, σ* − kₙ tan ψ Δλ₂ = s′fₜ, the shear return gives the same
                    // stresses
                    (s1, t, (sig - s1) / kn, (tau - t) / ks)
                }
            }
        };
        let resid = |r: f64| {
            let (_, _, l1, l2) = at(r);
            r - s * (-a * l1.max(0.0) - b * l2.max(0.0)).exp()
        };
        let r = if s > 0.0 && resid(s) > 0.0 {
            bisect(0.0, s, BISECTIONS, |r| resid(r) > 0.0)
        } else {
            s
        };
        let (s1, t, _, _) = at(r);
        (s1, t, r)
    }

    /// The return onto the cap alone from (σ*, |τ*|) with history κ₀: σ = σ*/(1 + 2Δλ kₙ),
    /// τ = τ*/(1 + 2Δλ kₛ C_ss) (associated flow), Δλ such that the point is on the cap
    /// of the new κ₃ = κ₀ + Δλ |(2σ, 2C_ss τ)| (theory.md, Eq. C4).
    fn ret_cap(&self, cap: &Cap, sig: f64, tau: f64, s: f64, kappa: f64) -> Option<Returned> {
        let (kn, ks) = self.stiffness();
        let css = cap.shear_factor;
        let at = |t: f64| {
            // t = 2 Δλ kₙ (dimensionless)
            let lam = t / (2.0 * kn);
            let sg = sig / (1.0 + t);
            let ta = tau / (1.0 + 2.0 * lam * ks * css);
            let k = kappa + cap.plastic_length(lam, sg, ta);
            (sg, ta, k)
        };
        let t = decreasing_root(
            |t| {
                let (sg, ta, k) = at(t);
                cap.radius(sg, ta) - cap.yield_value(k)
            },
            1e-9,
        )?;
        let (sg, ta, k) = at(t);
        Some(Returned {
            sig: sg,
            tau: ta,
            s,
            kappa: k,
        })
    }

    /// The return onto the corner of the cap and the shear surface: for a cap multiplier
    /// Δλ₃ the normal stress is σ*/(1 + 2Δλ₃ kₙ) and the shear return runs with the trial
    /// |τ*|/(1 + 2Δλ₃ kₛ C_ss) and the stiffness kₛ/(1 + 2Δλ₃ kₛ C_ss); Δλ₃ puts the result
    /// on the cap (theory.md, Eq. C5).
    fn ret_corner(&self, cap: &Cap, sig: f64, tau: f64, s: f64, kappa: f64) -> Option<Returned> {
        let (kn, ks) = self.stiffness();
        let css = cap.shear_factor;
        let at = |t: f64| {
            let lam = t / (2.0 * kn);
            let d = 1.0 + 2.0 * lam * ks * css;
            // σ (1 + 2Δλ₃kₙ) = σ* − kₙ Δλ₂ tan ψ: the slip return with kₙ/(1 + 2Δλ₃kₙ)
            let (sg, ta, r) = self.ret(
                sig / (1.0 + t),
                tau / d,
                s,
                (kn / (1.0 + t), ks / d),
                Active::Shear,
            );
            let k = kappa + cap.plastic_length(lam, sg, ta);
            (sg, ta, r, k)
        };
        let t = decreasing_root(
            |t| {
                let (sg, ta, _, k) = at(t);
                cap.radius(sg, ta) - cap.yield_value(k)
            },
            1e-9,
        )?;
        let (sg, ta, r, k) = at(t);
        Some(Returned {
            sig: sg,
            tau: ta,
            s: r,
            kappa: k,
        })
    }

    /// The return mapping of one contact, per unit area: trial stresses (σ*, τ*) (Pa)
    /// and history (ξ, κ₃) → stresses (Pa), state and new history. The state is open
    /// when the tension surface is active, slip when the shear surface is (alone or at the
    /// corner with the cap), stick otherwise (on the cap alone the contact crushes with its
    /// elastic springs in the secant matrix).
    pub fn stress_update(
        &self,
        sig: f64,
        tau: f64,
        h: History,
    ) -> ([f64; 2], ContactState, History) {
        let [xi, kappa] = h;
        let s = (1.0 - xi).clamp(0.0, 1.0);
        let (ft, c, tp) = (self.tensile_strength, self.cohesion, self.tan_phi);
        let cap_scale = self.cap.map_or(0.0, |c| c.strength);
        // relative tolerance of the yield checks: round-off of the stresses
        let tol = 1e-12 * (ft + c + cap_scale + sig.abs() + tau.abs());
        let f1 = |sg: f64, r: f64| sg - r * ft;
        let f2 = |sg: f64, ta: f64, r: f64| ta + sg * tp - r * c;
        let f3 = |sg: f64, ta: f64, k: f64| {
            self.cap.map_or(f64::NEG_INFINITY, |cp| {
                cp.radius(sg, ta) - cp.yield_value(k)
            })
        };
        let ta = tau.abs();
        if f1(sig, s) <= tol && f2(sig, ta, s) <= tol && f3(sig, ta, kappa) <= tol {
            return ([sig, tau], ContactState::Stick, h);
        }
        let done = |r: Returned, st| {
            (
                [r.sig, r.tau.copysign(tau)],
                st,
                [(1.0 - r.s).clamp(xi, 1.0), r.kappa.max(kappa)],
            )
        };
        let tension_shear = |active| {
            let (sg, t, r) = self.ret(sig, ta, s, self.stiffness(), active);
            Returned {
                sig: sg,
                tau: t,
                s: r,
                kappa,
            }
        };
        if f2(sig, ta, s) > tol {
            let out = tension_shear(Active::Shear);
            if f1(out.sig, out.s) <= tol && f3(out.sig, out.tau, kappa) <= tol {
                return done(out, ContactState::Slip);
            }
        }
        if f1(sig, s) > tol {
            let out = tension_shear(Active::Tension);
            if f2(out.sig, out.tau, out.s) <= tol {
                return done(out, ContactState::Open);
            }
            let out = tension_shear(Active::Both);
            if out.sig > 0.0 || self.cap.is_none() {
                return done(out, ContactState::Open);
            }
        }
        if let Some(cap) = &self.cap {
            if sig < 0.0 {
                if let Some(out) = self.ret_cap(cap, sig, ta, s, kappa) {
                    if f2(out.sig, out.tau, out.s) <= tol {
                        return done(out, ContactState::Stick);
                    }
                }
            }
            // a dilating joint reaches the corner in compression from a trial that is not
            // (its slip presses it): the corner, if it ends compressed
            if sig < 0.0 || self.dilatancy.is_some() {
                if let Some(out) = self.ret_corner(cap, sig, ta, s, kappa) {
                    if sig < 0.0 || out.sig <= 0.0 {
                        return done(out, ContactState::Slip);
                    }
                }
            }
        }
        done(tension_shear(Active::Both), ContactState::Open)
    }
}

impl ContactLaw for Softening {
    fn springs(&self, area: f64) -> ContactSprings {
        self.elastic.springs(area)
    }

    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        let (f, st, _) = self.update_history(area, committed, [0.0; 2], d);
        (f, st)
    }

    fn update_history(
        &self,
        area: f64,
        committed: [f64; 2],
        history: History,
        d: [f64; 2],
    ) -> ([f64; 2], ContactState, History) {
        let k = self.springs(area);
        let sig = (committed[0] + k.kn * d[0]) / area;
        let tau = (committed[1] + k.ks * d[1]) / area;
        let (s, st, h) = self.stress_update(sig, tau, history);
        ([s[0] * area, s[1] * area], st, h)
    }
}

impl Softening {
    /// The energy (J) a contact of area `area` (m²) spends in an increment against the
    /// strengths that soften or harden with its history, from the committed history
    /// `before` to `after` (ξ, κ₃), the contact ending in `state`:
    ///
    /// ```text
    /// ΔW = A (G Δξ + σ̄(κ₃) Δκ₃)                                  (theory.md, Eq. A2)
    /// ```
    ///
    /// with G = G_f^I where the tension surface is active (the contact opens) and G_f^II
    /// where the shear surface alone is (it slips). Along a pure mode this is exact:
    /// s′ = s exp(−fₜ Δλ₁/G_f^I) gives ∫ s fₜ dλ₁ = G_f^I (s − s′) = G_f^I Δξ, and likewise
    /// in shear with c and G_f^II; in mixed mode the work lies between G_f^I Δξ and
    /// G_f^II Δξ. The cap's work is its yield value at the end of the increment times the
    /// plastic length (backward Euler, exact under uniaxial compression). Friction is left
    /// out: it dissipates in whichever direction a joint slips, so an unloading that slides
    /// the joints back would dissipate as much as a crack that grows, while ξ and κ₃ only
    /// grow (docs/theory.md §3). The constraint of the dissipation-based arc length (Gutiérrez
    /// 2004, Verhoosel et al. 2009) in src/analysis/statics/arc_length.rs.
    pub fn softening_work(
        &self,
        area: f64,
        before: History,
        after: History,
        state: ContactState,
    ) -> f64 {
        let g = if state == ContactState::Open {
            self.fracture_energy_i
        } else {
            self.fracture_energy_ii
        };
        let dxi = (after[0] - before[0]).max(0.0);
        let cap = self.cap.map_or(0.0, |c| {
            c.yield_value(after[1]) * (after[1] - before[1]).max(0.0)
        });
        area * (g * dxi + cap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eindhoven joint data of docs/validation.md V8 in SI units: kₙ = 82 N/mm³, kₛ = 36 N/mm³
    /// with a 10 mm band, fₜ = 0.25 MPa, G_f^I = 0.018 N/mm, c = 0.35 MPa, tan φ = 0.75,
    /// G_f^II = 0.125 N/mm.
    pub(crate) fn eindhoven() -> Softening {
        Softening {
            elastic: ElasticBand {
                normal_modulus: 82e9 * 0.01,
                shear_modulus: 36e9 * 0.01,
                band: 0.01,
            },
            tan_phi: 0.75,
            cohesion: 0.35e6,
            tensile_strength: 0.25e6,
            fracture_energy_i: 18.0,
            fracture_energy_ii: 125.0,
            cap: None,
            dilatancy: None,
        }
    }

    /// [`eindhoven`] with the cap of Lourenço and Rots (1997) as docs/validation.md V8 gives
    /// it (fₘ = 10.5 N/mm², C_ss = 9) and the hardening/softening data of the example
    /// (`energy`: G_fc (N/m) and κₚ (m); `None`: perfectly plastic).
    fn with_cap(energy: Option<(f64, f64)>) -> Softening {
        Softening {
            cap: Some(Cap::new(10.5e6, 9.0, energy)),
            ..eindhoven()
        }
    }

    /// Uniaxial compression of a unit contact in steps of 0.1 µm to 3 mm: once on the
    /// cap, σ = −σ̄(κ₃) with κ₃ the plastic closure (the total closure less the elastic
    /// part σ/kₙ), and the work beyond the peak above the residual strength is G_fc.
    #[test]
    fn compression_follows_the_cap_law_and_dissipates_gfc() {
        let m = with_cap(Some((5000.0, 0.093e-3)));
        let cap = m.cap.unwrap();
        let kn = 82e9;
        let (mut f, mut h) = ([0.0, 0.0], [0.0; 2]);
        let (mut up, mut work, mut on_cap) = (0.0f64, 0.0, 0);
        let du = -1e-7;
        let (kp, _) = cap.softening.unwrap();
        for _ in 0..30_000 {
            let (g, st, h2) = m.update_history(1.0, f, h, [du, 0.0]);
            assert_eq!(st, ContactState::Stick);
            assert_eq!(g[1], 0.0);
            let dup = du - (g[0] - f[0]) / kn;
            if up.abs() >= kp {
                work += (-0.5 * (g[0] + f[0]) - 10.5e6 / 7.0) * -dup;
            }
            up += dup;
            if h2[1] > 0.0 {
                on_cap += 1;
                // the return's κ₃ is the plastic closure (to the bisection's 2⁻⁸⁰ and
                // the round-off of the sum of 30 000 steps) and σ = −σ̄(κ₃)
                assert!(
                    (h2[1] + up).abs() < 1e-9 * (1.0 + up.abs()) + 1e-15,
                    "{h2:?} {up}"
                );
                let expected = -cap.yield_value(-up);
                assert!(
                    (g[0] - expected).abs() < 1e-6 * 10.5e6,
                    "{} {}",
                    g[0],
                    expected
                );
            }
            assert_eq!(
                h2[0], 0.0,
                "compression spends no fracture energy of the joint"
            );
            f = g;
            h = h2;
        }
        assert!(on_cap > 25_000);
        // trapezoid rule with 0.1 µm on a softening length κₘ − κₚ = 0.58 mm, from κₚ
        // (the first step past it is counted whole: ≤ 0.1 µm × fₘ = 1 N/m); the tail
        // beyond 3 mm is exp(−2·2.9/0.58 · 0.5/0.36…) ≈ 1e-6 of G_fc
        assert!((work - 5000.0).abs() < 2e-3 * 5000.0, "work {work}");
    }

    /// A trial point outside the perfectly plastic cap returns onto the ellipse
    /// σ² + C_ss τ² = fₘ² along the associated flow: the plastic relative displacement
    /// (Δδ − ΔF/k) is parallel to (σ, C_ss τ). Checked against an independent Newton
    /// solution of the same return in the multiplier.
    #[test]
    fn cap_return_is_normal_to_the_ellipse() {
        let m = with_cap(None);
        let (kn, ks, css, fc) = (82e9, 36e9, 9.0, 10.5e6);
        // from σ₀ = −9 MPa, τ₀ = 3 MPa (inside the Coulomb cone: 3 < 0.35 + 6.75), a step
        // further in compression and shear
        let (s0, t0) = (-9.0e6, 3.0e6);
        let d = [-4e-5, 2e-5];
        let (g, st, h) = m.update_history(1.0, [s0, t0], [0.0; 2], d);
        assert_eq!(st, ContactState::Stick);
        let (sig, tau) = (g[0], g[1]);
        assert!((sig * sig + css * tau * tau).sqrt() - fc < 1e-9 * fc);
        let dup = [d[0] - (sig - s0) / kn, d[1] - (tau - t0) / ks];
        let cross = dup[0] * css * tau - dup[1] * sig;
        assert!(cross.abs() < 1e-9 * dup[0].hypot(dup[1]) * fc, "not normal");
        assert!((h[1] - dup[0].hypot(dup[1])).abs() < 1e-12, "κ₃ {h:?}");
        // independent: Newton on x = 2Δλ in σ = σ*/(1 + x kₙ), τ = τ*/(1 + x kₛ C_ss)
        let (ss, ts) = (s0 + kn * d[0], t0 + ks * d[1]);
        let mut x = 0.0;
        for _ in 0..50 {
            let (a, b) = (1.0 + x * kn, 1.0 + x * ks * css);
            let r = ss * ss / (a * a) + css * ts * ts / (b * b) - fc * fc;
            let dr =
                -2.0 * ss * ss * kn / (a * a * a) - 2.0 * css * ts * ts * ks * css / (b * b * b);
            x -= r / dr;
        }
        assert!((sig - ss / (1.0 + x * kn)).abs() < 1e-6, "{sig}");
        assert!((tau - ts / (1.0 + x * ks * css)).abs() < 1e-6, "{tau}");
    }

    /// With the cohesion spent (ξ = 1) and a perfectly plastic cap, the corner of the cap
    /// and the friction line is σ_c = −fₘ/√(1 + C_ss tan²φ), τ_c = −σ_c tan φ. A trial
    /// point built from it by positive multipliers of both flows returns to it.
    #[test]
    fn corner_of_cap_and_friction_line() {
        let m = with_cap(None);
        let (kn, ks, css, fc, tp): (f64, f64, f64, f64, f64) = (82e9, 36e9, 9.0, 10.5e6, 0.75);
        let sc = -fc / (1.0 + css * tp * tp).sqrt();
        let tc = -sc * tp;
        for (l2, l3) in [(1e-5, 1e-12), (1e-6, 1e-13), (0.0, 1e-12), (1e-5, 0.0)] {
            let trial = [
                sc * (1.0 + 2.0 * l3 * kn),
                tc * (1.0 + 2.0 * l3 * ks * css) + l2 * ks,
            ];
            let (g, st, h) = m.stress_update(trial[0], trial[1], [1.0, 0.0]);
            // on the cap's flow alone the return lands on the corner from the cap's side
            let expected = if l2 > 0.0 {
                ContactState::Slip
            } else {
                ContactState::Stick
            };
            assert_eq!(st, expected, "{l2} {l3}");
            assert!(
                (g[0] - sc).abs() < 1e-6 * fc,
                "{l2} {l3}: σ {} against {sc}",
                g[0]
            );
            assert!(
                (g[1] - tc).abs() < 1e-6 * fc,
                "{l2} {l3}: τ {} against {tc}",
                g[1]
            );
            // κ₃ = Δλ₃ |(2σ, 2C_ss τ)|
            let k = 2.0 * l3 * sc.hypot(css * tc);
            assert!(
                (h[1] - k).abs() <= 1e-6 * k + 1e-18,
                "{l2} {l3}: κ₃ {} against {k}",
                h[1]
            );
        }
        // the same trial without the cap slips along the friction line beyond fₘ
        let trial = [sc * (1.0 + 2e-12 * kn), tc + 1e-5 * ks];
        let (g, _, _) = eindhoven().stress_update(trial[0], trial[1], [1.0, 0.0]);
        assert!(g[0] < sc * 1.1);
    }

    /// Pure tension, one contact of unit area opened in small steps: σ follows
    /// fₜ exp(−fₜ u_p/G_f^I) at every step, and ∫σ du_p → G_f^I.
    #[test]
    fn tension_follows_the_exponential_and_dissipates_gf1() {
        let m = eindhoven();
        let kn = 82e9;
        let (mut f, mut xi, mut up, mut work) = ([0.0, 0.0], 0.0, 0.0, 0.0);
        let du = 1e-7; // 0.1 µm per step; the crack opens to 1 mm
        let mut opened = false;
        for _ in 0..10_000 {
            let (g, st, x) = m.update_history(1.0, f, [xi, 0.0], [du, 0.0]);
            // plastic opening of the step: the total minus the elastic change
            let dup = du - (g[0] - f[0]) / kn;
            work += 0.5 * (g[0] + f[0]) * dup;
            up += dup;
            if st == ContactState::Open {
                opened = true;
                let expected = 0.25e6 * (-0.25e6 * up / 18.0).exp();
                // the bisection returns s′ to 2⁻⁶⁰; round-off of the sum of u_p
                assert!(
                    (g[0] - expected).abs() <= 1e-9 * 0.25e6,
                    "{} {}",
                    g[0],
                    expected
                );
            }
            f = g;
            xi = x[0];
        }
        assert!(opened);
        // the trapezoidal rule of ∫σ du_p with steps of 0.1 µm on a decay length of
        // G/fₜ = 72 µm: relative error ~ (Δu/ℓ)²/12 ≈ 1e-7; at 1 mm the tail
        // exp(−1000/72) ≈ 1e-6 is left
        assert!((work - 18.0).abs() < 1e-4 * 18.0, "work {work}");
        assert!((xi - 1.0).abs() < 1e-4, "xi {xi}");
    }

    /// [`Softening::softening_work`] over a pull in tension of a unit contact in steps of
    /// 1 µm to 1 mm: zero on the elastic branch, positive at every step past the peak, and
    /// summing to G_f^I (1 − s) at the remaining fraction s exactly (the exponential's
    /// integral, to round-off); then a shear that slides the spent joint back and forth
    /// under compression spends nothing more, though friction dissipates.
    #[test]
    fn softening_work_of_a_pull_is_gf1_and_friction_is_left_out() {
        let m = eindhoven();
        let (mut f, mut h) = ([0.0, 0.0], [0.0; 2]);
        let mut sum = 0.0;
        let du = 1e-6;
        for _ in 0..1000 {
            let (g, st, h2) = m.update_history(1.0, f, h, [du, 0.0]);
            let w = m.softening_work(1.0, h, h2, st);
            if st == ContactState::Stick {
                assert_eq!(w, 0.0, "elastic step");
            } else {
                assert!(w > 0.0, "plastic step spends {w}");
            }
            sum += w;
            (f, h) = (g, h2);
        }
        let gf = 18.0;
        eprintln!("pull: spent {sum} J/m² of G_f^I = {gf}, ξ = {}", h[0]);
        assert!((sum - gf * h[0]).abs() < 1e-12 * gf, "{sum} {}", h[0]);
        assert!(h[0] > 1.0 - 1e-5, "ξ = {}", h[0]);
        // close the crack into compression, then slide it back and forth
        // (the crack's plastic opening stays: σ = −1 MPa after an elastic closure)
        let (g, _, h2) = m.update_history(1.0, f, h, [-(f[0] + 1e6) / 82e9, 0.0]);
        (f, h) = (g, h2);
        assert!(f[0] < 0.0, "{f:?}");
        // at most the remaining cohesion's G_f^II (1 − ξ) can be spent, against about
        // 0.75 MPa × 3 mm of friction work
        let left = 125.0 * (1.0 - h[0]);
        let (mut spent, mut friction) = (0.0, 0.0);
        for k in 0..40 {
            let ds = if (k / 10) % 2 == 0 { 1e-4 } else { -1e-4 };
            let (g, st, h2) = m.update_history(1.0, f, h, [0.0, ds]);
            spent += m.softening_work(1.0, h, h2, st);
            if st == ContactState::Slip {
                friction += g[1].abs() * (ds - (g[1] - f[1]) / 36e9).abs();
            }
            (f, h) = (g, h2);
        }
        eprintln!("slides: spent {spent} J/m² (≤ {left}), friction {friction} J/m²");
        assert!(spent <= left * (1.0 + 1e-9) + 1e-15, "{spent} {left}");
        assert!(friction > 1e3, "{friction}");
    }

    /// Shear under a constant compression σ = −0.3 MPa: τ = c exp(−c u_p/G_f^II) − σ tan φ,
    /// ending at the residual friction; the work beyond friction is G_f^II.
    #[test]
    fn shear_softens_to_friction_and_dissipates_gf2() {
        let m = eindhoven();
        let (kn, ks) = (82e9, 36e9);
        let sigma = -0.3e6;
        let mut f = [sigma, 0.0];
        let (mut xi, mut up, mut work) = (0.0, 0.0, 0.0);
        let du = 1e-6;
        // compress first (elastic), then shear in steps of 1 µm to 8 mm
        let (g, st, _) = m.update_history(1.0, [0.0, 0.0], [0.0; 2], [sigma / kn, 0.0]);
        assert_eq!(st, ContactState::Stick);
        assert!((g[0] - sigma).abs() < 1e-6);
        for _ in 0..8000 {
            let (g, st, x) = m.update_history(1.0, f, [xi, 0.0], [0.0, du]);
            assert!((g[0] - sigma).abs() < 1e-6, "the normal stress stays");
            let dup = du - (g[1] - f[1]) / ks;
            work += (0.5 * (g[1] + f[1]) + sigma * 0.75) * dup;
            up += dup;
            if st == ContactState::Slip {
                let expected = 0.35e6 * (-0.35e6 * up / 125.0).exp() - sigma * 0.75;
                assert!(
                    (g[1] - expected).abs() <= 1e-9 * 0.35e6,
                    "{} {}",
                    g[1],
                    expected
                );
            }
            f = g;
            xi = x[0];
        }
        assert!(
            (f[1] + sigma * 0.75).abs() < 1e-3 * 0.35e6,
            "residual friction"
        );
        // decay length G/c = 357 µm, steps of 1 µm: trapezoid error ~1e-6; the tail
        // exp(−8000/357) ≈ 2e-10
        assert!((work - 125.0).abs() < 1e-4 * 125.0, "work {work}");
    }

    /// A mixed-mode path (opening and sliding together) ends with no strength left and
    /// spends exactly the fracture energy fractions: ξ = W_I/G_f^I + W_II/G_f^II.
    #[test]
    fn mixed_mode_spends_the_energy_fractions() {
        let m = eindhoven();
        let (kn, ks) = (82e9, 36e9);
        let (mut f, mut xi) = ([0.0, 0.0], 0.0);
        let (mut w1, mut w2) = (0.0, 0.0);
        for _ in 0..20_000 {
            let d = [1e-7, 2e-7];
            let (g, _, x) = m.update_history(1.0, f, [xi, 0.0], d);
            let dn = d[0] - (g[0] - f[0]) / kn;
            let ds = d[1] - (g[1] - f[1]) / ks;
            let sn = 0.5 * (g[0] + f[0]);
            let ts = 0.5 * (g[1] + f[1]);
            w1 += sn * dn;
            // the cohesive part of the shear stress: |τ| + σ tan φ
            w2 += (ts + sn * 0.75) * ds;
            f = g;
            xi = x[0];
        }
        assert!(xi > 0.999, "xi {xi}");
        let spent = w1 / 18.0 + w2 / 125.0;
        assert!((spent - xi).abs() < 1e-3, "spent {spent} xi {xi}");
    }

    /// Closing a softened crack: elastic in compression, friction without cohesion.
    #[test]
    fn a_spent_joint_is_frictional() {
        let m = eindhoven();
        let (g, st, h) = m.update_history(1.0, [0.0, 0.0], [1.0, 0.0], [1e-6, 0.0]);
        assert_eq!((g, st, h), ([0.0, 0.0], ContactState::Open, [1.0, 0.0]));
        let (g, st, _) = m.update_history(1.0, [0.0, 0.0], [1.0, 0.0], [-1e-5, 1e-4]);
        assert_eq!(st, ContactState::Slip);
        assert!((g[0] + 82e9 * 1e-5).abs() < 1e-3);
        assert!((g[1] - 0.75 * 82e9 * 1e-5).abs() < 1e-3);
    }

    /// A joint pressed to σ₀ = −0.5 MPa, its normal relative displacement then held, and
    /// sheared in steps of 10 nm, with the cohesion spent (c = fₜ = 0: pure friction) and
    /// the dilatancy tan ψ₀ = 0.5, σᵤ = 2 MPa (Eq. D1). On the friction line the plastic
    /// opening tan ψ(σ) du_p is taken back by the held normal displacement, dσ = −kₙ
    /// tan ψ₀ (1 + σ/σᵤ) du_p, so
    ///
    /// ```text
    /// σ(u_p) = −σᵤ + (σ₀ + σᵤ) exp(−kₙ tan ψ₀ u_p / σᵤ),   τ = −σ tan φ
    /// ```
    ///
    /// with u_p = δₛ − τ/kₛ the plastic slip: the compression builds up towards σᵤ and no
    /// further. Backward Euler over steps of du_p ≤ 10 nm against the decay length
    /// L = σᵤ/(kₙ tan ψ₀) = 49 µm lags by at most du_p/(2L) of σ + σᵤ ≤ 1.5 MPa, 153 Pa:
    /// the tolerance is 10⁻⁴ σᵤ = 200 Pa (measured: 41 Pa). Without the dilatancy the
    /// same path keeps σ = σ₀.
    #[test]
    fn confined_slip_builds_compression_up_to_the_dilatancy_stress() {
        let (kn, ks, tp) = (82e9, 36e9, 0.75);
        let (s0, su, tpsi) = (-0.5e6, 2e6, 0.5);
        let base = Softening {
            cohesion: 0.0,
            tensile_strength: 0.0,
            ..eindhoven()
        };
        let dilating = Softening {
            dilatancy: Some(Dilatancy {
                tan_psi: tpsi,
                stress: su,
            }),
            ..base
        };
        for (m, dilates) in [(dilating, true), (base, false)] {
            let (mut f, mut h) = ([s0, 0.0], [0.0; 2]);
            let (mut ds, mut worst, mut slipped) = (0.0, 0.0_f64, 0);
            for _ in 0..30_000 {
                let step = 1e-8;
                let (g, st, hh) = m.update_history(1.0, f, h, [0.0, step]);
                (f, h, ds) = (g, hh, ds + step);
                if st != ContactState::Slip {
                    assert!(
                        f[1] < -s0 * tp * (1.0 + 1e-9),
                        "sticks below the friction line"
                    );
                    continue;
                }
                slipped += 1;
                let up = ds - f[1] / ks;
                let exact = if dilates {
                    -su + (s0 + su) * (-kn * tpsi * up / su).exp()
                } else {
                    s0
                };
                worst = worst.max((f[0] - exact).abs());
                assert!((f[1] + f[0] * tp).abs() < 1e-6 * su, "τ = −σ tan φ");
            }
            assert!(slipped > 25_000, "{slipped} slipping steps");
            assert!(worst < 1e-4 * su, "σ off the closed form by {worst} Pa");
            if dilates {
                // 270 µm of slip, 5.5 decay lengths: within 0.5 % of σᵤ
                assert!((f[0] + su).abs() < 0.005 * su, "σ = {} Pa at the end", f[0]);
            } else {
                assert_eq!(f[0], s0);
            }
        }
    }

    /// The dilatant return over a grid of trial stresses (σ* from −14 to +1 MPa, |τ*| to
    /// 8 MPa, fresh and 60 % spent joints), without and with the cap (σᵤ = 20 MPa so that
    /// the joint still dilates at the cap's corner): every result lies inside the
    /// surfaces (to 10⁻⁹ of the stress scale), and the plastic relative displacement
    /// (σ* − σ)/kₙ, (|τ*| − |τ|)/kₛ splits into the flows of the active surfaces with
    /// multipliers ≥ 0 (Eq. D1): a slipping joint's plastic opening is tan ψ(σ) times its
    /// plastic slip, plus 2σΔλ₃ on the cap's corner, whose slip is Δλ₂ + 2C_ss|τ|Δλ₃;
    /// an open one lies on the tension cut-off and opens (without dilating).
    #[test]
    fn dilatant_returns_stay_on_the_surfaces_with_nonnegative_flows() {
        let (kn, ks) = (82e9, 36e9);
        let mut checked = [0usize; 3];
        for (m, su) in [
            (eindhoven(), 2e6),
            (with_cap(Some((5000.0, 0.093e-3))), 20e6),
        ] {
            let d = Dilatancy {
                tan_psi: 0.5,
                stress: su,
            };
            let m = Softening {
                dilatancy: Some(d),
                ..m
            };
            let scale = 10.5e6;
            for xi in [0.0, 0.6] {
                for i in 0..=60 {
                    for j in 0..=40 {
                        let sig = -14e6 + 15e6 * i as f64 / 60.0;
                        let tau = 8e6 * j as f64 / 40.0;
                        let (g, st, h) = m.stress_update(sig, tau, [xi, 0.0]);
                        let (sg, ta) = (g[0], g[1].abs());
                        let r = 1.0 - h[0];
                        let tol = 1e-9 * scale;
                        assert!(sg - r * m.tensile_strength <= tol, "f1 at {sig} {tau}");
                        assert!(
                            ta + sg * m.tan_phi - r * m.cohesion <= tol,
                            "f2 at {sig} {tau}: σ {sg} τ {ta}"
                        );
                        if let Some(cap) = m.cap {
                            assert!(
                                cap.radius(sg, ta) - cap.yield_value(h[1]) <= tol,
                                "f3 at {sig} {tau}"
                            );
                        }
                        let (un, us) = ((sig - sg) / kn, (tau - ta) / ks);
                        let tp = d.tan_at(sg);
                        let flow_tol = 1e-7 * (un.abs() + us.abs()) + 1e-18;
                        match st {
                            ContactState::Stick if h[1] == 0.0 => {
                                assert!(un.abs() <= flow_tol && us.abs() <= flow_tol);
                                checked[0] += 1;
                            }
                            ContactState::Slip if h[1] == 0.0 => {
                                // the shear surface alone
                                assert!(us >= -flow_tol, "slip back at {sig} {tau}");
                                assert!(
                                    (un - tp * us).abs() <= flow_tol,
                                    "{sig} {tau}: opening {un} against tan ψ × slip {}",
                                    tp * us
                                );
                                checked[1] += 1;
                            }
                            ContactState::Slip => {
                                // the cap's corner: un = tp l2 + 2σ l3, us = l2 + 2 C_ss |τ| l3
                                let css = m.cap.unwrap().shear_factor;
                                let (a, b, c, e) = (tp, 2.0 * sg, 1.0, 2.0 * css * ta);
                                let det = a * e - b * c;
                                let l2 = (un * e - b * us) / det;
                                let l3 = (a * us - c * un) / det;
                                let lt = 1e-6 * (l2.abs() + l3.abs() * scale);
                                assert!(l2 >= -lt && l3 >= -lt, "{sig} {tau}: Δλ₂ {l2}, Δλ₃ {l3}");
                                checked[2] += 1;
                            }
                            ContactState::Open => {
                                // on the cut-off: opening, no dilatancy
                                assert!(un >= -flow_tol, "{sig} {tau}: {un} {us}");
                                assert!((sg - r * m.tensile_strength).abs() <= tol);
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
        // every kind of return was met on the grid
        assert!(checked.iter().all(|&n| n > 20), "{checked:?}");
    }
}
