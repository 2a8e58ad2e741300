//! The scheduler: a region of the image cut into bands of [`TILE_SIZE`] rows (each rendered as
//! `TILE_SIZE`-square tiles), taken in order from a shared counter by the threads of a pool,
//! each written straight into its rows of the region's image; cancellation checked before
//! every row of every tile, progress reported after every tile, finished bands handed to a
//! hook. With `alpha`,
//! each pixel also gets its coverage (the fraction of its samples whose camera ray hit an
//! object) and its colour leaves out the samples that saw only the background.

use super::group_objects::{GroupObjects, GroupObjectsBuilder};
use super::sampling::{mix, pixel_key, point_in_grid, strata, Sample};
use super::{Shader, TILE_SIZE};
use crate::camera::Camera;
use crate::film::{self, Image, Region, Vec3};
use crate::geometry::{DVec3, Ray};
use crate::scene::Scene;
use crate::shapes::LANES;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// What one render samples: the camera, the full image's size, the region of it to render,
/// the samples per pixel and the seed, and whether to measure coverage.
pub(crate) struct Job<'a> {
    /// The scene the shader shades (to find the coverage of a shader that does not report it).
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub full_width: u32,
    pub full_height: u32,
    /// Inside the full image (checked by the caller).
    pub region: Region,
    pub spp: u32,
    pub seed: u64,
    /// Make an image with alpha (see the module docs).
    pub alpha: bool,
    /// Keep the region's image (else each band is rendered into a buffer that is reused once
    /// the band has gone to [`Hooks::band_done`], and no image is returned).
    pub keep_image: bool,
}

/// A hook handed each finished band of a render: its first row, its pixels and, for a
/// render with alpha, their coverage (see the scheduler's `Hooks::band_done`).
pub type BandDone<'a> = dyn Fn(u32, &[Vec3], Option<&[f32]>) + Sync + 'a;

/// The caller's side of a render, all called from worker threads.
pub(crate) struct Hooks<'a> {
    /// Asked before each row of each tile; once it answers true, no more rows are started.
    pub cancelled: &'a (dyn Fn() -> bool + Sync),
    /// Told how many pixels each finished tile held.
    pub tile_done: &'a (dyn Fn(u64) + Sync),
    /// Handed each finished band: its first row (in the region's image), its pixels (whole
    /// rows of the region's image, [`TILE_SIZE`] of them except at the bottom edge) and, for
    /// a job with alpha, their coverage. Bands are taken in order from the top, so they
    /// finish in nearly ascending order, each exactly once; never called for a band left
    /// unfinished by a cancellation.
    pub band_done: &'a BandDone<'a>,
    /// Someone waits for this image (a live view's first frames): it takes the threads ahead
    /// of every render that is not, which hand them over before their next few pixels (see
    /// [`RenderPool`]).
    pub interactive: bool,
}

/// The threads renders run on, shared by every render of a `Renderer`, with the number of
/// renders running on them now. Renders started together share the threads band by band
/// (each render's threads hand over after every band while another is running), except that
/// an interactive render goes first: while one runs, every other render hands its threads
/// over before its next group of pixels of a tile's row (and goes on from that tile once no
/// interactive render is left), so a view a person waits for never waits for more than a
/// few pixels of another render. Interactive renders share the threads band by band among themselves.
pub(crate) struct RenderPool {
    threads: rayon::ThreadPool,
    /// As many threads again, for interactive renders only: idle between them (batch
    /// renders wait while one runs, so the two never compete for the cores), which also
    /// keeps the operating system's scheduler from counting a long batch render's CPU time
    /// against the threads a person waits for. Started by the first interactive render (a
    /// command-line render never has one: its threads would only compete with the render's
    /// start for the cores); should that start fail, interactive renders run on `threads`.
    interactive_threads: std::sync::OnceLock<Option<rayon::ThreadPool>>,
    active: AtomicUsize,
    /// Interactive renders running now.
    interactive: AtomicUsize,
    /// Told when the last interactive render ends (the others wait on it).
    calm: (Mutex<()>, Condvar),
}

impl RenderPool {
    /// A pool of `threads` threads (0: one per available core).
    pub(crate) fn new(threads: usize) -> Result<Self, rayon::ThreadPoolBuildError> {
        Ok(Self {
            threads: build_threads(threads, "render")?,
            interactive_threads: std::sync::OnceLock::new(),
            active: AtomicUsize::new(0),
            interactive: AtomicUsize::new(0),
            calm: (Mutex::new(()), Condvar::new()),
        })
    }

    /// Threads in the pool.
    pub(crate) fn threads(&self) -> usize {
        self.threads.current_num_threads()
    }

    /// The threads interactive renders run on, started at the first call.
    fn interactive_threads(&self) -> &rayon::ThreadPool {
        self.interactive_threads
            .get_or_init(|| build_threads(self.threads(), "interactive").ok())
            .as_ref()
            .unwrap_or(&self.threads)
    }

    /// Whether an interactive render is running (a render that is not hands its threads over).
    fn interactive_running(&self) -> bool {
        self.interactive.load(Ordering::SeqCst) > 0
    }

    /// Waits until no interactive render is running, or `cancelled` says stop (asked every
    /// few milliseconds).
    fn wait_for_interactive(&self, cancelled: &(dyn Fn() -> bool + Sync)) {
        let (lock, calm) = &self.calm;
        let mut guard = lock.lock().unwrap_or_else(|e| e.into_inner());
        while self.interactive_running() && !cancelled() {
            guard = calm
                .wait_timeout(guard, Duration::from_millis(5))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Counts an interactive render in (until the guard is dropped).
    fn enter_interactive(&self) -> InteractiveGuard<'_> {
        self.interactive.fetch_add(1, Ordering::SeqCst);
        InteractiveGuard(self)
    }
}

/// A pool of `threads` threads (0: one per available core) named `kardia-{name}-{i}`.
fn build_threads(
    threads: usize,
    name: &'static str,
) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(move |i| format!("kardia-{name}-{i}"))
        .build()
}

/// An interactive render running on a [`RenderPool`]; dropping it wakes the renders waiting
/// for the last one to end.
struct InteractiveGuard<'a>(&'a RenderPool);

impl Drop for InteractiveGuard<'_> {
    fn drop(&mut self) {
        let (lock, calm) = &self.0.calm;
        let _guard = lock.lock().unwrap_or_else(|e| e.into_inner());
        if self.0.interactive.fetch_sub(1, Ordering::SeqCst) == 1 {
            calm.notify_all();
        }
    }
}

impl std::fmt::Debug for RenderPool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RenderPool")
            .field("threads", &self.threads())
            .field("active", &self.active.load(Ordering::Relaxed))
            .field("interactive", &self.interactive.load(Ordering::Relaxed))
            .finish()
    }
}

/// How a band's rendering ended.
enum BandEnd {
    /// Every tile done (and the band handed to the hook).
    Finished,
    /// Cancelled: the render stops.
    Cancelled,
    /// Handed the threads to an interactive render before the tile from this column, which
    /// is rendered (again, whole) when the band goes on.
    Suspended(u32),
}

