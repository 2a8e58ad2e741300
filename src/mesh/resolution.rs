//! The local step: which tetrahedra to refine, by measurement. The solid is meshed on the
//! leaves of a conforming bisection of Kuhn tetrahedra ([`super::bisection`]): it starts
//! from a grid of cubes of the coarsest step (at most the clip radius /
//! [`FIRST_STEP_DIVISOR`]) and bisects a tetrahedron only where one of these checks fails for
//! it, down to cubes of the floor step of twice the tolerance (the step every surface got
//! before any search) for 2. and 3., and to cubes of the tolerance ([`BELOW_FLOOR`]) for 1.
//! (at the nodes and the sharpest bends), where everything is accepted:
//!
//! 1. **Accuracy**: every triangle marching tetrahedra makes in it (its vertices placed by the
//!    root finder, fanned from the first) has its centroid and edge midpoints within
//!    [`EXTRACT_SHARE`] of the tolerance of the boundary by the estimate `|φ|/|∇φ|`, with a
//!    second Newton step where the first leaves much of `φ` (beside a node:
//!    [`Field::distance_estimate`]) (a triangle with all vertices on the clip sphere:
//!    `|R − |x||`; one with vertices on both: the smaller of the two). And where a side of
//!    its polygon joins a surface vertex to a cap vertex with no crease point in its face
//!    (a chamfer that the extraction keeps, [`super::extract`]'s step 4), the crease within
//!    the tolerance of that side by [`Field::chamfer`], unless the solid's wedge there is
//!    thinner than twice the tolerance (a surface grazing the sphere, which the measurement
//!    counts apart as thin).
//! 2. **No edge crossed twice**: if its corners do not all have the same sign of `φ`, each of
//!    its six edges holds at most one distinct root of `φ` inside the clip ball: proven at
//!    once where `φ` is monotone along the edge by its coarse cube's bounds on `∇φ`, else
//!    counted exactly (Bernstein sign variations, then Sturm sequences by
//!    [`crate::roots::sturm_roots`] where those allow two or more). An edge crossed twice
//!    hides a handle, a thin part or a small piece between its ends. One exception, a shallow
//!    graze: exactly two roots, with the point midway between them within [`EXTRACT_SHARE`]
//!    of the tolerance of the surface and within [`GRAZE`] of the roots' distance apart (both
//!    by `|φ|/|∇φ|`): an edge nearly tangent to a curved sheet clips a cap off it no deeper
//!    than that.
//! 3. **No surface where the corners agree**: if its four corners have the same sign of `φ`
//!    (and its box meets the clip ball), it is proven free of `φ = 0` by a Taylor bound: with
//!    `φ(c + d) = Σ a_α d^α` about the centre `c` of its box, the remainder past the linear
//!    part is at most `Q = Σ_{|α|≥2} |a_α| r^{|α|}` on the cube of half-side `r` holding the
//!    box, and the linear part is least at a corner of the tetrahedron, so
//!    `s·φ ≥ min_corners s·φ − 2Q` in it (`s` the corners' sign; or
//!    `s·φ(c) − Σ_{|α|≥1} |a_α| r^{|α|}`, whichever is larger).
//!
//! Bisecting one tetrahedron bisects every tetrahedron around its refinement edge, and first
//! the coarser ones it needs ([`super::bisection::Refinement::mark`]), so the leaves stay
//! conforming and marching tetrahedra on them keeps every guarantee of a uniform grid. Each
//! round examines the leaves made by the last (in parallel; the marks are a set, so the
//! result does not depend on the number of threads).
//!
//! The work is kept to what can change the mesh: the leaves are kept per coarse cube, and a
//! round rebuilds only the cubes holding an edge it marked; a leaf in a cube proven empty, or
//! below a tetrahedron proven free of surface by 3., is not proven again; each edge's double
//! crossing (2.) and each polygon edge's crossing (1.) are computed once, by edge, whatever
//! the number of leaves sharing it, and the crossings are handed on to marching tetrahedra;
//! and the cubes proven empty where every corner has the same label (those wholly inside or
//! wholly outside the clip ball, and those outside the solid throughout, whatever the sphere
//! does) are neither labelled nor marched (a cube proven inside the solid that the sphere
//! cuts holds cap triangles and is kept).
//!
//! What this proves: within the ball, no piece of the surface that sampling at the floor
//! step would see lies inside a leaf whose corners agree (a small component, a bubble, a
//! bulge through a face), and no edge of a crossed leaf passes through the surface twice but
//! for a shallow graze. What it does not: features smaller than the floor step (as at the
//! floor itself); a second piece of surface wholly inside a crossed leaf that meets none of
//! its edges; the acute wedge at the crease that binary labels cannot see; and the
//! distance estimate of 1. is an estimate, not a bound, which the measured Hausdorff
//! distance afterwards checks. The Taylor bound is on `φ` expanded in monomials
//! ([`Field::expanded_terms`]: `±f`, or a shell's `f² − (T/2)²·|∇f|²`); a shell whose `φ`
//! has degree above [`MAX_DEGREE`] (a surface of degree 9 or more) is meshed on the uniform
//! grid of the floor step instead ([`super::extract::march`]). A shell's floor step is also
//! at most [`super::SHELL_FLOOR_SHARE`] of its thickness, so that its two sheets, each
//! crossing an edge, are told apart by 2. down to it.

use super::bisection::{kuhn_tetrahedra, Point, PointHasher, Refinement, Tet, TET_EDGES};
use super::extract::{self, marching_table, Crossings, Grid, Lattice, TablePolygon};
use super::field::{Field, SolidKind, VertexKind};
use super::TriangleMesh;
use crate::geometry::DVec3;
use crate::roots::sturm_roots;
use crate::shapes::implicit::MAX_DEGREE;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::sync::atomic::{AtomicBool, Ordering};

/// The share of the tolerance an extracted triangle may deviate from the surface (by the
/// distance estimate at its centroid and edge midpoints) for its tetrahedron to be kept:
/// the coarsening may then spend [`super::COARSEN_SHARE`] of it again.
pub const EXTRACT_SHARE: f64 = 0.75;

/// The coarsest step is at most the clip radius divided by this.
pub const FIRST_STEP_DIVISOR: f64 = 8.0;

/// How many more times than down to the floor step a cube's side may be halved for the
/// check 1. of the module doc (2. and 3. stop at the floor): at a node, where the floor's
/// triangles open or close the cone about half the floor step off the surface (a little
/// more than the tolerance), and at the sharpest bends. (Bisecting below the floor for 2.
/// too made Barth's sextic slower, with passes of its coarsening redone for crossings, and
/// no closer.)
pub const BELOW_FLOOR: u32 = 1;

/// Why a tetrahedron was bisected (module doc, 1. to 3.).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason {
    /// A triangle in it deviates by more than [`EXTRACT_SHARE`] of the tolerance.
    Deviation = 0,
    /// An edge of it (its corners differing in sign) crosses `φ = 0` twice.
    EdgeCrossedTwice = 1,
    /// Its corners agree in sign, and the Taylor bound does not prove it free of surface.
    SurfaceUnproven = 2,
    /// A side of its polygon from a surface vertex to a cap vertex finds no crease point in
    /// its face, and the crease lies farther than the tolerance from it where the solid's
    /// wedge is no thinner than twice the tolerance ([`Field::chamfer`]).
    ChamferedCrease = 3,
}

/// What the refinement made (object units).
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The domain's cubes: the coarsest step, each cut into six Kuhn tetrahedra.
    pub coarse: Grid,
    /// How many times a cube's side may be halved: the finest cubes have side
    /// `coarse.step() / 2^depth`, their tetrahedra level `3·depth`.
    pub depth: u32,
    /// How many times a cube's side is halved down to the floor step (twice the tolerance),
    /// where the proofs of emptiness stop: `depth` less [`BELOW_FLOOR`] (or `depth`).
    pub floor_depth: u32,
    /// Leaf tetrahedra at each level (`0..=3·depth`; the cube side of level `ℓ` is
    /// [`Refined::cube_side`]).
    pub leaves_by_level: Vec<usize>,
    /// Of those, the leaves whose corners' labels differ (where the mesh is), at each level.
    pub crossed_by_level: Vec<usize>,
    /// Tetrahedra bisected for each [`Reason`] (indexed by it), not counting those bisected
    /// to keep the leaves conforming.
    pub refined_for: [usize; 4],
    /// Rounds of examination.
    pub rounds: usize,
}

