//! The grid step, chosen by measurement from coarse to fine: the coarsest grid whose
//! marching-tetrahedra mesh is already close enough to the exact surface and whose grid sees
//! the surface's topology, down to the floor of twice the tolerance (the step every surface
//! got before; always accepted).
//!
//! A step is accepted only when all of these hold on its grid:
//!
//! 1. **Accuracy** ([`worst_deviation`]): every extracted triangle's centroid and edge
//!    midpoints are within [`EXTRACT_SHARE`] of the tolerance of the boundary by the
//!    first-order estimate `|φ|/|∇φ|` (a triangle with all vertices on the clip sphere:
//!    `|R − |x||`; one with vertices on both: the smaller of the two).
//! 2. **No edge crossed twice** ([`topology_problem`]): on every edge of the tetrahedra of a
//!    cell whose corners do not all have the same sign of `φ`, the part inside the clip ball
//!    holds at most one distinct root of `φ`, counted exactly (Bernstein sign variations,
//!    then Sturm sequences by [`crate::roots::sturm_roots`] where those allow two or more).
//!    An edge crossed twice hides a handle, a thin part or a small piece between its ends.
//!    One exception, a shallow graze: exactly two roots, with the point midway between them
//!    within [`EXTRACT_SHARE`] of the tolerance of the surface and within [`GRAZE`] of the
//!    roots' distance apart (both by `|φ|/|∇φ|`): an edge nearly tangent to a curved sheet
//!    clips a cap off it that is no deeper than that, which the labels may miss at the cost
//!    of that depth (a smooth convex surface has such edges at every step).
//! 3. **No surface in a cell whose corners agree** ([`topology_problem`]): every cell whose
//!    eight corners have the same sign of `φ` (and which meets the clip ball) is proven free
//!    of `φ = 0` by a Taylor bound about its centre: with `φ(c + d) = Σ a_α d^α`, the
//!    remainder past the linear part is at most `Q = Σ_{|α|≥2} |a_α| r^{|α|}` on the cube of
//!    half-side `r`, and the linear part is least at a corner, so `s·φ ≥ min_corners s·φ − 2Q`
//!    there (`s` the corners' sign; or `s·φ(c) − Σ_{|α|≥1} |a_α| r^{|α|}`, whichever is
//!    larger). A cell this does not prove is cut in eight, and its parts likewise, down to
//!    parts no larger than the floor step (parts wholly outside the ball are skipped): a part
//!    whose corners differ in sign rejects the step; a part of the floor's size whose corners
//!    agree is accepted unproven (the floor grid would see nothing there either). Blocks of
//!    4³ cells whose centre bound proves them empty skip their cells' own bounds.
//!
//! What this proves: within the ball, no piece of the surface that sampling at the floor
//! step would see lies inside a cell whose corners agree (a small component, a bubble, a
//! bulge through a face), and no grid edge of a crossed cell passes through the surface
//! twice but for a shallow graze. What it does not: features smaller than the floor step
//! (as at the floor itself); a second piece of surface wholly
//! inside a crossed cell that meets none of its edges (its corners already differ, so the
//! Taylor bound cannot help); the acute wedge at the crease that binary labels cannot see
//! (as at every step); and the first-order estimate of 1. is an estimate, not a bound, which
//! the measured Hausdorff distance afterwards checks. The Taylor bound is on `f` (the inside
//! and outside); a shell's `φ` (degree twice `f`'s, a square less a sum of squares) is meshed
//! at the floor step without a search.

use super::extract::{self, Grid};
use super::field::{Field, SolidKind, VertexKind};
use super::TriangleMesh;
use crate::geometry::DVec3;
use crate::roots::sturm_roots;
use crate::shapes::implicit::MAX_DEGREE;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// The share of the tolerance an extracted triangle may deviate from the surface (by the
/// first-order estimate at its centroid and edge midpoints) for its grid step to be
/// accepted: the coarsening may then spend [`super::COARSEN_SHARE`] of it again.
pub const EXTRACT_SHARE: f64 = 0.75;