/// A band left part-way for an interactive render (see [`BandEnd::Suspended`]).
struct Suspended {
    band: usize,
    /// The first column of the tile to render next.
    x0: u32,
    /// A streamed render's buffer holding the band's finished tiles.
    buffer: Option<BandBuffer>,
}

/// Renders `job.region` with `shader` on the threads of `pool`; returns the region's image
/// (`None` unless `job.keep_image`) and the rays traced, or `None` when cancelled before every
/// tile was done.
pub(crate) fn run<S: Shader>(
    pool: &RenderPool,
    shader: &S,
    job: &Job,
    hooks: &Hooks,
) -> Option<(Option<Image>, u64)> {
    let region = job.region;
    let (width, height) = (region.width, region.height);
    let sampler = PixelSampler::new(shader, job);
    let mut image = job.keep_image.then(|| {
        if job.alpha {
            Image::transparent(width, height)
        } else {
            Image::new(width, height)
        }
    });
    // Kept, each band of TILE_SIZE rows is a disjoint slice of the image, filled in place tile
    // by tile: no per-tile buffers, so the film exists once. Streamed, a band is filled in a
    // buffer of the render's, which goes back to it once the hook has had the band: at most
    // as many buffers as threads (and bands suspended), so the render's memory is a few bands
    // whatever the image's size (and the film's pages are never faulted in).
    // Workers take a suspended band first, else the next band from a shared counter: bands
    // finish in order from the top, and a worker that runs out of work waits for one band at
    // most.
    let band_len = width as usize * TILE_SIZE as usize;
    let band_count = height.div_ceil(TILE_SIZE) as usize;
    let kept: Option<Vec<Mutex<Band>>> = image.as_mut().map(|image| {
        let mut alpha_bands = image.alpha.as_mut().map(|a| a.chunks_mut(band_len));
        image
            .pixels
            .chunks_mut(band_len)
            .map(|pixels| {
                let alpha = alpha_bands.as_mut().and_then(Iterator::next);
                Mutex::new(Band { pixels, alpha })
            })
            .collect()
    });
    let buffers: Mutex<Vec<BandBuffer>> = Mutex::new(Vec::new());
    let suspended: Mutex<Vec<Suspended>> = Mutex::new(Vec::new());
    let next_band = AtomicUsize::new(0);
    let rays = AtomicU64::new(0);
    let stopped = AtomicBool::new(false);
    // A render that is not interactive hands its threads over while an interactive one runs.
    let give_way = || !hooks.interactive && pool.interactive_running();
    let stop_row = || (hooks.cancelled)() || give_way();
    // Band `band`'s rows from the tile at column `x0` on rendered into `out`, which the hook
    // is then handed.
    let render_band = |band: usize, x0: u32, out: &mut Band| -> BandEnd {
        let y0 = band as u32 * TILE_SIZE;
        let y1 = (y0 + TILE_SIZE).min(height);
        let mut band_rays = 0;
        let mut end = BandEnd::Finished;
        for x0 in (x0..width).step_by(TILE_SIZE as usize) {
            if (hooks.cancelled)() {
                end = BandEnd::Cancelled;
                break;
            }
            if give_way() {
                end = BandEnd::Suspended(x0);
                break;
            }
            let x1 = (x0 + TILE_SIZE).min(width);
            let (tile_rays, finished) =
                sampler.tile(shader, region, (x0, x1), (y0, y1), out, &stop_row);
            band_rays += tile_rays;
            if !finished {
                end = if (hooks.cancelled)() {
                    BandEnd::Cancelled
                } else {
                    BandEnd::Suspended(x0)
                };
                break;
            }
            (hooks.tile_done)(((x1 - x0) * (y1 - y0)) as u64);
        }
        rays.fetch_add(band_rays, Ordering::Relaxed);
        if let BandEnd::Finished = end {
            (hooks.band_done)(y0, &*out.pixels, out.alpha.as_deref());
        }
        end
    };
    let worker = || loop {
        if give_way() {
            return;
        }
        let resumed = suspended.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let (band, x0, buffer) = match resumed {
            Some(s) => (s.band, s.x0, s.buffer),
            None => {
                let band = next_band.fetch_add(1, Ordering::Relaxed);
                if band >= band_count {
                    return;
                }
                (band, 0, None)
            }
        };
        let (end, buffer) = match &kept {
            Some(bands) => {
                // A band is worked on by one thread at a time, so its lock is never contended.
                let mut out = bands[band].lock().unwrap_or_else(|e| e.into_inner());
                (render_band(band, x0, &mut out), None)
            }
            None => {
                let rows = (height - band as u32 * TILE_SIZE).min(TILE_SIZE) as usize;
                let len = rows * width as usize;
                let mut buffer = buffer.unwrap_or_else(|| {
                    let taken = buffers.lock().unwrap_or_else(|e| e.into_inner()).pop();
                    taken.unwrap_or_else(|| BandBuffer::new(band_len, job.alpha))
                });
                (render_band(band, x0, &mut buffer.band(len)), Some(buffer))
            }
        };
        match end {
            BandEnd::Finished => {
                if let Some(buffer) = buffer {
                    buffers
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push(buffer);
                }
            }
            BandEnd::Cancelled => {
                stopped.store(true, Ordering::Relaxed);
                return;
            }
            BandEnd::Suspended(x0) => {
                suspended
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(Suspended { band, x0, buffer });
                return;
            }
        }
        let others = if hooks.interactive {
            pool.interactive.load(Ordering::Relaxed)
        } else {
            pool.active.load(Ordering::Relaxed)
        };
        if others > 1 {
            // Another render waits for these threads: let it have them for a band.
            return;
        }
    };
    pool.active.fetch_add(1, Ordering::Relaxed);
    let interactive = hooks.interactive.then(|| pool.enter_interactive());
    // Until every band is done (or the render is cancelled): each round ends when every
    // thread has left the worker, after one band each while other renders are running, or
    // at once while an interactive render runs and this one is not (it waits for it to end).
    loop {
        let left = next_band.load(Ordering::Relaxed) < band_count
            || !suspended
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .is_empty();
        if stopped.load(Ordering::Relaxed) || !left {
            break;
        }
        if (hooks.cancelled)() {
            stopped.store(true, Ordering::Relaxed);
            break;
        }
        if !hooks.interactive {
            pool.wait_for_interactive(hooks.cancelled);
        }
        let threads = if hooks.interactive {
            pool.interactive_threads()
        } else {
            &pool.threads
        };
        threads.broadcast(|_| worker());
    }
    drop(interactive);
    pool.active.fetch_sub(1, Ordering::Relaxed);
    drop(kept);
    if stopped.into_inner() {
        return None;
    }
    Some((image, rays.into_inner()))
}

/// A streamed render's storage for one band (see [`run`]): every pixel of a band is written
/// before the hook sees it, so a reused buffer's old contents never show.
struct BandBuffer {
    pixels: Vec<Vec3>,
    alpha: Option<Vec<f32>>,
}

impl BandBuffer {
    /// Room for `len` pixels, with their coverage when `alpha`.
    fn new(len: usize, alpha: bool) -> Self {
        Self {
            pixels: vec![Vec3::ZERO; len],
            alpha: alpha.then(|| vec![0.0; len]),
        }
    }

