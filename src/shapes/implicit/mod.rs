//! Implicit polynomial surfaces typed as equations (`IMPLICIT "x^2 + y^2 + z^2 = 1" …`) or
//! named presets (`IMPLICIT torus 1 0.3 …`), placed like the heart by a position and basis.
//!
//! Pipeline: [`equation`] parses the text into a syntax tree with byte spans; [`poly`]
//! expands it once, exactly (rational coefficients), checking the language's rules; the
//! result is compiled to `f64` terms plus its three symbolic partial derivatives. Per ray,
//! the ray is re-parametrised over the chord it cuts from the clip sphere (`s ∈ [−1, 1]`,
//! origin at the chord's midpoint), the univariate polynomial in `s` is formed by nested
//! Horner composition (O(terms × degree), no allocation), its first root is found by the
//! scene's [`Solver`], and `s` is mapped back to the caller's `t`.
//!
//! The `heart` preset (and an equation written exactly as that preset writes it) is the
//! paper's heart: it builds and delegates to [`crate::shapes::Heart`] with the same frame and
//! solver, so it renders pixel-identical to `HEART`, including the heart's own accuracy work
//! at its equator curve. Any other way of typing the heart goes through the generic path.

pub mod coef;
pub mod equation;
pub mod poly;
pub mod presets;

use super::{Heart, Shape};
use crate::geometry::{Aabb, DVec3, Frame, Ray};
use crate::roots::Solver;
use poly::{Compiled, Poly, Uni};
pub use presets::{Preset, HEART_EQUATION};

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
    v.abs() <= MAX_ROOT_RESIDUAL * m
}

/// The expanded surface with its derivatives, compiled for evaluation.
#[derive(Debug, Clone)]
struct Surface {
    f: Compiled,
    grad: [Compiled; 3],
}

#[derive(Debug, Clone)]
enum Kind {
    Generic(Box<Surface>),
    Heart(Box<Heart>),
}

/// An implicit polynomial surface `p(x, y, z) = 0` in object space, placed by a [`Frame`],
/// clipped to the object-space sphere of radius `bound` about the origin.
#[derive(Debug, Clone)]
pub struct Implicit {
    frame: Frame,
    solver: Solver,
    bound: f64,
    kind: Kind,
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
    let expr = equation::parse(equation)?;
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
    Ok(poly)
}

impl Implicit {
    /// Parses and expands `equation` (see docs/scene-format.md) and places it with `frame`.
    /// `bound` is the object-space clip radius (`BOUND r`); `None` takes the preset's default
    /// when `equation` is exactly a preset's text (from [`preset_equation`]), else derives one
    /// (an error asking for `BOUND` when the surface may be unbounded).
    pub fn new(equation: &str, frame: Frame, bound: Option<f64>) -> Result<Self, EquationError> {
        let whole = equation::Span {
            start: 0,
            end: equation.len(),
        };
        if let Some(b) = bound {
            if !(b > 0.0 && b.is_finite()) {
                return Err(whole.error(format!(
                    "BOUND must be a finite number greater than 0, not {b}"
                )));
            }
        }
        if equation.trim() == HEART_EQUATION {
            return Ok(Self::heart(frame, bound.unwrap_or(2.0)));
        }
        let poly = expand(equation)?;
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
        let grad = [0, 1, 2].map(|v| Compiled::new(&poly.derivative(v)));
        Ok(Self {
            frame,
            solver: Solver::default(),
            bound,
            kind: Kind::Generic(Box::new(Surface { f, grad })),
        })
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

    fn heart(frame: Frame, bound: f64) -> Self {
        let heart = Heart::new(
            frame.position,
            frame.m.x_axis,
            frame.m.y_axis,
            frame.m.z_axis,
        )
        .expect("a valid frame makes a valid heart");
        Self {
            frame,
            solver: Solver::default(),
            bound,
            kind: Kind::Heart(Box::new(heart)),
        }
    }

    /// The same surface, intersected with the given root-isolation strategy.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        self.solver = solver;
        if let Kind::Heart(h) = self.kind {
            self.kind = Kind::Heart(Box::new(h.with_solver(solver)));
        }
        self
    }

    /// The object-space clip radius.
    pub fn bound(&self) -> f64 {
        self.bound
    }

    /// True when this is the `heart` preset, delegated to [`Heart`].
    pub fn is_heart(&self) -> bool {
        matches!(self.kind, Kind::Heart(_))
    }

    /// Total degree of the polynomial.
    pub fn degree(&self) -> usize {
        match &self.kind {
            Kind::Generic(s) => s.f.degree,
            Kind::Heart(_) => 6,
        }
    }

    /// The polynomial's value at an object-space point (negative inside, positive outside).
    pub fn value(&self, p: DVec3) -> f64 {
        match &self.kind {
            Kind::Generic(s) => s.f.eval(p.to_array()),
            Kind::Heart(_) => super::heart::heart_fn(p),
        }
    }

