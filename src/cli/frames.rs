//! The frame and part options of `kardia render` (`--frames`, `--frame`, `--resume`,
//! `--turntable`, `--print-frame-count`, `--tile`) and the plan they make with the output
//! name: which frames, how many the animation has, and where they go. A still is the plan of
//! frame 0 alone; `render.rs` carries every plan out the same way.

use std::path::Path;

use clap::Args;

use crate::animation::animated::AnimatedFormat;
use crate::animation::{self, FrameRange};
use crate::film::Region;
use crate::scene::Animation;

/// The animation and farm options of `kardia render`.
#[derive(Debug, Args, Clone, PartialEq, Default)]
pub struct AnimationArgs {
    /// Render frames FIRST..LAST (both included, from 0) of the scene's FRAMES (or of the
    /// --turntable); the output needs `####` for the frame number (out/heart_####.png) or is
    /// one animated .gif/.apng.
    #[arg(long, value_name = "FIRST..LAST", conflicts_with = "frame")]
    pub frames: Option<FrameRange>,
    /// Render frame N alone, exactly as it is in the sequence.
    #[arg(long, value_name = "N")]
    pub frame: Option<u32>,
    /// Skip frames (and tiles and regions) whose output file already exists, is complete and
    /// carries this render's key (same scene, settings and frame); any other is rendered anew.
    #[arg(long)]
    pub resume: bool,
    /// Orbit the camera once about its look-at point, around its up vector, in N frames.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub turntable: Option<u32>,
    /// Render nothing: print the number of frames the scene makes (--turntable's N, else its
    /// FRAMES, else 1) on stdout, for farm scripts.
    #[arg(long)]
    pub print_frame_count: bool,
    /// Render only row band I (from 0) of N, as a part file for `kardia assemble`.
    #[arg(long, value_name = "I/N", value_parser = parse_tile, conflicts_with = "region")]
    pub tile: Option<(u32, u32)>,
}

/// Parses `I/N`.
fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("expected I/N (band I from 0 of N), not '{s}'"))?;
    let (i, n) = (i.trim().parse::<u32>(), n.trim().parse::<u32>());
    match (i, n) {
        (Ok(i), Ok(n)) if n >= 1 && i < n => Ok((i, n)),
        (Ok(_), Ok(_)) => Err(format!(
            "in I/N, I must be from 0 to N - 1 (and N ≥ 1), not '{s}'"
        )),
        _ => Err(format!("expected I/N (two whole numbers), not '{s}'")),
    }
}

/// Which frames a render makes and where they go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    /// The frames to render.
    pub range: FrameRange,
    /// Frames in the animation (for `clock` and the render key): 1 unless a frame is chosen.
    pub count: u32,
    /// One animated file holds every frame.
    pub animated: Option<AnimatedFormat>,
    /// A plain still: the whole image of frame 0 of 1 to one file (`kardia render` with no
    /// frame, part or animated output asked for); its summary is a still's.
    pub still: bool,
}

impl AnimationArgs {
    /// The plan these options make with the `output` name, the `--region` and `--alpha`
    /// asked for, and what the scene declares; a usage error (without the `kardia: `
    /// prefix) when they do not fit together.
    pub fn plan(
        &self,
        output: &Path,
        region: Option<Region>,
        alpha: bool,
        declared: &Animation,
    ) -> Result<Plan, String> {
        let animated = AnimatedFormat::from_path(output);
        let pattern = animation::has_frame_pattern(output);
        let part = self.tile.is_some() || region.is_some();
        // Without a frame asked for, a scene is read as a still (frame 0 of 1), as a plain
        // `kardia render` reads it: so parts of a still join into exactly that render.
        let selects_frames = self.frame.is_some()
            || self.frames.is_some()
            || self.turntable.is_some()
            || animated.is_some()
            || pattern;
        let count = if selects_frames {
            self.turntable.or(declared.frames).unwrap_or(1)
        } else {
            1
        };
        let range = match (self.frame, self.frames) {
            (Some(n), _) => FrameRange { first: n, last: n },
            (None, Some(r)) => r,
            (None, None) if animated.is_some() || pattern => FrameRange::all(count),
            (None, None) => FrameRange { first: 0, last: 0 },
        };
        if range.last >= count {
            let source_of_count = match (self.turntable, declared.frames) {
                (Some(n), _) => format!("--turntable {n} makes {n}"),
                (None, Some(n)) => format!("the scene's FRAMES {n} makes {n}"),
                (None, None) => {
                    "the scene has no FRAMES statement (and no --turntable is given), so it has 1"
                        .into()
                }
            };
            return Err(format!(
                "frame {} does not exist: {source_of_count} frame{}, numbered from 0",
                range.last,
                if count == 1 { "" } else { "s" }
            ));
        }
        if animated.is_some() && part {
            return Err(
                "an animated output holds whole frames: --tile and --region need a .png or .exr output"
                    .into(),
            );
        }
        if alpha && animated == Some(AnimatedFormat::Gif) {
            return Err(
                "--alpha needs an output with an alpha channel: GIF has only on/off transparency; \
                 use .apng (or .png/.exr frames with `####`)"
                    .into(),
            );
        }
        if alpha && part {
            return Err(
                "--alpha is not available for parts: --tile and --region render opaque parts only"
                    .into(),
            );
        }
        if animated.is_none() && !pattern && range.len() > 1 {
            return Err(format!(
                "{} frames need `####` in the output name for the frame number (such as \
                 out/heart_####.png), or one animated .gif or .apng output",
                range.len()
            ));
        }
        Ok(Plan {
            range,
            count,
            animated,
            still: !selects_frames && !part,
        })
    }
}

/// "frame 7 (3 of 10)": what the progress shows while `frame` of `range` renders.
pub fn frame_message(frame: u32, range: FrameRange) -> String {
    format!(
        "frame {frame} ({} of {})",
        frame - range.first + 1,
        range.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn tiles_parse() {
        assert_eq!(parse_tile("0/4"), Ok((0, 4)));
        assert_eq!(parse_tile("3/4"), Ok((3, 4)));
        assert!(parse_tile("4/4").is_err());
        assert!(parse_tile("1/0").is_err());
        assert!(parse_tile("a/b").is_err());
        assert!(parse_tile("2").is_err());
    }

    #[test]
    fn a_still_is_frame_0_of_1_and_patterns_take_every_frame() {
        let declared = Animation {
            frames: Some(24),
            fps: 24.0,
            uses_time: true,
        };
        let none = AnimationArgs::default();
        let still = none
            .plan(&PathBuf::from("a.png"), None, false, &declared)
            .unwrap();
        assert_eq!(
            (still.range.first, still.range.last, still.count),
            (0, 0, 1)
        );
        assert!(still.still);
        let all = none
            .plan(&PathBuf::from("f_####.png"), None, false, &declared)
            .unwrap();
        assert_eq!((all.range.len(), all.count, all.still), (24, 24, false));
        let tile = AnimationArgs {
            tile: Some((0, 2)),
            ..AnimationArgs::default()
        };
        let part = tile
            .plan(&PathBuf::from("p.png"), None, false, &declared)
            .unwrap();
        assert_eq!((part.count, part.still), (1, false));
        assert!(tile
            .plan(&PathBuf::from("p.gif"), None, false, &declared)
            .is_err());
    }
}
