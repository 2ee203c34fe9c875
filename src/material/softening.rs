//! The softening joint (METHOD.md §3; docs/theory.md, "Softening joints"): tension
//! cut-off and Mohr–Coulomb strength whose tensile strength and cohesion soften
//! exponentially with the fracture energies G_f^I and G_f^II, friction remaining, after
//! the interface model of Lourenço and Rots (1997) without its compression cap.
//!
//! Stresses per unit contact area (Pa), compression negative; relative displacements
//! (m). With the elastic trial stresses σ* = σ₀ + kₙ Δδₙ, τ* = τ₀ + kₛ Δδₛ (kₙ = Eₙ/h,
//! kₛ = Gₛ/h in N/m³) and the history ξ (the spent fraction of the fracture energy,
//! 0 ≤ ξ ≤ 1; s = 1 − ξ the remaining fraction of the strengths):
//! * tension surface f₁ = σ − s fₜ, associated flow: plastic opening Δλ₁;
//! * shear surface f₂ = |τ| + σ tan φ − s c, no dilatancy: plastic slip Δλ₂;
//! * softening: dξ = (s fₜ dλ₁)/G_f^I + (s c dλ₂)/G_f^II, the work spent against the
//!   tensile strength and against the cohesion, each over its own fracture energy (the
//!   linear mixed-mode energy criterion). Within an increment s′ = s exp(−fₜ Δλ₁/G_f^I −
//!   c Δλ₂/G_f^II), exact along a radial plastic path. Under pure tension this is
//!   σ = fₜ exp(−fₜ u_p/G_f^I) with ∫σ du_p = G_f^I; under shear at constant σ,
//!   τ = c exp(−c u_p/G_f^II) − σ tan φ with ∫(τ + σ tan φ) du_p = G_f^II.
//!
//! Everything is per unit area and per unit relative displacement, so the dissipated
//! energy of a joint is G_f × its area whatever the number of contacts it is split
//! into: the regularisation that keeps the response independent of the mesh.

use super::{ContactLaw, ContactSprings, ContactState, ElasticBand};
use crate::scene::Joint;

/// Mode-I and mode-II exponential softening of a Mohr–Coulomb band with tension cut-off.
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
}

/// Which surfaces are active in a return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Active {
    Tension,
    Shear,
    Both,
}

/// Bisection steps of the scalar return equation: the bracket [0, s] shrinks to 2⁻⁶⁰ s.
const BISECTIONS: usize = 60;

impl Softening {
    pub fn from_joint(j: &Joint) -> Self {
        Softening {
            elastic: ElasticBand::from_joint(j),
            tan_phi: j.friction_angle.to_radians().tan(),
            cohesion: j.cohesion,
            tensile_strength: j.tensile_strength,
            fracture_energy_i: j.fracture_energy_i,
            fracture_energy_ii: j.fracture_energy_ii,
        }
    }

    /// The return of the trial stresses (σ*, |τ*|) (Pa) with the active set `active` from
    /// the remaining fraction `s`: (σ, |τ|, s′, Δλ₁, Δλ₂). The unknown is s′ ∈ [0, s]:
    /// the plastic multipliers follow from it linearly (the stresses on the active
    /// surfaces at strength s′), and s′ = s exp(−a Δλ₁ − b Δλ₂) is solved by bisection
    /// (its left side minus right side increases from −s·e^… < 0 at s′ = 0 to ≥ 0 at s′ = s).
    fn ret(&self, sig: f64, tau: f64, s: f64, active: Active) -> (f64, f64, f64, f64, f64) {
        let (kn, ks) = (
            self.elastic.normal_modulus / self.elastic.band,
            self.elastic.shear_modulus / self.elastic.band,
        );
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
                    let t = (r * c - sig * tp).max(0.0);
                    (sig, t, 0.0, (tau - t) / ks)
                }
                Active::Both => {
                    let s1 = r * ft;
                    let t = (r * c - s1 * tp).max(0.0);
                    (s1, t, (sig - s1) / kn, (tau - t) / ks)
                }
            }
        };
        let resid = |r: f64| {
            let (_, _, l1, l2) = at(r);
            r - s * (-a * l1.max(0.0) - b * l2.max(0.0)).exp()
        };
        let (mut lo, mut hi) = (0.0, s);
        if s > 0.0 && resid(hi) > 0.0 {
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if resid(mid) > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
        }
        let r = 0.5 * (lo + hi);
        let (s1, t, l1, l2) = at(r);
        (s1, t, r, l1, l2)
    }

    /// The return mapping of one contact, per unit area: trial stresses (σ*, τ*) (Pa)
    /// and history ξ → stresses (Pa), state and new history.
    pub fn stress_update(&self, sig: f64, tau: f64, xi: f64) -> ([f64; 2], ContactState, f64) {
        let s = (1.0 - xi).clamp(0.0, 1.0);
        let (ft, c, tp) = (self.tensile_strength, self.cohesion, self.tan_phi);
        // relative tolerance of the yield checks: round-off of the stresses
        let tol = 1e-12 * (ft + c + sig.abs() + tau.abs());
        let f1 = sig - s * ft;
        let f2 = tau.abs() + sig * tp - s * c;
        if f1 <= tol && f2 <= tol {
            return ([sig, tau], ContactState::Stick, xi);
        }
        let ta = tau.abs();
        let done = |(s1, t, r, _, _): (f64, f64, f64, f64, f64), st| {
            ([s1, t.copysign(tau)], st, (1.0 - r).clamp(xi, 1.0))
        };
        if f2 > tol {
            let out = self.ret(sig, ta, s, Active::Shear);
            if out.0 - out.2 * ft <= tol {
                return done(out, ContactState::Slip);
            }
        }
        if f1 > tol {
            let out = self.ret(sig, ta, s, Active::Tension);
            if out.1 + out.0 * tp - out.2 * c <= tol {
                return done(out, ContactState::Open);
            }
        }
        done(self.ret(sig, ta, s, Active::Both), ContactState::Open)
    }
}

