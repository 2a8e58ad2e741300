//! Shapes: everything a ray can hit. Each shape implements the small [`Shape`] trait; a new
//! primitive is one new file here plus one keyword in `scene::parser`.

pub use crate::geometry::LANES;
use crate::geometry::{Aabb, DVec3, Hexahedron, Ray, SolidEllipsoid};

mod boxes;
mod ellipsoid;
pub mod heart;
pub mod implicit;
pub mod placed;
mod plane;
mod polygon;
pub mod report;
pub mod solid;
mod sphere;
pub mod triangles;

pub use boxes::Parallelepiped;
pub use ellipsoid::Ellipsoid;
pub use heart::Heart;
pub use implicit::Implicit;
pub use plane::Plane;
pub use polygon::Polygon;
pub use report::{SettledBy, SolverReport};
pub use solid::PolynomialSolid;
pub use sphere::Sphere;
pub use triangles::{MeshNormals, MeshShape};

/// Why a shape's parameters do not describe a valid shape; the message completes the sentence
/// "this shape is invalid because …" and names the offending parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ShapeError(pub String);

impl From<crate::geometry::FrameError> for ShapeError {
    fn from(e: crate::geometry::FrameError) -> Self {
        ShapeError(e.to_string())
    }
}

/// A surface in world space.
///
/// Contract shared by every shape:
/// - `intersect` returns the smallest `t` with `t_min < t < t_max` where `ray.at(t)` is on the
///   surface, measured in units of `ray.dir` (which need not be unit length). Callers pass a
///   small positive `t_min` for rays that start on a surface; a shape whose own numerics are
///   coarser than that near `t = 0` must widen the guard itself so a ray never re-hits its origin.
/// - `normal` is the unit normal at a world point on (or within rounding of) the surface,
///   facing the shape's outside (for a plane or polygon: the side its normal was given on),
///   whatever side the ray came from. It is never NaN.
/// - `bounds` is a world box containing the whole surface (possibly infinite).
pub trait Shape: Send + Sync + std::fmt::Debug {
    /// Smallest ray parameter in `(t_min, t_max)` at which the ray meets the surface.
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64>;
    /// Whether the ray meets the surface at some `t` with `t_min < t < t_max`: always exactly
    /// `self.intersect(ray, t_min, t_max).is_some()` (shadow rays ask this; a shape may answer
    /// it more cheaply, never differently).
    fn occludes(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.intersect(ray, t_min, t_max).is_some()
    }
    /// [`Shape::intersect`] for [`LANES`] rays at once, each with its own range: lane `i` of
    /// the answer is always exactly `self.intersect(&rays[i], t_min[i], t_max[i])`, and
    /// `None` without any work when `t_max[i] <= t_min[i]` (an idle lane). Camera rays of
    /// neighbouring pixels ask this; a shape may answer it more cheaply, never differently.
    fn intersect_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        each_lane(t_min, t_max, |i| {
            self.intersect(&rays[i], t_min[i], t_max[i])
        })
    }
    /// [`Shape::occludes`] for [`LANES`] rays at once: lane `i` is always exactly
    /// `self.occludes(&rays[i], t_min[i], t_max[i])`, and `false` without any work when
    /// `t_max[i] <= t_min[i]`. The shadow rays of neighbouring pixels ask this.
    fn occludes_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [bool; LANES] {
        std::array::from_fn(|i| t_max[i] > t_min[i] && self.occludes(&rays[i], t_min[i], t_max[i]))
    }
    /// Unit outward normal at the world point `p` on the surface.
    fn normal(&self, p: DVec3) -> DVec3;
    /// [`Shape::normal`] at the [`LANES`] world points `p` where `live` is set: lane `i` is
    /// always exactly `self.normal(p[i])` there, and zero where `live[i]` is not (that lane's
    /// point is not read as a surface point). The hits of neighbouring camera rays ask this;
    /// a shape may answer it more cheaply, never differently.
    fn normal_lanes(&self, p: &[DVec3; LANES], live: [bool; LANES]) -> [DVec3; LANES] {
        std::array::from_fn(|i| {
            if live[i] {
                self.normal(p[i])
            } else {
                DVec3::ZERO
            }
        })
    }
    /// Whether [`Shape::normal_lanes`] does less work than [`Shape::normal`] asked lane by
    /// lane (false unless a shape says so): callers may ask either way, the answers are the
    /// same.
    fn normal_lanes_pays(&self) -> bool {
        false
    }
    /// World-space box containing the surface.
    fn bounds(&self) -> Aabb;
    /// World-space solid ellipsoids whose union holds every point at which `intersect` may
    /// report the surface (tighter than [`Shape::bounds`] somewhere, to be of use; the
    /// renderer leaves out the pixels that see none of them). Empty (the default): none known.
    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        Vec::new()
    }
    /// World-space convex cells whose union holds every point at which `intersect` may
    /// report the surface (many small ones along it, to be of use; the renderer leaves out
    /// the pixels that see none of them). Empty (the default): none known.
    fn enclosing_cells(&self) -> Vec<Hexahedron> {
        Vec::new()
    }
    /// For a surface found by a polynomial root finder: what the root finder did for this
    /// ray in `(t_min, t_max)`, from the same queries [`Shape::intersect`] makes (same hit);
    /// `None` for other shapes, and for rays that never reach the root finder.
    fn solver_report(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SolverReport> {
        let _ = (ray, t_min, t_max);
        None
    }
    /// The SHA-256 (hex) of the file the shape was read from (a `MESH`'s), which the render
    /// key takes in so that a changed file is a new render; `None` for shapes read from no
    /// file.
    fn source_digest(&self) -> Option<String> {
        None
    }
    /// For a surface given by a polynomial (HEART, IMPLICIT): its exact polynomial, clip ball
    /// and placement, the solid that `kardia mesh` turns into triangles; `None` for others.
    fn polynomial_solid(&self) -> Option<PolynomialSolid> {
        None
    }
}

/// `query(i)` for every lane `i` with `t_max[i] > t_min[i]`, `None` without asking for the
/// others: the one-at-a-time answer of a lane query (see [`Shape::intersect_lanes`]).
#[inline]
pub(crate) fn each_lane(
    t_min: [f64; LANES],
    t_max: [f64; LANES],
    mut query: impl FnMut(usize) -> Option<f64>,
) -> [Option<f64>; LANES] {
    std::array::from_fn(|i| if t_max[i] > t_min[i] { query(i) } else { None })
}

/// Parses a finite-check helper used by constructors: true when all vectors are finite.
pub(crate) fn all_finite(vs: &[DVec3]) -> bool {
    vs.iter().all(|v| v.is_finite())
}