impl Refined {
    /// The side of the cube a tetrahedron of `level` lies in (object units).
    pub fn cube_side(&self, level: usize) -> f64 {
        self.coarse.step() / f64::from(1u32 << (level / 3))
    }

    /// Leaf tetrahedra in all.
    pub fn leaves(&self) -> usize {
        self.leaves_by_level.iter().sum()
    }

    /// Leaf tetrahedra the mesh passes through (their corners' labels differ).
    pub fn crossed(&self) -> usize {
        self.crossed_by_level.iter().sum()
    }

    /// Tetrahedra a uniform grid of the floor step over the same domain would have.
    pub fn uniform_leaves(&self) -> usize {
        6 * (self.coarse.cells << self.floor_depth).pow(3)
    }

    /// The floor step: the side of the cubes where the proofs of emptiness stop (object
    /// units).
    pub fn floor_side(&self) -> f64 {
        self.coarse.step() / f64::from(1u32 << self.floor_depth)
    }

    /// The largest cube side of a leaf the mesh passes through (object units).
    pub fn coarsest_crossed_side(&self) -> f64 {
        self.crossed_by_level
            .iter()
            .position(|&n| n > 0)
            .map_or(0.0, |level| self.cube_side(level))
    }
}

/// How many times the coarsest cube's side is halved to reach the floor step `floor`: the
/// most with `floor·2^depth ≤ radius /` [`FIRST_STEP_DIVISOR`]; 0 when `φ`'s `degree` is
/// above [`MAX_DEGREE`] (a shell of a surface of degree 9 or more, beyond the root finder
/// and the Taylor bound here), which is meshed on the floor's uniform grid.
pub fn depth_for(radius: f64, floor: f64, degree: usize) -> u32 {
    if degree > MAX_DEGREE {
        return 0;
    }
    let mut depth = 0;
    while floor * f64::from(2u32 << depth) <= radius / FIRST_STEP_DIVISOR && depth < 12 {
        depth += 1;
    }
    depth
}

type PointMap<V> = HashMap<u64, V, BuildHasherDefault<PointHasher>>;

/// A coarse cube's leaves in order, each with whether it is known to be free of `φ = 0`.
type CubeLeaves = Vec<(Tet, bool)>;

/// Whether an edge ([`extract::edge_key`]) crosses `φ = 0` twice ([`crossed_twice`], from
/// its smaller packed end to the other).
type EdgeMap = HashMap<u128, bool, BuildHasherDefault<PointHasher>>;

/// `φ` at lattice points, computed once each.
struct Values {
    lattice: Lattice,
    map: PointMap<f64>,
}

impl Values {
    /// Computes `φ` (in parallel) at those of `points` not yet known.
    fn fill(&mut self, field: &Field, points: impl Iterator<Item = Point>) {
        let mut missing: Vec<u64> = points
            .map(extract::pack)
            .filter(|k| !self.map.contains_key(k))
            .collect();
        missing.par_sort_unstable();
        missing.dedup();
        let lattice = self.lattice;
        let computed: Vec<f64> = missing
            .par_iter()
            .map(|&k| field.value(lattice.position(extract::unpack(k))))
            .collect();
        self.map.extend(missing.into_iter().zip(computed));
    }

    fn get(&self, p: Point) -> f64 {
        self.map[&extract::pack(p)]
    }
}

/// The tetrahedra of the refinement's leaves and how they came about: see the module doc.
pub struct Adaptive {
    /// The marked edges.
    pub refinement: Refinement,
    /// The leaves the boundary passes through (their corners' labels differ), in the order
    /// of [`Refinement::leaves`] (whatever the number of threads); the others hold no
    /// triangle.
    pub leaves: Vec<Tet>,
    /// Each of those leaves' labels: bit `k` set when its corner `k` is inside
    /// ([`Field::inside`]).
    pub labels: Vec<u8>,
    /// Where the lattice lies in object space.
    pub lattice: Lattice,
    /// The crossings of edges the examinations placed vertices on ([`Field::crossing`] from
    /// the inside end), some of those marching tetrahedra needs.
    pub crossings: Crossings,
    /// What was made.
    pub refined: Refined,
}

