//! `[output]`: the blocks tracked, the ParaView frames and the checkpoints.

use super::{err_at, RawOutput, Src};
use crate::error::Result;
use crate::scene::{Block, Output};
use toml::Spanned;

/// `[output]`, checked: tracked blocks of the scene, whole numbers of steps ≥ 1.
pub(super) fn parse_output(
    src: &Src,
    output: Option<&Spanned<RawOutput>>,
    blocks: &[Block],
) -> Result<Output> {
    Ok(match output {
        None => Output {
            track: vec![],
            vtk: true,
            every: 1,
            checkpoint_every: None,
        },
        Some(o) => {
            let at = o.span().start;
            let o = o.get_ref();
            let track = o.track.clone().unwrap_or_default();
            for t in &track {
                if !blocks.iter().any(|b| &b.name == t) {
                    return Err(err_at(
                        src.key_line(at, "track"),
                        "[output] key 'track'",
                        format!("block '{t}' does not exist"),
                        "name blocks of the scene",
                    ));
                }
            }
            let every = o.every.unwrap_or(1);
            if every < 1 {
                return Err(err_at(
                    src.key_line(at, "every"),
                    "[output] key 'every'",
                    format!("every must be a whole number of steps ≥ 1, not {every}"),
                    "for example every = 10 (a ParaView frame every 10 time steps)",
                ));
            }
            let checkpoint_every = match o.checkpoint_every {
                Some(n) if n < 1 => {
                    return Err(err_at(
                        src.key_line(at, "checkpoint_every"),
                        "[output] key 'checkpoint_every'",
                        format!("checkpoint_every must be a whole number of steps ≥ 1, not {n}"),
                        "for example checkpoint_every = 100 (a checkpoint every 100 time steps), or leave it out for one every 30 s of wall time",
                    ));
                }
                n => n.map(|n| n as usize),
            };
            Output {
                track,
                vtk: o.vtk.unwrap_or(true),
                every: every as usize,
                checkpoint_every,
            }
        }
    })
}
