//! Adaptive coarsening of the extracted mesh: half-edge collapses and edge flips, which keep every
//! vertex where it was (on the exact surface, on the clip sphere, or on the crease), so the
//! grid decides the topology and the collapses only drop vertices where the surface is flat
//! enough for longer triangles.
//!
//! A collapse of the edge `u v` removes `u` and joins its other neighbours to `v`. It is made
//! only when all of these hold:
//!
//! - `u` is a surface vertex whose neighbours are all on the surface (surface or crease
//!   vertices), or a cap vertex whose neighbours are all on the sphere (cap or crease
//!   vertices), and `v` is of the same part; crease vertices are never removed, so the crease
//!   keeps every point the extraction put on it;
//! - the link condition: the vertices joined to both `u` and `v` are exactly the two opposite
//!   the edge, and neither of them nor `u` has only three neighbours (so the mesh stays a
//!   closed 2-manifold, one fan about every vertex);
//! - no new triangle turns by more than [`MAX_TURN_COS`] from the triangle it replaces (no
//!   normal flips), none is thinner than [`MIN_QUALITY`] unless the one it replaces already
//!   was, and none has zero area;
//! - the accuracy: each new triangle's centroid and edge midpoints are within `budget` of the
//!   surface by the first-order estimate `|φ|/|∇φ|` (of the sphere: `R − |x|` for a cap
//!   triangle), and so is the removed vertex of the nearest new triangle (the surface side).
//!
//! Edges are tried shortest first, in passes until a pass removes few vertices; after each
//! pass, edges are flipped to the other diagonal of their two triangles where that makes
//! the thinner of the two clearly thicker (which frees further collapses), under the same
//! conditions for the new triangles and with neither end of the edge left with three
//! neighbours or fewer. Whether two
//! triangles cross is decided by [`super::check`] on the finished mesh (the caller falls back
//! to the uncoarsened mesh if it ever finds one).

use super::field::{Field, VertexKind};
use super::TriangleMesh;
use crate::geometry::DVec3;
use crate::shapes::triangles::closest_on_triangle;
use std::sync::atomic::{AtomicBool, Ordering};

/// A new triangle's unit normal must be within this cosine of the replaced triangle's (60°).
pub const MAX_TURN_COS: f64 = 0.5;

/// The least quality `4√3·area / Σ edge²` (1 for an equilateral triangle, 0 for a flat one)
/// of a new triangle, unless the triangle it replaces was already thinner.
pub const MIN_QUALITY: f64 = 0.2;

/// Passes over the edges at most.
pub const MAX_PASSES: usize = 12;

/// The quality `4√3·area / Σ edge²` of a triangle: 1 when equilateral, 0 when flat.
pub fn quality([a, b, c]: [DVec3; 3]) -> f64 {
    let twice_area = (b - a).cross(c - a).length();
    let edges = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if edges > 0.0 {
        2.0 * 3f64.sqrt() * twice_area / edges
    } else {
        0.0
    }
}

/// What [`coarsen`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Coarsened {
    /// Vertices removed by collapses.
    pub collapses: usize,
    /// Edges flipped to the other diagonal of their two triangles.
    pub flips: usize,
    /// Passes over the edges made.
    pub passes: usize,
}

/// The mesh being coarsened: triangles with a live flag and the triangles about each vertex.
struct Work<'a> {
    field: &'a Field,
    vertices: &'a [DVec3],
    kinds: &'a [VertexKind],
    triangles: Vec<[u32; 3]>,
    alive: Vec<bool>,
    around: Vec<Vec<u32>>,
    removed: Vec<bool>,
    /// Scratch marks for the link condition (a vertex is marked when it holds `stamp`).
    mark: Vec<u32>,
    stamp: u32,
    budget: f64,
    h: f64,
}

