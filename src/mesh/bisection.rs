//! Conforming local refinement of a grid of Kuhn tetrahedra by newest-vertex bisection
//! (Maubach's), on an integer lattice.
//!
//! The domain is `cells³` cubes of side `2^depth` lattice units, each cut into six Kuhn
//! (Freudenthal) tetrahedra around its main diagonal `(0,0,0)–(1,1,1)` (the same way in every
//! cube, as [`super::extract`] cuts its uniform grid). A tetrahedron `(x0, x1, x2, x3)` with
//! tag `k` is bisected at the midpoint `z` of its refinement edge `x0 xk` into
//! `(x0, …, x_{k−1}, z, x_{k+1}, …, x3)` and `(x1, …, xk, z, x_{k+1}, …, x3)`, both with tag
//! `k − 1` (3 after 1). Three bisections halve a cube's side: the refinement edge of a
//! tetrahedron of level `3j` is the main diagonal of a cube of side `s = 2^(depth − j)`, of
//! level `3j + 1` a diagonal of a face of such a cube, of level `3j + 2` one of its axis
//! edges, and the tetrahedra of level `3j + 3` are again Kuhn tetrahedra of the cubes of side
//! `s/2`, each cut around the main diagonal through the centre of the cube it halves (so the
//! half cubes are mirror images of each other, and edges run along all 13 directions of
//! axes, face diagonals and main diagonals). Every vertex is a lattice point, every midpoint an exact integer: edges are
//! keyed exactly.
//!
//! **Conformity.** The tetrahedra around a refinement edge (its *diamond*: the six of a cube,
//! four about a face diagonal, eight about an axis edge) all have that edge as their own
//! refinement edge and the same level, so an edge is refined for all of them at once. A
//! diamond's tetrahedra exist once its *parents* are refined: the diamonds whose midpoints are
//! its vertices made one level before its own midpoint (two cube centres for a face diagonal,
//! four face centres for an axis edge, three edge midpoints for a cube). [`Refinement::mark`]
//! marks an edge (by its midpoint) with all its ancestors, and [`Refinement::leaves`] bisects
//! a tetrahedron exactly when its refinement edge is marked: every marked edge is then bisected
//! in every tetrahedron around it, and the leaves form a conforming mesh (every face of a leaf
//! inside the domain is a whole face of exactly one other leaf; a test checks it).

use std::collections::HashSet;
use std::hash::{BuildHasherDefault, Hasher};

/// A lattice point (lattice units, each coordinate in `0..=cells·2^depth`).
pub type Point = [i32; 3];

/// A tetrahedron of the bisection hierarchy: its corners in Maubach's order, the index of the
/// far end of its refinement edge (from corner 0), and its level (bisections from a Kuhn
/// tetrahedron of the domain's cubes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Tet {
    /// Corners in bisection order (not necessarily positively oriented).
    pub corners: [Point; 4],
    /// The refinement edge is `corners[0]`–`corners[tag]` (`tag` in 1..=3).
    pub tag: u8,
    /// Bisections from the domain's Kuhn tetrahedra.
    pub level: u8,
}

impl Tet {
    /// The midpoint of the refinement edge (exact for every level below the finest).
    pub fn midpoint(&self) -> Point {
        midpoint(self.corners[0], self.corners[self.tag as usize])
    }

    /// The two halves of the tetrahedron, bisected at its refinement edge's midpoint.
    pub fn children(&self) -> [Tet; 2] {
        let k = self.tag as usize;
        let z = self.midpoint();
        let x = self.corners;
        let mut first = x;
        first[k] = z;
        let mut second = x;
        second[..k].copy_from_slice(&x[1..=k]);
        second[k] = z;
        let tag = if k > 1 { self.tag - 1 } else { 3 };
        [first, second].map(|corners| Tet {
            corners,
            tag,
            level: self.level + 1,
        })
    }

    /// Six times the signed volume (lattice units³): positive when the corners are in
    /// right-handed order.
    pub fn orientation(&self) -> i64 {
        let [a, b, c, d] = self.corners;
        let e = |p: Point| [0, 1, 2].map(|i| i64::from(p[i]) - i64::from(a[i]));
        let (u, v, w) = (e(b), e(c), e(d));
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])
    }

    /// The smallest box holding the tetrahedron, `(min, max)` in lattice units.
    pub fn bounds(&self) -> (Point, Point) {
        let mut lo = self.corners[0];
        let mut hi = lo;
        for p in &self.corners[1..] {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        (lo, hi)
    }
}

/// A lattice point packed in a `u64` (21 bits a coordinate), ordered as its `(z, y, x)`.
pub fn pack(p: Point) -> u64 {
    (p[2] as u64) << 42 | (p[1] as u64) << 21 | p[0] as u64
}

