//! An ellipsoid: the unit sphere placed by a centre and three axis vectors.

use super::placed::{ObjectShape, Placed, Placement, PlacementNames};
use super::sphere::{first_root_in, sphere_roots, BOUNDS_PAD, SURFACE_SNAP};
use super::ShapeError;
use crate::geometry::{Aabb, DVec3, Ray, SolidEllipsoid};

/// The surface `centre + M·s`, `|s| = 1`, `M = [u v w]`: the unit sphere mapped by the frame,
/// so `u`, `v`, `w` are semi-axis vectors (world units) that need not be orthogonal. Normals
/// face outward (away from the centre).
pub type Ellipsoid = Placed<UnitSphere>;

/// The object space of an [`Ellipsoid`]: the unit sphere about the origin.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitSphere;

impl Ellipsoid {
    /// An ellipsoid with centre and semi-axis vectors `u`, `v`, `w`: all finite, and the three
    /// vectors linearly independent (the ellipsoid must not be flat).
    pub fn new(centre: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, ShapeError> {
        let names = PlacementNames {
            shape: "ellipsoid",
            position: "centre",
            vectors: "axis",
        };
        Ok(Placed::place(
            Placement::named(centre, u, v, w, names)?,
            UnitSphere,
        ))
    }
}

impl ObjectShape for UnitSphere {
    fn intersect(&self, at: &Placement, ray: &Ray, o: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        // Bound on the rounding of the object-space origin (the world origin, the subtraction,
        // then M⁻¹); see SURFACE_SNAP.
        let origin_err = SURFACE_SNAP * at.origin_reach(ray.origin);
        let roots = sphere_roots(o.origin, o.dir, 1.0, origin_err)?;
        first_root_in(roots, t_min, t_max)
    }

    fn normal(&self, at: &Placement, s: DVec3) -> DVec3 {
        // Gradient of |M⁻¹(p − c)|² is 2·M⁻ᵀ·s; rescale s first so tiny values cannot
        // underflow, and fall back to a fixed axis at the centre itself.
        let scale = s.abs().max_element();
        if scale > 0.0 && scale.is_finite() {
            let n = (at.frame().normal_matrix * (s / scale)).normalize_or_zero();
            if n != DVec3::ZERO {
                return n;
            }
        }
        at.frame().normal_to_world(DVec3::Z)
    }

    fn bounds(&self, at: &Placement) -> Aabb {
        // Tight: coordinate i of centre + M·s over |s| = 1 ranges over ± |row i of M|.
        let m = &at.frame().m;
        let ext = DVec3::new(m.row(0).length(), m.row(1).length(), m.row(2).length());
        let c = at.frame().position;
        Aabb::new(c - ext, c + ext).padded(BOUNDS_PAD)
    }

    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        vec![SolidEllipsoid::axis_aligned(DVec3::ZERO, DVec3::ONE)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;

    fn egg() -> Ellipsoid {
        Ellipsoid::new(
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        )
        .unwrap()
    }

    #[test]
    fn axis_hits_known_t_and_normal() {
        let e = egg();
        let r = Ray::new(DVec3::new(-9.0, 1.0, 1.0), DVec3::new(2.0, 0.0, 0.0));
        let t = e.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - 3.5).abs() < 1e-12, "{t}");
        assert!((e.normal(r.at(t)) - DVec3::NEG_X).length() < 1e-12);
        let r = Ray::new(DVec3::new(1.0, 1.0, 9.0), DVec3::NEG_Z);
        let t = e.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - 7.0).abs() < 1e-12);
        assert!((e.normal(r.at(t)) - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn off_axis_normal_matches_gradient() {
        // x²/9 + y²/4 + z² = 1 about (1,1,1): at object point s, the normal ∝ (x/9, y/4, z).
        let e = egg();
        let s = DVec3::new(0.6, 0.0, 0.8);
        let p = DVec3::ONE + DVec3::new(3.0 * s.x, 2.0 * s.y, s.z);
        let expected = DVec3::new(3.0 * s.x / 9.0, 0.0, s.z).normalize();
        assert!((e.normal(p) - expected).length() < 1e-12);
    }

    #[test]
    fn inside_miss_range() {
        let e = egg();
        let r = Ray::new(DVec3::new(1.0, 1.0, 1.0), DVec3::new(0.0, 0.5, 0.0));
        assert_eq!(e.intersect(&r, 0.0, f64::INFINITY), Some(4.0));
        assert_eq!(e.intersect(&r, 0.0, 4.0), None);
        let miss = Ray::new(DVec3::new(-9.0, 3.01, 1.0), DVec3::X);
        assert_eq!(e.intersect(&miss, 0.0, f64::INFINITY), None);
        let r = Ray::new(DVec3::new(-9.0, 1.0, 1.0), DVec3::X);
        assert_eq!(
            e.intersect(&r, 7.0, f64::INFINITY).map(|t| t.round()),
            Some(13.0)
        );
    }

    #[test]
    fn sheared_axes_contain_the_sphere_image() {
        let e = Ellipsoid::new(
            DVec3::new(0.5, -1.0, 2.0),
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(0.0, 1.0, 0.7),
            DVec3::new(0.2, 0.0, 0.4),
        )
        .unwrap();
        // Each c ± u etc. is on the surface: rays from the centre along u hit at t = 1.
        for a in [
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(0.0, 1.0, 0.7),
            DVec3::new(0.2, 0.0, 0.4),
        ] {
            let r = Ray::new(DVec3::new(0.5, -1.0, 2.0), -a);
            let t = e.intersect(&r, 1e-9, f64::INFINITY).unwrap();
            assert!((t - 1.0).abs() < 1e-12);
            let n = e.normal(r.at(t));
            assert!(n.dot(-a) > 0.0 && (n.length() - 1.0).abs() < 1e-12);
            assert!(e.bounds().contains(r.at(t)));
        }
        assert!(e.normal(DVec3::new(0.5, -1.0, 2.0)).is_finite());
    }

    #[test]
    fn rejects_flat_ellipsoids() {
        let e = Ellipsoid::new(DVec3::ZERO, DVec3::X, DVec3::Y, 2.0 * DVec3::Y).unwrap_err();
        assert!(e.0.contains("flat"), "{e}");
        assert!(Ellipsoid::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::splat(f64::NAN)).is_err());
    }
}