impl Work<'_> {
    fn corners(&self, t: [u32; 3]) -> [DVec3; 3] {
        t.map(|v| self.vertices[v as usize])
    }

    /// The first-order distance estimate of `p` from the part `surface` (φ = 0) or the sphere.
    fn off(&self, p: DVec3, surface: bool) -> f64 {
        if surface {
            let g = self.field.gradient(p, self.h).length();
            let v = self.field.value(p).abs();
            if g > 0.0 {
                v / g
            } else if v == 0.0 {
                0.0
            } else {
                f64::INFINITY
            }
        } else {
            (self.field.radius() - p.length()).abs()
        }
    }

    /// Flips the edge `a b` of live triangle `t` (its `k`-th side) to the other diagonal of
    /// the two triangles on it, if the thinner of the two new triangles is thicker than the
    /// thinner of the two old ones by a margin and every condition of the module doc holds
    /// for the new ones (same part, no turn, within the budget).
    fn try_flip(&mut self, t: u32, k: usize) -> bool {
        let t1 = self.triangles[t as usize];
        let (a, b, c) = (t1[k], t1[(k + 1) % 3], t1[(k + 2) % 3]);
        let Some(&t2) = self.around[a as usize]
            .iter()
            .find(|&&x| x != t && self.triangles[x as usize].contains(&b))
        else {
            return false;
        };
        let other = self.triangles[t2 as usize];
        let d = *other.iter().find(|&&w| w != a && w != b).unwrap();
        if c == d
            || self.around[a as usize].len() <= 3
            || self.around[b as usize].len() <= 3
            || self.around[c as usize]
                .iter()
                .any(|&x| self.triangles[x as usize].contains(&d))
        {
            return false;
        }
        let kinds = [a, b, c, d].map(|w| self.kinds[w as usize]);
        let surface = if kinds.iter().all(|k| k.on_surface()) {
            true
        } else if kinds.iter().all(|k| k.on_sphere()) {
            false
        } else {
            return false;
        };
        let (new1, new2) = ([a, d, c], [d, b, c]);
        let (o1, o2) = (self.corners(t1), self.corners(other));
        let (n1, n2) = (self.corners(new1), self.corners(new2));
        let before = quality(o1).min(quality(o2));
        if quality(n1).min(quality(n2)) <= 1.2 * before {
            return false;
        }
        let normal = |p: [DVec3; 3]| (p[1] - p[0]).cross(p[2] - p[0]);
        let unit = |p: [DVec3; 3]| normal(p).normalize_or_zero();
        let old_mean = unit(o1) + unit(o2);
        for n in [n1, n2] {
            let m = unit(n);
            if m == DVec3::ZERO
                || m.dot(unit(o1)) < MAX_TURN_COS
                || m.dot(unit(o2)) < MAX_TURN_COS
                || m.dot(old_mean) <= 0.0
            {
                return false;
            }
        }
        let (pc, pd) = (self.vertices[c as usize], self.vertices[d as usize]);
        for p in [
            0.5 * (pc + pd),
            (n1[0] + n1[1] + n1[2]) / 3.0,
            (n2[0] + n2[1] + n2[2]) / 3.0,
        ] {
            if self.off(p, surface) > self.budget {
                return false;
            }
        }
        self.triangles[t as usize] = new1;
        self.triangles[t2 as usize] = new2;
        self.around[a as usize].retain(|&x| x != t2);
        self.around[b as usize].retain(|&x| x != t);
        self.around[c as usize].push(t2);
        self.around[d as usize].push(t);
        true
    }

    /// Collapses `u` into `v` if every condition of the module doc holds.
    fn try_collapse(&mut self, u: u32, v: u32) -> bool {
        if self.removed[u as usize] || self.removed[v as usize] {
            return false;
        }
        let surface = match self.kinds[u as usize] {
            VertexKind::Surface => true,
            VertexKind::Cap => false,
            VertexKind::Crease => return false,
        };
        let same_part = |w: u32| {
            let k = self.kinds[w as usize];
            if surface {
                k.on_surface()
            } else {
                k.on_sphere()
            }
        };
        // Valences (on a closed 2-manifold, a vertex has as many neighbours as triangles).
        if self.around[u as usize].len() <= 3 || self.around[v as usize].len() <= 3 {
            return false;
        }
        if !self.around[u as usize]
            .iter()
            .all(|&t| self.triangles[t as usize].iter().all(|&w| same_part(w)))
        {
            return false;
        }
        // The two triangles on the edge and their opposite vertices.
        let mut shared = [u32::MAX; 2];
        let mut opposite = [u32::MAX; 2];
        let mut count = 0;
        for &t in &self.around[u as usize] {
            let tri = self.triangles[t as usize];
            if tri.contains(&v) {
                if count == 2 {
                    return false;
                }
                shared[count] = t;
                opposite[count] = *tri.iter().find(|&&w| w != u && w != v).unwrap();
                count += 1;
            }
        }
        if count != 2
            || opposite[0] == opposite[1]
            || opposite.iter().any(|&o| self.around[o as usize].len() <= 3)
        {
            return false;
        }
        // The link condition: v's neighbours marked, none of u's but v and the two opposite
        // may be among them.
        self.stamp += 1;
        let stamp = self.stamp;
        for &t in &self.around[v as usize] {
            for w in self.triangles[t as usize] {
                self.mark[w as usize] = stamp;
            }
        }
        for &t in &self.around[u as usize] {
            for w in self.triangles[t as usize] {
                if w != u && w != v && !opposite.contains(&w) && self.mark[w as usize] == stamp {
                    return false;
                }
            }
        }
        // The new triangles, checked.
        let target = self.vertices[v as usize];
        let removed_at = self.vertices[u as usize];
        let mut nearest_to_removed = f64::INFINITY;
        for &t in &self.around[u as usize] {
            if shared.contains(&t) {
                continue;
            }
            let old_tri = self.triangles[t as usize];
            let new_tri = old_tri.map(|w| if w == u { v } else { w });
            let (old, new) = (self.corners(old_tri), self.corners(new_tri));
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]);
            let n_new = (new[1] - new[0]).cross(new[2] - new[0]);
            let (l_old, l_new) = (n_old.length(), n_new.length());
            if !(l_new > 0.0 && l_old > 0.0) || n_old.dot(n_new) < MAX_TURN_COS * l_old * l_new {
                return false;
            }
            if quality(new) < MIN_QUALITY.min(quality(old)) {
                return false;
            }
            let centroid = (new[0] + new[1] + new[2]) / 3.0;
            let k = new_tri.iter().position(|&w| w == v).unwrap();
            let (b, c) = (new[(k + 1) % 3], new[(k + 2) % 3]);
            for p in [centroid, 0.5 * (target + b), 0.5 * (target + c)] {
                if self.off(p, surface) > self.budget {
                    return false;
                }
            }
            nearest_to_removed = nearest_to_removed
                .min((closest_on_triangle(removed_at, new) - removed_at).length());
        }
        if nearest_to_removed > self.budget {
            return false;
        }
        // Made: the two triangles on the edge go, the rest of u's fan turns to v.
        for &t in &shared {
            self.alive[t as usize] = false;
            let tri = self.triangles[t as usize];
            for w in tri {
                if w != u {
                    self.around[w as usize].retain(|&x| x != t);
                }
            }
        }
        let fan = std::mem::take(&mut self.around[u as usize]);
        for t in fan {
            if shared.contains(&t) {
                continue;
            }
            for w in &mut self.triangles[t as usize] {
                if *w == u {
                    *w = v;
                }
            }
            self.around[v as usize].push(t);
        }
        self.removed[u as usize] = true;
        true
    }
}

