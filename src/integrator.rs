//! The Whitted integrator: shading, shadows, reflection, refraction, supersampling, tiles.
//!
//! # Shading model
//! At a hit point with material `m`, unit normal `n` turned toward the incoming ray
//! (surfaces are two-sided) and diffuse colour `c` (`m.diffuse_at(p)`, or `m.inside` on the
//! back side when set), the colour is
//!
//! ```text
//! ambient·c + Σ_lights colour·V·(c·max(0, n·l) + ks·max(0, n·h)^shininess)
//!           + kr'·trace(reflected) + kt'·trace(refracted)
//! ```
//!
//! with `h` the Blinn half vector and `V` the light's visibility along a shadow ray:
//! 1 when unobstructed, 0 behind an opaque object, and behind transmissive objects the
//! product of `kt` for every surface crossed and of `exp(−attenuation·length)` for every
//! stretch travelled inside (so glass tints and dims shadows instead of blocking them).
//! Shadow rays go straight (no refraction).
//!
//! `kr' = kr + kt·F` and `kt' = kt·(1 − F)`, where `F` is the exact unpolarised Fresnel
//! reflectance of the interface (0 when `ior = 1`); under total internal reflection
//! `kr' = kr + kt` and `kt' = 0`. So `kt` is the weight of the dielectric interface as a
//! whole and `kr` an extra mirror weight. Whether a ray enters or leaves an object is decided
//! by the geometric normal: a hit on the back side is a ray leaving the object, and the whole
//! colour found there is dimmed by Beer–Lambert absorption `exp(−attenuation·d)` over the
//! distance `d` travelled inside. Recursion stops at [`RenderSettings::max_depth`].
//!
//! A spherical light is sampled on the disc through its centre facing the shaded point;
//! the pixel's samples take the disc's strata in a per-pixel rotated order, so soft shadows
//! smooth out as `spp` grows and stay deterministic for a seed.
//!
//! # Self-intersection
//! A secondary ray starts on a surface; it ignores hits closer than [`SELF_HIT_EPS`] times
//! the scale of the numbers that located its origin (the largest coordinate of the hit point
//! and of the incoming ray's origin, and the incoming segment's length). The guard thus
//! follows the scene's scale: a heart 10⁻³ across and one 10³ across are treated alike.

use crate::film::Image;
use crate::geometry::{DVec3, Ray};
use crate::lights::Light;
use crate::scene::Scene;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Relative self-intersection guard for secondary and shadow rays (see the module docs).
pub const SELF_HIT_EPS: f64 = 1e-9;

/// Side of the square image tiles, in pixels; each band of tiles one `TILE_SIZE` tall is one
/// unit of parallel work, rendered straight into its rows of the image.
pub const TILE_SIZE: u32 = 16;

/// Most surfaces a shadow ray passes through before the light counts as blocked.
pub const MAX_SHADOW_CROSSINGS: u32 = 64;

/// How to render: everything not in the scene text.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel (≥ 1; 0 is treated as 1), stratified and jittered.
    pub spp: u32,
    /// Maximum recursion depth for reflection and refraction (0 = primary hits only).
    pub max_depth: u32,
    /// Seed for the jitter and light sampling; the same seed gives the same image, whatever
    /// the thread count.
    pub seed: u64,
    /// Worker threads; 0 means one per available core.
    pub threads: usize,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            spp: 4,
            max_depth: 8,
            seed: 0,
            threads: 0,
        }
    }
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

/// Renders the scene to a linear-RGB image.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Image {
    render_with_progress(scene, settings, &|_| {}).0
}

/// Renders the scene, calling `progress(n)` from worker threads each time `n` more pixels
/// are finished (once per tile); returns the image and what it cost.
pub fn render_with_progress(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Image, RenderStats) {
    render_in_bands(scene, settings, progress, &|_, _| {})
}

