//! The compression cap of the softening joint (docs/theory.md, "Compression cap"), after
//! the composite interface model of Lourenço and Rots (1997): an ellipse in the
//! (σ, τ) plane (Pa, compression negative),
//!
//! ```text
//! f₃ = σ² + C_ss τ² − σ̄(κ₃)² ≤ 0                                   (theory.md, Eq. C1)
//! ```
//!
//! with associated flow (the plastic relative displacement Δu_p = Δλ₃ (2σ, 2 C_ss τ), m)
//! and the history κ₃ (m), the accumulated length |Δu_p| of the plastic relative
//! displacement on the cap. The yield value σ̄(κ₃) hardens from fₘ/3 to the compressive
//! strength fₘ at κₚ, then softens to fₘ/2 at κₘ and on to the residual fₘ/7 (Eq. C2):
//!
//! ```text
//! σ̄ = σ̄ᵢ + (σ̄ₚ − σ̄ᵢ) √(2κ/κₚ − κ²/κₚ²)                      0 ≤ κ ≤ κₚ
//! σ̄ = σ̄ₚ + (σ̄ₘ − σ̄ₚ) ((κ − κₚ)/(κₘ − κₚ))²                    κₚ ≤ κ ≤ κₘ
//! σ̄ = σ̄ᵣ + (σ̄ₘ − σ̄ᵣ) exp(m (κ − κₘ)/(σ̄ₘ − σ̄ᵣ)),  m = 2 (σ̄ₘ − σ̄ₚ)/(κₘ − κₚ)   κ ≥ κₘ
//! ```
//!
//! (σ̄ᵢ, σ̄ₚ, σ̄ₘ, σ̄ᵣ) = (fₘ/3, fₘ, fₘ/2, fₘ/7), C¹ across κₚ and κₘ. κₘ follows from the
//! compressive fracture energy G_fc (N/m), the work per unit joint area spent beyond the
//! peak above the residual strength in uniaxial compression (Eq. C3):
//!
//! ```text
//! G_fc = ∫_{κₚ}^{∞} (σ̄ − σ̄ᵣ) dκ = (κₘ − κₚ) fₘ (29/42 + 25/196) = (481/588) fₘ (κₘ − κₚ)
//! ```
//!
//! (the parabola gives (5/6 − 1/7) fₘ (κₘ − κₚ), the exponential tail
//! (σ̄ₘ − σ̄ᵣ)²/|m| = (25/196) fₘ (κₘ − κₚ)). Without G_fc the cap is perfectly plastic at
//! fₘ. Everything is per unit area and per unit relative displacement, so that, as for
//! G_f^I and G_f^II, the energy a joint dissipates does not depend on how many contacts
//! it is split into.

/// The compression cap of a joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cap {
    /// Compressive strength fₘ (Pa), > 0.
    pub strength: f64,
    /// C_ss, the weight of the shear stress in the cap (dimensionless, > 0).
    pub shear_factor: f64,
    /// Hardening and softening: `Some((κₚ, κₘ))` (m), the plastic relative displacement
    /// at the peak and at the end of the parabolic softening; `None`: perfectly plastic at
    /// fₘ.
    pub softening: Option<(f64, f64)>,
}

/// The part of G_fc / (fₘ (κₘ − κₚ)) of Eq. C3.
pub const ENERGY_FACTOR: f64 = 481.0 / 588.0;

impl Cap {
    /// The cap of strength `fc` (Pa) and shear factor `css`; with `Some((g_fc, κₚ))`
    /// (N/m, m) it hardens to fₘ at κₚ and softens with the energy G_fc (Eq. C3).
    pub fn new(fc: f64, css: f64, energy: Option<(f64, f64)>) -> Cap {
        Cap {
            strength: fc,
            shear_factor: css,
            softening: energy.map(|(g, kp)| (kp, kp + g / (ENERGY_FACTOR * fc))),
        }
    }

    /// σ̄(κ₃) (Pa) of Eq. C2 at the plastic relative displacement `k` (m).
    pub fn yield_value(&self, k: f64) -> f64 {
        let fc = self.strength;
        let Some((kp, km)) = self.softening else {
            return fc;
        };
        let (si, sp, sm, sr) = (fc / 3.0, fc, 0.5 * fc, fc / 7.0);
        let k = k.max(0.0);
        if k <= kp {
            let x = k / kp;
            si + (sp - si) * (2.0 * x - x * x).max(0.0).sqrt()
        } else if k <= km {
            let x = (k - kp) / (km - kp);
            sp + (sm - sp) * x * x
        } else {
            let m = 2.0 * (sm - sp) / (km - kp);
            sr + (sm - sr) * (m * (k - km) / (sm - sr)).exp()
        }
    }