/// The lattice point [`pack`] packed.
pub fn unpack(k: u64) -> Point {
    let mask = (1u64 << 21) - 1;
    [k & mask, k >> 21 & mask, k >> 42].map(|c| c as i32)
}

/// The midpoint of two lattice points whose coordinates differ by even numbers.
fn midpoint(a: Point, b: Point) -> Point {
    [0, 1, 2].map(|i| (a[i] + b[i]) / 2)
}

/// The edges of a tetrahedron as pairs of corner indices.
pub const TET_EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// The six orders of the axes x = 0, y = 1, z = 2: each is the path along a cube's edges from
/// its lowest corner to the opposite one that makes one of its Kuhn tetrahedra.
pub const AXIS_ORDERS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];

/// The six Kuhn tetrahedra of the cube of side `side` at `lo`, in Maubach's order (a path
/// along the cube's edges from `lo` to the opposite corner; refinement edge the main
/// diagonal, tag 3).
pub fn kuhn_tetrahedra(lo: Point, side: i32) -> [Tet; 6] {
    AXIS_ORDERS.map(|path| {
        let mut corners = [lo; 4];
        for (step, &axis) in path.iter().enumerate() {
            corners[step + 1] = corners[step];
            corners[step + 1][axis] += side;
        }
        Tet {
            corners,
            tag: 3,
            level: 0,
        }
    })
}

/// The marked edges (by midpoint) of a bisection hierarchy over `cells³` cubes of side
/// `2^depth` lattice units, kept closed under "a marked diamond's parents are marked".
#[derive(Debug, Clone)]
pub struct Refinement {
    cells: i32,
    depth: u32,
    /// Midpoints of the marked edges, [`pack`]ed.
    marked: HashSet<u64, BuildHasherDefault<PointHasher>>,
}

/// A hasher for lattice points, packed lattice points and edges of them, and for the vertex
/// indices and cells of [`super::check`] (a multiply per word; the keys are well spread
/// integers, and the tables are not exposed to chosen input).
#[derive(Default)]
pub struct PointHasher(u64);

impl Hasher for PointHasher {
    fn finish(&self) -> u64 {
        self.0 ^ self.0 >> 29
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(21) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
    fn write_u128(&mut self, v: u128) {
        self.write_u64((v >> 64) as u64);
        self.write_u64(v as u64);
    }
}

impl Refinement {
    /// No edge marked: the leaves are the domain's Kuhn tetrahedra. `depth`: how many times a
    /// cube's side may be halved (the finest tetrahedra have level `3·depth`).
    pub fn new(cells: usize, depth: u32) -> Self {
        assert!(depth <= 20 && cells << depth < 1 << 21, "lattice too large");
        Self {
            cells: cells as i32,
            depth,
            marked: HashSet::default(),
        }
    }

    /// Cubes along each side of the domain.
    pub fn cells(&self) -> usize {
        self.cells as usize
    }

    /// The finest level is `3 × depth`.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// The side of a domain cube in lattice units.
    pub fn cube_side(&self) -> i32 {
        1 << self.depth
    }

    /// The largest coordinate of the lattice.
    pub fn extent(&self) -> i32 {
        self.cells << self.depth
    }

    /// The finest level a tetrahedron may have; tetrahedra at it are never bisected.
    pub fn finest_level(&self) -> u8 {
        (3 * self.depth) as u8
    }

    /// How many edges are marked.
    pub fn marked(&self) -> usize {
        self.marked.len()
    }

    /// The Kuhn tetrahedra of every cube of the domain, cube by cube (x fastest).
    pub fn coarse(&self) -> Vec<Tet> {
        let side = self.cube_side();
        let n = self.cells;
        (0..n)
            .flat_map(|z| (0..n).flat_map(move |y| (0..n).map(move |x| [x, y, z])))
            .flat_map(|c| kuhn_tetrahedra(c.map(|v| v * side), side))
            .collect()
    }

    /// The level at which the lattice point `p` is made (as the midpoint of a refinement
    /// edge), or `None` for a corner of the domain's cubes.
    pub fn level_of(&self, p: Point) -> Option<u8> {
        let d = self.depth;
        let valuation = |c: i32| if c == 0 { d } else { c.trailing_zeros().min(d) };
        let v = p.map(valuation);
        let least = *v.iter().min().expect("three coordinates");
        if least >= d {
            return None;
        }
        // The cube side s = 2^(least + 1) = 2^(depth − j).
        let j = d - least - 1;
        let halves = v.iter().filter(|&&x| x == least).count() as u32;
        Some((3 * j + 3 - halves) as u8)
    }