/// Refines the Kuhn tetrahedra of `coarse` (`depth` ≥ 1 halvings down to the floor, and
/// [`BELOW_FLOOR`] more for the deviation check) where the checks of the module doc fail;
/// `tolerance` in object units. `progress(done, total)` after each round; `None` once
/// `cancel` is set (read before each round).
pub fn refine(
    field: &Field,
    coarse: Grid,
    depth: u32,
    tolerance: f64,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Option<Adaptive> {
    let (floor_depth, floor_level) = (depth, (3 * depth) as u8);
    let depth = finest_depth(coarse, depth);
    let mut refinement = Refinement::new(coarse.cells, depth);
    let lattice = Lattice::of_grid(coarse, depth);
    let mut values = Values {
        lattice,
        map: PointMap::default(),
    };
    let examiner = Examiner {
        spreads: Vec::new(),
        cube_side: 1,
        cells: 0,
        field,
        lattice,
        taylor: Taylor::new(field),
        table: marching_table(),
        tolerance,
        floor_level,
        f_sign: if field.kind() == SolidKind::Outside {
            -1.0
        } else {
            1.0
        },
    };
    let finest = refinement.finest_level();
    let total = 3 * depth as usize + 2;
    // Each leaf with whether it has been examined (or needs no examination): the coarse
    // cubes the Taylor bound about their centre proves free of surface need none (tried
    // first for blocks of BLOCK³ cubes at once).
    const BLOCK: usize = 4;
    let n = coarse.cells;
    let side = refinement.cube_side();
    let blocks = n.div_ceil(BLOCK);
    let cube_box = |x: usize, y: usize, z: usize, size: usize| {
        let lo = [x, y, z].map(|v| (v * side as usize) as i32);
        let hi = lo.map(|v| v + (size * side as usize) as i32);
        (lattice.position(lo), lattice.position(hi))
    };
    let block_sign: Vec<Option<f64>> = (0..blocks * blocks * blocks)
        .into_par_iter()
        .map(|b| {
            let (x, y, z) = (b % blocks, b / blocks % blocks, b / (blocks * blocks));
            let (lo, hi) = cube_box(x * BLOCK, y * BLOCK, z * BLOCK, BLOCK);
            examiner.empty_sign(lo, hi)
        })
        .collect();
    // Each cube's emptiness and, for the cubes not proven empty, φ's gradient at the centre
    // and how far it strays over the cube (the cheap bound of Examiner::quiet), from one
    // Taylor expansion about the cube's centre.
    let (empty_sign, spreads): (Vec<Option<f64>>, Vec<Option<Spread>>) = (0..n * n * n)
        .into_par_iter()
        .map(|c| {
            let (x, y, z) = (c % n, c / n % n, c / (n * n));
            let block = x / BLOCK + blocks * (y / BLOCK + blocks * (z / BLOCK));
            if let Some(sign) = block_sign[block] {
                return (Some(sign), None);
            }
            let (lo, hi) = cube_box(x, y, z, 1);
            let centre = 0.5 * (lo + hi);
            let r = 0.5 * (hi - lo).max_element();
            if examiner.outside_box(lo, hi) {
                return (Some(1.0), None);
            }
            let coef = examiner.taylor.coefficients(centre);
            if let Some(sums) = examiner.taylor.sums(&coef, centre, r) {
                if sums.proves_empty() {
                    return (Some(examiner.f_sign * sums.value.signum()), None);
                }
            }
            (None, Some(examiner.spread(&coef, centre, r)))
        })
        .unzip();
    let examiner = Examiner {
        spreads,
        cube_side: side,
        cells: n,
        ..examiner
    };
    // Each coarse cube's leaves, in the order of `Refinement::leaves` (empty while they are
    // still its six Kuhn tetrahedra), each with whether it is known to be free of `φ = 0`
    // (module doc, 3.: in a cube proven empty, or proven itself or below a tetrahedron
    // proven so, whose halves need no proof). The leaves to examine are those not yet
    // examined: at first the Kuhn tetrahedra of the cubes not proven empty, then the leaves
    // each round's bisections make (below the finest level), wherever they are; `todo`
    // holds them as (cube, index among its leaves).
    let kuhn = |c: usize| {
        let (x, y, z) = (c % n, c / n % n, c / (n * n));
        kuhn_tetrahedra([x, y, z].map(|v| v as i32 * side), side)
    };
    let mut cube_leaves: Vec<CubeLeaves> = vec![Vec::new(); n * n * n];
    let mut todo: Vec<(usize, usize)> = Vec::new();
    for c in (0..n * n * n).filter(|&c| empty_sign[c].is_none()) {
        cube_leaves[c] = kuhn(c).map(|t| (t, false)).to_vec();
        todo.extend((0..6).map(|i| (c, i)));
    }
    let mut refined_for = [0usize; 4];
    let mut rounds = 0;
    let mut fresh = Vec::new();
    let mut twice = EdgeMap::default();
    let mut crossings = Crossings::default();
    loop {
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        if todo.is_empty() {
            break;
        }
        rounds += 1;
        let leaf = |&(c, i): &(usize, usize)| cube_leaves[c][i];
        values.fill(
            field,
            todo.iter().flat_map(|e| leaf(e).0.corners.into_iter()),
        );
        // Whether each edge of the crossed leaves is crossed twice (module doc, 2.): once
        // for every edge, however many leaves share it, in any round.
        let mut edges: Vec<u128> = todo
            .par_iter()
            .map(leaf)
            .filter(|(t, _)| examiner.edges_matter(t, &values))
            .flat_map_iter(|(t, _)| {
                TET_EDGES.map(|(a, b)| extract::edge_key(t.corners[a], t.corners[b]))
            })
            .filter(|k| !twice.contains_key(k))
            .collect();
        edges.par_sort_unstable();
        edges.dedup();
        let crossed: Vec<bool> = edges
            .par_iter()
            .map(|&k| {
                let (p, q) = (extract::unpack((k >> 64) as u64), extract::unpack(k as u64));
                !examiner.monotone_along(p, q)
                    && crossed_twice(
                        field,
                        lattice.position(p),
                        lattice.position(q),
                        examiner.shallow(),
                    )
            })
            .collect();
        twice.extend(edges.into_iter().zip(crossed));
        let checked: Vec<(Checked, bool)> = todo
            .par_iter()
            .map(|e| {
                let (t, quiet) = leaf(e);
                examiner.examine(&t, quiet, &values, &twice)
            })
            .collect();
        // Where the boundary crosses each edge of the polygons of the leaves that passed
        // (module doc, 1.): once for every edge, from its inside end, in any round (and
        // again in marching tetrahedra).
        let mut ends: Vec<(u128, Point, Point)> = todo
            .par_iter()
            .zip(&checked)
            .filter_map(|(e, &(checked, _))| match checked {
                Checked::Pass { case } => Some((leaf(e).0, examiner.table[case].as_ref()?)),
                Checked::Bisect(_) => None,
            })
            .flat_map_iter(|(t, polygon)| {
                polygon.iter().map(move |&[i, j]| {
                    let (a, b) = (t.corners[i as usize], t.corners[j as usize]);
                    (extract::edge_key(a, b), a, b)
                })
            })
            .filter(|(k, _, _)| !crossings.contains_key(k))
            .collect();
        ends.par_sort_unstable_by_key(|e| e.0);
        ends.dedup_by_key(|e| e.0);
        let placed: Vec<(f64, VertexKind)> = ends
            .par_iter()
            .map(|&(_, a, b)| field.crossing(lattice.position(a), lattice.position(b)))
            .collect();
        crossings.extend(ends.into_iter().map(|e| e.0).zip(placed));
        let verdicts: Vec<(Option<Reason>, bool)> = todo
            .par_iter()
            .zip(&checked)
            .map(|(e, &(checked, quiet))| match checked {
                Checked::Bisect(reason) => (Some(reason), quiet),
                Checked::Pass { case } => (examiner.deviation(&leaf(e).0, case, &crossings), quiet),
            })
            .collect();
        fresh.clear();
        for (&(c, i), &(verdict, quiet)) in todo.iter().zip(&verdicts) {
            let (t, known) = &mut cube_leaves[c][i];
            *known = quiet;
            if let Some(reason) = verdict {
                refined_for[reason as usize] += 1;
                refinement.mark_collecting(t.midpoint(), &mut fresh);
            }
        }
        // Only a leaf whose refinement edge was just marked splits, and it lies in a coarse
        // cube whose closed box holds that edge's midpoint.
        let mut dirty: Vec<usize> = fresh
            .iter()
            .flat_map(|&m| cubes_holding(m, side, n))
            .collect();
        dirty.sort_unstable();
        dirty.dedup();
        let before: Vec<CubeLeaves> = dirty
            .iter()
            .map(|&c| std::mem::take(&mut cube_leaves[c]))
            .collect();
        let rebuilt: Vec<(CubeLeaves, Vec<usize>)> = dirty
            .par_iter()
            .zip(before)
            .map(|(&c, old)| {
                let old = if old.is_empty() {
                    kuhn(c).map(|t| (t, empty_sign[c].is_some())).to_vec()
                } else {
                    old
                };
                let (mut leaves, mut made, mut below) = (Vec::new(), Vec::new(), Vec::new());
                for (t, quiet) in old {
                    if refinement.splits(&t) {
                        below.clear();
                        refinement.expand(t, &mut below);
                        for &b in &below {
                            if b.level < finest {
                                made.push(leaves.len());
                            }
                            leaves.push((b, quiet));
                        }
                    } else {
                        leaves.push((t, quiet));
                    }
                }
                (leaves, made)
            })
            .collect();
        todo.clear();
        for (&c, (leaves, made)) in dirty.iter().zip(rebuilt) {
            cube_leaves[c] = leaves;
            todo.extend(made.into_iter().map(|i| (c, i)));
        }
        progress(rounds.min(total - 1), total);
    }
    // The cubes proven empty that lie wholly inside or wholly outside the clip ball (with a
    // margin for the rounding of the corners' positions): every corner of their leaves has
    // the same label, so they hold no triangle and are neither labelled nor marched.
    let r2 = field.radius() * field.radius();
    let uniform = |c: usize| {
        let (x, y, z) = (c % n, c / n % n, c / (n * n));
        let (lo, hi) = cube_box(x, y, z, 1);
        let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let nearest = (centre.abs() - half).max(DVec3::ZERO).length_squared();
        let farthest = (centre.abs() + half).length_squared();
        nearest > r2 * (1.0 + 1e-9) || farthest < r2 * (1.0 - 1e-9)
    };
    let mut refined = Refined {
        coarse,
        depth,
        floor_depth,
        leaves_by_level: vec![0; finest as usize + 1],
        crossed_by_level: vec![0; finest as usize + 1],
        refined_for,
        rounds,
    };
    let mut kept: Vec<Tet> = Vec::new();
    for (c, leaves) in cube_leaves.iter().enumerate() {
        // A cube where φ > 0 throughout (or wholly outside the ball) has every corner
        // outside, whatever the sphere does.
        let skip = empty_sign[c].is_some_and(|sign| sign > 0.0 || uniform(c));
        if leaves.is_empty() {
            refined.leaves_by_level[0] += 6;
            if !skip {
                kept.extend(kuhn(c));
            }
        } else {
            for (t, _) in leaves {
                refined.leaves_by_level[t.level as usize] += 1;
            }
            if !skip {
                kept.extend(leaves.iter().map(|&(t, _)| t));
            }
        }
    }
    values.fill(field, kept.iter().flat_map(|t| t.corners.into_iter()));
    let labels: Vec<u8> = kept
        .par_iter()
        .map(|t| {
            (0..4).fold(0u8, |m, k| {
                let p = t.corners[k];
                let inside = lattice.position(p).length_squared() < r2 && values.get(p) < 0.0;
                m | u8::from(inside) << k
            })
        })
        .collect();
    let (leaves, labels): (Vec<Tet>, Vec<u8>) = kept
        .into_iter()
        .zip(labels)
        .filter(|&(_, m)| m != 0 && m != 15)
        .unzip();
    for t in &leaves {
        refined.crossed_by_level[t.level as usize] += 1;
    }
    Some(Adaptive {
        refinement,
        leaves,
        labels,
        lattice,
        crossings,
        refined,
    })
}

/// How many times a side of `coarse`'s cubes may be halved at most: `depth` (down to the
/// floor step) and [`BELOW_FLOOR`] more, unless the lattice would then be too large.
fn finest_depth(coarse: Grid, depth: u32) -> u32 {
    let deeper = depth + BELOW_FLOOR;
    if deeper <= 20 && coarse.cells << deeper < 1 << 21 {
        deeper
    } else {
        depth
    }
}

/// The coarse cubes (x fastest, `n` a side of `side` lattice units) whose closed box holds
/// the lattice point `m`: one, or two, four or eight where `m` lies on their faces.
fn cubes_holding(m: Point, side: i32, n: usize) -> impl Iterator<Item = usize> {
    let range = |v: i32| {
        let c = (v / side) as usize;
        let first = if v % side == 0 && c > 0 { c - 1 } else { c };
        first..=c.min(n - 1)
    };
    let (rx, ry, rz) = (range(m[0]), range(m[1]), range(m[2]));
    rz.flat_map(move |z| {
        let rx = rx.clone();
        ry.clone()
            .flat_map(move |y| rx.clone().map(move |x| x + n * (y + n * z)))
    })
}

/// The mesh of `field`'s solid (object space, each vertex's kind) on the leaves of
/// [`refine`] for `coarse` and `depth` (≥ 1), with what the refinement made; `None` once
/// `cancel` is set.
pub fn mesh_adaptive(
    field: &Field,
    coarse: Grid,
    depth: u32,
    tolerance: f64,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Option<(TriangleMesh, Vec<VertexKind>, Refined)> {
    let adaptive = refine(field, coarse, depth, tolerance, progress, cancel)?;
    let (mesh, kinds) = extract::march_leaves(
        field,
        adaptive.lattice,
        &adaptive.leaves,
        &adaptive.labels,
        &adaptive.crossings,
        cancel,
    )?;
    let total = 3 * adaptive.refined.depth as usize + 2;
    progress(total, total);
    Some((mesh, kinds, adaptive.refined))
}

/// What the checks 2. and 3. of the module doc found for a tetrahedron.
#[derive(Debug, Clone, Copy)]
enum Checked {
    /// It must be bisected.
    Bisect(Reason),
    /// It passes them; `case` holds its corners' labels (bit `k` for corner `k`, as in the
    /// marching table), whose polygon's triangles check 1. measures.
    Pass { case: usize },
}

/// The checks of the module doc for one tetrahedron.
struct Examiner<'a> {
    field: &'a Field,
    lattice: Lattice,
    taylor: Taylor,
    table: Vec<Option<TablePolygon>>,
    /// The tolerance (object units): also how far the crease may lie from a chamfered side
    /// (the coarsening never changes the triangles joining a surface vertex to a cap vertex),
    /// and twice it the width below which the measurement counts a part of the solid as thin
    /// (`super::accuracy::measure`), where a chamfer is left.
    tolerance: f64,
    /// The level of the floor step's tetrahedra, at and below which corners of the same sign
    /// are accepted (module doc, 3.).
    floor_level: u8,
    /// `φ = f_sign · f` (1 inside, −1 outside).
    f_sign: f64,
    /// For each coarse cube (x fastest) not proven empty: how `∇φ` strays over it.
    spreads: Vec<Option<Spread>>,
    /// The side of a coarse cube (lattice units) and cubes a side.
    cube_side: i32,
    cells: usize,
}

/// `∇φ` at a coarse cube's centre and, per axis, a bound on how far `∂_i φ` strays from it
/// over the cube ([`Taylor::spread`]).
struct Spread {
    gradient: DVec3,
    spread: DVec3,
    /// A margin for rounding.
    margin: f64,
}

impl Examiner<'_> {
    /// The deepest graze allowed; also the deviation allowed ([`EXTRACT_SHARE`] of the
    /// tolerance).
    fn shallow(&self) -> f64 {
        EXTRACT_SHARE * self.tolerance
    }

    /// Whether `examine` asks whether `t`'s edges are crossed twice: its box meets the clip
    /// ball and its corners' signs of `φ` differ.
    fn edges_matter(&self, t: &Tet, values: &Values) -> bool {
        !self.outside_ball(t) && common_sign(&t.corners.map(|p| values.get(p))).is_none()
    }

    /// Why `t` must be bisected, or `None` if it passes every check, and whether it is now
    /// known to be free of `φ = 0` (module doc, 3.); `twice` holds [`crossed_twice`] for its
    /// edges if [`Examiner::edges_matter`]. A tetrahedron already `known_quiet` (in a cube
    /// or below a tetrahedron proven so) needs no proof again: the virtual bisection of
    /// [`Examiner::quiet`] for it is part of that for its ancestor.
    fn examine(
        &self,
        t: &Tet,
        known_quiet: bool,
        values: &Values,
        twice: &EdgeMap,
    ) -> (Checked, bool) {
        if self.outside_ball(t) {
            return (Checked::Pass { case: 0 }, known_quiet);
        }
        let points = t.corners.map(|p| self.lattice.position(p));
        let phi = t.corners.map(|p| values.get(p));
        let quiet = match common_sign(&phi) {
            Some(sign) => {
                if !known_quiet && !self.quiet(t, sign, phi) {
                    return (Checked::Bisect(Reason::SurfaceUnproven), false);
                }
                true
            }
            // Below the floor only the deviation (1.) is checked.
            None if t.level >= self.floor_level => false,
            None => {
                for (a, b) in TET_EDGES {
                    if twice[&extract::edge_key(t.corners[a], t.corners[b])] {
                        return (Checked::Bisect(Reason::EdgeCrossedTwice), false);
                    }
                }
                false
            }
        };
        let r2 = self.field.radius() * self.field.radius();
        let labels =
            std::array::from_fn::<bool, 4, _>(|i| points[i].length_squared() < r2 && phi[i] < 0.0);
        let case = (0..4).fold(0usize, |m, i| m | usize::from(labels[i]) << i);
        (Checked::Pass { case }, quiet)
    }

    /// [`Reason::Deviation`] if a triangle marching tetrahedra makes in `t` (its corners'
    /// labels `case`, as in [`Checked::Pass`]) deviates beyond the share allowed (module doc,
    /// 1.); `crossings` holds its polygon's edges' crossings.
    fn deviation(&self, t: &Tet, case: usize, crossings: &Crossings) -> Option<Reason> {
        let field = self.field;
        let polygon = self.table[case].as_ref()?;
        let placed: Vec<(DVec3, VertexKind)> = polygon
            .iter()
            .map(|&[i, j]| {
                let (p, q) = (t.corners[i as usize], t.corners[j as usize]);
                let (a, b) = (self.lattice.position(p), self.lattice.position(q));
                let crossing = crossings[&extract::edge_key(p, q)];
                (field.crossing_point(a, b, crossing), crossing.1)
            })
            .collect();
        for k in 1..placed.len() - 1 {
            let corners = [placed[0], placed[k], placed[k + 1]];
            let worst = triangle_deviation(field, corners.map(|c| c.0), corners.map(|c| c.1));
            if worst.is_nan() || worst > self.shallow() {
                return Some(Reason::Deviation);
            }
        }
        // A side from a surface vertex to a cap vertex cuts the solid's wedge at the crease
        // unless the extraction finds a crease point in its face (step 4 of
        // `extract::assemble`); the triangles' deviation cannot see how deep. The crease is
        // farther than the tolerance from it, unless the solid is so thin there that the
        // surface the chamfer cuts off is all within twice the tolerance of the sphere (where
        // a grazing surface meets it): the measurement counts such places apart, and
        // bisecting would not reach them before the floor. The estimate is one gradient; the
        // search for the crease point, the dearer test, is made only where it fails.
        let n = placed.len();
        for i in 0..n {
            let (e1, e2) = (polygon[i], polygon[(i + 1) % n]);
            let (v1, v2) = (placed[i], placed[(i + 1) % n]);
            let (cap_edge, other_edge, cap, surface) = match (v1.1, v2.1) {
                (VertexKind::Cap, VertexKind::Surface) => (e1, e2, v1.0, v2.0),
                (VertexKind::Surface, VertexKind::Cap) => (e2, e1, v2.0, v1.0),
                _ => continue,
            };
            let Some(face) = extract::side_face(cap_edge, other_edge) else {
                continue;
            };
            let deep = field
                .chamfer(surface, cap)
                .is_some_and(|c| c.gap > self.tolerance && c.width >= 2.0 * self.tolerance);
            if deep
                && field
                    .crease(
                        face.map(|c| self.lattice.position(t.corners[c as usize])),
                        cap,
                    )
                    .is_none()
            {
                return Some(Reason::ChamferedCrease);
            }
        }
        None
    }

    /// Whether the tetrahedron `t`, whose corners (values `phi`) all have the sign `sign` of
    /// `φ`, holds no surface the floor would see (module doc, 3.): proven by the cheap bound
    /// ([`Examiner::gradient_bound`]), or else bisected (without changing the mesh) into the
    /// tetrahedra below it, each proven by the cheap bound, down to the floor's level, where
    /// corners of the same sign are accepted, or else by the Taylor bound about its centre.
    /// A tetrahedron below it whose new corner has the other sign fails the bisection.
    fn quiet(&self, t: &Tet, sign: f64, phi: [f64; 4]) -> bool {
        // The Taylor bound about the tetrahedron's own centre is dearer than the virtual
        // bisection usually is, so it is tried last. The order does not change the answer:
        // the bisection fails only at a point of `t` where `s·φ ≤ 0` (or NaN), and the Taylor
        // bound, rigorous over `t` with a margin for rounding, then fails too.
        t.level >= self.floor_level
            || self.gradient_bound(t, sign, &phi)
            || self.split_quiet(t, sign, phi)
            || self.proven_empty(t, sign, &phi)
    }

    /// The tetrahedra below `t` (corner values `phi`, sign `sign`) quiet: [`Examiner::quiet`]
    /// by the cheap bound only ([`Examiner::gradient_bound`]), the Taylor bound about each
    /// part's own centre being the dearest part of the examination.
    fn below_quiet(&self, t: &Tet, sign: f64, phi: [f64; 4]) -> bool {
        if t.level >= self.floor_level || self.gradient_bound(t, sign, &phi) {
            return true;
        }
        self.split_quiet(t, sign, phi)
    }

    /// [`Examiner::below_quiet`] for the two halves of `t`, after checking the sign at the
    /// new corner.
    fn split_quiet(&self, t: &Tet, sign: f64, phi: [f64; 4]) -> bool {
        let m = t.midpoint();
        let x = self.lattice.position(m);
        let value = self.field.value(x);
        if sign * value <= 0.0 || value.is_nan() {
            // Surface in the tetrahedron (or its box's part outside the ball).
            return false;
        }
        let k = t.tag as usize;
        let [first, second] = t.children();
        let mut a = phi;
        a[k] = value;
        let mut b = phi;
        b[..k].copy_from_slice(&phi[1..=k]);
        b[k] = value;
        self.below_quiet(&first, sign, a) && self.below_quiet(&second, sign, b)
    }

    /// The cheap bound: with `g` the gradient of `φ` at the centre of the coarse cube holding
    /// `t` and `L_i` the bound on `|∂_i φ − g_i|` over that cube, for any corner `v` and any
    /// point `x` of `t`, `s·φ(x) ≥ s·φ(v) + s·g·(x − v) − Σ L_i |x_i − v_i|`, a concave
    /// function of `x`, least at a corner: `t` is proven free of surface if for some `v`
    /// that is positive at every corner.
    fn gradient_bound(&self, t: &Tet, sign: f64, phi: &[f64; 4]) -> bool {
        let Some(s) = self.cube_spread(t.bounds().0) else {
            return self.proven_empty(t, sign, phi);
        };
        let points = t.corners.map(|p| self.lattice.position(p));
        // least[v] = min over corners w of s·g·(w − v) − Σ L_i |w_i − v_i| (and 0, for w = v).
        // Each pair is computed once: swapping v and w negates the linear part exactly and
        // leaves the spread part unchanged.
        let mut least = [0.0f64; 4];
        for (v, w) in TET_EDGES {
            let d = points[w] - points[v];
            let linear = sign * s.gradient.dot(d);
            let spread = s.spread.dot(d.abs());
            least[v] = least[v].min(linear - spread);
            least[w] = least[w].min(-linear - spread);
        }
        (0..4).any(|v| sign * phi[v] + least[v] > s.margin)
    }

    /// How `∇φ` strays over the cube of half-side `r` about `centre`, from `f`'s Taylor
    /// coefficients about it ([`Taylor::coefficients`]).
    fn spread(&self, coef: &[f64], centre: DVec3, r: f64) -> Spread {
        let (value, gradient, spread) = self.taylor.spread(coef, r);
        Spread {
            gradient: self.f_sign * gradient,
            spread,
            margin: 1e-10 * (value.abs() + self.taylor.magnitude_bound(centre)),
        }
    }

    /// The spread of the coarse cube whose closed box holds whatever lies in it between the
    /// lattice point `lo` and points above it on every axis (a leaf with that least corner;
    /// on a face, either cube holds it), or `None` for a cube proven empty.
    fn cube_spread(&self, lo: Point) -> Option<&Spread> {
        let n = self.cells;
        let cube = lo.map(|c| ((c / self.cube_side) as usize).min(n - 1));
        self.spreads[cube[0] + n * (cube[1] + n * cube[2])].as_ref()
    }

    /// Whether `φ` is proven strictly monotone along the segment between the lattice points
    /// `p` and `q` (within one coarse cube, as a leaf's edge is), so that it crosses `φ = 0`
    /// at most once: `|g·e| > Σ L_i |e_i|` with `e = q − p` and the gradient `g` and its
    /// bounds `L_i` of the coarse cube that holds the segment ([`Spread`]).
    fn monotone_along(&self, p: Point, q: Point) -> bool {
        let lo = std::array::from_fn(|i| p[i].min(q[i]));
        let Some(s) = self.cube_spread(lo) else {
            return false;
        };
        let e = self.lattice.position(q) - self.lattice.position(p);
        let along = s.gradient.dot(e).abs();
        let stray = s.spread.dot(e.abs());
        along - stray > s.margin + 1e-9 * (along + stray)
    }

    /// Whether the box `lo`–`hi` is proven free of `φ = 0` inside the clip ball, with the
    /// sign every lattice point's `φ` then has for its label (1: outside): `Some(1)` if it
    /// lies wholly outside the ball, `Some(sign of φ(c))` if `|φ(c)| > Σ_{|α|≥1} |a_α|
    /// r^{|α|}` about its centre `c` (`r` its largest half-side), else `None`.
    fn empty_sign(&self, lo: DVec3, hi: DVec3) -> Option<f64> {
        let centre = 0.5 * (lo + hi);
        if self.outside_box(lo, hi) {
            return Some(1.0);
        }
        let sums = self.taylor.at(centre, 0.5 * (hi - lo).max_element())?;
        sums.proves_empty()
            .then(|| self.f_sign * sums.value.signum())
    }

    /// Whether the box `lo`–`hi` lies wholly outside the clip ball.
    fn outside_box(&self, lo: DVec3, hi: DVec3) -> bool {
        let centre = 0.5 * (lo + hi);
        let nearest = (centre.abs() - 0.5 * (hi - lo)).max(DVec3::ZERO);
        let radius = self.field.radius();
        nearest.length_squared() >= radius * radius
    }

    /// Whether the box of `t` lies wholly outside the clip ball.
    fn outside_ball(&self, t: &Tet) -> bool {
        let (lo, hi) = t.bounds();
        let (lo, hi) = (self.lattice.position(lo), self.lattice.position(hi));
        let nearest = (0.5 * (lo + hi)).abs() - 0.5 * (hi - lo);
        let r = self.field.radius();
        nearest.max(DVec3::ZERO).length_squared() >= r * r
    }

    /// Whether the Taylor bound proves `φ` of sign `sign` throughout the tetrahedron `t`
    /// with corner values `phi` (module doc, 3.): about the centre `c` of its box, with `r`
    /// the box's largest half-side, the linear part `s·(φ(c) + ∇φ(c)·(v − c))` is least at a
    /// corner `v` and the rest is at most `Q` in absolute value; also `min s·φ(v) − 2Q`.
    fn proven_empty(&self, t: &Tet, sign: f64, phi: &[f64; 4]) -> bool {
        let (lo, hi) = t.bounds();
        let (lo, hi) = (self.lattice.position(lo), self.lattice.position(hi));
        let centre = 0.5 * (lo + hi);
        let r = 0.5 * (hi - lo).max_element();
        if self.outside_ball(t) {
            return true;
        }
        self.taylor.at(centre, r).is_some_and(|sums| {
            let least_corner = phi.iter().map(|v| sign * v).fold(f64::INFINITY, f64::min);
            // The Taylor sums are of f (a shell's φ itself); φ = ±f.
            let s = sign * self.f_sign;
            let centre_value = s * sums.value;
            let least_linear = t
                .corners
                .iter()
                .map(|&p| centre_value + s * sums.gradient.dot(self.lattice.position(p) - centre))
                .fold(f64::INFINITY, f64::min);
            let bound = (least_corner - 2.0 * sums.quadratic).max(least_linear - sums.quadratic);
            // A margin for the rounding of the values and of the bound's own sums.
            bound > 1e-10 * sums.magnitude
        })
    }
}