    /// The cap's radius √(σ² + C_ss τ²) (Pa) of a stress point: the point is on the cap
    /// when this equals σ̄ (Eq. C1 written as a norm, which keeps the check in Pa).
    pub fn radius(&self, sig: f64, tau: f64) -> f64 {
        (sig * sig + self.shear_factor * tau * tau).sqrt()
    }

    /// The length of the plastic relative displacement (m) of a multiplier `lam` (m/Pa)
    /// at the stress (σ, τ): Δλ₃ |(2σ, 2 C_ss τ)|.
    pub fn plastic_length(&self, lam: f64, sig: f64, tau: f64) -> f64 {
        2.0 * lam * sig.hypot(self.shear_factor * tau)
    }
}

/// Bisection steps of the cap returns: the bracket shrinks to 2⁻⁸⁰ of its width.
const CAP_BISECTIONS: usize = 80;

/// The root t ∈ [0, ∞) of a decreasing `f` with f(0) > 0, by doubling an upper bound from
/// `t0` (at most 200 times) and bisecting; `None` when no sign change is found.
pub fn decreasing_root(f: impl Fn(f64) -> f64, t0: f64) -> Option<f64> {
    let mut hi = t0;
    let mut found = false;
    for _ in 0..200 {
        if f(hi) <= 0.0 {
            found = true;
            break;
        }
        hi *= 2.0;
    }
    if !found {
        return None;
    }
    Some(bisect(0.0, hi, CAP_BISECTIONS, |t| f(t) <= 0.0))
}

/// The midpoint of the bracket [lo, hi] after `steps` bisections of a condition `past`
/// that is false at `lo` and true at `hi` (and switches once between them).
pub fn bisect(mut lo: f64, mut hi: f64, steps: usize, past: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..steps {
        let mid = 0.5 * (lo + hi);
        if past(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// σ̄ is C¹ at κₚ and κₘ, starts at fₘ/3, peaks at fₘ and tends to fₘ/7; the area
    /// above the residual beyond the peak is G_fc (Eq. C3, by the trapezoid rule).
    #[test]
    fn yield_value_is_c1_and_spends_gfc() {
        let fc = 10.5e6;
        let cap = Cap::new(fc, 9.0, Some((5000.0, 0.093e-3)));
        let (kp, km) = cap.softening.unwrap();
        assert!((cap.yield_value(0.0) - fc / 3.0).abs() < 1e-6);
        assert!((cap.yield_value(kp) - fc).abs() < 1e-6);
        assert!((cap.yield_value(km) - 0.5 * fc).abs() < 1e-6);
        assert!((cap.yield_value(1.0) - fc / 7.0).abs() < 1e-3 * fc);
        for k in [kp, km] {
            let h = 1e-9 * km;
            let left = (cap.yield_value(k) - cap.yield_value(k - h)) / h;
            let right = (cap.yield_value(k + h) - cap.yield_value(k)) / h;
            // slopes of ~fₘ/(κₘ − κₚ) = 1.8e10 Pa/m; the difference quotients agree to
            // O(h σ̄'') ≈ 1e-9 of it
            assert!(
                (left - right).abs() < 1e-5 * fc / (km - kp),
                "{k}: {left} {right}"
            );
        }
        let n = 400_000;
        let end = km + 40.0 * (km - kp);
        let dk = (end - kp) / n as f64;
        let area: f64 = (0..n)
            .map(|i| {
                let a = kp + i as f64 * dk;
                0.5 * (cap.yield_value(a) + cap.yield_value(a + dk)) - fc / 7.0
            })
            .sum::<f64>()
            * dk;
        // trapezoid error ~ (dk/ℓ)² with ℓ = κₘ − κₚ: 1e-8; the tail beyond 40 ℓ: e^-28
        assert!((area - 5000.0).abs() < 1e-5 * 5000.0, "area {area}");
    }

    #[test]
    fn root_of_a_decreasing_function() {
        let r = decreasing_root(|t| 3.0 - t * t, 1e-3).unwrap();
        assert!((r - 3f64.sqrt()).abs() < 1e-12);
        assert!(decreasing_root(|_| 1.0, 1.0).is_none());
    }
}
