//! Depth, the [`View::Depth`](super::View::Depth) study view: each pixel shows the distance `d`
//! from the eye to the first surface its rays meet as the grey level `exp(−d / d₀)`, with `d₀`
//! the camera's eye-to-look-at distance (so the point looked at is at 1/e ≈ 0.37, nearer is
//! brighter, and the grey never reaches 0 for a hit). Rays that hit nothing are black.

use super::sampling::Sample;
use super::{ShadeSetup, Shader};
use crate::geometry::{DVec3, Ray};
use crate::scene::Scene;

/// The depth view of one scene through one camera.
pub struct Depth<'a> {
    scene: &'a Scene,
    /// `d₀`: the eye-to-look-at distance of the render's camera (> 0).
    scale: f64,
}

impl<'a> Depth<'a> {
    /// The view of `setup.scene` seen by `setup.camera`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        let scale = (setup.camera.look_at - setup.camera.eye).length();
        Self {
            scene: setup.scene,
            scale: if scale > 0.0 { scale } else { 1.0 },
        }
    }
}

/// How to read the view: the grey at a few distances, in units of `d₀`.
pub fn legend() -> super::Legend {
    super::Legend::new(
        "distance d to the first hit as the grey exp(−d / d₀), d₀ the eye-to-look-at distance",
        [0.25, 0.5, 1.0, 2.0, 4.0].map(|d: f64| {
            let g = crate::film::linear_to_srgb8((-d).exp());
            (format!("d = {d} d₀"), [g, g, g])
        }),
        "black: no hit",
    )
}

impl Shader for Depth<'_> {
    fn miss_colour(&self) -> Option<DVec3> {
        Some(DVec3::ZERO)
    }

    fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3 {
        sample.count_ray();
        let hit = self.scene.intersect(ray, 0.0, f64::INFINITY);
        sample.report_primary_hit(hit.is_some());
        match hit {
            Some(hit) => DVec3::splat((-hit.t * ray.dir.length() / self.scale).exp()),
            None => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::tests::{one_sample_setup, unit_sphere_scene};

    #[test]
    fn grey_falls_off_with_distance() {
        let scene = unit_sphere_scene();
        let setup = one_sample_setup(&scene);
        // The camera sits at z = 5 looking at the origin: d₀ = 5, the sphere's front at d = 4.
        let view = Depth::new(&setup);
        let mut sample = Sample::new(0, 0, 1);
        let ray = Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z * 2.0);
        let grey = view.radiance(&ray, &mut sample);
        assert!(
            (grey - DVec3::splat((-4.0f64 / 5.0).exp())).length() < 1e-12,
            "{grey}"
        );
        let miss = Ray::new(DVec3::new(0.0, 3.0, 5.0), -DVec3::Z);
        assert_eq!(view.radiance(&miss, &mut sample), DVec3::ZERO);
    }
}
