//! An ellipsoid: the unit sphere placed by a centre and three axis vectors.

use super::{Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Frame, Ray};

/// The surface `centre + M·s`, `|s| = 1`, `M = [u v w]`; normals face outward.
#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    frame: Frame,
}

impl Ellipsoid {
    /// An ellipsoid with semi-axis vectors `u`, `v`, `w` (linearly independent).
    pub fn new(centre: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, ShapeError> {
        Ok(Self {
            frame: Frame::new(centre, u, v, w)?,
        })
    }
}

impl Shape for Ellipsoid {
    fn intersect(&self, _ray: &Ray, _t_min: f64, _t_max: f64) -> Option<f64> {
        None // TODO: shapes work
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        DVec3::Z // TODO: shapes work
    }

    fn bounds(&self) -> Aabb {
        self.frame
            .bounds_to_world(&Aabb::new(DVec3::splat(-1.0), DVec3::ONE))
    }
}
