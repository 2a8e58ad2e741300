//! A parallelepiped: a corner and three edge vectors.

use super::{Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Frame, Ray};

/// The solid `corner + a·e1 + b·e2 + c·e3`, `a, b, c ∈ [0, 1]`; normals face outward.
#[derive(Debug, Clone, PartialEq)]
pub struct Parallelepiped {
    frame: Frame,
}

impl Parallelepiped {
    /// A box from one corner and three linearly independent edge vectors.
    pub fn new(corner: DVec3, e1: DVec3, e2: DVec3, e3: DVec3) -> Result<Self, ShapeError> {
        Ok(Self {
            frame: Frame::new(corner, e1, e2, e3)?,
        })
    }
}

impl Shape for Parallelepiped {
    fn intersect(&self, _ray: &Ray, _t_min: f64, _t_max: f64) -> Option<f64> {
        None // TODO: shapes work
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        DVec3::Z // TODO: shapes work
    }

    fn bounds(&self) -> Aabb {
        self.frame
            .bounds_to_world(&Aabb::new(DVec3::ZERO, DVec3::ONE))
    }
}