/// The largest estimated deviation of the triangle `corners` (vertex kinds `kinds`) from
/// the boundary at its centroid and edge midpoints (object units; module doc, 1.): infinite
/// where `∇φ` vanishes (a node). `∇φ` is exact for the inside and outside
/// ([`Field::value_and_gradient`]).
pub fn triangle_deviation(field: &Field, corners: [DVec3; 3], kinds: [VertexKind; 3]) -> f64 {
    let h = 1e-7 * field.radius();
    let off_surface = |p: DVec3| field.distance_estimate(p, h);
    let off_sphere = |p: DVec3| (field.radius() - p.length()).abs();
    let [a, b, c] = corners;
    let surface = kinds.iter().all(|k| k.on_surface());
    let sphere = kinds.iter().all(|k| k.on_sphere());
    [
        (a + b + c) / 3.0,
        0.5 * (a + b),
        0.5 * (b + c),
        0.5 * (c + a),
    ]
    .iter()
    .map(|&p| match (surface, sphere) {
        (true, false) => off_surface(p),
        (false, true) => off_sphere(p),
        _ => off_surface(p).min(off_sphere(p)),
    })
    .fold(0.0, f64::max)
}

/// The largest estimated deviation of `mesh`'s triangles from the boundary
/// ([`triangle_deviation`]).
pub fn worst_deviation(field: &Field, mesh: &TriangleMesh, kinds: &[VertexKind]) -> f64 {
    mesh.triangles
        .par_iter()
        .map(|t| {
            triangle_deviation(
                field,
                t.map(|v| mesh.vertices[v as usize]),
                t.map(|v| kinds[v as usize]),
            )
        })
        .reduce(|| 0.0, f64::max)
}

