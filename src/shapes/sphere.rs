//! A sphere given by centre and radius.

use super::{all_finite, Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray};

/// The sphere `|p − centre| = radius`; outside is away from the centre.
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    centre: DVec3,
    radius: f64,
}

impl Sphere {
    /// A sphere; `radius` must be finite and > 0.
    pub fn new(centre: DVec3, radius: f64) -> Result<Self, ShapeError> {
        if !all_finite(&[centre]) {
            return Err(ShapeError("the centre must be finite".into()));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(ShapeError(format!(
                "the radius must be a finite number greater than 0, not {radius}"
            )));
        }
        Ok(Self { centre, radius })
    }
}

impl Shape for Sphere {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        // Numerically careful quadratic: |d|²t² + 2(oc·d)t + |oc|² − r² = 0.
        let oc = ray.origin - self.centre;
        let a = ray.dir.length_squared();
        let half_b = oc.dot(ray.dir);
        // c computed as a difference of squares of the perpendicular distance is more accurate
        // than |oc|² − r² for far rays: |oc − (oc·d/|d|²)d|² − r².
        let perp = oc - (half_b / a) * ray.dir;
        let disc = a * (self.radius * self.radius - perp.length_squared());
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let q = -(half_b + half_b.signum() * sq);
        let c = oc.length_squared() - self.radius * self.radius;
        let (mut t0, mut t1) = if q != 0.0 { (q / a, c / q) } else { (0.0, 0.0) };
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        [t0, t1].into_iter().find(|&t| t > t_min && t < t_max)
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        let n = (p - self.centre).normalize_or_zero();
        if n == DVec3::ZERO {
            DVec3::Z
        } else {
            n
        }
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(
            self.centre - DVec3::splat(self.radius),
            self.centre + DVec3::splat(self.radius),
        )
    }
}