/// The coarsest step tried is at most the clip radius divided by this.
pub const FIRST_STEP_DIVISOR: f64 = 8.0;

/// Why a grid step was not accepted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rejection {
    /// An extracted triangle deviates by more than [`EXTRACT_SHARE`] of the tolerance: the
    /// worst first-order estimate found (object units).
    Deviation(f64),
    /// A grid edge inside the clip ball holds two or more roots of `φ`.
    EdgeCrossedTwice,
    /// A cell whose corners agree holds surface: a part of it has corners of both signs.
    SurfaceInQuietCell,
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rejection::Deviation(d) => write!(f, "a triangle {d:.2e} from the surface"),
            Rejection::EdgeCrossedTwice => write!(f, "an edge crosses the surface twice"),
            Rejection::SurfaceInQuietCell => {
                write!(f, "surface inside a cell whose corners agree")
            }
        }
    }
}

/// One grid step tried.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// The grid (object units).
    pub grid: Grid,
    /// `None` when this step was accepted (the last level tried), else why not.
    pub rejected: Option<Rejection>,
}

/// The steps to try, coarse to fine, in object units: the floor times 2ᵏ, from the largest
/// that is at most `radius /` [`FIRST_STEP_DIVISOR`] down to the floor itself (only the floor
/// when it is already coarser than that, or for a shell).
pub fn candidate_steps(radius: f64, floor: f64, kind: SolidKind) -> Vec<f64> {
    let mut steps = vec![floor];
    if !matches!(kind, SolidKind::Shell { .. }) {
        while steps[steps.len() - 1] * 2.0 <= radius / FIRST_STEP_DIVISOR {
            steps.push(steps[steps.len() - 1] * 2.0);
        }
    }
    steps.reverse();
    steps
}