/// [`render_with_progress`], also handing each finished band of rows to `band_done(first_row,
/// rows)` from the worker thread that rendered it (`rows`: whole rows of the image, top to
/// bottom, [`TILE_SIZE`] of them except at the bottom edge). Bands are taken in order from
/// the top, so they finish in nearly ascending order, each exactly once. Lets a caller
/// consume the image while the rest is being rendered (e.g. encode it).
pub fn render_in_bands(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
    band_done: &(dyn Fn(u32, &[Vec3]) + Sync),
) -> (Image, RenderStats) {
    let start = Instant::now();
    let (width, height) = (scene.width.max(1), scene.height.max(1));
    let tracer = Tracer::new(scene, settings);
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
            let tile = Tile {
                x0,
                y0,
                x1: (x0 + TILE_SIZE).min(width),
                y1,
            };
            band_rays += tracer.render_tile(&tile, width, height, &mut out);
            progress(((tile.x1 - tile.x0) * (y1 - y0)) as u64);
        }
        rays.fetch_add(band_rays, Ordering::Relaxed);
        band_done(y0, &out);
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build();
    let threads = match pool {
        Ok(pool) => {
            let threads = pool.current_num_threads();
            pool.broadcast(|_| worker());
            threads
        }
        Err(_) => {
            worker();
            1
        }
    };
    drop(bands);
    let stats = RenderStats {
        rays: rays.into_inner(),
        elapsed: start.elapsed(),
        threads,
    };
    (image, stats)
}

/// The colour seen along one world ray (which starts off any surface), shaded as in a
/// render with these settings; a spherical light is sampled once, at a point drawn from the
/// seed. Meant for tests and probes.
pub fn trace_ray(scene: &Scene, settings: &RenderSettings, ray: &Ray) -> DVec3 {
    let tracer = Tracer::new(scene, settings);
    let mut state = SampleState::new(settings.seed, 0, 1);
    tracer.radiance(ray, 0.0, 0, &mut state)
}

/// The strata grid `(columns, rows)` used for `spp` samples: `columns·rows = spp` with
/// `columns ≤ rows` as close as possible (a prime `spp` gives one column of `spp` strips).
pub fn strata(spp: u32) -> (u32, u32) {
    let n = spp.max(1);
    let mut cols = (n as f64).sqrt() as u32;
    while cols > 1 && !n.is_multiple_of(cols) {
        cols -= 1;
    }
    let cols = cols.max(1);
    (cols, n / cols)
}

/// The position of sample `i` of `spp` inside a unit pixel, given two uniform numbers in
/// `[0, 1)`: a jittered point of stratum `i` of the [`strata`] grid (row-major).
pub fn stratified_point(i: u32, spp: u32, u: f64, v: f64) -> (f64, f64) {
    point_in_grid(i, strata(spp), u, v)
}

/// [`stratified_point`] with the [`strata`] grid `(cols, rows)` already computed.
#[inline]
fn point_in_grid(i: u32, (cols, rows): (u32, u32), u: f64, v: f64) -> (f64, f64) {
    let i = i % (cols * rows);
    (
        ((i % cols) as f64 + u) / cols as f64,
        ((i / cols) as f64 + v) / rows as f64,
    )
}

/// A rectangle of pixels `[x0, x1) × [y0, y1)`.
#[derive(Debug, Clone, Copy)]
struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// splitmix64: a strong 64-bit mixer used to derive per-pixel seeds.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Per-sample state threaded through the recursion: random numbers, the sample's stratum
/// for light sampling, and the ray counter (a plain integer: one per tile, no atomics).
struct SampleState {
    rng: rand_pcg::Pcg64Mcg,
    /// Key of the pixel, to derive each light's stratum rotation.
    key: u64,
    /// Index of the current sample within the pixel.
    index: u32,
    /// Samples per pixel.
    count: u32,
    rays: u64,
}

impl SampleState {
    fn new(key: u64, index: u32, count: u32) -> Self {
        Self {
            rng: rand_pcg::Pcg64Mcg::seed_from_u64(key),
            key,
            index,
            count: count.max(1),
            rays: 0,
        }
    }

    fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// A jittered point of the unit square for shadow ray `ray` of `rays` that this sample
    /// sends to light `light`: the pixel's `count·rays` strata (laid out as `grid`, the
    /// [`strata`] of that number) are each taken once, in an order rotated per pixel and light.
    fn light_point(
        &mut self,
        light: usize,
        (ray, rays): (u32, u32),
        grid: (u32, u32),
    ) -> (f64, f64) {
        let rotation = mix(self.key ^ (light as u64).wrapping_mul(0xa076_1d64_78bd_642f));
        let strata = self.count as u64 * rays as u64;
        let index = self.index as u64 * rays as u64 + ray as u64;
        let stratum = ((index + rotation) % strata) as u32;
        let (u, v) = (self.uniform(), self.uniform());
        point_in_grid(stratum, grid, u, v)
    }
}

