//! Root polishing on the well-conditioned factor `g = A − ∛B·Z` along a ray.
//!
//! The solver's root of the sextic `f = g·Q` is accurate to the last bits where the root is
//! simple, but only to about `∛ε ≈ 1e-5` on the equator curve (a triple root of `f`) and
//! beside the singular points (where `f`'s terms are far below its rounding); there a solver
//! may also merge two nearby roots into one or report a near-tangency as a root. `g` has
//! simple roots there. Newton on `g` finishes a good root in one evaluation; when Newton
//! misbehaves (the cusp of `∛B` beside the Z axis, a poor start), a bracket is found by
//! searching outward for the nearest sign change of `g`, and the root is finished by Newton
//! safeguarded by bisection.

use super::surface::factor_g_with_slope;
use crate::geometry::DVec3;

/// A polished root of `g` along the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Polished {
    /// The root, in the ray's parameter.
    pub s: f64,
    /// Whether `g` crosses from negative (inside) to positive (outside) there; `None` at a
    /// touching (double) root, where `g` is at its rounding level without crossing.
    pub rising: Option<bool>,
}

/// `g(o + s·d)` and its slope in `s`.
#[inline]
fn g_at(o: DVec3, d: DVec3, s: f64) -> (f64, f64) {
    factor_g_with_slope(o + s * d, d)
}

/// Steps below this (in `s`) are rounding noise: a few ulps of the point's coordinates.
#[inline]
fn step_tolerance(o: DVec3, d: DVec3) -> f64 {
    2.0 * f64::EPSILON * (1.0 + o.abs().max_element()) / d.abs().max_element()
}

/// The root of `g(o + s·d)` nearest to `s0` (the solver's root of `f`), to rounding level and
/// no farther than `window` from `s0`; `None` when there is none there and `g(s0)` is above
/// its rounding level (the solver's root is not on the surface: a near-tangency, or noise).
#[inline]
pub(super) fn polish(o: DVec3, d: DVec3, s0: f64, window: f64) -> Option<Polished> {
    let tol = step_tolerance(o, d);
    let (mut s, (mut g, mut slope)) = (s0, g_at(o, d, s0));
    if g == 0.0 {
        return Some(Polished {
            s,
            rising: crossing(slope),
        });
    }
    // Plain Newton while it converges the way it does at a simple root.
    let mut bracket = None;
    for _ in 0..4 {
        let step = g / slope;
        if !step.is_finite() {
            break;
        }
        let next = s - step;
        if step.abs() <= tol {
            return Some(Polished {
                s: next,
                rising: crossing(slope),
            });
        }
        if (next - s0).abs() > window {
            break;
        }
        let (gn, sn) = g_at(o, d, next);
        if gn == 0.0 {
            return Some(Polished {
                s: next,
                rising: crossing(sn),
            });
        }
        if (gn < 0.0) != (g < 0.0) {
            bracket = Some(if s < next {
                (s, g, next, gn)
            } else {
                (next, gn, s, g)
            });
            break;
        }
        if gn.abs() > 0.5 * g.abs() {
            break; // not converging like Newton: bracket instead
        }
        (s, g, slope) = (next, gn, sn);
    }
    let bracket = match bracket {
        Some(b) => b,
        None => {
            // Where g is already down to its rounding (a tangent ray's double root, where g'
            // vanishes too), s is as good as it gets.
            let floor = 8.0 * f64::EPSILON * (1.0 + (o + s * d).length_squared());
            if g.abs() <= floor {
                return Some(Polished { s, rising: None });
            }
            search(o, d, s, g, s0, window, tol)?
        }
    };
    Some(solve_bracket(o, d, bracket, tol))
}

/// `Some(true)` for a rising `g`, `Some(false)` for a falling one, `None` when flat or NaN.
#[inline]
fn crossing(slope: f64) -> Option<bool> {
    if slope > 0.0 {
        Some(true)
    } else if slope < 0.0 {
        Some(false)
    } else {
        None
    }
}

/// The root of `g` in the bracket `(a, g(a), b, g(b))` (`a < b`, opposite signs): Newton from
/// the better end, bisecting whenever Newton would leave the bracket or is not halving the
/// step (a safeguarded Newton, as `rtsafe`).
fn solve_bracket(o: DVec3, d: DVec3, bracket: (f64, f64, f64, f64), tol: f64) -> Polished {
    let (mut a, mut ga, mut b, mut gb) = bracket;
    let rising = Some(gb > ga);
    let (mut s, mut g) = if ga.abs() <= gb.abs() {
        (a, ga)
    } else {
        (b, gb)
    };
    let mut slope = g_at(o, d, s).1;
    let mut dx_old = b - a;
    let mut dx = dx_old;
    for _ in 0..128 {
        let newton = s - g / slope;
        let use_newton = newton > a && newton < b && (2.0 * g).abs() <= (dx_old * slope).abs();
        dx_old = dx;
        let next = if use_newton {
            dx = s - newton;
            newton
        } else {
            dx = 0.5 * (b - a);
            a + dx
        };
        if next <= a || next >= b {
            break; // the bracket is down to adjacent floats
        }
        (g, slope) = g_at(o, d, next);
        s = next;
        if g == 0.0 {
            return Polished { s, rising };
        }
        if (g < 0.0) == (ga < 0.0) {
            (a, ga) = (s, g);
        } else {
            (b, gb) = (s, g);
        }
        if dx.abs() <= tol {
            break;
        }
    }
    let s = if ga.abs() <= gb.abs() { a } else { b };
    Polished { s, rising }
}

/// The nearest sign change of `g` around `s` (where `g(s) = g`), searched outward by steps
/// growing fourfold, within `window` of `s0`: `(a, g(a), b, g(b))` with `a < b`.
#[inline(never)]
fn search(
    o: DVec3,
    d: DVec3,
    s: f64,
    g: f64,
    s0: f64,
    window: f64,
    tol: f64,
) -> Option<(f64, f64, f64, f64)> {
    let mut h = (16.0 * tol).max(1e-13);
    while h <= 2.0 * window {
        for x in [s - h, s + h] {
            if (x - s0).abs() > window {
                continue;
            }
            let gx = g_at(o, d, x).0;
            if gx == 0.0 || (gx < 0.0) != (g < 0.0) {
                return Some(if x < s { (x, gx, s, g) } else { (s, g, x, gx) });
            }
        }
        h *= 4.0;
    }
    None
}

/// The crossing of `g` closest before `s` (a root of `g` where it leaves `start_sign`), for
/// when the solver reported a root whose crossing direction shows that an earlier one was
/// merged into it: walks back from `s` by doubling steps to the first point with `g` of
/// `start_sign`, not before `lo`, and solves that bracket.
#[inline(never)]
pub(super) fn earlier_crossing(
    o: DVec3,
    d: DVec3,
    lo: f64,
    s: f64,
    start_outside: bool,
) -> Option<Polished> {
    let tol = step_tolerance(o, d);
    let mut inner = s;
    let mut h = (16.0 * tol).max(1e-12);
    loop {
        let x = (s - h).max(lo);
        let gx = g_at(o, d, x).0;
        if gx != 0.0 && (gx > 0.0) == start_outside {
            if inner == s {
                return None; // g has the start's sign right before s: nothing was merged
            }
            let gi = g_at(o, d, inner).0;
            return Some(solve_bracket(o, d, (x, gx, inner, gi), tol));
        }
        if x <= lo {
            return None;
        }
        inner = x;
        h *= 2.0;
    }
}
