//! Implicit polynomial surfaces typed as equations (`IMPLICIT "x^2 + y^2 + z^2 = 1" …`) or
//! named presets (`IMPLICIT torus 1 0.3 …`), placed like the heart by a position and basis.
//!
//! Pipeline: [`equation`] parses the text into a syntax tree with byte spans; [`poly`]
//! expands it once, exactly (rational coefficients), checking the language's rules; the
//! result is compiled to `f64` terms plus its three symbolic partial derivatives. Per ray,
//! the ray is re-parametrised over the chord it cuts from the clip sphere (`s ∈ [−1, 1]`,
//! origin at the chord's midpoint), the univariate polynomial in `s` is formed by nested
//! Horner composition (O(terms × degree), no allocation; for a torus about the z axis by its
//! closed form, [`torus_form`], which also gives its gradient) over the ray's span inside a box
//! that holds the surface ([`extent`], found once at load time), its first root is found by
//! the scene's [`Solver`], and `s` is mapped back to the caller's `t`. A root that `f64`
//! cannot resolve (a multiple root or a cluster: `N/|p′|` large, `N` the rounding of `p`) is
//! found again on the polynomial recentred at it and composed in double-double arithmetic
//! ([`dd`]) with the exact coefficients; where `∇f` is near its rounding, the normal is the
//! plane that separates the signs of `f` on a small sphere about the point (see
//! docs/implicit-surfaces.md for why: the specks of Taubin's heart).
//!
//! An equation whose exact expansion is the paper's heart (the `heart` preset, or the heart
//! typed in any form) builds and delegates to [`crate::shapes::Heart`] with the same frame
//! and solver, so it renders pixel-identical to `HEART`, including the heart's own accuracy
//! work at its equator curve. One that expands to the heart stretched along x and y, with or
//! without x and y swapped ([`heart_form`]: Taubin's heart), is traced through the heart's
//! path too, in heart space (the shape's frame composed with the stretch).
//! [`Implicit::new_generic`] asks for the generic path instead.

pub mod coef;
pub mod composed;
mod corpus;
pub mod dd;
pub mod equation;
pub mod extent;
pub mod heart_form;
pub mod poly;
pub mod presets;
pub mod torus_form;
pub mod tree;

use super::heart::HeartShape;
use super::placed::{ObjectShape, Placed, Placement};
use super::report::Recorder;
use super::{SolverReport, LANES};
use crate::geometry::{Aabb, DMat3, DVec3, Frame, Ray, SolidEllipsoid};
use crate::roots::Solver;
use dd::Dd;
use poly::{Compiled, Gradient, Poly, Powers, PowersLanes, Uni};
pub use presets::{Preset, HEART_EQUATION};

#[doc(hidden)]
pub use corpus::{typed_corpus, TypedRay, TYPED_SURFACES};

/// Highest total degree accepted for an equation.
pub const MAX_DEGREE: usize = 16;

/// Why an equation could not be turned into a polynomial surface.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct EquationError {
    /// Byte offset of the problem within the equation text.
    pub offset: usize,
    /// Length in bytes of the offending part (at least 1 where the text has one).
    pub len: usize,
    /// What is wrong and what was expected.
    pub message: String,
}

/// The named presets and how many numeric parameters each takes, in scene order.
pub const PRESETS: &[(&str, usize)] = &[
    ("heart", 0),
    ("taubin_heart", 0),
    ("torus", 2),
    ("kummer", 1),
    ("barth_sextic", 0),
    ("clebsch", 0),
    ("chmutov", 1),
];

/// The equation text of a preset with its parameters, or a message saying what is wrong
/// with them (unknown name, wrong count, value out of range).
pub fn preset_equation(name: &str, params: &[f64]) -> Result<String, String> {
    presets::preset(name, params).map(|p| p.equation)
}

/// The preset with its parameters: equation text and default clip radius.
pub fn preset(name: &str, params: &[f64]) -> Result<Preset, String> {
    presets::preset(name, params)
}

/// Fraction of the clip chord (in `t`) below which a root is taken to be the ray's own
/// origin on the surface: shadow and secondary rays start on the surface, and the root there
/// is only known to about this relative accuracy (double roots: ~√ε).
const SELF_HIT_GUARD: f64 = 1e-7;

/// How far past the clip sphere, as a fraction of the half chord, the search for roots runs:
/// a surface that meets or lies on its clip sphere has its roots at the chord's ends, where
/// rounding puts them on either side of `s = ±1`. Searching `[-(1 + CLIP_SLACK), 1 +
/// CLIP_SLACK]` counts such a hit once on every ray, and keeps it off the search's ends (where
/// the solver could not tell its sign, and slowed down), while a hit it adds lies within
/// `CLIP_SLACK · BOUND` of the sphere, far below a pixel.
const CLIP_SLACK: f64 = 1.0 / (1u64 << 26) as f64;

/// The far end of the search in `s` (see [`CLIP_SLACK`]).
const S_REACH: f64 = 1.0 + CLIP_SLACK;

/// Largest residual `|p(s)|`, relative to `Σ |c_k sᵏ|` (the scale of rounding in evaluating
/// `p`), accepted from the solver as a root. Rounding alone gives ~1e-15; a polished multiple
/// root a few orders more. A larger residual means the solver reported a non-root, which is
/// skipped (defence in depth: it would be a wrong pixel).
const MAX_ROOT_RESIDUAL: f64 = 1e-8;

/// True when `s` is a root of `c` up to rounding (see [`MAX_ROOT_RESIDUAL`]).
fn is_root(c: &[f64], s: f64) -> bool {
    let (mut v, mut m) = (0.0f64, 0.0f64);
    let a = s.abs();
    for &k in c.iter().rev() {
        v = v * s + k;
        m = m * a + k.abs();
    }
    residual_is_rounding(v, m)
}

/// [`is_root`]'s test on the value `v = p(s)` and the magnitude sum `m = Σ |c_k|·|s|ᵏ`.
#[inline(always)]
fn residual_is_rounding(v: f64, m: f64) -> bool {
    v.abs() <= MAX_ROOT_RESIDUAL * m
}

/// How many times the expansion's rounding must exceed the tree's, near the surface, for
/// [`through_tree`]: the ordinary surfaces (presets, gallery) stay below 5 — their
/// expansions cancel little — and the cliffs of issue 36 lie above 150 (see the test
/// `only_cancelling_expansions_go_through_the_tree`).
const TREE_ADVANTAGE: f64 = 50.0;

/// Whether the equation's tree is to carry the surface's rays and normals: where the
/// expansion `f` cancels by many more orders than the tree near the surface (`(x+y+z+1)^16
/// = 1`: terms of `(|x|+|y|+|z|+1)^16` beside values near 1), by [`tree_advantage`].
fn through_tree(f: &Compiled, tree: &tree::Tree, bound: f64) -> bool {
    tree_advantage(f, tree, bound) >= TREE_ADVANTAGE
}

/// How many times the expansion's rounding `ε·Σ|terms|` exceeds the tree's error bound near
/// the surface: the median over the quarter of the points of a 9×9×9 grid inside the clip
/// ball of radius `bound` where `|f|` is smallest (0 where there are none).
fn tree_advantage(f: &Compiled, tree: &tree::Tree, bound: f64) -> f64 {
    const N: usize = 9;
    let mut points = Vec::with_capacity(N * N * N);
    for i in 0..N * N * N {
        // Cell centres, nudged off the symmetry planes where many surfaces vanish exactly.
        let at = |k: usize| ((2 * k + 1) as f64 / N as f64 - 1.0 + 0.0123) * bound;
        let p = [at(i % N), at(i / N % N), at(i / (N * N))];
        if p.iter().map(|c| c * c).sum::<f64>() > bound * bound {
            continue;
        }
        let rounding = f64::EPSILON * f.eval_with_bound(p).1;
        let tree_value = tree.value(p);
        let ratio = rounding / tree_value.error.max(f64::MIN_POSITIVE);
        points.push((tree_value.value.abs(), ratio));
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut near: Vec<f64> = points[..points.len().div_ceil(4)]
        .iter()
        .map(|&(_, ratio)| ratio)
        .collect();
    if near.is_empty() {
        return 0.0;
    }
    near.sort_by(f64::total_cmp);
    near[near.len() / 2]
}

/// The largest share of its box's volume the surface's cells may fill to be used for
/// culling (Chmutov's octic and the degree-16 sphere fill all of it; the torus about half,
/// Barth's sextic a fifth).
const MAX_CELL_SHARE: f64 = 0.75;

/// The expanded surface with its derivatives, compiled for evaluation.
#[derive(Debug, Clone)]
struct Surface {
    f: Compiled,
    grad: [Compiled; 3],
    /// The same three partials, evaluated together (for the normal).
    gradient: Gradient,
    /// The closed form of the ray polynomial when the surface is a torus about the z axis
    /// ([`torus_form`]); the general composition otherwise.
    torus: Option<torus_form::TorusForm>,
    /// The equation's own tree, when the expansion's rounding is far above the tree's
    /// ([`through_tree`]): rays are then composed through it with a bound on every
    /// coefficient's error, ill-conditioned roots recentred through it before double-double,
    /// and normals whose `f64` gradient is lost to the expansion's cancellation taken from
    /// it. `None` for every other surface, which the tree leaves untouched.
    tree: Option<tree::Tree>,
    /// Object-space box holding the surface's part inside the clip sphere
    /// ([`extent::zero_set`]); `None` when there is none.
    object_box: Option<Aabb>,
    /// Object-space boxes whose union holds the surface's part inside the clip sphere
    /// ([`extent::ZeroSet::cells`]); empty when not known, or when together they take more
    /// than [`MAX_CELL_SHARE`] of `object_box`'s volume.
    cells: Vec<Aabb>,
}

impl Surface {
    /// The ray polynomial along `mid + s·e` (object space) into `out` (entries above the
    /// degree zero, as `out` had them): the closed form where there is one, else the
    /// general composition.
    #[inline]
    fn compose(&self, mid: [f64; 3], e: [f64; 3], out: &mut Uni) {
        match (&self.torus, &self.tree) {
            (Some(t), _) => t.compose(mid, e, out),
            (None, Some(tree)) => tree.compose(mid, e, out, &mut [0.0; MAX_DEGREE + 1]),
            (None, None) => self.f.compose_into(mid, e, out),
        }
    }

    /// [`Surface::compose`] for [`LANES`] rays (ray `i` along `mid[axis][i] + s·e[axis][i]`),
    /// by power into `out[..=degree]` (the same bits as one at a time).
    #[inline(always)]
    fn compose_lanes(
        &self,
        mid: &[[f64; LANES]; 3],
        e: &[[f64; LANES]; 3],
        out: &mut [[f64; LANES]],
    ) {
        match &self.torus {
            Some(t) => t.compose_lanes(mid, e, out),
            None => self.f.compose_lanes(mid, e, out),
        }
    }

    /// `∇f` at the object-space point `p`, in `f64` (zero at singular points).
    fn gradient(&self, p: DVec3) -> DVec3 {
        let q = p.to_array();
        DVec3::from_array(self.grad.each_ref().map(|g| g.eval(q)))
    }

    /// A vector along the outward normal at the surface point `q` (not normalised; zero at a
    /// singular point where no direction can be told). Normally `∇f` in `f64`. Where `∇f` is
    /// not far above its rounding (close to a curve where it vanishes, such as the equator of
    /// a heart, `|∇f|` falls with the square of the distance to it), its direction is noise
    /// and also swings with the smallest distance of `q` from the surface (which a root
    /// found even in double-double arithmetic has, ~1e-11 at a triple root): then the plane
    /// separating the signs of `f` on a sphere of radius `h` about `q`
    /// ([`Surface::normal_from_signs`]), with `∇f` in double-double arithmetic as the
    /// fallback where the signs are not split by a plane.
    fn normal_direction(&self, q: DVec3, h: f64) -> DVec3 {
        let (values, magnitudes) = self.gradient_with_bound(q.to_array());
        self.direction_from_gradient(q, h, values, magnitudes)
    }

    /// `∇f` at `p` in `f64` and, for each component, the sum of its terms' magnitudes.
    #[inline]
    fn gradient_with_bound(&self, p: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        match &self.torus {
            Some(t) => t.gradient_with_bound(p),
            None => {
                // One table of powers and one pass for the three partial derivatives (the
                // same values each would compute alone).
                let powers = Powers::new(p, self.gradient.degree);
                self.gradient.eval_with_bound_on(&powers)
            }
        }
    }

    /// [`Surface::gradient_with_bound`] at [`LANES`] points of a surface without the torus
    /// form (its general expansion's partials; see [`ImplicitShape::lanes_surface`]): lane
    /// `i` is point `i`'s, the same bits.
    #[inline]
    fn expansion_gradient_lanes(
        &self,
        points: &[[f64; 3]; LANES],
    ) -> [([f64; 3], [f64; 3]); LANES] {
        debug_assert!(
            self.torus.is_none(),
            "the torus form takes its own gradient"
        );
        let powers = PowersLanes::new(points, self.gradient.degree);
        let (v, m) = self.gradient.eval_with_bound_lanes(&powers);
        std::array::from_fn(|i| (v.map(|c| c[i]), m.map(|c| c[i])))
    }

    /// [`Surface::normal_direction`] at `q`, given `∇f` there (`values`) and its terms'
    /// magnitudes as [`Surface::gradient_with_bound`] finds them.
    #[inline]
    fn direction_from_gradient(
        &self,
        q: DVec3,
        h: f64,
        values: [f64; 3],
        magnitudes: [f64; 3],
    ) -> DVec3 {
        let p = q.to_array();
        let g = DVec3::from_array(values);
        let scale = magnitudes.iter().fold(0.0f64, |m, &v| m.max(v));
        let terms = self.gradient.most_terms as f64;
        let noise = ROUNDING * terms * scale;
        if g.abs().max_element() > GRADIENT_MARGIN * noise {
            return g;
        }
        if let Some((g0, bound)) = self
            .tree
            .as_ref()
            .and_then(|tree| tree_smooth_direction(tree, q, h))
        {
            // The tree's own gradient where its bound puts its direction far below any
            // angle a normal needs; else the double-double gradient at `q` alone, as
            // `smooth_gradient` answers.
            if g0.abs().max_element() >= TREE_NORMAL_MARGIN * bound {
                return g0;
            }
            return self.gradient_dd(q);
        }
        if let Some(n) = self.smooth_gradient(q, h, g, noise) {
            return n;
        }
        if let Some(n) = self.normal_from_signs(q, h) {
            return n;
        }
        let g = DVec3::from_array(self.grad.each_ref().map(|g| g.eval_dd(p).to_f64()));
        if g.abs().max_element() > 1e3 * f64::EPSILON * noise {
            g
        } else {
            DVec3::ZERO
        }
    }
}

/// How far above its rounding `∇f` must be for its `f64` direction to be used as the normal
/// (the direction is then good to about the inverse of this, in radians).
const GRADIENT_MARGIN: f64 = 1e6;

/// Largest angle (radians) between `∇f` at a point and at the probes about it for
/// [`Surface::smooth_gradient`] to take `∇f` as the normal: 0.006°, far below what a
/// pixel's shading shows, and the turn of a normal across the probes' sphere on a surface
/// curved at a radius of a tenth of the clip radius.
const FLAT_ANGLE: f64 = 1e-4;

/// How far above its rounding `∇f` in `f64` must be at a point for
/// [`Surface::smooth_gradient`] to read the probes' directions in `f64` (each then good to
/// about a tenth of [`FLAT_ANGLE`]).
const PROBE_MARGIN: f64 = 10.0 / FLAT_ANGLE;

/// Radius, relative to the clip radius, of the sphere on which
/// [`Surface::normal_from_signs`] reads the signs of `f`: large enough for `f` to be far
/// above its double-double rounding there even where it vanishes to high order, small enough
/// for the surface to be flat across it (a tilt of about this many radians per unit
/// curvature).
const SIGN_SPHERE: f64 = 1e-5;

/// The corners of a regular tetrahedron on the unit cube's diagonals (times `1/√3` on the
/// unit sphere): the probes of [`Surface::smooth_gradient`] and [`tree_smooth_direction`].
const TETRAHEDRON: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
];

