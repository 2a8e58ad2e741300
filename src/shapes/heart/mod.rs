//! The paper's implicit heart, `(2X² + Y² + Z² − 1)³ − (0.1X² + Y²)·Z³ = 0`, placed in the
//! world by a position and a basis `u, v, w` (the scene line `HEART (position) (u) (v) (w)`).
//!
//! A ray's path through [`Heart::intersect`](super::Shape::intersect):
//! 1. into object space with `M⁻¹` (direction not renormalised, so `t` is shared);
//! 2. clipped to the object-space box [`surface::BOUNDS`] (the exact extents plus a margin),
//!    then to the hull of its spans above `Z = 0` and inside the ellipsoid
//!    `2X² + Y² + Z² ≤ 1` that holds the lower half: a ray that misses them costs a slab test
//!    and a quadratic only;
//! 3. re-parametrised over the clipped chord, `s ∈ [0, 1]` from box entry to exit, so the
//!    sextic's coefficients are built from a point near the heart and are well scaled whatever
//!    the distance, length of `d` or size of the heart;
//! 4. the coefficients in closed form ([`sextic_coefficients`]) and the first root in `(0, 1]`
//!    from the scene's [`Solver`] (four rays' chords at once by [`Solver::first_root_lanes_by_power`], the sextics laid out by power,
//!    where they come in lanes, the same answers);
//! 5. that root polished by a few safeguarded Newton steps on the well-conditioned factor
//!    `g = A − ∛B·Z` ([`factor_g`]): where `f` has a triple root (the equator curve) its root
//!    is only good to ~1e-5, where `g`'s is good to the last bit (away from that curve, where
//!    `f = g·3A²` with `A` resolved, one or two Newton steps on `f` itself do the same without
//!    a cube root);
//! 6. checked: a root with no root of `g` near it (a near-tangency or rounding noise of `f`)
//!    is skipped; a root where `g` crosses the wrong way (leaving the heart although the ray
//!    started outside) means the solver merged an earlier root into it, which is recovered
//!    from `g`; a root at or before the ray's own origin (a ray leaving the surface) is
//!    skipped. The search then resumes past the skipped root.
//!
//! The normal ([`super::Shape::normal`]) is `∇f` where its rounding is far below what a pixel
//! shows (most of the surface: no cube root), else `∇g` (parallel to `∇f` on the surface, but
//! well-defined and well-conditioned on the equator curve), with `∇f` and then the axis as
//! fallbacks at the two singular points, mapped to world space by `(M⁻¹)ᵀ`.

mod corpus;
mod lanes;
mod polish;
mod surface;

#[doc(hidden)]
pub use corpus::{heart_corpus, heart_hard_rays, CorpusRay};

use polish::{earlier_crossing, polish};

pub use surface::{
    factor_g, factor_g_with_slope, gradient_f, heart_fn, outward_direction, scaled_gradient_g,
    sextic_coefficients, BOUNDS, BOUNDS_MARGIN, EXTENTS, S_X, S_Y, S_Z,
};

use super::placed::{ObjectShape, Placed, Placement};
use super::report::Recorder;
use super::{ShapeError, SolverReport, LANES};
use crate::geometry::{Aabb, DVec3, Frame, Ray, SolidEllipsoid};
use crate::roots::Solver;

/// Object-space length (the heart is about 2 units across in object space) below which a
/// root next to the ray's origin counts as the origin itself: a ray leaving the surface never
/// reports a hit closer than this, at any world scale (see [`Heart::self_hit_guard`]).
pub const SELF_HIT_GUARD: f64 = 1e-6;

/// How far (object-space length) polishing may move a root found on `f`: far beyond the
/// error of a triple root of `f` in f64 (~1e-5), and beyond the spread of a cluster of roots
/// a solver may merge into one where `f` is below its rounding over a sliver of the heart
/// (measured up to ~1e-3 at the equator).
const POLISH_WINDOW: f64 = 1e-2;

/// How far (in units of the clipped chord) polishing must move the solver's root to count as
/// having settled the hit (see [`SettledBy::HeartPolish`](super::SettledBy::HeartPolish)):
/// far above the few ulps a simple root moves, far below the ~1e-5 error of `f`'s triple root.
const POLISH_VISIBLE: f64 = 1e-9;

/// How many roots may be skipped, at or before the ray's origin (a triple root of `f` splits
/// into at most three by rounding) or off the surface (near-tangencies), before the ray is
/// declared to miss.
const MAX_SKIPS: usize = 6;