    /// The first `len` pixels (at most the buffer's) as a band.
    fn band(&mut self, len: usize) -> Band<'_> {
        Band {
            pixels: &mut self.pixels[..len],
            alpha: self.alpha.as_mut().map(|a| &mut a[..len]),
        }
    }
}

/// One band of rows of the region's image: its pixels and, with alpha, their coverage.
struct Band<'a> {
    pixels: &'a mut [Vec3],
    alpha: Option<&'a mut [f32]>,
}

/// Everything fixed for one render's pixels.
struct PixelSampler<'a> {
    scene: &'a Scene,
    /// Whether to find each pixel's coverage (and leave the misses out of its colour).
    alpha: bool,
    camera: &'a Camera,
    /// The full image's size, which the camera spans.
    full: (u32, u32),
    spp: u32,
    /// The [`strata`] of `spp`: where a pixel's samples go.
    pixel_grid: (u32, u32),
    /// `mix(seed)`.
    seed: u64,
    /// Which pixels' camera rays may meet an object's bounds ([`seen_mask`]), and the stored
    /// value of a pixel whose rays meet none ([`unseen_pixel`]); `None`: every ray is traced.
    seen: Option<(SeenMask, Vec3)>,
    /// Each group's objects ([`seen_pixels`]), for a scene whose queries use its index: a
    /// group's camera rays ask those alone. `None`: they ask the whole scene.
    groups: Option<GroupObjects>,
}

/// What the film stores for a pixel all `spp` samples of which are misses of colour
/// `colour` (the shader's [`Shader::miss_colour`]): their mean as a traced pixel's is made
/// (nothing with `alpha`, where misses add no colour).
fn unseen_pixel(colour: DVec3, spp: u32, alpha: bool) -> Vec3 {
    let mut sum = DVec3::ZERO;
    for _ in 0..spp {
        sum += colour;
    }
    let sum = if alpha { DVec3::ZERO } else { sum };
    film::to_stored(sum * (1.0 / spp as f64))
}

/// Which pixels of a region may see an object, one bit a pixel, row by row from the top.
#[derive(Debug, Clone)]
struct SeenMask {
    /// The region's first column in the full image, and its width.
    x: u32,
    width: u32,
    /// Words of `bits` a row.
    words: usize,
    /// Bit `c % 64` of word `row · words + c / 64`: pixel `c` of the row (counted from `x`).
    bits: Vec<u64>,
}

impl SeenMask {
    /// No pixel of `region` marked.
    fn new(region: Region) -> Self {
        let words = (region.width as usize).div_ceil(64);
        Self {
            x: region.x,
            width: region.width,
            words,
            bits: vec![0; words * region.height as usize],
        }
    }

    /// Marks the pixels of the region's `row` whose camera rays may pass through the
    /// full-image columns `(x0, x1)`: pixel `c` (full-image column, spanning `[c, c + 1]`)
    /// when `c + 1 ≥ x0` and `c ≤ x1`. Nothing when `x0 > x1`.
    #[cfg(test)]
    fn mark(&mut self, row: usize, (x0, x1): (f64, f64)) {
        self.mark_columns(row, self.columns(pixel_bounds((x0, x1))));
    }

    /// [`pixel_bounds`]' whole-number bounds `(lo, hi)` (full-image columns) as columns of the
    /// region, clipped to it: `lo` to `[0, width]` and `hi` to `[−1, width − 1]`, so the pair
    /// is empty where it was or where it lies outside the region. A NaN bound takes no part,
    /// as in `f64::max` and `f64::min`: the larger and the smaller of two pairs of columns
    /// are the columns of the larger and the smaller of the two pairs of bounds.
    fn columns(&self, (lo, hi): (f64, f64)) -> (i64, i64) {
        let (first, width) = (i64::from(self.x), i64::from(self.width));
        // `as` saturates ±∞ (and whole numbers beyond `i64`).
        let lo = if lo.is_nan() {
            0
        } else {
            (lo as i64).saturating_sub(first).clamp(0, width)
        };
        let hi = if hi.is_nan() {
            width - 1
        } else {
            (hi as i64).saturating_sub(first).clamp(-1, width - 1)
        };
        (lo, hi)
    }