/// `Some(1.0)` when every value is positive, `Some(-1.0)` when every one is negative, else
/// `None` (a zero counts as neither: the tetrahedron is treated as crossed).
fn common_sign(values: &[f64]) -> Option<f64> {
    if values.iter().all(|&v| v > 0.0) {
        Some(1.0)
    } else if values.iter().all(|&v| v < 0.0) {
        Some(-1.0)
    } else {
        None
    }
}

/// Whether the part of the segment `p q` inside the clip ball crosses `φ = 0` twice or more
/// other than as a shallow graze (module doc, 2.): two roots with the point midway between
/// them within `shallow` of the surface and within [`GRAZE`] of their distance apart (by
/// `|φ|/|∇φ|`) pass.
fn crossed_twice(field: &Field, p: DVec3, q: DVec3, shallow: f64) -> bool {
    let e = q - p;
    let r2 = field.radius() * field.radius();
    let (qa, qb, qc) = (e.length_squared(), 2.0 * p.dot(e), p.length_squared() - r2);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc <= 0.0 {
        return false;
    }
    let root = disc.sqrt();
    let (s0, s1) = ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa));
    let (lo, hi) = (s0.max(0.0), s1.min(1.0));
    if lo >= hi {
        return false;
    }
    let (a, e) = (p + lo * e, (hi - lo) * e);
    let c = field.along(a, e);
    if bernstein_variations(&c) <= 1 {
        return false;
    }
    match sturm_roots(&c, -1e-12, 1.0)[..] {
        [s0, s1] => {
            let mid = a + 0.5 * (s0 + s1) * e;
            let g = field.gradient(mid, 1e-7 * field.radius()).length();
            let depth = field.value(mid).abs() / g;
            let apart = (s1 - s0) * e.length();
            depth.is_nan() || depth > shallow || depth > GRAZE * apart
        }
        ref roots => roots.len() >= 2,
    }
}

