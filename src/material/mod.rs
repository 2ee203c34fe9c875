//! Constitutive laws: the blocks' elastic matrix (docs/theory.md §2) and the contact
//! band (docs/theory.md §3) behind the [`ContactLaw`] trait.

pub mod cap;
pub mod friction_disc;
pub mod mohr_coulomb;
pub mod softening;

pub use mohr_coulomb::MohrCoulomb;
pub use softening::Softening;

use crate::scene::{Joint, JointSoftening, Material, Plane};

/// Elastic matrix Dₑ (Pa) in Voigt order (xx, yy, xy engineering shear), docs/theory.md Eq. B1.
/// Plane strain: [[λ+2μ, λ, 0], [λ, λ+2μ, 0], [0, 0, μ]]. Plane stress: the same with
/// λ replaced by 2λμ/(λ+2μ) (σ_zz = 0).
pub fn elastic_matrix(lambda: f64, mu: f64, plane: Plane) -> [[f64; 3]; 3] {
    let l = match plane {
        Plane::Strain => lambda,
        Plane::Stress => 2.0 * lambda * mu / (lambda + 2.0 * mu),
    };
    [
        [l + 2.0 * mu, l, 0.0],
        [l, l + 2.0 * mu, 0.0],
        [0.0, 0.0, mu],
    ]
}

/// Dₑ of a block material.
pub fn block_elastic(m: &Material, plane: Plane) -> [[f64; 3]; 3] {
    elastic_matrix(m.lame_lambda, m.lame_mu, plane)
}

/// Viscous matrix D_v (Pa·s) of a block material from its viscous Lamé constants
/// (λ*, μ*), docs/theory.md Eq. B2 (seed Eq. 8: σ = Dₑ ε + D_v ε̇), with the same plane reduction
/// as [`elastic_matrix`]. Zero when the material has no viscosity.
pub fn block_viscous(m: &Material, plane: Plane) -> [[f64; 3]; 3] {
    if m.viscous_mu == 0.0 && m.viscous_lambda == 0.0 {
        return [[0.0; 3]; 3];
    }
    if m.viscous_mu == 0.0 {
        // plane stress reduction needs μ* > 0; λ* alone acts as in plane strain
        return elastic_matrix(m.viscous_lambda, 0.0, Plane::Strain);
    }
    elastic_matrix(m.viscous_lambda, m.viscous_mu, plane)
}

/// Young's modulus E (Pa) and Poisson's ratio ν from the Lamé constants.
pub fn young_poisson(lambda: f64, mu: f64) -> (f64, f64) {
    (
        mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu),
        lambda / (2.0 * (lambda + mu)),
    )
}

/// State of a contact (docs/theory.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ContactState {
    Stick,
    Slip,
    Open,
}

impl ContactState {
    pub fn as_str(self) -> &'static str {
        match self {
            ContactState::Stick => "stick",
            ContactState::Slip => "slip",
            ContactState::Open => "open",
        }
    }
    /// Integer code for VTK cell data: 0 stick, 1 slip, 2 open.
    pub fn code(self) -> i32 {
        self as i32
    }
}

/// Springs of one contact (N/m): kₙ = Eₙ A_c / h, kₛ = Gₛ A_c / h (docs/theory.md Eq. K3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSprings {
    pub kn: f64,
    pub ks: f64,
}

/// The history variables of a contact's law: the spent fraction ξ of the fracture
/// energy of a softening joint (dimensionless) and the plastic relative displacement κ₃
/// on its compression cap (m); zero for a new contact.
pub type History = [f64; 2];

/// A contact law maps an increment of relative displacement of a contact (normal Δδₙ,
/// shear Δδₛ, m) from the forces committed at the start of the increment (Fₙ₀, Fₛ₀, N) to
/// the new forces (N) and state. The elastic band is the linear law; tension cut-off,
/// Mohr–Coulomb and softening laws implement the same trait.
pub trait ContactLaw: Sync + Send {
    /// Elastic springs of a contact of area `area` (m²).
    fn springs(&self, area: f64) -> ContactSprings;
    /// Forces (normal, shear; N) and state after the increment `d` = (Δδₙ, Δδₛ) (m).
    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState);
    /// [`ContactLaw::update`] for a law with history: `history` is the contact's committed
    /// [`History`] (zero for a new contact), returned updated. Laws without history keep
    /// it unchanged.
    fn update_history(
        &self,
        area: f64,
        committed: [f64; 2],
        history: History,
        d: [f64; 2],
    ) -> ([f64; 2], ContactState, History) {
        let (f, s) = self.update(area, committed, d);
        (f, s, history)
    }
}

/// The contact law of each contact of a model: one law for all ([`ContactLaw`] types
/// serve as their own), or one per contact ([`PerContact`]).
pub trait ContactLaws: Sync + Send {
    /// The law of contact `k`.
    fn law(&self, k: usize) -> &dyn ContactLaw;
}

impl<T: ContactLaw> ContactLaws for T {
    fn law(&self, _k: usize) -> &dyn ContactLaw {
        self
    }
}

