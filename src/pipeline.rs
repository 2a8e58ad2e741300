//! The render API: a loaded [`Scene`] plus a [`RenderRequest`] in, an [`Image`] out. The CLI,
//! the explorer and the render farm all call this.
//!
//! - Load a scene once ([`crate::scene::parse`] / [`crate::scene::parse_file`]; the root solver
//!   is a load option, [`crate::scene::LoadOptions::solver`], because it is built into each
//!   surface), share it between threads (`Arc<Scene>`) and render it as often as needed with
//!   another camera, size, region or view: nothing here mutates the scene.
//! - Keep one [`Renderer`] per process: it owns the thread pool, reused by every render, and
//!   may serve several renders at once from several threads.
//! - A [`Control`] carries a [`CancelToken`] (checked before every row of every 16×16 tile)
//!   and a progress callback.
//! - A [`Region`] renders exactly the pixels the full image has there (the same samples, byte
//!   for byte), so regions rendered apart, on any machines, join into the whole image.
//! - Encode the result with [`crate::film::encode_png`] / [`crate::film::encode_exr`] to any
//!   writer, or write it atomically through a [`crate::film::AtomicFile`].
//!
//! ```no_run
//! use kardia::{film, pipeline::{Control, RenderRequest, Renderer}, scene};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = scene::parse_file("scenes/heart.scene".as_ref(), &Default::default())?;
//! let renderer = Renderer::new(0)?; // one thread per core
//! let request = RenderRequest { width: Some(400), spp: 4, ..RenderRequest::default() };
//! let rendered = renderer.render(&scene, &request, &Control::default())?;
//! film::write_image(&rendered.image, "heart.png".as_ref())?;
//! # Ok(())
//! # }
//! ```

pub use crate::film::Region;
pub use crate::integrator::{BandDone, View};

use crate::camera::Camera;
use crate::film::Image;
use crate::geometry::{DVec3, Ray};
use crate::integrator::{self, Hooks, Job, ShadeSetup};
use crate::scene::Scene;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What to render, beyond the scene. `Default` is the scene as written: its SIZE and CAMERA,
/// 4 samples a pixel, seed 0, depth 8, the whole image, shaded. (The root solver is not here:
/// it is chosen when the scene is loaded, [`crate::scene::LoadOptions::solver`], because each
/// surface is built with it.)
#[derive(Debug, Clone, PartialEq)]
pub struct RenderRequest {
    /// Width of the full image in pixels (1 ..= [`Scene::MAX_SIDE`]); `None`: the scene's, or
    /// with only `height` given, the width that keeps the scene's aspect ratio.
    pub width: Option<u32>,
    /// Height of the full image in pixels (1 ..= [`Scene::MAX_SIDE`]); `None`: the scene's, or
    /// with only `width` given, the height that keeps the scene's aspect ratio.
    pub height: Option<u32>,
    /// The camera; `None`: the scene's.
    pub camera: Option<Camera>,
    /// Samples per pixel (0 is taken as 1), stratified and jittered.
    pub spp: u32,
    /// Seed of the jitter and light sampling: the same seed gives the same image, whatever
    /// the thread count or region.
    pub seed: u64,
    /// Maximum depth of mirror reflection and refraction (0 = primary hits only).
    pub max_depth: u32,
    /// The rectangle of the full image to render (its pixels exactly as in the full image);
    /// `None`: the whole image.
    pub region: Option<Region>,
    /// Which image to make.
    pub view: View,
    /// A transparent background: the image gets an alpha channel, each pixel's alpha the
    /// fraction of its samples whose camera ray hit an object (so an anti-aliased edge is
    /// partly covered), and its colour leaves out the samples that saw only the background
    /// (premultiplied; see [`crate::film::Image::alpha`]). `false`: an opaque image, the
    /// scene's background in the misses.
    pub alpha: bool,
    /// At most this many shadow rays per spherical light for each sample; `None`: each
    /// light's own `SAMPLES`. An interactive preview takes 1 (its soft shadows converge as
    /// samples accumulate, in fewer rays a frame); a saved image keeps the scene's.
    pub max_shadow_rays: Option<u32>,
}