/// How far above its error bound (the largest of its components') the tree's `∇f` at a
/// point must be for its `f64` value to be the normal itself
/// ([`Surface::direction_from_gradient`]): the direction is then good to about `1e-12`
/// radians, far below any angle the normal needs (and below what the double-double
/// gradient, the fallback, rounded to `f64`, is needed for).
const TREE_NORMAL_MARGIN: f64 = 1e12;

/// [`Surface::smooth_gradient`]'s test read from the equation's tree
/// ([`tree::Tree::gradient`], with its error bounds for the rounding): `Some` when, at `q`
/// and at the four probes on the sphere of radius `h` about it, `∇f` is [`GRADIENT_MARGIN`]
/// times above its bound (the largest of its components') and its directions agree within
/// [`FLAT_ANGLE`]; the surface is then flat across the sphere, and `∇f` at `q` is its
/// normal. Answers the tree's `∇f` at `q` with its bound (the largest of its components'
/// error bounds), for the caller to take it where the bound is
/// [`TREE_NORMAL_MARGIN`] times below it, or else `∇f` in double-double. Where the expansion
/// cancels and the tree does not (`(x+y+z+1)^16 = 1`), the probes cost a few `f64`
/// operations each instead of a double-double evaluation of the expansion. `None` near a
/// curve where `∇f` vanishes, or where the tree's own bound is not clear.
fn tree_smooth_direction(tree: &tree::Tree, q: DVec3, h: f64) -> Option<(DVec3, f64)> {
    let clear = |p: DVec3| {
        let g = tree.gradient(p.to_array());
        let v = DVec3::from_array(g.map(|c| c.value));
        let bound = g.iter().fold(0.0f64, |m, c| m.max(c.error));
        // False for a NaN or an infinite bound too.
        (v.abs().max_element() > GRADIENT_MARGIN * bound && bound.is_finite()).then_some((v, bound))
    };
    let (g0, bound0) = clear(q)?;
    let dir0 = g0 / g0.length();
    for s in TETRAHEDRON {
        let (gk, _) = clear(q + h / 3f64.sqrt() * DVec3::from_array(s))?;
        // False for a NaN too.
        let flat = (gk / gk.length() - dir0).length() <= FLAT_ANGLE;
        if !flat {
            return None;
        }
    }
    Some((g0, bound0))
}

impl Surface {
    /// `∇f` at `p` in double-double arithmetic, rounded to `f64`.
    fn gradient_dd(&self, p: DVec3) -> DVec3 {
        let p = p.to_array();
        DVec3::from_array(self.grad.each_ref().map(|g| g.eval_dd(p).to_f64()))
    }

    /// `∇f` at `q` as the outward normal direction where its `f64` value was not far enough
    /// above its rounding (`g`, with the rounding bound `noise`) but the gradient is smooth
    /// about `q`: the usual case of an equation whose expansion cancels heavily, such as
    /// `(x + y + z)^16 = 1` (terms of 10⁸ summing to 16) or `(x² + y² + z² − 1)^8 = 10⁻⁵`
    /// (`|∇f|` of 10⁻⁴ beside terms of 10³), where the rounding, not the geometry, hides the
    /// direction. Taken when, at `q` and at the four corners of a tetrahedron on the sphere
    /// of radius `h` about it (the sphere [`Surface::normal_from_signs`] reads), `∇f` is far
    /// above its rounding ([`GRADIENT_MARGIN`] times, in double-double arithmetic where
    /// `f64` is not [`PROBE_MARGIN`] times clear of it) and its directions agree within
    /// [`FLAT_ANGLE`]: the surface is then flat across the sphere to that angle, so `∇f` at `q`
    /// is its normal at least as closely as the plane separating the signs of `f` there
    /// (which this replaces, at a few evaluations instead of hundreds), however far `q` lies
    /// from the surface within `h`. `None` (the sign-plane's turn) near a curve where `∇f`
    /// vanishes (the heart's equator, a node), where its direction swings across the sphere.
    fn smooth_gradient(&self, q: DVec3, h: f64, g: DVec3, noise: f64) -> Option<DVec3> {
        // Double-double evaluation rounds about `ε` times less than `f64`'s.
        let noise_dd = noise * f64::EPSILON;
        let g0 = self.gradient_dd(q);
        let n0 = g0.abs().max_element();
        // False for a NaN too.
        let clear = n0 > GRADIENT_MARGIN * noise_dd;
        if !clear {
            return None;
        }
        let dir0 = g0 / g0.length();
        // The probes' directions need only be good to a fraction of `FLAT_ANGLE`: `f64`
        // serves where `∇f` at `q` is that far above its rounding (the magnitudes of the
        // terms at the probes are those at `q` to within `(1 + h/|q|)^degree`: twice
        // covers it).
        let in_f64 = g.abs().max_element() > PROBE_MARGIN * noise;
        for s in TETRAHEDRON {
            let p = q + h / 3f64.sqrt() * DVec3::from_array(s);
            let (gk, clear) = if in_f64 {
                let (values, magnitudes) = self.gradient_with_bound(p.to_array());
                let gk = DVec3::from_array(values);
                let scale = magnitudes.iter().fold(0.0f64, |m, &v| m.max(v));
                let noise_k = ROUNDING * self.gradient.most_terms as f64 * scale;
                (gk, gk.abs().max_element() > PROBE_MARGIN * noise_k)
            } else {
                let gk = self.gradient_dd(p);
                (
                    gk,
                    gk.abs().max_element() > GRADIENT_MARGIN * 2.0 * noise_dd,
                )
            };
            // False for a NaN too.
            let flat = (gk / gk.length() - dir0).length() <= FLAT_ANGLE;
            if !clear || !flat {
                return None;
            }
        }
        Some(g0)
    }

