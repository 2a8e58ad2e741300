//! Sampling: where a pixel's samples go (jittered strata), the per-pixel random streams, and
//! the strata of spherical lights.
//!
//! A pixel's samples depend only on the render's seed and the pixel's column and row in the
//! FULL image: not on the thread, the tile order or the region rendered. That is what makes
//! regions rendered apart join into the whole image byte for byte.

use crate::geometry::DVec3;
use rand::{Rng, SeedableRng};

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
pub(crate) fn point_in_grid(i: u32, (cols, rows): (u32, u32), u: f64, v: f64) -> (f64, f64) {
    let i = i % (cols * rows);
    (
        ((i % cols) as f64 + u) / cols as f64,
        ((i / cols) as f64 + v) / rows as f64,
    )
}

/// splitmix64: a strong 64-bit mixer used to derive per-pixel seeds.
pub(crate) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The key of pixel `(x, y)` of the full image for a render whose seed was mixed into
/// `mixed_seed` (= `mix(seed)`): it seeds the pixel's random stream.
#[inline]
pub(crate) fn pixel_key(mixed_seed: u64, x: u32, y: u32) -> u64 {
    mix(mixed_seed ^ mix((y as u64) << 32 | x as u64))
}

/// The state of one pixel's samples, handed to a [`Shader`](super::Shader) with each primary
/// ray: the pixel's random stream, which sample of the pixel this is (for stratified light
/// sampling), a counter of the rays traced, and whether the primary ray hit an object (for
/// the coverage of a transparent background).
pub struct Sample {
    rng: rand_pcg::Pcg64Mcg,
    /// Key of the pixel, to derive each light's stratum rotation.
    key: u64,
    /// Index of the current sample within the pixel.
    pub(crate) index: u32,
    /// Samples per pixel.
    count: u32,
    /// Rays traced so far for this pixel (a plain integer: no atomics per ray).
    pub(crate) rays: u64,
    /// What the shader said of the current sample's primary ray ([`Sample::report_primary_hit`]);
    /// `None` until it says.
    pub(crate) primary_hit: Option<bool>,
}

impl Sample {
    /// The state of a pixel with key `key` (its random stream's seed) taking `count` samples,
    /// at sample `index`.
    pub fn new(key: u64, index: u32, count: u32) -> Self {
        Self {
            rng: rand_pcg::Pcg64Mcg::seed_from_u64(key),
            key,
            index,
            count: count.max(1),
            rays: 0,
            primary_hit: None,
        }
    }

    /// Says whether this sample's primary (camera) ray hit an object; only the first report
    /// of a sample counts, so a shader may call it for every ray it traces, the primary one
    /// first. Optional: a shader that does not report spares nothing, and the render traces
    /// the primary ray once more when it needs the pixel's coverage (a transparent background).
    #[inline]
    pub fn report_primary_hit(&mut self, hit: bool) {
        if self.primary_hit.is_none() {
            self.primary_hit = Some(hit);
        }
    }

    /// The next number of the pixel's stream, uniform in `[0, 1)`.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// Counts one traced ray (primary, secondary or shadow segment) in the render's stats.
    #[inline]
    pub fn count_ray(&mut self) {
        self.rays += 1;
    }

    /// A jittered point of the unit square for shadow ray `ray` of `rays` that this sample
    /// sends to light `light`: the pixel's `count·rays` strata (laid out as `grid`, the
    /// [`strata`] of that number) are each taken once, in an order rotated per pixel and light.
    pub fn light_point(
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
pub(crate) fn concentric_disc(u: f64, v: f64) -> (f64, f64) {
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
pub(crate) fn basis(w: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(w.z);
    let a = -1.0 / (sign + w.z);
    let b = w.x * w.y * a;
    (
        DVec3::new(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x),
        DVec3::new(b, sign + w.y * w.y * a, -w.y),
    )
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
    fn pixel_keys_depend_on_seed_and_position_only() {
        let seed = mix(7);
        assert_eq!(pixel_key(seed, 3, 5), pixel_key(mix(7), 3, 5));
        assert_ne!(pixel_key(seed, 3, 5), pixel_key(seed, 5, 3));
        assert_ne!(pixel_key(seed, 3, 5), pixel_key(mix(8), 3, 5));
    }
}