/// Coarsens `mesh` (object space, with each vertex's kind) by half-edge collapses within
/// `budget` of the exact boundary (object units; see the module doc), in place: removed
/// vertices are dropped and the kinds kept in step. Gives up (`None`, the mesh untouched)
/// once `cancel` is set (read between batches of collapses). `pass_done(k)` is called as
/// pass `k` (1 to at most [`MAX_PASSES`]) ends.
pub fn coarsen(
    field: &Field,
    mesh: &mut TriangleMesh,
    kinds: &mut Vec<VertexKind>,
    budget: f64,
    cancel: &AtomicBool,
    pass_done: &dyn Fn(usize),
) -> Option<Coarsened> {
    let n = mesh.vertices.len();
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            around[v as usize].push(t as u32);
        }
    }
    let mut work = Work {
        field,
        vertices: &mesh.vertices,
        kinds,
        triangles: mesh.triangles.clone(),
        alive: vec![true; mesh.triangles.len()],
        around,
        removed: vec![false; n],
        mark: vec![0; n],
        stamp: 0,
        budget,
        h: 1e-7 * field.radius(),
    };
    let mut done = Coarsened::default();
    let i_cancelled = |i: usize| i.is_multiple_of(4096) && cancel.load(Ordering::Relaxed);
    for _ in 0..MAX_PASSES {
        // Every live edge in both directions, shortest first.
        let mut edges: Vec<(f64, u32, u32)> = Vec::new();
        for (t, tri) in work.triangles.iter().enumerate() {
            if !work.alive[t] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let length = (work.vertices[a as usize] - work.vertices[b as usize]).length();
                edges.push((length, a, b));
            }
        }
        edges.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        let before = done.collapses;
        for (i, &(_, a, b)) in edges.iter().enumerate() {
            if i_cancelled(i) {
                return None;
            }
            if work.try_collapse(a, b) {
                done.collapses += 1;
            }
        }
        // Flips toward thicker triangles, which free further collapses.
        for t in 0..work.triangles.len() {
            if i_cancelled(t) {
                return None;
            }
            for k in 0..3 {
                if work.alive[t] && work.try_flip(t as u32, k) {
                    done.flips += 1;
                }
            }
        }
        done.passes += 1;
        pass_done(done.passes);
        let alive_vertices = n - done.collapses;
        if (done.collapses - before) * 50 < alive_vertices {
            break;
        }
    }
    // Compact: live triangles, live vertices renumbered.
    let mut index = vec![u32::MAX; n];
    let mut vertices = Vec::with_capacity(n - done.collapses);
    let mut new_kinds = Vec::with_capacity(n - done.collapses);
    for v in 0..n {
        if !work.removed[v] {
            index[v] = vertices.len() as u32;
            vertices.push(mesh.vertices[v]);
            new_kinds.push(kinds[v]);
        }
    }
    let triangles = work
        .triangles
        .iter()
        .zip(&work.alive)
        .filter(|(_, &alive)| alive)
        .map(|(t, _)| t.map(|v| index[v as usize]))
        .collect();
    *mesh = TriangleMesh {
        vertices,
        triangles,
    };
    *kinds = new_kinds;
    Some(done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{check, extract, SolidKind};
    use crate::shapes::implicit::expand;

    #[test]
    fn quality_is_one_for_an_equilateral_triangle_and_zero_for_a_flat_one() {
        let equilateral = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.75f64.sqrt(), 0.0)];
        assert!((quality(equilateral) - 1.0).abs() < 1e-12);
        assert_eq!(quality([DVec3::ZERO, DVec3::X, DVec3::X * 2.0]), 0.0);
    }

    #[test]
    fn a_coarsened_sphere_keeps_every_guarantee_with_far_fewer_triangles() {
        let poly = expand("x^2 + y^2 + z^2 = 1").unwrap();
        let field = Field::new(&poly, 1.5, SolidKind::Inside);
        let grid = extract::Grid::covering(1.5, 0.04);
        let (mut mesh, mut kinds) = extract::march(&field, grid, &|_, _| {});
        let before = mesh.triangles.len();
        let done = coarsen(
            &field,
            &mut mesh,
            &mut kinds,
            0.01,
            &AtomicBool::new(false),
            &|_| {},
        )
        .unwrap();
        let v = check::verify(&mesh).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (1, 2));
        assert_eq!(kinds.len(), mesh.vertices.len());
        eprintln!("{before} -> {} triangles, {done:?}", mesh.triangles.len());
        assert!(
            mesh.triangles.len() * 4 < before,
            "{before} -> {}",
            mesh.triangles.len()
        );
        for p in &mesh.vertices {
            assert!((p.length() - 1.0).abs() < 1e-12);
        }
        // Every triangle's centroid within the budget (chord error of the sphere).
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.corners(t);
            assert!(1.0 - ((a + b + c) / 3.0).length() <= 0.0101);
        }
    }
}
