//! `[in_situ]`: the stress of the rock before the excavation.

use super::{err_at, warning, RawInSitu, Src};
use crate::error::Result;
use crate::scene::{Block, InSitu, Material, Support};
use std::path::Path;
use toml::Spanned;

/// `[in_situ]`, checked: finite; a gradient out of equilibrium with `gravity` (m/s²) in
/// the material of a free block is a warning in `warnings` (`file` names the scene).
pub(super) fn parse_in_situ(
    src: &Src,
    in_situ: Option<&Spanned<RawInSitu>>,
    gravity: [f64; 2],
    materials: &[Material],
    blocks: &[Block],
    file: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<Option<InSitu>> {
    Ok(match in_situ {
        None => None,
        Some(r) => {
            let at = r.span().start;
            let r = r.get_ref();
            let Some(stress) = r.stress else {
                return Err(err_at(
                    src.line(at),
                    "[in_situ]",
                    "the in-situ stress needs 'stress'",
                    "give stress = [σxx, σyy, σxy] in Pa at y = datum, tension positive, for example stress = [-1.0e6, -2.0e6, 0.0]",
                ));
            };
            let gradient = r.gradient.unwrap_or([0.0; 3]);
            let datum = r.datum.unwrap_or(0.0);
            for (key, ok) in [
                ("stress", stress.iter().all(|x| x.is_finite())),
                ("gradient", gradient.iter().all(|x| x.is_finite())),
                ("datum", datum.is_finite()),
            ] {
                if !ok {
                    return Err(err_at(
                        src.key_line(at, key),
                        format!("[in_situ] key '{key}'"),
                        format!("'{key}' must be finite"),
                        "give finite numbers: stress in Pa, gradient in Pa/m, datum in m",
                    ));
                }
            }
            // equilibrium with gravity: ∂σxy/∂y = −ρ g_x, ∂σyy/∂y = −ρ g_y in every free
            // block's material
            let g = gravity;
            let mut used: Vec<usize> = blocks
                .iter()
                .filter(|b| b.support == Support::Free)
                .map(|b| b.material)
                .collect();
            used.sort_unstable();
            used.dedup();
            for m in used {
                let mat = &materials[m];
                let rho = mat.density();
                // (0 − x rather than −x: no "-0" in the message)
                let want = [0.0 - rho * g[1], 0.0 - rho * g[0]];
                let have = [gradient[1], gradient[2]];
                let scale = want[0].hypot(want[1]).max(have[0].hypot(have[1]));
                let off = (have[0] - want[0]).hypot(have[1] - want[1]);
                if scale > 0.0 && off > 0.01 * scale {
                    warnings.push(warning(
                        file,
                        src.line(at),
                        format_args!(
                            "[in_situ]: gradient (dσyy/dy, dσxy/dy) = ({}, {}) Pa/m is not in equilibrium with gravity in material '{}' ({}, {} Pa/m): the difference is released over the whole rock mass with the excavation",
                            have[0],
                            have[1],
                            mat.name,
                            want[0],
                            want[1]
                        ),
                    ));
                }
            }
            Some(InSitu {
                stress,
                gradient,
                datum,
            })
        }
    })
}
