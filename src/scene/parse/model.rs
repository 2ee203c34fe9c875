//! `[model]`: the plane idealisation, the thickness and gravity.

use super::{err_at, RawModel, Src};
use crate::error::Result;
use crate::scene::{Model, Plane, STANDARD_GRAVITY};
use toml::Spanned;

/// `[model]`, checked; without the table plane strain, 1 m thick, under standard gravity.
pub(super) fn parse_model(src: &Src, model: Option<&Spanned<RawModel>>) -> Result<Model> {
    Ok(match model {
        None => Model {
            plane: Plane::Strain,
            thickness: 1.0,
            gravity: [0.0, -STANDARD_GRAVITY],
        },
        Some(m) => {
            let at = m.span().start;
            let m = m.get_ref();
            let plane = match m.plane.as_deref() {
                None | Some("strain") => Plane::Strain,
                Some("stress") => Plane::Stress,
                Some(p) => {
                    return Err(err_at(
                        src.key_line(at, "plane"),
                        "[model] key 'plane'",
                        format!("unknown plane '{p}'"),
                        "use \"strain\" or \"stress\"",
                    ))
                }
            };
            let thickness = m.thickness.unwrap_or(1.0);
            if !(thickness.is_finite() && thickness > 0.0) {
                return Err(err_at(
                    src.key_line(at, "thickness"),
                    "[model] key 'thickness'",
                    format!("thickness must be a positive number of metres, not {thickness}"),
                    "give the out-of-plane thickness in m, for example thickness = 1.0",
                ));
            }
            let gravity = m.gravity.unwrap_or([0.0, -STANDARD_GRAVITY]);
            if !gravity.iter().all(|g| g.is_finite()) {
                return Err(err_at(
                    src.key_line(at, "gravity"),
                    "[model] key 'gravity'",
                    "gravity must be finite",
                    "give gravity in m/s², for example [0.0, -9.81]",
                ));
            }
            Model {
                plane,
                thickness,
                gravity,
            }
        }
    })
}
