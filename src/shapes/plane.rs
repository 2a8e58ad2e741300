//! An infinite plane through a point with a given normal.

use super::{all_finite, Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray};

/// The plane `(p − point)·normal = 0`; its "outside" is the side `normal` points to.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    point: DVec3,
    normal: DVec3,
}

impl Plane {
    /// A plane; `normal` must be finite and non-zero (it is normalised here).
    pub fn new(point: DVec3, normal: DVec3) -> Result<Self, ShapeError> {
        if !all_finite(&[point, normal]) {
            return Err(ShapeError("the point and normal must be finite".into()));
        }
        let n = normal.normalize_or_zero();
        if n == DVec3::ZERO {
            return Err(ShapeError("the normal must not be the zero vector".into()));
        }
        Ok(Self { point, normal: n })
    }
}

impl Shape for Plane {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None;
        }
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        (t > t_min && t < t_max).then_some(t)
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        self.normal
    }

    fn bounds(&self) -> Aabb {
        Aabb::EVERYTHING
    }
}
