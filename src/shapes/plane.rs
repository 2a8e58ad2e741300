//! An infinite plane through a point with a given normal.

use super::sphere::SURFACE_SNAP;
use super::{all_finite, Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray};

/// The signed distance `n·(point − origin)` (for a unit `n`) from a ray origin to a plane, set
/// to exactly `0` when it is within rounding (see `SURFACE_SNAP`), so that a ray starting on the
/// plane gets `t = 0` (rejected by any `t_min ≥ 0`) even when it grazes the plane.
pub(crate) fn plane_gap(n: DVec3, point: DVec3, origin: DVec3) -> f64 {
    let gap = n.dot(point - origin);
    let err = SURFACE_SNAP * (point.abs().max_element() + origin.abs().max_element());
    if gap.abs() <= err {
        0.0
    } else {
        gap
    }
}

/// The plane `(p − point)·normal = 0`; its "outside" is the side `normal` points to.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    point: DVec3,
    normal: DVec3,
}

impl Plane {
    /// A plane through `point`; `normal` must be finite and non-zero (any length: it is
    /// normalised here) and points to the plane's front ("outside").
    pub fn new(point: DVec3, normal: DVec3) -> Result<Self, ShapeError> {
        if !all_finite(&[point]) {
            return Err(ShapeError(format!(
                "the plane's point must be finite, not ({}, {}, {})",
                point.x, point.y, point.z
            )));
        }
        if !all_finite(&[normal]) {
            return Err(ShapeError(format!(
                "the plane's normal must be finite, not ({}, {}, {})",
                normal.x, normal.y, normal.z
            )));
        }
        // Scale first so that tiny (but non-zero) normals do not underflow.
        let n = (normal / normal.abs().max_element()).normalize_or_zero();
        if !(n.is_finite() && n != DVec3::ZERO) {
            return Err(ShapeError(
                "the plane's normal must not be the zero vector (0, 0, 0)".into(),
            ));
        }
        Ok(Self { point, normal: n })
    }

    /// A point on the plane (world space).
    pub fn point(&self) -> DVec3 {
        self.point
    }

    /// The unit normal, pointing to the plane's front.
    pub fn unit_normal(&self) -> DVec3 {
        self.normal
    }
}

impl Shape for Plane {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None; // parallel (a ray inside the plane does not count as hitting it)
        }
        let t = plane_gap(self.normal, self.point, ray.origin) / denom;
        (t > t_min && t < t_max).then_some(t)
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        self.normal
    }

    fn bounds(&self) -> Aabb {
        Aabb::EVERYTHING
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor() -> Plane {
        Plane::new(DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 0.0, 3.0)).unwrap()
    }

    #[test]
    fn hit_from_both_sides_normal_stays_on_given_side() {
        let p = floor();
        let down = Ray::new(DVec3::new(1.0, 2.0, 4.0), DVec3::new(0.0, 0.0, -2.0));
        let t = p.intersect(&down, 0.0, f64::INFINITY).unwrap();
        assert!((t - 2.5).abs() < 1e-15);
        assert_eq!(p.normal(down.at(t)), DVec3::Z);
        let up = Ray::new(DVec3::new(1.0, 2.0, -3.0), DVec3::new(1.0, 0.0, 1.0));
        let t = p.intersect(&up, 0.0, f64::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-15);
        assert_eq!(p.normal(up.at(t)), DVec3::Z);
    }

    #[test]
    fn parallel_behind_and_range() {
        let p = floor();
        let par = Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::X);
        assert_eq!(p.intersect(&par, 0.0, f64::INFINITY), None);
        let away = Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::Z);
        assert_eq!(p.intersect(&away, 0.0, f64::INFINITY), None);
        let down = Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::NEG_Z);
        assert_eq!(p.intersect(&down, 0.0, 2.0), None);
        assert_eq!(p.intersect(&down, 2.0, 3.0), None);
        assert_eq!(p.intersect(&down, 1.0, 3.0), Some(2.0));
    }

    #[test]
    fn grazing_ray_from_the_plane_does_not_rehit() {
        let p = Plane::new(DVec3::new(0.1, 0.2, 0.3), DVec3::new(1.0, 2.0, 3.0)).unwrap();
        let n = p.unit_normal();
        let (e1, e2) = n.any_orthonormal_pair();
        for i in 0..100 {
            let s = i as f64 * 0.731;
            let on = p.point() + 37.0 * s.sin() * e1 + 11.0 * s.cos() * e2;
            let dir = e1 * s.cos() + e2 * s.sin() + 1e-9 * n;
            assert_eq!(p.intersect(&Ray::new(on, dir), 0.0, f64::INFINITY), None);
            assert_eq!(p.intersect(&Ray::new(on, -dir), 0.0, f64::INFINITY), None);
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Plane::new(DVec3::ZERO, DVec3::ZERO).is_err());
        assert!(Plane::new(DVec3::ZERO, DVec3::new(f64::NAN, 1.0, 0.0)).is_err());
        assert!(Plane::new(DVec3::splat(f64::INFINITY), DVec3::Z).is_err());
        let tiny = Plane::new(DVec3::ZERO, DVec3::new(0.0, 1e-310, 0.0)).unwrap();
        assert_eq!(tiny.unit_normal(), DVec3::Y);
    }
}
