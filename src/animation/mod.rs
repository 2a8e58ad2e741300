//! Animations: which frames to render, their file names, their sample seeds, the turntable
//! orbit, and loading a scene at a frame. Every frame is a pure function of the scene text,
//! the settings and the frame number, so frames rendered apart, in any order, on any machine,
//! equal those of one sequential run.

pub mod animated;
mod sequence;

pub use sequence::{render_animated_file, render_frames_to_files, Done, FrameEvent};

use std::path::{Path, PathBuf};

use crate::camera::Camera;
use crate::film::{self, AtomicFile, FileTag, ImageFormat, OutputError, Region};
use crate::pipeline::{Control, RenderError, RenderRequest, RenderSummary, Renderer};
use crate::scene::{self, Animation, FrameTime, LoadOptions, Scene, SceneError};
use crate::tiles::{self, PartInfo};

/// An inclusive range of frame numbers `first ..= last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame rendered.
    pub first: u32,
    /// Last frame rendered (≥ `first`).
    pub last: u32,
}

impl FrameRange {
    /// Every frame of an animation of `count ≥ 1` frames.
    pub fn all(count: u32) -> Self {
        Self {
            first: 0,
            last: count.max(1) - 1,
        }
    }

    /// The frames, in order.
    pub fn frames(self) -> std::ops::RangeInclusive<u32> {
        self.first..=self.last
    }

    /// How many frames.
    pub fn len(self) -> u32 {
        self.last - self.first + 1
    }

    /// Never true (a range holds at least one frame); for clippy's sake.
    pub fn is_empty(self) -> bool {
        false
    }
}

impl std::str::FromStr for FrameRange {
    type Err = String;

    /// `A..B` (both included, A ≤ B) or a single frame `N`.
    fn from_str(s: &str) -> Result<Self, String> {
        let number = |t: &str| {
            t.trim()
                .parse::<u32>()
                .map_err(|_| format!("`{t}` is not a frame number (a whole number ≥ 0)"))
        };
        let (first, last) = match s.split_once("..") {
            Some((a, b)) => (number(a)?, number(b.trim_start_matches('='))?),
            None => {
                let n = number(s)?;
                (n, n)
            }
        };
        if first > last {
            return Err(format!(
                "the range {s} is empty: write FIRST..LAST with FIRST ≤ LAST (both included)"
            ));
        }
        Ok(Self { first, last })
    }
}

impl std::fmt::Display for FrameRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.first, self.last)
    }
}

