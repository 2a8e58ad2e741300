//! Marching tetrahedra on a uniform grid cut into tetrahedra the same way in every cube
//! (Freudenthal's decomposition: six tetrahedra around the cube's main diagonal), so the
//! tetrahedra of neighbouring cubes share whole faces (a conforming decomposition).
//!
//! Every grid vertex gets a binary label ([`Field::inside`]: never zero). In each
//! tetrahedron whose labels differ, the boundary is one triangle (one corner apart) or two
//! (two and two), through one vertex on each edge whose labels differ, shared by every
//! tetrahedron around that edge. The result is a closed surface, a 2-manifold, consistently
//! oriented (outward), and free of self-intersections, whatever the labels are: it is the
//! boundary of the union of the pieces of the tetrahedra cut off around the inside corners,
//! each piece meeting its neighbours in the same face polygons. Each edge's vertex is put on
//! the exact boundary ([`Field::crossing`]): the solid's surface by the root finder, or the
//! clip sphere.

use super::field::{Field, VertexKind};
use super::TriangleMesh;
use crate::geometry::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The six tetrahedra of the unit cube (corner offsets as bits x = 1, y = 2, z = 4),
/// each ordered with positive orientation.
fn cube_tetrahedra() -> [[u8; 4]; 6] {
    const PERMUTATIONS: [[u8; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    PERMUTATIONS.map(|p| {
        let c1 = 1u8 << p[0];
        let c2 = c1 | (1u8 << p[1]);
        let mut t = [0u8, c1, c2, 7];
        if orientation(&t.map(corner)) < 0.0 {
            t.swap(1, 2);
        }
        t
    })
}

/// The unit-cube corner of offset bits `b`.
fn corner(b: u8) -> DVec3 {
    DVec3::new(
        f64::from(b & 1),
        f64::from((b >> 1) & 1),
        f64::from((b >> 2) & 1),
    )
}

/// Six times the signed volume of the tetrahedron `t`.
fn orientation(t: &[DVec3; 4]) -> f64 {
    (t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0])
}

/// A triangle of the marching table: three edges of the tetrahedron, each a pair of local
/// corner numbers (the inside corner first).
type TableTriangle = [[u8; 2]; 3];

/// For each of the 16 labellings of a positively oriented tetrahedron (bit `i` set when
/// corner `i` is inside), the triangles of its boundary piece, wound so their normals face
/// the outside corners. The winding is fixed on a reference tetrahedron with the vertices at
/// edge midpoints; it holds wherever the vertices are on the open edges, as no triangle of
/// the table can flatten or turn over while its vertices move along their edges.
fn marching_table() -> Vec<Vec<TableTriangle>> {
    let reference = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    (0..16u8)
        .map(|case| {
            let inside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 1).collect();
            let outside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 0).collect();
            let mut tris: Vec<TableTriangle> = match (inside.len(), outside.len()) {
                (1, 3) => vec![outside
                    .iter()
                    .map(|&o| [inside[0], o])
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()],
                (3, 1) => vec![inside
                    .iter()
                    .map(|&i| [i, outside[0]])
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()],
                (2, 2) => {
                    let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
                    vec![[[a, c], [a, d], [b, d]], [[a, c], [b, d], [b, c]]]
                }
                _ => Vec::new(),
            };
            let centroid =
                |s: &[u8]| s.iter().map(|&k| reference[k as usize]).sum::<DVec3>() / s.len() as f64;
            for t in &mut tris {
                let m = t.map(|[i, j]| 0.5 * (reference[i as usize] + reference[j as usize]));
                let n = (m[1] - m[0]).cross(m[2] - m[0]);
                if n.dot(centroid(&outside) - centroid(&inside)) < 0.0 {
                    t.swap(1, 2);
                }
            }
            tris
        })
        .collect()
}

/// The grid: `cells + 1` vertices a side over the cube `[−half, half]³`.
#[derive(Debug, Clone, Copy)]
pub struct Grid {
    /// Cubes along each axis.
    pub cells: usize,
    /// Half the cube's side (object units); larger than the clip radius, so every vertex of
    /// the grid's faces is outside the solid.
    pub half: f64,
}

impl Grid {
    /// The grid of step at most `step` over a cube one step wider than the ball of `radius`.
    pub fn covering(radius: f64, step: f64) -> Self {
        let half = radius + step;
        let cells = ((2.0 * half / step).ceil() as usize).max(2);
        Self { cells, half }
    }

    /// The distance between neighbouring vertices.
    pub fn step(&self) -> f64 {
        2.0 * self.half / self.cells as f64
    }

    fn point(&self, x: usize, y: usize, z: usize) -> DVec3 {
        let h = self.step();
        DVec3::new(x as f64, y as f64, z as f64) * h - DVec3::splat(self.half)
    }

    fn side(&self) -> usize {
        self.cells + 1
    }

    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.side() * (y + self.side() * z)
    }

    fn coords(&self, i: usize) -> (usize, usize, usize) {
        let n = self.side();
        (i % n, (i / n) % n, i / (n * n))
    }
}

