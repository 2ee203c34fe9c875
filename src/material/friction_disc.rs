//! The Mohr–Coulomb band of a contact in space (docs/theory.md §7, Eq. K6): a no-tension
//! (or limited-tension) normal spring and a friction disc, the shear force a vector in
//! the contact's plane returned radially onto the circle of radius cA − Fₙ tan φ.
//!
//! With the trial forces Fₙ = Fₙ₀ + kₙ Δδₙ and **t** = **F**ₛ₀ + kₛ Δ**δ**ₛ (the shear a
//! 2-vector in the contact's tangents t₁, t₂): open if Fₙ > fₜ A; slip if
//! |**t**| > L = max(cA − Fₙ tan φ, 0), with **F**ₛ = L **t**/|**t**|; stick otherwise. A
//! bond breaks as in the plane law ([`MohrCoulomb`]): once open or slipping, fₜ = c = 0.

use super::{ContactLaw, ContactState, History, MohrCoulomb};

/// Forces (N) of a contact in space: normal, then the shear along the two tangents.
pub type Force3 = [f64; 3];

impl MohrCoulomb {
    /// The disc law: forces (N) and state after the relative displacement increment
    /// `d` = (Δδₙ, Δδₛ₁, Δδₛ₂) (m) from the `committed` forces, with the bond's `history`
    /// (0 intact, 1 broken), and the history after it.
    pub fn update_disc(
        &self,
        area: f64,
        committed: Force3,
        history: History,
        d: [f64; 3],
    ) -> (Force3, ContactState, History) {
        let broken = history[0] >= 0.5;
        let (ft, c) = if broken {
            (0.0, 0.0)
        } else {
            (self.tensile_strength, self.cohesion)
        };
        let k = self.springs(area);
        let fn_ = committed[0] + k.kn * d[0];
        let (f, state) = if fn_ > ft * area {
            ([0.0; 3], ContactState::Open)
        } else {
            let t = [committed[1] + k.ks * d[1], committed[2] + k.ks * d[2]];
            let limit = (c * area - fn_ * self.tan_phi).max(0.0);
            let size = t[0].hypot(t[1]);
            if size > limit {
                let s = limit / size;
                ([fn_, s * t[0], s * t[1]], ContactState::Slip)
            } else {
                ([fn_, t[0], t[1]], ContactState::Stick)
            }
        };
        let breaks = state != ContactState::Stick && (ft > 0.0 || c > 0.0);
        (f, state, [if broken || breaks { 1.0 } else { 0.0 }, 0.0])
    }

    /// The derivative ∂F/∂(Δδ) (N/m, rows normal, shear 1, shear 2) of [`Self::update_disc`]
    /// at the same arguments: diag(kₙ, kₛ, kₛ) sticking, zero open, and slipping
    ///
    ///   ∂**F**ₛ/∂Δ**δ**ₛ = (L/|**t**|) kₛ (I − **t̂ t̂**ᵀ),   ∂**F**ₛ/∂Δδₙ = −tan φ kₙ **t̂**   (K7)
    ///
    /// (the radial return's consistent tangent; unsymmetric where it slips).
    pub fn tangent_disc(
        &self,
        area: f64,
        committed: Force3,
        history: History,
        d: [f64; 3],
    ) -> [[f64; 3]; 3] {
        let (f, state, _) = self.update_disc(area, committed, history, d);
        let k = self.springs(area);
        match state {
            ContactState::Open => [[0.0; 3]; 3],
            ContactState::Stick => [[k.kn, 0.0, 0.0], [0.0, k.ks, 0.0], [0.0, 0.0, k.ks]],
            ContactState::Slip => {
                let t = [committed[1] + k.ks * d[1], committed[2] + k.ks * d[2]];
                let size = t[0].hypot(t[1]);
                let u = [t[0] / size, t[1] / size];
                let limit = f[1].hypot(f[2]);
                let s = limit / size * k.ks;
                [
                    [k.kn, 0.0, 0.0],
                    [
                        -self.tan_phi * k.kn * u[0],
                        s * (1.0 - u[0] * u[0]),
                        -s * u[0] * u[1],
                    ],
                    [
                        -self.tan_phi * k.kn * u[1],
                        -s * u[1] * u[0],
                        s * (1.0 - u[1] * u[1]),
                    ],
                ]
            }
        }
    }
}

#[cfg(test)]
#[path = "friction_disc_tests.rs"]
mod tests;
