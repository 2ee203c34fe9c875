//! `[[joint]]`: the contact laws of the joints between blocks.

use super::{check_value, err_at, required, Named, RawJoint, Src};
use crate::error::Result;
use crate::scene::{Block, Joint, JointCap, JointSoftening};
use toml::Spanned;

/// The `[[joint]]` tables, checked: named, unique, the elastic, strength, softening,
/// cap and dilatancy parameters consistent. Their `blocks` are resolved by
/// [`resolve_blocks`] once the blocks are made.
pub(super) fn parse_joints(src: &Src, raw: &[Spanned<RawJoint>]) -> Result<Vec<Joint>> {
    let mut named = Named::new("joint");
    let mut joints: Vec<Joint> = Vec::new();
    for (i, j) in raw.iter().enumerate() {
        let at = j.span().start;
        let j = j.get_ref();
        let name = named
            .unique_name(src, at, i, j.name.as_deref())?
            .to_string();
        let place = format!("joint '{name}'");
        let need =
            |key: &str, v: Option<f64>, unit: &str| required(src, at, &place, key, v, true, unit);
        let normal_modulus = need("normal_modulus", j.normal_modulus, "Pa")?;
        let shear_modulus = need("shear_modulus", j.shear_modulus, "Pa")?;
        let band = need("band", j.band, "m")?;
        let opt = |key: &str, v: Option<f64>, unit: &str| -> Result<f64> {
            v.map_or(Ok(0.0), |v| {
                check_value(src, at, &place, key, v, false, unit)
            })
        };
        let friction_angle = match j.friction_angle {
            None => {
                return Err(err_at(
                    src.line(at),
                    place,
                    "key 'friction_angle' is missing",
                    "add friction_angle = <degrees, 0 to 89.9>",
                ))
            }
            Some(f) if f.is_finite() && (0.0..90.0).contains(&f) => f,
            Some(f) => {
                return Err(err_at(
                    src.key_line(at, "friction_angle"),
                    format!("{place} key 'friction_angle'"),
                    format!("friction angle {f}° is outside [0°, 90°)"),
                    "give the friction angle in degrees, for example 30",
                ))
            }
        };
        let cohesion = opt("cohesion", j.cohesion, "Pa")?;
        let tensile_strength = opt("tensile_strength", j.tensile_strength, "Pa")?;
        let softening = match j.softening.as_deref() {
            None | Some("none") => JointSoftening::None,
            Some("exponential") => JointSoftening::Exponential,
            Some(other) => {
                return Err(err_at(
                    src.key_line(at, "softening"),
                    format!("{place} key 'softening'"),
                    format!("unknown softening \"{other}\""),
                    "use \"exponential\" (or \"none\", the default)",
                ))
            }
        };
        let (fracture_energy_i, fracture_energy_ii) = if softening == JointSoftening::None {
            if let Some(key) = [
                ("fracture_energy_i", j.fracture_energy_i),
                ("fracture_energy_ii", j.fracture_energy_ii),
            ]
            .iter()
            .find_map(|(k, v)| v.map(|_| *k))
            {
                return Err(err_at(
                    src.key_line(at, key),
                    format!("{place} key '{key}'"),
                    "a fracture energy is given but the joint does not soften",
                    "add softening = \"exponential\" to the joint, or remove the key",
                ));
            }
            (0.0, 0.0)
        } else {
            let gf1 = need("fracture_energy_i", j.fracture_energy_i, "N/m")?;
            let gf2 = need("fracture_energy_ii", j.fracture_energy_ii, "N/m")?;
            let tan_phi = friction_angle.to_radians().tan();
            if tensile_strength * tan_phi > cohesion * (1.0 + 1e-12) {
                return Err(err_at(
                    src.key_line(at, "tensile_strength"),
                    format!("{place} key 'tensile_strength'"),
                    format!(
                        "the tension cut-off fₜ = {tensile_strength} Pa lies beyond the apex of the Coulomb line (c / tan φ = {} Pa)",
                        cohesion / tan_phi
                    ),
                    "a softening joint needs tensile_strength ≤ cohesion / tan(friction_angle): lower the tensile strength or raise the cohesion",
                ));
            }
            (gf1, gf2)
        };
        let cap = joint_cap(src, at, &place, j, softening)?;
        let (dilatancy_angle, dilatancy_stress) =
            joint_dilatancy(src, at, &place, j, softening, friction_angle)?;
        let within_unit = match j.within.as_deref() {
            None => false,
            Some("unit") => true,
            Some(other) => {
                return Err(err_at(
                    src.key_line(at, "within"),
                    format!("{place} key 'within'"),
                    format!("unknown value \"{other}\""),
                    "use within = \"unit\" (the joint of the potential cracks inside split bricks), or remove the key",
                ))
            }
        };
        joints.push(Joint {
            name,
            normal_modulus,
            shear_modulus,
            normal_viscosity: opt("normal_viscosity", j.normal_viscosity, "Pa·s")?,
            shear_viscosity: opt("shear_viscosity", j.shear_viscosity, "Pa·s")?,
            band,
            friction_angle,
            cohesion,
            tensile_strength,
            softening,
            fracture_energy_i,
            fracture_energy_ii,
            cap,
            dilatancy_angle,
            dilatancy_stress,
            within_unit,
            blocks: Vec::new(),
        });
    }
    Ok(joints)
}