    /// The sign of `f` at `p`, in double-double arithmetic (0 where even that is zero).
    fn sign_dd(&self, p: DVec3) -> f64 {
        let v = self.f.eval_dd(p.to_array()).hi;
        if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        }
    }

    /// The outward unit normal at `q` where `∇f` vanishes (to rounding) but the surface is
    /// smooth, as on the equator curve of a heart: the plane through `q` that separates the
    /// signs of `f` on the sphere of radius `h` about it. Two points of the sphere where `f`
    /// changes sign (found by bisection between sample directions of opposite signs) span
    /// the tangent plane. `None` when the signs are not split by a plane (a true singular
    /// point, such as a cone's apex) or `f` has one sign all round.
    fn normal_from_signs(&self, q: DVec3, h: f64) -> Option<DVec3> {
        // The 6 axis and 8 diagonal directions.
        let mut dirs = [DVec3::ZERO; 14];
        for (i, d) in dirs.iter_mut().enumerate() {
            *d = if i < 6 {
                let mut v = [0.0; 3];
                v[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
                DVec3::from_array(v)
            } else {
                let k = i - 6;
                DVec3::new(
                    if k & 1 == 0 { 1.0 } else { -1.0 },
                    if k & 2 == 0 { 1.0 } else { -1.0 },
                    if k & 4 == 0 { 1.0 } else { -1.0 },
                ) / 3f64.sqrt()
            };
        }
        let signs = dirs.map(|d| self.sign_dd(q + h * d));
        // The sign change between neighbouring directions a and b, by bisection on the arc.
        let boundary = |a: DVec3, sa: f64, b: DVec3, steps: usize| {
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for _ in 0..steps {
                let m = 0.5 * (lo + hi);
                let u = (a + m * (b - a)).normalize();
                if self.sign_dd(q + h * u) == sa {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            (a + 0.5 * (lo + hi) * (b - a)).normalize()
        };
        let mut crossings: Vec<(usize, usize, DVec3)> = Vec::new();
        for i in 0..14 {
            for j in i + 1..14 {
                let (si, sj) = (signs[i], signs[j]);
                if si != 0.0 && sj != 0.0 && si != sj && dirs[i].dot(dirs[j]) > 0.3 {
                    crossings.push((i, j, boundary(dirs[i], si, dirs[j], 12)));
                }
            }
        }
        // The two crossings farthest from parallel span the tangent plane; refine them.
        let mut best = (0.0, 0, 0);
        for a in 0..crossings.len() {
            for b in a + 1..crossings.len() {
                let w = crossings[a].2.cross(crossings[b].2).length();
                if w > best.0 {
                    best = (w, a, b);
                }
            }
        }
        if best.0 < 0.5 {
            return None;
        }
        let refine = |(i, j, _): (usize, usize, DVec3)| boundary(dirs[i], signs[i], dirs[j], 48);
        let n = refine(crossings[best.1])
            .cross(refine(crossings[best.2]))
            .normalize();
        // Every clear sample direction must lie on the side its sign says, then orient.
        let mut orient = 0.0;
        for (d, s) in dirs.iter().zip(signs) {
            let side = n.dot(*d);
            if side.abs() > 0.2 {
                if s == 0.0 {
                    return None;
                }
                let agree = side.signum() * s;
                if orient == 0.0 {
                    orient = agree;
                } else if agree != orient {
                    return None;
                }
            }
        }
        (orient != 0.0).then_some(n * orient)
    }
}

#[derive(Debug, Clone)]
enum Kind {
    Generic(Box<Surface>),
    Composed(Box<Composed>),
    Heart(HeartShape),
    MappedHeart(Box<MappedHeart>),
}

/// A surface `f = a·Pⁿ + c` ([`composed`]) traced as the union of its level sets `P = r`
/// (`r` a real root of `a·sⁿ + c`), each a generic surface of `P`'s low degree.
#[derive(Debug, Clone)]
struct Composed {
    /// The whole expansion (for [`Implicit::degree`] and the study views' ray polynomial).
    f: Compiled,
    /// `P` expanded and compiled (for the value `a·P(p)ⁿ + c`).
    inner: Compiled,
    /// `P`'s partial derivatives (for the gradient `h′(P)·∇P`).
    inner_grad: [Compiled; 3],
    /// The recognised form.
    form: composed::Composition,
    /// One surface `P − r = 0` for each real root `r`, ascending in `r`, with whether the
    /// outward normal of `f` there is `−∇P` (`h′(r) < 0`).
    levels: Vec<(Surface, bool)>,
}

impl Composed {
    /// The level whose set holds (or lies nearest to) the object-space point `q`, with
    /// whether its normal is flipped.
    fn level_at(&self, q: DVec3) -> (&Surface, bool) {
        let p = self.inner.eval(q.to_array());
        let nearest = self
            .form
            .levels
            .iter()
            .zip(&self.levels)
            .min_by(|(a, _), (b, _)| (p - a.value).abs().total_cmp(&(p - b.value).abs()))
            .map(|(_, level)| level)
            .expect("a composition has a level");
        (&nearest.0, nearest.1)
    }

    /// `∇f = h′(P)·∇P` at the object-space point `p`, in `f64`.
    fn gradient(&self, p: DVec3) -> DVec3 {
        let q = p.to_array();
        let slope = self.form.outer_derivative(self.inner.eval(q));
        slope * DVec3::from_array(self.inner_grad.each_ref().map(|g| g.eval(q)))
    }
}

impl Surface {
    /// The generic path's surface of the expanded `poly` (compiled to `f`) of the syntax
    /// tree `expr`, clipped to the ball of radius `bound`: its partials, closed forms, tree
    /// (where it pays), box and cells.
    fn new(expr: &equation::Expr, poly: &Poly, f: Compiled, bound: f64) -> Surface {
        let grad = [0, 1, 2].map(|v| Compiled::new(&poly.derivative(v)));
        let torus = torus_form::recognise(poly);
        let tree = if torus.is_none() {
            tree::Tree::new(expr, f.degree).filter(|t| through_tree(&f, t, bound))
        } else {
            None
        };
        let zero_set = extent::zero_set(&f, bound);
        let to_box = |(lo, hi): ([f64; 3], [f64; 3])| {
            Aabb::new(DVec3::from_array(lo), DVec3::from_array(hi))
        };
        let object_box = zero_set.as_ref().map(|z| to_box(z.bounds));
        let mut cells: Vec<Aabb> =
            zero_set.map_or_else(Vec::new, |z| z.cells.into_iter().map(to_box).collect());
        // Cells that fill most of their hull would leave out few pixels for their cost.
        let volume = |b: &Aabb| (b.max - b.min).max(DVec3::ZERO).element_product();
        let filled: f64 = cells.iter().map(volume).sum();
        if object_box.is_none_or(|b| filled > MAX_CELL_SHARE * volume(&b)) {
            cells.clear();
        }
        Surface {
            torus,
            tree,
            f,
            gradient: Gradient::new(&grad),
            grad,
            object_box,
            cells,
        }
    }
}

impl Composed {
    /// The level sets of `form` (recognised from the equation whose expansion is `poly`,
    /// compiled to `f`) as generic surfaces clipped to `bound`; `None` when a level's
    /// expression does not expand (never expected: `P` is part of the equation).
    fn new(form: composed::Composition, f: &Compiled, bound: f64) -> Option<Self> {
        let inner_poly = Poly::expand(&form.inner).ok()?;
        let inner = Compiled::new(&inner_poly);
        let span = form.inner.span;
        let levels = form
            .levels
            .iter()
            .map(|level| {
                // `P − r`, r as the f64 found.
                let expr = equation::Expr {
                    node: equation::Node::Sum(vec![
                        (false, form.inner.clone()),
                        (
                            true,
                            equation::Expr {
                                node: equation::Node::Num(coef::Coef::Approx(level.value)),
                                span,
                            },
                        ),
                    ]),
                    span,
                };
                let level_poly = Poly::expand(&expr).ok()?;
                let compiled = Compiled::new(&level_poly);
                Some((
                    Surface::new(&expr, &level_poly, compiled, bound),
                    level.descending,
                ))
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Composed {
            f: f.clone(),
            inner,
            inner_grad: [0, 1, 2].map(|v| Compiled::new(&inner_poly.derivative(v))),
            form,
            levels,
        })
    }
}

/// The paper's heart in other coordinates ([`heart_form`]: Taubin's heart, stretched
/// hearts), traced through the heart's own path in heart space.
#[derive(Debug, Clone)]
struct MappedHeart {
    heart: HeartShape,
    /// The heart-space point of an object-space point.
    to_heart: DMat3,
    /// The object-space point of a heart-space point.
    to_object: DMat3,
    /// The equation's polynomial is `scale · f_heart(to_heart · p)`.
    scale: f64,
    /// World space to heart space: the shape's placement followed by `to_heart`.
    at: Placement,
    /// A radius about the object-space origin that holds the whole surface.
    radius: f64,
}

impl MappedHeart {
    /// The heart of `form` placed by `frame` (the shape's own placement).
    fn new(form: heart_form::HeartForm, frame: &Frame) -> Result<Self, EquationError> {
        let to_object = form.to_object;
        let m = frame.m * to_object;
        let at = Frame::new(frame.position, m.x_axis, m.y_axis, m.z_axis)
            .map(Placement::new)
            .map_err(|e| EquationError {
                offset: 0,
                len: 1,
                message: format!("the heart's frame in heart space: {e}"),
            })?;
        // The farthest corner of the heart's box, carried to object space.
        let radius = super::heart::BOUNDS
            .corners()
            .iter()
            .map(|&corner| (to_object * corner).length())
            .fold(0.0, f64::max)
            * (1.0 + 1e-9);
        Ok(Self {
            heart: HeartShape::default(),
            to_heart: to_object.inverse(),
            to_object,
            scale: form.scale,
            at,
            radius,
        })
    }
}

/// An implicit polynomial surface `p(x, y, z) = 0` in object space, placed by a [`Frame`],
/// clipped to the object-space sphere of radius `bound` about the origin.
pub type Implicit = Placed<ImplicitShape>;

/// The object space of an [`Implicit`]: the surface, its clip radius and the root-isolation
/// strategy its intersections use.
#[derive(Debug, Clone)]
pub struct ImplicitShape {
    solver: Solver,
    bound: f64,
    kind: Kind,
    /// The equation's exact expansion (for [`ObjectShape::polynomial_solid`]).
    polynomial: std::sync::Arc<Poly>,
}

/// The per-ray univariate polynomial of an [`Implicit`] (for `kardia probe` and tests):
/// `f(o + t·d)` restricted to the clip chord, in the variable `s ∈ [−1, 1]` with
/// `t = t_mid + s·t_half`.
#[derive(Debug, Clone, PartialEq)]
pub struct RayPolynomial {
    /// Coefficients in ascending powers of `s` (not normalised), `degree + 1` of them.
    pub coeffs: Vec<f64>,
    /// `t` at the chord's midpoint (`s = 0`).
    pub t_mid: f64,
    /// Half the chord length in units of `t` (`s = ±1` are the clip sphere).
    pub t_half: f64,
}

/// The equation's polynomial, exactly expanded (`lhs − rhs`), or the first problem found.
pub fn expand(equation: &str) -> Result<Poly, EquationError> {
    expand_with(equation, &|_| None)
}

/// As [`expand`], with named constants besides x, y and z (see [`equation::parse_with`]).
pub fn expand_with(equation: &str, constants: equation::Constants) -> Result<Poly, EquationError> {
    parse_and_expand(equation, constants).map(|(_, poly)| poly)
}

/// [`expand_with`]'s syntax tree and expansion.
fn parse_and_expand(
    equation: &str,
    constants: equation::Constants,
) -> Result<(equation::Expr, Poly), EquationError> {
    let expr = equation::parse_with(equation, constants)?;
    let poly = Poly::expand(&expr)?;
    let whole = equation::Span {
        start: 0,
        end: equation.len(),
    };
    if poly.terms.is_empty() {
        return Err(whole.error(
            "the equation is identically zero (it holds everywhere), so it describes no surface",
        ));
    }
    if poly.terms.values().any(|c| !c.to_f64().is_finite()) {
        return Err(whole.error(
            "a coefficient of the expanded equation is too large for a floating-point number",
        ));
    }
    if poly.degree() == 0 {
        return Err(
            whole.error("the equation does not involve x, y or z, so it describes no surface")
        );
    }
    Ok((expr, poly))
}

/// `BOUND r`'s rule: a finite number greater than 0 (the error spans `whole`, the equation).
fn check_bound(bound: f64, whole: equation::Span) -> Result<(), EquationError> {
    if bound > 0.0 && bound.is_finite() {
        Ok(())
    } else {
        Err(whole.error(format!(
            "BOUND must be a finite number greater than 0, not {bound}"
        )))
    }
}

impl Implicit {
    /// Parses and expands `equation` (see docs/scene-format.md) and places it with `frame`.
    /// `bound` is the object-space clip radius (`BOUND r`); `None` takes the preset's default
    /// when `equation` is exactly a preset's text (from [`preset_equation`]), else derives one
    /// (an error asking for `BOUND` when the surface may be unbounded).
    pub fn new(equation: &str, frame: Frame, bound: Option<f64>) -> Result<Self, EquationError> {
        Self::with_constants(equation, &|_| None, frame, bound)
    }

    /// As [`Implicit::new`], where names other than x, y and z in `equation` take their values
    /// from `constants` (the scene's `LET` names).
    pub fn with_constants(
        equation: &str,
        constants: equation::Constants,
        frame: Frame,
        bound: Option<f64>,
    ) -> Result<Self, EquationError> {
        let whole = equation::Span {
            start: 0,
            end: equation.len(),
        };
        if let Some(b) = bound {
            check_bound(b, whole)?;
        }
        let (expr, poly) = parse_and_expand(equation, constants)?;
        let f = Compiled::new(&poly);
        let bound = match bound.or_else(|| presets::recognise(equation).map(|p| p.bound)) {
            Some(b) => b,
            None => poly::derive_bound(&f).ok_or_else(|| {
                whole.error(
                    "this surface may be unbounded (its highest-degree part changes sign or \
                     vanishes in some direction): add BOUND r to clip it to a sphere of radius r",
                )
            })?,
        };
        if let Some(form) = heart_form::recognise(&poly) {
            if form.is_identity() {
                return Ok(Self::heart(frame, bound, poly));
            }
            let mapped = MappedHeart::new(form, &frame)?;
            return Ok(Placed::place(
                Placement::new(frame),
                ImplicitShape {
                    solver: Solver::default(),
                    bound,
                    kind: Kind::MappedHeart(Box::new(mapped)),
                    polynomial: std::sync::Arc::new(poly),
                },
            ));
        }
        Self::generic(&expr, poly, f, frame, bound, true)
    }

    /// As [`Implicit::new`] with the bound given, always through the generic path of the
    /// whole expansion, even for an equation that is the paper's heart
    /// ([`Implicit::is_heart`]) or a power shifted by a constant ([`composed`], which
    /// [`Implicit::new`] traces as its level sets): for comparing the two.
    pub fn new_generic(equation: &str, frame: Frame, bound: f64) -> Result<Self, EquationError> {
        check_bound(
            bound,
            equation::Span {
                start: 0,
                end: equation.len(),
            },
        )?;
        let (expr, poly) = parse_and_expand(equation, &|_| None)?;
        let f = Compiled::new(&poly);
        Self::generic(&expr, poly, f, frame, bound, false)
    }

    /// The generic path's shape of the expanded `poly` (compiled to `f`) of the syntax tree
    /// `expr`, clipped to `bound` (already checked): traced as its level sets where it is a
    /// composition ([`composed`]) and `decompose` is set, else through the whole expansion.
    fn generic(
        expr: &equation::Expr,
        poly: Poly,
        f: Compiled,
        frame: Frame,
        bound: f64,
        decompose: bool,
    ) -> Result<Self, EquationError> {
        let composition = decompose
            .then(|| composed::recognise(expr))
            .flatten()
            .and_then(|form| Composed::new(form, &f, bound));
        let kind = match composition {
            Some(c) => Kind::Composed(Box::new(c)),
            None => Kind::Generic(Box::new(Surface::new(expr, &poly, f, bound))),
        };
        Ok(Placed::place(
            Placement::new(frame),
            ImplicitShape {
                solver: Solver::default(),
                bound,
                polynomial: std::sync::Arc::new(poly),
                kind,
            },
        ))
    }

    /// A named preset (see [`PRESETS`]) placed with `frame`; `bound` overrides the preset's
    /// default clip radius.
    pub fn from_preset(
        name: &str,
        params: &[f64],
        frame: Frame,
        bound: Option<f64>,
    ) -> Result<Self, String> {
        let p = presets::preset(name, params)?;
        Self::new(&p.equation, frame, Some(bound.unwrap_or(p.bound))).map_err(|e| e.message)
    }

    fn heart(frame: Frame, bound: f64, poly: Poly) -> Self {
        Placed::place(
            Placement::new(frame),
            ImplicitShape {
                solver: Solver::default(),
                bound,
                polynomial: std::sync::Arc::new(poly),
                kind: Kind::Heart(HeartShape::default()),
            },
        )
    }

    /// The same surface, intersected with the given root-isolation strategy.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        let shape = self.object_mut();
        shape.solver = solver;
        match &mut shape.kind {
            Kind::Heart(h) => *h = HeartShape::with_solver(solver),
            Kind::MappedHeart(m) => m.heart = HeartShape::with_solver(solver),
            Kind::Generic(_) | Kind::Composed(_) => {}
        }
        self
    }

    /// The object-space clip radius.
    pub fn bound(&self) -> f64 {
        self.object().bound
    }

    /// True when the equation is the paper's heart, possibly stretched along x and y or with
    /// them swapped (Taubin's heart; see [`heart_form`]), and is traced through
    /// [`super::Heart`]'s path rather than the generic one.
    pub fn is_heart(&self) -> bool {
        matches!(self.object().kind, Kind::Heart(_) | Kind::MappedHeart(_))
    }

    /// Total degree of the polynomial.
    pub fn degree(&self) -> usize {
        match &self.object().kind {
            Kind::Generic(s) => s.f.degree,
            Kind::Composed(c) => c.f.degree,
            Kind::Heart(_) | Kind::MappedHeart(_) => 6,
        }
    }

    /// The polynomial's value at an object-space point (negative inside, positive outside;
    /// for a composition `a·Pⁿ + c`, [`composed`], that form evaluated at `P`'s value).
    pub fn value(&self, p: DVec3) -> f64 {
        match &self.object().kind {
            Kind::Generic(s) => s.f.eval(p.to_array()),
            Kind::Composed(c) => c.form.outer(c.inner.eval(p.to_array())),
            Kind::Heart(_) => super::heart::heart_fn(p),
            Kind::MappedHeart(m) => m.scale * super::heart::heart_fn(m.to_heart * p),
        }
    }

    /// The symbolic gradient at an object-space point (may be zero at singular points; for a
    /// composition `a·Pⁿ + c`, [`composed`], `h′(P)·∇P`).
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        match &self.object().kind {
            Kind::Generic(s) => s.gradient(p),
            Kind::Composed(c) => c.gradient(p),
            Kind::Heart(_) => super::heart::gradient_f(p),
            Kind::MappedHeart(m) => {
                m.scale * (m.to_heart.transpose() * super::heart::gradient_f(m.to_heart * p))
            }
        }
    }

    /// The per-ray polynomial over the clip chord, or `None` when the ray's line misses the
    /// clip sphere. For the `heart` preset this is the generic composition of the heart's
    /// expanded equation (the shape itself intersects through [`super::Heart`]'s object
    /// space).
    pub fn ray_polynomial(&self, ray: &Ray) -> Option<RayPolynomial> {
        self.object()
            .ray_polynomial(&self.placement().ray_to_object(ray))
    }

    /// The first first-root query an intersection of the world ray (from `t = 0`) puts to
    /// the solver on the generic path: the normalised coefficients (ascending) and the
    /// interval `(lo, hi]`, or `None` when the ray misses the clip sphere or the surface's box
    /// (and for the `heart` preset, which intersects through the heart's own path). For the
    /// root-finder corpora of benchmarks and tests.
    #[doc(hidden)]
    pub fn solver_query(&self, ray: &Ray) -> Option<(Vec<f64>, f64, f64)> {
        self.object()
            .solver_query(&self.placement().ray_to_object(ray))
    }
}

impl ImplicitShape {
    /// The chord of the ray (in object space) through the clip sphere: `(t_mid, t_half,
    /// object-space midpoint, object-space half-chord vector)`, or `None` if the ray's line
    /// misses it.
    #[inline]
    fn chord(&self, r: &Ray) -> Option<(f64, f64, DVec3, DVec3)> {
        let dd = r.dir.length_squared();
        if !(dd > 0.0 && dd.is_finite()) {
            return None;
        }
        let t_mid = -r.origin.dot(r.dir) / dd;
        let mid = r.origin + t_mid * r.dir;
        let h2 = self.bound * self.bound - mid.length_squared();
        if h2.is_nan() || h2 <= 0.0 {
            return None;
        }
        let t_half = (h2 / dd).sqrt();
        Some((t_mid, t_half, mid, r.dir * t_half))
    }

    /// The span of `(t_min, t_max)` a heart (plain or mapped) searches: all of it when the
    /// clip sphere holds the whole surface (whose radius is `radius`), else its part inside
    /// the sphere; `None` when empty.
    #[inline]
    fn heart_span(&self, radius: f64, local: &Ray, t_min: f64, t_max: f64) -> Option<(f64, f64)> {
        if self.bound >= radius {
            return Some((t_min, t_max));
        }
        let (t_mid, t_half, _, _) = self.chord(local)?;
        let lo = t_min.max(t_mid - t_half);
        let hi = t_max.min(t_mid + t_half);
        (lo < hi).then_some((lo, hi))
    }

    /// See [`Implicit::solver_query`]; `ray` in object space.
    fn solver_query(&self, ray: &Ray) -> Option<(Vec<f64>, f64, f64)> {
        match &self.kind {
            Kind::Generic(s) => {
                let (_, c, q) = self.first_query(s, ray, 0.0, f64::INFINITY)?;
                Some((c[..=q.deg].to_vec(), q.s_lo, q.s_hi))
            }
            // The first level set's query on the ray.
            Kind::Composed(c) => c.levels.iter().find_map(|(s, _)| {
                let (_, c, q) = self.first_query(s, ray, 0.0, f64::INFINITY)?;
                Some((c[..=q.deg].to_vec(), q.s_lo, q.s_hi))
            }),
            Kind::Heart(_) | Kind::MappedHeart(_) => None,
        }
    }

    /// See [`Implicit::ray_polynomial`]; `ray` in object space.
    fn ray_polynomial(&self, ray: &Ray) -> Option<RayPolynomial> {
        let (t_mid, t_half, mid, e) = self.chord(ray)?;
        let coeffs: Vec<f64> = match &self.kind {
            Kind::Generic(s) => s.f.compose(mid.to_array(), e.to_array())[..=s.f.degree].to_vec(),
            Kind::Composed(c) => c.f.compose(mid.to_array(), e.to_array())[..=c.f.degree].to_vec(),
            Kind::Heart(_) => super::heart::sextic_coefficients(mid, e).to_vec(),
            Kind::MappedHeart(m) => {
                super::heart::sextic_coefficients(m.to_heart * mid, m.to_heart * e)
                    .map(|c| m.scale * c)
                    .to_vec()
            }
        };
        Some(RayPolynomial {
            coeffs,
            t_mid,
            t_half,
        })
    }

    /// The first query the generic path puts to the solver for the ray (object space) in
    /// `(t_min, t_max)`: the chord, the normalised ray polynomial and the query, or `None`
    /// when the ray misses the clip sphere or the surface's box there.
    #[inline]
    fn first_query(
        &self,
        s: &Surface,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<(Span, Uni, Query)> {
        let span = self.span(s, ray, t_min, t_max)?;
        let mut c: Uni = [0.0; MAX_DEGREE + 1];
        s.compose(span.mid, span.e, &mut c);
        let q = span.query(s, &mut c)?;
        Some((span, c, q))
    }

    /// The part of [`ImplicitShape::first_query`] before the composition: the chord and the
    /// span to search, or `None` when there is nothing to search.
    #[inline(always)]
    fn span(&self, s: &Surface, ray: &Ray, t_min: f64, t_max: f64) -> Option<Span> {
        let (t_mid, t_half, mid, e) = self.chord(ray)?;
        let guard = if t_min >= 0.0 {
            // `t_min.max(…)` (neither is NaN here) in one comparison.
            let g = SELF_HIT_GUARD * t_half;
            if g > t_min {
                g
            } else {
                t_min
            }
        } else {
            t_min
        };
        let reach = t_half * S_REACH;
        let lo_t = max_or_first(guard, t_mid - reach);
        let hi_t = min_or_first(t_max, t_mid + reach);
        if lo_t.is_nan() || hi_t.is_nan() || lo_t >= hi_t {
            return None;
        }
        // Only the span inside the box that holds the surface needs searching.
        let (lo_t, hi_t) = s.object_box?.clip(ray, lo_t, hi_t)?;
        if lo_t >= hi_t {
            return None;
        }
        Some(Span {
            t_mid,
            t_half,
            guard,
            mid: mid.to_array(),
            e: e.to_array(),
            lo_t,
            hi_t,
        })
    }

    /// [`ImplicitShape::span`] of each lane's ray (none where `t_max[i] ≤ t_min[i]`): the
    /// same spans bit for bit, computed lane by lane without branches (compiled for AVX2
    /// when the processor has it, for the baseline otherwise).
    #[inline(always)]
    fn spans_lanes(&self, s: &Surface, rays: LaneRays) -> LaneSpans {
        let Some(object_box) = &s.object_box else {
            return LaneSpans::NONE;
        };
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.spans_lanes_avx2(object_box, rays) };
        }
        self.spans_lanes_in(object_box, rays)
    }

    /// [`ImplicitShape::spans_lanes`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn spans_lanes_avx2(
        &self,
        object_box: &Aabb,
        LaneRays {
            local,
            t_min,
            t_max,
        }: LaneRays,
    ) -> LaneSpans {
        use std::arch::x86_64::*;
        // Four lanes a register, each operation the IEEE operation of `spans_lanes_in` (so
        // the same bits); a choice `if c {a} else {b}` is a blend on the comparison's mask.
        let load = |v: [f64; LANES]| _mm256_loadu_pd(v.as_ptr());
        let store = |v: __m256d| {
            let mut out = [0.0; LANES];
            _mm256_storeu_pd(out.as_mut_ptr(), v);
            out
        };
        let pick = |c: __m256d, a: __m256d, b: __m256d| _mm256_blendv_pd(b, a, c);
        let o: [__m256d; 3] =
            std::array::from_fn(|axis| load(std::array::from_fn(|i| local[i].origin[axis])));
        let d: [__m256d; 3] =
            std::array::from_fn(|axis| load(std::array::from_fn(|i| local[i].dir[axis])));
        let (t_min, t_max) = (load(t_min), load(t_max));
        let dot = |a: &[__m256d; 3], b: &[__m256d; 3]| {
            _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])),
                _mm256_mul_pd(a[2], b[2]),
            )
        };
        let zero = _mm256_setzero_pd();
        let sign = _mm256_set1_pd(-0.0);
        // The chord through the clip sphere.
        let dd = dot(&d, &d);
        let od = dot(&o, &d);
        let t_mid = _mm256_div_pd(_mm256_xor_pd(od, sign), dd);
        let mid = [0, 1, 2].map(|axis| _mm256_add_pd(o[axis], _mm256_mul_pd(t_mid, d[axis])));
        let mm = dot(&mid, &mid);
        let h2 = _mm256_sub_pd(_mm256_set1_pd(self.bound * self.bound), mm);
        let t_half = _mm256_sqrt_pd(_mm256_div_pd(h2, dd));
        let e = [0, 1, 2].map(|axis| _mm256_mul_pd(d[axis], t_half));
        // The span to search.
        let g = _mm256_mul_pd(_mm256_set1_pd(SELF_HIT_GUARD), t_half);
        let above = pick(_mm256_cmp_pd::<_CMP_GT_OQ>(g, t_min), g, t_min);
        let guard = pick(_mm256_cmp_pd::<_CMP_GE_OQ>(t_min, zero), above, t_min);
        // `max_or_first` and `min_or_first`.
        let reach = _mm256_mul_pd(t_half, _mm256_set1_pd(S_REACH));
        let low = _mm256_sub_pd(t_mid, reach);
        let high = _mm256_add_pd(t_mid, reach);
        let mut lo_t = pick(
            _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(guard, low),
                _mm256_cmp_pd::<_CMP_UNORD_Q>(low, low),
            ),
            guard,
            low,
        );
        let mut hi_t = pick(
            _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(t_max, high),
                _mm256_cmp_pd::<_CMP_UNORD_Q>(high, high),
            ),
            t_max,
            high,
        );
        let magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
        let finite = |v: __m256d| {
            _mm256_cmp_pd::<_CMP_LT_OQ>(_mm256_and_pd(v, magnitude), _mm256_set1_pd(f64::INFINITY))
        };
        let mut alive = _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(t_max, t_min),
                _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(dd, zero), finite(dd)),
            ),
            // `h2 > 0` is false for a NaN; neither end is NaN and `lo < hi` is `lo_t < hi_t`.
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(h2, zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(lo_t, hi_t),
            ),
        );
        object_box.clip_avx2(&o, &d, &mut lo_t, &mut hi_t, &mut alive);
        alive = _mm256_and_pd(alive, _mm256_cmp_pd::<_CMP_LT_OQ>(lo_t, hi_t));
        let bits = _mm256_movemask_pd(alive);
        LaneSpans {
            alive: std::array::from_fn(|i| bits >> i & 1 == 1),
            t_mid: store(t_mid),
            t_half: store(t_half),
            guard: store(guard),
            mid: mid.map(store),
            e: e.map(store),
            lo_t: store(lo_t),
            hi_t: store(hi_t),
        }
    }

    /// The body of [`ImplicitShape::spans_lanes`] (and, called directly, its baseline copy):
    /// [`ImplicitShape::chord`], [`ImplicitShape::span`] and [`Aabb::clip`] in their order,
    /// one operation across the lanes at a time, each `if` a choice between computed values
    /// (a lane the scalar code leaves early is computed on with meaningless values and
    /// marked dead at the end).
    #[inline(always)]
    fn spans_lanes_in(
        &self,
        object_box: &Aabb,
        LaneRays {
            local,
            t_min,
            t_max,
        }: LaneRays,
    ) -> LaneSpans {
        let o: [[f64; LANES]; 3] = std::array::from_fn(|axis| lanes(|i| local[i].origin[axis]));
        let d: [[f64; LANES]; 3] = std::array::from_fn(|axis| lanes(|i| local[i].dir[axis]));
        // The chord through the clip sphere.
        let dd = lanes(|i| d[0][i] * d[0][i] + d[1][i] * d[1][i] + d[2][i] * d[2][i]);
        let od = lanes(|i| o[0][i] * d[0][i] + o[1][i] * d[1][i] + o[2][i] * d[2][i]);
        let t_mid = lanes(|i| -od[i] / dd[i]);
        let mid: [[f64; LANES]; 3] =
            std::array::from_fn(|axis| lanes(|i| o[axis][i] + t_mid[i] * d[axis][i]));
        let mm = lanes(|i| mid[0][i] * mid[0][i] + mid[1][i] * mid[1][i] + mid[2][i] * mid[2][i]);
        let r2 = self.bound * self.bound;
        let h2 = lanes(|i| r2 - mm[i]);
        let t_half = lanes(|i| (h2[i] / dd[i]).sqrt());
        let e: [[f64; LANES]; 3] = std::array::from_fn(|axis| lanes(|i| d[axis][i] * t_half[i]));
        // The span to search.
        let guard = lanes(|i| {
            let g = SELF_HIT_GUARD * t_half[i];
            let above = if g > t_min[i] { g } else { t_min[i] };
            if t_min[i] >= 0.0 {
                above
            } else {
                t_min[i]
            }
        });
        let reach = lanes(|i| t_half[i] * S_REACH);
        let mut lo_t = lanes(|i| max_or_first(guard[i], t_mid[i] - reach[i]));
        let mut hi_t = lanes(|i| min_or_first(t_max[i], t_mid[i] + reach[i]));
        let mut alive: [bool; LANES] = std::array::from_fn(|i| {
            (t_max[i] > t_min[i])
                & (dd[i] > 0.0)
                & dd[i].is_finite()
                & !h2[i].is_nan()
                & (h2[i] > 0.0)
                & !lo_t[i].is_nan()
                & !hi_t[i].is_nan()
                & (lo_t[i] < hi_t[i])
        });
        object_box.clip_lanes(&o, &d, &mut lo_t, &mut hi_t, &mut alive);
        for i in 0..LANES {
            alive[i] &= lo_t[i] < hi_t[i];
        }
        LaneSpans {
            alive,
            t_mid,
            t_half,
            guard,
            mid,
            e,
            lo_t,
            hi_t,
        }
    }

    /// The surface whose normals [`ObjectShape::normal_lanes`] takes four at a time: a
    /// generic one with the general expansion. The torus's closed-form gradient and the
    /// heart's own normal are cheaper one at a time (`None`).
    fn lanes_surface(&self) -> Option<&Surface> {
        match &self.kind {
            Kind::Generic(s) if s.torus.is_none() => Some(s),
            _ => None,
        }
    }

    /// The unit world normal at the object-space surface point `q` of a generic surface
    /// whose outward normal runs along `g` ([`Surface::normal_direction`]); where `g` is zero
    /// (a singular point), the direction from the object's centre.
    #[inline]
    fn world_normal(at: &Placement, q: DVec3, g: DVec3) -> DVec3 {
        // Scale before normalising so tiny (but non-zero) gradients do not underflow.
        let big = g.abs().max_element();
        let n = if big > 0.0 && big.is_finite() {
            g / big
        } else {
            // A singular point: the direction from the object's centre is the best guess
            // available from the point alone (right for the tips of hearts and cones
            // pointing away from the centre).
            let r = q.abs().max_element();
            if r > 0.0 && r.is_finite() {
                q / r
            } else {
                DVec3::Z
            }
        };
        at.normal_to_world(n)
    }

    /// [`ImplicitShape::intersect_lanes_generic`] compiled for AVX2, with what it inlines (the
    /// same operations, so the same bits: AVX2 brings no fused multiply-add).
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn intersect_lanes_generic_avx2(
        &self,
        s: &Surface,
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        self.intersect_lanes_generic(s, local, t_min, t_max)
    }

    /// [`Shape::intersect_lanes`](crate::shapes::Shape::intersect_lanes) on the generic path
    /// (camera rays, and through `occludes_lanes` shadow rays): the rays that reach the
    /// composition are composed together and, where all four keep the surface's degree,
    /// normalised and given their first queries together; then each is solved as
    /// [`ImplicitShape::intersect_generic`] solves it alone (the same bits at every step).
    #[inline(always)]
    fn intersect_lanes_generic(
        &self,
        s: &Surface,
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        let spans = self.spans_lanes(
            s,
            LaneRays {
                local,
                t_min,
                t_max,
            },
        );
        let solver = self.solver;
        let mut first_root = |c: &[f64], lo: f64, hi: f64| solver.first_root(c, lo, hi);
        let alive = spans.alive.iter().filter(|&&a| a).count();
        if alive == 0 {
            return [None; LANES];
        }
        // A surface composed through its tree goes one ray at a time.
        if alive >= 2 && s.tree.is_none() {
            macro_rules! by_length {
                ($($d:literal)*) => {
                    match s.f.degree + 1 {
                        $($d => return self.intersect_lanes_fixed::<$d>(s, &spans, t_max),)*
                        _ => {}
                    }
                };
            }
            by_length!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
        }
        // One lane (or a constant, or a surface composed through its tree): each alone.
        std::array::from_fn(|i| {
            let span = spans.get(i)?;
            self.solve_span(s, &span, t_max[i], &mut first_root, &mut false)
        })
    }

    /// The part of [`ImplicitShape::intersect_lanes_generic`] from the composition on, for a
    /// surface of degree `D − 1` and at least two lanes with a span.
    #[inline(always)]
    fn intersect_lanes_fixed<const D: usize>(
        &self,
        s: &Surface,
        spans: &LaneSpans,
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        let solver = self.solver;
        let mut first_root = |c: &[f64], lo: f64, hi: f64| solver.first_root(c, lo, hi);
        let mut cs = [[0.0; LANES]; D];
        s.compose_lanes(&spans.mid, &spans.e, &mut cs);
        let Some(queries) = LaneQueries::new(spans, &mut cs) else {
            // Not all four keep the degree: each alone, from its composition.
            return std::array::from_fn(|i| {
                let span = spans.get(i)?;
                let mut c = lane_polynomial(&cs, i);
                let q = span.query(s, &mut c)?;
                self.solve(s, &span, &c, None, q, t_max[i], &mut first_root, &mut false)
            });
        };
        let settled = queries.first_hits(s, solver, spans, &cs, t_max);
        // A loop, not `from_fn`: its closure was an out-of-line call a lane, compiled for the
        // baseline even in the AVX2 copy.
        let mut hits = [None; LANES];
        for i in 0..LANES {
            hits[i] = match settled[i] {
                FirstHit::Answer(hit) => hit,
                FirstHit::GoOn(root) => self.go_on_lane(s, spans, &cs, &queries, i, root, t_max[i]),
            };
        }
        hits
    }

    /// Lane `i` of [`ImplicitShape::intersect_lanes_fixed`] where its first query's `root`
    /// did not settle the hit: solved on as [`ImplicitShape::solve`] goes on alone.
    #[allow(clippy::too_many_arguments)]
    fn go_on_lane<const D: usize>(
        &self,
        s: &Surface,
        spans: &LaneSpans,
        cs: &[[f64; LANES]; D],
        queries: &LaneQueries,
        i: usize,
        root: f64,
        t_max: f64,
    ) -> Option<f64> {
        let span = spans.get(i)?;
        let c = lane_polynomial(cs, i);
        let q = Query {
            deg: D - 1,
            inv: queries.inv[i],
            s_lo: queries.s_lo[i],
            s_hi: queries.s_hi[i],
        };
        let solver = self.solver;
        let mut answer = Some(Some(root));
        self.solve(
            s,
            &span,
            &c,
            None,
            q,
            t_max,
            &mut |c: &[f64], lo: f64, hi: f64| match answer.take() {
                Some(root) => root,
                None => solver.first_root(c, lo, hi),
            },
            &mut false,
        )
    }

    /// The nearest hit in `(t_min, t_max)` over `surfaces` (one surface, or a composition's
    /// level sets), each searched below the nearest hit so far.
    #[inline]
    fn nearest_over<'a>(
        &self,
        surfaces: impl IntoIterator<Item = &'a Surface>,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
        recentred: &mut bool,
    ) -> Option<f64> {
        let mut nearest = None;
        let mut far = t_max;
        for s in surfaces {
            if let Some(t) = self.intersect_generic(s, ray, t_min, far, first_root, recentred) {
                nearest = Some(t);
                far = t;
            }
        }
        nearest
    }

    /// The generic path of [`ObjectShape::intersect`], `ray` in object space, its first-root
    /// queries put to `first_root` (the solver's, plain or recorded); `recentred` is set when
    /// a root was re-solved in double-double arithmetic.
    #[inline(always)]
    fn intersect_generic(
        &self,
        s: &Surface,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
        recentred: &mut bool,
    ) -> Option<f64> {
        let span = self.span(s, ray, t_min, t_max)?;
        self.solve_span(s, &span, t_max, first_root, recentred)
    }

    /// [`ImplicitShape::intersect_generic`] from the ray's span on: the ray polynomial
    /// composed (through the tree, with its error bounds, for a surface that has one), then
    /// solved.
    #[inline(always)]
    fn solve_span(
        &self,
        s: &Surface,
        span: &Span,
        t_max: f64,
        first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
        recentred: &mut bool,
    ) -> Option<f64> {
        let mut c: Uni = [0.0; MAX_DEGREE + 1];
        if let Some(tree) = &s.tree {
            let mut error: Uni = [0.0; MAX_DEGREE + 1];
            tree.compose(span.mid, span.e, &mut c, &mut error);
            let q = span.query(s, &mut c)?;
            return self.solve(s, span, &c, Some(&error), q, t_max, first_root, recentred);
        }
        s.compose(span.mid, span.e, &mut c);
        let q = span.query(s, &mut c)?;
        self.solve(s, span, &c, None, q, t_max, first_root, recentred)
    }

    /// The root-finding part of [`ImplicitShape::intersect_generic`], from its first query
    /// `q` for the ray polynomial `c` (normalised by [`Span::query`]) on the chord `span`;
    /// `composed_error` bounds the error of each of `c`'s coefficients (before
    /// normalising) where it was composed through the surface's tree.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &self,
        s: &Surface,
        span: &Span,
        c: &Uni,
        composed_error: Option<&Uni>,
        q: Query,
        t_max: f64,
        first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
        recentred: &mut bool,
    ) -> Option<f64> {
        let Span {
            t_mid,
            t_half,
            guard,
            mid,
            e,
            ..
        } = *span;
        let Query {
            deg,
            inv,
            mut s_lo,
            s_hi,
        } = q;
        for _ in 0..8 {
            let root = first_root(&c[..=deg], s_lo, s_hi)?;
            let radius = ill_conditioned(s, &c[..=deg], composed_error, inv, mid, e, root);
            if radius == 0.0 {
                let t = t_mid + root * t_half;
                if t > guard && t < t_max && is_root(&c[..=deg], root) {
                    return Some(t);
                }
                if root <= s_lo {
                    return None;
                }
                s_lo = root;
                continue;
            }
            // f64 cannot tell the roots near `root` apart: solve again there with the
            // polynomial recentred, composed through the tree where that resolves it, else
            // recomputed in double-double arithmetic.
            *recentred = true;
            let (w_lo, w_hi) = (root - radius, root + radius);
            let through_tree = s.tree.as_ref().and_then(|tree| {
                tree_local_root(
                    tree,
                    s.f.degree,
                    first_root,
                    mid,
                    e,
                    root,
                    radius,
                    s_lo.max(w_lo),
                    s_hi.min(w_hi),
                )
            });
            if let Some(found) = through_tree {
                if let Some(r) = found {
                    let t = t_mid + r * t_half;
                    return (t > guard && t < t_max).then_some(t);
                }
            } else if let Some(r) = local_root(
                s,
                first_root,
                mid,
                e,
                root,
                radius,
                s_lo.max(w_lo),
                s_hi.min(w_hi),
            ) {
                let t = t_mid + r * t_half;
                return (t > guard && t < t_max).then_some(t);
            }
            if w_hi >= s_hi {
                return None;
            }
            s_lo = w_hi;
        }
        None
    }
}

