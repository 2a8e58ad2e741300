//! The guarantees of a mesh, checked on the mesh itself: closed (every edge in exactly two
//! triangles, once in each direction, so consistently oriented), one fan of triangles about
//! every vertex (a 2-manifold), positive volume (outward normals), no triangle of zero area
//! and no two triangles that cross or overlap. `kardia mesh` checks every file it writes;
//! the tests check every mesh they make.

use super::bisection::PointHasher;
use super::TriangleMesh;
use crate::geometry::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

/// What [`verify`] measured on a mesh that keeps every guarantee.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verified {
    /// Number of triangles.
    pub triangles: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Number of connected pieces (triangles joined by shared edges).
    pub components: usize,
    /// The enclosed volume (cubic units of the vertices; positive: outward normals).
    pub volume: f64,
    /// Euler characteristic `V − E + F` (2 per sphere-like piece, 2 − 2g for genus g).
    pub euler_characteristic: i64,
}

/// Checks every guarantee of the module doc; the first one broken is the error.
pub fn verify(mesh: &TriangleMesh) -> Result<Verified, String> {
    if mesh.triangles.is_empty() {
        return Err("the mesh has no triangles (the solid is empty at this tolerance)".into());
    }
    edges_pair_up(mesh)?;
    one_fan_per_vertex(mesh)?;
    if let Some(t) = (0..mesh.triangles.len()).find(|&t| mesh.area(t) <= 0.0) {
        return Err(format!("triangle {t} has zero area"));
    }
    if let Some((a, b)) = crossing_triangles(mesh).first() {
        return Err(format!("triangles {a} and {b} intersect"));
    }
    let volume = mesh.volume();
    if volume.is_nan() || volume <= 0.0 {
        return Err(format!(
            "the volume is {volume}, not positive (inward normals)"
        ));
    }
    let edges = mesh.triangles.len() * 3 / 2;
    Ok(Verified {
        triangles: mesh.triangles.len(),
        vertices: mesh.vertices.len(),
        components: components(mesh),
        volume,
        euler_characteristic: mesh.vertices.len() as i64 - edges as i64
            + mesh.triangles.len() as i64,
    })
}

/// Every directed edge `a → b` of a triangle appears in exactly one triangle, and `b → a`
/// in exactly one other: closed and consistently oriented.
pub fn edges_pair_up(mesh: &TriangleMesh) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), usize, BuildHasherDefault<PointHasher>> =
        HashMap::default();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(format!("triangle {t} repeats a vertex"));
        }
        for k in 0..3 {
            if directed.insert((tri[k], tri[(k + 1) % 3]), t).is_some() {
                return Err(format!(
                    "edge {}–{} is used twice in the same direction (non-manifold or \
                     inconsistently oriented)",
                    tri[k],
                    tri[(k + 1) % 3]
                ));
            }
        }
    }
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) {
            return Err(format!("edge {a}–{b} is in only one triangle (a hole)"));
        }
    }
    Ok(())
}

/// The triangles about each vertex form one cycle (a disc), not several touching at it.
pub fn one_fan_per_vertex(mesh: &TriangleMesh) -> Result<(), String> {
    // Around vertex a, triangle (a, b, c) links b to c; with paired edges each b has one c.
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); mesh.vertices.len()];
    for tri in &mesh.triangles {
        for k in 0..3 {
            link[tri[k] as usize].push((tri[(k + 1) % 3], tri[(k + 2) % 3]));
        }
    }
    for (v, edges) in link.iter_mut().enumerate() {
        if edges.is_empty() {
            return Err(format!("vertex {v} is in no triangle"));
        }
        edges.sort_unstable();
        let start = edges[0].0;
        let mut at = start;
        let mut steps = 0;
        loop {
            // With paired edges, each b has one c (a repeated b fails at edges_pair_up).
            let i = edges.partition_point(|&(b, _)| b < at);
            at = match edges.get(i) {
                Some(&(b, c)) if b == at => c,
                _ => return Err(format!("the triangles about vertex {v} do not close")),
            };
            steps += 1;
            if at == start {
                break;
            }
            if steps > edges.len() {
                return Err(format!("the triangles about vertex {v} do not close"));
            }
        }
        if steps != edges.len() {
            return Err(format!(
                "vertex {v} joins {} fans of triangles (a pinch: not a 2-manifold)",
                if steps < edges.len() {
                    "several"
                } else {
                    "broken"
                }
            ));
        }
    }
    Ok(())
}

