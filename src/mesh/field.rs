//! The indicator of the solid being meshed and where its boundary crosses a segment.
//!
//! A [`Field`] is a polynomial `φ` in object space with the solid `{φ < 0} ∩ ball`: `φ = f`
//! for the inside of a surface, `φ = −f` for its outside, and `φ = f² − (T/2)²·|∇f|²` for a
//! shell of thickness `T` (the points where `|f|/|∇f| < T/2`, the first-order estimate of
//! the distance to the surface). A point with `φ = 0` exactly counts as outside (a fixed
//! sign: no label is ever zero), and so does any point on or outside the clip sphere; but a
//! singular point of the surface (`f` zero to its rounding, [`SINGULAR_ROUNDING`], and `∇f`
//! with it) is in a shell's wall, whose `φ` is negative all about it ([`Field::value`] gives
//! it the least negative value).

use crate::geometry::{DMat3, DVec3};
use crate::roots::{sturm_roots, Solver};
use crate::shapes::implicit::poly::{Compiled, Gradient, Poly, Powers};
use crate::shapes::implicit::MAX_DEGREE;

/// Which side of the surface the mesh encloses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolidKind {
    /// The region `f ≤ 0` (inside) within the clip ball.
    Inside,
    /// The region `f ≥ 0` (outside) within the clip ball.
    Outside,
    /// A wall about the surface: the points where `|f|/|∇f| ≤ thickness/2` (object-space
    /// units, > 0), within the clip ball.
    Shell {
        /// The wall's full thickness in object-space units.
        thickness: f64,
    },
}

/// Where a crossing vertex lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VertexKind {
    /// On the solid's polynomial boundary `φ = 0` (the surface, or the shell's wall).
    Surface,
    /// On the clip sphere.
    Cap,
    /// On the crease where `φ = 0` meets the clip sphere: on both (see [`Field::crease`]).
    Crease,
}

impl VertexKind {
    /// Whether the vertex lies on `φ = 0` (a surface or crease vertex).
    pub fn on_surface(self) -> bool {
        matches!(self, VertexKind::Surface | VertexKind::Crease)
    }

    /// Whether the vertex lies on the clip sphere (a cap or crease vertex).
    pub fn on_sphere(self) -> bool {
        matches!(self, VertexKind::Cap | VertexKind::Crease)
    }
}

/// Fraction of an edge's length that keeps a crossing vertex away from each end of the edge,
/// so that no triangle collapses to zero area (a vertex moved by it is still measured by
/// [`crate::mesh::accuracy`]).
pub const END_GAP: f64 = 1e-3;

/// How far from zero, as a share of the size of its two parts, a shell's `φ` may be at a
/// root found along a line ([`Field::is_boundary_root`]): a root placed to within this share
/// of the wall's half thickness passes.
pub const WALL_ROOT_SHARE: f64 = 1e-3;

/// The share of the sum of `f`'s terms' magnitudes below which a shell's [`Field::value`]
/// takes `f` for zero where `φ ≥ 0`: a point of a singular curve or point of the surface,
/// where `f` and `∇f` vanish and their computed values are rounding (far above `f64`'s
/// 1.1·10⁻¹⁶ per operation, far below `f` a millionth of a grid step from the curve).
pub const SINGULAR_ROUNDING: f64 = 1e-12;

/// The share of the sums of `∇f`'s terms' magnitudes below which [`Field::is_singular`]
/// takes `∇f` for zero.
pub const SINGULAR_GRADIENT: f64 = 1e-6;

/// The most Newton steps [`Field::singular_point_near`] takes (from a grid step away they
/// converge to a node, where the Hessian is invertible, in about five).
pub const NODE_STEPS: usize = 12;

/// The share of the sum of `f`'s terms' magnitudes within which its value is zero to the
/// rounding of evaluating it ([`Field::at_rounding`], [`Field::sign_beyond_rounding`]).
const VALUE_ROUNDING: f64 = 1e-8;

/// The crease beside a chamfered mesh edge ([`Field::chamfer`]), in object units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chamfer {
    /// How far the crease lies from the edge.
    pub gap: f64,
    /// How thick the solid's wedge is at the edge's surface vertex, along the surface's
    /// normal (infinite where the wedge is a right angle or wider).
    pub width: f64,
}

/// The solid's indicator: see the module documentation.
#[derive(Debug, Clone)]
pub struct Field {
    f: Compiled,
    gradient: [Compiled; 3],
    /// The three partials of `gradient`, evaluated in one pass (the same bits).
    joint_gradient: Gradient,
    kind: SolidKind,
    /// `(T/2)²` for a shell.
    half_thickness_sq: f64,
    radius: f64,
    solver: Solver,
}

impl Field {
    /// The field of `polynomial` (`f`, negative inside) for `kind`, clipped to the ball of
    /// `clip_radius` about the origin.
    pub fn new(polynomial: &Poly, clip_radius: f64, kind: SolidKind) -> Self {
        let half = match kind {
            SolidKind::Shell { thickness } => thickness / 2.0,
            _ => 0.0,
        };
        let gradient = [0, 1, 2].map(|v| Compiled::new(&polynomial.derivative(v)));
        Self {
            f: Compiled::new(polynomial),
            joint_gradient: Gradient::new(&gradient),
            gradient,
            kind,
            half_thickness_sq: half * half,
            radius: clip_radius,
            solver: Solver::default(),
        }
    }

    /// The clip radius (object space).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// What is meshed.
    pub fn kind(&self) -> SolidKind {
        self.kind
    }

    /// The degree of `φ` along a line (`f`'s degree, twice it for a shell).
    pub fn degree(&self) -> usize {
        match self.kind {
            SolidKind::Shell { .. } => 2 * self.f.degree,
            _ => self.f.degree,
        }
    }