/// The mesh of the coarsest acceptable grid step (see the module doc) among `steps`
/// (coarse to fine; the last is accepted without checks), with each vertex's kind, the
/// grid, and every level tried. `tolerance` in object units. `progress(done, total)` is the
/// march's progress of each level (from any thread). `None` once `cancel` is set.
pub fn choose(
    field: &Field,
    steps: &[f64],
    tolerance: f64,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Option<(TriangleMesh, Vec<VertexKind>, Vec<Level>)> {
    let mut levels = Vec::new();
    for (i, &step) in steps.iter().enumerate() {
        let grid = Grid::covering(field.radius(), step);
        let last = i + 1 == steps.len();
        // The topology first: it needs no extraction.
        let rejected = if last {
            None
        } else {
            topology_problem(
                field,
                grid,
                EXTRACT_SHARE * tolerance,
                steps[steps.len() - 1],
                cancel,
            )
        };
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        if rejected.is_some() {
            levels.push(Level { grid, rejected });
            continue;
        }
        let (mesh, kinds) = extract::march_cancellable(field, grid, progress, cancel)?;
        if !last {
            let worst = worst_deviation(field, &mesh, &kinds);
            if worst.is_nan() || worst > EXTRACT_SHARE * tolerance {
                levels.push(Level {
                    grid,
                    rejected: Some(Rejection::Deviation(worst)),
                });
                continue;
            }
        }
        levels.push(Level {
            grid,
            rejected: None,
        });
        return Some((mesh, kinds, levels));
    }
    unreachable!("the last step is always accepted")
}

/// The largest first-order deviation of `mesh`'s triangles from the boundary at their
/// centroids and edge midpoints (object units; see the module doc, 1.): infinite where
/// `∇φ` vanishes (a node).
pub fn worst_deviation(field: &Field, mesh: &TriangleMesh, kinds: &[VertexKind]) -> f64 {
    let h = 1e-7 * field.radius();
    let off_surface = |p: DVec3| {
        let g = field.gradient(p, h).length();
        let v = field.value(p).abs();
        if v == 0.0 {
            0.0
        } else if g > 0.0 {
            v / g
        } else {
            f64::INFINITY
        }
    };
    let off_sphere = |p: DVec3| (field.radius() - p.length()).abs();
    mesh.triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.vertices[v as usize]);
            let k = t.map(|v| kinds[v as usize]);
            let surface = k.iter().all(|k| k.on_surface());
            let sphere = k.iter().all(|k| k.on_sphere());
            let points = [
                (a + b + c) / 3.0,
                0.5 * (a + b),
                0.5 * (b + c),
                0.5 * (c + a),
            ];
            points
                .iter()
                .map(|&p| match (surface, sphere) {
                    (true, false) => off_surface(p),
                    (false, true) => off_sphere(p),
                    _ => off_surface(p).min(off_sphere(p)),
                })
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

/// The first reason found (see the module doc, 2. and 3.) why `grid` does not see `field`'s
/// topology, or `None`; `shallow`: the deepest graze allowed, `floor_step`: the finest step
/// (object units). Stops early (with `None`) once `cancel` is set.
pub fn topology_problem(
    field: &Field,
    grid: Grid,
    shallow: f64,
    floor_step: f64,
    cancel: &AtomicBool,
) -> Option<Rejection> {
    let taylor = Taylor::new(field);
    let n = grid.cells + 1;
    let h = grid.step();
    let point = |x: usize, y: usize, z: usize| {
        DVec3::new(x as f64, y as f64, z as f64) * h - DVec3::splat(grid.half)
    };
    let values: Vec<f64> = (0..n * n * n)
        .into_par_iter()
        .map(|i| field.value(point(i % n, (i / n) % n, i / (n * n))))
        .collect();
    let radius = field.radius();
    // Cells, one z layer per task: a quiet cell proven, a crossed cell's edges counted.
    // Blocks of BLOCK³ cells far from the surface are proven free of it at once (the
    // Taylor bound about the block's centre), sparing their cells' own bounds.
    const BLOCK: usize = 4;
    let blocks = grid.cells.div_ceil(BLOCK);
    let block_is_empty = |bx: usize, by: usize, bz: usize| {
        let r = 0.5 * h * BLOCK as f64;
        let centre = point(bx * BLOCK, by * BLOCK, bz * BLOCK) + DVec3::splat(r);
        taylor.at(centre, r).is_some_and(|sums| {
            let v = field.value(centre).abs();
            v - sums.linear - sums.quadratic > 1e-10 * sums.magnitude
        })
    };
    (0..grid.cells).into_par_iter().find_map_any(|z| {
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        let mut empty: Vec<Option<bool>> = vec![None; blocks * blocks];
        for y in 0..grid.cells {
            for x in 0..grid.cells {
                let lo = point(x, y, z);
                let centre = lo + DVec3::splat(0.5 * h);
                if outside_ball(centre, 0.5 * h, radius) {
                    continue;
                }
                let (bx, by) = (x / BLOCK, y / BLOCK);
                if *empty[bx + blocks * by].get_or_insert_with(|| block_is_empty(bx, by, z / BLOCK))
                {
                    continue;
                }
                let corner_value = |b: usize| {
                    values[(x + (b & 1)) + n * ((y + (b >> 1 & 1)) + n * (z + (b >> 2 & 1)))]
                };
                let corners: [f64; 8] = std::array::from_fn(corner_value);
                if let Some(sign) = common_sign(&corners) {
                    let quiet = Quiet {
                        field,
                        taylor: &taylor,
                        sign,
                        finest: floor_step,
                    };
                    if let Err(r) = quiet.prove(centre, 0.5 * h, corners) {
                        return Some(r);
                    }
                } else {
                    for (b0, b1) in CELL_EDGES {
                        let (p, q) = (lo + corner(b0) * h, lo + corner(b1) * h);
                        if crossed_twice(field, p, q, shallow) {
                            return Some(Rejection::EdgeCrossedTwice);
                        }
                    }
                }
            }
        }
        None
    })
}

/// The 19 edges of a cube's six Freudenthal tetrahedra, as pairs of corner bits (x = 1,
/// y = 2, z = 4): a corner to one whose bits hold its own.
const CELL_EDGES: [(u8, u8); 19] = [
    (0, 1),
    (0, 2),
    (0, 4),
    (0, 3),
    (0, 5),
    (0, 6),
    (0, 7),
    (1, 3),
    (1, 5),
    (1, 7),
    (2, 3),
    (2, 6),
    (2, 7),
    (4, 5),
    (4, 6),
    (4, 7),
    (3, 7),
    (5, 7),
    (6, 7),
];

/// The unit-cube corner of offset bits `b`.
fn corner(b: u8) -> DVec3 {
    DVec3::new(
        f64::from(b & 1),
        f64::from((b >> 1) & 1),
        f64::from((b >> 2) & 1),
    )
}

/// Whether the cube of half-side `r` about `centre` lies wholly outside the open ball.
fn outside_ball(centre: DVec3, r: f64, radius: f64) -> bool {
    let nearest = (centre.abs() - DVec3::splat(r)).max(DVec3::ZERO);
    nearest.length_squared() >= radius * radius
}

/// `Some(1.0)` when every value is positive, `Some(-1.0)` when every one is negative, else
/// `None` (a zero counts as neither: the cell is treated as crossed).
fn common_sign(values: &[f64]) -> Option<f64> {
    if values.iter().all(|&v| v > 0.0) {
        Some(1.0)
    } else if values.iter().all(|&v| v < 0.0) {
        Some(-1.0)
    } else {
        None
    }
}

/// A cell whose corners all have the sign `sign` of `φ`, to be shown free of surface the
/// floor grid would see (module doc, 3.).
struct Quiet<'a> {
    field: &'a Field,
    taylor: &'a Taylor,
    sign: f64,
    /// The floor step: parts are cut no smaller.
    finest: f64,
}