/// The largest ratio of a graze's depth to its length that counts as shallow (module doc,
/// 2.): a segment crossing a sheet of the surface at an angle θ goes half the sheet's
/// thickness deep over `thickness / sin θ`, a ratio of `sin θ / 2`, so 1/4 passes only
/// crossings within 30° of the sheet, where an edge of another of the grid's seven
/// directions crosses it more steeply.
pub const GRAZE: f64 = 0.25;

/// Sign variations of the Bernstein coefficients on `[0, 1]` of the polynomial with
/// ascending power coefficients `c`: at least its roots in `(0, 1)`, of the same parity.
fn bernstein_variations(c: &[f64]) -> usize {
    let n = c.len() - 1;
    let binomial =
        |n: usize, k: usize| (0..k).fold(1.0, |b, i| b * (n - i) as f64 / (i + 1) as f64);
    let mut last = 0.0f64;
    let mut variations = 0;
    for i in 0..=n {
        let b: f64 = (0..=i)
            .map(|j| binomial(i, j) / binomial(n, j) * c[j])
            .sum();
        if b != 0.0 {
            if last != 0.0 && (b > 0.0) != (last > 0.0) {
                variations += 1;
            }
            last = b;
        }
    }
    variations
}

/// Binomial coefficients `C(n, k)` for `n ≤ MAX_DEGREE`.
const BINOMIAL: [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1] = {
    let mut table = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
    let mut n = 0;
    while n <= MAX_DEGREE {
        table[n][0] = 1.0;
        let mut k = 1;
        while k <= n {
            table[n][k] = table[n - 1][k - 1] + if k < n { table[n - 1][k] } else { 0.0 };
            k += 1;
        }
        n += 1;
    }
    table
};

impl TaylorSums {
    /// Whether `|f(c)|` exceeds every other term on the cube (with a margin for rounding):
    /// `f` has no zero in it.
    fn proves_empty(&self) -> bool {
        self.value.abs() - self.linear - self.quadratic > 1e-10 * self.magnitude
    }
}

/// Taylor coefficients of `φ` (up to the outside's sign: [`Field::expanded_terms`]) about a
/// point, summed by degree. Below, `f` names that polynomial: the surface's, or a shell's `φ`.
struct Taylor {
    terms: Vec<([usize; 3], f64)>,
    degree: usize,
    /// Where the row of coefficients `a_(·,j,l)` (`i ≤ degree − j − l`) starts in
    /// [`Taylor::coefficients`], at `j + d·l` (`d` the degree + 1).
    rows: Vec<usize>,
    /// How many coefficients of total degree ≤ `degree` there are.
    size: usize,
}

impl Taylor {
    /// `Σ |c·x^a·y^b·z^e|` over the terms at `p`.
    fn magnitude_bound(&self, p: DVec3) -> f64 {
        self.terms
            .iter()
            .map(|&([a, b, e], k)| {
                (k * p.x.powi(a as i32) * p.y.powi(b as i32) * p.z.powi(e as i32)).abs()
            })
            .sum()
    }
}

/// The sums [`Taylor::at`] gives for a cube of half-side `r`.
struct TaylorSums {
    /// `f` at the centre (the coefficient of degree 0).
    value: f64,
    /// `∇f` at the centre (the coefficients of degree 1).
    gradient: DVec3,
    /// `Σ_{|α|=1} |a_α| r`.
    linear: f64,
    /// `Σ_{|α|≥2} |a_α| r^{|α|}`.
    quadratic: f64,
    /// `Σ |terms of f at c|`, the scale of the rounding of `f` near `c`.
    magnitude: f64,
}

impl Taylor {
    fn new(field: &Field) -> Self {
        let degree = field.degree();
        let d = degree + 1;
        let mut rows = vec![usize::MAX; d * d];
        let mut size = 0;
        for l in 0..d {
            for j in 0..d - l {
                rows[j + d * l] = size;
                size += d - j - l;
            }
        }
        Self {
            terms: field.expanded_terms(),
            degree,
            rows,
            size,
        }
    }

    /// The sums of the Taylor coefficients' magnitudes of `f` about `c` for the cube of
    /// half-side `r` (the same for `φ = −f`); `None` if not finite.
    fn at(&self, c: DVec3, r: f64) -> Option<TaylorSums> {
        self.sums(&self.coefficients(c), c, r)
    }

