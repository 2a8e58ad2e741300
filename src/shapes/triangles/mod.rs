//! `MESH`: a triangle mesh read from a file (STL, OBJ, PLY: [`read`]) and placed by a
//! position and a basis, with its own bounding volume hierarchy over the triangles
//! ([`crate::bvh::Bvh`], the same code as the scene's over its objects).
//!
//! Ray–triangle tests are watertight (the ray-space shear of Woop, Benthin and Wald, 2013:
//! the edge functions of an edge two triangles share are each other's exact negation, so a
//! ray through a shared edge or corner meets at least one of the triangles). Normals face
//! the side from which the triangle's corners run counter-clockwise (the outside of a closed
//! mesh written by `kardia mesh`), flat per triangle or smooth: interpolated from normals at
//! the corners, each the area-weighted mean of the triangles about that corner whose normals
//! turn by less than [`CREASE_DEGREES`] from the triangle's own, so creases stay sharp.

pub mod read;

use super::placed::{ObjectShape, Placed, Placement, PlacementNames};
use super::{ShapeError, LANES};
use crate::bvh::Bvh;
use crate::geometry::{Aabb, DVec3, Ray, RayLanes};
use std::path::Path;

/// Neighbouring triangles whose normals turn by more than this many degrees are not smoothed
/// into each other (smooth normals keep the crease between them).
pub const CREASE_DEGREES: f64 = 50.0;

/// Each triangle's box in the hierarchy is grown by this fraction of its extent and
/// coordinates ([`Aabb::padded`]).
const TRIANGLE_BOX_PAD: f64 = 1e-9;

/// How a mesh's normals are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MeshNormals {
    /// Each triangle's own normal: the facets show.
    Flat,
    /// Interpolated across each triangle from its corners' normals, creases kept (the
    /// module doc).
    #[default]
    Smooth,
}

/// A triangle mesh placed in the world: `position + M·p` for each object-space point `p` of
/// the file, `M = [u v w]`.
pub type MeshShape = Placed<Triangles>;

/// The object space of a [`MeshShape`]: the triangles, their hierarchy and their normals.
#[derive(Clone)]
pub struct Triangles {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Smooth normals: per triangle, the (unnormalised) normal at each corner.
    corner_normals: Option<Vec<[DVec3; 3]>>,
    bvh: Bvh,
    bounds: Aabb,
    /// The SHA-256 (hex) of the file the mesh was read from, if it was read from one.
    source_digest: Option<String>,
}

impl std::fmt::Debug for Triangles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Triangles")
            .field("vertices", &self.vertices.len())
            .field("triangles", &self.triangles.len())
            .field("smooth", &self.corner_normals.is_some())
            .finish()
    }
}

impl MeshShape {
    /// The mesh of the file at `path` (see [`read::read_mesh_file`]) placed at `position`
    /// with basis `u`, `v`, `w` (finite, linearly independent).
    pub fn from_file(
        path: &Path,
        [position, u, v, w]: [DVec3; 4],
        normals: MeshNormals,
    ) -> Result<Self, ShapeError> {
        let (data, digest) = read::read_mesh_file_with_digest(path)
            .map_err(|e| ShapeError(format!("cannot read the mesh file {e}")))?;
        let mut triangles = Triangles::new(data.vertices, data.triangles, normals)?;
        triangles.source_digest = Some(digest);
        Self::in_world(triangles, [position, u, v, w])
    }

    /// The mesh of `triangles` (indices into `vertices`, finite points) placed at `position`
    /// with basis `u`, `v`, `w`. Triangles of zero area are left out (no ray can hit them);
    /// an error when none is left or an index is out of range.
    pub fn new(
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        [position, u, v, w]: [DVec3; 4],
        normals: MeshNormals,
    ) -> Result<Self, ShapeError> {
        Self::in_world(
            Triangles::new(vertices, triangles, normals)?,
            [position, u, v, w],
        )
    }

    /// `triangles` placed at `position` with basis `u`, `v`, `w`.
    fn in_world(triangles: Triangles, [position, u, v, w]: [DVec3; 4]) -> Result<Self, ShapeError> {
        let names = PlacementNames {
            shape: "mesh",
            position: "position",
            vectors: "basis",
        };
        let at = Placement::named(position, u, v, w, names)?;
        Ok(Placed::place(at, triangles))
    }
}

