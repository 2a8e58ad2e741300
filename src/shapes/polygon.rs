//! A planar polygon, convex or not.

use super::plane::plane_gap;
use super::sphere::BOUNDS_PAD;
use super::{Shape, ShapeError};
use crate::geometry::{Aabb, DVec3, Ray};
use glam::DVec2;

/// A flat polygon with at least 3 coplanar vertices, convex or not; its normal follows the
/// right-hand rule on the vertex order (counter-clockwise seen from the front).
///
/// The inside is decided by the even–odd (crossing-number) rule in the polygon's plane, so a
/// self-crossing outline alternates between filled and empty regions.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<DVec3>,
    /// Unit normal (right-hand rule), from Newell's method.
    normal: DVec3,
    /// Centroid of the vertices: a point on the polygon's (best-fit) plane.
    centre: DVec3,
    /// Orthonormal in-plane axes.
    axes: (DVec3, DVec3),
    /// The vertices in the plane's 2-D coordinates, relative to `centre`.
    outline: Vec<DVec2>,
}

impl Polygon {
    /// How far a vertex may lie off the polygon's best-fit plane: this fraction of the
    /// polygon's size (the diagonal of its bounding box).
    pub const PLANARITY_TOLERANCE: f64 = 1e-6;

    /// The smallest area accepted, as a fraction of size² (size = bounding-box diagonal); a
    /// polygon below it is treated as having no area (e.g. all vertices on one line).
    pub const MIN_AREA_RATIO: f64 = 1e-10;

    /// A polygon through `vertices` in order (the last joins back to the first). Fails, with a
    /// message for the scene author, for fewer than 3 vertices, non-finite ones, a polygon
    /// without area (all vertices on one line, or an outline whose parts cancel), or vertices
    /// farther than [`Self::PLANARITY_TOLERANCE`] × size from one plane.
    pub fn new(vertices: Vec<DVec3>) -> Result<Self, ShapeError> {
        let n = vertices.len();
        if n < 3 {
            return Err(ShapeError(format!(
                "a polygon needs at least 3 vertices, but this one has {n}"
            )));
        }
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            let v = vertices[i];
            return Err(ShapeError(format!(
                "vertex {} of the polygon is not a finite point: ({}, {}, {})",
                i + 1,
                v.x,
                v.y,
                v.z
            )));
        }
        let bbox = Aabb::from_points(vertices.iter().copied());
        let size = (bbox.max - bbox.min).length();
        if !(size > 0.0 && size.is_finite()) {
            return Err(ShapeError(if size > 0.0 {
                "the polygon's vertices are too far apart to be handled in floating point".into()
            } else {
                format!("all {n} vertices of the polygon are the same point")
            }));
        }
        let centre = centroid(&vertices);
        let area_vec = newell(&vertices, centre);
        // |area_vec| is twice the (projected) area.
        if area_vec.length() * 0.5 <= Self::MIN_AREA_RATIO * size * size {
            return Err(ShapeError(if collinear(&vertices, size) {
                "the polygon has no area: all its vertices lie on one line".into()
            } else {
                "the polygon has no area: its outline crosses itself so that the parts \
                 cancel out (like a figure of eight with equal loops)"
                    .into()
            }));
        }
        let normal = area_vec.normalize();
        let tol = Self::PLANARITY_TOLERANCE * size;
        let off = |v: DVec3| (v - centre).dot(normal).abs();
        if vertices.iter().any(|&v| off(v) > tol) {
            return Err(non_planar(&vertices, size, tol));
        }
        let axes = normal.any_orthonormal_pair();
        let outline = vertices
            .iter()
            .map(|&v| {
                let r = v - centre;
                DVec2::new(r.dot(axes.0), r.dot(axes.1))
            })
            .collect();
        Ok(Self {
            vertices,
            normal,
            centre,
            axes,
            outline,
        })
    }

    /// The vertices, in the order given (world space).
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The unit normal: right-hand rule on the vertex order.
    pub fn unit_normal(&self) -> DVec3 {
        self.normal
    }
}

/// Mean of the points.
fn centroid(vs: &[DVec3]) -> DVec3 {
    vs.iter().copied().sum::<DVec3>() / vs.len() as f64
}