/// A heart placed in the world; see the module doc.
pub type Heart = Placed<HeartShape>;

/// The object-space heart `f = 0` of the module doc, with the root-isolation strategy its
/// intersections use.
#[derive(Debug, Clone, PartialEq)]
pub struct HeartShape {
    solver: Solver,
}

impl Heart {
    /// A heart at `position` with object-to-world basis columns `u, v, w` (any invertible
    /// basis; a singular or nearly singular one is an error).
    pub fn new(position: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, ShapeError> {
        Ok(Self::from_frame(Frame::new(position, u, v, w)?))
    }

    /// A heart placed by an already validated frame.
    pub fn from_frame(frame: Frame) -> Self {
        Placed::place(Placement::new(frame), HeartShape::default())
    }

    /// The same heart, intersected with the given root-isolation strategy.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        self.object_mut().solver = solver;
        self
    }

    /// The root-isolation strategy in use.
    pub fn solver(&self) -> Solver {
        self.object().solver
    }

    /// The object-space distance along a ray from `origin_obj` within which roots are taken to
    /// be the origin itself: [`SELF_HIT_GUARD`], or more when the origin is so far away (in
    /// object units, counting the world position) that its own rounding exceeds that.
    #[inline]
    pub fn self_hit_guard(&self, origin_obj: DVec3) -> f64 {
        HeartShape::self_hit_guard(self.placement(), origin_obj)
    }

    /// [`Shape::intersect`](super::Shape::intersect) with the first-root query supplied by
    /// the caller (tests use it to check the geometry independently of the solver).
    /// `first_root(c, lo, hi)` must return the smallest root in `(lo, hi]` of
    /// `c0 + c1·s + … + c6·s⁶`, if any.
    pub fn intersect_with(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        first_root: impl FnMut(&[f64; 7], f64, f64) -> Option<f64>,
    ) -> Option<f64> {
        let local = self.placement().ray_to_object(ray);
        HeartShape::intersect_with(
            self.placement(),
            &local,
            t_min,
            t_max,
            first_root,
            &mut false,
        )
    }
}

impl Default for HeartShape {
    /// The heart with the default strategy.
    fn default() -> Self {
        Self {
            solver: Solver::default(),
        }
    }
}

impl HeartShape {
    /// The heart intersected with `solver`.
    pub fn with_solver(solver: Solver) -> Self {
        Self { solver }
    }

    /// See [`Heart::self_hit_guard`].
    #[inline]
    fn self_hit_guard(at: &Placement, origin_obj: DVec3) -> f64 {
        let reach = origin_obj.abs().max_element() + at.position_reach();
        SELF_HIT_GUARD.max(1024.0 * f64::EPSILON * reach)
    }

    /// See [`Heart::intersect_with`]; `r` is the ray in object space. `polished` is set when
    /// the checks on `g` (step 6 of the module doc) changed the first query's answer: moved
    /// its root beyond rounding, replaced it by an earlier crossing, or skipped it.
    #[inline(always)]
    fn intersect_with(
        at: &Placement,
        r: &Ray,
        t_min: f64,
        t_max: f64,
        first_root: impl FnMut(&[f64; 7], f64, f64) -> Option<f64>,
        polished: &mut bool,
    ) -> Option<f64> {
        let chord = Self::chord(at, r, t_min, t_max)?;
        Self::hit_on_chord(&chord, t_max, first_root, polished)
    }

    /// Steps 1–4 of the module doc up to the coefficients: the part of the object-space ray
    /// `r` that can meet the heart, or `None` when none can ([`lanes::chords`] computes the
    /// same for several rays at once, bit for bit).
    #[inline(always)]
    fn chord(at: &Placement, r: &Ray, t_min: f64, t_max: f64) -> Option<Chord> {
        // |d|, without the underflow or overflow of squaring tiny or huge components.
        let scale = r.dir.abs().max_element();
        let dir_len = scale * (r.dir / scale).length();
        if !(dir_len > 0.0 && dir_len.is_finite() && r.origin.is_finite()) {
            return None;
        }
        let t_lo = t_min.max(Self::self_hit_guard(at, r.origin) / dir_len);
        let (t0, t1) = BOUNDS.clip(r, t_lo, t_max)?;
        let (t0, t1) = clip_lower_half(r, t0, t1)?;
        let len = t1 - t0;
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        // s ∈ [0, 1] over the chord: origin at box entry (or at t_lo), direction the chord.
        let o = r.at(t0);
        let d = r.dir * len;
        Some(Chord {
            t_lo,
            t0,
            len,
            o,
            d,
            coeffs: sextic_coefficients(o, d),
            window: POLISH_WINDOW / (dir_len * len),
        })
    }