    /// `φ` expanded in monomials, up to the sign of the outside: `(exponents of x, y, z,
    /// coefficient)`, of total degree at most [`Field::degree`]. For the inside and outside
    /// these are `f`'s terms (`φ = ±f`); for a shell, those of `f² − (T/2)²·|∇f|²` (each
    /// coefficient a sum of products of `f`'s, rounded).
    pub fn expanded_terms(&self) -> Vec<([usize; 3], f64)> {
        let terms = |p: &Compiled| -> Vec<([usize; 3], f64)> {
            p.terms
                .iter()
                .map(|t| (t.e.map(usize::from), t.c))
                .collect()
        };
        if !matches!(self.kind, SolidKind::Shell { .. }) {
            return terms(&self.f);
        }
        let mut sum: std::collections::BTreeMap<[usize; 3], f64> = Default::default();
        let mut add_product = |p: &[([usize; 3], f64)], scale: f64| {
            for &(a, x) in p {
                for &(b, y) in p {
                    let e = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
                    *sum.entry(e).or_default() += scale * x * y;
                }
            }
        };
        add_product(&terms(&self.f), 1.0);
        for g in &self.gradient {
            add_product(&terms(g), -self.half_thickness_sq);
        }
        sum.into_iter().filter(|&(_, c)| c != 0.0).collect()
    }

    /// `f` at an object-space point.
    pub fn surface_value(&self, p: DVec3) -> f64 {
        self.f.eval(p.to_array())
    }

    /// Whether `φ` at `p` is zero up to the rounding of evaluating it: for the inside and
    /// outside, `|f| ≤ 1e-8 · Σ|terms of f|`; for a shell, whose `φ` is a square less a
    /// square, `|φ| ≤ 1e-16 · (F² + (T/2)²·Σ Gᵢ²)` with `F`, `Gᵢ` those sums for `f` and its
    /// partial derivatives (the square of the same margin). A point on the surface as far as
    /// `f64` can tell, where the root finder may see a double root at a node as none.
    pub fn at_rounding(&self, p: DVec3) -> bool {
        self.value(p).abs() <= self.rounding(p, Compiled::magnitude_bound)
    }

    /// The sign of `φ(p)` (−1 or 1), or 0 where `φ(p)` is zero up to the rounding of
    /// evaluating it at `p` itself: as [`Field::at_rounding`], but with the sums of the terms'
    /// magnitudes at `p` (not a bound from its largest coordinate, which where most terms
    /// vanish, as on a plane z = 0 for a polynomial even in z, is orders of magnitude
    /// larger). A sign that can be trusted, as [`Field::at_rounding`] need not be: that one is
    /// the rounding of a line's polynomial through `p`, this one of `φ` at the point.
    pub fn sign_beyond_rounding(&self, p: DVec3) -> f64 {
        let (v, rounding) = match self.kind {
            // One evaluation of f gives its value and its terms' magnitudes.
            SolidKind::Inside | SolidKind::Outside => {
                let (f, terms) = self.f.eval_with_bound(p.to_array());
                let v = if self.kind == SolidKind::Outside {
                    -f
                } else {
                    f
                };
                (v, VALUE_ROUNDING * terms)
            }
            SolidKind::Shell { .. } => (
                self.value(p),
                self.rounding(p, |c, q| c.eval_with_bound(q).1),
            ),
        };
        if v == 0.0 || v.abs() <= rounding {
            0.0
        } else {
            v.signum()
        }
    }

    /// The rounding of `φ` at `p` from `magnitude`, a bound on the sum of a polynomial's
    /// terms' magnitudes: for the inside and outside `1e-8` of `f`'s; for a shell, whose `φ`
    /// is a square less a square, `1e-16 · (F² + (T/2)²·Σ Gᵢ²)` with `F`, `Gᵢ` those of `f`
    /// and its partial derivatives (the square of the same margin).
    fn rounding(&self, p: DVec3, magnitude: impl Fn(&Compiled, [f64; 3]) -> f64) -> f64 {
        let q = p.to_array();
        match self.kind {
            SolidKind::Shell { .. } => {
                let f = magnitude(&self.f, q);
                let g: f64 = self.gradient.iter().map(|d| magnitude(d, q).powi(2)).sum();
                1e-16 * (f * f + self.half_thickness_sq * g)
            }
            _ => VALUE_ROUNDING * magnitude(&self.f, q),
        }
    }

    /// Whether `∇f` vanishes at `p` up to the rounding of a root's place (a millionth of the
    /// sum of its terms' magnitudes): a singular point of the surface. Always false for a
    /// shell, whose wall is smooth wherever the surface is.
    pub fn is_singular(&self, p: DVec3) -> bool {
        if matches!(self.kind, SolidKind::Shell { .. }) {
            return false;
        }
        let (gradient, bound) = self.surface_gradient(p);
        gradient.length() <= SINGULAR_GRADIENT * bound
    }

    /// `∇f` at `p` and the length of the sums of its partials' terms' magnitudes.
    fn surface_gradient(&self, p: DVec3) -> (DVec3, f64) {
        let powers = Powers::new(p.to_array(), self.f.degree);
        let (gradient, bound) = self.joint_gradient.eval_with_bound_on(&powers);
        (
            DVec3::from_array(gradient),
            DVec3::from_array(bound).length(),
        )
    }

    /// Whether Newton's steps on `∇f = 0` from `p` reach, within `width` of it, a point where
    /// `∇f` vanishes ([`Field::is_singular`]) and `f` too (to [`SINGULAR_ROUNDING`] of its
    /// terms): a node or other isolated singular point of the surface near `p`. Always false
    /// for a shell.
    pub fn singular_point_near(&self, p: DVec3, width: f64) -> bool {
        if matches!(self.kind, SolidKind::Shell { .. }) {
            return false;
        }
        let gradient = |q: DVec3| self.surface_gradient(q).0;
        let h = 1e-6 * width;
        let mut q = p;
        for _ in 0..NODE_STEPS {
            let (g, bound) = self.surface_gradient(q);
            // The gradient may pass its test a few steps before `f` passes its own (10⁻⁶ of
            // the gradient's terms is not yet 10⁻¹² of f's beside a node away from the
            // origin, where those terms do not vanish): a point off the surface, where `∇f`
            // vanishes too, is told apart by stepping on until the steps run out.
            if g.length() <= SINGULAR_GRADIENT * bound
                && self.f.eval(q.to_array()).abs()
                    <= SINGULAR_ROUNDING * self.f.magnitude_bound(q.to_array())
            {
                return true;
            }
            let hessian = DMat3::from_cols(
                (gradient(q + DVec3::X * h) - gradient(q - DVec3::X * h)) / (2.0 * h),
                (gradient(q + DVec3::Y * h) - gradient(q - DVec3::Y * h)) / (2.0 * h),
                (gradient(q + DVec3::Z * h) - gradient(q - DVec3::Z * h)) / (2.0 * h),
            );
            let det = hessian.determinant();
            if !det.is_normal() {
                return false;
            }
            q -= hessian.inverse() * g;
            let moved = q.distance(p);
            if moved > width || moved.is_nan() {
                return false;
            }
        }
        false
    }