    /// Whether `p` lies in the domain.
    fn in_domain(&self, p: Point) -> bool {
        let e = self.extent();
        p.iter().all(|&c| (0..=e).contains(&c))
    }

    /// The parents of the diamond whose refinement edge has midpoint `m` (see the module
    /// doc): its vertices in the domain made one level before `m`.
    pub fn parents(&self, m: Point) -> Vec<Point> {
        let Some(level) = self.level_of(m) else {
            return Vec::new();
        };
        if level == 0 {
            return Vec::new();
        }
        let least = m
            .iter()
            .map(|&c| if c == 0 { 31 } else { c.trailing_zeros() })
            .min()
            .expect("three coordinates");
        let h = 1i32 << least;
        let half: Vec<usize> = (0..3).filter(|&i| m[i].trailing_zeros() == least).collect();
        let shift = |p: Point, axis: usize, by: i32| {
            let mut q = p;
            q[axis] += by;
            q
        };
        let mut around: Vec<Point> = Vec::with_capacity(8);
        match half.len() {
            3 => {
                for b in 0..8 {
                    around.push([0, 1, 2].map(|i| m[i] + if b >> i & 1 == 1 { h } else { -h }));
                }
            }
            2 => {
                let (i, k) = (half[0], half[1]);
                let n = 3 - i - k;
                around.push(shift(shift(m, i, h), k, -h));
                around.push(shift(shift(m, i, -h), k, h));
                around.push(shift(m, n, h));
                around.push(shift(m, n, -h));
            }
            _ => {
                let i = half[0];
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                for (a, b) in [
                    (h, 0),
                    (-h, 0),
                    (0, h),
                    (0, -h),
                    (h, h),
                    (h, -h),
                    (-h, h),
                    (-h, -h),
                ] {
                    around.push(shift(shift(m, j, a), k, b));
                }
            }
        }
        around
            .into_iter()
            .filter(|&p| self.in_domain(p) && self.level_of(p) == Some(level - 1))
            .collect()
    }

    /// Marks the refinement edge of midpoint `m` and, recursively, every diamond it needs
    /// refined first; returns how many edges were newly marked.
    pub fn mark(&mut self, m: Point) -> usize {
        let mut fresh = Vec::new();
        self.mark_collecting(m, &mut fresh);
        fresh.len()
    }

    /// [`Refinement::mark`], appending to `fresh` the midpoint of every edge newly marked
    /// (the only tetrahedra that may split are those whose refinement edge is among them).
    pub fn mark_collecting(&mut self, m: Point, fresh: &mut Vec<Point>) {
        let mut stack = vec![m];
        while let Some(p) = stack.pop() {
            if self.marked.insert(pack(p)) {
                fresh.push(p);
                stack.extend(
                    self.parents(p)
                        .into_iter()
                        .filter(|&q| !self.marked.contains(&pack(q))),
                );
            }
        }
    }

    /// Whether `t` is bisected: below the finest level with its refinement edge marked.
    pub fn splits(&self, t: &Tet) -> bool {
        t.level < self.finest_level() && self.marked.contains(&pack(t.midpoint()))
    }

    /// `t` if it is not bisected, else the leaves below it, in order (first child first).
    pub fn expand(&self, t: Tet, out: &mut Vec<Tet>) {
        if self.splits(&t) {
            for c in t.children() {
                self.expand(c, out);
            }
        } else {
            out.push(t);
        }
    }

