//! How far the mesh is from the exact surface, measured with the project's root finder.
//!
//! - Vertices: each surface or crease vertex's distance to the surface: the nearest root of `φ` on the
//!   line along `∇φ` or along any of the tetrahedra's 13 edge directions (the least of these
//!   bounds the distance from above).
//! - Mesh to surface: from the centroid of every triangle whose corners are all on the
//!   surface (or the crease), the nearest root of `φ` along the triangle's normal (or along
//!   `∇φ` if nearer); where neither line meets the surface within half the tolerance (beside
//!   a node, where the surface is a cone; a shell's wall beside a singular curve), the
//!   nearest along the 13 edge directions too, and the distance to where Newton steps from
//!   the centroid converge (a part of the zero set that is a curve or a point, which lines
//!   miss). A triangle with every corner on the crease may be a piece of the cap: the nearer
//!   of the surface and the clip sphere.
//! - Surface to mesh: points of the exact surface (every root of `φ` on lines parallel to
//!   the axes, half a grid step off the grid's own lines, inside the clip ball; for a shell,
//!   those that are points of its wall: [`Field::is_boundary_root`]), each one's distance to
//!   the nearest triangle.
//!
//! The larger of the two directed distances estimates the two-sided Hausdorff distance
//! between the surface part of the mesh and the surface (from samples: an estimate, not a
//! bound). Distances beyond the search reach are counted and reported as the reach.

use super::field::{Field, VertexKind};
use super::TriangleMesh;
use crate::bvh::Bvh;
use crate::geometry::{Aabb, DVec3};
use crate::roots::sturm_roots;
use crate::shapes::implicit::MAX_DEGREE;
pub use crate::shapes::triangles::closest_on_triangle;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// The directions of the tetrahedra's edges ([`super::bisection`]: the axes, the diagonals
/// of the faces and the main diagonals of cubes, every one of them, as the bisection's half
/// cubes are mirror images of each other).
const EDGE_DIRECTIONS: [DVec3; 13] = [
    DVec3::X,
    DVec3::Y,
    DVec3::Z,
    DVec3::new(1.0, 1.0, 0.0),
    DVec3::new(1.0, 0.0, 1.0),
    DVec3::new(0.0, 1.0, 1.0),
    DVec3::new(1.0, -1.0, 0.0),
    DVec3::new(1.0, 0.0, -1.0),
    DVec3::new(0.0, 1.0, -1.0),
    DVec3::ONE,
    DVec3::new(-1.0, 1.0, 1.0),
    DVec3::new(1.0, -1.0, 1.0),
    DVec3::new(1.0, 1.0, -1.0),
];

/// Distances measured between a mesh and the exact surface (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Deviation {
    /// The largest distance of a surface vertex from the surface.
    pub vertex: f64,
    /// Surface vertices measured.
    pub vertices: usize,
    /// Surface vertices with no surface point within the tolerance on any of those lines.
    pub vertices_beyond: usize,
    /// Surface vertices where no root was found on those lines but `f` is zero up to its
    /// rounding (at a node, a double root that rounding hides from the root finder).
    pub vertices_at_rounding: usize,
    /// The largest distance from a sampled point of the mesh to the surface.
    pub mesh_to_surface: f64,
    /// The largest distance from a sampled point of the surface to the mesh.
    pub surface_to_mesh: f64,
    /// Surface samples taken (points of the solid's boundary).
    pub surface_samples: usize,
    /// Roots of `φ` on the sampling lines left out because `φ` does not change sign there
    /// (a curve or point of `f = 0`, or a sheet along which `f` is a square: inside the
    /// solid or outside it, never on its boundary, so no mesh of the solid comes near it).
    pub touching_samples: usize,
    /// The largest distance either way ([`Deviation::hausdorff`]) left when the samples
    /// farther than the tolerance that lie where the solid, or a gap in it, is thinner than
    /// the grid's step ([`Deviation::thin_samples`]) are set aside.
    pub away_from_thin: f64,
    /// Samples (either way) farther than the tolerance at a place where the solid or a gap
    /// in it is thinner than the grid's step: a surface sample with another point of the
    /// boundary (or the clip sphere) within a step along `∇φ`, or at or within a step of a
    /// singular point of the surface; a triangle with the boundary on both sides within a
    /// step along its normal. The labels close or open such parts (beside a singular point
    /// or curve, where two sheets nearly touch, where the surface meets the clip sphere at
    /// a glancing angle), so they are counted apart from the rest.
    pub thin_samples: usize,
    /// The width below which a part counts as thin: the grid's step the samples are spaced
    /// by.
    pub thin_width: f64,
    /// Samples (either way) with nothing found within the search reach (counted at the reach).
    pub beyond_reach: usize,
    /// Whether the surface could be measured (its line polynomials have degree ≤ 16).
    pub measured: bool,
}

