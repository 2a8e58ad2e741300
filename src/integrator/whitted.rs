//! Whitted shading, the [`View::Shaded`](super::View::Shaded) view: direct light with shadows,
//! mirror reflection and refraction.
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
//! distance `d` travelled inside. Recursion stops at the
//! render's `max_depth`.
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

use super::sampling::{basis, concentric_disc, strata, Sample};
use super::{ShadeSetup, Shader};
use crate::geometry::{DVec3, Ray};
use crate::lights::Light;
use crate::materials::Material;
use crate::scene::{Scene, SceneHit};
use crate::shapes::LANES;

/// Relative self-intersection guard for secondary and shadow rays (see the module docs).
pub const SELF_HIT_EPS: f64 = 1e-9;

/// Most surfaces a shadow ray passes through before the light counts as blocked.
pub const MAX_SHADOW_CROSSINGS: u32 = 64;

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

/// What shading needs of a hit point (see [`Whitted::surface`]).
#[derive(Debug, Clone, Copy)]
struct SurfacePoint<'a> {
    /// The material of the object hit.
    m: &'a Material,
    /// The unit direction of the ray that arrived.
    d: DVec3,
    /// How far the ray travelled, in world units.
    travelled: f64,
    /// The hit point.
    p: DVec3,
    /// Whether the ray arrived on the outer side.
    front: bool,
    /// The unit normal on the side the ray arrived from.
    n: DVec3,
    /// The parameter below which a ray leaving `p` would re-hit it (see [`guard`]).
    eps: f64,
    /// The diffuse colour there.
    base: DVec3,
}

impl SurfacePoint<'_> {
    /// The unit direction towards a light point `target` and its distance, or `None` when
    /// the light cannot reach the side the ray arrived on (or sits at the point).
    #[inline]
    fn towards(&self, target: DVec3) -> Option<(DVec3, f64)> {
        let to_light = target - self.p;
        let dist = to_light.length();
        if dist <= self.eps {
            return None;
        }
        let l = to_light / dist;
        if self.n.dot(l) <= 0.0 {
            return None;
        }
        Some((l, dist))
    }

    /// The light a unit of light from the direction `l` leaves towards the eye (diffuse and
    /// highlight).
    #[inline]
    fn reflected_light(&self, l: DVec3) -> DVec3 {
        let mut f = self.base * self.n.dot(l);
        if self.m.specular > 0.0 {
            let h = (l - self.d).normalize_or_zero();
            f +=
                DVec3::splat(self.m.specular * highlight(self.n.dot(h).max(0.0), self.m.shininess));
        }
        f
    }
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

/// `cosine^shininess` (`cosine ∈ [0, 1]`): by repeated squaring for the usual whole-number
/// exponents (a few multiplications, relatively within `shininess` ulps of `powf`, a library
/// call of about a hundred instructions), else `powf`.
#[inline]
fn highlight(cosine: f64, shininess: f64) -> f64 {
    if (0.0..=1024.0).contains(&shininess) && shininess.fract() == 0.0 {
        // `powi` with an exponent known only at run time is a library call (`__powidf2`);
        // this is its loop, inlined: the same multiplications in the same order, the same
        // bits.
        let mut n = shininess as u32;
        let mut base = cosine;
        let mut power = if n % 2 == 1 { base } else { 1.0 };
        n /= 2;
        while n > 0 {
            base *= base;
            if n % 2 == 1 {
                power *= base;
            }
            n /= 2;
        }
        power
    } else {
        cosine.powf(shininess)
    }
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

/// Whitted shading of one scene, fixed for one render.
pub struct Whitted<'a> {
    scene: &'a Scene,
    /// Per light: its shadow rays per pixel sample and the [`strata`] of `spp` times that.
    light_grids: Vec<(u32, (u32, u32))>,
    max_depth: u32,
    /// No object transmits light: a shadow ray is blocked by any hit at all.
    opaque: bool,
}

impl Shader for Whitted<'_> {
    fn miss_colour(&self) -> Option<DVec3> {
        // `trace` counts the ray, and `shade` reports the miss and returns the background.
        Some(self.scene.background)
    }

    fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3 {
        self.trace(ray, 0.0, 0, sample)
    }

    #[inline(always)]
    fn radiance_lanes(&self, rays: &[Ray; LANES], samples: &mut [Sample; LANES]) -> [DVec3; LANES] {
        // The camera rays' first hits together (the shapes may share work across lanes),
        // then each lane shaded as `trace` shades it.
        let hits = self.scene.intersect_lanes(rays, 0.0, f64::INFINITY);
        self.shade_camera_lanes(rays, hits, samples)
    }

    #[inline(always)]
    fn radiance_lanes_among(
        &self,
        rays: &[Ray; LANES],
        samples: &mut [Sample; LANES],
        objects: &[u32],
    ) -> [DVec3; LANES] {
        // The same hits as `intersect_lanes` finds, asking only the objects the rays may meet.
        let hits = self
            .scene
            .intersect_lanes_among(rays, 0.0, f64::INFINITY, objects);
        self.shade_camera_lanes(rays, hits, samples)
    }
}

