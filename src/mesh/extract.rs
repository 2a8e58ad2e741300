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

pub use super::bisection::{pack, unpack};
use super::bisection::{Point, PointHasher, Tet, AXIS_ORDERS};
use super::field::{Field, VertexKind};
use super::TriangleMesh;
use crate::geometry::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The six tetrahedra of the unit cube (corner offsets as bits x = 1, y = 2, z = 4),
/// each ordered with positive orientation.
fn cube_tetrahedra() -> [[u8; 4]; 6] {
    AXIS_ORDERS.map(|p| {
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

/// A polygon of the marching table: three or four edges of the tetrahedron in order around
/// the polygon, each a pair of local corner numbers (the inside corner first).
pub(crate) type TablePolygon = Vec<[u8; 2]>;

/// For each of the 16 labellings of a positively oriented tetrahedron (bit `i` set when
/// corner `i` is inside), the polygon of its boundary piece (a triangle when one corner is
/// apart, a quadrilateral when two and two), wound so its normal faces the outside corners.
/// Consecutive edges of a polygon lie in one face of the tetrahedron, and each face holds at
/// most one of the polygon's sides. The winding is fixed on a reference tetrahedron with the
/// vertices at edge midpoints; it holds wherever the vertices are on the open edges, as no
/// triangle of the polygon's fan can flatten or turn over while its vertices move along their
/// edges.
pub(crate) fn marching_table() -> Vec<Option<TablePolygon>> {
    let reference = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    (0..16u8)
        .map(|case| {
            let inside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 1).collect();
            let outside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 0).collect();
            let mut polygon: TablePolygon = match (inside.len(), outside.len()) {
                (1, 3) => outside.iter().map(|&o| [inside[0], o]).collect(),
                (3, 1) => inside.iter().map(|&i| [i, outside[0]]).collect(),
                (2, 2) => {
                    let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
                    vec![[a, c], [a, d], [b, d], [b, c]]
                }
                _ => return None,
            };
            let centroid =
                |s: &[u8]| s.iter().map(|&k| reference[k as usize]).sum::<DVec3>() / s.len() as f64;
            let m: Vec<DVec3> = polygon
                .iter()
                .map(|[i, j]| 0.5 * (reference[*i as usize] + reference[*j as usize]))
                .collect();
            let n = (m[1] - m[0]).cross(m[2] - m[0]);
            if n.dot(centroid(&outside) - centroid(&inside)) < 0.0 {
                polygon[1..].reverse();
            }
            Some(polygon)
        })
        .collect()
}

/// The grid: `cells + 1` vertices a side over the cube `[−half, half]³`.
#[derive(Debug, Clone, Copy, PartialEq)]
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

    /// The grid whose cells, halved `depth` times, give a lattice of spacing `u` at most
    /// `floor` with no point on the sphere of `radius` about the origin: the cells are even
    /// in number (the origin is a lattice point at every level) and `(radius / u)²` is an
    /// integer plus ½, so every lattice point lies at least about `u² / (4·radius)` off the
    /// sphere, where the crossings of the edges through it would crowd it. The cube is at
    /// least one cell wider than the ball on each side.
    pub fn clear_of_sphere(radius: f64, floor: f64, depth: u32) -> Self {
        let n = ((radius / floor).powi(2) - 0.5).ceil().max(0.0);
        let unit = radius / (n + 0.5).sqrt();
        let step = unit * f64::from(1u32 << depth);
        let cells = 2 * ((radius + step) / step).ceil() as usize;
        Self {
            cells,
            half: cells as f64 * step / 2.0,
        }
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

/// The `total` that [`march`] reports progress against for `grid`: its layers of labels, its
/// layers of cubes, and the placing of the vertices.
pub fn march_steps(grid: Grid) -> usize {
    2 * grid.side() + 1
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
    let total = march_steps(grid);
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

    // 2. Polygons as cycles of edge keys (the lower vertex's index × 8 + the offset bits
    // to the upper one; a triangle's fourth key is NO_KEY), one z layer of cubes per task,
    // joined in order.
    if cancelled() {
        return None;
    }
    let tetrahedra = cube_tetrahedra();
    let table = marching_table();
    let key = |v: usize, bits: u8| (v as u64) << 3 | u64::from(bits);
    let by_layer: Vec<Vec<[u64; 4]>> = (0..grid.cells)
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
                        let Some(polygon) = &table[case] else {
                            continue;
                        };
                        let mut keys = [NO_KEY; 4];
                        for (slot, [i, j]) in keys.iter_mut().zip(polygon) {
                            let (bi, bj) = (t[*i as usize], t[*j as usize]);
                            // Freudenthal edges join a corner to one whose bits hold its own.
                            let (lo, hi) = if bi & bj == bi { (bi, bj) } else { (bj, bi) };
                            *slot = key(at(lo), hi & !lo);
                        }
                        out.push(keys);
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
    let polygons: Vec<[u64; 4]> = by_layer.into_iter().flatten().collect();
    let ends = |k: u64| {
        let lower = (k >> 3) as usize;
        let bits = (k & 7) as u8;
        let (x, y, z) = grid.coords(lower);
        let upper = grid.index(
            x + (bits & 1) as usize,
            y + (bits >> 1 & 1) as usize,
            z + (bits >> 2 & 1) as usize,
        );
        (lower, upper)
    };
    let position = |v: usize| {
        let (x, y, z) = grid.coords(v);
        grid.point(x, y, z)
    };
    let mesh = assemble(
        field,
        &polygons,
        NO_KEY,
        ends,
        position,
        |v| labels[v],
        |_| None,
        cancelled,
    );
    tick();
    mesh
}

/// Steps 3 to 5 of marching tetrahedra, for any conforming tetrahedral mesh: `polygons` are
/// cycles of edge keys (a triangle's fourth key `none`), each key an edge whose `ends` are
/// mesh vertices (`position` in object space, `inside` their labels). One vertex per crossed
/// edge placed on the exact boundary ([`Field::crossing`]); a side joining a surface vertex
/// to a cap vertex split at the crease point in the face the two edges span (the same face
/// of both tetrahedra that share it, so the split is the same in both); each polygon fanned
/// from its first crease vertex or else its first vertex (see the module doc); `known(key)`,
/// where `Some`, is the edge's crossing already found (as [`Field::crossing`] would find
/// it). `None` once `cancelled()` (read before each vertex is placed).
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble<K, P>(
    field: &Field,
    polygons: &[[K; 4]],
    none: K,
    ends: impl Fn(K) -> (P, P) + Sync,
    position: impl Fn(P) -> DVec3 + Sync,
    inside: impl Fn(P) -> bool + Sync,
    known: impl Fn(K) -> Option<(f64, VertexKind)> + Sync,
    cancelled: impl Fn() -> bool + Sync,
) -> Option<(TriangleMesh, Vec<VertexKind>)>
where
    K: Copy + Ord + Send + Sync,
    P: Copy + PartialEq + Send + Sync,
{
    // 3. One vertex per crossed edge, placed on the exact boundary.
    let mut keys: Vec<K> = polygons
        .iter()
        .flatten()
        .copied()
        .filter(|&k| k != none)
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    let placed: Vec<(DVec3, VertexKind)> = keys
        .par_iter()
        .map(|&k| {
            if cancelled() {
                return None;
            }
            let (lower, upper) = ends(k);
            let (p, q) = (position(lower), position(upper));
            let (a, b) = if inside(lower) { (p, q) } else { (q, p) };
            let crossing = known(k).unwrap_or_else(|| field.crossing(a, b));
            Some((field.crossing_point(a, b, crossing), crossing.1))
        })
        .collect::<Option<_>>()?;
    let (mut vertices, mut kinds): (Vec<DVec3>, Vec<VertexKind>) = placed.into_iter().unzip();
    let indexed: Vec<([u32; 4], usize)> = polygons
        .par_iter()
        .map(|p| {
            let n = if p[3] == none { 3 } else { 4 };
            let mut out = [u32::MAX; 4];
            for (o, k) in out.iter_mut().zip(&p[..n]) {
                *o = keys.binary_search(k).expect("every key was placed") as u32;
            }
            (out, n)
        })
        .collect();

    if cancelled() {
        return None;
    }

    // 4. Where a polygon's side joins a surface vertex to a cap vertex, a vertex on the
    // crease, in the face of the tetrahedron that holds the side (shared by the two
    // tetrahedra of that face).
    let mixed = |a: u32, b: u32| {
        let (ka, kb) = (kinds[a as usize], kinds[b as usize]);
        (ka == VertexKind::Surface && kb == VertexKind::Cap)
            || (ka == VertexKind::Cap && kb == VertexKind::Surface)
    };
    let mut sides: Vec<(u32, u32)> = indexed
        .iter()
        .flat_map(|&(p, n)| (0..n).map(move |i| (p[i], p[(i + 1) % n])))
        .filter(|&(a, b)| mixed(a, b))
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    sides.sort_unstable();
    sides.dedup();
    let creases: Vec<Option<DVec3>> = sides
        .par_iter()
        .map(|&(a, b)| {
            let (cap, other) = if kinds[a as usize] == VertexKind::Cap {
                (a, b)
            } else {
                (b, a)
            };
            let (c0, c1) = ends(keys[cap as usize]);
            let (o0, o1) = ends(keys[other as usize]);
            let face = side_face([c0, c1], [o0, o1]).expect("a polygon's sides lie in faces");
            field.crease(face.map(&position), vertices[cap as usize])
        })
        .collect();
    let mut crease_vertex: HashMap<(u32, u32), u32> = HashMap::new();
    for (&side, point) in sides.iter().zip(creases) {
        if let Some(point) = point {
            crease_vertex.insert(side, vertices.len() as u32);
            vertices.push(point);
            kinds.push(VertexKind::Crease);
        }
    }

    // 5. Triangles: each polygon as a fan from its first vertex; a polygon with crease
    // vertices on its sides as a fan from its first crease vertex (see the module doc).
    let mut triangles = Vec::with_capacity(indexed.len() * 2);
    let mut cycle = Vec::with_capacity(8);
    for &(p, n) in &indexed {
        cycle.clear();
        let mut apex = None;
        for i in 0..n {
            cycle.push(p[i]);
            let (a, b) = (p[i], p[(i + 1) % n]);
            if let Some(&x) = crease_vertex.get(&(a.min(b), a.max(b))) {
                apex.get_or_insert(cycle.len());
                cycle.push(x);
            }
        }
        let apex = apex.unwrap_or(0);
        let m = cycle.len();
        for k in 1..m - 1 {
            triangles.push([
                cycle[apex],
                cycle[(apex + k) % m],
                cycle[(apex + k + 1) % m],
            ]);
        }
    }
    Some((
        TriangleMesh {
            vertices,
            triangles,
        },
        kinds,
    ))
}

/// The face of a tetrahedron that holds a polygon's side from the vertex on the edge
/// `cap_edge` to the vertex on the edge `other_edge` (edges given by their ends), as
/// [`Field::crease`] takes it: `[shared, q, r]` with `shared` the corner both edges share, `q`
/// the other edge's other end and `r` the cap edge's; `None` when the edges share no corner.
pub(crate) fn side_face<T: Copy + PartialEq>(
    cap_edge: [T; 2],
    other_edge: [T; 2],
) -> Option<[T; 3]> {
    let shared = *cap_edge.iter().find(|c| other_edge.contains(c))?;
    let other_end = |edge: [T; 2]| if edge[0] == shared { edge[1] } else { edge[0] };
    Some([shared, other_end(other_edge), other_end(cap_edge)])
}

/// Where the lattice of a [`Refinement`] lies in object space: lattice point `p` is at
/// `origin + unit · p`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    /// The object-space position of lattice point `(0, 0, 0)`.
    pub origin: DVec3,
    /// The lattice spacing (object units): the side of the finest cubes.
    pub unit: f64,
}

impl Lattice {
    /// The lattice whose domain cubes (side `2^depth` units) are the cells of `grid`.
    pub fn of_grid(grid: Grid, depth: u32) -> Self {
        Self {
            origin: DVec3::splat(-grid.half),
            unit: grid.step() / f64::from(1u32 << depth),
        }
    }

    /// The object-space position of a lattice point.
    pub fn position(&self, p: Point) -> DVec3 {
        self.origin + DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * self.unit
    }
}

/// The marching-tetrahedra mesh of `field`'s solid on the `leaves` of a conforming
/// refinement (object space, with each vertex's kind), on `lattice`; `labels[i]`: bit `k` set
/// when corner `k` of leaf `i` is inside ([`Field::inside`] at its position; the same for a
/// lattice point in every leaf). Closed, 2-manifold, outward and free of self-intersections
/// as on a uniform grid (module doc): the leaves share whole faces. An edge in `crossings`
/// takes its crossing from there (it must be that edge's [`Field::crossing`] from its inside
/// end). `None` once `cancel` is set.
pub fn march_leaves(
    field: &Field,
    lattice: Lattice,
    leaves: &[Tet],
    labels: &[u8],
    crossings: &Crossings,
    cancel: &AtomicBool,
) -> Option<(TriangleMesh, Vec<VertexKind>)> {
    let cancelled = || cancel.load(Ordering::Relaxed);
    let table = marching_table();
    let polygons: Vec<[u128; 4]> = leaves
        .par_iter()
        .zip(labels)
        .filter(|(_, &m)| m != 0 && m != 15)
        .filter_map(|(t, &m)| {
            let mut c = t.corners;
            let mut case = usize::from(m);
            if t.orientation() < 0 {
                c.swap(1, 2);
                case = case & 0b1001 | (case & 2) << 1 | (case & 4) >> 1;
            }
            let polygon = table[case].as_ref()?;
            let mut keys = [NO_EDGE; 4];
            for (slot, [i, j]) in keys.iter_mut().zip(polygon) {
                *slot = edge_key(c[*i as usize], c[*j as usize]);
            }
            Some(keys)
        })
        .collect();
    if cancelled() {
        return None;
    }
    // A lattice point's label, from any leaf that has it as a corner.
    let mut label_of: Vec<(u64, bool)> = leaves
        .par_iter()
        .zip(labels)
        .filter(|(_, &m)| m != 0 && m != 15)
        .flat_map_iter(|(t, &m)| (0..4).map(move |k| (pack(t.corners[k]), m >> k & 1 == 1)))
        .collect();
    label_of.par_sort_unstable();
    label_of.dedup();
    let inside = |p: Point| {
        let k = pack(p);
        let i = label_of.partition_point(|&(q, _)| q < k);
        label_of[i].1
    };
    let ends = |k: u128| (unpack((k >> 64) as u64), unpack(k as u64));
    assemble(
        field,
        &polygons,
        NO_EDGE,
        ends,
        |p| lattice.position(p),
        inside,
        |k| crossings.get(&k).copied(),
        cancelled,
    )
}

/// Where the boundary crosses edges of lattice points ([`edge_key`]): [`Field::crossing`]
/// from the edge's inside end to its outside end, as [`march_leaves`] would place it.
pub type Crossings = HashMap<u128, (f64, VertexKind), BuildHasherDefault<PointHasher>>;

/// An edge of lattice points as one key: the two packed ends, the smaller first.
pub fn edge_key(a: Point, b: Point) -> u128 {
    let (a, b) = (pack(a), pack(b));
    u128::from(a.min(b)) << 64 | u128::from(a.max(b))
}

/// The fourth key of a triangle's polygon in [`march_leaves`] (no edge).
const NO_EDGE: u128 = u128::MAX;

/// The fourth key of a triangle's polygon (no vertex).
const NO_KEY: u64 = u64::MAX;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_lattice_point_lies_on_the_clip_sphere() {
        // The default tolerance (1% of the radius) asks for a floor step of radius / 50,
        // where a plain grid through the origin puts lattice points such as (0, 30, 40) and
        // (14, 48, 0) exactly on the sphere.
        for (radius, floor, depth) in [
            (1.0, 0.02, 2),
            (3.16228, 0.0632456, 2),
            (1.14, 0.0228, 3),
            (2.5, 0.01, 4),
            (1.0, 0.06, 0),
        ] {
            let grid = Grid::clear_of_sphere(radius, floor, depth);
            let lattice = Lattice::of_grid(grid, depth);
            let u = lattice.unit;
            assert!(u <= floor && u > 0.99 * floor, "{radius} {floor}: {u}");
            assert_eq!(grid.cells % 2, 0);
            assert!(grid.half >= radius + grid.step());
            // The origin is a lattice point; every point within a step of the sphere keeps
            // the promised distance from it.
            let centre = (grid.half / u).round();
            assert!((grid.half / u - centre).abs() < 1e-9);
            let n = (radius / u).ceil() as i32 + 1;
            let margin = 0.9 * u * u / (4.0 * radius);
            let mut near = 0;
            for x in -n..=n {
                for y in -n..=n {
                    for z in -n..=n {
                        let p = lattice.position([x, y, z].map(|c| c + centre as i32));
                        let off = (p.length() - radius).abs();
                        assert!(off >= margin, "{radius} {floor} {depth}: {x} {y} {z} {off}");
                        near += usize::from(off < u);
                    }
                }
            }
            assert!(near > 0);
        }
    }

    #[test]
    fn a_side_s_face_has_the_shared_corner_first_and_the_cap_edge_s_end_last() {
        assert_eq!(side_face([1, 2], [1, 3]), Some([1, 3, 2]));
        assert_eq!(side_face([2, 1], [3, 1]), Some([1, 3, 2]));
        assert_eq!(side_face([2, 1], [1, 3]), Some([1, 3, 2]));
        assert_eq!(side_face([1, 2], [3, 4]), None);
    }

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
    fn the_table_cuts_one_corner_with_a_triangle_and_two_with_a_quadrilateral() {
        let table = marching_table();
        assert!(table[0].is_none() && table[15].is_none());
        for (case, polygon) in table.iter().enumerate().skip(1).take(14) {
            let polygon = polygon.as_ref().unwrap();
            let n = (case as u32).count_ones();
            assert_eq!(polygon.len(), if n == 2 { 4 } else { 3 }, "case {case}");
            for [i, j] in polygon {
                assert!(case >> i & 1 == 1 && case >> j & 1 == 0, "inside first");
            }
            // Consecutive sides share a corner (they lie in one face of the tetrahedron).
            for k in 0..polygon.len() {
                let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
                assert!(a[0] == b[0] || a[1] == b[1], "case {case}");
            }
        }
    }
}