/// Newell's area vector Σ (vᵢ − c) × (vᵢ₊₁ − c): twice the vector area of the closed outline,
/// pointing by the right-hand rule. Taken about `c` (a point near the polygon) for accuracy.
fn newell(vs: &[DVec3], c: DVec3) -> DVec3 {
    let mut sum = DVec3::ZERO;
    let mut prev = vs[vs.len() - 1] - c;
    for &v in vs {
        let cur = v - c;
        sum += prev.cross(cur);
        prev = cur;
    }
    sum
}

/// True when every vertex is within 1e-9 × size of the line through the first
/// vertex and the vertex farthest from it.
fn collinear(vs: &[DVec3], size: f64) -> bool {
    let a = vs[0];
    let far = vs
        .iter()
        .copied()
        .max_by(|p, q| (*p - a).length().total_cmp(&(*q - a).length()))
        .unwrap_or(a);
    let dir = (far - a).normalize_or_zero();
    vs.iter().all(|&v| {
        let r = v - a;
        (r - r.dot(dir) * dir).length() <= 1e-9 * size
    })
}

/// The error for vertices not in one plane. When removing a single vertex leaves the others
/// in a plane, that vertex is named with its distance from their plane; otherwise the vertex
/// farthest from the best-fit plane of all of them is named.
fn non_planar(vs: &[DVec3], size: f64, tol: f64) -> ShapeError {
    let mut culprit: Option<(usize, f64)> = None;
    if vs.len() >= 4 {
        for i in 0..vs.len() {
            let others: Vec<DVec3> = vs
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &v)| v)
                .collect();
            let c = centroid(&others);
            let a = newell(&others, c);
            if a.length() * 0.5 <= Polygon::MIN_AREA_RATIO * size * size {
                continue;
            }
            let n = a.normalize();
            if others.iter().all(|&v| (v - c).dot(n).abs() <= tol) {
                let d = (vs[i] - c).dot(n).abs();
                if culprit.is_none_or(|(_, best)| d > best) {
                    culprit = Some((i, d));
                }
            }
        }
    }
    if let Some((i, d)) = culprit {
        return ShapeError(format!(
            "the polygon's vertices are not in one plane: vertex {} is {} units off the plane \
             of the others (at most {} is allowed: {:e} × the polygon's size)",
            i + 1,
            short(d),
            short(tol),
            Polygon::PLANARITY_TOLERANCE
        ));
    }
    let c = centroid(vs);
    let n = newell(vs, c).normalize_or_zero();
    let (i, d) =
        vs.iter()
            .map(|&v| (v - c).dot(n).abs())
            .enumerate()
            .fold(
                (0, 0.0),
                |best, (i, d)| if d > best.1 { (i, d) } else { best },
            );
    ShapeError(format!(
        "the polygon's vertices are not in one plane: vertex {} is {} units off the plane that \
         best fits them all, and more than one vertex is off (at most {} is allowed: {:e} × the \
         polygon's size)",
        i + 1,
        short(d),
        short(tol),
        Polygon::PLANARITY_TOLERANCE
    ))
}

/// A length with about 4 significant digits, for messages.
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = 3 - x.abs().log10().floor() as i32;
    if (0..=8).contains(&digits) {
        let s = format!("{:.*}", digits as usize, x);
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.3e}")
    }
}

/// Even–odd test: does the closed outline enclose `q`? A horizontal ray from `q` towards +x
/// is crossed by each edge that straddles its line (half-open in y, so a vertex on the line is
/// counted once) at an x beyond `q`.
fn encloses(outline: &[DVec2], q: DVec2) -> bool {
    let mut inside = false;
    let mut prev = outline[outline.len() - 1];
    for &cur in outline {
        if (prev.y > q.y) != (cur.y > q.y) {
            let x = prev.x + (q.y - prev.y) * (cur.x - prev.x) / (cur.y - prev.y);
            if q.x < x {
                inside = !inside;
            }
        }
        prev = cur;
    }
    inside
}

