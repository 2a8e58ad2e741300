//! `kardia render` for sequences, turntables, animated files and parts of a frame
//! (`--frames`, `--frame`, `--resume`, `--turntable`, `--tile`, `--region`): arguments →
//! [`crate::animation`] → files, one progress bar across all frames.

use std::path::{Path, PathBuf};

use clap::Args;

use super::progress::Progress;
use super::render::{RenderArgs, INTERRUPTED};
use crate::animation::animated::{AnimatedEncoder, AnimatedFormat};
use crate::animation::{self, FrameError, FrameJob, FrameRange, SceneSource};
use crate::film::{self, AtomicFile, ImageFormat};
use crate::pipeline::{CancelToken, Control, RenderError, Renderer};
use crate::tiles;

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

impl AnimationArgs {
    /// True when `kardia render` with these arguments is this file's business.
    pub fn applies(&self, args: &RenderArgs) -> bool {
        self.frames.is_some()
            || self.print_frame_count
            || self.frame.is_some()
            || self.turntable.is_some()
            || self.tile.is_some()
            || args.region.is_some()
            || AnimatedFormat::from_path(&args.output).is_some()
            || animation::has_frame_pattern(&args.output)
    }
}

/// Prints `err` the miette way and returns exit code 1.
fn report(err: impl miette::Diagnostic + Send + Sync + 'static) -> i32 {
    eprintln!("{:?}", miette::Report::new(err));
    1
}

fn usage(message: String) -> i32 {
    eprintln!("kardia: {message}");
    1
}

/// Runs `kardia render` for frames, turntables, animated outputs and parts.
pub fn run(args: &RenderArgs, interrupt: &CancelToken) -> i32 {
    let a = &args.animation;
    let source = match &args.scene {
        Some(path) => SceneSource::from_file(path),
        None => Ok(SceneSource::default_scene()),
    };
    let source = match source {
        Ok(s) => s,
        Err(e) => return report(e),
    };
    let options = args.load_options();
    let (still, declared) = match source.still(&options) {
        Ok(s) => s,
        Err(e) => return report(e),
    };
    if a.print_frame_count {
        outln!("{}", a.turntable.or(declared.frames).unwrap_or(1));
        return 0;
    }
    let animated = AnimatedFormat::from_path(&args.output);
    let pattern = animation::has_frame_pattern(&args.output);
    // Without a frame asked for, a scene is read as a still (frame 0 of 1), as a plain
    // `kardia render` reads it: so parts of a still join into exactly that render.
    let selects_frames = a.frame.is_some()
        || a.frames.is_some()
        || a.turntable.is_some()
        || animated.is_some()
        || pattern;
    let count = if selects_frames {
        a.turntable.or(declared.frames).unwrap_or(1)
    } else {
        1
    };
    let range = match (a.frame, a.frames) {
        (Some(n), _) => FrameRange { first: n, last: n },
        (None, Some(r)) => r,
        (None, None) if animated.is_some() || pattern => FrameRange::all(count),
        (None, None) => FrameRange { first: 0, last: 0 },
    };
    if range.last >= count {
        let source_of_count = match (a.turntable, declared.frames) {
            (Some(n), _) => format!("--turntable {n} makes {n}"),
            (None, Some(n)) => format!("the scene's FRAMES {n} makes {n}"),
            (None, None) => {
                "the scene has no FRAMES statement (and no --turntable is given), so it has 1"
                    .into()
            }
        };
        return usage(format!(
            "frame {} does not exist: {source_of_count} frame{}, numbered from 0",
            range.last,
            if count == 1 { "" } else { "s" }
        ));
    }
    if animated.is_some() && (a.tile.is_some() || args.region.is_some()) {
        return usage(
            "an animated output holds whole frames: --tile and --region need a .png or .exr output"
                .into(),
        );
    }
    if args.alpha && animated == Some(AnimatedFormat::Gif) {
        return usage(
            "--alpha needs an output with an alpha channel: GIF has only on/off transparency; \
             use .apng (or .png/.exr frames with `####`)"
                .into(),
        );
    }
    if args.alpha && (a.tile.is_some() || args.region.is_some()) {
        return usage(
            "--alpha is not available for parts: --tile and --region render opaque parts only"
                .into(),
        );
    }
    if animated.is_none() && !pattern && range.len() > 1 {
        return usage(format!(
            "{} frames need `####` in the output name for the frame number (such as \
             out/heart_####.png), or one animated .gif or .apng output",
            range.len()
        ));
    }
    let format = if animated.is_some() {
        None
    } else {
        let checked = film::check_output_path(&animation::frame_path(&args.output, range.first));
        match checked {
            Ok(ImageFormat::ExrFloat) if args.half => Some(ImageFormat::ExrHalf),
            Ok(f) => Some(f),
            Err(e) => return report(e),
        }
    };
    let mut request = args.request();
    let (full_width, full_height) = match request.full_size(&still) {
        Ok(s) => s,
        Err(e) => return report(e),
    };
    if let Some((i, n)) = a.tile {
        match tiles::band(i, n, full_width, full_height) {
            Ok(r) => request.region = Some(r),
            Err(m) => return usage(m),
        }
    }
    let region = match request.region_in(&still) {
        Ok(r) => r,
        Err(e) => return report(e),
    };
    let job = FrameJob {
        source,
        options,
        request,
        turntable: a.turntable,
        count,
    };
    let renderer = match Renderer::new(args.threads.map_or(0, |t| t as usize)) {
        Ok(r) => r,
        Err(e) => return report(e),
    };
    let bar = Progress::new(
        args.quiet,
        region.pixel_count() * u64::from(range.len()),
        args.progress_every,
        "kardia: {msg} {wide_bar} {percent:>3}% {elapsed}, eta {eta}",
    );
    let control = Control::new(interrupt.clone(), |p| bar.inc(p.finished));
    let started = std::time::Instant::now();
    let outcome = match animated {
        Some(kind) => {
            if a.resume && animation::is_complete_animation(&args.output) {
                Ok(Done {
                    rendered: 0,
                    skipped: range.len(),
                })
            } else {
                animate_into_one_file(
                    &job,
                    &renderer,
                    &control,
                    range,
                    kind,
                    &args.output,
                    declared.fps,
                    region,
                    &bar,
                )
            }
        }
        None => frames_to_files(
            &job,
            &renderer,
            &control,
            range,
            format.expect("a still format"),
            &args.output,
            a.resume,
            &bar,
            region.pixel_count(),
        ),
    };
    bar.finish();
    match outcome {
        Ok(done) => {
            if !args.quiet {
                let skipped = if done.skipped > 0 {
                    format!(" ({} already complete, skipped)", done.skipped)
                } else {
                    String::new()
                };
                eprintln!(
                    "kardia: {} frame{} of {}×{}{}, {} spp, {} thread{}, {:.2} s{skipped} → {}",
                    done.rendered,
                    if done.rendered == 1 { "" } else { "s" },
                    region.width,
                    region.height,
                    if a.tile.is_some() || args.region.is_some() {
                        format!(
                            " at ({}, {}) of {full_width}×{full_height}",
                            region.x, region.y
                        )
                    } else {
                        String::new()
                    },
                    args.spp,
                    renderer.threads(),
                    if renderer.threads() == 1 { "" } else { "s" },
                    started.elapsed().as_secs_f64(),
                    args.output.display()
                );
            }
            0
        }
        Err(FrameError::Render(RenderError::Cancelled)) => {
            if !args.quiet {
                eprintln!("kardia: interrupted; the frame in progress was not written");
            }
            INTERRUPTED
        }
        Err(e) => report(e),
    }
}