/// Maps the unit square onto the unit disc keeping strata compact (Shirley–Chiu).
fn concentric_disc(u: f64, v: f64) -> (f64, f64) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let quarter = std::f64::consts::FRAC_PI_4;
    let (r, phi) = if a.abs() > b.abs() {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    (r * phi.cos(), r * phi.sin())
}

/// Two unit vectors completing the unit `w` to an orthonormal basis (Duff et al. 2017).
fn basis(w: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(w.z);
    let a = -1.0 / (sign + w.z);
    let b = w.x * w.y * a;
    (
        DVec3::new(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x),
        DVec3::new(b, sign + w.y * w.y * a, -w.y),
    )
}

/// `SELF_HIT_EPS` scaled to the numbers that produced a point (see the module docs).
#[inline]
fn guard(point: DVec3, origin: DVec3, travelled: f64) -> f64 {
    let scale = point
        .abs()
        .max_element()
        .max(origin.abs().max_element())
        .max(travelled);
    (SELF_HIT_EPS * scale).max(f64::MIN_POSITIVE)
}

/// Direction of the ray through an interface by Snell's law, `d` unit and `n` the unit
/// normal on the incoming side (`d·n < 0`), `eta = n_incoming / n_outgoing`; `None` under
/// total internal reflection.
fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<(DVec3, f64)> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(((eta * d + (eta * cos_i - cos_t) * n).normalize(), cos_t))
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface for the given cosines
/// and `eta = n_incoming / n_outgoing`.
fn fresnel(cos_i: f64, cos_t: f64, eta: f64) -> f64 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0)
}

/// `exp(−a·d)` per channel; exactly 1 when there is no absorption.
#[inline]
fn beer_lambert(attenuation: DVec3, distance: f64) -> DVec3 {
    if attenuation == DVec3::ZERO {
        DVec3::ONE
    } else {
        (-attenuation * distance).exp()
    }
}

/// Everything fixed for one render.
struct Tracer<'a> {
    scene: &'a Scene,
    spp: u32,
    /// The [`strata`] of `spp`: where a pixel's samples go.
    pixel_grid: (u32, u32),
    /// Per light: its shadow rays per pixel sample and the [`strata`] of `spp` times that.
    light_grids: Vec<(u32, (u32, u32))>,
    max_depth: u32,
    seed: u64,
}

impl<'a> Tracer<'a> {
    fn new(scene: &'a Scene, settings: &RenderSettings) -> Self {
        let spp = settings.spp.max(1);
        let light_grids = scene
            .lights
            .iter()
            .map(|light| {
                let rays = if light.radius > 0.0 {
                    light.samples.max(1)
                } else {
                    1
                };
                (rays, strata(spp.saturating_mul(rays)))
            })
            .collect();
        Self {
            scene,
            spp,
            pixel_grid: strata(spp),
            light_grids,
            max_depth: settings.max_depth,
            seed: mix(settings.seed),
        }
    }

    /// Renders `tile` into `band`, the image rows from `tile.y0` on (full width), each pixel's
    /// `f64` mean rounded to `f32`; returns the rays traced.
    fn render_tile(&self, tile: &Tile, width: u32, height: u32, band: &mut [Vec3]) -> u64 {
        let mut rays = 0;
        let inv = 1.0 / self.spp as f64;
        for y in tile.y0..tile.y1 {
            for x in tile.x0..tile.x1 {
                let key = mix(self.seed ^ mix((y as u64) << 32 | x as u64));
                let mut state = SampleState::new(key, 0, self.spp);
                let mut sum = DVec3::ZERO;
                for i in 0..self.spp {
                    state.index = i;
                    let (u, v) = (state.uniform(), state.uniform());
                    let (dx, dy) = point_in_grid(i, self.pixel_grid, u, v);
                    let ray = self
                        .scene
                        .camera
                        .ray(x as f64 + dx, y as f64 + dy, width, height);
                    sum += self.radiance(&ray, 0.0, 0, &mut state);
                }
                rays += state.rays;
                band[((y - tile.y0) * width + x) as usize] = (sum * inv).as_vec3();
            }
        }
        rays
    }