impl Default for RenderRequest {
    fn default() -> Self {
        Self {
            width: None,
            height: None,
            camera: None,
            spp: 4,
            seed: 0,
            max_depth: 8,
            region: None,
            view: View::Shaded,
            alpha: false,
            max_shadow_rays: None,
        }
    }
}

impl RenderRequest {
    /// The size of the full image: [`resolve_size`] of the scene's SIZE and this request's
    /// width and height; an error for a side outside `1 ..= Scene::MAX_SIDE`.
    pub fn full_size(&self, scene: &Scene) -> Result<(u32, u32), RenderError> {
        for side in [self.width, self.height].into_iter().flatten() {
            if !(1..=Scene::MAX_SIDE).contains(&side) {
                return Err(RenderError::BadSize(side));
            }
        }
        Ok(resolve_size(
            (scene.width, scene.height),
            self.width,
            self.height,
        ))
    }

    /// The region rendered (the whole image without one), checked to be non-empty and inside
    /// the full image.
    pub fn region_in(&self, scene: &Scene) -> Result<Region, RenderError> {
        let (w, h) = self.full_size(scene)?;
        match self.region {
            None => Ok(Region::full(w, h)),
            Some(r) if r.fits(w, h) => Ok(r),
            Some(r) => Err(RenderError::BadRegion {
                region: r,
                width: w,
                height: h,
            }),
        }
    }
}

/// The image size for a scene whose SIZE is `scene_size` when `width` and/or `height` are
/// asked for: both given, exactly those; one alone, the other follows the scene's aspect ratio
/// (rounded, at least 1, at most [`Scene::MAX_SIDE`]); neither, the scene's.
pub fn resolve_size(scene_size: (u32, u32), width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let (sw, sh) = scene_size;
    let aspect = sh as f64 / sw.max(1) as f64;
    let clamp = |v: f64| (v.round() as u32).clamp(1, Scene::MAX_SIDE);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, clamp(w as f64 * aspect)),
        (None, Some(h)) => (clamp(h as f64 / aspect), h),
        (None, None) => (sw, sh),
    }
}

/// A cancellation flag shared by a render and whoever may stop it: clones share one flag.
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token not yet cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every render holding this token (or a clone) to stop; they return
    /// [`RenderError::Cancelled`] within about one tile's time. Cannot be undone.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`CancelToken::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// How far a render has got, in pixels of its region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Pixels the tile just finished held.
    pub finished: u64,
    /// Pixels finished so far, this tile included (reaches `total` exactly once).
    pub done: u64,
    /// Pixels of the region.
    pub total: u64,
}

/// How a render shares the [`Renderer`]'s threads with the others running at the same time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Priority {
    /// The default: renders share the threads band by band (16 rows of the image each), and
    /// hand them over to an `Interactive` render within a few pixels (before the next group
    /// of pixels of a tile's row), going on from the start of that tile once no interactive
    /// render runs. The pixels are the same whatever the sharing (the rays counted include
    /// the part of a tile rendered again).
    #[default]
    Batch,
    /// Someone is waiting for this image (a live view's first frames after a change): it
    /// takes the threads ahead of every `Batch` render, so it never waits for more than a
    /// few pixels of theirs; interactive renders share the threads band by band among
    /// themselves. Keep it for small, short renders, since batch renders stand still while
    /// it runs.
    Interactive,
}

/// The caller's hold on a running render: a cancel token, a progress callback (called from
/// worker threads after each tile; keep it short) and the render's [`Priority`].
pub struct Control<'a> {
    /// Cancels the render.
    pub cancel: CancelToken,
    /// Called after each finished tile.
    pub progress: Box<dyn Fn(Progress) + Send + Sync + 'a>,
    /// How it shares the threads with other renders ([`Priority::Batch`] by default).
    pub priority: Priority,
}