impl Deviation {
    /// The estimated two-sided Hausdorff distance: the larger directed distance.
    pub fn hausdorff(&self) -> f64 {
        self.mesh_to_surface.max(self.surface_to_mesh)
    }

    /// Whether every distance beyond `tolerance` is at a place thinner than the grid's step
    /// (and there is one): the estimate exceeds the tolerance only where the labels close
    /// or open a part.
    pub fn beyond_only_where_thin(&self, tolerance: f64) -> bool {
        self.thin_samples > 0 && self.away_from_thin <= tolerance
    }

    /// Every distance multiplied by `k` (object units to world units by the frame's stretch:
    /// an upper bound).
    pub fn scaled(mut self, k: f64) -> Self {
        self.vertex *= k;
        self.mesh_to_surface *= k;
        self.surface_to_mesh *= k;
        self.away_from_thin *= k;
        self.thin_width *= k;
        self
    }
}

/// Measures the object-space mesh of `field` (see the module doc). `tolerance`: the reach
/// for vertices, and twice the distance past which a triangle is measured along more lines;
/// `step`: the grid step (the surface samples' spacing; the reach of the other measurements
/// is twice it).
pub fn measure(
    field: &Field,
    mesh: &TriangleMesh,
    kinds: &[VertexKind],
    tolerance: f64,
    step: f64,
) -> Deviation {
    measure_cancellable(
        field,
        mesh,
        kinds,
        tolerance,
        step,
        &AtomicBool::new(false),
        &|_| {},
    )
    .expect("never cancelled")
}

/// The parts of [`measure_cancellable`] reported to its `part_done` (1, 2, 3: the vertices,
/// the mesh→surface side, the surface→mesh side).
pub const MEASURE_PARTS: usize = 3;