/// Each joint's `blocks` (names in `raw`, the joints' tables) as indices into `blocks`.
pub(super) fn resolve_blocks(
    src: &Src,
    raw: &[Spanned<RawJoint>],
    joints: &mut [Joint],
    blocks: &[Block],
) -> Result<()> {
    for (joint, raw) in joints.iter_mut().zip(raw) {
        let at = raw.span().start;
        let place = format!("joint '{}'", joint.name);
        for name in raw.get_ref().blocks.iter().flatten() {
            let b = blocks.iter().position(|b| &b.name == name).ok_or_else(|| {
                err_at(
                    src.key_line(at, "blocks"),
                    format!("{place} key 'blocks'"),
                    format!("there is no block '{name}'"),
                    "name blocks of the scene (generated walls call their base \"base\" and their top beam \"top\")",
                )
            })?;
            joint.blocks.push(b);
        }
    }
    Ok(())
}

/// The compression cap of a `[[joint]]` (`compressive_strength` and its companions),
/// checked: only on softening joints; G_fc and κₚ together.
fn joint_cap(
    src: &Src,
    at: usize,
    place: &str,
    j: &RawJoint,
    softening: JointSoftening,
) -> Result<Option<JointCap>> {
    let companions = [
        ("cap_shear_factor", j.cap_shear_factor),
        ("compressive_fracture_energy", j.compressive_fracture_energy),
        ("cap_peak_displacement", j.cap_peak_displacement),
    ];
    let Some(fc) = j.compressive_strength else {
        if let Some((key, _)) = companions.iter().find(|(_, v)| v.is_some()) {
            return Err(err_at(
                src.key_line(at, key),
                format!("{place} key '{key}'"),
                "a parameter of the compression cap is given without compressive_strength",
                "add compressive_strength = <Pa> (the cap's strength), or remove the key",
            ));
        }
        return Ok(None);
    };
    let fc = check_value(src, at, place, "compressive_strength", fc, true, "Pa")?;
    softening_only(
        src,
        at,
        place,
        softening,
        "compressive_strength",
        "the compression cap",
    )?;
    let shear_factor = match j.cap_shear_factor {
        None => 9.0,
        Some(v) => check_value(
            src,
            at,
            place,
            "cap_shear_factor",
            v,
            true,
            "(dimensionless)",
        )?,
    };
    let (fracture_energy, peak_displacement) =
        match (j.compressive_fracture_energy, j.cap_peak_displacement) {
            (None, None) => (None, 0.0),
            (Some(g), Some(k)) => (
                Some(check_value(
                    src,
                    at,
                    place,
                    "compressive_fracture_energy",
                    g,
                    true,
                    "N/m",
                )?),
                check_value(src, at, place, "cap_peak_displacement", k, true, "m")?,
            ),
            (Some(_), None) => {
                return Err(err_at(
                    src.key_line(at, "compressive_fracture_energy"),
                    format!("{place} key 'compressive_fracture_energy'"),
                    "the cap softens with compressive_fracture_energy but its peak is not given",
                    "add cap_peak_displacement = <m> (the plastic relative displacement at the peak), or remove compressive_fracture_energy for a perfectly plastic cap",
                ))
            }
            (None, Some(_)) => {
                return Err(err_at(
                    src.key_line(at, "cap_peak_displacement"),
                    format!("{place} key 'cap_peak_displacement'"),
                    "the cap's peak is given without compressive_fracture_energy",
                    "add compressive_fracture_energy = <N/m>, or remove cap_peak_displacement for a perfectly plastic cap",
                ))
            }
        };
    Ok(Some(JointCap {
        compressive_strength: fc,
        shear_factor,
        fracture_energy,
        peak_displacement,
    }))
}

