//! `kardia render`.

use crate::film::{self, ImageFormat};
use crate::integrator::{self, RenderSettings};
use crate::roots::Solver;
use crate::scene::{self, LoadOptions, Scene};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use std::io::IsTerminal;
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
    #[arg(long, default_value_t = RenderSettings::default().spp,
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Worker threads [default: one per core].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Maximum depth of mirror reflection and refraction (0 = no secondary rays).
    #[arg(long, default_value_t = RenderSettings::default().max_depth)]
    pub max_depth: u32,
    /// Seed for the sample jitter and soft shadows; the same seed gives the same image.
    #[arg(long, default_value_t = RenderSettings::default().seed)]
    pub seed: u64,
    /// Root solver for hearts and implicit surfaces.
    #[arg(long, default_value = Solver::default().name(), value_parser = solver_parser())]
    pub solver: Solver,
    /// Write an .exr output with 16-bit half-float channels instead of 32-bit float.
    #[arg(long)]
    pub half: bool,
    /// Print nothing but errors: no progress bar, no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

fn solver_parser() -> impl TypedValueParser<Value = Solver> {
    PossibleValuesParser::new(Solver::ALL.iter().map(|(_, name)| *name))
        .map(|name| name.parse::<Solver>().unwrap_or_default())
}

impl Default for RenderArgs {
    fn default() -> Self {
        let settings = RenderSettings::default();
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
            half: false,
            quiet: false,
        }
    }
}

/// Prints an error the miette way (message, and for scene errors the source line with a
/// caret) to stderr.
fn report(err: impl miette::Diagnostic + Send + Sync + 'static) {
    eprintln!("{:?}", miette::Report::new(err));
}

/// The scene's size after the command-line overrides: a lone width or height keeps the
/// scene's aspect ratio.
fn override_size(scene: &mut Scene, width: Option<u32>, height: Option<u32>) {
    let aspect = scene.height as f64 / scene.width.max(1) as f64;
    let clamp = |v: f64| (v.round() as u32).clamp(1, Scene::MAX_SIDE);
    match (width, height) {
        (Some(w), Some(h)) => (scene.width, scene.height) = (w, h),
        (Some(w), None) => (scene.width, scene.height) = (w, clamp(w as f64 * aspect)),
        (None, Some(h)) => (scene.width, scene.height) = (clamp(h as f64 / aspect), h),
        (None, None) => {}
    }
}

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

/// Runs `kardia render`; returns the exit code (0 success, 1 any error).
pub fn run(args: RenderArgs) -> i32 {
    // From here on an interrupt exits with code 130 and removes a half-written image.
    if let Err(e) = film::install_interrupt_cleanup() {
        eprintln!("kardia: warning: Ctrl-C will not clean up: {e}");
    }
    // Everything that can fail before rendering is checked first.
    let mut format = match film::check_output_path(&args.output) {
        Ok(f) => f,
        Err(e) => {
            report(e);
            return 1;
        }
    };
    if args.half && format == ImageFormat::ExrFloat {
        format = ImageFormat::ExrHalf;
    }
    let options = LoadOptions {
        solver: args.solver,
        ..LoadOptions::default()
    };
    let loaded = match &args.scene {
        Some(path) => scene::parse_file(path, &options),
        None => scene::parse(scene::DEFAULT_SCENE, "scenes/heart.scene", &options),
    };
    let mut scene = match loaded {
        Ok(s) => s,
        Err(e) => {
            report(e);
            return 1;
        }
    };
    override_size(&mut scene, args.width, args.height);

    let settings = RenderSettings {
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        threads: args.threads.map_or(0, |t| t as usize),
    };
    let pixels = scene.width as u64 * scene.height as u64;
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::with_draw_target(
            Some(pixels),
            indicatif::ProgressDrawTarget::stderr(),
        );
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "kardia: rendering {wide_bar} {percent:>3}% {elapsed}, eta {eta}",
        ) {
            bar.set_style(style);
        }
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    let progress = |n| bar.inc(n);
    let written = if format == ImageFormat::Png {
        // Rows are compressed while the rest of the image renders.
        film::write_png_streaming(&args.output, scene.width, scene.height, |sink| {
            integrator::render_in_bands(&scene, &settings, &progress, &|row, rows| {
                sink.rows(row, rows)
            })
            .1
        })
    } else {
        let (image, stats) = integrator::render_with_progress(&scene, &settings, &progress);
        film::write_image_as(&image, &args.output, format).map(|()| stats)
    };
    bar.finish_and_clear();
    let stats = match written {
        Ok(stats) => stats,
        Err(e) => {
            report(e);
            return 1;
        }
    };
    if !args.quiet {
        eprintln!(
            "kardia: {}×{}, {} spp, {} thread{}, {:.2} s, {} rays, {} → {}",
            scene.width,
            scene.height,
            settings.spp,
            stats.threads,
            if stats.threads == 1 { "" } else { "s" },
            stats.elapsed.as_secs_f64(),
            stats.rays,
            rate(stats.rays_per_second()),
            args.output.display()
        );
    }
    0
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
        assert!(Wrapper::try_parse_from(["render", "--spp", "0"]).is_err());
        assert!(Wrapper::try_parse_from(["render", "--solver", "nonsense"]).is_err());
        assert!(Wrapper::try_parse_from(["render", "--width", "40000"]).is_err());
    }

    #[test]
    fn lone_size_keeps_aspect() {
        let mut scene = Scene {
            width: 800,
            height: 400,
            camera: crate::camera::Camera::new(
                crate::geometry::DVec3::Z,
                crate::geometry::DVec3::ZERO,
                crate::geometry::DVec3::Y,
                40.0,
            )
            .unwrap(),
            background: crate::geometry::DVec3::ZERO,
            ambient: crate::geometry::DVec3::ZERO,
            lights: vec![],
            objects: vec![],
        };
        override_size(&mut scene, Some(64), None);
        assert_eq!((scene.width, scene.height), (64, 32));
        override_size(&mut scene, None, Some(10));
        assert_eq!((scene.width, scene.height), (20, 10));
        override_size(&mut scene, Some(3), Some(5));
        assert_eq!((scene.width, scene.height), (3, 5));
    }

    #[test]
    fn rates_read_well() {
        assert_eq!(rate(4.5e6), "4.5 M rays/s");
        assert_eq!(rate(2500.0), "2.5 k rays/s");
        assert_eq!(rate(12.0), "12 rays/s");
    }
}
