//! Root polishing on the well-conditioned factor `g = A − ∛B·Z` along a ray.
//!
//! The solver's root of the sextic `f = g·Q` is accurate to the last bits where the root is
//! simple, but only to about `∛ε ≈ 1e-5` on the equator curve (a triple root of `f`) and
//! beside the singular points (where `f`'s terms are far below its rounding); there a solver
//! may also merge two nearby roots into one or report a near-tangency as a root. `g` has
//! simple roots there. Where `A` is resolved (away from the equator curve) `f = g·Q` with
//! `Q = 3A²` on the surface, so Newton on `f` places the root as well and needs no cube root:
//! one or two steps of it finish a good root. Elsewhere Newton on `g` finishes a good root in
//! one evaluation; when Newton
//! misbehaves (the cusp of `∛B` beside the Z axis, a poor start), a bracket is found by
//! searching outward for the nearest sign change of `g`, and the root is finished by Newton
//! safeguarded by bisection.

use super::surface::{factor_g_with_slope, resolved_f_with_slope};
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
    match newton_on_f(o, d, s0, tol) {
        Some(done) => Some(done),
        None => polish_on_g(o, d, s0, window, tol),
    }
}

/// [`polish`] by `g` alone: Newton on `g` while it converges as at a simple root, else a
/// bracket searched outward from `s0` and solved.
fn polish_on_g(o: DVec3, d: DVec3, s0: f64, window: f64, tol: f64) -> Option<Polished> {
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

/// Steps of the solver's root beyond which Newton on `f` is not tried a second time: far
/// above the error of a simple root (~1e-13 at worst, the exit of a ray from inside), far
/// below the ~1e-5 of the equator's triple root.
const F_STEP_LIMIT: f64 = 1e-9;

/// The root near `s0` by Newton on `f` itself (no cube root), where
/// [`resolved_f_with_slope`] says it places the root as well as Newton on `g` would: at most
/// two steps, the second only after a first below [`F_STEP_LIMIT`]; `None` (polish on `g`)
/// wherever that does not hold or the steps do not fall below `tol`.
#[inline]
fn newton_on_f(o: DVec3, d: DVec3, s0: f64, tol: f64) -> Option<Polished> {
    let mut s = s0;
    for _ in 0..2 {
        let (f, slope) = resolved_f_with_slope(o + s * d, d)?;
        let step = f / slope;
        if step.abs() <= tol {
            return Some(Polished {
                s: s - step,
                rising: crossing(slope),
            });
        }
        if step.abs() > F_STEP_LIMIT {
            return None;
        }
        s -= step;
    }
    None
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays from outside through random points near the heart's centre, and the roots of `g`
    /// along them (bisected to adjacent floats), with the ray's chord as `o + s·d`.
    fn crossings(seed: u64, count: usize) -> Vec<(DVec3, DVec3, f64)> {
        let mut uniform = crate::testing::uniform_stream(seed);
        let mut out = Vec::new();
        while out.len() < count {
            let mut v = || 2.0 * uniform() - 1.0;
            let from = DVec3::new(v(), v(), v()).normalize() * 3.0;
            let to = DVec3::new(0.5 * v(), 0.8 * v(), 0.9 * v());
            let (o, d) = (from, (to - from) * 2.0);
            // Sign changes of g on a fine grid, each bisected.
            let mut prev = (0.0, factor_g(o));
            for k in 1..=4000 {
                let s = f64::from(k) / 4000.0;
                let g = factor_g(o + s * d);
                if (g > 0.0) != (prev.1 > 0.0) {
                    let (mut a, mut b) = (prev.0, s);
                    while b - a > 2.0 * f64::EPSILON * b {
                        let m = 0.5 * (a + b);
                        if (factor_g(o + m * d) > 0.0) == (prev.1 > 0.0) {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    out.push((o, d, a));
                }
                prev = (s, g);
            }
        }
        out
    }

    use super::super::surface::factor_g;

    #[test]
    fn newton_on_f_places_roots_where_polish_on_g_does_and_declines_at_the_equator() {
        let (mut taken, mut declined) = (0, 0);
        for (o, d, root) in crossings(0x9e37_79b9_7f4a_7c15, 3000) {
            let tol = step_tolerance(o, d);
            // A start far off (as at the equator's triple root, ~1e-5) is never taken.
            let far = root + 1e-6;
            assert!(
                newton_on_f(o, d, far, tol).is_none(),
                "took {far} at {}",
                o + root * d
            );
            // Starts as the solver gives them: good to the last bits, or to ~1e-13 (the exit
            // of a ray from inside).
            for start in [root, root + 3e-14, root - 1e-13] {
                let Some(by_f) = newton_on_f(o, d, start, tol) else {
                    declined += 1;
                    continue;
                };
                taken += 1;
                let by_g = polish_on_g(o, d, start, 1e-2, tol).expect("a root of g");
                assert!(
                    (by_f.s - by_g.s).abs() <= 4.0 * tol,
                    "{}: f {} g {} ({} tol)",
                    o + root * d,
                    by_f.s,
                    by_g.s,
                    (by_f.s - by_g.s).abs() / tol
                );
                // The same crossing direction, where g's noise lets it tell one.
                assert!(
                    by_g.rising.is_none() || by_f.rising == by_g.rising,
                    "{}: {:?} against {:?}",
                    o + root * d,
                    by_f.rising,
                    by_g.rising
                );
                assert!(by_f.rising.is_some());
            }
        }
        // Nearly every good start away from the equator curve is taken (8 982 of 9 000 when
        // written).
        assert!(taken > 99 * declined, "{taken} taken, {declined} declined");
        // On the equator curve (a triple root of f: A = 0) never; beside it, on the surface
        // at heights from 1e-17 up, only where it agrees with g (A there is about ∛B·Z, at
        // or far below its own rounding up to Z ≈ 1e-14).
        let mut uniform = crate::testing::uniform_stream(0x2545_f491_4f6c_dd1d);
        let (mut near_taken, mut near_declined) = (0, 0);
        for k in 0..2000 {
            let phi = std::f64::consts::TAU * uniform();
            let (cx, cy) = (phi.cos() * std::f64::consts::FRAC_1_SQRT_2, phi.sin());
            let z = if k % 4 == 0 {
                0.0
            } else {
                1e-17 * 10f64.powi(k % 13) * if k % 2 == 0 { 1.0 } else { -1.0 }
            };
            let mut r = 1.0f64;
            for _ in 0..4 {
                let b = 0.1 * (r * cx).powi(2) + (r * cy).powi(2);
                r = ((1.0 + b.cbrt() * z - z * z) / (2.0 * cx * cx + cy * cy)).sqrt();
            }
            let p = DVec3::new(r * cx, r * cy, z);
            // A ray through p from outside, entering at s = 1/2.
            let d = DVec3::new(-cx, -cy, 0.3 * (uniform() - 0.5)) * 2.0;
            let o = p - 0.5 * d;
            let tol = step_tolerance(o, d);
            let Some(by_f) = newton_on_f(o, d, 0.5, tol) else {
                near_declined += 1;
                continue;
            };
            near_taken += 1;
            assert!(z != 0.0, "took the equator point {p}");
            let by_g = polish_on_g(o, d, 0.5, 1e-2, tol).expect("a root of g");
            assert!(
                (by_f.s - by_g.s).abs() <= 4.0 * tol,
                "{p}: f {} g {}",
                by_f.s,
                by_g.s
            );
            assert!(by_g.rising.is_none() || by_f.rising == by_g.rising, "{p}");
        }
        // The equator curve's points (a quarter) and those within ~1e-14 of it are declined;
        // farther ones are taken (807 taken, 1 193 declined when written).
        assert!(
            near_taken > 500 && near_declined > 500,
            "{near_taken} taken, {near_declined} declined"
        );
    }
}
