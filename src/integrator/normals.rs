//! False-colour normals, the [`View::Normals`](super::View::Normals) study view: each pixel
//! shows the outward unit normal `n` of the first surface its rays meet as the linear colour
//! `(n + 1) / 2` (so +x is red, +y green, +z blue; a back side shows the normal facing away
//! from the camera). Rays that hit nothing are black. No lights, no shadows, no secondary rays.

use super::sampling::Sample;
use super::{ShadeSetup, Shader};
use crate::geometry::{DVec3, Ray};
use crate::scene::Scene;

/// The normals view of one scene.
pub struct Normals<'a> {
    scene: &'a Scene,
}

impl<'a> Normals<'a> {
    /// The view of `setup.scene` (nothing else of the setup matters).
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        Self { scene: setup.scene }
    }
}

/// How to read the view: the colours of the six axis directions.
pub fn legend() -> super::Legend {
    let axes = [
        ("+x", DVec3::X),
        ("−x", -DVec3::X),
        ("+y", DVec3::Y),
        ("−y", -DVec3::Y),
        ("+z", DVec3::Z),
        ("−z", -DVec3::Z),
    ];
    super::Legend::new(
        "outward unit normal n as the colour (n + 1) / 2",
        axes.map(|(name, n)| {
            let c = (n + DVec3::ONE) * 0.5;
            let srgb = [c.x, c.y, c.z].map(crate::film::linear_to_srgb8);
            (format!("normal {name}"), srgb)
        }),
        "black: no hit",
    )
}

impl Shader for Normals<'_> {
    fn miss_colour(&self) -> Option<DVec3> {
        Some(DVec3::ZERO)
    }

    fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3 {
        sample.count_ray();
        let hit = self.scene.intersect(ray, 0.0, f64::INFINITY);
        sample.report_primary_hit(hit.is_some());
        match hit {
            Some(hit) => (hit.normal + DVec3::ONE) * 0.5,
            None => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::tests::{one_sample_setup, unit_sphere_scene};

    #[test]
    fn facing_normal_is_blue_and_misses_are_black() {
        let scene = unit_sphere_scene();
        let setup = one_sample_setup(&scene);
        let view = Normals::new(&setup);
        let mut sample = Sample::new(0, 0, 1);
        let towards = Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z);
        let c = view.radiance(&towards, &mut sample);
        assert!((c - DVec3::new(0.5, 0.5, 1.0)).length() < 1e-12, "{c}");
        let away = Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z);
        assert_eq!(view.radiance(&away, &mut sample), DVec3::ZERO);
        assert_eq!(sample.rays, 2);
    }
}