/// The mesh of `field`'s solid on `grid`, in object space, with each vertex's kind.
/// `progress(done, total)` is called as the grid's layers are done (from any thread).
pub fn march(
    field: &Field,
    grid: Grid,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (TriangleMesh, Vec<VertexKind>) {
    march_cancellable(field, grid, progress, &AtomicBool::new(false)).expect("never cancelled")
}

/// [`march`], giving up (`None`) once `cancel` is set: it is read before each layer of the
/// grid (labels and triangles) and before each vertex is placed on the boundary, so a
/// cancelled march stops within about one layer's work.
pub fn march_cancellable(
    field: &Field,
    grid: Grid,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Option<(TriangleMesh, Vec<VertexKind>)> {
    let cancelled = || cancel.load(Ordering::Relaxed);
    let side = grid.side();
    let total = 2 * side + 1;
    let done = AtomicUsize::new(0);
    let tick = || progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);

    // 1. Labels, one z layer per task.
    let mut labels = vec![false; side * side * side];
    labels
        .par_chunks_mut(side * side)
        .enumerate()
        .for_each(|(z, layer)| {
            if cancelled() {
                return;
            }
            for y in 0..side {
                for x in 0..side {
                    layer[x + side * y] = field.inside(grid.point(x, y, z));
                }
            }
            tick();
        });

    // 2. Triangles as triples of edge keys (the lower vertex's index × 8 + the offset bits
    // to the upper one), one z layer of cubes per task, joined in order.
    if cancelled() {
        return None;
    }
    let tetrahedra = cube_tetrahedra();
    let table = marching_table();
    let key = |v: usize, bits: u8| (v as u64) << 3 | u64::from(bits);
    let by_layer: Vec<Vec<[u64; 3]>> = (0..grid.cells)
        .into_par_iter()
        .map(|z| {
            let mut out = Vec::new();
            if cancelled() {
                return out;
            }
            for y in 0..grid.cells {
                for x in 0..grid.cells {
                    let base = grid.index(x, y, z);
                    let at = |b: u8| {
                        base + (b & 1) as usize
                            + side * ((b >> 1 & 1) as usize)
                            + side * side * ((b >> 2 & 1) as usize)
                    };
                    let mut mask = 0u8;
                    for b in 0..8u8 {
                        mask |= u8::from(labels[at(b)]) << b;
                    }
                    if mask == 0 || mask == 0xff {
                        continue;
                    }
                    for t in &tetrahedra {
                        let case =
                            (0..4).fold(0usize, |c, i| c | usize::from(mask >> t[i] & 1) << i);
                        for tri in &table[case] {
                            out.push(tri.map(|[i, j]| {
                                let (bi, bj) = (t[i as usize], t[j as usize]);
                                // Freudenthal edges join a corner to one whose bits hold its own.
                                let (lo, hi) = if bi & bj == bi { (bi, bj) } else { (bj, bi) };
                                key(at(lo), hi & !lo)
                            }));
                        }
                    }
                }
            }
            tick();
            out
        })
        .collect();
    if cancelled() {
        return None;
    }
    let keyed: Vec<[u64; 3]> = by_layer.into_iter().flatten().collect();

    // 3. One vertex per crossed edge, placed on the exact boundary.
    let mut keys: Vec<u64> = keyed.iter().flatten().copied().collect();
    keys.par_sort_unstable();
    keys.dedup();
    let placed: Vec<(DVec3, VertexKind)> = keys
        .par_iter()
        .map(|&k| {
            if cancelled() {
                return None;
            }
            let lower = (k >> 3) as usize;
            let bits = (k & 7) as u8;
            let (x, y, z) = grid.coords(lower);
            let p = grid.point(x, y, z);
            let q = grid.point(
                x + (bits & 1) as usize,
                y + (bits >> 1 & 1) as usize,
                z + (bits >> 2 & 1) as usize,
            );
            let (a, b) = if labels[lower] { (p, q) } else { (q, p) };
            let (s, kind) = field.crossing(a, b);
            Some((a + s * (b - a), kind))
        })
        .collect::<Option<_>>()?;
    tick();
    let triangles = keyed
        .par_iter()
        .map(|t| t.map(|k| keys.binary_search(&k).expect("every key was placed") as u32))
        .collect();
    let (vertices, kinds) = placed.into_iter().unzip();
    Some((
        TriangleMesh {
            vertices,
            triangles,
        },
        kinds,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_six_tetrahedra_fill_the_cube_with_positive_orientation() {
        let tets = cube_tetrahedra();
        let mut volume = 0.0;
        for t in &tets {
            let o = orientation(&t.map(corner));
            assert!(o > 0.0);
            volume += o / 6.0;
            assert!(t.contains(&0) && t.contains(&7));
        }
        assert!((volume - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_table_cuts_one_corner_with_one_triangle_and_two_with_two() {
        let table = marching_table();
        assert!(table[0].is_empty() && table[15].is_empty());
        for (case, tris) in table.iter().enumerate() {
            let n = (case as u32).count_ones();
            let want = match n {
                1 | 3 => 1,
                2 => 2,
                _ => 0,
            };
            assert_eq!(tris.len(), want, "case {case}");
            for t in tris {
                for [i, j] in t {
                    assert!(case >> i & 1 == 1 && case >> j & 1 == 0, "inside first");
                }
            }
        }
    }
}