    /// Steps 4–6 of the module doc for the lanes' chords from [`lanes::chords`] (`alive`,
    /// `chords`, `by_power` as it wrote them): each live lane's first hit before `t_max[i]`.
    #[inline(always)]
    fn hits_on_chords(
        &self,
        alive: [bool; LANES],
        chords: &std::mem::MaybeUninit<[Chord; LANES]>,
        by_power: &lanes::ByPower,
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        if alive == [false; LANES] {
            return [None; LANES];
        }
        // SAFETY: `lanes::chords` writes every chord when a lane is alive; borrowed, not
        // copied out.
        let chords = unsafe { chords.assume_init_ref() };
        let solver = self.solver;
        // Every chord's first query, `(0, 1]`, for the lanes at once (the sextics already laid
        // out by power); a lane's later queries (past a root the checks skipped) one at a time.
        let first = solver.first_root_lanes_by_power(by_power, [0.0; LANES], [1.0; LANES], alive);
        let mut hits = [None; LANES];
        for (i, hit) in hits.iter_mut().enumerate() {
            if alive[i] {
                let mut first = Some(first[i]);
                *hit = Self::hit_on_chord(
                    &chords[i],
                    t_max[i],
                    |c, lo, hi| match first.take() {
                        Some(answer) => answer,
                        None => solver.first_root(c, lo, hi),
                    },
                    &mut false,
                );
            }
        }
        hits
    }

    /// Steps 4–6 of the module doc on a chord from [`HeartShape::chord`]: the first hit
    /// before `t_max`, with `polished` as for [`HeartShape::intersect_with`]. Its first query
    /// is always `first_root(&chord.coeffs, 0.0, 1.0)` (the lanes answer it ahead).
    #[inline(always)]
    fn hit_on_chord(
        chord: &Chord,
        t_max: f64,
        mut first_root: impl FnMut(&[f64; 7], f64, f64) -> Option<f64>,
        polished: &mut bool,
    ) -> Option<f64> {
        let Chord {
            t_lo,
            t0,
            len,
            o,
            d,
            ref coeffs,
            window,
        } = *chord;
        // Which side of the surface the search starts on (f's sign is g's: use the free c0
        // when it is clear of rounding, else g, which is accurate there).
        let side = |s: f64, f_value: f64| -> Option<bool> {
            if f_value.abs() > 1e-10 {
                return Some(f_value > 0.0);
            }
            let g = factor_g(o + s * d);
            (g != 0.0).then_some(g > 0.0)
        };
        let mut outside = side(0.0, coeffs[0]);
        let mut side_lo = 0.0; // where `outside` holds
        let mut lo = 0.0;
        for _ in 0..MAX_SKIPS {
            let s_root = first_root(coeffs, lo, 1.0)?;
            let Some(mut root) = polish(o, d, s_root, window) else {
                // Not on the surface (a near-tangency or rounding noise the solver took for a
                // root), and g keeps its sign within the window around it: go on past it.
                *polished = true;
                lo = (s_root + window).max(s_root.next_up());
                if lo >= 1.0 {
                    return None;
                }
                continue;
            };
            // From outside the first crossing must enter (g falls), from inside leave (g
            // rises). The other way round, the solver merged or lost an earlier root.
            if let (Some(rising), Some(out)) = (root.rising, outside) {
                if rising == out {
                    if let Some(earlier) = earlier_crossing(o, d, side_lo, root.s, out) {
                        root = earlier;
                    }
                }
            }
            if (root.s - s_root).abs() > POLISH_VISIBLE {
                *polished = true;
            }
            let t = t0 + root.s * len;
            if t > t_lo {
                return (t < t_max).then_some(t);
            }
            *polished = true;
            // The root is the ray's own origin (or another below the guard): rounding of a
            // multiple root may put more copies just after it, spread about as far from the
            // true root as this one; resume the search beyond them.
            lo = (s_root + 2.0 * (s_root - root.s).abs()).max(s_root.next_up());
            side_lo = lo;
            outside = side(lo, 0.0);
        }
        None
    }
}

