//! Tension cut-off and Mohr–Coulomb strength of the contact band (docs/theory.md Eq. K5, seed §4).
//!
//! Compression is negative. With the elastic trial forces Fₙ = Fₙ₀ + kₙ Δδₙ and
//! Fₛ = Fₛ₀ + kₛ Δδₛ from the forces committed at the start of the increment:
//! * **open** if Fₙ > fₜ A_c: the contact carries no force;
//! * **slip** if |Fₛ| > c A_c − Fₙ tan φ: Fₛ is returned to ±(c A_c − Fₙ tan φ) with the
//!   sign of the trial;
//! * **stick** otherwise.
//!
//! The bond is brittle, as in UDEC's Coulomb slip joint: a contact that has once opened
//! in tension or slipped has lost its tensile strength and its cohesion for good (its
//! history variable, 0 intact, 1 broken), and from then on is a dry frictional contact.
//! Without this a crack would carry fₜ A_c again in every increment after it opened
//! (its committed force is zero, so the next trial starts from zero): a joint pulled
//! open step by step would re-crack each step, and the answer would depend on the steps.

use super::{ContactLaw, ContactSprings, ContactState, ElasticBand, History};
use crate::scene::Joint;

/// The no-tension (or limited-tension) Mohr–Coulomb band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MohrCoulomb {
    pub elastic: ElasticBand,
    /// tan φ.
    pub tan_phi: f64,
    /// Cohesion c (Pa).
    pub cohesion: f64,
    /// Tensile strength fₜ (Pa).
    pub tensile_strength: f64,
}

impl MohrCoulomb {
    pub fn from_joint(j: &Joint) -> Self {
        MohrCoulomb {
            elastic: ElasticBand::from_joint(j),
            tan_phi: j.friction_angle.to_radians().tan(),
            cohesion: j.cohesion,
            tensile_strength: j.tensile_strength,
        }
    }
}

impl MohrCoulomb {
    /// The history of this contact's bond broken for good, where `history` has it intact
    /// and the bond carries something (cohesion or tensile strength): the strength such a
    /// contact loses at once when it opens, its cohesive shear and its tension, makes its
    /// law jump there. `None` for a dry contact or a bond already broken.
    pub fn broken_bond(&self, history: History) -> Option<History> {
        let bonded = self.cohesion > 0.0 || self.tensile_strength > 0.0;
        (bonded && history[0] < 0.5).then_some([1.0, 0.0])
    }

    /// The return to the strength envelope with the given tensile strength (Pa) and
    /// cohesion (Pa): forces (N) and state.
    fn ret(
        &self,
        area: f64,
        committed: [f64; 2],
        d: [f64; 2],
        ft: f64,
        c: f64,
    ) -> ([f64; 2], ContactState) {
        let k = self.springs(area);
        let fn_ = committed[0] + k.kn * d[0];
        if fn_ > ft * area {
            return ([0.0, 0.0], ContactState::Open);
        }
        let fs = committed[1] + k.ks * d[1];
        let limit = (c * area - fn_ * self.tan_phi).max(0.0);
        if fs.abs() > limit {
            ([fn_, limit.copysign(fs)], ContactState::Slip)
        } else {
            ([fn_, fs], ContactState::Stick)
        }
    }
}

impl ContactLaw for MohrCoulomb {
    fn springs(&self, area: f64) -> ContactSprings {
        self.elastic.springs(area)
    }

    /// The intact law (history 0).
    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        self.update_history(area, committed, [0.0; 2], d).map_two()
    }

    /// `history[0]`: 0 while the bond is intact, 1 once it has broken (opened or
    /// slipped); a broken contact has fₜ = c = 0. `history[1]` is unused (0).
    fn update_history(
        &self,
        area: f64,
        committed: [f64; 2],
        history: History,
        d: [f64; 2],
    ) -> ([f64; 2], ContactState, History) {
        let broken = history[0] >= 0.5;
        let (ft, c) = if broken {
            (0.0, 0.0)
        } else {
            (self.tensile_strength, self.cohesion)
        };
        let (f, state) = self.ret(area, committed, d, ft, c);
        let breaks = state != ContactState::Stick && (ft > 0.0 || c > 0.0);
        (f, state, [if broken || breaks { 1.0 } else { 0.0 }, 0.0])
    }
}

/// The first two of a triple.
trait MapTwo<A, B> {
    fn map_two(self) -> (A, B);
}