    /// Marks the pixels of the region's `row` in the region's columns `lo ..= hi` (as
    /// [`SeenMask::columns`] gives them). Nothing when `lo > hi`.
    fn mark_columns(&mut self, row: usize, (lo, hi): (i64, i64)) {
        if lo > hi {
            return;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        let words = &mut self.bits[row * self.words..(row + 1) * self.words];
        let (first, last) = (lo / 64, hi / 64);
        let from = u64::MAX << (lo % 64);
        let to = u64::MAX >> (63 - hi % 64);
        if first == last {
            words[first] |= from & to;
        } else {
            words[first] |= from;
            words[first + 1..last].fill(u64::MAX);
            words[last] |= to;
        }
    }

    /// Whether any of the `count` pixels from full-image column `image_x` rightwards (inside
    /// the region) in the region's `row` is marked.
    #[inline]
    fn any(&self, row: usize, image_x: u32, count: u32) -> bool {
        let words = &self.bits[row * self.words..(row + 1) * self.words];
        (image_x - self.x..image_x - self.x + count)
            .any(|c| words[c as usize / 64] >> (c % 64) & 1 == 1)
    }
}

/// The first and last pixel columns `c` whose camera rays may pass through the full-image
/// columns `(x0, x1)` (pixel `c` spans `[c, c + 1]`: `c + 1 ≥ x0` and `c ≤ x1`), as
/// whole numbers in `f64`; the first above the last when there are none. Both ends are
/// monotone in theirs, so the bounds of `(x0.max(a), x1.min(b))` are the larger and the
/// smaller of the two pairs' bounds.
#[inline]
fn pixel_bounds((x0, x1): (f64, f64)) -> (f64, f64) {
    ((x0 - 1.0).ceil(), x1.floor())
}

/// The region's rows `first ..= last` (counted from its top; empty when `first > last`)
/// outside which no row's pixels `y` (full-image rows, spanning `[y, y + 1]`) have
/// `y + 1 ≥ y0` and `y ≤ y1`: those rows and one more on each side (for the rounding of the
/// bounds); a NaN bound does not narrow them.
fn box_rows((y0, y1): (f64, f64), region: Region) -> (usize, usize) {
    let last_row = region.height as f64 - 1.0;
    let top = f64::from(region.y);
    let lo = (y0 - 1.0 - top).ceil() - 1.0;
    let hi = (y1 - top).floor() + 1.0;
    // `f64::max` and `min` pass over a NaN: the whole region then.
    let (lo, hi) = (lo.max(0.0), hi.min(last_row));
    if lo > hi {
        return (1, 0);
    }
    (lo as usize, hi as usize)
}

/// The pixels of `job`'s region whose camera rays may meet an object: those that see its
/// bounding box and, where the object gives them, one of its enclosing ellipsoids and one of
/// its enclosing cells. `None` when the camera does not see every box from in front.
#[cfg(test)]
fn seen_mask(job: &Job) -> Option<SeenMask> {
    seen_pixels(job, false).map(|(mask, _)| mask)
}

/// [`seen_mask`], and with `list_objects` each group's objects: those whose pixels the mask
/// marks on the group (a camera ray of the group meets no other object's box, or meets it
/// outside every region where the object can be hit).
fn seen_pixels(job: &Job, list_objects: bool) -> Option<(SeenMask, Option<GroupObjects>)> {
    let (camera, w, h) = (job.camera, job.full_width, job.full_height);
    let nothing = (f64::INFINITY, f64::NEG_INFINITY);
    let hull = |a: (f64, f64), b: (f64, f64)| (a.0.min(b.0), a.1.max(b.1));
    let region = job.region;
    let mut mask = SeenMask::new(region);
    let mut lists = if list_objects && u32::try_from(job.scene.objects.len()).is_ok() {
        GroupObjectsBuilder::new(region.width, region.height)
    } else {
        None
    };
    let row_y = |row: usize| f64::from(region.y) + row as f64;
    for (index, object) in job.scene.objects.iter().enumerate() {
        if let Some(lists) = &mut lists {
            // Fits: checked above.
            lists.start_object(index as u32);
        }
        let boxed = camera.image_rect(&object.bounds, w, h)?;
        // The ellipsoids' images, if the camera sees them all.
        let images: Option<Vec<_>> = object
            .shape
            .enclosing_ellipsoids()
            .iter()
            .map(|e| camera.ellipsoid_image(e, w, h))
            .collect();
        let images = images.filter(|i| !i.is_empty());
        // The rows that may see the box (all of them where its rectangle is NaN): only their
        // spans are worked out, so an object costs its own rows, not the region's.
        let (first, last) = box_rows(boxed.y, region);
        // For each of those rows, the columns outside which no camera ray meets the box or
        // the ellipsoids.
        let spans: Vec<(f64, f64)> = (first..=last)
            .map(|row| {
                let y = row_y(row);
                let sees_box = y + 1.0 >= boxed.y.0 && y <= boxed.y.1;
                if !sees_box {
                    return nothing;
                }
                let mut seen = boxed.x;
                if let Some(images) = &images {
                    let near = images
                        .iter()
                        .filter_map(|i| i.row_span(y, y + 1.0))
                        .fold(nothing, hull);
                    seen = (seen.0.max(near.0), seen.1.min(near.1));
                }
                seen
            })
            .collect();
        if spans.is_empty() {
            continue;
        }
        // The cells' images, if the camera sees them all.
        let cells: Option<Vec<_>> = object
            .shape
            .enclosing_cells()
            .iter()
            .map(|c| camera.hull_rect(&c.corners, w, h))
            .collect();
        match cells.filter(|c| !c.is_empty()) {
            None => {
                for (k, &span) in spans.iter().enumerate() {
                    let columns = mask.columns(pixel_bounds(span));
                    mask.mark_columns(first + k, columns);
                    if let Some(lists) = &mut lists {
                        lists.mark(first + k, columns);
                    }
                }
            }
            Some(rects) => {
                // Each row's and each rectangle's columns once, not once a pair.
                let rows: Vec<(i64, i64)> = spans
                    .iter()
                    .map(|&span| mask.columns(pixel_bounds(span)))
                    .collect();
                for rect in rects {
                    let (rect_lo, rect_hi) = mask.columns(pixel_bounds(rect.x));
                    // The rows with `y + 1 ≥ rect.y.0` and `y ≤ rect.y.1`, among the box's.
                    let lo = (rect.y.0 - 1.0 - f64::from(region.y))
                        .ceil()
                        .max(first as f64);
                    let hi = (rect.y.1 - f64::from(region.y)).floor().min(last as f64);
                    if lo > hi {
                        continue;
                    }
                    let rows = rows.iter().enumerate().take(hi as usize - first + 1);
                    for (k, &(row_lo, row_hi)) in rows.skip(lo as usize - first) {
                        let columns = (row_lo.max(rect_lo), row_hi.min(rect_hi));
                        mask.mark_columns(first + k, columns);
                        if let Some(lists) = &mut lists {
                            lists.mark(first + k, columns);
                        }
                    }
                }
            }
        }
    }
    Some((mask, lists.map(GroupObjectsBuilder::finish)))
}

impl<'a> PixelSampler<'a> {
    /// The sampler of `job`'s pixels for `shader`.
    fn new<S: Shader>(shader: &S, job: &Job<'a>) -> Self {
        let seen = shader.miss_colour().and_then(|colour| {
            let stored = unseen_pixel(colour, job.spp.max(1), job.alpha);
            let (mask, groups) = seen_pixels(job, job.scene.may_use_index())?;
            Some(((mask, stored), groups))
        });
        let (seen, groups) = match seen {
            Some((seen, groups)) => (Some(seen), groups),
            None => (None, None),
        };
        PixelSampler {
            scene: job.scene,
            alpha: job.alpha,
            camera: job.camera,
            full: (job.full_width, job.full_height),
            spp: job.spp.max(1),
            pixel_grid: strata(job.spp),
            seed: mix(job.seed),
            seen,
            groups,
        }
    }