impl Shape for Polygon {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None; // parallel: a ray in the polygon's plane does not hit it
        }
        let t = plane_gap(self.normal, self.centre, ray.origin) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let r = (ray.origin - self.centre) + t * ray.dir;
        let q = DVec2::new(r.dot(self.axes.0), r.dot(self.axes.1));
        encloses(&self.outline, q).then_some(t)
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        self.normal
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().copied()).padded(BOUNDS_PAD)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    /// An L in the plane z = 2: the notch is the square [1,2]×[1,2].
    fn ell() -> Polygon {
        Polygon::new(vec![
            v(0.0, 0.0, 2.0),
            v(2.0, 0.0, 2.0),
            v(2.0, 1.0, 2.0),
            v(1.0, 1.0, 2.0),
            v(1.0, 2.0, 2.0),
            v(0.0, 2.0, 2.0),
        ])
        .unwrap()
    }

    fn down_at(x: f64, y: f64) -> Ray {
        Ray::new(v(x, y, 7.0), v(0.0, 0.0, -0.5))
    }

    #[test]
    fn l_shape_hits_arms_and_misses_notch() {
        let p = ell();
        assert_eq!(p.unit_normal(), DVec3::Z);
        for (x, y) in [(0.5, 0.5), (1.5, 0.5), (0.5, 1.5), (0.01, 1.99)] {
            let t = p.intersect(&down_at(x, y), 0.0, f64::INFINITY);
            assert!((t.unwrap() - 10.0).abs() < 1e-12, "({x},{y})");
        }
        for (x, y) in [
            (1.5, 1.5),
            (1.01, 1.99),
            (2.5, 0.5),
            (-0.1, 1.0),
            (0.5, 2.01),
        ] {
            assert_eq!(p.intersect(&down_at(x, y), 0.0, f64::INFINITY), None);
        }
    }

    #[test]
    fn rays_level_with_vertices_are_classified_correctly() {
        // The 2-D test's horizontal line may pass exactly through vertices: the half-open rule
        // must count each crossing once, whichever in-plane axes were chosen.
        let p = ell();
        for (x, y) in [
            (0.5, 1.0),
            (1.0, 0.5),
            (0.25, 1.0),
            (1.0, 0.25),
            (0.999, 1.0),
        ] {
            assert_eq!(
                p.intersect(&down_at(x, y), 0.0, 99.0),
                Some(10.0),
                "({x},{y})"
            );
        }
        for (x, y) in [
            (2.5, 1.0),
            (-0.5, 1.0),
            (1.0, 2.5),
            (1.0, -0.5),
            (1.5, 1.001),
        ] {
            assert_eq!(p.intersect(&down_at(x, y), 0.0, 99.0), None, "({x},{y})");
        }
        // Exactly at a vertex or on an edge: either answer, but no panic and a sane t.
        for (x, y) in [(0.0, 0.0), (1.0, 1.0), (2.0, 0.5), (1.5, 1.0)] {
            if let Some(t) = p.intersect(&down_at(x, y), 0.0, 99.0) {
                assert!((t - 10.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn star_polygon_with_reflex_vertices() {
        // Five-pointed star (10 vertices), counter-clockwise seen from +z: normal +z.
        let pts: Vec<DVec3> = (0..10)
            .map(|i| {
                let a = std::f64::consts::PI * (0.5 + i as f64 / 5.0);
                let r = if i % 2 == 0 { 1.0 } else { 0.4 };
                v(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        let star = Polygon::new(pts).unwrap();
        assert!((star.unit_normal() - DVec3::Z).length() < 1e-12);
        let r = |x, y| Ray::new(v(x, y, -1.0), DVec3::Z);
        assert_eq!(star.intersect(&r(0.0, 0.0), 0.0, 9.0), Some(1.0));
        assert_eq!(star.intersect(&r(0.0, 0.9), 0.0, 9.0), Some(1.0)); // top point
        assert_eq!(star.intersect(&r(0.0, -0.5), 0.0, 9.0), None); // between bottom points
        assert_eq!(star.intersect(&r(0.5, 0.5), 0.0, 9.0), None); // between two points
    }

    #[test]
    fn normal_follows_vertex_order_and_range_is_respected() {
        let cw = Polygon::new(vec![v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(1.0, 0.0, 0.0)]).unwrap();
        assert_eq!(cw.unit_normal(), DVec3::NEG_Z);
        let r = Ray::new(v(0.2, 0.2, 1.0), v(0.0, 0.0, -4.0));
        assert_eq!(cw.intersect(&r, 0.0, f64::INFINITY), Some(0.25));
        assert_eq!(cw.normal(r.at(0.25)), DVec3::NEG_Z);
        assert_eq!(cw.intersect(&r, 0.0, 0.25), None);
        assert_eq!(cw.intersect(&r, 0.25, 1.0), None);
        let parallel = Ray::new(v(0.2, 0.2, 0.0), DVec3::X);
        assert_eq!(cw.intersect(&parallel, 0.0, f64::INFINITY), None);
        let behind = Ray::new(v(0.2, 0.2, 1.0), DVec3::Z);
        assert_eq!(cw.intersect(&behind, 0.0, f64::INFINITY), None);
    }

    #[test]
    fn tilted_polygon_far_from_origin() {
        let c = v(1e4, -2e4, 3e3);
        let (a, b) = v(1.0, 2.0, 2.0).normalize().any_orthonormal_pair();
        let quad = Polygon::new(vec![c, c + 3.0 * a, c + 3.0 * a + b, c + b]).unwrap();
        let n = quad.unit_normal();
        assert!((n - a.cross(b)).length() < 1e-9);
        let target = c + 1.5 * a + 0.5 * b;
        let r = Ray::new(
            target + 5.0 * n + v(0.1, 0.0, 0.0),
            -(5.0 * n + v(0.1, 0.0, 0.0)),
        );
        let t = quad.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-9);
        assert!(quad.bounds().contains(r.at(t)));
    }

    #[test]
    fn rejects_too_few_and_non_finite() {
        let e = Polygon::new(vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)]).unwrap_err();
        assert!(e.0.contains("at least 3 vertices"), "{e}");
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(f64::NAN, 1.0, 0.0),
        ])
        .unwrap_err();
        assert!(e.0.contains("vertex 3") && e.0.contains("finite"), "{e}");
        let e = Polygon::new(vec![DVec3::ONE; 4]).unwrap_err();
        assert!(e.0.contains("same point"), "{e}");
    }

    #[test]
    fn rejects_collinear_and_cancelling_outlines() {
        let e =
            Polygon::new(vec![v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), v(3.0, 3.0, 3.0)]).unwrap_err();
        assert!(e.0.contains("one line"), "{e}");
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(1.0, 1e-13, 0.0),
            v(5.0, 0.0, 0.0),
        ])
        .unwrap_err();
        assert!(e.0.contains("one line"), "{e}");
        // Figure of eight (bow tie) with equal loops.
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
        ])
        .unwrap_err();
        assert!(e.0.contains("crosses itself"), "{e}");
    }

    #[test]
    fn rejects_non_planar_naming_the_vertex() {
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.3),
        ])
        .unwrap_err();
        assert!(
            e.0.contains("vertex 4 is 0.3 units off the plane of the others"),
            "{e}"
        );
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.5),
            v(1.0, 0.0, 0.0),
            v(2.0, 0.5, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0),
        ])
        .unwrap_err();
        assert!(e.0.contains("vertex 1 is 0.5 units off"), "{e}");
        let e = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.2),
            v(2.0, 0.5, 0.0),
            v(1.0, 1.0, -0.2),
            v(0.0, 1.0, 0.0),
        ])
        .unwrap_err();
        assert!(e.0.contains("more than one vertex"), "{e}");
    }

    #[test]
    fn planarity_tolerance_scales_with_size() {
        for scale in [1e-6, 1.0, 1e6] {
            let ok = |dz: f64| {
                Polygon::new(vec![
                    v(0.0, 0.0, 0.0) * scale,
                    v(1.0, 0.0, 0.0) * scale,
                    v(1.0, 1.0, 0.0) * scale,
                    v(0.0, 1.0, dz) * scale,
                ])
                .is_ok()
            };
            assert!(ok(1e-7), "{scale}");
            assert!(!ok(1e-5), "{scale}");
        }
    }

    #[test]
    fn repeated_vertices_are_harmless() {
        let sq = Polygon::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(0.0, 0.0, 0.0),
        ])
        .unwrap();
        assert_eq!(sq.unit_normal(), DVec3::Z);
        let r = |x, y| Ray::new(v(x, y, 1.0), DVec3::NEG_Z);
        assert_eq!(sq.intersect(&r(0.5, 0.5), 0.0, 9.0), Some(1.0));
        assert_eq!(sq.intersect(&r(0.5, 1.5), 0.0, 9.0), None);
        assert_eq!(sq.intersect(&r(1.5, 0.0), 0.0, 9.0), None);
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.3), "0.3");
        assert_eq!(short(0.30000000000000004), "0.3");
        assert_eq!(short(1234.5678), "1235");
        assert_eq!(short(1.5e-12), "1.500e-12");
    }
}