    /// The symbolic gradient at an object-space point (may be zero at singular points).
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        match &self.kind {
            Kind::Generic(s) => {
                let q = p.to_array();
                DVec3::new(s.grad[0].eval(q), s.grad[1].eval(q), s.grad[2].eval(q))
            }
            Kind::Heart(_) => {
                let a = 2.0 * p.x * p.x + p.y * p.y + p.z * p.z - 1.0;
                let (a2, z2, z3) = (a * a, p.z * p.z, p.z * p.z * p.z);
                DVec3::new(
                    12.0 * p.x * a2 - 0.2 * p.x * z3,
                    6.0 * p.y * a2 - 2.0 * p.y * z3,
                    6.0 * p.z * a2 - 3.0 * z2 * (0.1 * p.x * p.x + p.y * p.y),
                )
            }
        }
    }

    /// The chord of the world ray through the clip sphere: `(t_mid, t_half, object-space
    /// midpoint, object-space half-chord vector)`, or `None` if the ray's line misses it.
    fn chord(&self, ray: &Ray) -> Option<(f64, f64, DVec3, DVec3)> {
        let r = self.frame.ray_to_object(ray);
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

    /// The per-ray polynomial over the clip chord, or `None` when the ray's line misses the
    /// clip sphere. For the `heart` preset this is the generic composition of the heart's
    /// expanded equation (the shape itself intersects through [`Heart`]).
    pub fn ray_polynomial(&self, ray: &Ray) -> Option<RayPolynomial> {
        let (t_mid, t_half, mid, e) = self.chord(ray)?;
        let coeffs: Vec<f64> = match &self.kind {
            Kind::Generic(s) => s.f.compose(mid.to_array(), e.to_array())[..=s.f.degree].to_vec(),
            Kind::Heart(_) => super::heart::sextic_coefficients(mid, e).to_vec(),
        };
        Some(RayPolynomial {
            coeffs,
            t_mid,
            t_half,
        })
    }

    fn intersect_generic(&self, s: &Surface, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let (t_mid, t_half, mid, e) = self.chord(ray)?;
        let guard = if t_min >= 0.0 {
            t_min.max(SELF_HIT_GUARD * t_half)
        } else {
            t_min
        };
        let lo_t = guard.max(t_mid - t_half);
        let hi_t = t_max.min(t_mid + t_half);
        if lo_t.is_nan() || hi_t.is_nan() || lo_t >= hi_t {
            return None;
        }
        let n = s.f.degree;
        let mut c: Uni = s.f.compose(mid.to_array(), e.to_array());
        // Normalise (the solver sees coefficients of order 1) and drop leading terms too
        // small to matter anywhere on |s| ≤ 1.
        let big = c[..=n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !(big > 0.0 && big.is_finite()) {
            return None;
        }
        let mut deg = n;
        while deg > 0 && c[deg].abs() <= 1e-15 * big {
            deg -= 1;
        }
        // A power of two: exact, so the solver sees the composed coefficients unrounded.
        let inv = 2f64.powi(-(big.log2().floor() as i32));
        for v in &mut c[..=deg] {
            *v *= inv;
        }
        let mut s_lo = (lo_t - t_mid) / t_half;
        let s_hi = ((hi_t - t_mid) / t_half).min(1.0);
        for _ in 0..8 {
            let root = self.solver.first_root(&c[..=deg], s_lo, s_hi)?;
            let t = t_mid + root * t_half;
            if t > guard && t < t_max && is_root(&c[..=deg], root) {
                return Some(t);
            }
            if root <= s_lo {
                return None;
            }
            s_lo = root;
        }
        None
    }
}

impl Shape for Implicit {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        match &self.kind {
            Kind::Generic(s) => self.intersect_generic(s, ray, t_min, t_max),
            Kind::Heart(h) => {
                if self.bound >= presets::HEART_RADIUS {
                    h.intersect(ray, t_min, t_max)
                } else {
                    let (t_mid, t_half, _, _) = self.chord(ray)?;
                    let lo = t_min.max(t_mid - t_half);
                    let hi = t_max.min(t_mid + t_half);
                    if lo < hi {
                        h.intersect(ray, lo, hi)
                    } else {
                        None
                    }
                }
            }
        }
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        let q = self.frame.point_to_object(p);
        if let Kind::Heart(h) = &self.kind {
            return h.normal(p);
        }
        let g = self.gradient(q);
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
        let w = self.frame.normal_to_world(n);
        if w.is_finite() {
            w
        } else {
            DVec3::Z
        }
    }

    fn bounds(&self) -> Aabb {
        // The clip sphere's image is an ellipsoid: its half-extent along world axis a is
        // r·|row a of M|.
        let m = self.frame.m;
        let rows = m.transpose();
        let half = DVec3::new(
            rows.x_axis.length(),
            rows.y_axis.length(),
            rows.z_axis.length(),
        ) * self.bound;
        let sphere = Aabb::new(self.frame.position - half, self.frame.position + half).padded(1e-9);
        match &self.kind {
            Kind::Heart(h) => {
                let hb = h.bounds();
                Aabb::new(hb.min.max(sphere.min), hb.max.min(sphere.max))
            }
            Kind::Generic(_) => sphere,
        }
    }
}