    /// `φ` at an object-space point (negative inside the solid, ignoring the ball).
    pub fn value(&self, p: DVec3) -> f64 {
        let q = p.to_array();
        let f = self.f.eval(q);
        match self.kind {
            SolidKind::Inside => f,
            SolidKind::Outside => -f,
            SolidKind::Shell { .. } => {
                let (square, gradient_part) = self.shell_parts(f, q);
                let phi = square - gradient_part;
                if phi >= 0.0 && f.abs() <= SINGULAR_ROUNDING * self.f.magnitude_bound(q) {
                    // A singular point of the surface (f zero to its rounding, and ∇f too,
                    // or φ would be negative): in the wall, as every point about it is, not
                    // outside as the rounding of a zero of φ would have it.
                    -f64::MIN_POSITIVE
                } else {
                    phi
                }
            }
        }
    }

    /// Whether a root of `φ` found at `p` (along a line, by the root finder) lies on the
    /// solid's boundary: always for the inside and outside; for a shell, where `φ(p)` is
    /// within [`WALL_ROOT_SHARE`] of `f² + (T/2)²·|∇f|²`, the size of its two parts. Beside a
    /// singular point or curve of the surface (in the wall's inside, where both parts vanish)
    /// `φ` is zero only to the rounding of a line's polynomial, and roots found there are not
    /// points of the wall.
    pub fn is_boundary_root(&self, p: DVec3) -> bool {
        if !matches!(self.kind, SolidKind::Shell { .. }) {
            return true;
        }
        let q = p.to_array();
        let (first, second) = self.shell_parts(self.f.eval(q), q);
        (first - second).abs() < WALL_ROOT_SHARE * (first + second)
    }

    /// A shell's `φ` at `q` as its two parts, `f²` and `(T/2)²·|∇f|²`, given `f` there.
    fn shell_parts(&self, f: f64, q: [f64; 3]) -> (f64, f64) {
        let g: f64 = self.gradient.iter().map(|d| d.eval(q).powi(2)).sum();
        (f * f, self.half_thickness_sq * g)
    }

    /// Whether an object-space point is in the solid: strictly inside the clip ball and
    /// `φ < 0` (a zero counts as outside, but for a shell a singular point of the surface is
    /// inside: see the module doc).
    pub fn inside(&self, p: DVec3) -> bool {
        p.length_squared() < self.radius * self.radius && self.value(p) < 0.0
    }

    /// The coefficients (ascending) of `φ(a + s·e)` in `s`, `degree() + 1` of them.
    pub fn along(&self, a: DVec3, e: DVec3) -> Vec<f64> {
        let (o, d) = (a.to_array(), e.to_array());
        let n = self.f.degree + 1;
        let f = self.f.compose(o, d);
        match self.kind {
            SolidKind::Inside => f[..n].to_vec(),
            SolidKind::Outside => f[..n].iter().map(|c| -c).collect(),
            SolidKind::Shell { .. } => {
                let mut out = multiply(&f[..n], &f[..n]);
                for g in &self.gradient {
                    let gs = g.compose(o, d);
                    let sq = multiply(&gs[..n], &gs[..n]);
                    for (k, c) in sq.iter().enumerate() {
                        out[k] -= self.half_thickness_sq * c;
                    }
                }
                out
            }
        }
    }

    /// The first point where the solid's boundary meets the segment from `a` (in the solid)
    /// to `b` (not in it), as the fraction `s` of the way (`END_GAP ≤ s ≤ 1 − END_GAP`) and
    /// whether it lies on `φ = 0` or on the clip sphere: the first root of `φ` along the
    /// segment by the project's root finder, or the segment's exit from the ball if that
    /// comes first (a root of `φ` if both lie in the end gap at `b`).
    pub fn crossing(&self, a: DVec3, b: DVec3) -> (f64, VertexKind) {
        let e = b - a;
        let r2 = self.radius * self.radius;
        let ball_exit = (b.length_squared() >= r2).then(|| {
            let (qa, qb, qc) = (e.length_squared(), 2.0 * a.dot(e), a.length_squared() - r2);
            let root = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
            // The positive root, in the form that avoids cancellation.
            if qb >= 0.0 {
                2.0 * qc / (-qb - root)
            } else {
                (-qb + root) / (2.0 * qa)
            }
        });
        // An exit in the end gap at `b` is searched past, so that a root of `φ` in the same
        // gap (an end on both the surface and the sphere) is found.
        let exit_in_end_gap = ball_exit.is_some_and(|x| x > 1.0 - END_GAP);
        let hi = match ball_exit {
            Some(x) if !exit_in_end_gap => x,
            _ => 1.0,
        };
        let surface = self.first_root(a, e, hi);
        let (s, kind) = match (surface, ball_exit) {
            (Some(s), Some(x)) if s < x => (s, VertexKind::Surface),
            // Both in the end gap: the vertex the gap holds off the end is not moved onto
            // the sphere, like its neighbours about the same end (which the surface crosses
            // there too), so that the triangles about that end do not fold.
            (Some(s), Some(_)) if exit_in_end_gap => (s, VertexKind::Surface),
            (Some(s), None) => (s, VertexKind::Surface),
            (_, Some(x)) => (x, VertexKind::Cap),
            // The labels say φ changes sign on the segment but the root finder found no
            // root (rounding at a root of high multiplicity): bisect the sign itself.
            (None, None) => (self.bisect(a, e), VertexKind::Surface),
        };
        (s.clamp(END_GAP, 1.0 - END_GAP), kind)
    }

    /// The vertex of a [`Field::crossing`] `(s, kind)` of the segment from `a` to `b`: the
    /// point a fraction `s` of the way, a cap vertex on the clip sphere (to rounding) even
    /// where `END_GAP` held it off an end that lies on the sphere itself.
    pub fn crossing_point(&self, a: DVec3, b: DVec3, (s, kind): (f64, VertexKind)) -> DVec3 {
        let x = a + s * (b - a);
        if kind == VertexKind::Cap {
            x * (self.radius / x.length())
        } else {
            x
        }
    }

