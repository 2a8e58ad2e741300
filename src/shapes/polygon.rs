//! A planar polygon, convex or not.

use super::{Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray};

/// A flat polygon with at least 3 coplanar vertices; its normal follows the right-hand rule
/// on the vertex order (counter-clockwise seen from the front).
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<DVec3>,
}

impl Polygon {
    /// A polygon; fails for fewer than 3 vertices, non-finite, collinear or non-planar ones.
    pub fn new(vertices: Vec<DVec3>) -> Result<Self, ShapeError> {
        if vertices.len() < 3 {
            return Err(ShapeError(format!(
                "a polygon needs at least 3 vertices, not {}",
                vertices.len()
            )));
        }
        Ok(Self { vertices }) // TODO: shapes work (planarity)
    }
}

impl Shape for Polygon {
    fn intersect(&self, _ray: &Ray, _t_min: f64, _t_max: f64) -> Option<f64> {
        None // TODO: shapes work
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        DVec3::Z // TODO: shapes work
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().copied())
    }
}