impl Default for Control<'_> {
    fn default() -> Self {
        Self {
            cancel: CancelToken::new(),
            progress: Box::new(|_| {}),
            priority: Priority::Batch,
        }
    }
}

impl<'a> Control<'a> {
    /// No progress reports, cancelled by `cancel`.
    pub fn with_cancel(cancel: CancelToken) -> Self {
        Self {
            cancel,
            ..Self::default()
        }
    }

    /// Reports progress to `progress`, cancelled by `cancel`.
    pub fn new(cancel: CancelToken, progress: impl Fn(Progress) + Send + Sync + 'a) -> Self {
        Self {
            cancel,
            progress: Box::new(progress),
            ..Self::default()
        }
    }

    /// The same control with `priority`.
    pub fn with_priority(self, priority: Priority) -> Self {
        Self { priority, ..self }
    }
}

impl std::fmt::Debug for Control<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field("cancel", &self.cancel)
            .field("priority", &self.priority)
            .finish_non_exhaustive()
    }
}

/// Why a render made no image.
#[derive(Debug, Clone, PartialEq, thiserror::Error, miette::Diagnostic)]
pub enum RenderError {
    /// The cancel token was cancelled before every tile was done.
    #[error("the render was cancelled")]
    Cancelled,
    /// An image side outside `1 ..= Scene::MAX_SIDE`.
    #[error("an image side of {0} pixels is outside 1 ..= 32768")]
    BadSize(u32),
    /// The region is empty or reaches outside the full image.
    #[error("the region {}×{} at ({}, {}) does not lie inside the {width}×{height} image",
            .region.width, .region.height, .region.x, .region.y)]
    BadRegion {
        /// The region asked for.
        region: Region,
        /// Full image width.
        width: u32,
        /// Full image height.
        height: u32,
    },
}

/// What a render cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderStats {
    /// Rays traced: primary, reflected, refracted and shadow rays (each shadow-ray segment
    /// between transmissive surfaces counts as one).
    pub rays: u64,
    /// Wall-clock time of the render (not counting image writing).
    pub elapsed: Duration,
    /// Worker threads used.
    pub threads: usize,
}

impl RenderStats {
    /// Rays per second of wall-clock time (0 for an instantaneous render).
    pub fn rays_per_second(&self) -> f64 {
        let s = self.elapsed.as_secs_f64();
        if s > 0.0 {
            self.rays as f64 / s
        } else {
            0.0
        }
    }
}

/// A finished render.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The region's pixels (`region.width × region.height`; the whole image without a region).
    pub image: Image,
    /// Width of the full image the region belongs to.
    pub full_width: u32,
    /// Height of the full image the region belongs to.
    pub full_height: u32,
    /// Where `image` lies in the full image.
    pub region: Region,
    /// What it cost.
    pub stats: RenderStats,
}

impl Rendered {
    /// Everything but the pixels.
    pub fn summary(&self) -> RenderSummary {
        RenderSummary {
            full_width: self.full_width,
            full_height: self.full_height,
            region: self.region,
            stats: self.stats,
        }
    }
}

/// A finished render without its pixels ([`Renderer::render_streamed`] handed them to its
/// hook band by band): the same fields as [`Rendered`] but the image.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSummary {
    /// Width of the full image the region belongs to.
    pub full_width: u32,
    /// Height of the full image the region belongs to.
    pub full_height: u32,
    /// Where the rendered pixels lie in the full image.
    pub region: Region,
    /// What it cost.
    pub stats: RenderStats,
}

impl RenderSummary {
    /// The finished render with its region's image.
    pub fn with_image(self, image: Image) -> Rendered {
        let Self {
            full_width,
            full_height,
            region,
            stats,
        } = self;
        Rendered {
            image,
            full_width,
            full_height,
            region,
            stats,
        }
    }
}

/// The thread pool could not be built.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("cannot start the render threads: {0}")]
pub struct PoolError(String);

/// Renders scenes on a thread pool of its own, reused by every render. `Send + Sync`: keep one
/// per process and call it from any thread, several renders at once if need be (they share the
/// pool's threads).
#[derive(Debug)]
pub struct Renderer {
    pool: integrator::RenderPool,
}