/// The number of pieces: triangles joined through shared edges.
pub fn components(mesh: &TriangleMesh) -> usize {
    let mut parent: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let mut by_edge: HashMap<(u32, u32), u32, BuildHasherDefault<PointHasher>> = HashMap::default();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let e = (a.min(b), a.max(b));
            if let Some(&other) = by_edge.get(&e) {
                let (x, y) = (find(&mut parent, t as u32), find(&mut parent, other));
                parent[x as usize] = y;
            } else {
                by_edge.insert(e, t as u32);
            }
        }
    }
    (0..parent.len() as u32)
        .filter(|&i| find(&mut parent, i) == i)
        .count()
}

/// Six times the signed volume of the tetrahedron `a b c d`.
fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

/// Whether the segment `p q` crosses the triangle `a b c` at a point inside both (strict:
/// touching at an end, an edge or a corner does not count).
fn segment_crosses(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    segment_crosses_sided(p, q, orient(a, b, c, p), orient(a, b, c, q), [a, b, c])
}

/// [`segment_crosses`] given `sp = orient(a, b, c, p)` and `sq = orient(a, b, c, q)` (the
/// same answer, for callers that share those among the edges of a triangle).
fn segment_crosses_sided(p: DVec3, q: DVec3, sp: f64, sq: f64, [a, b, c]: [DVec3; 3]) -> bool {
    if sp * sq >= 0.0 || (sp * sq).is_nan() {
        return false;
    }
    let (u, v, w) = (orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a));
    (u > 0.0 && v > 0.0 && w > 0.0) || (u < 0.0 && v < 0.0 && w < 0.0)
}

/// Pairs of triangles `(i, j)`, `i < j`, that intersect other than in the vertices and
/// edges they share: a broad phase by a uniform grid of cells about the triangles' size,
/// then exact tests of each candidate pair (segment against triangle in both directions;
/// pairs that share an edge: the two folded onto each other, to within [`FOLD_SINE`]).
pub fn crossing_triangles(mesh: &TriangleMesh) -> Vec<(usize, usize)> {
    let tris = &mesh.triangles;
    if tris.is_empty() {
        return Vec::new();
    }
    let corners = |t: usize| tris[t].map(|v| mesh.vertices[v as usize]);
    // Each triangle's box, the box of them all and their mean longest side from a corner.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut size = 0.0;
    let boxes: Vec<(DVec3, DVec3)> = (0..tris.len())
        .map(|t| {
            let c = corners(t);
            size += (c[1] - c[0]).length().max((c[2] - c[0]).length());
            let (a, b) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
            (lo, hi) = (lo.min(a), hi.max(b));
            (a, b)
        })
        .collect();
    // Cells at least a 2^20th of the box's largest side, so each index fits in 21 bits.
    let cell = (2.0 * size / tris.len() as f64)
        .max((hi - lo).max_element() / f64::from(1u32 << 20))
        .max(1e-300);
    let dims = ((hi - lo) / cell).floor().as_uvec3() + 1;
    let cell_of = |p: DVec3| ((p - lo) / cell).floor().as_uvec3().min(dims - 1);
    let key = |x: u32, y: u32, z: u32| u64::from(x) | u64::from(y) << 21 | u64::from(z) << 42;
    let ranges: Vec<_> = boxes
        .iter()
        .map(|&(a, b)| (cell_of(a), cell_of(b)))
        .collect();
    let mut cells: HashMap<u64, Vec<u32>, BuildHasherDefault<PointHasher>> = HashMap::default();
    for (t, &(a, b)) in ranges.iter().enumerate() {
        for x in a.x..=b.x {
            for y in a.y..=b.y {
                for z in a.z..=b.z {
                    cells.entry(key(x, y, z)).or_default().push(t as u32);
                }
            }
        }
    }
    // Each triangle against the later triangles of its cells whose boxes meet its own (a
    // pair that meets has boxes that meet), in parallel.
    let mut found: Vec<(usize, usize)> = ranges
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, &(a, b))| {
            let (lo_i, hi_i) = boxes[i];
            let mut candidates = Vec::new();
            for x in a.x..=b.x {
                for y in a.y..=b.y {
                    for z in a.z..=b.z {
                        candidates.extend(cells[&key(x, y, z)].iter().map(|&j| j as usize).filter(
                            |&j| {
                                let (lo_j, hi_j) = boxes[j];
                                j > i && lo_j.cmple(hi_i).all() && lo_i.cmple(hi_j).all()
                            },
                        ));
                    }
                }
            }
            candidates.sort_unstable();
            candidates.dedup();
            candidates
                .into_iter()
                .filter(move |&j| triangles_cross(mesh, i, j))
                .map(move |j| (i, j))
        })
        .collect();
    found.sort_unstable();
    found
}