/// The part of an object-space ray that can meet the heart, re-parametrised as
/// `o + s·d`, `s ∈ [0, 1]` (step 3 of the module doc), with the sextic on it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Chord {
    /// The ray parameter below which a root is the ray's own origin.
    t_lo: f64,
    /// The ray parameter at `s = 0`.
    t0: f64,
    /// The ray parameter's length of the chord (`t = t0 + s·len`), positive and finite.
    len: f64,
    /// The object-space point at `s = 0`.
    o: DVec3,
    /// The object-space chord, `s = 0` to `s = 1`.
    d: DVec3,
    /// `f(o + s·d)`, ascending powers of `s`.
    coeffs: [f64; 7],
    /// [`POLISH_WINDOW`] in units of `s`.
    window: f64,
}

/// The part of `[t0, t1]` (a chord of [`BOUNDS`]) that can meet the heart, given that its
/// lower half lies in the ellipsoid `2X² + Y² + Z² ≤ 1` (below `Z = 0`, `g ≤ 0` gives
/// `A ≤ ∛B·Z ≤ 0`): the hull of the ray's spans inside that ellipsoid and above `Z = 0`, each
/// widened by [`BOUNDS_MARGIN`], the span above `Z = 0` further cut to an ellipsoid that holds
/// the upper half ([`upper_span`]). Rejects the rays that pass beside the tip in the box's
/// lower corners or beside the lobes in its upper corners, and shortens the chord the solver
/// sees.
#[inline]
fn clip_lower_half(r: &Ray, t0: f64, t1: f64) -> Option<(f64, f64)> {
    // Parametrise from the box entry so that every quantity is of the heart's size.
    let o = r.at(t0);
    let d = r.dir;
    let len = t1 - t0;
    // Above Z = −margin: a half-line in u = t − t0.
    let z_floor = -BOUNDS_MARGIN;
    let above = if d.z > 0.0 {
        let u = ((z_floor - o.z) / d.z).max(0.0);
        (u <= len).then_some((u, len))
    } else if d.z < 0.0 {
        let u = (z_floor - o.z) / d.z;
        (u >= 0.0).then_some((0.0, u.min(len)))
    } else {
        (o.z >= z_floor).then_some((0.0, len))
    };
    // Inside 2X² + Y² + Z² ≤ (1 + margin)².
    let (p, e) = (o.to_array(), d.to_array());
    let (inside_ok, u0, u1) = ellipsoid_span(p, e, LOWER_ELLIPSOID, len, (0.0, len));
    let inside = inside_ok.then_some((u0, u1));
    let upper = above.and_then(|range| {
        let (ok, w0, w1) = ellipsoid_span(p, e, upper_ellipsoid(), len, range);
        ok.then_some((w0, w1))
    });
    let (u0, u1) = match (upper, inside) {
        (Some(p), Some(q)) => (p.0.min(q.0), p.1.max(q.1)),
        (Some(p), None) | (None, Some(p)) => p,
        (None, None) => return None,
    };
    Some((t0 + u0, t0 + u1))
}

/// `∛B` at most, anywhere in [`BOUNDS`]: `B = 0.1X² + Y² ≤ 0.1·0.7194² + 1.1392² < 1.3494`,
/// whose cube root is below 1.1050.
const CBRT_B_MAX: f64 = 1.106;

/// The ellipsoid `2X² + Y² + Z² ≤ (1 + margin)²` that holds the heart's lower half, as
/// `(c, R²)` of `2X² + Y² + (Z − c)² ≤ R²` (see [`ellipsoid_span`]).
const LOWER_ELLIPSOID: (f64, f64) = (0.0, (1.0 + BOUNDS_MARGIN) * (1.0 + BOUNDS_MARGIN));

/// The ellipsoid `2X² + Y² + (Z − c)² ≤ R²` that holds the heart's upper half, as `(c, R²)`:
/// above `Z = 0` the surface has `A = ∛B·Z ≤ 2c·Z` with `c = CBRT_B_MAX/2`, i.e.
/// `2X² + Y² + (Z − c)² ≤ 1 + c²`; `R` is widened by [`BOUNDS_MARGIN`].
#[inline(always)]
fn upper_ellipsoid() -> (f64, f64) {
    let c = 0.5 * CBRT_B_MAX;
    let r = (1.0 + c * c).sqrt() + BOUNDS_MARGIN;
    (c, r * r)
}