impl<'a> Whitted<'a> {
    /// The colours of camera rays `rays` from their first hits `hits` (each counted here).
    #[inline(always)]
    fn shade_camera_lanes(
        &self,
        rays: &[Ray; LANES],
        hits: [Option<SceneHit>; LANES],
        samples: &mut [Sample; LANES],
    ) -> [DVec3; LANES] {
        for sample in samples.iter_mut() {
            sample.count_ray();
        }
        if self.opaque {
            return self.shade_lanes(rays, hits, samples);
        }
        let mut out = [DVec3::ZERO; LANES];
        for (lane, sample) in samples.iter_mut().enumerate() {
            out[lane] = self.shade(&rays[lane], hits[lane], 0, sample);
        }
        out
    }

    /// The shader of `setup.scene` for `setup.spp` samples a pixel (which fixes the strata
    /// of spherical lights) and recursion to `setup.max_depth`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        let spp = setup.spp.max(1);
        let light_grids = setup
            .scene
            .lights
            .iter()
            .map(|light| {
                let rays = if light.radius > 0.0 {
                    light
                        .samples
                        .min(setup.max_shadow_rays.unwrap_or(u32::MAX))
                        .max(1)
                } else {
                    1
                };
                (rays, strata(spp.saturating_mul(rays)))
            })
            .collect();
        Self {
            scene: setup.scene,
            light_grids,
            max_depth: setup.max_depth,
            opaque: setup
                .scene
                .objects
                .iter()
                .all(|o| o.material.transmit <= 0.0),
        }
    }

    /// The colour arriving along `ray` from its first hit beyond `t_min`.
    fn trace(&self, ray: &Ray, t_min: f64, depth: u32, s: &mut Sample) -> DVec3 {
        s.count_ray();
        let hit = self.scene.intersect(ray, t_min, f64::INFINITY);
        self.shade(ray, hit, depth, s)
    }

    /// The colour `trace` returns for `ray`, given its first hit `hit` (already counted).
    #[inline]
    fn shade(&self, ray: &Ray, hit: Option<SceneHit>, depth: u32, s: &mut Sample) -> DVec3 {
        let scene = self.scene;
        if depth == 0 {
            s.report_primary_hit(hit.is_some());
        }
        let Some(hit) = hit else {
            return scene.background;
        };
        let at = self.surface(ray, &hit);
        let mut colour = scene.ambient * at.base;
        for (index, light) in scene.lights.iter().enumerate() {
            let (rays, grid) = self.light_grids[index];
            let mut lit = DVec3::ZERO;
            for ray in 0..rays {
                let target = self.light_sample(light, index, (ray, rays), grid, at.p, s);
                let Some((l, dist)) = at.towards(target) else {
                    continue;
                };
                let visibility = self.transmittance(at.p, l, at.eps, dist, s);
                if visibility == DVec3::ZERO {
                    continue;
                }
                lit += visibility * at.reflected_light(l);
            }
            colour += light.colour * lit / rays as f64;
        }
        self.finish(&at, colour, depth, s)
    }

    /// [`Whitted::shade`] at depth 0 for each lane, the shadow rays of the lanes' hits asked
    /// together ([`Scene::occluded_lanes_from`] the first lane's object), for an opaque scene (where a shadow ray is an
    /// any-hit query). Every lane draws its random numbers in the order `shade` draws them
    /// (all lanes walk the same lights and light samples), so the colours are the same.
    #[inline(always)]
    fn shade_lanes(
        &self,
        rays: &[Ray; LANES],
        hits: [Option<SceneHit>; LANES],
        samples: &mut [Sample; LANES],
    ) -> [DVec3; LANES] {
        let scene = self.scene;
        let mut points: [Option<SurfacePoint>; LANES] = [None; LANES];
        let mut colours = [scene.background; LANES];
        for lane in 0..LANES {
            samples[lane].report_primary_hit(hits[lane].is_some());
            if let Some(hit) = &hits[lane] {
                let at = self.surface(&rays[lane], hit);
                colours[lane] = scene.ambient * at.base;
                points[lane] = Some(at);
            }
        }
        // The object of the first lane's hit, where the shadow rays' walk starts.
        let Some(from) = hits.iter().flatten().map(|hit| hit.object).next() else {
            // Every lane saw the background: no light to walk, no random number drawn.
            return colours;
        };
        for (index, light) in scene.lights.iter().enumerate() {
            let (count, grid) = self.light_grids[index];
            let mut lit = [DVec3::ZERO; LANES];
            for ray in 0..count {
                let mut shadow = [Ray::new(DVec3::ZERO, DVec3::Z); LANES];
                let (mut near, mut far) = ([0.0; LANES], [f64::NEG_INFINITY; LANES]);
                let mut asked = [false; LANES];
                for lane in 0..LANES {
                    let Some(at) = &points[lane] else {
                        continue;
                    };
                    let target = self.light_sample(
                        light,
                        index,
                        (ray, count),
                        grid,
                        at.p,
                        &mut samples[lane],
                    );
                    if let Some((l, dist)) = at.towards(target) {
                        samples[lane].count_ray();
                        shadow[lane] = Ray::new(at.p, l);
                        (near[lane], far[lane]) = (at.eps, dist);
                        asked[lane] = true;
                    }
                }
                let blocked = scene.occluded_lanes_from(&shadow, near, far, from);
                for lane in 0..LANES {
                    if let (Some(at), true, false) = (&points[lane], asked[lane], blocked[lane]) {
                        lit[lane] += DVec3::ONE * at.reflected_light(shadow[lane].dir);
                    }
                }
            }
            for lane in 0..LANES {
                if points[lane].is_some() {
                    colours[lane] += light.colour * lit[lane] / count as f64;
                }
            }
        }
        for lane in 0..LANES {
            if let Some(at) = &points[lane] {
                colours[lane] = self.finish(at, colours[lane], 0, &mut samples[lane]);
            }
        }
        colours
    }

    /// What shading needs of the hit `hit` of `ray`.
    #[inline(always)]
    fn surface(&self, ray: &Ray, hit: &SceneHit) -> SurfacePoint<'a> {
        let scene: &'a Scene = self.scene;
        let m = &scene.objects[hit.object].material;
        let dir_len = ray.dir.length();
        let d = ray.dir / dir_len;
        let travelled = hit.t * dir_len;
        let p = hit.point;
        let front = hit.normal.dot(d) < 0.0;
        let n = if front { hit.normal } else { -hit.normal };
        let base = match (front, m.inside) {
            (false, Some(inside)) => inside,
            _ => m.diffuse_at(p),
        };
        SurfacePoint {
            m,
            d,
            travelled,
            p,
            front,
            n,
            eps: guard(p, ray.origin, travelled),
            base,
        }
    }

    /// The colour of the surface point `at`, given `colour` from the lights: what its reflection and refraction add (below the maximum depth), attenuated
    /// on a back side.
    #[inline(always)]
    fn finish(&self, at: &SurfacePoint, mut colour: DVec3, depth: u32, s: &mut Sample) -> DVec3 {
        let SurfacePoint {
            m,
            d,
            travelled,
            p,
            front,
            n,
            eps,
            ..
        } = *at;
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
                colour += kr * self.trace(&Ray::new(p, r), eps, depth + 1, s);
            }
            if let (Some(t_dir), true) = (refracted, kt > 0.0) {
                colour += kt * self.trace(&Ray::new(p, t_dir), eps, depth + 1, s);
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
    /// `p` for a spherical one (`grid`: the light's strata, see `Whitted::light_grids`).
    fn light_sample(
        &self,
        light: &Light,
        index: usize,
        rays: (u32, u32),
        grid: (u32, u32),
        p: DVec3,
        s: &mut Sample,
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
    fn transmittance(&self, p: DVec3, l: DVec3, eps: f64, dist: f64, s: &mut Sample) -> DVec3 {
        let scene = self.scene;
        if self.opaque {
            // The walk below would stop at its first hit, whichever object: an any-hit query
            // gives the same answer without the nearest hit's normal.
            s.count_ray();
            return if scene.occluded(&Ray::new(p, l), eps, dist) {
                DVec3::ZERO
            } else {
                DVec3::ONE
            };
        }
        let mut through = DVec3::ONE;
        let mut origin = p;
        let mut t_min = eps;
        let mut remaining = dist;
        for _ in 0..MAX_SHADOW_CROSSINGS {
            s.count_ray();
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
    fn the_highlight_is_powi_bit_for_bit_for_whole_exponents() {
        let mut uniform = crate::testing::uniform_stream(0x05ee_d0f1_9417);
        for k in 0..20_000 {
            let cosine = if k % 7 == 0 {
                1.0 - 1e-9 * uniform()
            } else {
                uniform()
            };
            let shininess = f64::from(k % 1025);
            assert_eq!(
                highlight(cosine, shininess).to_bits(),
                cosine.powi(shininess as i32).to_bits(),
                "{cosine}^{shininess}"
            );
        }
        assert_eq!(highlight(0.0, 0.0), 1.0);
        assert_eq!(highlight(0.5, 2.5).to_bits(), 0.5f64.powf(2.5).to_bits());
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

    /// Scenes of the repository without transmissive objects: hearts, typed surfaces over a
    /// reflecting floor with a spherical light, every primitive.
    fn opaque_scenes() -> Vec<Scene> {
        [
            "hearts.scene",
            "menagerie.scene",
            "implicit/barth_sextic.scene",
            "implicit/chmutov.scene",
        ]
        .iter()
        .map(|name| {
            let path = format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
            crate::scene::parse_file(path.as_ref(), &Default::default()).unwrap()
        })
        .collect()
    }

    #[test]
    fn any_hit_shadows_give_the_walks_colours_exactly() {
        // The any-hit shadow query of an opaque scene against the crossing walk it replaces:
        // the same colour, bit for bit, for every pixel of a 32×24 image with reflections.
        let mut shadowed = 0;
        for scene in opaque_scenes() {
            let setup = ShadeSetup {
                max_depth: 3,
                ..crate::integrator::tests::one_sample_setup(&scene)
            };
            let any_hit = Whitted::new(&setup);
            assert!(any_hit.opaque);
            let walk = Whitted {
                opaque: false,
                ..Whitted::new(&setup)
            };
            let (w, h) = (32, 24);
            for y in 0..h {
                for x in 0..w {
                    let ray = scene.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
                    let key = (y * w + x) as u64;
                    let a = any_hit.radiance(&ray, &mut Sample::new(key, 0, 1));
                    let b = walk.radiance(&ray, &mut Sample::new(key, 0, 1));
                    assert_eq!(
                        a.to_array().map(f64::to_bits),
                        b.to_array().map(f64::to_bits)
                    );
                }
            }
            // Shadow rays toward each light from the surface points the camera sees: the
            // any-hit answer is the nearest-hit query's, and some are blocked.
            for y in 0..h {
                for x in 0..w {
                    let ray = scene.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
                    let Some(hit) = scene.intersect(&ray, 0.0, f64::INFINITY) else {
                        continue;
                    };
                    for light in &scene.lights {
                        let to_light = light.position - hit.point;
                        let dist = to_light.length();
                        let eps = guard(hit.point, ray.origin, hit.t * ray.dir.length());
                        let shadow = Ray::new(hit.point, to_light / dist);
                        let blocked = scene.intersect(&shadow, eps, dist).is_some();
                        assert_eq!(scene.occluded(&shadow, eps, dist), blocked);
                        shadowed += usize::from(blocked);
                    }
                }
            }
        }
        assert!(shadowed > 50, "{shadowed}");
    }

    #[test]
    fn the_highlight_is_powf_to_within_shininess_ulps() {
        // Repeated squaring's relative error grows with the exponent: measured below a third
        // of an ulp per unit of the exponent, far below the f32 film's resolution.
        for k in 0..=1024 {
            let shininess = f64::from(k);
            for i in 0..=1000 {
                let cosine = f64::from(i) / 1000.0;
                let (fast, exact) = (highlight(cosine, shininess), cosine.powf(shininess));
                let tolerance = (shininess + 1.0) * f64::EPSILON * exact + f64::MIN_POSITIVE;
                assert!((fast - exact).abs() <= tolerance, "{cosine}^{shininess}");
            }
        }
        // A fractional exponent is powf's own.
        assert_eq!(highlight(0.7, 12.5), 0.7f64.powf(12.5));
        assert_eq!(highlight(0.0, 0.0), 1.0);
    }

    #[test]
    fn guard_scales_with_the_scene() {
        let small = guard(DVec3::splat(1e-3), DVec3::splat(2e-3), 1e-3);
        let big = guard(DVec3::splat(1e3), DVec3::splat(2e3), 1e3);
        assert!((big / small - 1e6).abs() < 1e-3);
        assert!(guard(DVec3::ZERO, DVec3::ZERO, 0.0) > 0.0);
    }
}