/// Two triangles sharing an edge, on the same side of it, count as folded onto each other
/// (meeting) when the sine of the angle between them is at most this: the rounding of
/// their coordinates (to `f32` in the files) could make them coplanar.
pub const FOLD_SINE: f64 = 1e-6;

/// Whether triangles `i` and `j` meet anywhere but in what they share (see
/// [`crossing_triangles`]).
fn triangles_cross(mesh: &TriangleMesh, i: usize, j: usize) -> bool {
    triangles_meet(mesh.triangles[i], mesh.triangles[j], &mesh.vertices)
}

/// Whether the triangles `ti` and `tj` (indices into `vertices`) meet anywhere but in the
/// corners and sides they share: the exact test [`verify`] makes on every candidate pair,
/// for callers that keep their own triangles (the coarsening's test of each new fan).
pub fn triangles_meet(ti: [u32; 3], tj: [u32; 3], vertices: &[DVec3]) -> bool {
    let (pi, pj) = (
        ti.map(|v| vertices[v as usize]),
        tj.map(|v| vertices[v as usize]),
    );
    corners_meet(ti, pi, tj, pj)
}

/// [`triangles_meet`] for callers that hold the corners already: `pi` must be the points of
/// `ti`'s vertices and `pj` those of `tj`'s (the answer is then the same).
pub fn corners_meet(ti: [u32; 3], pi: [DVec3; 3], tj: [u32; 3], pj: [DVec3; 3]) -> bool {
    let mut shared = [u32::MAX; 3];
    let mut count = 0;
    for &v in &ti {
        if tj.contains(&v) {
            shared[count] = v;
            count += 1;
        }
    }
    let shared = &shared[..count];
    match count {
        0 => {
            // Each corner's side of the other triangle's plane, once: `orient` of it (the
            // same arithmetic, so the same answer as testing edge by edge).
            let sides = |[a, b, c]: [DVec3; 3], p: [DVec3; 3]| {
                let normal = (b - a).cross(c - a);
                p.map(|x| normal.dot(x - a))
            };
            let (of_i, of_j) = (sides(pj, pi), sides(pi, pj));
            (0..3).any(|k| {
                let l = (k + 1) % 3;
                segment_crosses_sided(pi[k], pi[l], of_i[k], of_i[l], pj)
                    || segment_crosses_sided(pj[k], pj[l], of_j[k], of_j[l], pi)
            })
        }
        1 => {
            // Only the edges opposite the shared corner can cross the other triangle.
            let opposite = |t: [u32; 3], p: [DVec3; 3]| {
                let k = t.iter().position(|&v| v == shared[0]).unwrap();
                (p[(k + 1) % 3], p[(k + 2) % 3])
            };
            let (a, b) = opposite(ti, pi);
            let (c, d) = opposite(tj, pj);
            segment_crosses(a, b, pj) || segment_crosses(c, d, pi)
        }
        2 => {
            // Sharing an edge u v: they overlap only when folded flat onto the same side.
            let at =
                |t: [u32; 3], p: [DVec3; 3], w: u32| p[t.iter().position(|&x| x == w).unwrap()];
            let (u, v) = (at(ti, pi, shared[0]), at(ti, pi, shared[1]));
            let other =
                |t: [u32; 3], p: [DVec3; 3]| p[t.iter().position(|w| !shared.contains(w)).unwrap()];
            let (a, b) = (other(ti, pi), other(tj, pj));
            // Folded to within FOLD_SINE counts: rounding (the files' f32) could close it.
            let na = (v - u).cross(a - u);
            let nb = (v - u).cross(b - u);
            let sine = orient(u, v, a, b).abs() / (na.length() * (b - u).length());
            (sine <= FOLD_SINE || sine.is_nan()) && na.dot(nb) > 0.0
        }
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron with outward faces.
    fn tetrahedron() -> TriangleMesh {
        TriangleMesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn a_tetrahedron_keeps_every_guarantee() {
        let v = verify(&tetrahedron()).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (1, 2));
        assert!((v.volume - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn each_broken_guarantee_is_caught() {
        let mut hole = tetrahedron();
        hole.triangles.pop();
        assert!(verify(&hole).unwrap_err().contains("only one"));
        let mut flipped = tetrahedron();
        flipped.triangles[3].swap(1, 2);
        assert!(verify(&flipped).unwrap_err().contains("same direction"));
        let mut inward = tetrahedron();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        assert!(verify(&inward).unwrap_err().contains("volume"));
        let mut flat = tetrahedron();
        flat.vertices[3] = DVec3::new(0.5, 0.5, 0.0);
        assert!(verify(&flat).is_err());
        // Two tetrahedra sharing one corner: closed, but a pinch at that corner.
        let mut pinch = tetrahedron();
        let more = tetrahedron();
        pinch.vertices.extend([-DVec3::X, -DVec3::Y, -DVec3::Z]);
        let map = |v: u32| if v == 0 { 0 } else { v + 3 };
        for t in &more.triangles {
            // Mirrored through the origin: reverse the winding to stay outward.
            pinch.triangles.push([map(t[0]), map(t[2]), map(t[1])]);
        }
        assert!(verify(&pinch).unwrap_err().contains("fans"));
        // Two tetrahedra passing through each other.
        let mut crossing = tetrahedron();
        let shift = DVec3::splat(0.1);
        crossing
            .vertices
            .extend(tetrahedron().vertices.iter().map(|&p| p + shift));
        for t in &tetrahedron().triangles {
            crossing.triangles.push(t.map(|v| v + 4));
        }
        assert!(verify(&crossing).unwrap_err().contains("intersect"));
    }

    #[test]
    fn two_triangles_folded_onto_each_other_to_rounding_meet() {
        // Sharing the edge u v, on the same side, in one plane up to rounding (the shape the
        // coarsening once made at one of Barth's nodes, which f32 rounding made coplanar).
        let vertices = vec![
            DVec3::new(-1.0200023690523115, 1.0200023690523115, 1.04),
            DVec3::new(-1.0000400000000003, 0.99996, 1.00004),
            DVec3::new(-1.0000400000000003, 1.00004, 0.99996),
            DVec3::new(-1.0200023690523108, 1.04, 1.0200023690523108),
        ];
        assert!(triangles_meet([0, 1, 2], [3, 1, 0], &vertices));
        // Turned out of the plane by a thousandth of a radian, they do not.
        let mut turned = vertices.clone();
        turned[3].x += 1e-3 * 0.028;
        assert!(!triangles_meet([0, 1, 2], [3, 1, 0], &turned));
    }
}