/// [`LANES`] object-space rays with their ranges `(t_min[i], t_max[i])`, as
/// [`ObjectShape::intersect_lanes`] receives them.
#[derive(Clone, Copy)]
struct LaneRays<'a> {
    local: &'a [Ray; LANES],
    t_min: [f64; LANES],
    t_max: [f64; LANES],
}

/// The chord of one ray through the clip sphere (`t = t_mid + s·t_half`, object-space
/// points `mid + s·e`) and the span `(lo_t, hi_t)` of it to search, before the composition.
#[derive(Clone, Copy)]
struct Span {
    t_mid: f64,
    t_half: f64,
    /// Roots at or below this `t` are the ray's own origin.
    guard: f64,
    mid: [f64; 3],
    e: [f64; 3],
    lo_t: f64,
    hi_t: f64,
}

/// `a.max(b)` as the spans take it: `a` where `a > b` or `b` is NaN, else `b` (one
/// definition for the scalar and the lanes' code, signed zeros included).
#[inline(always)]
fn max_or_first(a: f64, b: f64) -> f64 {
    if a > b || b.is_nan() {
        a
    } else {
        b
    }
}

/// `a.min(b)` as the spans take it: `a` where `a < b` or `b` is NaN, else `b`.
#[inline(always)]
fn min_or_first(a: f64, b: f64) -> f64 {
    if a < b || b.is_nan() {
        a
    } else {
        b
    }
}