/// [`measure`], giving up (`None`) once `cancel` is set: every vertex, triangle and surface
/// sample reads it first, so a cancelled measurement stops within about one sample's work
/// per thread. `part_done(k)` is called as each of the [`MEASURE_PARTS`] parts ends.
pub fn measure_cancellable(
    field: &Field,
    mesh: &TriangleMesh,
    kinds: &[VertexKind],
    tolerance: f64,
    step: f64,
    cancel: &AtomicBool,
    part_done: &(dyn Fn(usize) + Sync),
) -> Option<Deviation> {
    if field.degree() > MAX_DEGREE {
        return Some(Deviation::default());
    }
    let cancelled = || cancel.load(Ordering::Relaxed);
    let reach = 2.0 * step;
    let h = 1e-7 * field.radius();
    let surface_vertices: Vec<usize> = (0..mesh.vertices.len())
        .filter(|&v| kinds[v].on_surface())
        .collect();
    let vertex_distances: Vec<Option<f64>> = surface_vertices
        .par_iter()
        .map(|&v| {
            if cancelled() {
                return None;
            }
            vertex_distance(field, mesh.vertices[v], tolerance)
        })
        .collect();
    if cancelled() {
        return None;
    }
    part_done(1);
    let vertex = vertex_distances
        .iter()
        .flatten()
        .copied()
        .fold(0.0, f64::max);
    let unresolved: Vec<usize> = surface_vertices
        .iter()
        .zip(&vertex_distances)
        .filter(|(_, d)| d.is_none())
        .map(|(&v, _)| v)
        .collect();
    let vertices_at_rounding = unresolved
        .iter()
        .filter(|&&v| field.at_rounding(mesh.vertices[v]))
        .count();
    let vertices_beyond = unresolved.len() - vertices_at_rounding;

    // The triangles with every corner on the surface (or the crease).
    let measured_triangles: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| {
            mesh.triangles[t]
                .iter()
                .all(|&v| kinds[v as usize].on_surface())
        })
        .collect();
    let mut distance_of_vertex = vec![None; mesh.vertices.len()];
    for (&v, &d) in surface_vertices.iter().zip(&vertex_distances) {
        distance_of_vertex[v] = d;
    }
    let mesh_side: Vec<Option<f64>> = measured_triangles
        .par_iter()
        .map(|&t| {
            if cancelled() {
                return None;
            }
            let [a, b, c] = mesh.corners(t);
            let centroid = (a + b + c) / 3.0;
            // Every corner on the crease: the triangle may be a piece of the cap.
            let off_sphere = mesh.triangles[t]
                .iter()
                .all(|&v| kinds[v as usize].on_sphere())
                .then(|| (field.radius() - centroid.length()).abs());
            let along_normal = field.distance_along(centroid, mesh.normal(t), reach);
            let along_gradient = field.distance_along(centroid, field.gradient(centroid, h), reach);
            let nearest = along_normal
                .into_iter()
                .chain(along_gradient)
                .chain(off_sphere)
                .reduce(f64::min);
            // Each line gives an upper bound on the distance; where those two are far (a
            // shell's wall beside a singular curve bends away from them), the 13 others.
            match nearest {
                Some(d) if d <= 0.5 * tolerance => Some(d),
                _ => nearest
                    .into_iter()
                    .chain(nearest_along_edges(field, centroid, reach))
                    .chain(descent_to_zero(field, centroid, reach))
                    // A corner's distance to the surface and the centroid's to the corner: a
                    // bound that needs no line to meet the surface, as none may beside a
                    // curve of the zero set (the z axis of x² + y⁴ + y³z², where f > 0 on
                    // both sides along x and the Newton steps stall in the valley x = 0).
                    .chain(mesh.triangles[t].iter().filter_map(|&v| {
                        distance_of_vertex[v as usize]
                            .map(|d: f64| d + centroid.distance(mesh.vertices[v as usize]))
                            .filter(|&d| d <= reach)
                    }))
                    .reduce(f64::min),
            }
        })
        .collect();
    let mesh_to_surface = mesh_side
        .iter()
        .map(|d| d.unwrap_or(reach))
        .fold(0.0, f64::max);
    // The triangles beyond the tolerance, each with whether it lies where the solid or a
    // gap is thinner than a step (the boundary on both sides along its normal).
    let far_triangles: Vec<(f64, bool)> = measured_triangles
        .par_iter()
        .zip(&mesh_side)
        .filter_map(|(&t, d)| {
            let d = d.unwrap_or(reach);
            (d > tolerance).then(|| {
                let [a, b, c] = mesh.corners(t);
                let centroid = (a + b + c) / 3.0;
                (d, between_sheets(field, centroid, mesh.normal(t), step))
            })
        })
        .collect();

    if cancelled() {
        return None;
    }
    part_done(2);
    let (samples, touching_samples) = surface_samples(field, step);
    let nearest = NearestTriangle::new(mesh);
    let surface_side: Vec<Option<f64>> = samples
        .par_iter()
        .map(|&p| {
            if cancelled() {
                return None;
            }
            nearest.distance(p, reach)
        })
        .collect();
    if cancelled() {
        return None;
    }
    part_done(3);
    let surface_to_mesh = surface_side
        .iter()
        .map(|d| d.unwrap_or(reach))
        .fold(0.0, f64::max);
    let far_samples: Vec<(f64, bool)> = samples
        .par_iter()
        .zip(&surface_side)
        .filter_map(|(&p, d)| {
            let d = d.unwrap_or(reach);
            (d > tolerance).then(|| (d, thin_at(field, p, step)))
        })
        .collect();
    let far = far_triangles.iter().chain(&far_samples);
    let thin_samples = far.clone().filter(|(_, thin)| *thin).count();
    let within = mesh_side
        .iter()
        .chain(&surface_side)
        .map(|d| d.unwrap_or(reach))
        .filter(|&d| d <= tolerance)
        .fold(0.0, f64::max);
    let away_from_thin = far
        .filter(|(_, thin)| !thin)
        .map(|&(d, _)| d)
        .fold(within, f64::max);
    let beyond_reach = mesh_side
        .iter()
        .chain(&surface_side)
        .filter(|d| d.is_none())
        .count();
    Some(Deviation {
        vertex,
        vertices: surface_vertices.len(),
        vertices_beyond,
        vertices_at_rounding,
        mesh_to_surface,
        surface_to_mesh,
        surface_samples: samples.len(),
        touching_samples,
        away_from_thin,
        thin_samples,
        thin_width: step,
        beyond_reach,
        measured: true,
    })
}

