//! `kardia render`: arguments → a plan of frames (`frames.rs`; a still is frame 0 alone) →
//! [`crate::animation`] → image files, and a summary line.

use super::frames::{frame_message, AnimationArgs};
use super::progress::{Progress, DEFAULT_INTERVAL_SECONDS};
use crate::animation::animated::AnimatedFormat;
use crate::animation::{self, FrameError, FrameEvent, FrameJob, SceneSource};
use crate::film::{self, ImageFormat};
use crate::pipeline::{
    CancelToken, Control, Region, RenderError, RenderRequest, RenderSummary, Renderer, View,
};
use crate::roots::Solver;
use crate::scene::{LoadOptions, Scene};
use crate::tiles;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use std::path::PathBuf;

/// Output written when no `-o` is given.
pub const DEFAULT_OUTPUT: &str = "heart.png";

/// Arguments of `kardia render`. `Default` gives the same values as `kardia render` with no
/// arguments.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct RenderArgs {
    /// Scene file; without it, the built-in default heart scene (scenes/heart.scene).
    pub scene: Option<PathBuf>,
    /// Output image: .png (8-bit sRGB) or .exr (linear float), chosen by the extension.
    #[arg(short, long, default_value = DEFAULT_OUTPUT)]
    pub output: PathBuf,
    /// Image width in pixels, overriding the scene's SIZE (alone, it keeps the aspect ratio).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=Scene::MAX_SIDE as i64))]
    pub width: Option<u32>,
    /// Image height in pixels, overriding the scene's SIZE (alone, it keeps the aspect ratio).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=Scene::MAX_SIDE as i64))]
    pub height: Option<u32>,
    /// Samples per pixel, stratified and jittered.
    #[arg(long, default_value_t = RenderRequest::default().spp,
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Worker threads [default: one per core].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Maximum depth of mirror reflection and refraction (0 = no secondary rays).
    #[arg(long, default_value_t = RenderRequest::default().max_depth)]
    pub max_depth: u32,
    /// Seed for the sample jitter and soft shadows; the same seed gives the same image.
    #[arg(long, default_value_t = RenderRequest::default().seed)]
    pub seed: u64,
    /// Root solver for hearts and implicit surfaces.
    #[arg(long, default_value = Solver::default().name(), value_parser = solver_parser())]
    pub solver: Solver,
    /// What to render: the shaded image, or a study view of the geometry (normals, depth)
    /// or of the root finder's work per pixel (roots, path, iterations, conditioning); a
    /// study view's legend is printed after the summary.
    #[arg(long, default_value = View::default().name(), value_parser = view_parser())]
    pub view: View,
    /// Render only the rectangle X,Y,WIDTH,HEIGHT (pixels of the full image, from its top-left
    /// corner) and write it as an image of its own, exactly as those pixels of the full image.
    #[arg(long, value_name = "X,Y,WIDTH,HEIGHT", value_parser = parse_region)]
    pub region: Option<Region>,
    /// Write an .exr output with 16-bit half-float channels instead of 32-bit float.
    #[arg(long)]
    pub half: bool,
    /// Transparent background: each pixel's alpha is the fraction of its samples whose camera
    /// ray hit an object. A .png is RGBA with straight alpha, an .exr RGBA with premultiplied
    /// colours; also for frames and .apng (not .gif, --tile or --region).
    #[arg(long)]
    pub alpha: bool,
    /// Print nothing but errors: no progress bar, no summary line.
    #[arg(short, long)]
    pub quiet: bool,
    /// Without a terminal (a farm job's log), print a plain progress line (frame, percentage,
    /// time left) every this many seconds; 0 after every tile. A terminal shows a bar instead.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_INTERVAL_SECONDS,
          value_parser = parse_interval)]
    pub progress_every: f64,
    /// Frames, turntables and tiles (see `frames.rs`).
    #[command(flatten)]
    pub animation: AnimationArgs,
}

impl RenderArgs {
    /// How the scene is loaded: with the chosen solver, at no particular time.
    pub(super) fn load_options(&self) -> LoadOptions {
        LoadOptions {
            solver: self.solver,
            ..LoadOptions::default()
        }
    }