/// The span `(u0, u1)` within `range` where the ray `p + u·e` is inside the ellipsoid
/// `2X² + Y² + (Z − c)² ≤ R²` (`(c, R²)` given), and whether it is not empty; a ray of
/// `len` along the chord. The scalar chord and the lanes ([`lanes::chords`]) both call it,
/// so they make the same operations.
#[inline(always)]
fn ellipsoid_span(
    p: [f64; 3],
    e: [f64; 3],
    (centre_z, r2): (f64, f64),
    len: f64,
    range: (f64, f64),
) -> (bool, f64, f64) {
    let pz = p[2] - centre_z;
    let a = 2.0 * e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    let hb = 2.0 * p[0] * e[0] + p[1] * e[1] + pz * e[2];
    let k = 2.0 * p[0] * p[0] + p[1] * p[1] + pz * pz - r2;
    quadratic_span(a, hb, k, len, range)
}

/// The span `(u0, u1)` within `[lo, hi]` where `a·u² + 2·hb·u + k ≤ 0` (`a > 0`: a ray inside an
/// ellipsoid), and whether it is not empty; a degenerate ray through the centre plane
/// (`q = 0`) keeps `[0, len]`. Without branches, so that the lanes ([`lanes::chords`]) and the
/// scalar chord make the same operations.
#[inline(always)]
fn quadratic_span(a: f64, hb: f64, k: f64, len: f64, (lo, hi): (f64, f64)) -> (bool, f64, f64) {
    let disc = hb * hb - a * k;
    let q = -(hb + hb.signum() * disc.sqrt());
    let (u0, u1) = (q / a, k / q);
    let (u0, u1) = if u0 > u1 { (u1, u0) } else { (u0, u1) };
    let (u0, u1) = if u0.is_finite() & u1.is_finite() {
        (u0, u1)
    } else {
        (0.0, len)
    };
    let (u0, u1) = (u0.max(lo), u1.min(hi));
    ((disc >= 0.0) & (u0 <= u1), u0, u1)
}