/// An upper bound on the distance from the object-space point `p` to `φ = 0`: the nearest
/// root of `φ` on the line through `p` along `∇φ`, or where that line has none within
/// `reach` (at a node, where `∇φ` vanishes), the nearest on the lines along the tetrahedra's
/// 13 edge directions (a vertex was found on one of them), by the root finder; `None` if
/// there is none within `reach`. (The line along `∇φ` is the one that meets the surface
/// nearest wherever the surface is smooth on the scale of the distance, so the others are
/// searched only when it finds nothing: one root search per vertex instead of fourteen.)
pub fn vertex_distance(field: &Field, p: DVec3, reach: f64) -> Option<f64> {
    let h = 1e-7 * field.radius();
    field
        .distance_along(p, field.gradient(p, h), reach)
        .or_else(|| nearest_along_edges(field, p, reach))
}

/// The nearest root of `φ` within `reach` of `p` on the lines through `p` along the
/// tetrahedra's 13 edge directions (an upper bound on the distance to `φ = 0`), if any.
fn nearest_along_edges(field: &Field, p: DVec3, reach: f64) -> Option<f64> {
    EDGE_DIRECTIONS
        .into_iter()
        .filter_map(|d| field.distance_along(p, d, reach))
        .reduce(f64::min)
}

/// The distance from `p` to where Newton steps from `p` converge (at most
/// [`DESCENT_STEPS`], until a step is shorter than `1e-9 · reach` or `φ` is zero to
/// rounding, [`Field::at_rounding`]), with twice the last step's length added for the rest
/// of the way, if that is within `reach` and (for a shell) a point of the wall
/// ([`Field::is_boundary_root`]): an upper bound on the distance to `φ = 0` where no line
/// through `p` meets it, as beside a part of the zero set that is a curve or a point (the
/// cross-cap's stick, where `φ` touches 0 without changing sign and a line misses it).
fn descent_to_zero(field: &Field, p: DVec3, reach: f64) -> Option<f64> {
    let h = 1e-7 * field.radius();
    let mut q = p;
    for _ in 0..DESCENT_STEPS {
        let (v, g) = field.value_and_gradient(q, h);
        let g2 = g.length_squared();
        let step = if v == 0.0 {
            DVec3::ZERO
        } else if g2 > 0.0 && v.is_finite() {
            g * (v / g2)
        } else {
            return None;
        };
        q -= step;
        let d = q.distance(p) + 2.0 * step.length();
        if d > reach {
            return None;
        }
        if step.length() <= 1e-9 * reach || field.at_rounding(q) {
            return field.is_boundary_root(q).then_some(d);
        }
    }
    None
}