/// Lane `i`'s polynomial of the lanes' `cs` (by power), ascending, zero above the degree.
#[inline(always)]
fn lane_polynomial<const D: usize>(cs: &[[f64; LANES]; D], i: usize) -> Uni {
    std::array::from_fn(|k| if k < D { cs[k][i] } else { 0.0 })
}

/// One value per lane, lane `i`'s from `f(i)`.
#[inline(always)]
fn lanes(f: impl FnMut(usize) -> f64) -> [f64; LANES] {
    std::array::from_fn(f)
}

/// [`Span`]s of [`LANES`] rays by field (`alive[i]`: lane `i` has one; the other lanes'
/// fields are meaningless).
#[derive(Clone, Copy)]
struct LaneSpans {
    alive: [bool; LANES],
    t_mid: [f64; LANES],
    t_half: [f64; LANES],
    guard: [f64; LANES],
    mid: [[f64; LANES]; 3],
    e: [[f64; LANES]; 3],
    lo_t: [f64; LANES],
    hi_t: [f64; LANES],
}

impl LaneSpans {
    /// No lane has a span.
    const NONE: LaneSpans = LaneSpans {
        alive: [false; LANES],
        t_mid: [0.0; LANES],
        t_half: [0.0; LANES],
        guard: [0.0; LANES],
        mid: [[0.0; LANES]; 3],
        e: [[0.0; LANES]; 3],
        lo_t: [0.0; LANES],
        hi_t: [0.0; LANES],
    };

    /// Lane `i`'s span, if it has one.
    #[inline(always)]
    fn get(&self, i: usize) -> Option<Span> {
        self.alive[i].then(|| Span {
            t_mid: self.t_mid[i],
            t_half: self.t_half[i],
            guard: self.guard[i],
            mid: [self.mid[0][i], self.mid[1][i], self.mid[2][i]],
            e: [self.e[0][i], self.e[1][i], self.e[2][i]],
            lo_t: self.lo_t[i],
            hi_t: self.hi_t[i],
        })
    }
}

impl Span {
    /// The query for the ray polynomial `c` composed on this chord (normalised here, in
    /// place), or `None` for a zero or non-finite polynomial.
    #[inline(always)]
    fn query(&self, s: &Surface, c: &mut Uni) -> Option<Query> {
        let (deg, inv) = normalise(c, s.f.degree)?;
        let (s_lo, s_hi) = search_interval(self.lo_t, self.hi_t, self.t_mid, self.t_half);
        Some(Query {
            deg,
            inv,
            s_lo,
            s_hi,
        })
    }
}

/// The span `(lo_t, hi_t)` of the chord `t = t_mid + s·t_half` in `s`, the upper end at most
/// [`S_REACH`] (`.min(S_REACH)`, `S_REACH` for a NaN, in one comparison).
#[inline(always)]
fn search_interval(lo_t: f64, hi_t: f64, t_mid: f64, t_half: f64) -> (f64, f64) {
    let s_lo = (lo_t - t_mid) / t_half;
    let s_hi = (hi_t - t_mid) / t_half;
    (s_lo, if s_hi < S_REACH { s_hi } else { S_REACH })
}

/// What the generic path hands the solver for one ray beside the normalised ray polynomial
/// in `s` over the clip chord (`t = t_mid + s·t_half`): its degree, its scale and the
/// interval `(s_lo, s_hi]` to search.
#[derive(Clone, Copy)]
struct Query {
    /// Degree: `deg + 1` coefficients (ascending) are used, scaled by `inv`.
    deg: usize,
    inv: f64,
    s_lo: f64,
    s_hi: f64,
}

/// What a lane's first query, asked with the other lanes', settled of
/// [`ImplicitShape::solve`].
#[derive(Clone, Copy)]
enum FirstHit {
    /// `solve`'s answer: no root, or a simple root in range (no doubt about its conditioning).
    Answer(Option<f64>),
    /// `solve` goes on from this first root the query found.
    GoOn(f64),
}

/// [`Span::query`] of all [`LANES`] lanes at once, when every lane has a span and a
/// polynomial that keeps the full degree: the coefficients normalised in place (the same
/// bits as lane by lane) and each lane's scale and interval.
struct LaneQueries {
    inv: [f64; LANES],
    s_lo: [f64; LANES],
    s_hi: [f64; LANES],
}

impl LaneQueries {
    /// Normalises the lanes' ray polynomials `cs` (of degree `D − 1`, composed on `spans`)
    /// as [`normalise`] does each; `None` (and `cs` unchanged) unless every lane is alive,
    /// its polynomial non-zero and finite-sized and its degree kept.
    #[inline(always)]
    fn new<const D: usize>(spans: &LaneSpans, cs: &mut [[f64; LANES]; D]) -> Option<LaneQueries> {
        let n = D - 1;
        let mut big = [0.0f64; LANES];
        for c in cs.iter() {
            for i in 0..LANES {
                big[i] = larger_magnitude(big[i], c[i]);
            }
        }
        // Every lane tested, without branches (`all` stopped at the first failing lane, a
        // loop of its own).
        let mut kept = true;
        for i in 0..LANES {
            let dropped = (n > 0) & negligible_beside(cs[n][i], big[i]);
            kept &= spans.alive[i] & (big[i] > 0.0) & big[i].is_finite() & !dropped;
        }
        if !kept {
            return None;
        }
        // A loop, not `map`: `map` was an out-of-line call whose answer the scaling below
        // then read back in wide loads from its narrow stores, and waited.
        let mut inv = [0.0; LANES];
        for i in 0..LANES {
            inv[i] = pow2_inverse(big[i]);
        }
        for c in cs.iter_mut() {
            for i in 0..LANES {
                c[i] *= inv[i];
            }
        }
        let interval: [(f64, f64); LANES] = std::array::from_fn(|i| {
            search_interval(
                spans.lo_t[i],
                spans.hi_t[i],
                spans.t_mid[i],
                spans.t_half[i],
            )
        });
        Some(LaneQueries {
            inv,
            s_lo: interval.map(|(lo, _)| lo),
            s_hi: interval.map(|(_, hi)| hi),
        })
    }