impl ObjectShape for HeartShape {
    // Inlined whole into `Placed::intersect`, as it was into the heart's own before the
    // placement wrapper (1.3% of the benchmark's instructions otherwise).
    #[inline(always)]
    fn intersect(
        &self,
        at: &Placement,
        _: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64> {
        let solver = self.solver;
        Self::intersect_with(
            at,
            local,
            t_min,
            t_max,
            |c, lo, hi| solver.first_root(c, lo, hi),
            &mut false,
        )
    }

    fn intersect_lanes(
        &self,
        at: &Placement,
        _: &[Ray; LANES],
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        let mut chords = std::mem::MaybeUninit::uninit();
        let mut by_power = [[0.0; LANES]; 7];
        let alive = lanes::chords(at, local, t_min, t_max, &mut chords, &mut by_power);
        self.hits_on_chords(alive, &chords, &by_power, t_max)
    }

    fn intersect_lanes_mapped(
        &self,
        at: &Placement,
        world: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        let mut chords = std::mem::MaybeUninit::uninit();
        let mut by_power = [[0.0; LANES]; 7];
        let alive = lanes::chords_of_world(at, world, t_min, t_max, &mut chords, &mut by_power);
        self.hits_on_chords(alive, &chords, &by_power, t_max)
    }

    fn solver_report(
        &self,
        at: &Placement,
        _: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<SolverReport> {
        let mut recorder = Recorder::new(self.solver);
        let mut polished = false;
        let hit = Self::intersect_with(
            at,
            local,
            t_min,
            t_max,
            |c, lo, hi| recorder.first_root(c, lo, hi),
            &mut polished,
        );
        // A root the solver found but the checks dropped (the ray misses) was settled by them.
        let polished = polished || (hit.is_none() && recorder.first_answer().is_some());
        let gradient = hit.map(|t| gradient_f(local.at(t)).length());
        recorder.finish(hit, polished, gradient)
    }

    fn normal(&self, at: &Placement, q: DVec3) -> DVec3 {
        // Never NaN: `+Z` for a zero direction, unreachable for an invertible frame.
        at.normal_to_world(outward_direction(q))
    }

    fn bounds(&self, at: &Placement) -> Aabb {
        at.bounds_to_world(&BOUNDS)
    }

    fn polynomial_solid(&self) -> Option<(std::sync::Arc<super::implicit::poly::Poly>, f64)> {
        Some((
            super::solid::heart_polynomial(),
            super::solid::heart_clip_radius(),
        ))
    }

    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        // The lower and the upper half's ellipsoids, `2X² + Y² + (Z − c)² ≤ R²`: every chord
        // the solver searches meets one of them.
        [LOWER_ELLIPSOID, upper_ellipsoid()]
            .map(|(c, r2)| {
                let r = r2.sqrt();
                SolidEllipsoid::axis_aligned(
                    DVec3::new(0.0, 0.0, c),
                    DVec3::new(r * std::f64::consts::FRAC_1_SQRT_2, r, r),
                )
            })
            .to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_upper_ellipsoid_holds_the_upper_half_of_the_surface() {
        // ∛B's bound covers the whole box (B is largest at its corners).
        let corner = |x: f64, y: f64| (0.1 * x * x + y * y).cbrt();
        let (lo, hi) = (BOUNDS.min, BOUNDS.max);
        for (x, y) in [(lo.x, lo.y), (lo.x, hi.y), (hi.x, lo.y), (hi.x, hi.y)] {
            assert!(corner(x, y) < CBRT_B_MAX, "{x} {y}");
        }
        // Surface points above Z = 0 (sign changes of g along vertical lines, bisected): each
        // in the ellipsoid, and tight enough that the test means something.
        let (c, r2) = upper_ellipsoid();
        let r = r2.sqrt() - BOUNDS_MARGIN;
        let mut worst = f64::NEG_INFINITY;
        let mut points = 0;
        for i in 0..=60 {
            for j in 0..=60 {
                let x = lo.x + (hi.x - lo.x) * f64::from(i) / 60.0;
                let y = lo.y + (hi.y - lo.y) * f64::from(j) / 60.0;
                let g = |z: f64| factor_g(DVec3::new(x, y, z));
                let steps = 400;
                for k in 0..steps {
                    let (mut a, mut b) = (
                        hi.z * f64::from(k) / f64::from(steps),
                        hi.z * f64::from(k + 1) / f64::from(steps),
                    );
                    if (g(a) < 0.0) == (g(b) < 0.0) {
                        continue;
                    }
                    for _ in 0..60 {
                        let m = 0.5 * (a + b);
                        if (g(m) < 0.0) == (g(a) < 0.0) {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    let z = 0.5 * (a + b) - c;
                    let q = (2.0 * x * x + y * y + z * z).sqrt() - r;
                    worst = worst.max(q);
                    points += 1;
                }
            }
        }
        assert!(points > 2000, "{points}");
        assert!(
            worst <= 0.0,
            "a surface point {worst} outside the ellipsoid"
        );
        assert!(worst > -0.05, "the ellipsoid is loose: {worst}");
    }

    #[test]
    fn every_hit_is_inside_an_enclosing_ellipsoid() {
        use crate::shapes::Shape;
        // Placed off the origin and tilted, so that the placement of the ellipsoids counts.
        let heart = Heart::new(
            DVec3::new(0.5, -1.0, 2.0),
            DVec3::new(1.0, 0.2, 0.0),
            DVec3::new(-0.1, 0.8, 0.1),
            DVec3::new(0.0, 0.0, 1.3),
        )
        .unwrap();
        let ellipsoids = heart.enclosing_ellipsoids();
        assert_eq!(ellipsoids.len(), 2);
        let inside = |p: DVec3| {
            ellipsoids
                .iter()
                .map(|e| (e.axes.inverse() * (p - e.centre)).length())
                .fold(f64::INFINITY, f64::min)
        };
        let bounds = heart.bounds();
        let (mut hits, mut deepest) = (0, 0.0f64);
        for corpus_ray in heart_corpus() {
            // The corpus rays are object-space: carry them to the world.
            let frame = heart.frame();
            let ray = Ray::new(
                frame.point_to_world(corpus_ray.origin),
                frame.m * corpus_ray.dir,
            );
            let Some(t) = heart.intersect(&ray, 0.0, f64::INFINITY) else {
                continue;
            };
            hits += 1;
            let q = inside(ray.at(t));
            assert!(q <= 1.0, "a hit at {} of the nearest ellipsoid's radius", q);
            deepest = deepest.max(q);
            assert!(bounds.contains(ray.at(t)));
        }
        assert!(hits > 1000, "{hits}");
        assert!(deepest > 0.97, "the ellipsoids are loose: {deepest}");
    }
}
