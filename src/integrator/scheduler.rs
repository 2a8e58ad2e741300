//! The scheduler: a region of the image cut into bands of [`TILE_SIZE`] rows (each rendered as
//! `TILE_SIZE`-square tiles), taken in order from a shared counter by the threads of a pool,
//! each written straight into its rows of the region's image; cancellation checked before every
//! tile, progress reported after every tile, finished bands handed to a hook.

use super::sampling::{mix, pixel_key, point_in_grid, strata, Sample};
use super::{Shader, TILE_SIZE};
use crate::camera::Camera;
use crate::film::{self, Image, Region, Vec3};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

/// What one render samples: the camera, the full image's size, the region of it to render,
/// the samples per pixel and the seed.
pub(crate) struct Job<'a> {
    pub camera: &'a Camera,
    pub full_width: u32,
    pub full_height: u32,
    /// Inside the full image (checked by the caller).
    pub region: Region,
    pub spp: u32,
    pub seed: u64,
}

/// The caller's side of a render, all called from worker threads.
pub(crate) struct Hooks<'a> {
    /// Asked before each tile; once it answers true, no more tiles are started.
    pub cancelled: &'a (dyn Fn() -> bool + Sync),
    /// Told how many pixels each finished tile held.
    pub tile_done: &'a (dyn Fn(u64) + Sync),
    /// Handed each finished band: its first row (in the region's image) and its pixels (whole
    /// rows of the region's image, [`TILE_SIZE`] of them except at the bottom edge). Bands are
    /// taken in order from the top, so they finish in nearly ascending order, each exactly
    /// once; never called for a band left unfinished by a cancellation.
    pub band_done: &'a (dyn Fn(u32, &[Vec3]) + Sync),
}

/// Renders `job.region` with `shader` on the threads of `pool`; returns the region's image and
/// the rays traced, or `None` when cancelled before every tile was done.
pub(crate) fn run<S: Shader>(
    pool: &rayon::ThreadPool,
    shader: &S,
    job: &Job,
    hooks: &Hooks,
) -> Option<(Image, u64)> {
    let region = job.region;
    let (width, height) = (region.width, region.height);
    let sampler = PixelSampler {
        camera: job.camera,
        full: (job.full_width, job.full_height),
        spp: job.spp.max(1),
        pixel_grid: strata(job.spp),
        seed: mix(job.seed),
    };
    let mut image = Image::new(width, height);
    // Each band of TILE_SIZE rows is a disjoint slice of the image, filled in place tile by
    // tile: no per-tile buffers, so the film exists once. Workers take the next band from a
    // shared counter: bands finish in order from the top, and a worker that runs out of work
    // waits for one band at most.
    let band_len = width as usize * TILE_SIZE as usize;
    let bands: Vec<Mutex<&mut [Vec3]>> =
        image.pixels.chunks_mut(band_len).map(Mutex::new).collect();
    let next_band = AtomicUsize::new(0);
    let rays = AtomicU64::new(0);
    let stopped = AtomicBool::new(false);
    let worker = || loop {
        let band = next_band.fetch_add(1, Ordering::Relaxed);
        let Some(slot) = bands.get(band) else {
            return;
        };
        // Each band is taken once, so its lock is never contended.
        let mut out = slot.lock().unwrap_or_else(|e| e.into_inner());
        let y0 = band as u32 * TILE_SIZE;
        let y1 = (y0 + TILE_SIZE).min(height);
        let mut band_rays = 0;
        for x0 in (0..width).step_by(TILE_SIZE as usize) {
            if (hooks.cancelled)() {
                stopped.store(true, Ordering::Relaxed);
                rays.fetch_add(band_rays, Ordering::Relaxed);
                return;
            }
            let x1 = (x0 + TILE_SIZE).min(width);
            band_rays += sampler.tile(shader, region, (x0, x1), (y0, y1), width, &mut out);
            (hooks.tile_done)(((x1 - x0) * (y1 - y0)) as u64);
        }
        rays.fetch_add(band_rays, Ordering::Relaxed);
        (hooks.band_done)(y0, &out);
    };
    pool.broadcast(|_| worker());
    drop(bands);
    if stopped.into_inner() {
        return None;
    }
    Some((image, rays.into_inner()))
}

/// Everything fixed for one render's pixels.
struct PixelSampler<'a> {
    camera: &'a Camera,
    /// The full image's size, which the camera spans.
    full: (u32, u32),
    spp: u32,
    /// The [`strata`] of `spp`: where a pixel's samples go.
    pixel_grid: (u32, u32),
    /// `mix(seed)`.
    seed: u64,
}

impl PixelSampler<'_> {
    /// Renders the tile of columns `xs` and rows `ys` of the region's image into `band`, the
    /// region's rows from `ys.0` on (`width` wide), each pixel's `f64` mean stored as the film
    /// stores it; returns the rays traced. Pixel `(x, y)` of the region is pixel
    /// `(region.x + x, region.y + y)` of the full image, and is sampled as that pixel.
    fn tile<S: Shader>(
        &self,
        shader: &S,
        region: Region,
        (x0, x1): (u32, u32),
        (y0, y1): (u32, u32),
        width: u32,
        band: &mut [Vec3],
    ) -> u64 {
        let mut rays = 0;
        let inv = 1.0 / self.spp as f64;
        let (full_w, full_h) = self.full;
        for y in y0..y1 {
            let image_y = region.y + y;
            for x in x0..x1 {
                let image_x = region.x + x;
                let mut state = Sample::new(pixel_key(self.seed, image_x, image_y), 0, self.spp);
                let mut sum = crate::geometry::DVec3::ZERO;
                for i in 0..self.spp {
                    state.index = i;
                    let (u, v) = (state.uniform(), state.uniform());
                    let (dx, dy) = point_in_grid(i, self.pixel_grid, u, v);
                    let ray =
                        self.camera
                            .ray(image_x as f64 + dx, image_y as f64 + dy, full_w, full_h);
                    sum += shader.radiance(&ray, &mut state);
                }
                rays += state.rays;
                band[((y - y0) * width + x) as usize] = film::to_stored(sum * inv);
            }
        }
        rays
    }
}