    /// The leaves of the hierarchy: every tetrahedron whose ancestors are all bisected and
    /// which is not, in the order of [`Refinement::coarse`] and then of the bisections.
    pub fn leaves(&self) -> Vec<Tet> {
        let mut out = Vec::new();
        for t in self.coarse() {
            self.expand(t, &mut out);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Each face as its sorted corners.
    fn faces(t: &Tet) -> [[Point; 3]; 4] {
        let c = t.corners;
        [
            [c[1], c[2], c[3]],
            [c[0], c[2], c[3]],
            [c[0], c[1], c[3]],
            [c[0], c[1], c[2]],
        ]
        .map(|mut f| {
            f.sort();
            f
        })
    }

    /// Conforming: every face inside the domain is shared by exactly two leaves, every face
    /// on its boundary belongs to one, and the volumes sum to the domain's.
    fn assert_conforming(r: &Refinement, leaves: &[Tet]) {
        let mut count: HashMap<[Point; 3], usize> = HashMap::new();
        let mut volume = 0i64;
        for t in leaves {
            let o = t.orientation();
            assert_ne!(o, 0, "{t:?}");
            volume += o.abs();
            for f in faces(t) {
                *count.entry(f).or_default() += 1;
            }
        }
        let e = r.extent();
        assert_eq!(
            volume,
            6 * i64::from(e).pow(3),
            "the leaves fill the domain"
        );
        for (f, n) in count {
            let on_boundary = (0..3).any(|i| {
                (f[0][i] == f[1][i] && f[1][i] == f[2][i]) && (f[0][i] == 0 || f[0][i] == e)
            });
            let want = if on_boundary { 1 } else { 2 };
            assert_eq!(n, want, "face {f:?} in {n} leaves");
        }
    }

    #[test]
    fn three_bisections_make_the_kuhn_tetrahedra_of_the_half_cubes() {
        let r = Refinement::new(1, 1);
        let mut level = r.coarse();
        for depth in 0..3 {
            // The refinement edges: the main diagonal, a face diagonal, an axis edge.
            for t in &level {
                let [a, b] = [t.corners[0], t.corners[t.tag as usize]];
                let d: Vec<i32> = (0..3).map(|i| (a[i] - b[i]).abs()).collect();
                let expected = [2, 2, 2, 2, 2, 0, 2, 0, 0];
                let mut sorted = d.clone();
                sorted.sort_unstable_by(|x, y| y.cmp(x));
                assert_eq!(sorted, &expected[3 * depth..3 * depth + 3], "{t:?}");
                assert_eq!(r.level_of(t.midpoint()), Some(depth as u8));
            }
            level = level.iter().flat_map(|t| t.children()).collect();
        }
        // 48 tetrahedra, six in each half cube around one of its main diagonals (the one
        // through the big cube's centre: the half cubes are mirror images of each other).
        assert_eq!(level.len(), 48);
        let centre = [1, 1, 1];
        for t in &level {
            let (lo, hi) = t.bounds();
            assert_eq!([0, 1, 2].map(|i| hi[i] - lo[i]), [1, 1, 1], "{t:?}");
            assert_eq!(t.orientation().abs(), 1, "{t:?}");
            assert!(t.corners.contains(&centre), "{t:?}");
            let far = [0, 1, 2].map(|i| if lo[i] == 1 { 2 } else { 0 });
            assert!(t.corners.contains(&far), "{t:?}");
        }
    }

    #[test]
    fn the_points_made_at_each_level_are_classified() {
        let r = Refinement::new(2, 2);
        assert_eq!(r.level_of([0, 4, 8]), None);
        assert_eq!(r.level_of([2, 2, 2]), Some(0));
        assert_eq!(r.level_of([2, 2, 4]), Some(1));
        assert_eq!(r.level_of([2, 4, 4]), Some(2));
        assert_eq!(r.level_of([1, 1, 1]), Some(3));
        assert_eq!(r.level_of([1, 3, 2]), Some(4));
        assert_eq!(r.level_of([1, 2, 6]), Some(5));
        assert_eq!(r.parents([2, 2, 2]), Vec::<Point>::new());
        assert_eq!(r.parents([2, 2, 4]).len(), 2);
        assert_eq!(r.parents([2, 4, 4]).len(), 4);
        assert_eq!(r.parents([1, 1, 1]).len(), 3);
        // On the domain's boundary a diamond has fewer parents.
        assert_eq!(r.parents([2, 2, 0]).len(), 1);
    }

    #[test]
    fn marking_any_edges_leaves_a_conforming_mesh() {
        // Marks scattered by a fixed pseudo-random sequence at every level, then the leaves.
        let r0 = Refinement::new(3, 2);
        let mut r = r0.clone();
        assert_conforming(&r, &r.leaves());
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        for round in 0..6 {
            let leaves = r.leaves();
            for _ in 0..(4 + round * 3) {
                let t = leaves[next() % leaves.len()];
                if t.level < r.finest_level() {
                    r.mark(t.midpoint());
                }
            }
            let leaves = r.leaves();
            assert_conforming(&r, &leaves);
            // Every leaf's edges are unmarked (no hanging vertex on an edge).
            for t in &leaves {
                for (a, b) in TET_EDGES {
                    let (p, q) = (t.corners[a], t.corners[b]);
                    if (0..3).all(|i| (p[i] - q[i]) % 2 == 0) {
                        let m = midpoint(p, q);
                        let made = r.level_of(m);
                        assert!(
                            !(r.marked.contains(&pack(m)) && made.is_some()),
                            "leaf {t:?} has a marked edge at {m:?}"
                        );
                    }
                }
            }
        }
        // Marking one edge of the finest level refines only around it.
        let mut one = r0;
        one.mark([1, 1, 2]);
        let leaves = one.leaves();
        assert_conforming(&one, &leaves);
        assert!(leaves.len() < 6 * 27 * 4, "{}", leaves.len());
    }
}