    /// The first root of `φ(a + s·e)` in `(0, hi]`, by the project's root finder where the
    /// degree allows, else by bisection of the sign when the end is outside.
    fn first_root(&self, a: DVec3, e: DVec3, hi: f64) -> Option<f64> {
        if hi.is_nan() || hi <= 0.0 {
            return None;
        }
        let c = self.along(a, e);
        if c.len() <= MAX_DEGREE + 1 {
            if let Some(s) = self.solver.first_root(&c, 0.0, hi) {
                return Some(s);
            }
        }
        (self.value(a + hi * e) >= 0.0).then(|| self.bisect(a, e * hi) * hi)
    }

    /// A point of the segment `a + s·e`, `s ∈ (0, 1]`, where `φ` turns from negative to not
    /// negative, by bisection of the sign (`φ(a) < 0`).
    fn bisect(&self, a: DVec3, e: DVec3) -> f64 {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if self.value(a + mid * e) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// The distance from `p` to the nearest point of `φ = 0` on the line through `p` along
    /// `dir` (any length), within `reach` (object units), by the project's root finder
    /// (every real root in the window; where it finds none, a double root at a node that
    /// rounding hides: a root of its derivative where `φ` is zero to rounding); `None` when there is none within
    /// reach, or when `φ` has degree above 16 along lines.
    pub fn distance_along(&self, p: DVec3, dir: DVec3, reach: f64) -> Option<f64> {
        let len = dir.length();
        if len.is_nan() || len <= 0.0 || self.degree() > MAX_DEGREE {
            return None;
        }
        let c = self.along(p, dir * (reach / len));
        if c[0] == 0.0 {
            return Some(0.0);
        }
        // Every root (Sturm), and where rounding hides a multiple root from the sequence
        // (at a node), the first root on each side by the solver that placed the vertex.
        let mirrored: Vec<f64> = c
            .iter()
            .enumerate()
            .map(|(k, &x)| if k % 2 == 1 { -x } else { x })
            .collect();
        let e = dir * (reach / len);
        let found = sturm_roots(&c, -1.0 - 1e-12, 1.0)
            .into_iter()
            .chain(self.solver.first_root(&c, 0.0, 1.0))
            .chain(self.solver.first_root(&mirrored, 0.0, 1.0).map(|s| -s))
            .filter(|&s| self.is_boundary_root(p + s * e))
            .map(|s| s.abs() * reach)
            .reduce(f64::min);
        found.or_else(|| self.hidden_double_root(p, e, &c).map(|s| s * reach))
    }

    /// The nearest `|s| ≤ 1` where `φ(p + s·e)` (coefficients `c`) has a root that rounding
    /// hides from the root finder: a double root at a node of the surface, where `φ` touches
    /// 0 without changing sign and its computed values hover about 0 at the rounding of `f`.
    /// Such a root is a simple root of the line polynomial's derivative (found by Sturm
    /// sequences) at which `φ` is zero to its rounding ([`Field::at_rounding`]) and which is
    /// a point of the boundary ([`Field::is_boundary_root`]: for a shell, not the surface's
    /// own node, which is inside the wall).
    fn hidden_double_root(&self, p: DVec3, e: DVec3, c: &[f64]) -> Option<f64> {
        if c.len() < 3 {
            return None;
        }
        let derivative: Vec<f64> = c
            .iter()
            .enumerate()
            .skip(1)
            .map(|(k, &x)| k as f64 * x)
            .collect();
        sturm_roots(&derivative, -1.0 - 1e-12, 1.0)
            .into_iter()
            .filter(|&s| self.at_rounding(p + s * e) && self.is_boundary_root(p + s * e))
            .map(f64::abs)
            .reduce(f64::min)
    }

    /// The crease point for the mesh edge from a surface vertex to a cap vertex: the first
    /// point where `φ` turns from negative to zero along the circle in which the plane of the
    /// triangle `face = [p, q, r]` (a face of a grid tetrahedron) cuts the clip sphere,
    /// starting at `cap` (the cap vertex, on the edge `p r`) and turning into the face, by
    /// the project's root finder on `φ` along the circle (in the rational parameter
    /// `t = tan(θ/2)`, a polynomial of twice `φ`'s degree; past degree 16, bisection of the
    /// sign on sampled arcs). So the point is on the clip sphere (to rounding) and on
    /// `φ = 0` (to the root finder's accuracy). `None` when there is no such point within
    /// 172° of the circle, or it is not inside the face by at least [`END_GAP`] in each
    /// barycentric coordinate (the caller then keeps the mesh edge as it is).
    pub fn crease(&self, face: [DVec3; 3], cap: DVec3) -> Option<DVec3> {
        let [p, q, r] = face;
        let normal = (q - p).cross(r - p);
        let twice_area = normal.length();
        if twice_area.is_nan() || twice_area <= 0.0 {
            return None;
        }
        let n = normal / twice_area;
        let centre = n * n.dot(p);
        let rho_sq = self.radius * self.radius - centre.length_squared();
        if rho_sq.is_nan() || rho_sq <= 0.0 {
            return None;
        }
        let rho = rho_sq.sqrt();
        let out = cap - centre;
        let u = (out - n * n.dot(out)).try_normalize()?;
        let mut tangent = n.cross(u);
        // Into the face: toward q from the edge p r.
        let along = (r - p).normalize();
        let inward = (q - p) - along * along.dot(q - p);
        if tangent.dot(inward) < 0.0 {
            tangent = -tangent;
        }
        let at = |theta: f64| centre + rho * (theta.cos() * u + theta.sin() * tangent);
        const MAX_TURN: f64 = 3.0;
        let theta = match self.along_circle(centre, rho * u, rho * tangent) {
            Some(c) => {
                let t = self.solver.first_root(&c, 0.0, (0.5 * MAX_TURN).tan())?;
                2.0 * t.atan()
            }
            None => {
                // Bisection of the sign on the first sampled arc where it changes.
                const SAMPLES: usize = 256;
                let step = MAX_TURN / SAMPLES as f64;
                let k = (1..=SAMPLES).find(|&k| self.value(at(k as f64 * step)) >= 0.0)?;
                let (mut lo, mut hi) = ((k - 1) as f64 * step, k as f64 * step);
                for _ in 0..64 {
                    let mid = 0.5 * (lo + hi);
                    if self.value(at(mid)) < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                hi
            }
        };
        let x = at(theta);
        // Barycentric coordinates in the face's plane.
        let weight = |a: DVec3, b: DVec3| (b - x).cross(a - x).dot(n) / twice_area;
        let inside = [weight(r, q), weight(p, r), weight(q, p)];
        inside.iter().all(|&w| w >= END_GAP).then_some(x)
    }

    /// The crease beside the mesh edge from the surface vertex `surface` to the cap vertex
    /// `cap` where that edge is left without a crease point (a chamfer), by the line in which
    /// the tangent planes of the surface and of the clip sphere meet, both taken at the
    /// edge's midpoint (their linear approximations there, as `|φ|/|∇φ|` is for a distance):
    /// how far it lies from the edge, and how thin the solid's wedge is at `surface`. `None`
    /// where the two planes are parallel (the surface grazes the sphere) or `∇φ` vanishes.
    pub fn chamfer(&self, surface: DVec3, cap: DVec3) -> Option<Chamfer> {
        let m = 0.5 * (surface + cap);
        let (v, g) = self.value_and_gradient(m, 1e-7 * self.radius);
        let (g_len, m_len) = (g.length(), m.length());
        if !(g_len > 0.0 && m_len > 0.0 && v.is_finite()) {
            return None;
        }
        // The planes n_s·x = d_s (φ's linear part zero) and n_c·x = d_c (on the sphere),
        // with x measured from m, each normal pointing out of the solid; their line's
        // nearest point is a·n_s + b·n_c.
        let (n_s, d_s) = (g / g_len, -v / g_len);
        let (n_c, d_c) = (m / m_len, self.radius - m_len);
        let k = n_s.dot(n_c);
        let sin_sq = 1.0 - k * k;
        if sin_sq.is_nan() || sin_sq <= 1e-12 {
            return None;
        }
        let a = (d_s - k * d_c) / sin_sq;
        let b = (d_c - k * d_s) / sin_sq;
        let tip = m + a * n_s + b * n_c;
        let side = cap - surface;
        let along = ((tip - surface).dot(side) / side.length_squared()).clamp(0.0, 1.0);
        // The wedge's angle θ has cos θ = −k (normals out of the solid): below a right
        // angle, the line from `surface` along the surface's normal meets the sphere at
        // tan θ times its distance from the crease.
        let width = if k < 0.0 {
            tip.distance(surface) * sin_sq.sqrt() / -k
        } else {
            f64::INFINITY
        };
        Some(Chamfer {
            gap: tip.distance(surface + along * side),
            width,
        })
    }

    /// The coefficients (ascending in `t`) of `φ` along the circle
    /// `centre + a·(1 − t²)/(1 + t²) + b·2t/(1 + t²)`, multiplied by `(1 + t²)^D` with `D`
    /// the degree of `φ` (so a polynomial of degree `2D` with the signs of `φ`); `None` when
    /// that degree is above 16.
    fn along_circle(&self, centre: DVec3, a: DVec3, b: DVec3) -> Option<Vec<f64>> {
        if 2 * self.degree() > MAX_DEGREE {
            return None;
        }
        // N(t) = centre·(1 + t²) + a·(1 − t²) + b·2t, and W(t) = 1 + t².
        let conic = [centre + a, 2.0 * b, centre - a];
        let d = self.f.degree;
        let f = along_conic(&self.f, d, conic);
        Some(match self.kind {
            SolidKind::Inside => f,
            SolidKind::Outside => f.iter().map(|c| -c).collect(),
            SolidKind::Shell { .. } => {
                // φ·W^(2d) = F² − (T/2)²·W²·Σ Gᵢ², with F, Gᵢ homogenised to d and d − 1.
                let mut out = multiply(&f, &f);
                let w2 = [1.0, 0.0, 2.0, 0.0, 1.0];
                for g in &self.gradient {
                    let gs = along_conic(g, d.saturating_sub(1), conic);
                    let sq = multiply(&multiply(&gs, &gs), &w2);
                    for (k, c) in sq.iter().enumerate() {
                        out[k] -= self.half_thickness_sq * c;
                    }
                }
                out
            }
        })
    }

    /// An estimate of the distance from the object-space point `p` to `φ = 0` (object
    /// units): `|φ|/|∇φ|`, and where the Newton step that gives leaves more than a tenth of
    /// `|φ|` at its end (beside a node, where `φ` is locally a cone's quadratic and that
    /// first estimate is about half the distance), the next step's length added. 0 where
    /// `φ(p)` is 0; infinite where `∇φ` vanishes and `φ` does not. `h` as for
    /// [`Field::value_and_gradient`].
    pub fn distance_estimate(&self, p: DVec3, h: f64) -> f64 {
        // The Newton step from `p`: its length, its end and |φ(p)|.
        let step = |p: DVec3| {
            let (v, g) = self.value_and_gradient(p, h);
            let g2 = g.length_squared();
            if v == 0.0 {
                (0.0, p, 0.0)
            } else if g2 > 0.0 {
                (v.abs() / g2.sqrt(), p - g * (v / g2), v.abs())
            } else {
                (f64::INFINITY, p, v.abs())
            }
        };
        let (first, next, before) = step(p);
        if first == 0.0 || !first.is_finite() {
            return first;
        }
        let after = self.value(next).abs();
        if after.is_nan() || after > 0.1 * before {
            first + step(next).0
        } else {
            first
        }
    }

    /// `φ` and its gradient at `p` (object space): the gradient by the exact partial
    /// derivatives of `f` for the inside and outside (4 evaluations sharing one table of the
    /// coordinates' powers: the same bits as one by one), by central differences of step `h`
    /// for a shell ([`Field::gradient`]).
    pub fn value_and_gradient(&self, p: DVec3, h: f64) -> (f64, DVec3) {
        let exact = || {
            // The partials' degrees are below f's, so its powers serve them all.
            let powers = Powers::new(p.to_array(), self.f.degree);
            let (gradient, _) = self.joint_gradient.eval_with_bound_on(&powers);
            (
                self.f.eval_with_bound_on(&powers).0,
                DVec3::from_array(gradient),
            )
        };
        match self.kind {
            SolidKind::Inside => exact(),
            SolidKind::Outside => {
                let (f, g) = exact();
                (-f, -g)
            }
            SolidKind::Shell { .. } => (self.value(p), self.gradient(p, h)),
        }
    }

    /// The gradient of `φ` at `p` (object space), by central differences of step `h`.
    pub fn gradient(&self, p: DVec3, h: f64) -> DVec3 {
        let d = |e: DVec3| (self.value(p + e * h) - self.value(p - e * h)) / (2.0 * h);
        DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
    }
}

/// The coefficients (ascending in `t`, `2k + 1` of them) of `W(t)^k · P(N(t)/W(t))` for the
/// quadratic curve `N(t) = n[0] + n[1]·t + n[2]·t²` and `W(t) = 1 + t²`, with `k` at least
/// `P`'s degree: each term `c·x^a·y^b·z^e` becomes `c·N_x^a·N_y^b·N_z^e·W^(k−a−b−e)`.
fn along_conic(p: &Compiled, k: usize, n: [DVec3; 3]) -> Vec<f64> {
    let powers = |q: [f64; 3]| {
        let mut out = vec![vec![1.0]];
        for i in 1..=k {
            let next = multiply(&out[i - 1], &q);
            out.push(next);
        }
        out
    };
    let xs = powers([n[0].x, n[1].x, n[2].x]);
    let ys = powers([n[0].y, n[1].y, n[2].y]);
    let zs = powers([n[0].z, n[1].z, n[2].z]);
    let ws = powers([1.0, 0.0, 1.0]);
    let mut out = vec![0.0; 2 * k + 1];
    for term in &p.terms {
        let [a, b, e] = term.e.map(usize::from);
        let Some(rest) = k.checked_sub(a + b + e) else {
            continue;
        };
        let product = multiply(&multiply(&xs[a], &ys[b]), &multiply(&zs[e], &ws[rest]));
        for (o, c) in out.iter_mut().zip(&product) {
            *o += term.c * c;
        }
    }
    out
}

/// The product of two polynomials (ascending coefficients).
fn multiply(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::expand;

    fn sphere(kind: SolidKind, clip: f64) -> Field {
        Field::new(&expand("x^2 + y^2 + z^2 = 1").unwrap(), clip, kind)
    }

    /// The inside of `equation`'s surface clipped to radius 2.
    fn inside(equation: &str) -> Field {
        Field::new(&expand(equation).unwrap(), 2.0, SolidKind::Inside)
    }

    #[test]
    fn a_chamfer_s_gap_is_near_the_crease_s_distance_from_its_side() {
        // The outside of the plane z = 1/2 in the unit ball: an acute wedge whose crease is
        // the circle of radius √3/2 at z = 1/2. In the plane y = 0 a chamfer from the
        // surface vertex (0.6, 0, 0.5) to the cap vertex at 50° from the pole misses the
        // crease point (√3/2, 0, 1/2) by 0.1735.
        let f = Field::new(&expand("z = 0.5").unwrap(), 1.0, SolidKind::Outside);
        let surface = DVec3::new(0.6, 0.0, 0.5);
        let angle = 50f64.to_radians();
        let cap = DVec3::new(angle.sin(), 0.0, angle.cos());
        let crease = DVec3::new(0.75f64.sqrt(), 0.0, 0.5);
        let side = cap - surface;
        let along = (crease - surface).dot(side) / side.length_squared();
        let exact = crease.distance(surface + along * side);
        assert!((exact - 0.1735).abs() < 1e-4, "{exact}");
        let chamfer = f.chamfer(surface, cap).unwrap();
        assert!(
            chamfer.gap >= exact && chamfer.gap < 1.15 * exact,
            "{chamfer:?} for {exact}"
        );
        // The wedge's angle is 60° (the sphere's normal at the crease 60° from the pole).
        // Along the plane's normal the solid is √(1 − 0.6²) − 0.5 = 0.3 thick at the surface
        // vertex; by the planes at the midpoint (the sphere's normal there 50° from the pole)
        // it is 0.34.
        let thick = (1.0f64 - 0.36).sqrt() - 0.5;
        assert!(
            (chamfer.width - thick).abs() < 0.15 * thick,
            "{chamfer:?} for {thick}"
        );
        // A short chord of the crease (ends 2° apart on it) misses it by its sagitta,
        // (√3/2)·(1 − cos 1°) = 1.3·10⁻⁴.
        let on_crease = |degrees: f64| {
            let (s, c) = degrees.to_radians().sin_cos();
            DVec3::new(0.75f64.sqrt() * c, 0.75f64.sqrt() * s, 0.5)
        };
        let gap = f.chamfer(on_crease(0.0), on_crease(2.0)).unwrap().gap;
        assert!((1.2e-4..1.5e-4).contains(&gap), "{gap}");
        // Where the surface grazes the sphere there is no crease line to measure to.
        let touching = Field::new(&expand("z = 1").unwrap(), 1.0, SolidKind::Inside);
        assert_eq!(
            touching.chamfer(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, 1.0)),
            None
        );
        // The inside of the same plane: the wedge is obtuse (120°), never thin.
        let inside = Field::new(&expand("z = 0.5").unwrap(), 1.0, SolidKind::Inside);
        let below = DVec3::new(0.6, 0.0, 0.5);
        let cap = DVec3::new(0.95, 0.0, -(1.0f64 - 0.95 * 0.95).sqrt());
        assert_eq!(inside.chamfer(below, cap).unwrap().width, f64::INFINITY);
    }

    #[test]
    fn a_cap_vertex_held_off_an_end_on_the_sphere_goes_back_onto_it() {
        // The solid (the ball of radius 3) reaches past the clip sphere of radius 2; the
        // segment ends on the sphere, so the crossing is held END_GAP off that end.
        let f = inside("x^2 + y^2 + z^2 = 9");
        let (a, b) = (DVec3::new(0.0, 0.3, 0.0), DVec3::new(0.0, 1.2, 1.6));
        let crossing = f.crossing(a, b);
        assert_eq!(crossing, (1.0 - END_GAP, VertexKind::Cap));
        assert!((a + crossing.0 * (b - a)).length() < 2.0 - 1e-4);
        let p = f.crossing_point(a, b, crossing);
        assert!((p.length() - 2.0).abs() < 1e-15, "{p}");
        // A surface vertex stays where the crossing puts it.
        let surface = (0.5, VertexKind::Surface);
        assert_eq!(f.crossing_point(a, b, surface), a + 0.5 * (b - a));
    }

    #[test]
    fn the_distance_estimate_takes_a_second_step_beside_a_node() {
        // A cone with its node at the origin: from (0, 0, a) the nearest point is a/√2 away;
        // |φ|/|∇φ| says a/2 (its step leaves a quarter of φ), the second step makes it 3a/4.
        let cone = inside("x^2 + y^2 - z^2 = 0");
        let a = 0.1;
        let d = cone.distance_estimate(DVec3::new(0.0, 0.0, a), 1e-7);
        assert!((d - 0.75 * a).abs() < 1e-12, "{d}");
        // Beside a smooth surface the first step leaves little of φ, and is the estimate.
        let d = sphere(SolidKind::Inside, 2.0).distance_estimate(DVec3::new(0.0, 0.0, 1.01), 1e-7);
        assert!((d - 0.0201 / 2.02).abs() < 1e-12, "{d}");
        assert_eq!(cone.distance_estimate(DVec3::ZERO, 1e-7), 0.0);
        // Where ∇φ vanishes and φ does not (the centre of the sphere): infinite.
        let centre = sphere(SolidKind::Inside, 2.0).distance_estimate(DVec3::ZERO, 1e-7);
        assert_eq!(centre, f64::INFINITY);
    }

    #[test]
    fn the_exact_gradient_agrees_with_central_differences() {
        let poly = expand("x^3 + 2*y^2*z - z^2 = 1").unwrap();
        let p = DVec3::new(0.3, -0.7, 0.4);
        for kind in [
            SolidKind::Inside,
            SolidKind::Outside,
            SolidKind::Shell { thickness: 0.1 },
        ] {
            let field = Field::new(&poly, 2.0, kind);
            let (v, g) = field.value_and_gradient(p, 1e-6);
            assert_eq!(v, field.value(p));
            if kind == SolidKind::Inside {
                // The shared table of powers gives the bits of each partial on its own.
                let one_by_one = field.gradient.each_ref().map(|d| d.eval(p.to_array()));
                assert_eq!(g.to_array(), one_by_one, "{kind:?}");
            }
            assert!((g - field.gradient(p, 1e-6)).length() < 1e-7, "{kind:?}");
        }
    }

    #[test]
    fn a_crossing_on_the_surface_is_the_exact_root() {
        let f = sphere(SolidKind::Inside, 2.0);
        let (s, kind) = f.crossing(DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0) / 1.5);
        assert_eq!(kind, VertexKind::Surface);
        assert!((s * 2.0 / 1.5 - 1.0).abs() < 1e-14, "{s}");
    }

