//! Root polishing on the well-conditioned factor `g = A − ∛B·Z` along a ray.
//!
//! The solver's root of the sextic `f = g·Q` is accurate to the last bits where the root is
//! simple, but only to about `∛ε ≈ 1e-5` on the equator curve (a triple root of `f`) and
//! beside the singular points (where `f`'s terms are far below its rounding). `g` has a simple
//! root there. Newton on `g` finishes a good root in one evaluation; when Newton misbehaves
//! (the cusp of `∛B` beside the Z axis, a poor start), a bracket is found by searching outward
//! for the nearest sign change of `g` and the root finished by Newton safeguarded by bisection.

use super::surface::factor_g_with_slope;
use crate::geometry::DVec3;

/// The root of `g(o + s·d)` nearest to `s0` (the solver's root of `f`), to rounding level; no
/// farther than `window` from `s0`, else the best point found (at worst `s0` unchanged).
#[inline]
pub(super) fn polish(o: DVec3, d: DVec3, s0: f64, window: f64) -> f64 {
    let at = |s: f64| factor_g_with_slope(o + s * d, d);
    // A step below a few ulps of the point's coordinates is rounding noise.
    let tol = 2.0 * f64::EPSILON * (1.0 + o.abs().max_element()) / d.abs().max_element();

    let (mut s, (mut g, mut slope)) = (s0, at(s0));
    if g == 0.0 {
        return s0;
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
            return next;
        }
        if (next - s0).abs() > window {
            break;
        }
        let (gn, sn) = at(next);
        if gn == 0.0 {
            return next;
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
    if bracket.is_none() {
        // Newton stalled without crossing the root. Where g is already down to its rounding
        // (a tangent ray's double root, where g' ≈ 0 too), s is as good as it gets.
        let floor = 8.0 * f64::EPSILON * (1.0 + (o + s * d).length_squared());
        if g.abs() <= floor {
            return s;
        }
    }
    let Some((mut a, mut ga, mut b, mut gb)) =
        bracket.or_else(|| search(&at, s, g, s0, window, tol))
    else {
        return s;
    };
    // Newton inside the bracket from its better end, bisecting whenever Newton would leave
    // the bracket or is not halving the step (a safeguarded Newton, as `rtsafe`).
    (s, g) = if ga.abs() <= gb.abs() {
        (a, ga)
    } else {
        (b, gb)
    };
    slope = at(s).1;
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
        (g, slope) = at(next);
        s = next;
        if g == 0.0 {
            return s;
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
    if ga.abs() <= gb.abs() {
        a
    } else {
        b
    }
}

/// The nearest sign change of `g` around `s` (where `g(s) = g`), searched outward by steps
/// growing fourfold, within `window` of `s0`: `(a, g(a), b, g(b))` with `a < b`.
#[inline(never)]
fn search(
    at: &impl Fn(f64) -> (f64, f64),
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
            let gx = at(x).0;
            if gx == 0.0 || (gx < 0.0) != (g < 0.0) {
                return Some(if x < s { (x, gx, s, g) } else { (s, g, x, gx) });
            }
        }
        h *= 4.0;
    }
    None
}