impl ContactLaw for Softening {
    fn springs(&self, area: f64) -> ContactSprings {
        self.elastic.springs(area)
    }

    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        let (f, st, _) = self.update_history(area, committed, 0.0, d);
        (f, st)
    }

    fn update_history(
        &self,
        area: f64,
        committed: [f64; 2],
        history: f64,
        d: [f64; 2],
    ) -> ([f64; 2], ContactState, f64) {
        let k = self.springs(area);
        let sig = (committed[0] + k.kn * d[0]) / area;
        let tau = (committed[1] + k.ks * d[1]) / area;
        let (s, st, xi) = self.stress_update(sig, tau, history);
        ([s[0] * area, s[1] * area], st, xi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eindhoven joint data of BENCHMARKS.md V8 in SI units: kₙ = 82 N/mm³, kₛ = 36 N/mm³
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
        }
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
            let (g, st, x) = m.update_history(1.0, f, xi, [du, 0.0]);
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
            xi = x;
        }
        assert!(opened);
        // the trapezoidal rule of ∫σ du_p with steps of 0.1 µm on a decay length of
        // G/fₜ = 72 µm: relative error ~ (Δu/ℓ)²/12 ≈ 1e-7; at 1 mm the tail
        // exp(−1000/72) ≈ 1e-6 is left
        assert!((work - 18.0).abs() < 1e-4 * 18.0, "work {work}");
        assert!((xi - 1.0).abs() < 1e-4, "xi {xi}");
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
        let (g, st, _) = m.update_history(1.0, [0.0, 0.0], 0.0, [sigma / kn, 0.0]);
        assert_eq!(st, ContactState::Stick);
        assert!((g[0] - sigma).abs() < 1e-6);
        for _ in 0..8000 {
            let (g, st, x) = m.update_history(1.0, f, xi, [0.0, du]);
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
            xi = x;
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
            let (g, _, x) = m.update_history(1.0, f, xi, d);
            let dn = d[0] - (g[0] - f[0]) / kn;
            let ds = d[1] - (g[1] - f[1]) / ks;
            let sn = 0.5 * (g[0] + f[0]);
            let ts = 0.5 * (g[1] + f[1]);
            w1 += sn * dn;
            // the cohesive part of the shear stress: |τ| + σ tan φ
            w2 += (ts + sn * 0.75) * ds;
            f = g;
            xi = x;
        }
        assert!(xi > 0.999, "xi {xi}");
        let spent = w1 / 18.0 + w2 / 125.0;
        assert!((spent - xi).abs() < 1e-3, "spent {spent} xi {xi}");
    }

    /// Closing a softened crack: elastic in compression, friction without cohesion.
    #[test]
    fn a_spent_joint_is_frictional() {
        let m = eindhoven();
        let (g, st, xi) = m.update_history(1.0, [0.0, 0.0], 1.0, [1e-6, 0.0]);
        assert_eq!((g, st, xi), ([0.0, 0.0], ContactState::Open, 1.0));
        let (g, st, _) = m.update_history(1.0, [0.0, 0.0], 1.0, [-1e-5, 1e-4]);
        assert_eq!(st, ContactState::Slip);
        assert!((g[0] + 82e9 * 1e-5).abs() < 1e-3);
        assert!((g[1] - 0.75 * 82e9 * 1e-5).abs() < 1e-3);
    }
}