/// A law per contact: `laws[of[k]]` for contact k.
#[derive(Debug, Clone, PartialEq)]
pub struct PerContact<L> {
    pub laws: Vec<L>,
    pub of: Vec<u32>,
}

impl<L: ContactLaw> ContactLaws for PerContact<L> {
    fn law(&self, k: usize) -> &dyn ContactLaw {
        &self.laws[self.of[k] as usize]
    }
}

impl<L> PerContact<L> {
    /// The law of contact `k`, as its own type.
    pub fn get(&self, k: usize) -> &L {
        &self.laws[self.of[k] as usize]
    }
}

impl PerContact<JointLaw> {
    /// The laws of the scene's `[[joint]]`s, each contact of `mesh` given that of the
    /// joint between its two blocks ([`crate::scene::Scene::joint_of`]).
    pub fn of_scene(scene: &crate::scene::Scene, mesh: &crate::mesh::Mesh) -> Self {
        PerContact {
            laws: scene.joints.iter().map(JointLaw::from_joint).collect(),
            of: mesh
                .contacts
                .iter()
                .map(|c| scene.joint_of(c.block_l as usize, c.block_m as usize) as u32)
                .collect(),
        }
    }
}

/// The law of a `[[joint]]`: Mohr–Coulomb with tension cut-off (docs/theory.md §3), or with
/// softening of the tensile strength and the cohesion (`softening = "exponential"`,
/// [`Softening`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointLaw {
    MohrCoulomb(MohrCoulomb),
    Softening(Softening),
}

impl JointLaw {
    pub fn from_joint(j: &Joint) -> Self {
        match j.softening {
            JointSoftening::None => JointLaw::MohrCoulomb(MohrCoulomb::from_joint(j)),
            JointSoftening::Exponential => JointLaw::Softening(Softening::from_joint(j)),
        }
    }
    /// The elastic band.
    pub fn elastic(&self) -> ElasticBand {
        match self {
            JointLaw::MohrCoulomb(m) => m.elastic,
            JointLaw::Softening(m) => m.elastic,
        }
    }
    /// The history of a contact whose bond breaks for good at opening, for a law whose
    /// strength jumps there ([`MohrCoulomb::broken_bond`]); `None` for the softening law,
    /// whose strength falls continuously with the opening.
    pub fn broken_bond(&self, history: History) -> Option<History> {
        match self {
            JointLaw::MohrCoulomb(m) => m.broken_bond(history),
            JointLaw::Softening(_) => None,
        }
    }
    /// tan φ: the dependence of the shear strength on the normal force.
    pub fn tan_phi(&self) -> f64 {
        match self {
            JointLaw::MohrCoulomb(m) => m.tan_phi,
            JointLaw::Softening(m) => m.tan_phi,
        }
    }
}

impl ContactLaw for JointLaw {
    fn springs(&self, area: f64) -> ContactSprings {
        self.elastic().springs(area)
    }
    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        match self {
            JointLaw::MohrCoulomb(m) => m.update(area, committed, d),
            JointLaw::Softening(m) => m.update(area, committed, d),
        }
    }
    fn update_history(
        &self,
        area: f64,
        committed: [f64; 2],
        history: History,
        d: [f64; 2],
    ) -> ([f64; 2], ContactState, History) {
        match self {
            JointLaw::MohrCoulomb(m) => m.update_history(area, committed, history, d),
            JointLaw::Softening(m) => m.update_history(area, committed, history, d),
        }
    }
}

/// The elastic band without strength limits (docs/theory.md §3, stick state everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticBand {
    /// Eₙ and Gₛ (Pa), band thickness h (m).
    pub normal_modulus: f64,
    pub shear_modulus: f64,
    pub band: f64,
}

impl ElasticBand {
    pub fn from_joint(j: &Joint) -> Self {
        ElasticBand {
            normal_modulus: j.normal_modulus,
            shear_modulus: j.shear_modulus,
            band: j.band,
        }
    }
}

impl ContactLaw for ElasticBand {
    fn springs(&self, area: f64) -> ContactSprings {
        ContactSprings {
            kn: self.normal_modulus * area / self.band,
            ks: self.shear_modulus * area / self.band,
        }
    }
    fn update(&self, area: f64, committed: [f64; 2], d: [f64; 2]) -> ([f64; 2], ContactState) {
        let k = self.springs(area);
        (
            [committed[0] + k.kn * d[0], committed[1] + k.ks * d[1]],
            ContactState::Stick,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_stress_reduces_to_e_nu() {
        let (lambda, mu) = (56e9, 21e9);
        let (e, nu) = young_poisson(lambda, mu);
        let d = elastic_matrix(lambda, mu, Plane::Stress);
        let f = e / (1.0 - nu * nu);
        assert!((d[0][0] - f).abs() < 1e-6 * f);
        assert!((d[0][1] - f * nu).abs() < 1e-6 * f);
        assert!((d[2][2] - mu).abs() < 1e-6 * mu);
    }
}