impl<A, B, C> MapTwo<A, B> for (A, B, C) {
    fn map_two(self) -> (A, B) {
        (self.0, self.1)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn law() -> MohrCoulomb {
        MohrCoulomb {
            elastic: ElasticBand {
                normal_modulus: 1e9,
                shear_modulus: 1e8,
                band: 0.01,
            },
            tan_phi: 0.5,
            cohesion: 0.0,
            tensile_strength: 0.0,
        }
    }

    #[test]
    fn states() {
        let m = law();
        // kn = 1e11 N/m, ks = 1e10 N/m for A = 1
        let (f, s) = m.update(1.0, [0.0, 0.0], [1e-6, 0.0]);
        assert_eq!((f, s), ([0.0, 0.0], ContactState::Open));
        let (f, s) = m.update(1.0, [0.0, 0.0], [-1e-6, 1e-5]);
        assert_eq!(s, ContactState::Slip);
        assert_eq!(f, [-1e5, 0.5e5]);
        let (f, s) = m.update(1.0, [0.0, 0.0], [-1e-6, -4e-6]);
        assert_eq!((f, s), ([-1e5, -4e4], ContactState::Stick));
        let (f, s) = m.update(1.0, [-1e5, 4e4], [0.0, -1e-5]);
        assert_eq!((f, s), ([-1e5, -5e4], ContactState::Slip));
    }

    /// A bonded joint (fₜ = 1 MPa, c = 2 MPa) pulled open in two steps: the first
    /// step breaks it, and the second, which opens it less than the first, finds no
    /// tensile strength left (the intact law would give it kₙ Δδ = 0.5 MPa of tension).
    #[test]
    fn a_broken_bond_stays_broken() {
        let m = MohrCoulomb {
            cohesion: 2e6,
            tensile_strength: 1e6,
            ..law()
        };
        // kn = 1e11 N/m: 2e-5 m is 2 MPa > fₜ
        let (f, s, h) = m.update_history(1.0, [0.0, 0.0], [0.0; 2], [2e-5, 0.0]);
        assert_eq!((f, s, h), ([0.0, 0.0], ContactState::Open, [1.0, 0.0]));
        let (f, s, h) = m.update_history(1.0, f, h, [5e-6, 0.0]);
        assert_eq!((f, s, h), ([0.0, 0.0], ContactState::Open, [1.0, 0.0]));
        // intact: the same small opening is held in tension
        let (f, s, h) = m.update_history(1.0, [0.0, 0.0], [0.0; 2], [5e-6, 0.0]);
        assert_eq!((s, h), (ContactState::Stick, [0.0; 2]));
        assert!((f[0] - 5e5).abs() < 1e-6 && f[1] == 0.0, "{f:?}");
        // sheared past c − σ tan φ under 1 MPa compression (limit 2.5 MPa): slips and
        // breaks; then the dry friction limit 0.5 MPa holds
        let (f, s, h) = m.update_history(1.0, [-1e6, 0.0], [0.0; 2], [0.0, 3e-4]);
        assert_eq!((f, s, h), ([-1e6, 2.5e6], ContactState::Slip, [1.0, 0.0]));
        let (f, s, h) = m.update_history(1.0, f, h, [0.0, 0.0]);
        assert_eq!((f, s, h), ([-1e6, 0.5e6], ContactState::Slip, [1.0, 0.0]));
        // a dry joint (fₜ = c = 0) has no bond to break
        let (_, s, h) = law().update_history(1.0, [0.0, 0.0], [0.0; 2], [1e-6, 0.0]);
        assert_eq!((s, h), (ContactState::Open, [0.0; 2]));
    }

    /// The history `broken_bond` gives is the one the law itself writes when the bond
    /// breaks, and with it the contact holds no cohesion: under 1 MPa of compression a
    /// shear of 1 MPa that the intact bond (limit 2.5 MPa) holds slips at the dry limit
    /// 0.5 MPa.
    #[test]
    fn a_bond_broken_by_the_driver_is_the_laws_broken_bond() {
        let m = MohrCoulomb {
            cohesion: 2e6,
            tensile_strength: 0.0,
            ..law()
        };
        let broken = m.broken_bond([0.0; 2]).expect("an intact bond");
        let (_, _, written) = m.update_history(1.0, [0.0, 0.0], [0.0; 2], [1e-6, 0.0]);
        assert_eq!(broken, written);
        assert_eq!(m.broken_bond(broken), None, "broken twice");
        assert_eq!(law().broken_bond([0.0; 2]), None, "a dry joint has no bond");
        let shear = [-1e6, 1e6];
        let (f, s, _) = m.update_history(1.0, shear, [0.0; 2], [0.0, 0.0]);
        assert_eq!((f, s), (shear, ContactState::Stick));
        let (f, s, _) = m.update_history(1.0, shear, broken, [0.0, 0.0]);
        assert_eq!((f, s), ([-1e6, 0.5e6], ContactState::Slip));
    }
}
