//! `[contacts]`: the default joint and the contact tolerance.

use super::{err_at, index_of, RawContacts, Src};
use crate::error::{Error, Result};
use crate::geometry::polygon;
use crate::scene::{Block, Contacts, Joint};
use toml::Spanned;

/// `[contacts]`, checked: the joint named or the only one, the tolerance (m) given or a
/// millionth of the scene's size.
pub(super) fn parse_contacts(
    src: &Src,
    contacts: Option<&Spanned<RawContacts>>,
    joints: &[Joint],
    blocks: &[Block],
) -> Result<Contacts> {
    let (joint_name, tol_given, cline) = match contacts {
        None => (None, None, 1),
        Some(c) => (
            c.get_ref().joint.clone(),
            c.get_ref().tolerance,
            src.line(c.span().start),
        ),
    };
    let scene_size = {
        let all: Vec<[f64; 2]> = blocks
            .iter()
            .flat_map(|b| b.vertices.iter().copied())
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .collect();
        if all.is_empty() {
            1.0
        } else {
            polygon::size(&all)
        }
    };
    let tolerance = match tol_given {
        None => 1e-6 * scene_size.max(1e-3),
        Some(t) if t.is_finite() && t >= 0.0 => t,
        Some(t) => {
            return Err(err_at(
                cline,
                "[contacts] key 'tolerance'",
                format!("tolerance must be a non-negative length, not {t}"),
                "give it in m, for example tolerance = 1e-6",
            ))
        }
    };
    let joint = match joint_name {
        Some(n) => index_of(
            "joint",
            joints.iter().map(|j| j.name.as_str()),
            &n,
            cline,
            "[contacts] key 'joint'",
        )?,
        None if joints.len() == 1 => 0,
        None if joints.is_empty() && blocks.len() > 1 => {
            return Err(Error::new(
                "no [[joint]] is defined, so touching blocks would have no contact properties",
            )
            .line(Some(1))
            .fix("add a [[joint]] table (normal_modulus, shear_modulus, band, friction_angle)"))
        }
        None if joints.is_empty() => usize::MAX,
        None => {
            return Err(err_at(
                cline,
                "[contacts]",
                "several joints are defined and none is chosen",
                "add [contacts] joint = \"<name>\"",
            ))
        }
    };
    Ok(Contacts { joint, tolerance })
}