    /// The colour arriving along `ray` from its first hit beyond `t_min`.
    fn radiance(&self, ray: &Ray, t_min: f64, depth: u32, s: &mut SampleState) -> DVec3 {
        s.rays += 1;
        let scene = self.scene;
        let Some(hit) = scene.intersect(ray, t_min, f64::INFINITY) else {
            return scene.background;
        };
        let m = &scene.objects[hit.object].material;
        let dir_len = ray.dir.length();
        let d = ray.dir / dir_len;
        let travelled = hit.t * dir_len;
        let p = hit.point;
        let front = hit.normal.dot(d) < 0.0;
        let n = if front { hit.normal } else { -hit.normal };
        let eps = guard(p, ray.origin, travelled);

        let base = match (front, m.inside) {
            (false, Some(inside)) => inside,
            _ => m.diffuse_at(p),
        };
        let mut colour = scene.ambient * base;
        for (index, light) in scene.lights.iter().enumerate() {
            let (rays, grid) = self.light_grids[index];
            let mut lit = DVec3::ZERO;
            for ray in 0..rays {
                let target = self.light_sample(light, index, (ray, rays), grid, p, s);
                let to_light = target - p;
                let dist = to_light.length();
                if dist <= eps {
                    continue;
                }
                let l = to_light / dist;
                let n_dot_l = n.dot(l);
                if n_dot_l <= 0.0 {
                    continue;
                }
                let visibility = self.transmittance(p, l, eps, dist, s);
                if visibility == DVec3::ZERO {
                    continue;
                }
                let mut f = base * n_dot_l;
                if m.specular > 0.0 {
                    let h = (l - d).normalize_or_zero();
                    f += DVec3::splat(m.specular * n.dot(h).max(0.0).powf(m.shininess));
                }
                lit += visibility * f;
            }
            colour += light.colour * lit / rays as f64;
        }

        if depth < self.max_depth {
            let mut kr = m.reflect;
            let mut kt = 0.0;
            let mut refracted = None;
            if m.transmit > 0.0 {
                let eta = if front { 1.0 / m.ior } else { m.ior };
                match refract(d, n, eta) {
                    Some((t_dir, cos_t)) => {
                        let f = fresnel(-d.dot(n), cos_t, eta);
                        kr += m.transmit * f;
                        kt = m.transmit * (1.0 - f);
                        refracted = Some(t_dir);
                    }
                    None => kr += m.transmit,
                }
            }
            if kr > 0.0 {
                let r = d - 2.0 * d.dot(n) * n;
                colour += kr * self.radiance(&Ray::new(p, r), eps, depth + 1, s);
            }
            if let (Some(t_dir), true) = (refracted, kt > 0.0) {
                colour += kt * self.radiance(&Ray::new(p, t_dir), eps, depth + 1, s);
            }
        }

        if !front {
            // The ray travelled inside this object to reach its back side.
            colour *= beer_lambert(m.attenuation, travelled);
        }
        colour
    }

    /// The point of `light` (number `index` in the scene) that shadow ray `ray` of `rays`
    /// from `p` aims at: the centre of a point light, a stratified point of the disc facing
    /// `p` for a spherical one (`grid`: the light's strata, see [`Tracer::light_grids`]).
    fn light_sample(
        &self,
        light: &Light,
        index: usize,
        rays: (u32, u32),
        grid: (u32, u32),
        p: DVec3,
        s: &mut SampleState,
    ) -> DVec3 {
        if light.radius <= 0.0 {
            return light.position;
        }
        let w = (light.position - p).normalize_or_zero();
        if w == DVec3::ZERO {
            return light.position;
        }
        let (u, v) = s.light_point(index, rays, grid);
        let (a, b) = concentric_disc(u, v);
        let (e1, e2) = basis(w);
        light.position + light.radius * (a * e1 + b * e2)
    }