    /// The render these arguments ask for (every field written out, so that a new one is
    /// decided here): the scene's camera, each light's own shadow samples.
    pub(super) fn request(&self) -> RenderRequest {
        RenderRequest {
            width: self.width,
            height: self.height,
            camera: None,
            spp: self.spp,
            seed: self.seed,
            max_depth: self.max_depth,
            region: self.region,
            view: self.view,
            alpha: self.alpha,
            max_shadow_rays: None,
        }
    }
}

fn solver_parser() -> impl TypedValueParser<Value = Solver> {
    PossibleValuesParser::new(Solver::ALL.iter().map(|(_, name)| *name))
        .map(|name| name.parse::<Solver>().unwrap_or_default())
}

fn view_parser() -> impl TypedValueParser<Value = View> {
    PossibleValuesParser::new(View::ALL.iter().map(|(_, name)| *name))
        .map(|name| name.parse::<View>().unwrap_or_default())
}

/// Parses a number of seconds ≥ 0.
fn parse_interval(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("expected a number of seconds ≥ 0, not '{s}'")),
    }
}

/// Parses `X,Y,WIDTH,HEIGHT` (non-negative integers, width and height at least 1).
fn parse_region(s: &str) -> Result<Region, String> {
    let numbers: Vec<u32> = s
        .split(',')
        .map(|part| part.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected X,Y,WIDTH,HEIGHT (four whole numbers), not '{s}'"))?;
    let [x, y, width, height] = numbers[..] else {
        return Err(format!(
            "expected X,Y,WIDTH,HEIGHT (four numbers), not '{s}'"
        ));
    };
    if width == 0 || height == 0 {
        return Err("the region's width and height must be at least 1".into());
    }
    Ok(Region {
        x,
        y,
        width,
        height,
    })
}

impl Default for RenderArgs {
    fn default() -> Self {
        let settings = RenderRequest::default();
        Self {
            scene: None,
            output: PathBuf::from(DEFAULT_OUTPUT),
            width: None,
            height: None,
            spp: settings.spp,
            threads: None,
            max_depth: settings.max_depth,
            seed: settings.seed,
            solver: Solver::default(),
            view: View::default(),
            region: None,
            half: false,
            alpha: false,
            quiet: false,
            progress_every: DEFAULT_INTERVAL_SECONDS,
            animation: AnimationArgs::default(),
        }
    }
}

/// Prints an error the miette way (message, and for scene errors the source line with a
/// caret) to stderr.
fn report(err: impl miette::Diagnostic + Send + Sync + 'static) {
    eprintln!("{:?}", miette::Report::new(err));
}

/// Exit code of a render stopped by `interrupt` (as a shell reports SIGINT; the binary turns
/// it into 128 + the number of the signal that cancelled, 143 for SIGTERM).
pub const INTERRUPTED: i32 = 130;

/// "4.5 M rays/s" and the like.
fn rate(per_second: f64) -> String {
    if per_second >= 1e6 {
        format!("{:.1} M rays/s", per_second / 1e6)
    } else if per_second >= 1e3 {
        format!("{:.1} k rays/s", per_second / 1e3)
    } else {
        format!("{per_second:.0} rays/s")
    }
}

/// Runs `kardia render`; returns the exit code (0 success, 1 any error, [`INTERRUPTED`] when
/// `interrupt` was cancelled: then the frame in progress is not written and no temporary file
/// is left).
pub fn run(args: RenderArgs, interrupt: &CancelToken) -> i32 {
    match render(&args, interrupt) {
        Ok(()) => 0,
        Err(Failure::Interrupted { still }) => {
            if !args.quiet {
                if still {
                    eprintln!("kardia: interrupted, nothing written");
                } else {
                    eprintln!("kardia: interrupted; the frame in progress was not written");
                }
            }
            INTERRUPTED
        }
        Err(Failure::Reported) => 1,
    }
}

/// How `kardia render` failed.
enum Failure {
    /// The error was printed.
    Reported,
    /// The interrupt token was cancelled (while rendering a plain still, or frames or parts).
    Interrupted { still: bool },
}

/// Prints `err` and gives up.
fn fail(err: impl miette::Diagnostic + Send + Sync + 'static) -> Failure {
    report(err);
    Failure::Reported
}

/// Prints a usage error and gives up.
fn usage(message: String) -> Failure {
    eprintln!("kardia: {message}");
    Failure::Reported
}

/// `kardia render` itself, one flow for a still, frames, a turntable, an animated file, a
/// tile or a region: check the output, load the scene (translated when foreign), plan the
/// frames, render each into an atomic file (or all into one animated file), print.
fn render(args: &RenderArgs, interrupt: &CancelToken) -> Result<(), Failure> {
    let a = &args.animation;
    let animated = AnimatedFormat::from_path(&args.output);
    // What can be checked of the output before loading is checked first (a frame pattern's
    // files all share its folder and extension).
    let format = if animated.is_some() || a.print_frame_count {
        None
    } else {
        let first = animation::frame_path(&args.output, 0);
        match film::check_output_path(&first).map_err(fail)? {
            ImageFormat::ExrFloat if args.half => Some(ImageFormat::ExrHalf),
            f => Some(f),
        }
    };
    let options = args.load_options();
    let (still, source, declared) = match &args.scene {
        Some(path) => crate::formats::load(path, &options).map(|loaded| {
            if !args.quiet {
                super::convert::print_warnings(path, &loaded.warnings);
            }
            // A foreign file is read at every frame, and keyed, by its translation.
            let source = SceneSource {
                text: loaded.text,
                name: path.display().to_string(),
            };
            (loaded.scene, source, loaded.animation)
        }),
        None => {
            let source = SceneSource::default_scene();
            source
                .still(&options)
                .map(|(scene, animation)| (scene, source, animation))
        }
    }
    .map_err(fail)?;
    if a.print_frame_count {
        outln!("{}", a.turntable.or(declared.frames).unwrap_or(1));
        return Ok(());
    }
    let plan = a
        .plan(&args.output, args.region, args.alpha, &declared)
        .map_err(usage)?;
    let interrupted = Failure::Interrupted { still: plan.still };
    let mut request = args.request();
    let (full_width, full_height) = request.full_size(&still).map_err(fail)?;
    if let Some((i, n)) = a.tile {
        request.region = Some(tiles::band(i, n, full_width, full_height).map_err(usage)?);
    }
    let region = request.region_in(&still).map_err(fail)?;
    let job = FrameJob {
        source,
        options,
        request,
        turntable: a.turntable,
        count: plan.count,
    };
    let renderer = Renderer::new(args.threads.map_or(0, |t| t as usize)).map_err(fail)?;
    let range = plan.range;
    let pixels_per_frame = region.pixel_count();
    let template = if plan.still {
        "kardia: rendering {wide_bar} {percent:>3}% {elapsed}, eta {eta}"
    } else {
        "kardia: {msg} {wide_bar} {percent:>3}% {elapsed}, eta {eta}"
    };
    let progress = Progress::new(
        args.quiet,
        pixels_per_frame * u64::from(range.len()),
        args.progress_every,
        template,
    );
    let on_frame = |event: FrameEvent| match event {
        FrameEvent::Rendering(frame) if !plan.still => {
            progress.set_message(frame_message(frame, range))
        }
        FrameEvent::Rendering(_) => {}
        FrameEvent::Skipped(frame) => {
            progress.set_message(frame_message(frame, range));
            progress.inc(pixels_per_frame);
        }
    };
    let control = Control::new(interrupt.clone(), |p| progress.inc(p.finished));
    let started = std::time::Instant::now();
    let outcome = match (animated, format) {
        (Some(kind), _) => animation::render_animated_file(
            &job,
            &renderer,
            &control,
            range,
            kind,
            &args.output,
            declared.fps,
            region,
            a.resume,
            &on_frame,
        ),
        (None, Some(format)) => animation::render_frames_to_files(
            &job,
            &renderer,
            &control,
            range,
            format,
            &args.output,
            a.resume,
            Some(&still),
            &on_frame,
        ),
        (None, None) => unreachable!("a still output's format is checked above"),
    };
    progress.finish();
    let done = match outcome {
        Ok(done) => done,
        Err(FrameError::Render(RenderError::Cancelled)) => return Err(interrupted),
        Err(_) if interrupt.is_cancelled() => return Err(interrupted),
        Err(e) => return Err(fail(e)),
    };
    if interrupt.is_cancelled() {
        return Err(interrupted);
    }
    if args.quiet {
        return Ok(());
    }
    match done.last {
        Some(summary) if plan.still => print_still_summary(args, &summary),
        _ => {
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
    }
    Ok(())
}

/// The summary of a plain still: its size, view, samples, threads, time, rays and file, then
/// a study view's legend.
fn print_still_summary(args: &RenderArgs, rendered: &RenderSummary) {
    let stats = &rendered.stats;
    let size = format!("{}×{}", rendered.full_width, rendered.full_height);
    let mut view = match args.view {
        View::Shaded => String::new(),
        other => format!(", {other} view"),
    };
    if args.alpha {
        view.push_str(", transparent background");
    }
    eprintln!(
        "kardia: {size}{view}, {} spp, {} thread{}, {:.2} s, {} rays, {} → {}",
        args.spp,
        stats.threads,
        if stats.threads == 1 { "" } else { "s" },
        stats.elapsed.as_secs_f64(),
        stats.rays,
        rate(stats.rays_per_second()),
        args.output.display()
    );
    if let Some(legend) = args.view.legend() {
        eprint!("{}", legend_text(args.view, &legend));
    }
}

/// A view's legend as lines of text: the title, then each colour (`#rrggbb`) and its meaning.
fn legend_text(view: View, legend: &crate::integrator::Legend) -> String {
    let mut out = format!("kardia: {view} view: {}\n", legend.title);
    for s in &legend.swatches {
        let [r, g, b] = s.srgb;
        out += &format!("  #{r:02x}{g:02x}{b:02x}  {}\n", s.label);
    }
    if !legend.note.is_empty() {
        out += &format!("  ({})\n", legend.note);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrapper {
        #[command(flatten)]
        args: RenderArgs,
    }

    #[test]
    fn default_matches_parsed_defaults() {
        let parsed = Wrapper::try_parse_from(["render"]).unwrap().args;
        assert_eq!(parsed, RenderArgs::default());
    }

    #[test]
    fn parses_every_option() {
        let a = Wrapper::try_parse_from([
            "render",
            "s.scene",
            "-o",
            "x.exr",
            "--width",
            "64",
            "--height",
            "32",
            "--spp",
            "9",
            "--threads",
            "2",
            "--max-depth",
            "3",
            "--seed",
            "7",
            "--solver",
            Solver::ALL[0].1,
            "--half",
            "--alpha",
            "--quiet",
        ])
        .unwrap()
        .args;
        assert_eq!(a.scene, Some(PathBuf::from("s.scene")));
        assert_eq!(
            (a.width, a.height, a.spp, a.threads),
            (Some(64), Some(32), 9, Some(2))
        );
        assert_eq!((a.max_depth, a.seed, a.half, a.quiet), (3, 7, true, true));
        assert!(a.alpha);
        assert!(Wrapper::try_parse_from(["render", "--spp", "0"]).is_err());
        assert!(Wrapper::try_parse_from(["render", "--solver", "nonsense"]).is_err());
        assert!(Wrapper::try_parse_from(["render", "--width", "40000"]).is_err());
    }

    #[test]
    fn views_and_regions_parse() {
        let a = Wrapper::try_parse_from(["render", "--view", "normals", "--region", "1,2,30,40"])
            .unwrap()
            .args;
        assert_eq!(a.view, View::Normals);
        assert_eq!(
            a.region,
            Some(Region {
                x: 1,
                y: 2,
                width: 30,
                height: 40
            })
        );
        for bad in ["1,2,3", "1,2,0,4", "a,b,c,d", "1,2,3,4,5", "-1,0,2,2"] {
            assert!(
                Wrapper::try_parse_from(["render", "--region", bad]).is_err(),
                "{bad}"
            );
        }
        assert!(Wrapper::try_parse_from(["render", "--view", "nonsense"]).is_err());
    }

    #[test]
    fn rates_read_well() {
        assert_eq!(rate(4.5e6), "4.5 M rays/s");
        assert_eq!(rate(2500.0), "2.5 k rays/s");
        assert_eq!(rate(12.0), "12 rays/s");
    }
}