/// The most Newton steps [`descent_to_zero`] takes: beside a curve or point where `φ`
/// vanishes to second order each step halves the distance, so from a grid step away this
/// converges to a billionth of it.
pub const DESCENT_STEPS: usize = 64;

/// Whether the point `p` of the boundary lies where the solid or a gap in it is thinner
/// than `width`: `∇φ` vanishes there or at a node within `width` of it (a singular point),
/// or the line along `∇φ` meets the boundary again within `width` of `p` (another sheet
/// that near).
fn thin_at(field: &Field, p: DVec3, width: f64) -> bool {
    let h = 1e-7 * field.radius();
    let g = field.gradient(p, h);
    if g.length_squared() == 0.0 || field.is_singular(p) || field.singular_point_near(p, width) {
        return true;
    }
    other_sheet(field, p, g, width, 1.0).is_some()
        || other_sheet(field, p, -g, width, 1.0).is_some()
}

/// Whether the boundary lies on both sides of `p` within `width` along `dir`: a triangle
/// there spans a gap or a part of the solid thinner than `width`.
fn between_sheets(field: &Field, p: DVec3, dir: DVec3, width: f64) -> bool {
    other_sheet(field, p, dir, width, 0.0).is_some()
        && other_sheet(field, p, -dir, width, 0.0).is_some()
}

/// A point of the boundary on the ray from `p` along `dir` within `width` (past
/// `skip · 1e-6 · width`, so that `p`'s own root is not counted when `p` is a point of the
/// boundary), as a distance: the nearest of `φ = 0` (for a shell a point of its wall), or
/// `width` where the ray leaves the clip ball within it.
fn other_sheet(field: &Field, p: DVec3, dir: DVec3, width: f64, skip: f64) -> Option<f64> {
    let e = dir.normalize_or_zero() * width;
    if e == DVec3::ZERO {
        return None;
    }
    // The clip sphere bounds the solid too (|x|² is convex along the ray: the far end is
    // outside the ball if any point is).
    if (p + e).length() > field.radius() {
        return Some(width);
    }
    let c = field.along(p, e);
    sturm_roots(&c, 0.0, 1.0)
        .into_iter()
        .filter(|&s| s > skip * 1e-6 && field.is_boundary_root(p + s * e))
        .map(|s| s * width)
        .reduce(f64::min)
}