    /// [`Taylor::at`] from the coefficients about `c` ([`Taylor::coefficients`]).
    fn sums(&self, coef: &[f64], c: DVec3, r: f64) -> Option<TaylorSums> {
        let d = self.degree + 1;
        let mut by_degree = [0.0f64; 3 * (MAX_DEGREE + 1)];
        for l in 0..d {
            for j in 0..d - l {
                let row = &coef[self.rows[j + d * l]..][..d - j - l];
                for (i, a) in row.iter().enumerate() {
                    by_degree[i + j + l] += a.abs();
                }
            }
        }
        let (mut linear, mut quadratic) = (0.0, 0.0);
        let mut power = 1.0;
        for (k, s) in by_degree[..3 * d].iter().enumerate() {
            let term = s * power;
            match k {
                0 => {}
                1 => linear += term,
                _ => quadratic += term,
            }
            power *= r;
        }
        let value = coef[0];
        let gradient = self.gradient(coef);
        (linear + quadratic).is_finite().then_some(TaylorSums {
            value,
            gradient,
            linear,
            quadratic,
            magnitude: self.magnitude_bound(c),
        })
    }

    /// `f(c)`, `∇f(c)` and, for each axis `i`, a bound `L_i` on `|∂_i f(x) − ∂_i f(c)|` over
    /// the cube of half-side `r` about `c`: `Σ_{|α|≥2, α_i≥1} |a_α| α_i r^{|α|−1}`, from the
    /// coefficients about `c` ([`Taylor::coefficients`]).
    fn spread(&self, coef: &[f64], r: f64) -> (f64, DVec3, DVec3) {
        let d = self.degree + 1;
        let mut spread = [0.0f64; 3];
        let mut powers = [1.0f64; 3 * (MAX_DEGREE + 1)];
        for k in 1..3 * d {
            powers[k] = powers[k - 1] * r;
        }
        for l in 0..d {
            for j in 0..d - l {
                let row = &coef[self.rows[j + d * l]..][..d - j - l];
                for (i, c) in row.iter().enumerate() {
                    let total = i + j + l;
                    if total < 2 {
                        continue;
                    }
                    let a = c.abs() * powers[total - 1];
                    spread[0] += a * i as f64;
                    spread[1] += a * j as f64;
                    spread[2] += a * l as f64;
                }
            }
        }
        (coef[0], self.gradient(coef), DVec3::from_array(spread))
    }

    /// `∇f` at the centre: the coefficients of degree 1 ([`Taylor::coefficients`]).
    fn gradient(&self, coef: &[f64]) -> DVec3 {
        let d = self.degree + 1;
        DVec3::new(coef[1], coef[self.rows[1]], coef[self.rows[d]])
    }

    /// The Taylor coefficients of `f` about `c`, those of total degree ≤ f's (the others
    /// are zero): `a_(i,j,l)` at `rows[j + d·l] + i`, `d` the degree + 1 (by `l`, then `j`,
    /// then `i`).
    fn coefficients(&self, c: DVec3) -> Vec<f64> {
        const N: usize = MAX_DEGREE + 1;
        let d = self.degree + 1;
        let mut coef = vec![0.0f64; self.size];
        // Row `a` of an axis's table (at `a·(a + 1)/2` within it) holds C(a, i)·x^(a−i) for
        // `i ≤ a`: the coefficient of d^i in (x + d)^a.
        let per_axis = d * (d + 1) / 2;
        let mut tables = Vec::with_capacity(3 * per_axis);
        for x in [c.x, c.y, c.z] {
            let mut powers = [1.0f64; N];
            for i in 1..d {
                powers[i] = powers[i - 1] * x;
            }
            for a in 0..d {
                tables.extend((0..=a).map(|i| BINOMIAL[a][i] * powers[a - i]));
            }
        }
        let row = |axis: usize, a: usize| &tables[axis * per_axis + a * (a + 1) / 2..][..=a];
        for &([a, b, e], k) in &self.terms {
            let (px, py, pz) = (row(0, a), row(1, b), row(2, e));
            for (j, y) in py.iter().enumerate() {
                for (l, z) in pz.iter().enumerate() {
                    let yz = k * y * z;
                    let row = &mut coef[self.rows[j + d * l]..][..=a];
                    for (o, x) in row.iter_mut().zip(px) {
                        *o += yz * x;
                    }
                }
            }
        }
        coef
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{check, extract::march};
    use crate::shapes::implicit::expand;

    fn field(equation: &str, radius: f64) -> Field {
        Field::new(&expand(equation).unwrap(), radius, SolidKind::Inside)
    }

    /// The mesh on the leaves for `tolerance`, from the coarsest grid at most radius / 8.
    fn adaptive(f: &Field, tolerance: f64) -> (TriangleMesh, Vec<VertexKind>, Refined) {
        let floor = 2.0 * tolerance;
        let depth = depth_for(f.radius(), floor, f.degree());
        let coarse = Grid::covering(f.radius(), floor * f64::from(1u32 << depth));
        mesh_adaptive(
            f,
            coarse,
            depth,
            tolerance,
            &|_, _| {},
            &AtomicBool::new(false),
        )
        .unwrap()
    }

    #[test]
    fn the_depth_halves_from_an_eighth_of_the_radius_down_to_the_floor() {
        assert_eq!(depth_for(2.0, 0.04, 6), 2);
        assert_eq!(depth_for(2.0, 0.3, 6), 0);
        // A shell of a surface of degree 9 and more: φ of degree 18 and more.
        assert_eq!(depth_for(2.0, 0.04, 16), 2);
        assert_eq!(depth_for(2.0, 0.04, 18), 0);
    }

    #[test]
    fn bernstein_variations_bound_the_roots_in_the_unit_interval() {
        // (s − 0.3)(s − 0.6): two roots; s² + 1: none; s − 2: none in [0, 1].
        assert_eq!(bernstein_variations(&[0.18, -0.9, 1.0]), 2);
        assert_eq!(bernstein_variations(&[1.0, 0.0, 1.0]), 0);
        assert_eq!(bernstein_variations(&[-2.0, 1.0]), 0);
        assert_eq!(bernstein_variations(&[-0.5, 1.0]), 1);
    }

    #[test]
    fn an_end_on_the_surface_and_the_sphere_keeps_the_mesh_closed() {
        // `adaptive` builds the plain grid through the origin (`Grid::covering`), on which
        // the clip sphere of radius 3.16228 passes through lattice points of the plane x = 0
        // at 1% of it ((0, 30, 40) steps): the vertices held off those points must stay on
        // their edges.
        let f = field("x", 3.16228);
        let lattice = Lattice::of_grid(Grid::covering(f.radius(), 0.0632456 * 4.0), 2);
        let on_both = lattice.position([54, 84, 94]);
        assert!((on_both.length() - f.radius()).abs() < 1e-12 && on_both.x.abs() < 1e-12);
        let (mesh, _, _) = adaptive(&f, 0.0316228);
        check::verify(&mesh).unwrap();
    }

    #[test]
    fn a_segment_proven_monotone_crosses_at_most_once() {
        // A torus on a grid of 0.25 steps, its lattice four times finer; segments between
        // lattice points of one cube, in the seven directions of Kuhn edges and others.
        let f = field("(x^2 + y^2 + z^2 + 0.75)^2 - 4*(x^2 + y^2)", 1.6);
        let coarse = Grid::covering(f.radius(), 0.25);
        let (n, depth) = (coarse.cells, 2);
        let side = 1 << depth;
        let lattice = Lattice::of_grid(coarse, depth);
        let mut examiner = Examiner {
            spreads: Vec::new(),
            cube_side: side,
            cells: n,
            field: &f,
            lattice,
            taylor: Taylor::new(&f),
            table: marching_table(),
            tolerance: 0.01 / EXTRACT_SHARE,
            floor_level: 3 * depth as u8,
            f_sign: 1.0,
        };
        examiner.spreads = (0..n * n * n)
            .map(|c| {
                let lo = [c % n, c / n % n, c / (n * n)].map(|v| v as i32 * side);
                let centre = lattice.position(lo.map(|v| v + side / 2));
                let coef = examiner.taylor.coefficients(centre);
                Some(examiner.spread(&coef, centre, 0.5 * coarse.step()))
            })
            .collect();
        let (mut proven, mut not) = (0, 0);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = |m: i32| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            ((state >> 33) % m as u64) as i32
        };
        for _ in 0..20_000 {
            let cube = [0; 3].map(|_| next(n as i32) * side);
            let p = cube.map(|c| c + next(side + 1));
            let q = cube.map(|c| c + next(side + 1));
            if p == q {
                continue;
            }
            if !examiner.monotone_along(p, q) {
                not += 1;
                continue;
            }
            proven += 1;
            let (a, b) = (lattice.position(p), lattice.position(q));
            let samples: Vec<f64> = (0..=64)
                .map(|k| f.value(a.lerp(b, f64::from(k) / 64.0)))
                .collect();
            let rising = samples[64] > samples[0];
            assert!(
                samples.windows(2).all(|w| (w[1] > w[0]) == rising),
                "{p:?} {q:?}"
            );
        }
        assert!(proven > 1000 && not > 1000, "{proven} {not}");
    }