    /// Renders the tile of columns `xs` and rows `ys` of the region's image into `band`, the
    /// region's rows from `ys.0` on (the region's width), each pixel's `f64` mean stored as
    /// the film stores it; returns the rays traced. Pixel `(x, y)` of the region is pixel
    /// `(region.x + x, region.y + y)` of the full image, and is sampled as that pixel. With
    /// alpha, a sample whose primary ray hit nothing adds nothing to the colour (which is thus
    /// premultiplied) and the pixel's alpha is the fraction of samples that hit.
    /// `cancelled` is asked before each row of the tile and each group of pixels of a row but
    /// the first (a tile at many samples a pixel takes long enough for a page to notice):
    /// `false` with the rays so far when it says stop.
    fn tile<S: Shader>(
        &self,
        shader: &S,
        region: Region,
        xs: (u32, u32),
        ys: (u32, u32),
        band: &mut Band,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> (u64, bool) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.tile_avx2(shader, region, xs, ys, band, cancelled) };
        }
        self.tile_in(shader, region, xs, ys, band, cancelled)
    }

    /// [`PixelSampler::tile`] compiled for AVX2, with what it inlines (the sampling, the
    /// camera rays and the shader's own work around the scene's queries): the same
    /// operations, so the same bits (AVX2 brings no fused multiply-add).
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn tile_avx2<S: Shader>(
        &self,
        shader: &S,
        region: Region,
        xs: (u32, u32),
        ys: (u32, u32),
        band: &mut Band,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> (u64, bool) {
        self.tile_in(shader, region, xs, ys, band, cancelled)
    }

    /// [`PixelSampler::tile`]'s body, compiled into each of its copies.
    #[inline(always)]
    fn tile_in<S: Shader>(
        &self,
        shader: &S,
        region: Region,
        (x0, x1): (u32, u32),
        (y0, y1): (u32, u32),
        band: &mut Band,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> (u64, bool) {
        let width = region.width;
        let mut rays = 0;
        let inv = 1.0 / self.spp as f64;
        for y in y0..y1 {
            if y > y0 && cancelled() {
                return (rays, false);
            }
            let image_y = region.y + y;
            let mut x = x0;
            while x < x1 {
                // Also between groups of a row: a row at many samples a pixel takes long
                // enough to keep a waiting interactive render (or a cancel) waiting.
                if x > x0 && cancelled() {
                    return (rays, false);
                }
                // Whole groups of LANES neighbouring pixels go to the shader together.
                let lanes = (x1 - x).min(LANES as u32);
                if let Some(stored) = self.unseen(region.x + x, lanes, y) {
                    // No camera ray of these pixels meets a box: each sample is a miss.
                    let start = ((y - y0) * width + x) as usize;
                    let end = start + lanes as usize;
                    band.pixels[start..end].fill(stored);
                    if let Some(alpha) = band.alpha.as_deref_mut() {
                        alpha[start..end].fill(film::to_stored_alpha(0.0));
                    }
                    rays += u64::from(lanes * self.spp);
                    x += lanes;
                    continue;
                }
                let (sums, hits, group_rays) = if lanes == LANES as u32 {
                    let among = self.groups.as_ref().and_then(|g| g.of(y as usize, x));
                    self.pixels_together(shader, region.x + x, image_y, among)
                } else {
                    let mut sums = [DVec3::ZERO; LANES];
                    let mut hits = [0u32; LANES];
                    let mut group_rays = 0;
                    for lane in 0..lanes as usize {
                        let (sum, hit, r) = self.pixel(shader, region.x + x + lane as u32, image_y);
                        (sums[lane], hits[lane]) = (sum, hit);
                        group_rays += r;
                    }
                    (sums, hits, group_rays)
                };
                rays += group_rays;
                for lane in 0..lanes as usize {
                    let index = ((y - y0) * width + x) as usize + lane;
                    band.pixels[index] = film::to_stored(sums[lane] * inv);
                    if let Some(alpha) = band.alpha.as_deref_mut() {
                        alpha[index] = film::to_stored_alpha(hits[lane] as f64 * inv);
                    }
                }
                x += lanes;
            }
        }
        (rays, true)
    }

    /// The stored value of a pixel every sample of which misses ([`unseen_pixel`]) when no
    /// camera ray of the `count` pixels from column `image_x` rightwards, in row `region_y`
    /// of the region, can meet an object's bounds ([`seen_mask`]), else `None`.
    #[inline]
    fn unseen(&self, image_x: u32, count: u32, region_y: u32) -> Option<Vec3> {
        let (mask, stored) = self.seen.as_ref()?;
        (!mask.any(region_y as usize, image_x, count)).then_some(*stored)
    }

    /// The sum of the colours of pixel `(image_x, image_y)`'s samples (of those that hit an
    /// object, with alpha), how many of its samples hit, and the rays traced.
    fn pixel<S: Shader>(&self, shader: &S, image_x: u32, image_y: u32) -> (DVec3, u32, u64) {
        let mut state = Sample::new(pixel_key(self.seed, image_x, image_y), 0, self.spp);
        let mut sum = DVec3::ZERO;
        let mut hits = 0u32;
        for i in 0..self.spp {
            let ray = self.camera_ray(&mut state, i, image_x, image_y);
            let colour = shader.radiance(&ray, &mut state);
            if !self.alpha {
                sum += colour;
            } else if self.primary_hit(&ray, &mut state) {
                sum += colour;
                hits += 1;
            }
        }
        (sum, hits, state.rays)
    }

    /// [`PixelSampler::pixel`] for the `LANES` pixels from `(image_x, image_y)` rightwards,
    /// each sample index shaded for all of them at once ([`Shader::radiance_lanes`], or
    /// [`Shader::radiance_lanes_among`] with the group's objects `among`); every pixel's random
    /// numbers are drawn in the same order as by `pixel`, so the results are the same.
    #[inline(always)]
    fn pixels_together<S: Shader>(
        &self,
        shader: &S,
        image_x: u32,
        image_y: u32,
        among: Option<&[u32]>,
    ) -> ([DVec3; LANES], [u32; LANES], u64) {
        let mut states: [Sample; LANES] = std::array::from_fn(|lane| {
            Sample::new(
                pixel_key(self.seed, image_x + lane as u32, image_y),
                0,
                self.spp,
            )
        });
        let mut sums = [DVec3::ZERO; LANES];
        let mut hits = [0u32; LANES];
        for i in 0..self.spp {
            let rays = self.camera_rays(&mut states, i, image_x, image_y);
            let colours = match among {
                Some(objects) => shader.radiance_lanes_among(&rays, &mut states, objects),
                None => shader.radiance_lanes(&rays, &mut states),
            };
            for lane in 0..LANES {
                if !self.alpha {
                    sums[lane] += colours[lane];
                } else if self.primary_hit(&rays[lane], &mut states[lane]) {
                    sums[lane] += colours[lane];
                    hits[lane] += 1;
                }
            }
        }
        (sums, hits, states.iter().map(|s| s.rays).sum())
    }

    /// The camera ray of sample `i` of pixel `(image_x, image_y)`, its jitter drawn from
    /// `state` (made ready for that sample).
    #[inline]
    fn camera_ray(&self, state: &mut Sample, i: u32, image_x: u32, image_y: u32) -> Ray {
        let (full_w, full_h) = self.full;
        let (x, y) = self.sample_point(state, i, image_x, image_y);
        self.camera.ray(x, y, full_w, full_h)
    }

    /// The image-plane point (pixels) of sample `i` of pixel `(image_x, image_y)`, its jitter
    /// drawn from `state`, which is made ready for that sample.
    #[inline]
    fn sample_point(&self, state: &mut Sample, i: u32, image_x: u32, image_y: u32) -> (f64, f64) {
        state.index = i;
        state.primary_hit = None;
        let (u, v) = (state.uniform(), state.uniform());
        let (dx, dy) = point_in_grid(i, self.pixel_grid, u, v);
        (image_x as f64 + dx, image_y as f64 + dy)
    }

    /// [`PixelSampler::camera_ray`] of sample `i` for the [`LANES`] pixels from
    /// `(image_x, image_y)` rightwards, lane `lane` drawing from `states[lane]`: the same rays
    /// and random numbers, the rays made together ([`Camera::rays_lanes`]).
    #[inline(always)]
    fn camera_rays(
        &self,
        states: &mut [Sample; LANES],
        i: u32,
        image_x: u32,
        image_y: u32,
    ) -> [Ray; LANES] {
        let (full_w, full_h) = self.full;
        let mut xs = [0.0; LANES];
        let mut ys = [0.0; LANES];
        for (lane, state) in states.iter_mut().enumerate() {
            (xs[lane], ys[lane]) = self.sample_point(state, i, image_x + lane as u32, image_y);
        }
        self.camera.rays_lanes(xs, ys, full_w, full_h)
    }

    /// Whether the sample's primary `ray` hit an object: as its shader reported, or else
    /// found here (one more ray traced).
    fn primary_hit(&self, ray: &Ray, state: &mut Sample) -> bool {
        state.primary_hit.unwrap_or_else(|| {
            state.count_ray();
            self.scene.intersect(ray, 0.0, f64::INFINITY).is_some()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{DVec3, Ray};
    use crate::integrator::tests::unit_sphere_scene;
    use crate::integrator::{whitted::Whitted, ShadeSetup};

    /// White wherever it looks, and says nothing of what its rays hit.
    struct Silent;
    impl Shader for Silent {
        fn radiance(&self, _: &Ray, _: &mut Sample) -> DVec3 {
            DVec3::ONE
        }
    }

    fn render<S: Shader>(scene: &Scene, shader: &S, spp: u32, alpha: bool) -> Image {
        render_counting(scene, shader, spp, alpha).0
    }

    /// [`render`] with the rays traced.
    fn render_counting<S: Shader>(
        scene: &Scene,
        shader: &S,
        spp: u32,
        alpha: bool,
    ) -> (Image, u64) {
        let pool = RenderPool::new(2).unwrap();
        let job = Job {
            scene,
            camera: &scene.camera,
            full_width: scene.width,
            full_height: scene.height,
            region: Region::full(scene.width, scene.height),
            spp,
            seed: 3,
            alpha,
            keep_image: true,
        };
        let hooks = Hooks {
            cancelled: &|| false,
            tile_done: &|_| {},
            band_done: &|_, pixels, band_alpha| {
                assert_eq!(band_alpha.map(<[f32]>::len), alpha.then_some(pixels.len()));
            },
            interactive: false,
        };
        let (image, rays) = run(&pool, shader, &job, &hooks).unwrap();
        (image.expect("a kept image"), rays)
    }

    /// `S` with every ray traced: no [`Shader::miss_colour`].
    struct Traced<'a, S>(&'a S);

    impl<S: Shader> Shader for Traced<'_, S> {
        fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3 {
            self.0.radiance(ray, sample)
        }

        fn radiance_lanes(
            &self,
            rays: &[Ray; LANES],
            samples: &mut [Sample; LANES],
        ) -> [DVec3; LANES] {
            self.0.radiance_lanes(rays, samples)
        }
    }

    /// `shader`'s render of `scene` has the same pixels, coverage and ray count as the same
    /// shader's with every ray traced.
    fn assert_culling_changes_nothing<S: Shader>(scene: &Scene, shader: &S, spp: u32, alpha: bool) {
        let (culled, culled_rays) = render_counting(scene, shader, spp, alpha);
        let (traced, traced_rays) = render_counting(scene, &Traced(shader), spp, alpha);
        assert_eq!(culled.pixels, traced.pixels, "spp {spp} alpha {alpha}");
        assert_eq!(culled.alpha, traced.alpha);
        assert_eq!(culled_rays, traced_rays);
    }

    #[test]
    fn pixels_no_camera_ray_can_see_are_the_traced_misses() {
        // A sphere off to the left of a wide image, with a light and shadows: most pixels
        // are outside the rectangle its box projects to, and are answered untraced.
        let mut scene = unit_sphere_scene();
        (scene.width, scene.height) = (37, 21);
        scene.camera = Camera::new(
            DVec3::new(2.5, 0.0, 5.0),
            DVec3::new(2.5, 0.0, 0.0),
            DVec3::Y,
            70.0,
        )
        .unwrap();
        scene.background = DVec3::new(0.2, 0.4, 0.6);
        scene.ambient = DVec3::splat(0.1);
        scene.lights.push(crate::lights::Light {
            position: DVec3::new(3.0, 4.0, 5.0),
            colour: DVec3::ONE,
            radius: 0.5,
            samples: 4,
        });
        let job = Job {
            scene: &scene,
            camera: &scene.camera,
            full_width: scene.width,
            full_height: scene.height,
            region: Region::full(scene.width, scene.height),
            spp: 1,
            seed: 0,
            alpha: false,
            keep_image: true,
        };
        let mask = seen_mask(&job).expect("the box is in front of the eye");
        let seen_in = |row: usize| (0..37).filter(|&c| mask.any(row, c, 1)).collect::<Vec<_>>();
        assert!(seen_in(0).is_empty(), "the top row sees nothing: {mask:?}");
        assert!((0..21).all(|row| seen_in(row).iter().all(|&c| c < 25)));
        // The sphere's outline: narrower in its top row than in its middle.
        assert!(!seen_in(3).is_empty() && seen_in(10).len() > seen_in(3).len());
        for spp in [1, 3] {
            let setup = ShadeSetup {
                scene: &scene,
                camera: &scene.camera,
                spp,
                max_depth: 2,
                max_shadow_rays: None,
            };
            let whitted = Whitted::new(&setup);
            let normals = crate::integrator::normals::Normals::new(&setup);
            let depth = crate::integrator::depth::Depth::new(&setup);
            for alpha in [false, true] {
                assert_culling_changes_nothing(&scene, &whitted, spp, alpha);
                assert_culling_changes_nothing(&scene, &normals, spp, alpha);
                assert_culling_changes_nothing(&scene, &depth, spp, alpha);
            }
        }
        // No object: every pixel is the background, untraced, one ray a sample.
        scene.objects.clear();
        let setup = ShadeSetup {
            scene: &scene,
            camera: &scene.camera,
            spp: 2,
            max_depth: 2,
            max_shadow_rays: None,
        };
        let whitted = Whitted::new(&setup);
        let (image, rays) = render_counting(&scene, &whitted, 2, false);
        assert_eq!(rays, 2 * 37 * 21);
        assert_eq!(
            image.pixels,
            render(&scene, &Traced(&whitted), 2, false).pixels
        );
    }

    #[test]
    fn a_rectangle_clipped_by_bounds_marks_what_its_clipped_span_marks() {
        // `seen_mask` marks a cell's rectangle in a row by the larger and the smaller of the
        // two pairs of columns; the span clipped first must mark the same pixels.
        let region = Region {
            x: 30,
            y: 0,
            width: 200,
            height: 1,
        };
        let ends = [
            f64::NEG_INFINITY,
            -3.0,
            29.5,
            30.0,
            64.0,
            64.25,
            99.999,
            100.0,
            127.5,
            229.0,
            229.5,
            500.0,
            f64::INFINITY,
            f64::NAN,
        ];
        let mut marked = 0;
        for &a0 in &ends {
            for &a1 in &ends {
                for &b0 in &ends[..ends.len() / 2] {
                    for &b1 in &ends[ends.len() / 2..] {
                        let mut clipped = SeenMask::new(region);
                        clipped.mark(0, (a0.max(b0), a1.min(b1)));
                        let mut by_bounds = SeenMask::new(region);
                        let a = by_bounds.columns(pixel_bounds((a0, a1)));
                        let b = by_bounds.columns(pixel_bounds((b0, b1)));
                        by_bounds.mark_columns(0, (a.0.max(b.0), a.1.min(b.1)));
                        assert_eq!(
                            clipped.bits, by_bounds.bits,
                            "({a0}, {a1}) and ({b0}, {b1})"
                        );
                        marked += usize::from(clipped.bits.iter().any(|&w| w != 0));
                    }
                }
            }
        }
        assert!(marked > 100, "only {marked} cases marked anything");
    }

    #[test]
    fn an_objects_rows_hold_every_row_that_sees_its_box() {
        // Bounds at and between whole rows, beyond the region and NaN, for a region that
        // starts below the image's top.
        let region = Region {
            x: 0,
            y: 7,
            width: 4,
            height: 20,
        };
        let bounds = [
            f64::NAN,
            f64::NEG_INFINITY,
            f64::INFINITY,
            -3.0,
            0.0,
            6.5,
            7.0,
            8.0,
            8.25,
            15.0,
            26.0,
            27.0,
            26.999,
            40.0,
        ];
        for &y0 in &bounds {
            for &y1 in &bounds {
                let (first, last) = box_rows((y0, y1), region);
                for row in 0..region.height as usize {
                    let y = f64::from(region.y) + row as f64;
                    let sees = y + 1.0 >= y0 && y <= y1;
                    if sees {
                        assert!(
                            first <= row && row <= last,
                            "{y0} {y1}: row {row} not in {first}..={last}"
                        );
                    }
                }
                // Not much more than the rows that see it.
                if !(y0.is_nan() || y1.is_nan()) && first <= last {
                    assert!(
                        last - first <= ((y1 - y0).max(0.0) + 4.0) as usize,
                        "{y0} {y1}"
                    );
                }
            }
        }
    }

    #[test]
    fn every_run_of_columns_marks_exactly_its_pixels() {
        // Every pair of whole-number bounds around a region three words wide, against the
        // pixels one by one.
        let region = Region {
            x: 40,
            y: 0,
            width: 150,
            height: 2,
        };
        for lo in 36..=194 {
            for hi in 36..=194 {
                let mut mask = SeenMask::new(region);
                mask.mark_columns(1, mask.columns((f64::from(lo), f64::from(hi))));
                assert!(
                    mask.bits[..mask.words].iter().all(|&w| w == 0),
                    "row 0 untouched"
                );
                for c in 40..190u32 {
                    let want = i64::from(lo) <= i64::from(c) && i64::from(c) <= i64::from(hi);
                    assert_eq!(mask.any(1, c, 1), want, "bounds {lo}..={hi}, column {c}");
                }
            }
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn the_seen_mask_marks_what_each_span_says() {
        let region = Region {
            x: 70,
            y: 5,
            width: 150,
            height: 3,
        };
        let mut mask = SeenMask::new(region);
        // Pixel c (spanning [c, c + 1]) sees columns (x0, x1) when c + 1 ≥ x0 and c ≤ x1.
        let spans = [
            (100.5, 100.5),
            (63.0, 69.0),
            (133.2, 201.7),
            (219.5, 400.0),
            (90.0, 89.0),
        ];
        let mut want = vec![[false; 3]; 220];
        for (row, &(x0, x1)) in spans.iter().enumerate() {
            mask.mark(row % 3, (x0, x1));
            for (c, w) in want.iter_mut().enumerate().skip(70) {
                w[row % 3] |= c as f64 + 1.0 >= x0 && c as f64 <= x1;
            }
        }
        for row in 0..3 {
            for c in 70..220u32 {
                assert_eq!(
                    mask.any(row, c, 1),
                    want[c as usize][row],
                    "row {row} column {c}"
                );
                let count = (220 - c).min(4);
                let any = (c..c + count).any(|k| want[k as usize][row]);
                assert_eq!(
                    mask.any(row, c, count),
                    any,
                    "row {row} columns {c}+{count}"
                );
            }
        }
        assert!(!mask.any(0, 99, 1) && mask.any(0, 100, 1) && !mask.any(0, 101, 1));
        assert!(!mask.any(1, 70, 4), "(63, 69) ends left of the region");
        assert!(mask.any(0, 219, 1), "(219.5, 400) reaches the last column");
    }

    /// Hearts and spheres crowded in front of the camera (overlapping on the image, two
    /// spheres the same, so that rays meet several objects and ties between them), with a
    /// light: enough objects for the scene's index, every box in front of the eye.
    fn crowded_in_view() -> Scene {
        use crate::materials::Material;
        use crate::scene::{Object, ObjectIndex};
        use crate::shapes::{Heart, Sphere};
        let mut objects = Vec::new();
        let material = |r: f64| Material {
            diffuse: DVec3::new(r, 0.5, 0.3),
            ..Material::default()
        };
        for i in 0..4 {
            for j in 0..3 {
                let p = DVec3::new(
                    0.3 * f64::from(j) - 0.3,
                    f64::from(i) - 1.6,
                    f64::from(j) - 1.0,
                );
                let a = 0.45 + 0.05 * f64::from(i);
                let heart = Heart::new(p, DVec3::X * a, DVec3::Y * a, DVec3::Z * a).unwrap();
                objects.push(Object::new(Box::new(heart), material(0.2), "HEART", 1));
            }
        }
        for (c, r) in [
            (DVec3::new(1.0, 0.3, 0.2), 0.4),
            (DVec3::new(1.0, 0.3, 0.2), 0.4),
            (DVec3::new(0.5, -0.6, -0.5), 0.5),
        ] {
            let sphere = Sphere::new(c, r).unwrap();
            objects.push(Object::new(Box::new(sphere), material(0.9), "SPHERE", 1));
        }
        Scene {
            width: 37,
            height: 23,
            camera: Camera::new(DVec3::new(9.0, 0.5, 0.3), DVec3::ZERO, DVec3::Z, 32.0).unwrap(),
            background: DVec3::new(0.1, 0.2, 0.3),
            ambient: DVec3::splat(0.1),
            lights: vec![crate::lights::Light {
                position: DVec3::new(6.0, -3.0, 5.0),
                colour: DVec3::ONE,
                radius: 0.3,
                samples: 2,
            }],
            index: ObjectIndex::of(&objects),
            objects,
        }
    }

    #[test]
    fn a_groups_camera_rays_asking_its_listed_objects_find_what_the_index_finds() {
        let scene = crowded_in_view();
        assert!(scene.may_use_index());
        let setup = |spp| ShadeSetup {
            scene: &scene,
            camera: &scene.camera,
            spp,
            max_depth: 2,
            max_shadow_rays: None,
        };
        // The whole image, and a region whose columns start off the groups of the image.
        let regions = [
            Region::full(scene.width, scene.height),
            Region {
                x: 3,
                y: 2,
                width: 29,
                height: 15,
            },
        ];
        for region in regions {
            for (spp, alpha) in [(1, false), (2, true)] {
                let job = Job {
                    scene: &scene,
                    camera: &scene.camera,
                    full_width: scene.width,
                    full_height: scene.height,
                    region,
                    spp,
                    seed: 5,
                    alpha,
                    keep_image: true,
                };
                let whitted = Whitted::new(&setup(spp));
                // The lists are made and used, and some groups list several objects.
                let sampler = PixelSampler::new(&whitted, &job);
                let groups = sampler.groups.as_ref().expect("lists for an indexed scene");
                let listed = |row: usize| {
                    (0..region.width)
                        .step_by(LANES)
                        .map(|x| groups.of(row, x).map_or(0, <[u32]>::len))
                        .max()
                        .unwrap_or(0)
                };
                assert!((0..region.height as usize).any(|row| listed(row) >= 3));
                let pool = RenderPool::new(2).unwrap();
                let hooks = Hooks {
                    cancelled: &|| false,
                    tile_done: &|_| {},
                    band_done: &|_, _, _| {},
                    interactive: false,
                };
                let (listed, listed_rays) = run(&pool, &whitted, &job, &hooks).unwrap();
                let (traced, traced_rays) = run(&pool, &Traced(&whitted), &job, &hooks).unwrap();
                let (listed, traced) = (listed.unwrap(), traced.unwrap());
                assert_eq!(listed.pixels, traced.pixels, "{region:?} spp {spp}");
                assert_eq!(listed.alpha, traced.alpha);
                assert_eq!(listed_rays, traced_rays);
            }
        }
    }

    #[test]
    fn a_typed_surfaces_cells_leave_out_its_hole_and_change_no_pixel() {
        // A torus seen from above, a little off its axis, with shadows from a soft light and
        // a plane under it: the pixels through its hole see its clip sphere and its box but
        // none of its cells, and are answered untraced.
        let text = "SIZE 80 60\n\
            CAMERA (0.3, -0.4, 5) (0, 0, 0) (0, 1, 0) 40\n\
            BACKGROUND (0.2, 0.4, 0.6)\n\
            AMBIENT (0.1, 0.1, 0.1)\n\
            LIGHT (3, 4, 5) (1, 1, 1) 0.5 SAMPLES 4\n\
            IMPLICIT torus 1 0.3 (0.1, 0, 0) (0.9, 0.1, 0) (-0.1, 0.9, 0.2) (0, -0.2, 0.9) \
            (0.9, 0.5, 0.1) SPECULAR 0.4 40\n";
        let scene = crate::scene::parse(text, "torus", &Default::default()).unwrap();
        let job = Job {
            scene: &scene,
            camera: &scene.camera,
            full_width: scene.width,
            full_height: scene.height,
            region: Region::full(scene.width, scene.height),
            spp: 1,
            seed: 0,
            alpha: false,
            keep_image: true,
        };
        let mask = seen_mask(&job).expect("the box is in front of the eye");
        assert!(!mask.any(29, 38, 4), "the hole is left out: {mask:?}");
        assert!(
            mask.any(29, 14, 4) && mask.any(29, 62, 4),
            "the tube is seen: {mask:?}"
        );
        for spp in [1, 3] {
            let setup = ShadeSetup {
                scene: &scene,
                camera: &scene.camera,
                spp,
                max_depth: 2,
                max_shadow_rays: None,
            };
            let whitted = Whitted::new(&setup);
            let normals = crate::integrator::normals::Normals::new(&setup);
            let depth = crate::integrator::depth::Depth::new(&setup);
            for alpha in [false, true] {
                assert_culling_changes_nothing(&scene, &whitted, spp, alpha);
                assert_culling_changes_nothing(&scene, &normals, spp, alpha);
                assert_culling_changes_nothing(&scene, &depth, spp, alpha);
            }
        }
    }

    #[test]
    fn coverage_is_the_fraction_of_samples_that_hit() {
        let mut scene = unit_sphere_scene();
        scene.background = DVec3::new(0.2, 0.4, 0.6);
        scene.ambient = DVec3::ONE;
        let setup = ShadeSetup {
            scene: &scene,
            camera: &scene.camera,
            spp: 16,
            max_depth: 0,
            max_shadow_rays: None,
        };
        let whitted = Whitted::new(&setup);
        let opaque = render(&scene, &whitted, 16, false);
        assert_eq!(opaque.alpha, None);
        let image = render(&scene, &whitted, 16, true);
        let alpha = image.alpha.clone().unwrap();
        assert_eq!(
            image.alpha_at(0, 0),
            0.0,
            "a corner sees only the background"
        );
        assert_eq!(image.get(0, 0), DVec3::ZERO, "and keeps none of its colour");
        assert_eq!(
            opaque.get(0, 0),
            DVec3::new(0.2, 0.4, 0.6).as_vec3().as_dvec3()
        );
        assert_eq!(image.alpha_at(4, 4), 1.0, "the sphere covers the centre");
        assert_eq!(
            image.get(4, 4),
            opaque.get(4, 4),
            "a covered pixel keeps its colour"
        );
        let edges: Vec<f32> = alpha
            .iter()
            .copied()
            .filter(|a| *a > 0.0 && *a < 1.0)
            .collect();
        assert!(!edges.is_empty(), "the silhouette is partly covered");
        for a in &alpha {
            assert_eq!((a * 16.0).fract(), 0.0, "a multiple of 1/16: {a}");
        }
        // A shader that does not report its hits gets the same coverage (found again).
        let silent = render(&scene, &Silent, 16, true);
        assert_eq!(silent.alpha, image.alpha);
        for (p, a) in silent.pixels.iter().zip(&alpha) {
            assert_eq!(*p, Vec3::splat(*a), "white premultiplied by its coverage");
        }
    }

    #[test]
    fn both_copies_of_the_tile_render_the_same_bits() {
        // The tile's body compiled for AVX2 (where this processor has it) and for the baseline
        // (what a processor without AVX2 runs of it; the scene's queries it calls choose their
        // own copies at run time, and their tests check both), on shipped scenes of every kind
        // of object and shader path (the opaque lanes, glass through one ray at a time, the
        // culling mask), with and without alpha: every stored pixel the same bits.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut traced = 0;
        for name in [
            "heart.scene",
            "glass_heart.scene",
            "menagerie.scene",
            "implicit/torus.scene",
            "implicit/barth_sextic.scene",
        ] {
            let text = std::fs::read_to_string(root.join(name)).unwrap();
            let mut scene =
                crate::scene::parse(&text, name, &crate::scene::LoadOptions::default()).unwrap();
            (scene.width, scene.height) = (41, 29);
            for (spp, alpha) in [(1, false), (2, true)] {
                let setup = ShadeSetup {
                    scene: &scene,
                    camera: &scene.camera,
                    spp,
                    max_depth: 2,
                    max_shadow_rays: None,
                };
                let whitted = Whitted::new(&setup);
                let job = Job {
                    scene: &scene,
                    camera: &scene.camera,
                    full_width: scene.width,
                    full_height: scene.height,
                    region: Region::full(scene.width, scene.height),
                    spp,
                    seed: 5,
                    alpha,
                    keep_image: true,
                };
                let sampler = PixelSampler::new(&whitted, &job);
                let len = (scene.width * scene.height) as usize;
                let render = |avx2: bool| {
                    let mut pixels = vec![Vec3::ZERO; len];
                    let mut alphas = vec![0.0f32; len];
                    let mut band = Band {
                        pixels: &mut pixels,
                        alpha: alpha.then_some(&mut alphas[..]),
                    };
                    let (xs, ys) = ((0, scene.width), (0, scene.height));
                    let region = job.region;
                    let (rays, done) = if avx2 {
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: asked only where the processor has AVX2 (below).
                        unsafe {
                            sampler.tile_avx2(&whitted, region, xs, ys, &mut band, &|| false)
                        }
                        #[cfg(not(target_arch = "x86_64"))]
                        unreachable!()
                    } else {
                        sampler.tile_in(&whitted, region, xs, ys, &mut band, &|| false)
                    };
                    assert!(done);
                    let bits: Vec<u32> = pixels
                        .iter()
                        .flat_map(|p| p.to_array())
                        .chain(alphas)
                        .map(f32::to_bits)
                        .collect();
                    (bits, rays)
                };
                let (baseline, rays) = render(false);
                traced += rays;
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    assert_eq!(
                        render(true),
                        (baseline, rays),
                        "{name} spp {spp} alpha {alpha}"
                    );
                }
            }
        }
        assert!(traced > 5_000, "{traced}");
    }
}
