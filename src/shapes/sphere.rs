//! A sphere given by centre and radius, and the careful ray–sphere quadratic that the sphere
//! and the ellipsoid share.

use super::{all_finite, Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray, SolidEllipsoid};

/// How close, relative to the magnitude of the coordinates involved, a ray origin must be to a
/// surface to count as lying on it (its root is then reported as exactly `t = 0`). Covers the
/// rounding of hit points computed by `origin + t·dir` from origins up to ~50× farther away
/// than the hit; only origins within ~1.4e-14 × |coordinates| of the surface are affected.
pub(crate) const SURFACE_SNAP: f64 = 64.0 * f64::EPSILON;

/// Relative padding of the bounding boxes of the bounded primitives (see [`Aabb::padded`]).
pub(crate) const BOUNDS_PAD: f64 = 1e-9;

/// Both parameters `t0 ≤ t1` (in units of `d`) at which the line `o + t·d` meets the sphere
/// `|p| = r` centred at the origin, or `None` when the line misses it (or `d` is zero).
///
/// Numerically careful: the discriminant is computed from the line's perpendicular distance to
/// the centre (no cancellation for far, small spheres) and the two roots as `q/a` and `c/q`
/// (no cancellation between `-b` and `√disc`). `origin_err` is an absolute bound on the error
/// already in `o` (from a subtraction or a change of frame); when `o` lies on the sphere within
/// that error plus this function's own rounding, the root belonging to the origin is returned
/// as exactly `0`, so a ray leaving the surface never re-hits its own origin.
pub(crate) fn sphere_roots(o: DVec3, d: DVec3, r: f64, origin_err: f64) -> Option<(f64, f64)> {
    let a = d.length_squared();
    if !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let half_b = o.dot(d);
    let r2 = r * r;
    // b²/4 − a·c = a·(r² − |perpendicular part of o|²): exact-ish even when |o| ≫ r.
    let perp = o - (half_b / a) * d;
    let disc = a * (r2 - perp.length_squared());
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let q = -(half_b + disc.sqrt().copysign(half_b));
    let oo = o.length_squared();
    let mut c = oo - r2;
    let c_err = 32.0 * f64::EPSILON * (oo + r2) + 2.0 * oo.sqrt() * origin_err;
    if c.abs() <= c_err {
        c = 0.0;
    }
    if q == 0.0 {
        // Only when half_b = 0 and disc = 0: a tangent line through the closest point o.
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q / a, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// The first of the sorted roots strictly inside `(t_min, t_max)`.
pub(crate) fn first_root_in(roots: (f64, f64), t_min: f64, t_max: f64) -> Option<f64> {
    [roots.0, roots.1]
        .into_iter()
        .find(|&t| t > t_min && t < t_max)
}

/// The sphere `|p − centre| = radius`; outside is away from the centre.
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    centre: DVec3,
    radius: f64,
}

impl Sphere {
    /// A sphere; `centre` must be finite and `radius` finite and > 0 (world units).
    pub fn new(centre: DVec3, radius: f64) -> Result<Self, ShapeError> {
        if !all_finite(&[centre]) {
            return Err(ShapeError(format!(
                "the sphere's centre must be a finite point, not ({}, {}, {})",
                centre.x, centre.y, centre.z
            )));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(ShapeError(format!(
                "the sphere's radius must be a finite number greater than 0, not {radius}"
            )));
        }
        Ok(Self { centre, radius })
    }

    /// The centre (world space).
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// The radius (world units).
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

impl Shape for Sphere {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let oc = ray.origin - self.centre;
        // Rounding in the subtraction above and in the origin itself (see SURFACE_SNAP).
        let origin_err =
            SURFACE_SNAP * (ray.origin.abs().max_element() + self.centre.abs().max_element());
        let roots = sphere_roots(oc, ray.dir, self.radius, origin_err)?;
        first_root_in(roots, t_min, t_max)
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        // Dividing by the radius first keeps tiny spheres away from underflow.
        let n = ((p - self.centre) / self.radius).normalize_or_zero();
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
        .padded(BOUNDS_PAD)
    }

    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        vec![SolidEllipsoid::axis_aligned(
            self.centre,
            DVec3::splat(self.radius + BOUNDS_PAD),
        )]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Sphere {
        Sphere::new(DVec3::ZERO, 1.0).unwrap()
    }

    #[test]
    fn hit_from_outside_known_t_and_normal() {
        let s = Sphere::new(DVec3::new(1.0, 2.0, 3.0), 2.0).unwrap();
        let r = Ray::new(DVec3::new(1.0, 2.0, -7.0), DVec3::Z);
        let t = s.intersect(&r, 1e-9, f64::INFINITY).unwrap();
        assert!((t - 8.0).abs() < 1e-12);
        let n = s.normal(r.at(t));
        assert!((n - DVec3::NEG_Z).length() < 1e-12);
    }

    #[test]
    fn non_unit_direction_scales_t() {
        let s = unit();
        let r = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::new(4.0, 0.0, 0.0));
        let t = s.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-14);
        let tiny = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::new(1e-3, 0.0, 0.0));
        let t = s.intersect(&tiny, 0.0, f64::INFINITY).unwrap();
        assert!((t - 4000.0).abs() < 1e-9);
    }

    #[test]
    fn misses_and_behind() {
        let s = unit();
        let r = Ray::new(DVec3::new(-5.0, 1.0001, 0.0), DVec3::X);
        assert_eq!(s.intersect(&r, 0.0, f64::INFINITY), None);
        let behind = Ray::new(DVec3::new(5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(s.intersect(&behind, 0.0, f64::INFINITY), None);
    }

    #[test]
    fn from_inside_returns_exit() {
        let s = unit();
        let r = Ray::new(DVec3::new(0.0, 0.5, 0.0), DVec3::new(0.0, 2.0, 0.0));
        let t = s.intersect(&r, 1e-9, f64::INFINITY).unwrap();
        assert!((t - 0.25).abs() < 1e-15);
        assert!((s.normal(r.at(t)) - DVec3::Y).length() < 1e-15);
    }

    #[test]
    fn t_range_is_respected() {
        let s = unit();
        let r = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(s.intersect(&r, 0.0, 4.0), None); // exactly at t_max: excluded
        assert_eq!(s.intersect(&r, 0.0, 3.9), None);
        assert_eq!(s.intersect(&r, 4.0, 10.0), Some(6.0)); // t_min skips the entry
        assert_eq!(s.intersect(&r, 6.0, 10.0), None);
    }

    #[test]
    fn ray_leaving_the_surface_does_not_rehit_its_origin() {
        let s = Sphere::new(DVec3::new(0.3, -0.2, 0.1), 0.7).unwrap();
        for i in 0..200 {
            let a = i as f64 * 0.1;
            let b = i as f64 * 0.37;
            let dir = DVec3::new(a.cos() * b.sin(), a.sin() * b.sin(), b.cos());
            let p = s.centre() + s.radius() * dir;
            let n = s.normal(p);
            // Grazing outward ray: nearly tangent.
            let out = (n * 1e-7 + n.any_orthogonal_vector()).normalize();
            assert_eq!(s.intersect(&Ray::new(p, out), 0.0, f64::INFINITY), None);
            // Inward ray: only the far side.
            let inward = Ray::new(p, -n);
            let t = s.intersect(&inward, 0.0, f64::INFINITY).unwrap();
            assert!((t - 1.4).abs() < 1e-12, "{t}");
        }
    }

    #[test]
    fn tangent_ray_hits_at_most_at_touch_point() {
        let s = unit();
        let r = Ray::new(DVec3::new(-3.0, 1.0, 0.0), DVec3::X);
        if let Some(t) = s.intersect(&r, 0.0, f64::INFINITY) {
            assert!((t - 3.0).abs() < 1e-6);
        }
    }

    #[test]
    fn small_far_sphere_is_accurate() {
        // The textbook b² − 4ac loses everything here: b² ≈ 1e10, disc ≈ 1e-6.
        let r = 1e-3;
        let s = Sphere::new(DVec3::new(1e5, 0.0, 0.0), r).unwrap();
        let h = 0.5 * r;
        let ray = Ray::new(DVec3::new(0.0, h, 0.0), DVec3::X);
        let t = s.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        let expected = 1e5 - (r * r - h * h).sqrt();
        assert!((t - expected).abs() < 1e-10, "{t} vs {expected}");
        let p = ray.at(t);
        assert!(((p - s.centre()).length() - r).abs() < 1e-10);
    }

    #[test]
    fn normal_is_never_nan() {
        let s = unit();
        assert_eq!(s.normal(DVec3::ZERO), DVec3::Z);
        let n = s.normal(DVec3::new(1e-300, 0.0, 0.0));
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Sphere::new(DVec3::ZERO, 0.0).is_err());
        assert!(Sphere::new(DVec3::ZERO, -1.0).is_err());
        assert!(Sphere::new(DVec3::ZERO, f64::NAN).is_err());
        assert!(Sphere::new(DVec3::ZERO, f64::INFINITY).is_err());
        let e = Sphere::new(DVec3::new(f64::NAN, 0.0, 0.0), 1.0).unwrap_err();
        assert!(e.0.contains("centre"), "{e}");
    }

    #[test]
    fn padding_grows_finite_boxes_only() {
        let b = Aabb::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(2.0, 2.0, 5.0)).padded(1e-3);
        let m = 1e-3 * (2.0 + 5.0);
        assert!((b.min - DVec3::new(1.0 - m, 2.0 - m, 3.0 - m)).length() < 1e-15);
        assert!((b.max - DVec3::new(2.0 + m, 2.0 + m, 5.0 + m)).length() < 1e-15);
        assert_eq!(Aabb::EMPTY.padded(1e-3), Aabb::EMPTY);
        assert_eq!(Aabb::EVERYTHING.padded(1e-3), Aabb::EVERYTHING);
    }

    #[test]
    fn bounds_contain_the_sphere() {
        let s = Sphere::new(DVec3::new(1.0, -2.0, 3.0), 0.5).unwrap();
        let b = s.bounds();
        for p in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ] {
            assert!(b.contains(s.centre() + 0.5 * p));
        }
    }
}