/// Points of the solid's boundary inside the clip ball: every root of `φ` on the lines
/// parallel to each axis through the points `(i + ½)·step` of the other two axes (by the
/// root finder; for a shell, those that are points of its wall,
/// [`Field::is_boundary_root`]) at which `φ` changes sign along the line, or takes both
/// signs about it (where the line passes through a crossing of two sheets), each where `φ`
/// itself changes sign or is zero to rounding ([`Field::sign_beyond_rounding`]); with how many
/// roots were left out because `φ` only touches 0 there (a curve or point of `f = 0`, or a
/// sheet along which `f` is a square, inside the solid or outside it but never on its
/// boundary). Roots of the line's polynomial where `φ` is neither zero to rounding nor
/// changes sign (that polynomial's rounding) are neither.
pub fn surface_samples(field: &Field, step: f64) -> (Vec<DVec3>, usize) {
    let r = field.radius();
    let count = (r / step).ceil() as i64;
    let offsets: Vec<f64> = (-count..count).map(|i| (i as f64 + 0.5) * step).collect();
    let mut lines = Vec::new();
    for axis in 0..3 {
        for &u in &offsets {
            for &v in &offsets {
                let rest = r * r - u * u - v * v;
                if rest > 0.0 {
                    lines.push((axis, u, v, rest.sqrt()));
                }
            }
        }
    }
    let per_line: Vec<(Vec<DVec3>, usize)> = lines
        .par_iter()
        .map(|&(axis, u, v, half)| {
            let place = |t: f64| {
                let mut p = [u, v, u];
                p[axis] = t;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                DVec3::from_array(p)
            };
            let start = place(-half);
            let e = place(half) - start;
            let c = field.along(start, e);
            let roots = sturm_roots(&c, 0.0, 1.0);
            // The sign between consecutive roots (and the ends) is constant: a root changes
            // sign when the midpoints on its two sides differ. The sign is read off `φ` at the
            // point itself, not the line's polynomial, whose coefficients (scaled by powers of
            // the chord's length) can drown small values in their rounding, so that the root
            // finder places a root where `φ` is not zero (SingSurf's Bour surface, degree 16:
            // at z = 0 for z = 0.74 on lines across the clip ball). A value zero to the
            // rounding of evaluating it has no sign.
            let sign_at = |s: f64| field.sign_beyond_rounding(start + s * e);
            let mut boundary = Vec::new();
            let mut touching = 0;
            for (i, &s) in roots.iter().enumerate() {
                let p = start + s * e;
                if p.length_squared() >= r * r || !field.is_boundary_root(p) {
                    continue;
                }
                let before = 0.5 * (s + if i == 0 { 0.0 } else { roots[i - 1] });
                let after = 0.5 * (s + roots.get(i + 1).copied().unwrap_or(1.0));
                let (a, b) = (sign_at(before), sign_at(after));
                if a * b < 0.0 {
                    // Where the line's polynomial placed the root off the surface, the sign
                    // change of `φ` itself between the midpoints.
                    let q = if field.sign_beyond_rounding(p) == 0.0 {
                        p
                    } else {
                        sign_change(field, start, e, before, after, a)
                    };
                    if q.length_squared() < r * r {
                        boundary.push(q);
                    }
                } else if both_signs_about(field, p, 1e-2 * step) {
                    boundary.push(p);
                } else if field.sign_beyond_rounding(p) == 0.0 {
                    touching += 1;
                }
            }
            (boundary, touching)
        })
        .collect();
    let touching = per_line.iter().map(|(_, t)| t).sum();
    (
        per_line.into_iter().flat_map(|(b, _)| b).collect(),
        touching,
    )
}

/// The point where `φ` changes sign on the line `start + s·e` between `s0`, where its sign
/// is `sign`, and `s1`, where it is the other, by bisection on `φ` at the points themselves
/// (to the last bit of `s`, or to where `φ` is zero to rounding,
/// [`Field::sign_beyond_rounding`]).
fn sign_change(
    field: &Field,
    start: DVec3,
    e: DVec3,
    mut s0: f64,
    mut s1: f64,
    sign: f64,
) -> DVec3 {
    loop {
        let m = 0.5 * (s0 + s1);
        let q = start + m * e;
        if m <= s0 || m >= s1 {
            return q;
        }
        match field.sign_beyond_rounding(q) {
            0.0 => return q,
            v if v == sign => s0 = m,
            _ => s1 = m,
        }
    }
}

/// Whether `φ` takes both signs at the 26 points `p + ε·d` (`d` the unit direction to a
/// neighbour of a cube's centre; a value zero to its rounding, [`Field::at_rounding`],
/// counts as neither): `p` is a point of the boundary where the
/// line through it happened to pass where two sheets cross (a crossing curve, a node),
/// not a curve or sheet along which `φ` only touches 0.
fn both_signs_about(field: &Field, p: DVec3, epsilon: f64) -> bool {
    let (mut negative, mut positive) = (false, false);
    for k in 0..27 {
        let d = DVec3::new(
            f64::from(k % 3) - 1.0,
            f64::from(k / 3 % 3) - 1.0,
            f64::from(k / 9) - 1.0,
        );
        if d == DVec3::ZERO {
            continue;
        }
        let q = p + epsilon * d.normalize();
        if field.at_rounding(q) {
            continue;
        }
        let v = field.value(q);
        negative |= v < 0.0;
        positive |= v > 0.0;
    }
    negative && positive
}