impl Triangles {
    /// See [`MeshShape::new`].
    pub fn new(
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        normals: MeshNormals,
    ) -> Result<Self, ShapeError> {
        if let Some(p) = vertices.iter().find(|p| !p.is_finite()) {
            return Err(ShapeError(format!(
                "a vertex of the mesh is not finite: {p}"
            )));
        }
        let count = vertices.len();
        if let Some(t) = triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= count))
        {
            return Err(ShapeError(format!(
                "the triangle {t:?} names a vertex beyond the mesh's {count}"
            )));
        }
        let corners = |t: &[u32; 3]| t.map(|i| vertices[i as usize]);
        let triangles: Vec<[u32; 3]> = triangles
            .into_iter()
            .filter(|t| {
                let [a, b, c] = corners(t);
                (b - a).cross(c - a) != DVec3::ZERO
            })
            .collect();
        if triangles.is_empty() {
            return Err(ShapeError(
                "the mesh has no triangle of non-zero area".into(),
            ));
        }
        if u32::try_from(triangles.len()).is_err() {
            return Err(ShapeError("the mesh has too many triangles".into()));
        }
        let boxes: Vec<(u32, Aabb)> = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| (i as u32, Aabb::from_points(corners(t))))
            .collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, (_, t)| b.union(*t));
        // The hierarchy's slab tests round: a ray through a corner or along an edge could
        // miss the exact boxes of every triangle there, so each box is padded by a small
        // fraction of its size and position (as the scene pads its objects' boxes).
        let boxes: Vec<(u32, Aabb)> = boxes
            .into_iter()
            .map(|(i, b)| (i, b.padded(TRIANGLE_BOX_PAD)))
            .collect();
        let bvh = Bvh::new(&boxes);
        let corner_normals =
            (normals == MeshNormals::Smooth).then(|| corner_normals(&vertices, &triangles));
        Ok(Self {
            vertices,
            triangles,
            corner_normals,
            bvh,
            bounds,
            source_digest: None,
        })
    }

    /// The number of triangles (those of non-zero area).
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether it has no triangle (never: a mesh is refused without one).
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The object-space box of the triangles.
    pub fn object_bounds(&self) -> Aabb {
        self.bounds
    }

    fn corners(&self, t: u32) -> [DVec3; 3] {
        self.triangles[t as usize].map(|i| self.vertices[i as usize])
    }

    /// The nearest triangle's `t` in `(t_min, t_max)` along the object-space ray `ray`.
    fn nearest(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let shear = Shear::of(ray);
        let mut hit = None;
        self.bvh.walk(ray, t_min, t_max, |id, t_max| {
            if let Some(t) = shear.hit(self.corners(id), t_min, *t_max) {
                *t_max = t;
                hit = Some(t);
            }
        });
        hit
    }

    /// The triangle nearest to the object-space point `q` and the closest point on it.
    fn triangle_at(&self, q: DVec3) -> Option<(u32, DVec3)> {
        // Every triangle whose box meets a short segment through q (along a direction with
        // no zero component); widened until one is found.
        let size = (self.bounds.max - self.bounds.min)
            .max_element()
            .max(1e-300);
        let probe = Ray::new(q, DVec3::new(1.0, 0.8, 0.6));
        let mut reach = 1e-9 * size;
        while reach <= 4.0 * size {
            let mut best: Option<(u32, DVec3, f64)> = None;
            self.bvh.walk(&probe, -reach, reach, |id, _| {
                let c = closest_on_triangle(q, self.corners(id));
                let d = (c - q).length_squared();
                if best.is_none_or(|b| d < b.2) {
                    best = Some((id, c, d));
                }
            });
            if let Some((id, c, _)) = best {
                return Some((id, c));
            }
            reach *= 1000.0;
        }
        None
    }

    /// The object-space normal (any length, facing the counter-clockwise side) at `q`.
    fn object_normal(&self, q: DVec3) -> DVec3 {
        let Some((id, c)) = self.triangle_at(q) else {
            return DVec3::Z;
        };
        let [a, b, d] = self.corners(id);
        let flat = (b - a).cross(d - a);
        let Some(normals) = &self.corner_normals else {
            return flat;
        };
        let [wa, wb, wd] = barycentric(c, [a, b, d]);
        let n = normals[id as usize];
        let smooth = n[0] * wa + n[1] * wb + n[2] * wd;
        // Interpolated normals never face against the triangle they are on.
        if smooth.dot(flat) > 0.0 {
            smooth
        } else {
            flat
        }
    }
}