/// The sample seed of `frame` for the render seed `seed`: `seed` itself at frame 0 (so frame 0
/// renders exactly as a still with that seed), a different stream at every other frame.
pub fn frame_seed(seed: u64, frame: u32) -> u64 {
    seed.wrapping_add(u64::from(frame).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// True when the file name of `path` holds a run of `#` to be replaced by the frame number.
pub fn has_frame_pattern(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n.to_string_lossy().contains('#'))
}

/// The path of `frame` for a pattern such as `out/heart_####.png`: the last run of `#` in the
/// file name becomes the frame number, zero-padded to the run's length (longer numbers are
/// written in full). A path without `#` is returned as it is.
pub fn frame_path(pattern: &Path, frame: u32) -> PathBuf {
    let Some(name) = pattern
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
    else {
        return pattern.to_path_buf();
    };
    let Some(end) = name.rfind('#').map(|i| i + 1) else {
        return pattern.to_path_buf();
    };
    let start = name[..end].trim_end_matches('#').len();
    let width = end - start;
    let replaced = format!("{}{frame:0width$}{}", &name[..start], &name[end..]);
    pattern.with_file_name(replaced)
}

/// The camera of frame `frame` of a turntable of `count ≥ 1` frames: the eye turned about the
/// line through `look_at` along the camera's up vector by `frame / count` of a full turn
/// (counter-clockwise seen from above), everything else as it was. Frame 0 is the camera
/// itself and frame `count` would be again, so the frames loop without a repeated frame.
pub fn orbit(camera: &Camera, frame: u32, count: u32) -> Camera {
    let angle = std::f64::consts::TAU * f64::from(frame) / f64::from(count.max(1));
    let axis = camera.up.normalize();
    let offset = camera.eye - camera.look_at;
    // Rodrigues' rotation of the offset about the axis.
    let (sin, cos) = angle.sin_cos();
    let turned = offset * cos + axis.cross(offset) * sin + axis * axis.dot(offset) * (1.0 - cos);
    camera
        .moved(camera.look_at + turned, camera.look_at, camera.up)
        .unwrap_or_else(|_| camera.clone())
}

/// A scene text to be read at many frames. For a foreign file (`.jsurf`, `.pic`) it is the
/// translation ([`crate::formats::Loaded::text`]), never the file's own text.
#[derive(Debug, Clone)]
pub struct SceneSource {
    /// kardia's scene text.
    pub text: String,
    /// Its name in error messages (usually the file path).
    pub name: String,
}

impl SceneSource {
    /// The built-in default scene.
    pub fn default_scene() -> Self {
        Self {
            text: scene::DEFAULT_SCENE.to_string(),
            name: "scenes/heart.scene".to_string(),
        }
    }

    /// The scene as a still (frame 0 of 1) and what it says about its animation.
    pub fn still(&self, options: &LoadOptions) -> Result<(Scene, Animation), SceneError> {
        let options = LoadOptions {
            time: None,
            ..*options
        };
        scene::parse_animated(&self.text, &self.name, &options)
    }

    /// The scene at frame `frame` of `count`: read anew with that frame's `clock`.
    pub fn at_frame(
        &self,
        options: &LoadOptions,
        frame: u32,
        count: u32,
    ) -> Result<Scene, SceneError> {
        let options = LoadOptions {
            time: Some(FrameTime { frame, count }),
            ..*options
        };
        scene::parse(&self.text, &self.name, &options)
    }
}

/// Everything that fixes the pixels of a frame besides its number: the scene text, the load
/// options, the render request (its seed is frame 0's), the turntable and the frame count.
#[derive(Debug, Clone)]
pub struct FrameJob {
    /// The scene text.
    pub source: SceneSource,
    /// Load options (the solver; the time is set per frame).
    pub options: LoadOptions,
    /// The request of every frame; `seed` is the seed of frame 0 (see [`frame_seed`]), and the
    /// camera, when given, is the one a turntable orbits.
    pub request: RenderRequest,
    /// Orbit the camera once in this many frames (`--turntable N`).
    pub turntable: Option<u32>,
    /// Frames in the animation (for `clock`): the turntable's, else the scene's `FRAMES`.
    pub count: u32,
}

/// Why a frame made no file.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum FrameError {
    /// The scene is wrong at this frame (the message names the frame when the value at fault
    /// depends on the time).
    #[error(transparent)]
    #[diagnostic(transparent)]
    Scene(#[from] SceneError),
    /// The render failed or was cancelled.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl FrameJob {
    /// The scene and render request of `frame`: the scene read anew at that frame, the
    /// frame's seed, and the turntable's camera.
    pub fn frame(&self, frame: u32) -> Result<(Scene, RenderRequest), SceneError> {
        let scene = self.source.at_frame(&self.options, frame, self.count)?;
        let request = self.request_at(frame, &scene);
        Ok((scene, request))
    }

    /// The render request of `frame`, whose scene (read at that frame) is `scene`: the
    /// frame's seed and the turntable's camera.
    pub fn request_at(&self, frame: u32, scene: &Scene) -> RenderRequest {
        let mut request = self.request.clone();
        request.seed = frame_seed(self.request.seed, frame);
        if let Some(n) = self.turntable {
            let camera = request.camera.as_ref().unwrap_or(&scene.camera);
            request.camera = Some(orbit(camera, frame, n));
        }
        request
    }

    /// The render key of `frame` (see [`tiles::render_key`]): the scene text and every
    /// setting that changes its pixels, except the region.
    pub fn key(&self, scene: &Scene, request: &RenderRequest, frame: u32) -> String {
        let (w, h) = request.full_size(scene).unwrap_or((0, 0));
        let mut settings = format!(
            "size={w}x{h} spp={} seed={} depth={} view={} solver={} frame={frame} count={} \
             turntable={:?} camera={:?}",
            request.spp,
            request.seed,
            request.max_depth,
            request.view.name(),
            self.options.solver.name(),
            self.count,
            self.turntable,
            request.camera.as_ref().map(|c| (
                c.eye,
                c.look_at,
                c.up,
                c.fov_degrees,
                c.orthographic_height()
            )),
        );
        if request.alpha {
            settings.push_str(" alpha");
        }
        // The files the scene read (MESH), by their bytes; nothing for a scene without one,
        // so its key is as before.
        for digest in scene.objects.iter().filter_map(|o| o.shape.source_digest()) {
            settings.push_str(" file=");
            settings.push_str(&digest);
        }
        tiles::render_key(&self.source.text, &settings)
    }

    /// The job of a still: `request` at frame 0 of 1, no turntable (what a plain
    /// `kardia render` does, and what parts of a still join into).
    pub fn still(source: SceneSource, options: LoadOptions, request: RenderRequest) -> Self {
        Self {
            source,
            options,
            request,
            turntable: None,
            count: 1,
        }
    }

    /// The render key of an animated file of `range` in `kind` at `fps` frames per second,
    /// each frame cropped to `region`: the first frame's key ([`FrameJob::key`], which names
    /// the scene text and every setting) with the range, format, rate and region.
    pub fn animation_key(
        &self,
        range: FrameRange,
        kind: animated::AnimatedFormat,
        fps: f64,
        region: Region,
    ) -> Result<String, FrameError> {
        let (scene, request) = self.frame(range.first)?;
        Ok(format!(
            "{} frames={}..={} format={kind:?} fps={fps} region={},{} {}x{}",
            self.key(&scene, &request, range.first),
            range.first,
            range.last,
            region.x,
            region.y,
            region.width,
            region.height
        ))
    }

    /// True when `path` already holds `frame` as this job makes it: the file decodes to the
    /// end ([`is_complete`]) and carries this frame's render key (a whole image, under
    /// [`tiles::KEY_TAG`]) or this frame's [`PartInfo`] (a region, under
    /// [`tiles::METADATA_KEY`]). A file from other settings, another scene or another frame,
    /// or one without a key, is not. What `--resume` checks before skipping a frame.
    pub fn is_done(&self, frame: u32, path: &Path) -> bool {
        let Ok((scene, request)) = self.frame(frame) else {
            return false;
        };
        let (Ok(region), Ok((full_width, full_height))) =
            (request.region_in(&scene), request.full_size(&scene))
        else {
            return false;
        };
        let key = self.key(&scene, &request, frame);
        let (name, expected) = if region == Region::full(full_width, full_height) {
            (tiles::KEY_TAG, key)
        } else {
            let info = PartInfo {
                full_width,
                full_height,
                region,
                seed: request.seed,
                spp: request.spp.max(1),
                frame,
                key,
            };
            (tiles::METADATA_KEY, info.to_text())
        };
        film::read_tag(path, name).is_some_and(|t| t == expected) && is_complete(path)
    }

    /// Renders `frame` (its `request.region`, if any) and writes it to `path` atomically in
    /// `format`: a whole image as `kardia render` writes a still, with its render key under
    /// [`tiles::KEY_TAG`]; a region as a part file with its [`PartInfo`]. Nothing is written when the render fails or is cancelled.
    pub fn render_to_file(
        &self,
        renderer: &Renderer,
        frame: u32,
        control: &Control,
        format: ImageFormat,
        path: &Path,
    ) -> Result<RenderSummary, FrameError> {
        let scene = self.source.at_frame(&self.options, frame, self.count)?;
        self.render_scene_to_file(renderer, frame, &scene, control, format, path)
    }

    /// [`FrameJob::render_to_file`] with the scene of `frame` already read (`scene` must be
    /// this job's scene at that frame: for a job of one frame, the scene read as a still).
    pub fn render_scene_to_file(
        &self,
        renderer: &Renderer,
        frame: u32,
        scene: &Scene,
        control: &Control,
        format: ImageFormat,
        path: &Path,
    ) -> Result<RenderSummary, FrameError> {
        let request = self.request_at(frame, scene);
        let region = request.region_in(scene)?;
        let (full_width, full_height) = request.full_size(scene)?;
        if region != Region::full(full_width, full_height) {
            if request.alpha {
                return Err(OutputError::Encode(
                    "a part of a frame (a region or tile) cannot have alpha".into(),
                )
                .into());
            }
            let rendered = renderer.render(scene, &request, control)?;
            let info = PartInfo {
                full_width,
                full_height,
                region,
                seed: request.seed,
                spp: request.spp.max(1),
                frame,
                key: self.key(scene, &request, frame),
            };
            tiles::write_part(&rendered.image, &info, format, path)?;
            return Ok(rendered.summary());
        }
        let key = self.key(scene, &request, frame);
        let tag = Some(FileTag {
            name: tiles::KEY_TAG,
            text: &key,
        });
        let mut file = AtomicFile::create(path)?;
        let rendered = if format == ImageFormat::Png {
            let (rendered, written) = film::encode_png_streaming_tagged(
                &mut file,
                region.width,
                region.height,
                request.alpha,
                tag,
                |sink| {
                    renderer.render_streamed(scene, &request, control, &|row, rows, alpha| {
                        sink.rows(row, rows, alpha)
                    })
                },
            );
            let rendered = rendered?;
            written?;
            rendered
        } else {
            let rendered = renderer.render(scene, &request, control)?;
            film::encode_tagged(&rendered.image, format, tag, &mut file)?;
            rendered.summary()
        };
        if control.cancel.is_cancelled() {
            return Err(RenderError::Cancelled.into());
        }
        file.commit()?;
        Ok(rendered)
    }
}

/// True when `path` holds a complete image: it exists and decodes to the end (PNG or EXR by
/// its extension). Outputs are written atomically, so an existing file is complete unless
/// something else wrote it; this checks anyway.
pub fn is_complete(path: &Path) -> bool {
    if !path.is_file() {
        return false;
    }
    match ImageFormat::from_path(path) {
        Ok(ImageFormat::Png) => image::open(path).is_ok(),
        Ok(_) => {
            use exr::prelude::*;
            read_first_rgba_layer_from_file(
                path,
                |_, _| (),
                |_: &mut (), _: Vec2<usize>, _: (f32, f32, f32, f32)| {},
            )
            .is_ok()
        }
        Err(_) => false,
    }
}

/// True when `path` holds a complete animated file (GIF or APNG by its extension) whose
/// every frame decodes.
pub fn is_complete_animation(path: &Path) -> bool {
    use image::AnimationDecoder;
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let reader = std::io::BufReader::new(file);
    match animated::AnimatedFormat::from_path(path) {
        Some(animated::AnimatedFormat::Gif) => image::codecs::gif::GifDecoder::new(reader)
            .is_ok_and(|d| d.into_frames().all(|f| f.is_ok())),
        Some(animated::AnimatedFormat::Apng) => {
            let Ok(mut reader) = png::Decoder::new(reader).read_info() else {
                return false;
            };
            let frames = reader.info().animation_control.map_or(1, |c| c.num_frames);
            let mut buffer = vec![0; reader.output_buffer_size().unwrap_or(0)];
            (0..frames).all(|_| reader.next_frame(&mut buffer).is_ok())
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DVec3;

    #[test]
    fn ranges_parse_inclusive() {
        assert_eq!("3..7".parse(), Ok(FrameRange { first: 3, last: 7 }));
        assert_eq!("3..=7".parse(), Ok(FrameRange { first: 3, last: 7 }));
        assert_eq!("5".parse(), Ok(FrameRange { first: 5, last: 5 }));
        assert_eq!("3..7".parse::<FrameRange>().unwrap().len(), 5);
        assert!("7..3".parse::<FrameRange>().is_err());
        assert!("a..3".parse::<FrameRange>().is_err());
        assert!("-1".parse::<FrameRange>().is_err());
        assert_eq!(FrameRange::all(24), FrameRange { first: 0, last: 23 });
    }

    #[test]
    fn frame_paths_are_zero_padded() {
        let p = |s: &str, f| frame_path(Path::new(s), f).display().to_string();
        assert_eq!(p("out/heart_####.png", 7), "out/heart_0007.png");
        assert_eq!(p("out/heart_##.png", 123), "out/heart_123.png");
        assert_eq!(p("a#b/f_###_x.exr", 4), "a#b/f_004_x.exr");
        assert_eq!(p("still.png", 4), "still.png");
        assert!(has_frame_pattern(Path::new("x/#.png")));
        assert!(!has_frame_pattern(Path::new("a#b/x.png")));
    }

    #[test]
    fn seeds_differ_per_frame_and_frame_zero_is_the_seed() {
        assert_eq!(frame_seed(42, 0), 42);
        assert_ne!(frame_seed(42, 1), frame_seed(42, 2));
        assert_ne!(frame_seed(42, 1), 42);
    }

    #[test]
    fn orbit_turns_about_the_look_at_point() {
        let c = Camera::new(
            DVec3::new(6.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::Z,
            40.0,
        )
        .unwrap();
        assert_eq!(orbit(&c, 0, 4).eye, c.eye);
        let quarter = orbit(&c, 1, 4);
        assert!((quarter.eye - DVec3::new(0.0, 6.0, 1.0)).length() < 1e-12);
        let half = orbit(&c, 2, 4);
        assert!((half.eye - DVec3::new(-6.0, 0.0, 1.0)).length() < 1e-12);
        assert_eq!(half.look_at, c.look_at);
        assert_eq!(half.fov_degrees, c.fov_degrees);
    }
}