/// The mesh's triangles in a bounding volume hierarchy, for nearest-triangle distances.
struct NearestTriangle<'a> {
    mesh: &'a TriangleMesh,
    bvh: Bvh,
}

impl<'a> NearestTriangle<'a> {
    fn new(mesh: &'a TriangleMesh) -> Self {
        let boxes: Vec<(u32, Aabb)> = (0..mesh.triangles.len())
            .map(|t| (t as u32, Aabb::from_points(mesh.corners(t))))
            .collect();
        Self {
            mesh,
            bvh: Bvh::new(&boxes),
        }
    }

    /// The distance from `p` to the nearest triangle, if one is within `reach`.
    fn distance(&self, p: DVec3, reach: f64) -> Option<f64> {
        let mut best = f64::INFINITY;
        self.bvh.walk_near(p, reach, |t, within| {
            let q = closest_on_triangle(p, self.mesh.corners(t as usize));
            best = best.min((p - q).length());
            *within = within.min(best);
        });
        (best <= reach).then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inside of `equation`'s surface clipped to `radius`.
    fn inside(equation: &str, radius: f64) -> Field {
        let poly = crate::shapes::implicit::expand(equation).unwrap();
        Field::new(&poly, radius, super::super::SolidKind::Inside)
    }

    #[test]
    fn a_cancelled_measurement_stops_before_its_first_part_ends() {
        let field = inside("x^2 + y^2 + z^2 = 1", 1.5);
        let grid = super::super::extract::Grid::covering(1.5, 0.05);
        let (mesh, kinds) = super::super::extract::march(&field, grid, &|_, _| {});
        let parts = std::sync::atomic::AtomicUsize::new(0);
        let count = |_| {
            parts.fetch_add(1, Ordering::Relaxed);
        };
        let run = |cancel: bool| {
            let flag = AtomicBool::new(cancel);
            measure_cancellable(&field, &mesh, &kinds, 0.025, grid.step(), &flag, &count)
        };
        assert!(run(true).is_none());
        assert_eq!(parts.load(Ordering::Relaxed), 0);
        let d = run(false).unwrap();
        assert_eq!(parts.load(Ordering::Relaxed), MEASURE_PARTS);
        // Vertices are on the sphere but for those held off an edge's end (0.1% of an edge).
        assert!(d.measured && d.vertex < 2e-4, "{d:?}");
    }

    #[test]
    fn a_point_is_thin_beside_another_sheet_a_singular_point_or_the_clip_sphere() {
        let one = DVec3::X;
        // A sphere, far from its clip sphere: nowhere thin.
        assert!(!thin_at(&inside("x^2 + y^2 + z^2 = 1", 2.0), one, 0.1));
        // Two spheres 0.01 apart along x: the solid between them is thinner than 0.1, not
        // than 0.001.
        let two = inside("(x^2 + y^2 + z^2 - 1)*(x^2 + y^2 + z^2 - 1.0201)", 2.0);
        assert!(thin_at(&two, one, 0.1));
        assert!(!thin_at(&two, one, 0.001));
        // Beside a node: a point of Kummer-like cone 0.01 from its apex, thin at 0.1 (the
        // node within it, found by Newton's steps on ∇f = 0), not at 0.001.
        let cone = inside("x^2 + y^2 - z^2 + x^3", 2.0);
        let near = DVec3::new(0.01, 0.0, (0.0001f64 + 1e-6).sqrt());
        assert!(cone.singular_point_near(near, 0.1));
        assert!(!cone.singular_point_near(near, 0.001));
        assert!(thin_at(&cone, near, 0.1));
        // A sphere's centre is a critical point of f but not on the surface.
        assert!(!inside("x^2 + y^2 + z^2 = 1", 2.0).singular_point_near(one, 1.5));
        // The apex of a cone, where ∇f vanishes, is thin at any width.
        assert!(thin_at(&inside("x^2 + y^2 - z^2", 2.0), DVec3::ZERO, 1e-9));
        // The clip sphere 0.05 beyond the surface along the normal.
        let clipped = inside("x^2 + y^2 + z^2 = 1", 1.05);
        assert!(thin_at(&clipped, one, 0.1));
        assert!(!thin_at(&clipped, one, 0.01));
        // A point between two sheets 0.01 apart, across them.
        assert!(between_sheets(&two, DVec3::new(1.005, 0.0, 0.0), one, 0.1));
        assert!(!between_sheets(
            &two,
            DVec3::new(1.005, 0.0, 0.0),
            DVec3::Y,
            0.1
        ));
    }

    #[test]
    fn surface_samples_are_on_the_surface() {
        let field = inside("x^2 + y^2 + z^2 = 1", 1.5);
        let (samples, touching) = surface_samples(&field, 0.1);
        assert_eq!(touching, 0);
        assert!(samples.len() > 500);
        for p in samples {
            assert!((p.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn roots_where_f_touches_zero_are_no_samples_of_the_boundary() {
        // The diagonal x = y = z is a curve of f = 0 inside the ball, where f ≤ 0 all
        // around (a factor that is a sum of squares): the lines parallel to an axis through
        // it (y = z for those along x) touch 0 there without a change of sign.
        let field = inside("(x^2 + y^2 + z^2 - 1)*((x - y)^2 + (y - z)^2) = 0", 1.5);
        let (samples, touching) = surface_samples(&field, 0.1);
        assert!(touching > 10, "{touching}");
        assert!(samples.len() > 500);
        for p in samples {
            assert!((p.length() - 1.0).abs() < 1e-9, "{p}");
        }
    }

    #[test]
    fn roots_the_line_polynomial_misplaces_are_moved_to_where_f_changes_sign() {
        // Across a ball of radius 4 the line polynomial in z has a z¹⁶ coefficient of
        // 8¹⁶ ≈ 3·10¹⁴, whose rounding (about 0.03) drowns the values of f about z = 0,
        // where f has a minimum of about 10⁻⁵ between the roots z ≈ ±0.1: the root finder
        // places roots where f is not 0 (up to 10⁻³ off).
        let field = inside("0.000001*(1 + x^2 + y^2) + 0.01*z^2 - z^4 + z^16 = 0", 4.0);
        let (samples, _) = surface_samples(&field, 0.25);
        let h = 1e-9;
        let near_middle = samples.iter().filter(|p| p.z.abs() < 1.0).count();
        assert!(near_middle > 50, "{near_middle}");
        for p in samples {
            let g = field.gradient(p, h);
            let off = field.value(p).abs() / g.length();
            assert!(
                field.sign_beyond_rounding(p) == 0.0 || off < 1e-9,
                "{p}: {off}"
            );
        }
    }

    #[test]
    fn a_small_triangle_beside_a_curve_of_the_zero_set_is_measured_by_its_corners() {
        // x² + y⁴ + y³z² is zero on the z axis, with f > 0 on both sides of the plane x = 0
        // where |y| > z²: no line through the centroid meets the zero set and Newton steps
        // stall in that valley. The corners are within 3·10⁻⁴ of the axis.
        let field = inside("x^2 + y^4 + y^3*z^2 = 0", 2.6);
        let h = 2.0867513352992861e-4;
        let mesh = TriangleMesh {
            vertices: vec![
                DVec3::new(-h, -h, 0.0),
                DVec3::new(0.0, -0.5 * h, 0.5 * h),
                DVec3::new(0.0, -h, 0.0),
            ],
            triangles: vec![[0, 1, 2]],
        };
        let kinds = vec![VertexKind::Surface; 3];
        let d = measure(&field, &mesh, &kinds, 0.026, 0.052);
        assert!(d.mesh_to_surface < 1e-3, "{}", d.mesh_to_surface);
    }
}