    /// Every lane's first query on the normalised `cs` (of the surface's degree `D − 1`) by
    /// [`Solver::first_root_lanes_by_power`], and the hits that first root settles the way
    /// [`ImplicitShape::solve`] would settle them.
    #[inline(always)]
    fn first_hits<const D: usize>(
        &self,
        s: &Surface,
        solver: Solver,
        spans: &LaneSpans,
        c: &[[f64; LANES]; D],
        t_max: [f64; LANES],
    ) -> [FirstHit; LANES] {
        let roots = solver.first_root_lanes_by_power(c, self.s_lo, self.s_hi, [true; LANES]);
        if roots.iter().all(Option::is_none) {
            // No lane has a root (the usual answer to a group of shadow rays): nothing to
            // check.
            return [FirstHit::Answer(None); LANES];
        }
        // `ill_conditioned`'s first test and `is_root`, lane by lane in the same operations;
        // a lane without a root computes on at 0 and is answered by its `None`.
        let at = roots.map(|r| r.unwrap_or(0.0));
        // `p` is also `is_root`'s value: the same Horner steps.
        let (mut p, mut dp, mut m) = ([0.0f64; LANES], [0.0f64; LANES], [0.0f64; LANES]);
        for k in c.iter().rev() {
            for i in 0..LANES {
                dp[i] = dp[i] * at[i] + p[i];
                p[i] = p[i] * at[i] + k[i];
                m[i] = m[i] * at[i].abs() + k[i].abs();
            }
        }
        let point: [[f64; LANES]; 3] =
            std::array::from_fn(|axis| lanes(|i| spans.mid[axis][i] + at[i] * spans.e[axis][i]));
        let bound = s.f.magnitude_bound_lanes::<D>(&point);
        let mut settled = [FirstHit::Answer(None); LANES];
        for i in 0..LANES {
            let Some(root) = roots[i] else {
                continue;
            };
            let t = spans.t_mid[i] + root * spans.t_half[i];
            let hit = resolved(D, self.inv[i], bound[i], dp[i])
                && t > spans.guard[i]
                && t < t_max[i]
                && residual_is_rounding(p[i], m[i]);
            settled[i] = if hit {
                FirstHit::Answer(Some(t))
            } else {
                FirstHit::GoOn(root)
            };
        }
        settled
    }
}

/// Scales `c[..=n]` by a power of two (exact) so its largest coefficient is in `[1, 2)` and
/// drops leading coefficients below `1e-15` of it (they cannot matter on `|s| ≤ 1`): the
/// degree left and the factor applied, or `None` for a zero or non-finite polynomial.
#[inline]
fn normalise(c: &mut Uni, n: usize) -> Option<(usize, f64)> {
    // `f64::max`'s answer (a NaN coefficient is passed over; `m` is never NaN or −0) in one
    // comparison.
    let big = c[..=n].iter().fold(0.0f64, |m, &v| larger_magnitude(m, v));
    if !(big > 0.0 && big.is_finite()) {
        return None;
    }
    let mut deg = n;
    while deg > 0 && negligible_beside(c[deg], big) {
        deg -= 1;
    }
    let inv = pow2_inverse(big);
    for v in &mut c[..=deg] {
        *v *= inv;
    }
    Some((deg, inv))
}

/// `|v|` where it exceeds `m`, else `m` ([`normalise`]'s fold: a NaN `v` is passed over).
#[inline(always)]
fn larger_magnitude(m: f64, v: f64) -> f64 {
    if v.abs() > m {
        v.abs()
    } else {
        m
    }
}

/// Whether a leading coefficient `c` is dropped beside the largest one, `big` (it cannot
/// matter on `|s| ≤ 1`).
#[inline(always)]
fn negligible_beside(c: f64, big: f64) -> bool {
    c.abs() <= 1e-15 * big
}

/// `2⁻ᵏ` with `2ᵏ ≤ x < 2ᵏ⁺¹` (`x` finite and positive), from the bits of `x` when `x` is a
/// normal number whose inverse power is too.
#[inline]
fn pow2_inverse(x: f64) -> f64 {
    let biased = ((x.to_bits() >> 52) & 0x7ff) as i64;
    let k = biased - 1023;
    if biased > 0 && (-1022..=1023).contains(&-k) {
        f64::from_bits(((1023 - k) as u64) << 52)
    } else {
        2f64.powi(-(x.log2().floor() as i32))
    }
}

/// Relative rounding of a composed coefficient, per unit of `Σ |terms|` at the point, and of
/// its evaluation: `f64` composition and Horner evaluation each lose a few units of
/// `(degree + 1)·ε`; a generous multiple keeps the estimate an upper bound.
const ROUNDING: f64 = 16.0 * f64::EPSILON;

/// Widest uncertainty (in `s`) accepted for an `f64` root before it is recomputed in
/// double-double arithmetic. A root is good to `N/|p′|` (`N` the rounding of `p`); at a
/// simple root of a well-scaled ray that is ~1e-15. Where it is larger, the ray meets the
/// surface nearly tangentially or close to a curve where `∇f` vanishes (a multiple root of
/// the ray polynomial): there the `f64` root may be off the surface by up to `∛ε ≈ 1e-5`, the
/// normal `∇f` taken there can point anywhere, and a ray starting on the surface may find
/// spurious roots next to its origin (self-shadowing specks).
const SIMPLE_ROOT_RADIUS: f64 = 1e-11;

/// The rounding of a normalised ray polynomial of `len` coefficients (scaled by `inv`) and
/// of its evaluation, where the terms of `f` sum to `magnitude` in size.
#[inline(always)]
fn rounding_noise(len: usize, inv: f64, magnitude: f64) -> f64 {
    ROUNDING * (len as f64) * inv * magnitude
}

/// [`ill_conditioned`]'s first test: a root where the polynomial's derivative is `dp` is
/// resolved to [`SIMPLE_ROOT_RADIUS`] when its [`rounding_noise`] from `magnitude` allows.
#[inline(always)]
fn resolved(len: usize, inv: f64, magnitude: f64, dp: f64) -> bool {
    rounding_noise(len, inv, magnitude) <= SIMPLE_ROOT_RADIUS * dp.abs()
}

/// Zero when `root` of the normalised ray polynomial `c` (scaled by `inv` from the
/// composition of `s.f` with `mid + s·e`, or of the surface's tree, whose bounds on the
/// coefficients' errors before scaling are `composed_error`) is resolved by `f64` to
/// [`SIMPLE_ROOT_RADIUS`]; otherwise the half-width (a power of two, at most 2) of the
/// interval around it within which the rounding of `p` can hide other roots or move this
/// one.
#[inline]
fn ill_conditioned(
    s: &Surface,
    c: &[f64],
    composed_error: Option<&Uni>,
    inv: f64,
    mid: [f64; 3],
    e: [f64; 3],
    root: f64,
) -> f64 {
    // p and p′ at the root.
    let (mut p, mut dp) = (0.0f64, 0.0f64);
    for &k in c.iter().rev() {
        dp = dp * root + p;
        p = p * root + k;
    }
    let noise = if let Some(error) = composed_error {
        let noise = tree_noise(c, error, inv, root);
        if noise <= SIMPLE_ROOT_RADIUS * dp.abs() {
            return 0.0;
        }
        noise
    } else {
        let point = [0, 1, 2].map(|i| mid[i] + root * e[i]);
        // The noise below grows with the magnitude sum; its cheap upper bound settles most
        // roots (with the same answer: rounding keeps the order of the products).
        if resolved(c.len(), inv, s.f.magnitude_bound(point), dp) {
            return 0.0;
        }
        let noise = rounding_noise(c.len(), inv, s.f.eval_with_bound(point).1);
        if noise <= SIMPLE_ROOT_RADIUS * dp.abs() {
            return 0.0;
        }
        noise
    };
    // The radius within which |p − p(root)| may stay below the noise: the smallest
    // (noise / |p⁽ᵐ⁾(root)/m!|)^(1/m) over m ≥ 1 (Taylor coefficients by synthetic division).
    let n = c.len() - 1;
    let mut a = [0.0f64; MAX_DEGREE + 1];
    a[..=n].copy_from_slice(c);
    let mut radius = f64::INFINITY;
    for m in 0..=n {
        for k in (m..n).rev() {
            a[k] += root * a[k + 1];
        }
        if m >= 1 && a[m] != 0.0 {
            radius = radius.min((noise / a[m].abs()).powf(1.0 / m as f64));
        }
    }
    // Margin for the region's extent on both sides and the estimate's factor of n^(1/m).
    let w = (4.0 * radius).clamp(f64::MIN_POSITIVE, 2.0);
    (1.0 / pow2_inverse(w) * 2.0).min(2.0)
}

/// The first root in `[lo, hi]` (within `radius` of `root`) of the ray polynomial recentred
/// at `root`: `q(u) = f(P + u·E)` with `P = mid + root·e`, `E = radius·e`, composed in
/// double-double arithmetic from the exact coefficients, where the cancellation that hid the
/// roots from `f64` happens; rounded to `f64` only afterwards, `q`'s roots are well
/// separated on `|u| ≤ 1`, and the ordinary solver finds them.
#[allow(clippy::too_many_arguments)]
fn local_root(
    s: &Surface,
    first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
    mid: [f64; 3],
    e: [f64; 3],
    root: f64,
    radius: f64,
    lo: f64,
    hi: f64,
) -> Option<f64> {
    if lo >= hi || lo.is_nan() || hi.is_nan() {
        return None;
    }
    let p = [0, 1, 2].map(|i| Dd::from_f64(mid[i] + root * e[i]));
    // radius is a power of two: E is exact.
    let big_e = [0, 1, 2].map(|i| Dd::from_f64(e[i] * radius));
    let mut q = [Dd::ZERO; MAX_DEGREE + 1];
    s.f.compose_dd(p, big_e, &mut q);
    let mut c: Uni = q.map(Dd::to_f64);
    let (deg, _) = normalise(&mut c, s.f.degree)?;
    let u_lo = ((lo - root) / radius).max(-1.0);
    let u_hi = ((hi - root) / radius).min(1.0);
    let u = first_root(&c[..=deg], u_lo, u_hi)?;
    Some((root + u * radius).clamp(lo, hi))
}

/// The noise of the normalised ray polynomial `c` at `u`, composed through a tree whose
/// coefficients' errors (before the scaling by `inv`) are bounded by `error`: that error at
/// `u`, `inv·Σ error_k·|u|ᵏ`, and the rounding of `c`'s evaluation there.
#[inline]
fn tree_noise(c: &[f64], error: &Uni, inv: f64, u: f64) -> f64 {
    let a = u.abs();
    let (mut composed, mut magnitude) = (0.0f64, 0.0f64);
    for k in (0..c.len()).rev() {
        composed = composed * a + error[k];
        magnitude = magnitude * a + c[k].abs();
    }
    inv * composed * (1.0 + 1e-9) + ROUNDING * c.len() as f64 * magnitude
}

/// [`local_root`] through the equation's tree in `f64`: the first root in `[lo, hi]` (within
/// `radius` of `root`) of `q(u) = f(P + u·E)` composed through `tree` (`P = mid + root·e`,
/// `E = radius·e`, a polynomial of the surface's `degree`), with its coefficients' error
/// bounds. `Some(Some(s))` when the root it finds is resolved by those bounds to
/// [`SIMPLE_ROOT_RADIUS`] (as [`ill_conditioned`] asks of any root); `Some(None)` when there
/// is none: the solver finds none in `q` even with its constant term moved towards zero by
/// the largest error `q` may have on the window, so no polynomial within the bounds has one;
/// `None` when the bounds cannot tell (the caller asks double-double).
#[allow(clippy::too_many_arguments)]
fn tree_local_root(
    tree: &tree::Tree,
    degree: usize,
    first_root: &mut impl FnMut(&[f64], f64, f64) -> Option<f64>,
    mid: [f64; 3],
    e: [f64; 3],
    root: f64,
    radius: f64,
    lo: f64,
    hi: f64,
) -> Option<Option<f64>> {
    if lo >= hi || lo.is_nan() || hi.is_nan() {
        return Some(None);
    }
    let p = [0, 1, 2].map(|i| mid[i] + root * e[i]);
    // radius is a power of two: E is exact.
    let big_e = [0, 1, 2].map(|i| e[i] * radius);
    let (mut c, mut error): (Uni, Uni) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
    tree.compose(p, big_e, &mut c, &mut error);
    let (deg, inv) = normalise(&mut c, degree)?;
    // The leading coefficients `normalise` dropped (left unscaled) count as error on
    // `|u| ≤ 1`.
    let dropped = inv
        * (deg + 1..=degree)
            .map(|k| c[k].abs() + error[k])
            .sum::<f64>();
    let u_lo = ((lo - root) / radius).max(-1.0);
    let u_hi = ((hi - root) / radius).min(1.0);
    let c = &c[..=deg];
    if let Some(u) = first_root(c, u_lo, u_hi) {
        let (mut v, mut dv) = (0.0f64, 0.0f64);
        for &k in c.iter().rev() {
            dv = dv * u + v;
            v = v * u + k;
        }
        let noise = tree_noise(c, &error, inv, u) + dropped;
        return (radius * noise <= SIMPLE_ROOT_RADIUS * dv.abs())
            .then(|| Some((root + u * radius).clamp(lo, hi)));
    }
    // No root in `q`: none in any polynomial within the bounds when `q` stays farther from
    // zero than they reach on the window, i.e. when `q` moved towards zero by that much
    // still has none and keeps its sign.
    let reach = u_lo.abs().max(u_hi.abs());
    let (mut composed, mut at_mid, mut magnitude) = (0.0f64, 0.0f64, 0.0f64);
    let middle = 0.5 * (u_lo + u_hi);
    for k in (0..=deg).rev() {
        composed = composed * reach + error[k];
        at_mid = at_mid * middle + c[k];
        magnitude = magnitude * middle.abs() + c[k].abs();
    }
    let shift = inv * composed * (1.0 + 1e-9) + dropped;
    let sign = if at_mid > ROUNDING * (deg + 1) as f64 * magnitude + shift {
        1.0
    } else if at_mid < -(ROUNDING * (deg + 1) as f64 * magnitude + shift) {
        -1.0
    } else {
        return None;
    };
    let mut moved: Uni = [0.0; MAX_DEGREE + 1];
    moved[..=deg].copy_from_slice(c);
    // Moved by at least `shift`, whatever the rounding of the subtraction.
    moved[0] -= sign * (shift + 2.0 * f64::EPSILON * c[0].abs());
    match first_root(&moved[..=deg], u_lo, u_hi) {
        None => Some(None),
        Some(_) => None,
    }
}