/// Per triangle, each corner's normal: the area-weighted sum of the normals of the triangles
/// about that vertex that turn by less than [`CREASE_DEGREES`] from this triangle's normal.
fn corner_normals(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Vec<[DVec3; 3]> {
    let face: Vec<DVec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    let mut about: Vec<Vec<u32>> = vec![Vec::new(); vertices.len()];
    for (k, t) in triangles.iter().enumerate() {
        for &v in t {
            about[v as usize].push(k as u32);
        }
    }
    let cos_crease = CREASE_DEGREES.to_radians().cos();
    triangles
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let own = face[k].normalize();
            t.map(|v| {
                about[v as usize]
                    .iter()
                    .map(|&j| face[j as usize])
                    .filter(|n| n.normalize().dot(own) >= cos_crease)
                    .sum::<DVec3>()
            })
        })
        .collect()
}

/// The weights of the corners `a`, `b`, `c` at the point `p` of their plane (summing to 1).
fn barycentric(p: DVec3, [a, b, c]: [DVec3; 3]) -> [f64; 3] {
    let (e0, e1, e2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (e2.dot(e0), e2.dot(e1));
    let denom = d00 * d11 - d01 * d01;
    if denom.is_nan() || denom <= 0.0 {
        return [1.0 / 3.0; 3];
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    [1.0 - v - w, v, w]
}

/// A ray's watertight-test setup: the axis along which it runs most (`kz`), the two others
/// in an order that keeps the winding, and the shear that makes it run along `kz`.
#[derive(Debug, Clone, Copy)]
struct Shear {
    origin: DVec3,
    axes: [usize; 3],
    s: DVec3,
}

impl Shear {
    fn of(ray: &Ray) -> Self {
        let d = ray.dir;
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            origin: ray.origin,
            axes: [kx, ky, kz],
            s: DVec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        }
    }

    /// The ray's `t` at the triangle `[a, b, c]` if it meets it in `(t_min, t_max)`.
    #[inline]
    fn hit(&self, [a, b, c]: [DVec3; 3], t_min: f64, t_max: f64) -> Option<f64> {
        let [kx, ky, kz] = self.axes;
        let (a, b, c) = (a - self.origin, b - self.origin, c - self.origin);
        let (ax, ay) = (a[kx] - self.s.x * a[kz], a[ky] - self.s.y * a[kz]);
        let (bx, by) = (b[kx] - self.s.x * b[kz], b[ky] - self.s.y * b[kz]);
        let (cx, cy) = (c[kx] - self.s.x * c[kz], c[ky] - self.s.y * c[kz]);
        // Edge functions of the edges b c, c a, a b: the same products for a shared edge
        // in either direction, so exactly opposite signs.
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        let t = (u * a[kz] + v * b[kz] + w * c[kz]) * self.s.z / det;
        (t > t_min && t < t_max).then_some(t)
    }
}

impl ObjectShape for Triangles {
    fn source_digest(&self) -> Option<String> {
        self.source_digest.clone()
    }

    fn intersect(
        &self,
        _: &Placement,
        _: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64> {
        self.nearest(local, t_min, t_max)
    }

    fn intersect_lanes(
        &self,
        _: &Placement,
        _: &[Ray; LANES],
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        // One walk for the four rays; each lane keeps its nearest hit, so each lane's answer
        // is the least t among the triangles its own walk would meet: `intersect`'s.
        let shear: [Shear; LANES] = std::array::from_fn(|i| Shear::of(&local[i]));
        let live: [bool; LANES] = std::array::from_fn(|i| t_max[i] > t_min[i]);
        let mut hit = [None; LANES];
        let idle = t_min.map(|t| t - 1.0);
        let start: [f64; LANES] = std::array::from_fn(|i| if live[i] { t_max[i] } else { idle[i] });
        self.bvh
            .walk_lanes(&RayLanes::new(local), t_min, start, |id, t_max| {
                let corners = self.corners(id);
                for i in 0..LANES {
                    if live[i] && t_max[i] > t_min[i] {
                        if let Some(t) = shear[i].hit(corners, t_min[i], t_max[i]) {
                            t_max[i] = t;
                            hit[i] = Some(t);
                        }
                    }
                }
            });
        hit
    }

    fn normal(&self, at: &Placement, q: DVec3) -> DVec3 {
        at.normal_to_world(self.object_normal(q))
    }

    fn bounds(&self, at: &Placement) -> Aabb {
        at.bounds_to_world(&self.bounds)
    }
}

/// The point of the triangle `a b c` nearest to `p` (by the regions of the triangle's
/// corners, edges and face).
pub fn closest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;

    /// An octahedron of "radius" 1 about the origin, faces outward.
    fn octahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let v = vec![
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ];
        let mut t = Vec::new();
        for (x, y) in [(0, 2), (2, 1), (1, 3), (3, 0)] {
            t.push([x, y, 4]);
            t.push([y, x, 5]);
        }
        (v, t)
    }

    fn placed(normals: MeshNormals, frame: [DVec3; 4]) -> MeshShape {
        let (v, t) = octahedron();
        MeshShape::new(v, t, frame, normals).unwrap()
    }

    const UNIT: [DVec3; 4] = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];

    #[test]
    fn the_closest_point_is_found_in_every_region() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let cases = [
            (DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, 0.0)),
            (DVec3::new(-1.0, -1.0, 0.0), DVec3::ZERO),
            (DVec3::new(2.0, -0.5, 0.3), DVec3::X),
            (DVec3::new(0.5, -1.0, 0.0), DVec3::new(0.5, 0.0, 0.0)),
            (DVec3::new(-1.0, 0.5, 0.0), DVec3::new(0.0, 0.5, 0.0)),
            (DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.5, 0.5, 0.0)),
            (DVec3::new(-0.5, 3.0, 0.0), DVec3::Y),
        ];
        for (p, want) in cases {
            assert!((closest_on_triangle(p, t) - want).length() < 1e-15, "{p}");
        }
    }

    #[test]
    fn rays_hit_the_octahedron_where_its_plane_is_with_outward_flat_normals() {
        let m = placed(MeshNormals::Flat, UNIT);
        // Towards the face x + y + z = 1 from far along the diagonal.
        let r = Ray::new(DVec3::splat(5.0), DVec3::splat(-1.0));
        let t = m.intersect(&r, 0.0, f64::INFINITY).unwrap();
        assert!((t - (5.0 - 1.0 / 3.0)).abs() < 1e-12, "{t}");
        let n = m.normal(r.at(t));
        assert!((n - DVec3::ONE.normalize()).length() < 1e-12, "{n}");
        // From inside, the far face; a range that ends before it, nothing.
        let inside = Ray::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(m.intersect(&inside, 0.0, f64::INFINITY), Some(0.5));
        assert_eq!(m.intersect(&inside, 0.0, 0.5), None);
        assert_eq!(
            m.intersect(&Ray::new(DVec3::splat(5.0), DVec3::X), 0.0, 1e9),
            None
        );
    }

    #[test]
    fn rays_through_shared_edges_and_corners_never_slip_through() {
        // Rays from outside through a point of an edge or a corner into the inside: each must
        // meet the octahedron at that point (t = 2/3), not slip between its triangles.
        let m = placed(MeshNormals::Flat, UNIT);
        let targets = [
            DVec3::X,
            DVec3::Z,
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.0, 0.25, 0.75),
            DVec3::new(-0.5, 0.0, -0.5),
            DVec3::new(0.1, -0.9, 0.0),
        ];
        for target in targets {
            for k in 0..200 {
                let b = k as f64 * 0.37;
                let inside = 0.4 * DVec3::new(b.cos(), b.sin(), 0.5 * (2.0 * b).sin());
                let from = target + 2.0 * (target - inside);
                let r = Ray::new(from, inside - from);
                let t = m.intersect(&r, 0.0, f64::INFINITY);
                assert!(
                    t.is_some_and(|t| (t - 2.0 / 3.0).abs() < 1e-12),
                    "{target} from {from}: {t:?}"
                );
            }
        }
    }

    #[test]
    fn a_placement_moves_the_mesh_and_its_normals_and_lanes_agree() {
        // Stretched along x by 2, mirrored in y, moved to (10, 0, 0).
        let frame = [
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::X * 2.0,
            DVec3::NEG_Y,
            DVec3::Z,
        ];
        for normals in [MeshNormals::Flat, MeshNormals::Smooth] {
            let m = placed(normals, frame);
            // World (x, 0.2, 0.1) is object (·, −0.2, 0.1), on the face −x − y + z = 1 at
            // object x = −0.7, world x = 10 − 1.4.
            let r = Ray::new(DVec3::new(0.0, 0.2, 0.1), DVec3::X);
            let t = m.intersect(&r, 0.0, f64::INFINITY).unwrap();
            assert!((t - 8.6).abs() < 1e-12, "{t}");
            // The object normal (−1, −1, 1) by M⁻ᵀ = diag(½, −1, 1).
            let n = m.normal(r.at(t));
            assert!(
                (n - DVec3::new(-1.0, 2.0, 2.0) / 3.0).length() < 1e-12,
                "{n}"
            );
            let b = m.bounds();
            assert!(
                (b.min - DVec3::new(8.0, -1.0, -1.0)).length() < 1e-6,
                "{b:?}"
            );
            let rays: [Ray; LANES] = std::array::from_fn(|i| {
                Ray::new(
                    DVec3::new(0.0, 0.1 * i as f64, -0.2),
                    DVec3::new(1.0, 0.01, 0.03 * i as f64),
                )
            });
            let t_min = [0.0, 0.0, 9.0, 0.0];
            let t_max = [f64::INFINITY, 8.5, f64::INFINITY, 0.0];
            let lanes = m.intersect_lanes(&rays, t_min, t_max);
            for i in 0..LANES {
                assert_eq!(
                    lanes[i],
                    m.intersect(&rays[i], t_min[i], t_max[i]),
                    "lane {i}"
                );
            }
            assert!(lanes[0].is_some() && lanes[2].is_some() && lanes[3].is_none());
        }
    }

    #[test]
    fn smooth_normals_follow_the_corners_and_keep_creases() {
        // On the octahedron every neighbour turns by about 71°, more than the crease: smooth
        // normals are the flat ones.
        let flat = placed(MeshNormals::Flat, UNIT);
        let smooth = placed(MeshNormals::Smooth, UNIT);
        let p = DVec3::new(0.5, 0.3, 0.2);
        assert!((flat.normal(p) - smooth.normal(p)).length() < 1e-12);
        // A gently folded strip: at the fold the normal is the mean of the two sides.
        let v = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.2),
            DVec3::new(1.0, 1.0, 0.2),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
        ];
        let t = vec![[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]];
        let strip = MeshShape::new(v, t, UNIT, MeshNormals::Smooth).unwrap();
        let n = strip.normal(DVec3::new(1.0, 0.5, 0.2));
        assert!((n - DVec3::Z).length() < 1e-12, "{n}");
        let n = strip.normal(DVec3::new(0.5, 0.5, 0.1));
        assert!(n.x < 0.0 && n.z > 0.9, "{n}");
    }

    #[test]
    fn bad_meshes_are_refused() {
        let bad = |v: Vec<DVec3>, t: Vec<[u32; 3]>| {
            MeshShape::new(v, t, UNIT, MeshNormals::Flat).unwrap_err().0
        };
        assert!(bad(vec![DVec3::ZERO; 3], vec![[0, 1, 2]]).contains("non-zero area"));
        assert!(bad(vec![DVec3::ZERO; 3], vec![[0, 1, 3]]).contains("beyond"));
        let nan = vec![DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)];
        assert!(bad(nan, vec![[0, 1, 2]]).contains("finite"));
        let (v, t) = octahedron();
        let flat = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X];
        assert!(MeshShape::new(v, t, flat, MeshNormals::Flat).is_err());
    }
}
