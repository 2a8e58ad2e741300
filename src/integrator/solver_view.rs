//! The shader shared by the root-finder study views ([`super::roots`], [`super::path`],
//! [`super::iterations`], [`super::conditioning`]): each pixel shows, through the view's own
//! colour table ([`ReportColour`]), what the root finder did for its camera ray against the
//! polynomial surface the ray meets first ([`crate::shapes::SolverReport`]): real data from the
//! queries of the intersection, not an image effect.
//!
//! Only polynomial surfaces (`HEART`, `IMPLICIT`) are drawn: other shapes are transparent in
//! these views. A ray that hits no polynomial surface shows the report of the first one (in
//! scene order) whose bounds it enters and whose root finder it reaches (a proved miss);
//! a ray that reaches no root finder is black. No lights, shadows or secondary rays.

use super::sampling::Sample;
use super::{ShadeSetup, Shader};
use crate::geometry::{DVec3, Ray};
use crate::scene::Scene;
use crate::shapes::SolverReport;

/// A study view's colour for one ray's report (linear RGB).
pub trait ReportColour: Sync {
    /// The colour of `report`.
    fn colour(&self, report: &SolverReport) -> DVec3;
}

/// A root-finder study view of one scene, coloured by `C`.
pub struct SolverView<'a, C> {
    scene: &'a Scene,
    colours: C,
}

impl<'a, C: ReportColour> SolverView<'a, C> {
    /// The view of `setup.scene` coloured by `colours`.
    pub fn with_colours(setup: &ShadeSetup<'a>, colours: C) -> Self {
        Self {
            scene: setup.scene,
            colours,
        }
    }
}

/// The report for `ray` of the nearest polynomial surface it hits, else of the first one
/// whose root finder it reaches (see the module documentation).
pub fn primary_report(scene: &Scene, ray: &Ray) -> Option<SolverReport> {
    let mut nearest: Option<SolverReport> = None;
    let mut first_miss: Option<SolverReport> = None;
    for obj in &scene.objects {
        if obj.bounds.clip(ray, 0.0, f64::INFINITY).is_none() {
            continue;
        }
        let Some(report) = obj.shape.solver_report(ray, 0.0, f64::INFINITY) else {
            continue;
        };
        match (report.hit, nearest.and_then(|n| n.hit)) {
            (Some(t), Some(best)) if t >= best => {}
            (Some(_), _) => nearest = Some(report),
            (None, _) => {
                first_miss.get_or_insert(report);
            }
        }
    }
    nearest.or(first_miss)
}

impl<C: ReportColour> Shader for SolverView<'_, C> {
    fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3 {
        sample.count_ray();
        primary_report(self.scene, ray).map_or(DVec3::ZERO, |r| self.colours.colour(&r))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::materials::Material;
    use crate::scene::Object;
    use crate::shapes::{Heart, Sphere};

    /// The default heart seen from +x, 16×16 pixels, with a sphere in front of its centre.
    pub(crate) fn heart_scene() -> Scene {
        let heart = Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        let eye = DVec3::new(4.0, 0.0, 0.1);
        Scene {
            width: 16,
            height: 16,
            camera: Camera::new(eye, DVec3::new(0.0, 0.0, 0.1), DVec3::Z, 40.0).unwrap(),
            background: DVec3::ZERO,
            ambient: DVec3::ZERO,
            lights: vec![],
            index: Default::default(),
            objects: vec![
                Object::new(
                    Box::new(Sphere::new(DVec3::new(2.0, 0.0, 0.1), 0.1).unwrap()),
                    Material::default(),
                    "SPHERE",
                    1,
                ),
                Object::new(Box::new(heart), Material::default(), "HEART", 2),
            ],
        }
    }

    #[test]
    fn reports_see_through_other_shapes_and_tell_hits_from_proved_misses() {
        let scene = heart_scene();
        let eye = scene.camera.eye;
        // Through the sphere to the heart's centre: the heart's hit, not the sphere's.
        let centre = Ray::new(eye, DVec3::new(-1.0, 0.0, 0.0));
        let r = primary_report(&scene, &centre).expect("the heart is queried");
        let t = r.hit.expect("a hit");
        assert_eq!(
            Some(t),
            scene.objects[1]
                .shape
                .intersect(&centre, 0.0, f64::INFINITY)
        );
        assert!(r.distinct_roots >= 2 && r.degree == 6, "{r:?}");
        assert!(r.gradient_norm.unwrap() > 0.0);
        // Inside the heart's box but beside it: a proved miss, no gradient.
        let beside = Ray::new(eye, DVec3::new(-4.0, 0.0, 1.3));
        let r = primary_report(&scene, &beside).expect("the box is entered");
        assert_eq!((r.hit, r.gradient_norm, r.distinct_roots), (None, None, 0));
        // Far away: nothing queried.
        let away = Ray::new(eye, DVec3::X);
        assert_eq!(primary_report(&scene, &away), None);
    }
}
