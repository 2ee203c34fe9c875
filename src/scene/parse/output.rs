//! `[output]`: the blocks tracked, the ParaView frames and the checkpoints.

use super::{err_at, RawOutput, Src};
use crate::error::Result;
use crate::scene::{Block, Frames, Output};
use toml::Spanned;

/// `[output]`, checked: tracked blocks of the scene, whole numbers of steps ≥ 1, a frame
/// interval > 0 s, not both `every` and `frame_interval`.
pub(super) fn parse_output(
    src: &Src,
    output: Option<&Spanned<RawOutput>>,
    blocks: &[Block],
) -> Result<Output> {
    Ok(match output {
        None => Output {
            track: vec![],
            vtk: true,
            frames: Frames::Default,
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
            let frames = match (o.every, o.frame_interval) {
                (Some(_), Some(_)) => {
                    return Err(err_at(
                        src.key_line(at, "frame_interval"),
                        "[output] key 'frame_interval'",
                        "every and frame_interval both set: they are two rules for the same frames",
                        "keep one: every = k (a frame every k time steps) or frame_interval = s (one per s seconds of simulated time)",
                    ));
                }
                (Some(every), None) if every < 1 => {
                    return Err(err_at(
                        src.key_line(at, "every"),
                        "[output] key 'every'",
                        format!("every must be a whole number of steps ≥ 1, not {every}"),
                        "for example every = 10 (a ParaView frame every 10 time steps)",
                    ));
                }
                (Some(every), None) => Frames::Steps(every as usize),
                (None, Some(s)) if !(s.is_finite() && s > 0.0) => {
                    return Err(err_at(
                        src.key_line(at, "frame_interval"),
                        "[output] key 'frame_interval'",
                        format!("frame_interval must be a time > 0 s, not {s}"),
                        "for example frame_interval = 0.05 (a ParaView frame every 0.05 s of simulated time), or leave it out for the default",
                    ));
                }
                (None, Some(s)) => Frames::Interval(s),
                (None, None) => Frames::Default,
            };
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
                frames,
                checkpoint_every,
            }
        }
    })
}
