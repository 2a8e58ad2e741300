//! The paper's implicit heart, `(2X² + Y² + Z² − 1)³ − (0.1X² + Y²)·Z³ = 0`, placed in the
//! world by a position and a basis `u, v, w` (the scene line `HEART (position) (u) (v) (w)`).

use super::{Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Frame, Ray};
use crate::roots::Solver;

/// The coefficients `c0..=c6` (ascending powers of `t`) of `f(o + t·d)` for the object-space
/// heart `f`, by the closed form of the paper (the a…k route of shared notes).
#[inline]
pub fn sextic_coefficients(o: DVec3, d: DVec3) -> [f64; 7] {
    let (x0, y0, z0) = (o.x, o.y, o.z);
    let (x1, y1, z1) = (d.x, d.y, d.z);
    let a = 2.0 * x0 * x0 + y0 * y0 + z0 * z0 - 1.0;
    let b = 4.0 * x0 * x1 + 2.0 * y0 * y1 + 2.0 * z0 * z1;
    let c = 2.0 * x1 * x1 + y1 * y1 + z1 * z1;
    let d_ = 0.1 * x0 * x0 + y0 * y0;
    let e = 0.2 * x0 * x1 + 2.0 * y0 * y1;
    let f = 0.1 * x1 * x1 + y1 * y1;
    let g = z0 * z0 * z0;
    let h = 3.0 * z0 * z0 * z1;
    let i = 3.0 * z0 * z1 * z1;
    let k = z1 * z1 * z1;
    [
        a * a * a - d_ * g,
        3.0 * a * a * b - d_ * h - e * g,
        3.0 * a * a * c + 3.0 * a * b * b - d_ * i - e * h - f * g,
        6.0 * a * b * c + b * b * b - d_ * k - e * i - f * h,
        3.0 * b * b * c + 3.0 * a * c * c - e * k - f * i,
        3.0 * b * c * c - f * k,
        c * c * c,
    ]
}

/// The heart function `f` at an object-space point: negative inside, positive outside.
#[inline]
pub fn heart_fn(p: DVec3) -> f64 {
    let a = 2.0 * p.x * p.x + p.y * p.y + p.z * p.z - 1.0;
    a * a * a - (0.1 * p.x * p.x + p.y * p.y) * p.z * p.z * p.z
}

/// A heart placed in the world; see the module doc.
#[derive(Debug, Clone, PartialEq)]
pub struct Heart {
    frame: Frame,
    solver: Solver,
}

impl Heart {
    /// A heart at `position` with object-to-world basis columns `u, v, w` (any invertible
    /// basis; a singular or nearly singular one is an error).
    pub fn new(position: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, ShapeError> {
        Ok(Self {
            frame: Frame::new(position, u, v, w)?,
            solver: Solver::default(),
        })
    }

    /// The same heart, intersected with the given root-isolation strategy.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        self.solver = solver;
        self
    }
}

impl Shape for Heart {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        // TODO: heart work (bounding box, equator accuracy, scale-aware t_min).
        let r = self.frame.ray_to_object(ray);
        let c = sextic_coefficients(r.origin, r.dir);
        self.solver.first_root(&c, t_min, t_max.min(1e6))
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        // TODO: heart work (gradient, singular points).
        let _q = self.frame.point_to_object(p);
        DVec3::Z
    }

    fn bounds(&self) -> Aabb {
        self.frame.bounds_to_world(&Aabb::new(
            DVec3::new(-0.72, -1.14, -1.0),
            DVec3::new(0.72, 1.14, 1.24),
        ))
    }
}