    #[test]
    fn an_end_on_both_the_surface_and_the_sphere_keeps_its_vertex_on_the_edge() {
        // The plane x = 0 clipped to the unit ball; the edge ends just outside the ball
        // (by 1e-9) on the plane, so the ball's exit and the plane's root are both in the
        // end gap. The vertex stays on the edge as a surface vertex: moved onto the sphere,
        // it would leave the edge, and the triangles about that end could fold.
        let f = Field::new(&expand("x").unwrap(), 1.0, SolidKind::Inside);
        let (a, b) = (
            DVec3::new(-0.1, 0.55, 0.75),
            DVec3::new(0.0, 0.6, 0.8) * (1.0 + 1e-9),
        );
        let crossing = f.crossing(a, b);
        assert_eq!(crossing, (1.0 - END_GAP, VertexKind::Surface));
        let x = f.crossing_point(a, b, crossing);
        assert!(
            (x - (a + (1.0 - END_GAP) * (b - a))).length() < 1e-15,
            "{x}"
        );
        // Where only the exit is in the end gap, the vertex is a cap vertex on the sphere.
        let off = DVec3::new(-0.01, 0.6, 0.8) * (1.0 + 1e-9);
        let crossing = f.crossing(a, off);
        assert_eq!(crossing.1, VertexKind::Cap);
        assert!((f.crossing_point(a, off, crossing).length() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_ball_exit_comes_first_when_the_surface_is_beyond_it() {
        let f = sphere(SolidKind::Inside, 0.5);
        let (s, kind) = f.crossing(DVec3::new(0.1, 0.0, 0.0), DVec3::new(0.9, 0.0, 0.0));
        assert_eq!(kind, VertexKind::Cap);
        assert!((0.1 + s * 0.8 - 0.5).abs() < 1e-14);
    }

    #[test]
    fn outside_and_shell_flip_and_thicken_the_sign() {
        let p = DVec3::new(0.5, 0.0, 0.0);
        assert!(sphere(SolidKind::Inside, 2.0).inside(p));
        assert!(!sphere(SolidKind::Outside, 2.0).inside(p));
        let shell = sphere(SolidKind::Shell { thickness: 0.2 }, 2.0);
        assert!(!shell.inside(p));
        assert!(shell.inside(DVec3::new(1.04, 0.0, 0.0)));
        assert!(shell.inside(DVec3::new(0.96, 0.0, 0.0)));
        assert!(!shell.inside(DVec3::new(1.2, 0.0, 0.0)));
        // Along a line, the shell's polynomial is the one evaluated pointwise.
        let (a, e) = (DVec3::new(0.3, -0.2, 0.1), DVec3::new(0.4, 0.5, -0.3));
        let c = shell.along(a, e);
        for s in [0.0, 0.3, 1.0] {
            let v: f64 = c.iter().rev().fold(0.0, |acc, k| acc * s + k);
            assert!((v - shell.value(a + s * e)).abs() < 1e-12);
        }
        // The expanded polynomial is the same φ.
        let terms = shell.expanded_terms();
        assert!(terms
            .iter()
            .all(|(e, _)| e.iter().sum::<usize>() <= shell.degree()));
        for p in [a, a + e, DVec3::new(1.01, 0.2, -0.1)] {
            let v: f64 = terms
                .iter()
                .map(|&([i, j, k], c)| {
                    c * p.x.powi(i as i32) * p.y.powi(j as i32) * p.z.powi(k as i32)
                })
                .sum();
            assert!((v - shell.value(p)).abs() < 1e-12, "{v} {}", shell.value(p));
        }
        // A singular point of the surface is in the wall (φ is negative all about it).
        let cone = Field::new(
            &expand("x*y*z").unwrap(),
            1.0,
            SolidKind::Shell { thickness: 0.1 },
        );
        assert!(cone.inside(DVec3::ZERO) && cone.inside(DVec3::splat(1e-3)));
        assert!(!inside("x*y*z").inside(DVec3::ZERO));
        // So is every point of a singular curve, where the expanded f and ∇f are rounding,
        // not exactly zero: the Bohemian dome's double line x = z, y = 0 (f = (x² − z²)²
        // on y = 0), at points of the kind a lattice has.
        let dome = Field::new(
            &expand(
                "y^4 - ((1 - x^2)^2 + (1 - z^2)^2 + 6*(1 - x^2)*(1 - z^2) \
                 + 2*(y^2 - (1 - x^2) - (1 - z^2))*((1 - x^2) + (1 - z^2)))",
            )
            .unwrap(),
            2.14,
            SolidKind::Shell { thickness: 0.0642 },
        );
        // (Within the clip ball: t·√2 < 2.14.)
        for k in 1..71 {
            let t = 2.0 * f64::from(k) * 0.0107;
            assert!(dome.inside(DVec3::new(t, 0.0, t)), "{t}");
            assert!(dome.inside(DVec3::new(-t, 0.0, t)), "{t}");
        }
        // Off the curve by more than the wall's half thickness: outside.
        assert!(!dome.inside(DVec3::new(1.5, 0.0, 1.3)));
    }

    #[test]
    fn a_zero_is_outside_and_crossings_keep_off_the_ends() {
        let f = sphere(SolidKind::Inside, 2.0);
        assert!(!f.inside(DVec3::X));
        let (s, _) = f.crossing(DVec3::new(0.5, 0.0, 0.0), DVec3::X);
        assert_eq!(s, 1.0 - END_GAP);
    }

    #[test]
    fn distances_along_a_line_find_the_nearest_root() {
        let f = sphere(SolidKind::Inside, 2.0);
        let d = f
            .distance_along(DVec3::new(0.9, 0.0, 0.0), DVec3::X, 0.5)
            .unwrap();
        assert!((d - 0.1).abs() < 1e-14);
        assert!(f.distance_along(DVec3::ZERO, DVec3::X, 0.5).is_none());
    }

    #[test]
    fn a_small_value_where_most_terms_vanish_keeps_its_sign() {
        // On y = z = 0 only the linear terms are left: f = 10⁻⁹ there is a million times its
        // rounding at the point, though below the rounding of a line's polynomial, whose
        // bound counts the quartic term at the largest coordinate.
        let poly = crate::shapes::implicit::expand("1000000*z^4 + 0.001*(x - 0.3) = 0").unwrap();
        let f = Field::new(&poly, 1.0, SolidKind::Inside);
        let p = DVec3::new(0.3 + 1e-6, 0.0, 0.0);
        assert!(f.value(p) > 0.0);
        assert!(f.at_rounding(p) && f.sign_beyond_rounding(p) == 1.0);
        assert_eq!(f.sign_beyond_rounding(DVec3::new(0.3, 0.0, 0.0)), 0.0);
    }

    #[test]
    fn a_node_that_rounding_hides_from_the_root_finder_is_still_found() {
        // (1, −1, −1) is one of Barth's nodes: along a line inside its cone the sextic
        // touches 0 there (a double root) and its computed values hover about 0, so the root
        // finder sees no root. A point 1e-4 from the node along (1, 1, 0), where a grid edge
        // ending at the node puts its vertex, is within √2·1e-4 of the surface.
        let p = crate::shapes::implicit::preset("barth_sextic", &[]).unwrap();
        let poly = expand(&p.equation).unwrap();
        let node = DVec3::new(1.0, -1.0, -1.0);
        let near = node - DVec3::new(1e-4, 1e-4, 0.0);
        for kind in [SolidKind::Inside, SolidKind::Outside] {
            let f = Field::new(&poly, p.bound, kind);
            assert!(f.at_rounding(node) && !f.at_rounding(near));
            let d = f
                .distance_along(near, DVec3::new(1.0, 1.0, 0.0), 0.05)
                .unwrap();
            assert!((d - 2f64.sqrt() * 1e-4).abs() < 1e-9, "{kind:?} {d}");
        }
        // A shell's φ touches 0 from below at each node too, but the node is inside the
        // wall (φ < 0 all about it), not a point of it: the wall is farther off.
        let shell = Field::new(&poly, p.bound, SolidKind::Shell { thickness: 0.1 });
        assert!(shell.at_rounding(node) && !shell.at_rounding(near));
        assert!(!shell.is_boundary_root(node) && shell.inside(near));
        let d = shell.distance_along(near, DVec3::new(1.0, 1.0, 0.0), 0.05);
        assert!(d.is_none_or(|d| d > 0.01), "{d:?}");
    }

    #[test]
    fn a_node_away_from_the_origin_is_found_from_every_side() {
        // A cone's apex at (5, 3, 4), bent by cubic terms so that Newton's steps on ∇f = 0
        // take several steps: there the gradient's terms do not vanish, and its test passes
        // a step or two before f is zero to its rounding (26 of these 200 starts were missed
        // when the first step whose gradient passed decided).
        let poly = crate::shapes::implicit::expand(
            "(x - 5)^2 + (y - 3)^2 - (z - 4)^2 + (x - 5)^3 + (y - 3)^2*(z - 4) = 0",
        )
        .unwrap();
        let f = Field::new(&poly, 9.0, SolidKind::Inside);
        let node = DVec3::new(5.0, 3.0, 4.0);
        for k in 0..200 {
            let t = f64::from(k) * 0.7;
            let d = DVec3::new(
                t.cos() * (1.3 * t).sin(),
                t.sin() * (1.3 * t).sin(),
                (1.3 * t).cos(),
            );
            let p = node + d * (0.01 + 0.0004 * f64::from(k));
            assert!(f.singular_point_near(p, 0.2), "{p}");
        }
        // A point 1.6 from the apex has none within 0.2.
        assert!(!f.singular_point_near(DVec3::new(6.0, 3.0, 5.0 + 2f64.sqrt().recip()), 0.2));
    }
}