    /// The fraction of light (per channel) that reaches `p` along the unit direction `l`
    /// from `dist` away, through any transmissive surfaces on the way.
    fn transmittance(&self, p: DVec3, l: DVec3, eps: f64, dist: f64, s: &mut SampleState) -> DVec3 {
        let scene = self.scene;
        let mut through = DVec3::ONE;
        let mut origin = p;
        let mut t_min = eps;
        let mut remaining = dist;
        for _ in 0..MAX_SHADOW_CROSSINGS {
            s.rays += 1;
            let ray = Ray::new(origin, l);
            let Some(hit) = scene.intersect(&ray, t_min, remaining) else {
                return through;
            };
            let m = &scene.objects[hit.object].material;
            if m.transmit <= 0.0 {
                return DVec3::ZERO;
            }
            through *= m.transmit;
            if hit.normal.dot(l) > 0.0 {
                // Leaving the object: absorbed along the stretch inside.
                through *= beer_lambert(m.attenuation, hit.t);
            }
            if through.max_element() <= 0.0 {
                return DVec3::ZERO;
            }
            t_min = guard(hit.point, origin, hit.t);
            origin = hit.point;
            remaining -= hit.t;
        }
        DVec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_factor_spp() {
        assert_eq!(strata(1), (1, 1));
        assert_eq!(strata(4), (2, 2));
        assert_eq!(strata(8), (2, 4));
        assert_eq!(strata(9), (3, 3));
        assert_eq!(strata(7), (1, 7));
        assert_eq!(strata(0), (1, 1));
    }

    #[test]
    fn stratified_points_fill_each_stratum_once() {
        for spp in [1, 2, 4, 6, 9, 16] {
            let (c, r) = strata(spp);
            let mut seen = vec![false; spp as usize];
            for i in 0..spp {
                let (x, y) = stratified_point(i, spp, 0.5, 0.5);
                let cell = (y * r as f64) as u32 * c + (x * c as f64) as u32;
                assert!(!seen[cell as usize]);
                seen[cell as usize] = true;
            }
        }
    }

    #[test]
    fn disc_and_basis() {
        for (u, v) in [(0.0, 0.0), (0.99, 0.5), (0.3, 0.8), (0.5, 0.5)] {
            let (a, b) = concentric_disc(u, v);
            assert!(a * a + b * b <= 1.0 + 1e-12);
        }
        for w in [DVec3::Z, -DVec3::Z, DVec3::new(1.0, 2.0, -3.0).normalize()] {
            let (e1, e2) = basis(w);
            assert!(e1.dot(w).abs() < 1e-12 && e2.dot(w).abs() < 1e-12);
            assert!(e1.dot(e2).abs() < 1e-12);
            assert!((e1.length() - 1.0).abs() < 1e-12 && (e2.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn snell_and_fresnel() {
        let n = DVec3::Z;
        let d = DVec3::new(1.0, 0.0, -1.0).normalize();
        let (t, cos_t) = refract(d, n, 1.0 / 1.5).unwrap();
        let sin_i = d.x;
        let sin_t = t.x;
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-12);
        assert!((cos_t + t.z).abs() < 1e-12);
        // Leaving glass at 45° exceeds the critical angle (41.8°).
        assert!(refract(d, n, 1.5).is_none());
        // Normal incidence: ((n1 − n2)/(n1 + n2))².
        assert!((fresnel(1.0, 1.0, 1.0 / 1.5) - 0.04).abs() < 1e-12);
        assert_eq!(fresnel(0.3, 0.3, 1.0), 0.0);
    }

    #[test]
    fn bands_are_handed_over_once_each_and_match_the_image() {
        let mut scene = crate::scene::parse(
            crate::scene::DEFAULT_SCENE,
            "heart.scene",
            &crate::scene::LoadOptions::default(),
        )
        .unwrap();
        (scene.width, scene.height) = (40, 37); // the last band is short
        let settings = RenderSettings {
            threads: 2,
            ..RenderSettings::default()
        };
        let seen = Mutex::new(Vec::new());
        let (image, stats) = render_in_bands(&scene, &settings, &|_| {}, &|row, rows| {
            seen.lock().unwrap().push((row, rows.to_vec()));
        });
        let mut seen = seen.into_inner().unwrap();
        seen.sort_by_key(|(row, _)| *row);
        let rows: Vec<u32> = seen.iter().map(|(row, _)| *row).collect();
        assert_eq!(rows, vec![0, 16, 32]);
        let handed: Vec<Vec3> = seen.into_iter().flat_map(|(_, px)| px).collect();
        assert_eq!(handed, image.pixels);
        assert_eq!(image, render(&scene, &settings));
        assert!(stats.rays >= 40 * 37);
    }

    #[test]
    fn guard_scales_with_the_scene() {
        let small = guard(DVec3::splat(1e-3), DVec3::splat(2e-3), 1e-3);
        let big = guard(DVec3::splat(1e3), DVec3::splat(2e3), 1e3);
        assert!((big / small - 1e6).abs() < 1e-3);
        assert!(guard(DVec3::ZERO, DVec3::ZERO, 0.0) > 0.0);
    }
}