impl Renderer {
    /// A renderer with `threads` worker threads (0: one per available core).
    pub fn new(threads: usize) -> Result<Self, PoolError> {
        let pool = integrator::RenderPool::new(threads).map_err(|e| PoolError(e.to_string()))?;
        Ok(Self { pool })
    }

    /// Worker threads in the pool.
    pub fn threads(&self) -> usize {
        self.pool.threads()
    }

    /// Renders `request` of `scene`: the region's image (linear RGB, every pixel finite), or
    /// why not ([`RenderError::Cancelled`] when `control.cancel` was cancelled before the last
    /// tile was done). Blocks the calling thread until then (from an async server, call it
    /// on a blocking thread).
    pub fn render(
        &self,
        scene: &Scene,
        request: &RenderRequest,
        control: &Control,
    ) -> Result<Rendered, RenderError> {
        self.render_in_bands(scene, request, control, &|_, _, _| {})
    }

    /// [`Renderer::render`], also handing each finished band of rows to `band_done(first_row,
    /// rows, alpha)` from the worker thread that rendered it (`first_row` counted in the
    /// region's image; `rows`: whole rows of it, [`integrator::TILE_SIZE`] of them except at
    /// the bottom edge; `alpha`: their coverage when the request asks for alpha). Bands are taken in order from the top, so they finish in nearly ascending order,
    /// each exactly once (none after a cancellation). Lets a caller consume the image while
    /// the rest is being rendered (e.g. compress it, [`crate::film::encode_png_streaming`]).
    pub fn render_in_bands(
        &self,
        scene: &Scene,
        request: &RenderRequest,
        control: &Control,
        band_done: &BandDone<'_>,
    ) -> Result<Rendered, RenderError> {
        let (image, summary) = self.render_with(scene, request, control, band_done, true)?;
        // `render_with` keeps the image when asked to.
        Ok(summary.with_image(image.expect("a kept image")))
    }

    /// [`Renderer::render_in_bands`] without keeping the image: each band's rows are handed to
    /// `band_done` (in the same order and with the same pixels) from a buffer that is reused
    /// for a later band once the hook returns, so the hook must copy what it keeps. For a
    /// caller that consumes the rows as they come (a streamed PNG): a whole image's memory is
    /// never allocated, so the render's memory is a few bands (one buffer per thread) whatever
    /// the image's size.
    pub fn render_streamed(
        &self,
        scene: &Scene,
        request: &RenderRequest,
        control: &Control,
        band_done: &BandDone<'_>,
    ) -> Result<RenderSummary, RenderError> {
        Ok(self
            .render_with(scene, request, control, band_done, false)?
            .1)
    }

    /// The render behind [`Renderer::render_in_bands`] (`keep_image`) and
    /// [`Renderer::render_streamed`].
    fn render_with(
        &self,
        scene: &Scene,
        request: &RenderRequest,
        control: &Control,
        band_done: &BandDone<'_>,
        keep_image: bool,
    ) -> Result<(Option<Image>, RenderSummary), RenderError> {
        let start = Instant::now();
        let (full_width, full_height) = request.full_size(scene)?;
        let region = request.region_in(scene)?;
        let camera = request.camera.as_ref().unwrap_or(&scene.camera);
        let setup = ShadeSetup {
            scene,
            camera,
            spp: request.spp.max(1),
            max_depth: request.max_depth,
            max_shadow_rays: request.max_shadow_rays,
        };
        let job = Job {
            scene,
            camera,
            full_width,
            full_height,
            region,
            spp: request.spp.max(1),
            seed: request.seed,
            alpha: request.alpha,
            keep_image,
        };
        let total = region.pixel_count();
        let done = AtomicU64::new(0);
        let cancelled = || control.cancel.is_cancelled();
        let tile_done = |finished| {
            let done = done.fetch_add(finished, Ordering::Relaxed) + finished;
            (control.progress)(Progress {
                finished,
                done,
                total,
            });
        };
        let hooks = Hooks {
            cancelled: &cancelled,
            tile_done: &tile_done,
            band_done,
            interactive: control.priority == Priority::Interactive,
        };
        let (image, rays) = integrator::render(&self.pool, request.view, &setup, &job, &hooks)
            .ok_or(RenderError::Cancelled)?;
        Ok((
            image,
            RenderSummary {
                full_width,
                full_height,
                region,
                stats: RenderStats {
                    rays,
                    elapsed: start.elapsed(),
                    threads: self.threads(),
                },
            },
        ))
    }
}