impl Quiet<'_> {
    /// Proves the cube of half-side `r` about `centre` (corner values `corners`) free of
    /// `φ = 0` inside the clip ball, cutting it in eight where the bound does not suffice,
    /// down to parts no smaller than the floor step, where corners of the same sign are
    /// accepted; a part with corners of both signs is an error.
    fn prove(&self, centre: DVec3, r: f64, corners: [f64; 8]) -> Result<(), Rejection> {
        let (field, sign) = (self.field, self.sign);
        // A part no larger than the floor step whose corners agree: what the floor grid
        // would see here too.
        if r < 0.75 * self.finest {
            return Ok(());
        }
        let proven = self.taylor.at(centre, r).is_some_and(|sums| {
            let least_corner = corners
                .iter()
                .map(|v| sign * v)
                .fold(f64::INFINITY, f64::min);
            let centre_value = sign * field.value(centre);
            let bound = (least_corner - 2.0 * sums.quadratic)
                .max(centre_value - sums.linear - sums.quadratic);
            // A margin for the rounding of the values and of the bound's own sums.
            bound > 1e-10 * sums.magnitude
        });
        if proven {
            return Ok(());
        }
        let half = 0.5 * r;
        let lo = centre - DVec3::splat(r);
        // The 27 points of the cube cut in eight (3 a side, step r).
        let mut values = [0.0f64; 27];
        for (i, v) in values.iter_mut().enumerate() {
            let (a, b, c) = (i % 3, (i / 3) % 3, i / 9);
            *v = match (a % 2, b % 2, c % 2) {
                (0, 0, 0) => corners[(a / 2) | ((b / 2) << 1) | ((c / 2) << 2)],
                _ => field.value(lo + DVec3::new(a as f64, b as f64, c as f64) * r),
            };
        }
        for part in 0..8usize {
            let (ox, oy, oz) = (part & 1, part >> 1 & 1, part >> 2 & 1);
            let sub_centre = lo + DVec3::new(ox as f64 + 0.5, oy as f64 + 0.5, oz as f64 + 0.5) * r;
            if outside_ball(sub_centre, half, field.radius()) {
                continue;
            }
            let sub: [f64; 8] = std::array::from_fn(|b| {
                values[(ox + (b & 1)) + 3 * (oy + (b >> 1 & 1)) + 9 * (oz + (b >> 2 & 1))]
            });
            if common_sign(&sub) != Some(sign) {
                return Err(Rejection::SurfaceInQuietCell);
            }
            self.prove(sub_centre, half, sub)?;
        }
        Ok(())
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

/// Taylor coefficients of `f` (the surface's polynomial) about a point, summed by degree.
struct Taylor {
    terms: Vec<([usize; 3], f64)>,
    degree: usize,
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
    /// `Σ_{|α|=1} |a_α| r`.
    linear: f64,
    /// `Σ_{|α|≥2} |a_α| r^{|α|}`.
    quadratic: f64,
    /// `Σ |terms of f at c|`, the scale of the rounding of `f` near `c`.
    magnitude: f64,
}

impl Taylor {
    fn new(field: &Field) -> Self {
        let f = field.surface_polynomial();
        Self {
            terms: f
                .terms
                .iter()
                .map(|t| (t.e.map(usize::from), t.c))
                .collect(),
            degree: f.degree,
        }
    }

    /// The sums of the Taylor coefficients' magnitudes of `f` about `c` for the cube of
    /// half-side `r` (the same for `φ = −f`); `None` if not finite.
    fn at(&self, c: DVec3, r: f64) -> Option<TaylorSums> {
        const N: usize = MAX_DEGREE + 1;
        let d = self.degree + 1;
        let mut coef = vec![0.0f64; d * d * d];
        let powers = |x: f64| {
            let mut out = [1.0f64; N];
            for i in 1..d {
                out[i] = out[i - 1] * x;
            }
            out
        };
        let (xs, ys, zs) = (powers(c.x), powers(c.y), powers(c.z));
        // C(a, i)·x^(a−i) for i = 0..=a.
        let shifted = |a: usize, pw: &[f64; N]| {
            let mut out = [0.0f64; N];
            for (i, o) in out.iter_mut().enumerate().take(a + 1) {
                *o = BINOMIAL[a][i] * pw[a - i];
            }
            out
        };
        for &([a, b, e], k) in &self.terms {
            let (px, py, pz) = (shifted(a, &xs), shifted(b, &ys), shifted(e, &zs));
            for (i, x) in px.iter().enumerate().take(a + 1) {
                for (j, y) in py.iter().enumerate().take(b + 1) {
                    let xy = k * x * y;
                    let row = &mut coef[i + d * j..];
                    for (l, z) in pz.iter().enumerate().take(e + 1) {
                        row[d * d * l] += xy * z;
                    }
                }
            }
        }
        let mut by_degree = vec![0.0f64; 3 * d];
        for l in 0..d {
            for j in 0..d {
                for i in 0..d {
                    by_degree[i + j + l] += coef[i + d * (j + d * l)].abs();
                }
            }
        }
        let (mut linear, mut quadratic) = (0.0, 0.0);
        let mut power = 1.0;
        for (k, s) in by_degree.iter().enumerate() {
            let term = s * power;
            match k {
                0 => {}
                1 => linear += term,
                _ => quadratic += term,
            }
            power *= r;
        }
        (linear + quadratic).is_finite().then_some(TaylorSums {
            linear,
            quadratic,
            magnitude: self.magnitude_bound(c),
        })
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

    #[test]
    fn the_steps_double_from_the_floor_up_to_an_eighth_of_the_radius() {
        assert_eq!(
            candidate_steps(2.0, 0.04, SolidKind::Inside),
            vec![0.16, 0.08, 0.04]
        );
        assert_eq!(candidate_steps(2.0, 0.3, SolidKind::Outside), vec![0.3]);
        let shell = SolidKind::Shell { thickness: 0.1 };
        assert_eq!(candidate_steps(2.0, 0.04, shell), vec![0.04]);
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
    fn a_sphere_meets_its_tolerance_at_the_coarsest_step() {
        let f = field("x^2 + y^2 + z^2 = 1", 1.5);
        let steps = candidate_steps(1.5, 0.04, SolidKind::Inside);
        assert_eq!(steps.len(), 3);
        let (mesh, kinds, levels) =
            choose(&f, &steps, 0.02, &|_, _| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!(levels.len(), 1, "{levels:?}");
        assert!(worst_deviation(&f, &mesh, &kinds) <= EXTRACT_SHARE * 0.02);
        // At half the tolerance the same step is refused for its deviation.
        let (_, _, levels) = choose(&f, &steps, 0.01, &|_, _| {}, &AtomicBool::new(false)).unwrap();
        assert!(matches!(levels[0].rejected, Some(Rejection::Deviation(_))));
    }

    /// A ball of radius 0.06 (with the unit ball) wholly inside one cell of the coarsest grid
    /// tried, whose corners are all outside: that grid loses it, and the search refuses it.
    #[test]
    fn a_small_component_inside_a_quiet_cell_forces_a_finer_step() {
        let f = field(
            "(x^2 + y^2 + z^2 - 1)*((x - 1.6)^2 + y^2 + z^2 - 0.0036) = 0",
            2.0,
        );
        let steps = candidate_steps(2.0, 0.04, SolidKind::Inside);
        let coarsest = Grid::covering(2.0, steps[0]);
        let (lost, _) = march(&f, coarsest, &|_, _| {});
        assert_eq!(
            check::components(&lost),
            1,
            "the coarsest grid sees the small ball"
        );
        let never = AtomicBool::new(false);
        assert_eq!(
            topology_problem(&f, coarsest, 0.015, 0.04, &never),
            Some(Rejection::SurfaceInQuietCell)
        );
        let (mesh, _, levels) = choose(&f, &steps, 0.02, &|_, _| {}, &never).unwrap();
        assert!(
            levels.len() > 1 && levels[0].rejected.is_some(),
            "{levels:?}"
        );
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
    /// crossing the neck cross the surface twice, so coarse steps are refused, and the mesh
    /// is one piece with the neck in it.
    #[test]
    fn a_thin_neck_is_kept() {
        // y² + z² = g(x), g ≥ 0.0025 everywhere, wide lobes about x = ±0.35.
        let f = field(
            "y^2 + z^2 - 0.0025 - 1.2*(1 - (x/0.6)^2)^2*(x/0.6)^2 = 0",
            1.0,
        );
        let steps = candidate_steps(1.0, 0.02, SolidKind::Inside);
        let never = AtomicBool::new(false);
        let (mesh, _, levels) = choose(&f, &steps, 0.01, &|_, _| {}, &never).unwrap();
        let v = check::verify(&mesh).unwrap();
        let (coarse, _) = march(&f, Grid::covering(1.0, steps[0]), &|_, _| {});
        eprintln!(
            "neck: levels {levels:?}; the coarsest grid gives {} pieces",
            check::components(&coarse)
        );
        assert_eq!(v.components, 1, "{levels:?}");
        assert!(
            check::components(&coarse) > 1,
            "the coarsest grid keeps the neck"
        );
        assert_eq!(levels[0].rejected, Some(Rejection::EdgeCrossedTwice));
        assert!(mesh
            .vertices
            .iter()
            .any(|p| p.x.abs() < 0.03 && (p.y * p.y + p.z * p.z).sqrt() < 0.1));
    }
}
