//! Tension cut-off and Mohr–Coulomb strength of the contact band (METHOD.md §3, seed §4).
//!
//! Compression is negative. With the elastic trial forces Fₙ = Fₙ₀ + kₙ Δδₙ and
//! Fₛ = Fₛ₀ + kₛ Δδₛ from the forces committed at the start of the increment:
//! * **open** if Fₙ > fₜ A_c: the contact carries no force;
//! * **slip** if |Fₛ| > c A_c − Fₙ tan φ: Fₛ is returned to ±(c A_c − Fₙ tan φ) with the
//!   sign of the trial;
//! * **stick** otherwise.

use super::{ContactLaw, ContactSprings, ContactState, ElasticBand};
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

impl ContactLaw for MohrCoulomb {
    fn springs(&self, area: f64) -> ContactSprings {
        self.elastic.springs(area)
    }

    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        let k = self.springs(area);
        let fn_ = committed[0] + k.kn * d[0];
        if fn_ > self.tensile_strength * area {
            return ([0.0, 0.0], ContactState::Open);
        }
        let fs = committed[1] + k.ks * d[1];
        let limit = (self.cohesion * area - fn_ * self.tan_phi).max(0.0);
        if fs.abs() > limit {
            ([fn_, limit.copysign(fs)], ContactState::Slip)
        } else {
            ([fn_, fs], ContactState::Stick)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> MohrCoulomb {
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
}
