//! A parallelepiped: a corner and three edge vectors.

use super::placed::{ObjectShape, Placed, Placement, PlacementNames};
use super::sphere::{BOUNDS_PAD, SURFACE_SNAP};
use super::ShapeError;
use crate::geometry::{Aabb, DVec3, Ray};

/// The solid `corner + a·e1 + b·e2 + c·e3`, `a, b, c ∈ [0, 1]` (the edges need not be
/// orthogonal); its surface is the six faces, normals face outward.
///
/// Intersected in object space, where it is the unit cube `[0, 1]³`; a ray starting inside gets
/// its exit point. At edges and corners the normal is that of the face nearest (in world
/// distance) to the point.
pub type Parallelepiped = Placed<UnitCube>;

/// The object space of a [`Parallelepiped`]: the unit cube `[0, 1]³`, with what its placement
/// makes of its faces in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitCube {
    /// Unit world normals of the faces `a = 1`, `b = 1`, `c = 1`; the faces `a = 0` etc.
    /// have the opposite normals.
    face_normals: [DVec3; 3],
    /// World distance between the two faces `a = 0` and `a = 1` (and likewise for b, c).
    thickness: [f64; 3],
}

impl Parallelepiped {
    /// A box from one corner and three edge vectors (world units) that must be finite and
    /// linearly independent (the box must not be flat).
    pub fn new(corner: DVec3, e1: DVec3, e2: DVec3, e3: DVec3) -> Result<Self, ShapeError> {
        let names = PlacementNames {
            shape: "box",
            position: "corner",
            vectors: "edge",
        };
        let at = Placement::named(corner, e1, e2, e3, names)?;
        let mut face_normals = [DVec3::ZERO; 3];
        let mut thickness = [0.0; 3];
        for axis in 0..3 {
            // Row `axis` of M⁻¹ is the world gradient of the object coordinate along `axis`.
            let g = at.frame().normal_matrix.col(axis);
            let len = g.length();
            face_normals[axis] = g / len;
            thickness[axis] = 1.0 / len;
        }
        Ok(Placed::place(
            at,
            UnitCube {
                face_normals,
                thickness,
            },
        ))
    }
}

impl ObjectShape for UnitCube {
    fn intersect(&self, at: &Placement, ray: &Ray, o: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        // Bound on the rounding of the object-space origin: a face within it of the origin is
        // treated as passing exactly through it (t = 0), so rays leaving the surface, even at
        // grazing angles, never re-hit the face they start on.
        let tol = SURFACE_SNAP * (1.0 + at.origin_reach(ray.origin));
        let mut t_near = f64::NEG_INFINITY;
        let mut t_far = f64::INFINITY;
        for axis in 0..3 {
            let (oa, da) = (o.origin[axis], o.dir[axis]);
            let snap = |g: f64| if g.abs() <= tol { 0.0 } else { g };
            let (gap_lo, gap_hi) = (snap(-oa), snap(1.0 - oa));
            if da == 0.0 {
                if gap_lo > 0.0 || gap_hi < 0.0 {
                    return None; // parallel to this slab and outside it
                }
                continue;
            }
            let (a, b) = (gap_lo / da, gap_hi / da);
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            t_near = t_near.max(a);
            t_far = t_far.min(b);
            if t_near > t_far {
                return None;
            }
        }
        // Entry if it is in range, otherwise the exit (the ray starts inside, or t_min skips
        // the entry).
        [t_near, t_far]
            .into_iter()
            .find(|&t| t > t_min && t < t_max)
    }

    fn normal(&self, _: &Placement, po: DVec3) -> DVec3 {
        // The face whose plane is nearest in world distance; ties (edges, corners) go to the
        // first. Never NaN: the candidates are precomputed unit vectors.
        let mut best = (f64::INFINITY, -self.face_normals[0]);
        for axis in 0..3 {
            let h = self.thickness[axis];
            let n = self.face_normals[axis];
            for (dist, normal) in [(po[axis].abs() * h, -n), ((1.0 - po[axis]).abs() * h, n)] {
                if dist < best.0 {
                    best = (dist, normal);
                }
            }
        }
        best.1
    }

    fn bounds(&self, at: &Placement) -> Aabb {
        at.bounds_to_world(&Aabb::new(DVec3::ZERO, DVec3::ONE))
            .padded(BOUNDS_PAD)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;

    fn cube() -> Parallelepiped {
        // [1,3] × [2,4] × [3,5]
        Parallelepiped::new(
            DVec3::new(1.0, 2.0, 3.0),
            2.0 * DVec3::X,
            2.0 * DVec3::Y,
            2.0 * DVec3::Z,
        )
        .unwrap()
    }

    fn sheared() -> Parallelepiped {
        Parallelepiped::new(
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.5, 1.0),
        )
        .unwrap()
    }