/// The error for `key`, a parameter of `what` (a part of the softening joint law), given
/// on a joint without softening.
fn softening_only(
    src: &Src,
    at: usize,
    place: &str,
    softening: JointSoftening,
    key: &str,
    what: &str,
) -> Result<()> {
    if softening != JointSoftening::None {
        return Ok(());
    }
    Err(err_at(
        src.key_line(at, key),
        format!("{place} key '{key}'"),
        format!("{what} belongs to softening joints"),
        format!("add softening = \"exponential\" with the fracture energies, or remove {key}"),
    ))
}

/// `dilatancy_angle` (degrees, 0 ≤ ψ₀ ≤ φ) and `dilatancy_stress` (Pa, > 0, required
/// with ψ₀ > 0) of a softening joint: (ψ₀, σᵤ), (0, 0) without dilatancy.
fn joint_dilatancy(
    src: &Src,
    at: usize,
    place: &str,
    j: &RawJoint,
    softening: JointSoftening,
    friction_angle: f64,
) -> Result<(f64, f64)> {
    let Some(psi) = j.dilatancy_angle else {
        if j.dilatancy_stress.is_some() {
            return Err(err_at(
                src.key_line(at, "dilatancy_stress"),
                format!("{place} key 'dilatancy_stress'"),
                "dilatancy_stress is given without dilatancy_angle",
                "add dilatancy_angle = <degrees> (the dilatancy at zero normal stress), or remove dilatancy_stress",
            ));
        }
        return Ok((0.0, 0.0));
    };
    let psi = check_value(src, at, place, "dilatancy_angle", psi, false, "degrees")?;
    softening_only(
        src,
        at,
        place,
        softening,
        "dilatancy_angle",
        "the dilatancy",
    )?;
    if psi > friction_angle {
        return Err(err_at(
            src.key_line(at, "dilatancy_angle"),
            format!("{place} key 'dilatancy_angle'"),
            format!("the dilatancy angle {psi}° exceeds the friction angle {friction_angle}°"),
            "give a dilatancy angle between 0 and the friction angle (degrees)",
        ));
    }
    if psi == 0.0 {
        return Ok((0.0, 0.0));
    }
    let Some(su) = j.dilatancy_stress else {
        return Err(err_at(
            src.key_line(at, "dilatancy_angle"),
            format!("{place} key 'dilatancy_angle'"),
            "a dilatancy angle is given without dilatancy_stress",
            "add dilatancy_stress = <Pa> (the compression at which the joint stops dilating; without it a held joint's compression would grow without bound as it slips)",
        ));
    };
    let su = check_value(src, at, place, "dilatancy_stress", su, true, "Pa")?;
    Ok((psi, su))
}