impl ObjectShape for ImplicitShape {
    fn polynomial_solid(&self) -> Option<(std::sync::Arc<Poly>, f64)> {
        Some((self.polynomial.clone(), self.bound))
    }

    fn intersect(
        &self,
        at: &Placement,
        world: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64> {
        match &self.kind {
            Kind::Generic(s) => {
                let solver = self.solver;
                self.intersect_generic(
                    s,
                    local,
                    t_min,
                    t_max,
                    &mut |c, lo, hi| solver.first_root(c, lo, hi),
                    &mut false,
                )
            }
            Kind::Composed(c) => {
                let solver = self.solver;
                self.nearest_over(
                    c.levels.iter().map(|(s, _)| s),
                    local,
                    t_min,
                    t_max,
                    &mut |c, lo, hi| solver.first_root(c, lo, hi),
                    &mut false,
                )
            }
            Kind::Heart(h) => {
                let (lo, hi) = self.heart_span(presets::HEART_RADIUS, local, t_min, t_max)?;
                h.intersect(at, world, local, lo, hi)
            }
            Kind::MappedHeart(m) => {
                let (lo, hi) = self.heart_span(m.radius, local, t_min, t_max)?;
                m.heart
                    .intersect(&m.at, world, &m.at.ray_to_object(world), lo, hi)
            }
        }
    }

    fn intersect_lanes(
        &self,
        at: &Placement,
        world: &[Ray; LANES],
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        match &self.kind {
            Kind::Generic(s) => {
                #[cfg(target_arch = "x86_64")]
                if crate::cpu::avx2() {
                    // SAFETY: the processor has AVX2, checked just above.
                    return unsafe { self.intersect_lanes_generic_avx2(s, local, t_min, t_max) };
                }
                self.intersect_lanes_generic(s, local, t_min, t_max)
            }
            Kind::Composed(c) => {
                // As `intersect`, lane by lane: each level set below each lane's nearest hit.
                let mut nearest = [None; LANES];
                let mut far = t_max;
                for (s, _) in &c.levels {
                    #[cfg(target_arch = "x86_64")]
                    let hits = if crate::cpu::avx2() {
                        // SAFETY: the processor has AVX2, checked just above.
                        unsafe { self.intersect_lanes_generic_avx2(s, local, t_min, far) }
                    } else {
                        self.intersect_lanes_generic(s, local, t_min, far)
                    };
                    #[cfg(not(target_arch = "x86_64"))]
                    let hits = self.intersect_lanes_generic(s, local, t_min, far);
                    for i in 0..LANES {
                        if let Some(t) = hits[i] {
                            nearest[i] = Some(t);
                            far[i] = t;
                        }
                    }
                }
                nearest
            }
            Kind::Heart(_) => super::each_lane(t_min, t_max, |i| {
                self.intersect(at, &world[i], &local[i], t_min[i], t_max[i])
            }),
            Kind::MappedHeart(m) => {
                // The lanes' spans, then the heart's own lanes (the scalar answers bit for
                // bit) in heart space; a lane with no span searches nothing.
                let spans: [Option<(f64, f64)>; LANES] = std::array::from_fn(|i| {
                    if t_max[i] > t_min[i] {
                        self.heart_span(m.radius, &local[i], t_min[i], t_max[i])
                    } else {
                        None
                    }
                });
                let lo = spans.map(|s| s.map_or(0.0, |s| s.0));
                let hi = spans.map(|s| s.map_or(0.0, |s| s.1));
                let heart_local = world.each_ref().map(|r| m.at.ray_to_object(r));
                let hits = m.heart.intersect_lanes(&m.at, world, &heart_local, lo, hi);
                std::array::from_fn(|i| spans[i].and(hits[i]))
            }
        }
    }

    fn solver_report(
        &self,
        at: &Placement,
        world: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<SolverReport> {
        let surfaces: Vec<&Surface> = match &self.kind {
            Kind::Heart(h) => {
                let (lo, hi) = self.heart_span(presets::HEART_RADIUS, local, t_min, t_max)?;
                return h.solver_report(at, world, local, lo, hi);
            }
            Kind::MappedHeart(m) => {
                let (lo, hi) = self.heart_span(m.radius, local, t_min, t_max)?;
                let heart_local = m.at.ray_to_object(world);
                return m.heart.solver_report(&m.at, world, &heart_local, lo, hi);
            }
            Kind::Generic(s) => vec![s.as_ref()],
            // Every level set's queries in turn, each below the nearest hit so far.
            Kind::Composed(c) => c.levels.iter().map(|(s, _)| s).collect(),
        };
        let mut recorder = Recorder::new(self.solver);
        let mut recentred = false;
        let hit = self.nearest_over(
            surfaces.iter().copied(),
            local,
            t_min,
            t_max,
            &mut |c, lo, hi| recorder.first_root(c, lo, hi),
            &mut recentred,
        );
        if recentred {
            recorder.recentred();
        }
        let gradient = hit.map(|t| {
            let p = local.at(t);
            match &self.kind {
                Kind::Composed(c) => c.gradient(p).length(),
                _ => surfaces[0].gradient(p).length(),
            }
        });
        recorder.finish(hit, false, gradient)
    }

    fn normal(&self, at: &Placement, q: DVec3) -> DVec3 {
        let s = match &self.kind {
            Kind::Heart(h) => return h.normal(at, q),
            Kind::MappedHeart(m) => return m.heart.normal(&m.at, m.to_heart * q),
            Kind::Generic(s) => s,
            Kind::Composed(c) => {
                // ∇f = h′(P)·∇P: the level set's normal, turned where h′ < 0 there.
                let (s, descending) = c.level_at(q);
                let g = s.normal_direction(q, SIGN_SPHERE * self.bound);
                return Self::world_normal(at, q, if descending { -g } else { g });
            }
        };
        let g = s.normal_direction(q, SIGN_SPHERE * self.bound);
        Self::world_normal(at, q, g)
    }

    fn normal_lanes(
        &self,
        at: &Placement,
        q: &[DVec3; LANES],
        live: [bool; LANES],
    ) -> [DVec3; LANES] {
        let Some(s) = self.lanes_surface() else {
            return super::placed::normals_one_at_a_time(self, at, q, live);
        };
        // Every lane's gradient is taken (a lane that is not live, at whatever point it
        // holds), and only the live lanes' are used.
        let gradients = s.expansion_gradient_lanes(&q.map(|p| p.to_array()));
        let h = SIGN_SPHERE * self.bound;
        std::array::from_fn(|i| {
            if !live[i] {
                return DVec3::ZERO;
            }
            let (values, magnitudes) = gradients[i];
            let g = s.direction_from_gradient(q[i], h, values, magnitudes);
            Self::world_normal(at, q[i], g)
        })
    }

    fn normal_lanes_pays(&self) -> bool {
        self.lanes_surface().is_some()
    }

    fn bounds(&self, at: &Placement) -> Aabb {
        // The clip sphere's image is an ellipsoid: its half-extent along world axis a is
        // r·|row a of M|.
        let m = at.frame().m;
        let rows = m.transpose();
        let half = DVec3::new(
            rows.x_axis.length(),
            rows.y_axis.length(),
            rows.z_axis.length(),
        ) * self.bound;
        let c = at.frame().position;
        let sphere = Aabb::new(c - half, c + half).padded(1e-9);
        match &self.kind {
            Kind::Heart(h) => {
                let hb = h.bounds(at);
                Aabb::new(hb.min.max(sphere.min), hb.max.min(sphere.max))
            }
            Kind::MappedHeart(m) => {
                let hb = m.heart.bounds(&m.at);
                Aabb::new(hb.min.max(sphere.min), hb.max.min(sphere.max))
            }
            Kind::Generic(s) => match &s.object_box {
                Some(b) => {
                    let wb = at.bounds_to_world(b).padded(1e-9);
                    Aabb::new(wb.min.max(sphere.min), wb.max.min(sphere.max))
                }
                None => Aabb::new(sphere.min, sphere.min),
            },
            Kind::Composed(c) => {
                // The union of the level sets' boxes.
                let boxes: Vec<Aabb> = c.levels.iter().filter_map(|(s, _)| s.object_box).collect();
                let Some(first) = boxes.first() else {
                    return Aabb::new(sphere.min, sphere.min);
                };
                let b = boxes
                    .iter()
                    .fold(*first, |u, b| Aabb::new(u.min.min(b.min), u.max.max(b.max)));
                let wb = at.bounds_to_world(&b).padded(1e-9);
                Aabb::new(wb.min.max(sphere.min), wb.max.min(sphere.max))
            }
        }
    }

    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        match &self.kind {
            // The whole heart without a clip, else the clip sphere (see `heart_span`).
            Kind::Heart(h) if self.bound >= presets::HEART_RADIUS => h.enclosing_ellipsoids(),
            // The heart's, carried to object space: they hold every point of the surface,
            // clipped or not.
            Kind::MappedHeart(m) => m
                .heart
                .enclosing_ellipsoids()
                .into_iter()
                .map(|e| SolidEllipsoid {
                    centre: m.to_object * e.centre,
                    axes: m.to_object * e.axes,
                })
                .collect(),
            _ => vec![SolidEllipsoid::axis_aligned(
                DVec3::ZERO,
                DVec3::splat(self.bound * (1.0 + 1e-9)),
            )],
        }
    }

    fn enclosing_cells(&self) -> Vec<Aabb> {
        match &self.kind {
            // Every hit lies in the box (the chord is clipped to it) and on a zero of `f`.
            Kind::Generic(s) => s.cells.clone(),
            // None for a composition: its level sets' cells would hold it, but are left out
            // as the whole surface's are where they fill its box (the degree-16 sphere's).
            Kind::Composed(_) | Kind::Heart(_) | Kind::MappedHeart(_) => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A span's bits, field by field.
    fn bits(span: Option<Span>) -> Option<Vec<u64>> {
        span.map(|s| {
            let mut v = vec![s.t_mid, s.t_half, s.guard, s.lo_t, s.hi_t];
            v.extend(s.mid);
            v.extend(s.e);
            v.into_iter().map(f64::to_bits).collect()
        })
    }

    /// `normal_lanes` gives, lane by lane, exactly what `normal` gives alone: on the surfaces
    /// whose gradient is taken in lanes (Barth's sextic, Chmutov's octic, a cone through its
    /// apex, where the gradient vanishes and the fallbacks answer) and on those answered one
    /// at a time (the torus's closed form, the paper's heart), placed by a frame that is not
    /// the identity, with lanes left out.
    #[test]
    fn normals_in_lanes_are_the_normals_one_at_a_time_bit_for_bit() {
        use crate::shapes::Shape;
        let frame = Frame::new(
            DVec3::new(0.3, -1.2, 2.0),
            DVec3::new(0.8, 0.1, 0.0),
            DVec3::new(-0.1, 0.9, 0.2),
            DVec3::new(0.0, -0.3, 1.1),
        )
        .unwrap();
        let surfaces = [
            presets::preset("barth_sextic", &[]).unwrap().equation,
            presets::preset("chmutov", &[8.0]).unwrap().equation,
            "x^2 + y^2 - z^2".to_string(),
            presets::preset("torus", &[1.0, 0.3]).unwrap().equation,
            presets::preset("heart", &[]).unwrap().equation,
        ];
        let mut uniform = crate::testing::uniform_stream(0x2545_f491_4f6c_dd1d);
        for (k, equation) in surfaces.iter().enumerate() {
            let shape = Implicit::new(equation, frame, Some(1.5)).unwrap();
            // The first three take the lanes path; the torus and the heart one at a time.
            assert_eq!(shape.normal_lanes_pays(), k < 3, "{equation}");
            let centre = frame.point_to_world(DVec3::ZERO);
            // Points on the surface: where rays from outside towards the centre meet it, and
            // the object's centre itself (the cone's apex).
            let mut points = vec![centre];
            while points.len() < 400 {
                let mut v = || 2.0 * uniform() - 1.0;
                let origin = centre + DVec3::new(v(), v(), v()).normalize_or(DVec3::X) * 8.0;
                let target = centre + DVec3::new(v(), v(), v()) * 0.7;
                let ray = Ray::new(origin, target - origin);
                if let Some(t) = shape.intersect(&ray, 0.0, f64::INFINITY) {
                    points.push(ray.at(t));
                }
            }
            for (k, group) in points.chunks_exact(LANES).enumerate() {
                let p: [DVec3; LANES] = std::array::from_fn(|i| group[i]);
                let live: [bool; LANES] = std::array::from_fn(|i| (k + i) % 5 != 0);
                let lanes = shape.normal_lanes(&p, live);
                for i in 0..LANES {
                    let want = if live[i] {
                        shape.normal(p[i])
                    } else {
                        DVec3::ZERO
                    };
                    assert_eq!(
                        lanes[i].to_array().map(f64::to_bits),
                        want.to_array().map(f64::to_bits),
                        "{equation} at {:?}",
                        p[i]
                    );
                }
            }
        }
    }

    /// Points where rays from outside towards the centre meet `shape` (unit frame), with
    /// its generic surface.
    fn hits_of(shape: &Implicit, count: usize, seed: u64) -> Vec<DVec3> {
        use crate::shapes::Shape;
        let mut uniform = crate::testing::uniform_stream(seed);
        let mut points = Vec::new();
        for _ in 0..50 * count {
            let mut v = || 2.0 * uniform() - 1.0;
            let origin = DVec3::new(v(), v(), v()).normalize_or(DVec3::X) * 8.0;
            let target = DVec3::new(v(), v(), v()) * 1.6;
            let ray = Ray::new(origin, target - origin);
            if let Some(t) = shape.intersect(&ray, 0.0, f64::INFINITY) {
                points.push(ray.at(t));
                if points.len() == count {
                    break;
                }
            }
        }
        assert_eq!(points.len(), count, "too few hits");
        points
    }

    /// Where the expansion cancels so much that `f64`'s gradient is not far enough above its
    /// rounding (issue 36's cliffs: every such normal went to the sign-plane, hundreds of
    /// double-double evaluations), the normal is a gradient taken exactly enough — the
    /// equation's tree's where it goes through the tree and its bound certifies it, else
    /// `∇f` in double-double arithmetic: along the closed form's normal and the double-double
    /// gradient to 1e-12 (the sign-plane, good to about its sphere's radius, is not used),
    /// and the sign-plane's to 1e-4 where that one answers.
    #[test]
    fn a_cancelling_expansion_takes_its_gradient_in_double_double() {
        type Normal = fn(DVec3) -> DVec3;
        let cases: [(&str, Normal); 3] = [
            ("(x+y+z)^16 - 1", |p| {
                DVec3::ONE.normalize() * (p.x + p.y + p.z).signum()
            }),
            ("(x^2+y^2+z^2-1)^8 - 1e-5", |p| {
                p.normalize() * (p.length_squared() - 1.0).signum()
            }),
            ("(x^2+y^2-1)^8 - 1e-12", |p| {
                let r = DVec3::new(p.x, p.y, 0.0);
                r.normalize() * (r.length_squared() - 1.0).signum()
            }),
        ];
        for (equation, exact) in cases {
            let shape = Implicit::new_generic(equation, Frame::identity(), 2.0).unwrap();
            let Kind::Generic(s) = &shape.object().kind else {
                panic!("{equation}: the generic path")
            };
            let h = SIGN_SPHERE * 2.0;
            let mut compared = 0;
            let mut taken = 0;
            for q in hits_of(&shape, 100, 0x9e37_79b9_7f4a_7c15) {
                let (values, magnitudes) = s.gradient_with_bound(q.to_array());
                let g = DVec3::from_array(values);
                let scale = magnitudes.iter().fold(0.0f64, |m, &v| m.max(v));
                let noise = ROUNDING * s.gradient.most_terms as f64 * scale;
                if g.abs().max_element() > GRADIENT_MARGIN * noise {
                    continue; // f64's gradient does
                }
                // Smooth about `q`, so answered before the sign-plane: by the tree's test
                // where the surface goes through the tree, by the expansion's otherwise.
                let smooth = match &s.tree {
                    Some(tree) => tree_smooth_direction(tree, q, h).is_some(),
                    None => s.smooth_gradient(q, h, g, noise).is_some(),
                };
                assert!(smooth, "{equation} at {q}: smooth, yet not taken");
                taken += 1;
                let n = s.normal_direction(q, h).normalize();
                assert!((n - exact(q)).length() < 1e-12, "{equation} at {q}: {n}");
                let dd = s.gradient_dd(q).normalize();
                assert!((n - dd).length() < 1e-12, "{equation} at {q}: {n}, {dd}");
                if let Some(plane) = s.normal_from_signs(q, h) {
                    assert!((plane - n).length() < 1e-4, "{equation} at {q}: {plane}");
                    compared += 1;
                }
            }
            assert!(taken >= 10, "{equation}: {taken} of 100 in double-double");
            assert!(2 * compared >= taken, "{equation}: {compared} sign-planes");
        }
    }

    /// Near a point where `∇f` vanishes (a cone's apex within the sign sphere) its direction
    /// swings across the probes: the double-double gradient is not taken, whatever its size.
    #[test]
    fn a_gradient_that_swings_across_the_sign_sphere_is_not_taken() {
        let shape = Implicit::new("x^2 + y^2 - z^2", Frame::identity(), Some(2.0)).unwrap();
        let Kind::Generic(s) = &shape.object().kind else {
            panic!("the generic path")
        };
        let h = SIGN_SPHERE * 2.0;
        for q in [
            DVec3::new(2e-6, 0.0, 2e-6),
            DVec3::new(0.0, -1e-5, 1e-5),
            DVec3::new(3e-5, 4e-5, -5e-5),
        ] {
            let g = s.gradient(q);
            assert_eq!(s.smooth_gradient(q, h, g, 1e-300), None, "{q}");
        }
        // Far from the apex the cone is smooth across the sphere: taken.
        let q = DVec3::new(0.6, 0.8, 1.0);
        assert!(s.smooth_gradient(q, h, s.gradient(q), 1e-300).is_some());
    }

    /// A sphere clipped by its own radius, and by radii one ulp either side, is hit at its
    /// near side by every ray that meets it (none drops the hit at the chord's end and
    /// shows the far side, none misses), one ray at a time and four at once alike.
    #[test]
    fn a_surface_on_its_clip_sphere_is_hit_once_on_every_ray() {
        use crate::shapes::Shape;
        let radius: f64 = 6.0;
        let bounds = [
            radius,
            f64::from_bits(radius.to_bits() - 1),
            f64::from_bits(radius.to_bits() + 1),
        ];
        let mut uniform = crate::testing::uniform_stream(0x0c11_9e5f_0a7e_5eed);
        for bound in bounds {
            let shape = Implicit::new("x^2 + y^2 + z^2 = 36", Frame::identity(), Some(bound))
                .unwrap_or_else(|e| panic!("BOUND {bound}: {}", e.message));
            let (mut hits, mut rays) = (0, 0);
            for k in 0..4000 {
                // Parallel rays along a random direction through points of the disc of radius
                // 0.99·6 across it (as an orthographic camera sends them), and rays from a
                // point 20 away through points of that disc (as a pinhole does).
                let mut v = || 2.0 * uniform() - 1.0;
                let axis = DVec3::new(v(), v(), v()).normalize_or(DVec3::Z);
                let side = axis.any_orthonormal_pair();
                let (a, b) = (v(), v());
                let offset = (side.0 * a + side.1 * b) * radius * 0.99 / 2f64.sqrt();
                let ray = if k % 2 == 0 {
                    Ray::new(offset - axis * 20.0, axis)
                } else {
                    let eye = -axis * 20.0;
                    Ray::new(eye, (offset - eye).normalize())
                };
                rays += 1;
                // The near intersection of the ray's line with the sphere.
                let (b, c) = (ray.origin.dot(ray.dir), ray.origin.length_squared() - 36.0);
                let near = -b - (b * b - c).sqrt();
                let Some(t) = shape.intersect(&ray, 0.0, f64::INFINITY) else {
                    panic!("BOUND {bound}: ray {k} ({ray:?}) misses the sphere");
                };
                assert!(
                    (t - near).abs() < 1e-6,
                    "BOUND {bound}: ray {k} hits at {t}, not at the near side {near}"
                );
                let lanes =
                    shape.intersect_lanes(&[ray; LANES], [0.0; LANES], [f64::INFINITY; LANES]);
                for hit in lanes {
                    assert_eq!(
                        hit.map(f64::to_bits),
                        Some(t.to_bits()),
                        "BOUND {bound}: ray {k}"
                    );
                }
                hits += 1;
            }
            assert_eq!(hits, rays);
        }
    }

    /// The preset `name` (with `params`) through the generic path, at the origin.
    fn generic_preset(name: &str, params: &[f64]) -> Implicit {
        let p = presets::preset(name, params).unwrap();
        Implicit::new_generic(&p.equation, Frame::identity(), p.bound).unwrap()
    }

    /// The object-space shape of a surface made by [`generic_preset`], and its surface.
    fn generic_parts(shape: &Implicit) -> (&ImplicitShape, &Surface) {
        let object = shape.object();
        let Kind::Generic(s) = &object.kind else {
            panic!("made generic");
        };
        (object, s)
    }

    #[test]
    fn spans_in_lanes_are_the_scalar_spans_bit_for_bit_in_both_copies() {
        for (name, params) in [
            ("torus", vec![1.0, 0.3]),
            ("barth_sextic", vec![]),
            ("taubin_heart", vec![]),
        ] {
            // Taubin's heart through the generic path (its preset takes the heart's).
            let shape = generic_preset(name, &params);
            let (object, s) = generic_parts(&shape);
            let r = object.bound;
            let mut uniform = crate::testing::uniform_stream(0x7f4a_7c15_9e37_79b9);
            let mut counts = [0usize; 2];
            for k in 0..4000usize {
                let rays: [Ray; LANES] = std::array::from_fn(|l| {
                    let mut v = || 2.0 * uniform() - 1.0;
                    let origin = DVec3::new(v(), v(), v()) * 4.0 * r;
                    let target = DVec3::new(v(), v(), v()) * r;
                    let mut dir = (target - origin) * (0.1 + 10.0 * uniform());
                    match (k + l) % 11 {
                        0 => dir.x = 0.0, // parallel to a slab
                        1 => dir = DVec3::ZERO,
                        2 => dir.y = f64::NAN,
                        _ => {}
                    }
                    // Secondary rays start inside the sphere.
                    let origin = if (k + l) % 3 == 0 { target } else { origin };
                    Ray::new(origin, dir)
                });
                let t_min: [f64; LANES] = std::array::from_fn(|l| match (k + l) % 5 {
                    0 => -1.0,
                    1 => 1e-3,
                    2 => 0.3,
                    _ => 0.0,
                });
                let t_max: [f64; LANES] = std::array::from_fn(|l| match (k + l) % 7 {
                    0 => f64::NEG_INFINITY,
                    1 => 0.5,
                    _ => f64::INFINITY,
                });
                let lanes = LaneRays {
                    local: &rays,
                    t_min,
                    t_max,
                };
                let object_box = s.object_box.as_ref().expect("a box");
                let baseline = object.spans_lanes_in(object_box, lanes);
                let detected = object.spans_lanes(s, lanes);
                let (baseline, detected) = (
                    std::array::from_fn::<_, LANES, _>(|i| baseline.get(i)),
                    std::array::from_fn::<_, LANES, _>(|i| detected.get(i)),
                );
                for i in 0..LANES {
                    let want = (t_max[i] > t_min[i])
                        .then(|| object.span(s, &rays[i], t_min[i], t_max[i]))
                        .flatten();
                    assert_eq!(bits(baseline[i]), bits(want), "{name}: {:?}", rays[i]);
                    assert_eq!(bits(detected[i]), bits(want), "{name}: {:?}", rays[i]);
                    counts[usize::from(want.is_some())] += 1;
                }
            }
            assert!(counts[0] > 2000 && counts[1] > 2000, "{name}: {counts:?}");
        }
    }

    #[test]
    fn intersections_in_lanes_are_the_same_in_both_copies() {
        // The generic lanes query's body compiled for AVX2 (where this processor has it) and
        // for the baseline (what a processor without AVX2 runs of it; the spans and the roots'
        // front it calls choose their own copies at run time, and their tests check both): the
        // same hits, bit for bit, on camera-like and secondary rays through typed surfaces of
        // degrees 4 to 8.
        for (name, params) in [
            ("torus", vec![1.0, 0.3]),
            ("barth_sextic", vec![]),
            ("chmutov", vec![8.0]),
            ("taubin_heart", vec![]),
        ] {
            let shape = generic_preset(name, &params);
            let (object, s) = generic_parts(&shape);
            let r = object.bound;
            let mut uniform = crate::testing::uniform_stream(0x9e37_79b9_7f4a_7c15);
            let mut hits = 0usize;
            for k in 0..3000usize {
                let rays: [Ray; LANES] = std::array::from_fn(|l| {
                    let mut v = || 2.0 * uniform() - 1.0;
                    let origin = DVec3::new(v(), v(), v()) * 4.0 * r;
                    let target = DVec3::new(v(), v(), v()) * r;
                    let origin = if (k + l) % 3 == 0 { target } else { origin };
                    Ray::new(origin, target - origin + DVec3::splat(0.01 * v()))
                });
                let t_min = [0.0, 1e-6, 0.0, 1e-3];
                let t_max = [f64::INFINITY, 2.0, f64::INFINITY, f64::INFINITY];
                let baseline = object.intersect_lanes_generic(s, &rays, t_min, t_max);
                hits += baseline.iter().flatten().count();
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2, checked just above.
                    let detected =
                        unsafe { object.intersect_lanes_generic_avx2(s, &rays, t_min, t_max) };
                    let bits = |x: [Option<f64>; LANES]| x.map(|t| t.map(f64::to_bits));
                    assert_eq!(bits(detected), bits(baseline), "{name}: {rays:?}");
                }
            }
            assert!(hits > 2000, "{name}: {hits}");
        }
    }
}

#[cfg(test)]
mod tree_choice_tests {
    use super::*;

    /// Which surfaces go through their tree: the cliffs of issue 36, whose expansions cancel
    /// by many orders; none of the presets, gallery surfaces or shipped scenes' equations.
    #[test]
    fn only_cancelling_expansions_go_through_the_tree() {
        let ordinary = [
            ("kummer 1.140175425", 1.0),
            ("barth_sextic", 1.0),
            ("clebsch", 1.0),
            ("chmutov 6", 1.0),
            ("chmutov 12", 1.0),
            ("chmutov 16", 1.0),
            ("(x^2+y^2+z^2)^8 = 1", 1.5),
            ("4*(x^2 + y^2 + z^2) + 16*x*y*z - 1", 1.6),
            ("x^2*y^2 + y^2*z^2 + z^2*x^2 - x*y*z", 1.0),
            ("x^2 + y^2 + z^3 - z^2", 1.6),
            ("x^2 + y^2 + z^2 - 1", 2.0),
        ];
        // `(x+y+z+1)^4 − 1` cancels little (17 times) and keeps its expansion.
        let cliffs = [
            "(x+y+z+1)^8 - 1",
            "(x+y+z+1)^16 - 1",
            "(x+y+z)^16 - 1",
            "(x^2+y^2+z^2-1)^8 - 1e-5",
            "(x^2+y^2-1)^8 - 1e-12",
            "((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1",
        ];
        let advantage = |text: &str, bound: f64| {
            let (expr, poly) = parse_and_expand(text, &|_| None).unwrap();
            let f = Compiled::new(&poly);
            let tree = tree::Tree::new(&expr, f.degree).unwrap();
            tree_advantage(&f, &tree, bound)
        };
        let mut failed = Vec::new();
        for (name, bound) in ordinary {
            let mut words = name.split(' ');
            let head = words.next().unwrap();
            let text = if PRESETS.iter().any(|(p, _)| *p == head) {
                let params: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                preset_equation(head, &params).unwrap()
            } else {
                name.to_string()
            };
            let a = advantage(&text, bound);
            eprintln!("{name}: {a:e}");
            if a >= TREE_ADVANTAGE / 5.0 {
                failed.push(format!("{name}: {a:e}"));
            }
        }
        for text in cliffs {
            let a = advantage(text, 2.0);
            eprintln!("{text}: {a:e}");
            if a < TREE_ADVANTAGE {
                failed.push(format!("{text}: {a:e}"));
            }
        }
        assert!(failed.is_empty(), "{failed:?}");
        // The shipped scene's equation that is not a preset is a torus (its closed form).
        let menagerie = "(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2) = 0";
        let shape = Implicit::new(menagerie, Frame::identity(), Some(2.0)).unwrap();
        let Kind::Generic(s) = &shape.object().kind else {
            panic!("the generic path")
        };
        assert!(s.torus.is_some() && s.tree.is_none());
    }
}