/// How many frames were rendered and how many skipped as complete.
struct Done {
    rendered: u32,
    skipped: u32,
}

/// "frame 7 (3 of 10)": what the progress shows while `frame` of `range` renders.
fn frame_message(frame: u32, range: FrameRange) -> String {
    format!(
        "frame {frame} ({} of {})",
        frame - range.first + 1,
        range.len()
    )
}

/// Each frame to its own file (the pattern's `####` filled in).
#[allow(clippy::too_many_arguments)]
fn frames_to_files(
    job: &FrameJob,
    renderer: &Renderer,
    control: &Control,
    range: FrameRange,
    format: ImageFormat,
    pattern: &Path,
    resume: bool,
    bar: &Progress,
    pixels_per_frame: u64,
) -> Result<Done, FrameError> {
    let mut done = Done {
        rendered: 0,
        skipped: 0,
    };
    for frame in range.frames() {
        let path: PathBuf = animation::frame_path(pattern, frame);
        bar.set_message(frame_message(frame, range));
        if resume && job.is_done(frame, &path) {
            done.skipped += 1;
            bar.inc(pixels_per_frame);
            continue;
        }
        job.render_to_file(renderer, frame, control, format, &path)?;
        done.rendered += 1;
    }
    Ok(done)
}

/// Every frame into one animated file, written atomically.
#[allow(clippy::too_many_arguments)]
fn animate_into_one_file(
    job: &FrameJob,
    renderer: &Renderer,
    control: &Control,
    range: FrameRange,
    kind: AnimatedFormat,
    output: &Path,
    fps: f64,
    region: film::Region,
    bar: &Progress,
) -> Result<Done, FrameError> {
    let mut file = AtomicFile::create(output)?;
    let mut encoder = AnimatedEncoder::new(
        kind,
        &mut file,
        region.width,
        region.height,
        range.len(),
        fps,
        job.request.alpha,
    )?;
    for frame in range.frames() {
        bar.set_message(frame_message(frame, range));
        let (scene, request) = job.frame(frame)?;
        let rendered = renderer.render(&scene, &request, control)?;
        encoder.add_frame(&rendered.image)?;
    }
    encoder.finish()?;
    file.commit()?;
    Ok(Done {
        rendered: range.len(),
        skipped: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_parse() {
        assert_eq!(parse_tile("0/4"), Ok((0, 4)));
        assert_eq!(parse_tile("3/4"), Ok((3, 4)));
        assert!(parse_tile("4/4").is_err());
        assert!(parse_tile("1/0").is_err());
        assert!(parse_tile("a/b").is_err());
        assert!(parse_tile("2").is_err());
    }
}