/// The colour `request.view` gives one world ray (which starts off any surface), shaded as in
/// a render of `request` (its camera, samples, depth and seed); a spherical light is sampled
/// once, at a point drawn from the seed. Meant for tests and probes.
pub fn trace_ray(scene: &Scene, request: &RenderRequest, ray: &Ray) -> DVec3 {
    let setup = ShadeSetup {
        scene,
        camera: request.camera.as_ref().unwrap_or(&scene.camera),
        spp: request.spp.max(1),
        max_depth: request.max_depth,
        max_shadow_rays: request.max_shadow_rays,
    };
    integrator::trace_ray(request.view, &setup, request.seed, ray)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Vec3;
    use crate::scene::{self, LoadOptions};
    use std::sync::Mutex;

    fn heart() -> Scene {
        scene::parse(scene::DEFAULT_SCENE, "heart.scene", &LoadOptions::default()).unwrap()
    }

    /// A band as a hook was handed it: first row, pixels, coverage, and the address of the
    /// pixels (which storage the renderer handed over).
    type HandedBand = (u32, Vec<Vec3>, Option<Vec<f32>>, usize);

    /// Renders with `render` (given the hook), collecting every band it hands over; returns
    /// what `render` returned and the bands sorted by first row.
    fn collect_bands<R>(render: impl FnOnce(&BandDone<'_>) -> R) -> (R, Vec<HandedBand>) {
        let handed = Mutex::new(Vec::new());
        let result = render(&|row, rows, alpha| {
            let band = (
                row,
                rows.to_vec(),
                alpha.map(<[f32]>::to_vec),
                rows.as_ptr() as usize,
            );
            handed.lock().unwrap().push(band);
        });
        let mut bands = handed.into_inner().unwrap();
        bands.sort_by_key(|band| band.0);
        (result, bands)
    }

    #[test]
    fn renderer_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Renderer>();
        check::<CancelToken>();
        check::<Control>();
        check::<Scene>();
    }

    #[test]
    fn lone_size_keeps_aspect() {
        assert_eq!(resolve_size((800, 400), Some(64), None), (64, 32));
        assert_eq!(resolve_size((800, 400), None, Some(10)), (20, 10));
        assert_eq!(resolve_size((800, 400), Some(3), Some(5)), (3, 5));
        assert_eq!(resolve_size((800, 400), None, None), (800, 400));
        assert_eq!(resolve_size((1, 32768), Some(2), None), (2, 32768));
    }

    #[test]
    fn sizes_and_regions_are_checked() {
        let scene = heart();
        let too_big = RenderRequest {
            width: Some(Scene::MAX_SIDE + 1),
            ..RenderRequest::default()
        };
        assert_eq!(too_big.full_size(&scene), Err(RenderError::BadSize(32769)));
        let outside = RenderRequest {
            width: Some(10),
            height: Some(10),
            region: Some(Region {
                x: 5,
                y: 0,
                width: 6,
                height: 2,
            }),
            ..RenderRequest::default()
        };
        let renderer = Renderer::new(1).unwrap();
        let err = renderer.render(&scene, &outside, &Control::default());
        assert!(matches!(err, Err(RenderError::BadRegion { .. })), "{err:?}");
    }

    #[test]
    fn bands_are_handed_over_once_each_and_match_the_image() {
        let scene = heart();
        let request = RenderRequest {
            width: Some(40),
            height: Some(37), // the last band is short
            ..RenderRequest::default()
        };
        let renderer = Renderer::new(2).unwrap();
        let (rendered, bands) = collect_bands(|hook| {
            renderer.render_in_bands(&scene, &request, &Control::default(), hook)
        });
        let rendered = rendered.unwrap();
        let rows: Vec<u32> = bands.iter().map(|band| band.0).collect();
        assert_eq!(rows, vec![0, 16, 32]);
        assert!(bands.iter().all(|band| band.2.is_none()), "no alpha asked");
        let handed: Vec<Vec3> = bands.into_iter().flat_map(|band| band.1).collect();
        assert_eq!(handed, rendered.image.pixels);
        let again = renderer
            .render(&scene, &request, &Control::default())
            .unwrap();
        assert_eq!(again.image, rendered.image);
        assert!(rendered.stats.rays >= 40 * 37);
        assert_eq!(rendered.stats.threads, 2);
    }

    #[test]
    fn streamed_bands_are_the_kept_image_with_and_without_alpha() {
        let scene = heart();
        for alpha in [false, true] {
            let request = RenderRequest {
                width: Some(40),
                height: Some(69), // five bands on two threads (buffers reused), the last short
                alpha,
                ..RenderRequest::default()
            };
            let renderer = Renderer::new(2).unwrap();
            let kept = renderer
                .render(&scene, &request, &Control::default())
                .unwrap();
            let (summary, bands) = collect_bands(|hook| {
                renderer.render_streamed(&scene, &request, &Control::default(), hook)
            });
            let summary = summary.unwrap();
            let rows: Vec<u32> = bands.iter().map(|band| band.0).collect();
            assert_eq!(rows, vec![0, 16, 32, 48, 64]);
            assert!(
                bands.iter().all(|band| band.1.len() % 40 == 0),
                "whole rows"
            );
            assert_eq!(bands[4].1.len(), 40 * 5, "the last band is five rows");
            // The memory promise: five bands from at most one buffer per thread.
            let mut buffers: Vec<usize> = bands.iter().map(|band| band.3).collect();
            buffers.sort_unstable();
            buffers.dedup();
            assert!(buffers.len() <= 2, "{} buffers for 5 bands", buffers.len());
            let pixels: Vec<Vec3> = bands.iter().flat_map(|band| band.1.clone()).collect();
            assert_eq!(pixels, kept.image.pixels);
            let coverage: Option<Vec<f32>> = alpha.then(|| {
                bands
                    .iter()
                    .flat_map(|band| band.2.clone().expect("coverage"))
                    .collect()
            });
            assert_eq!(coverage, kept.image.alpha);
            assert_eq!(summary.full_width, 40);
            assert_eq!(summary.full_height, 69);
            assert_eq!(summary.region, kept.region);
            assert_eq!(summary.stats.rays, kept.stats.rays);
        }
    }

    #[test]
    fn a_cancelled_streamed_render_says_so() {
        let scene = heart();
        let token = CancelToken::new();
        token.cancel();
        let control = Control::new(token, |_| {});
        let renderer = Renderer::new(2).unwrap();
        let bands = AtomicU64::new(0);
        let result =
            renderer.render_streamed(&scene, &RenderRequest::default(), &control, &|_, _, _| {
                bands.fetch_add(1, Ordering::Relaxed);
            });
        assert_eq!(result, Err(RenderError::Cancelled));
        assert_eq!(bands.into_inner(), 0);
    }

    #[test]
    fn a_cancelled_token_stops_before_any_tile() {
        let scene = heart();
        let token = CancelToken::new();
        let clone = token.clone();
        clone.cancel();
        assert!(token.is_cancelled());
        let tiles = AtomicU64::new(0);
        let control = Control::new(token, |_| {
            tiles.fetch_add(1, Ordering::Relaxed);
        });
        let renderer = Renderer::new(2).unwrap();
        let result = renderer.render(&scene, &RenderRequest::default(), &control);
        assert_eq!(result, Err(RenderError::Cancelled));
        drop(control);
        assert_eq!(tiles.into_inner(), 0);
    }
}