    #[test]
    fn axis_aligned_hits_every_face() {
        let b = cube();
        let c = DVec3::new(2.0, 3.0, 4.0);
        for n in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ] {
            let r = Ray::new(c + 10.0 * n, -0.5 * n);
            let t = b.intersect(&r, 0.0, f64::INFINITY).unwrap();
            assert!((t - 18.0).abs() < 1e-12, "{n}: {t}");
            assert!((b.normal(r.at(t)) - n).length() < 1e-12);
        }
    }

    #[test]
    fn from_inside_returns_exit_and_range_is_respected() {
        let b = cube();
        let r = Ray::new(DVec3::new(2.0, 3.0, 4.0), DVec3::new(0.0, 0.0, 2.0));
        assert_eq!(b.intersect(&r, 1e-9, f64::INFINITY), Some(0.5));
        assert_eq!(b.intersect(&r, 1e-9, 0.5), None);
        let out = Ray::new(DVec3::new(2.0, 3.0, 0.0), DVec3::Z);
        assert_eq!(b.intersect(&out, 0.0, f64::INFINITY), Some(3.0));
        assert_eq!(b.intersect(&out, 3.0, f64::INFINITY), Some(5.0));
        assert_eq!(b.intersect(&out, 5.0, f64::INFINITY), None);
        assert_eq!(b.intersect(&out, 0.0, 2.9), None);
    }

    #[test]
    fn misses_including_parallel_rays() {
        let b = cube();
        let par = Ray::new(DVec3::new(0.0, 4.5, 4.0), DVec3::X);
        assert_eq!(b.intersect(&par, 0.0, f64::INFINITY), None);
        let diag = Ray::new(DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, -1.0, 0.0));
        assert_eq!(b.intersect(&diag, 0.0, f64::INFINITY), None);
        let behind = Ray::new(DVec3::new(2.0, 3.0, 10.0), DVec3::Z);
        assert_eq!(b.intersect(&behind, 0.0, f64::INFINITY), None);
    }

    #[test]
    fn sheared_box_normal_is_outward_face_normal() {
        let b = sheared();
        // Top face c = 1 is the plane z = 1; the ray comes straight down into it.
        let r = Ray::new(DVec3::new(1.6, 0.9, 5.0), DVec3::NEG_Z);
        let t = b.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-12);
        assert!((b.normal(r.at(t)) - DVec3::Z).length() < 1e-12);
        // Face a = 0 is spanned by e2 = (1,1,0) and e3 = (0,0.5,1); outward is away from e1.
        let p = 0.5 * DVec3::new(1.0, 1.0, 0.0) + 0.5 * DVec3::new(0.0, 0.5, 1.0);
        let n = b.normal(p);
        assert!(n.dot(DVec3::new(1.0, 1.0, 0.0)).abs() < 1e-12);
        assert!(n.dot(DVec3::new(0.0, 0.5, 1.0)).abs() < 1e-12);
        assert!(n.dot(DVec3::new(2.0, 0.0, 0.0)) < 0.0);
        assert!((n.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn edges_and_corners_get_a_finite_face_normal() {
        let b = cube();
        for p in [
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(3.0, 4.0, 5.0),
            DVec3::new(3.0, 3.0, 5.0),
            DVec3::new(2.0, 3.0, 4.0), // centre: any face will do
            DVec3::splat(f64::NAN),
        ] {
            let n = b.normal(p);
            assert!(
                n.is_finite() && (n.length() - 1.0).abs() < 1e-12,
                "{p}: {n}"
            );
            assert_eq!(n.abs().max_element(), 1.0);
        }
        // A ray through an edge exactly hits it.
        let r = Ray::new(DVec3::new(0.0, 1.0, 4.0), DVec3::new(1.0, 1.0, 0.0));
        assert_eq!(b.intersect(&r, 0.0, f64::INFINITY), Some(1.0));
    }

    #[test]
    fn rays_leaving_a_face_do_not_rehit_it() {
        let b = sheared();
        for i in 1..100 {
            let s = i as f64 / 100.0;
            // A point on face a = 1 and a grazing direction along the face, slightly outward.
            let p = DVec3::new(2.0, 0.0, 0.0)
                + s * DVec3::new(1.0, 1.0, 0.0)
                + (1.0 - s) * DVec3::new(0.0, 0.5, 1.0);
            let n = b.normal(p);
            let along = DVec3::new(1.0, 1.0, 0.0).normalize();
            let r = Ray::new(p, along + 1e-10 * n);
            assert_eq!(b.intersect(&r, 0.0, f64::INFINITY), None, "{p}");
            // Straight inward: the exit through the opposite face at world distance 2·h.
            let inward = Ray::new(p, -n);
            let t = b.intersect(&inward, 0.0, f64::INFINITY).unwrap();
            assert!(t > 1e-6, "{t}");
        }
    }

    #[test]
    fn rejects_flat_boxes() {
        let e =
            Parallelepiped::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y).unwrap_err();
        assert!(e.0.contains("flat"), "{e}");
        let e = Parallelepiped::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ZERO).unwrap_err();
        assert!(e.0.contains("flat"), "{e}");
        assert!(
            Parallelepiped::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::splat(f64::NAN)).is_err()
        );
    }
}