    #[test]
    fn the_taylor_sums_bound_the_polynomial_on_the_cube() {
        let f = field("(2*x^2 + y^2 + z^2 - 1)^3 - (0.1*x^2 + y^2)*z^3", 2.0);
        let taylor = Taylor::new(&f);
        let (c, r) = (DVec3::new(0.3, -0.7, 0.5), 0.2);
        let sums = taylor.at(c, r).unwrap();
        let centre = f.value(c);
        let mut worst = 0.0f64;
        for i in 0..1000u32 {
            let t = |k: u32| f64::from((i * 7919 + k * 104_729) % 1000) / 500.0 - 1.0;
            let d = DVec3::new(t(1), t(2), t(3)) * r;
            worst = worst.max((f.value(c + d) - centre).abs());
        }
        assert!(
            worst <= sums.linear + sums.quadratic,
            "{worst} {}",
            sums.linear
        );
        // Not wildly loose: within a few times the largest change seen.
        assert!(sums.linear + sums.quadratic < 10.0 * worst);
    }

    #[test]
    fn a_chamfered_crease_is_refined_until_the_crease_is_within_the_tolerance() {
        // The outside of a tilted plane in the unit ball: a cap whose wedge at the crease is
        // acute, so that binary labels leave sides from a surface vertex to a cap vertex
        // with no crease point in their face (docs/mesh.md, "How it is made", 4). Before
        // the chamfer check the crease lay up to 0.028 from the mesh for 0.02 (0.019 with it).
        let tolerance = 0.02;
        let f = Field::new(&expand("z - 0.3*x - 0.5").unwrap(), 1.0, SolidKind::Outside);
        let (mesh, _, refined) = adaptive(&f, tolerance);
        assert!(refined.refined_for[Reason::ChamferedCrease as usize] > 0);
        let n = DVec3::new(-0.3, 0.0, 1.0).normalize();
        let d = 0.5 / DVec3::new(-0.3, 0.0, 1.0).length();
        let (centre, rho) = (n * d, (1.0 - d * d).sqrt());
        let u = DVec3::new(1.0, 0.0, 0.3).normalize();
        let v = n.cross(u);
        let worst = (0..720)
            .map(|k| {
                let (s, c) = (f64::from(k) * 0.5).to_radians().sin_cos();
                let p = centre + rho * (c * u + s * v);
                mesh.triangles
                    .iter()
                    .map(|t| {
                        let corners = t.map(|i| mesh.vertices[i as usize]);
                        p.distance(crate::shapes::triangles::closest_on_triangle(p, corners))
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(worst <= tolerance, "the crease {worst} from the mesh");
    }

    #[test]
    fn a_sphere_is_meshed_coarse_and_refined_only_for_a_finer_tolerance() {
        let f = field("x^2 + y^2 + z^2 = 1", 1.5);
        let (mesh, kinds, refined) = adaptive(&f, 0.02);
        check::verify(&mesh).unwrap();
        eprintln!("sphere 0.02: {refined:?}");
        assert!(worst_deviation(&f, &mesh, &kinds) <= EXTRACT_SHARE * 0.02);
        // Every crossed leaf is in a cube of the coarsest step: nothing needed refining.
        let crossed = &refined.crossed_by_level;
        assert!(
            crossed[0] > 0 && crossed[3..].iter().all(|&n| n == 0),
            "{refined:?}"
        );
        // At a quarter of the tolerance the same coarse cubes are refined for the deviation,
        // and the mesh is still within its share.
        let (mesh, _, refined) = adaptive(&f, 0.005);
        eprintln!("sphere 0.005: {refined:?}");
        check::verify(&mesh).unwrap();
        assert!(refined.refined_for[Reason::Deviation as usize] > 0);
        let finest = refined.crossed_by_level.len() - 1;
        assert!(refined.crossed_by_level[finest] < refined.crossed() / 2);
    }

    /// `refine` hands marching tetrahedra only the leaves of cubes that may hold a triangle:
    /// they must be exactly the leaves of the whole refinement whose labels differ, here for
    /// a solid wholly inside a clip ball (every triangle a cap's, in cubes proven empty of
    /// surface that the sphere cuts) and a torus the sphere clips.
    #[test]
    fn the_marched_leaves_are_every_leaf_whose_labels_differ() {
        for (equation, radius) in [
            ("x^2 + y^2 + z^2 = 4", 1.0),
            ("(x^2 + y^2 + z^2 + 0.64 - 0.09)^2 = 2.56*(x^2 + y^2)", 1.0),
        ] {
            let f = field(equation, radius);
            let tolerance = 0.01;
            let floor = 2.0 * tolerance;
            let depth = depth_for(f.radius(), floor, f.degree());
            let coarse = Grid::covering(f.radius(), floor * f64::from(1u32 << depth));
            let cancel = AtomicBool::new(false);
            let a = refine(&f, coarse, depth, tolerance, &|_, _| {}, &cancel).unwrap();
            let all = a.refinement.leaves();
            let label = |t: &Tet| {
                (0..4).fold(0u8, |m, k| {
                    m | u8::from(f.inside(a.lattice.position(t.corners[k]))) << k
                })
            };
            let (crossed, labels): (Vec<Tet>, Vec<u8>) = all
                .iter()
                .map(|t| (*t, label(t)))
                .filter(|&(_, m)| m != 0 && m != 15)
                .unzip();
            assert!(crossed.len() > 100, "{equation}: {}", crossed.len());
            assert_eq!(a.leaves, crossed, "{equation}");
            assert_eq!(a.labels, labels, "{equation}");
            assert_eq!(a.refined.leaves(), all.len(), "{equation}");
            assert_eq!(a.refined.crossed(), crossed.len(), "{equation}");
        }
    }

    /// A ball of radius 0.06 (with the unit ball) wholly inside one cube of the coarsest grid,
    /// whose corners are all outside: that grid loses it, and the refinement finds it.
    #[test]
    fn a_small_component_inside_a_quiet_tetrahedron_is_found() {
        let f = field(
            "(x^2 + y^2 + z^2 - 1)*((x - 1.6)^2 + y^2 + z^2 - 0.0036) = 0",
            2.0,
        );
        let coarsest = Grid::covering(2.0, 0.04 * 4.0);
        let (lost, _) = march(&f, coarsest, &|_, _| {});
        assert_eq!(
            check::components(&lost),
            1,
            "the coarsest grid sees the small ball"
        );
        let (mesh, _, refined) = adaptive(&f, 0.02);
        eprintln!("small ball: {refined:?}");
        assert!(refined.refined_for[Reason::SurfaceUnproven as usize] > 0);
        let v = check::verify(&mesh).unwrap();
        assert_eq!(v.components, 2);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * (1.0 + 0.06f64.powi(3));
        let small = 4.0 / 3.0 * std::f64::consts::PI * 0.06f64.powi(3);
        assert!(
            (v.volume - exact).abs() < 0.5 * small + 0.03,
            "{} {exact}",
            v.volume
        );
    }

    /// Two lobes joined by a neck of radius 0.05 (a surface of revolution about x): edges
    /// crossing the neck cross the surface twice, so the tetrahedra there are refined, and
    /// the mesh is one piece with the neck in it.
    #[test]
    fn a_thin_neck_is_kept() {
        // y² + z² = g(x), g ≥ 0.0025 everywhere, wide lobes about x = ±0.35.
        let f = field(
            "y^2 + z^2 - 0.0025 - 1.2*(1 - (x/0.6)^2)^2*(x/0.6)^2 = 0",
            1.0,
        );
        let (mesh, _, refined) = adaptive(&f, 0.01);
        let v = check::verify(&mesh).unwrap();
        let (coarse, _) = march(&f, refined.coarse, &|_, _| {});
        eprintln!(
            "neck: {refined:?}; the coarsest grid gives {} pieces",
            check::components(&coarse)
        );
        assert_eq!(v.components, 1, "{refined:?}");
        assert!(
            check::components(&coarse) > 1,
            "the coarsest grid keeps the neck"
        );
        assert!(refined.refined_for[Reason::EdgeCrossedTwice as usize] > 0);
        assert!(mesh
            .vertices
            .iter()
            .any(|p| p.x.abs() < 0.03 && (p.y * p.y + p.z * p.z).sqrt() < 0.1));
    }
}
