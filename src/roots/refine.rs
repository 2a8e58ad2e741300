//! Refinement of a bracketed root: the safeguarded Newton/Schröder iteration every strategy
//! uses on a sign-change bracket, and its Halley variant for a bracket known to hold exactly
//! one simple root (the Bernstein fast path).

use super::trace::Observer;

/// Steps allowed to the refinement (bisection of a `f64` range needs at most about 2100).
const MAX_ITER: usize = 2200;

/// `(p(x), p'(x), p''(x)/2, A(|x|))` for ascending `c`.
#[inline(always)]
fn eval3(c: &[f64], x: f64) -> (f64, f64, f64, f64) {
    let ax = x.abs();
    let (mut v, mut d, mut h, mut s) = (0.0, 0.0, 0.0, 0.0);
    for &a in c.iter().rev() {
        h = h * x + d;
        d = d * x + v;
        v = v * x + a;
        s = s * ax + a.abs();
    }
    (v, d, h, s)
}

/// The root of `c` in `[a, b]`, where `fa = c(a)` and `fb = c(b)` have opposite signs (neither
/// zero): safeguarded Newton/Schröder steps inside the shrinking sign-change bracket, starting
/// from false position, a bisection whenever a step leaves it or makes slow progress. To a few
/// ulps of the root. Schröder's step (Newton on p/p') stays quadratic towards a multiple root
/// or a cluster of roots, which is what the heart's f = A³ − B·Z³ looks like from afar.
/// Inlined, so a fixed-size caller gets its loops unrolled.
#[inline(always)]
pub(crate) fn refine(c: &[f64], a: f64, b: f64, fa: f64, fb: f64, obs: &mut impl Observer) -> f64 {
    let start = a - fa * ((b - a) / (fb - fa));
    refine_with::<false>(c, a, b, fa, start, obs)
}

/// [`refine`] for a bracket known to hold exactly one root, a simple one (the Bernstein fast
/// path's certain single sign variation), from the caller's starting point `start`: Halley's
/// step, cubically convergent at a simple root, where Schröder's is only quadratic.
#[inline(always)]
pub(crate) fn refine_simple(
    c: &[f64],
    a: f64,
    b: f64,
    fa: f64,
    start: f64,
    obs: &mut impl Observer,
) -> f64 {
    refine_with::<true>(c, a, b, fa, start, obs)
}

/// The iteration behind [`refine`] (`HALLEY = false`) and [`refine_simple`].
#[inline(always)]
fn refine_with<const HALLEY: bool>(
    c: &[f64],
    mut a: f64,
    mut b: f64,
    fa: f64,
    start: f64,
    obs: &mut impl Observer,
) -> f64 {
    let neg_a = fa < 0.0;
    let mut x = start;
    if !(x > a && x < b) {
        x = 0.5 * (a + b);
    }
    let (mut step, mut step_before) = (b - a, b - a);
    for _ in 0..MAX_ITER {
        obs.refine_step();
        let (v, d, h, size) = eval3(c, x);
        if v == 0.0 {
            return x;
        }
        if v.abs() <= 4.0 * f64::EPSILON * size {
            // `p(x)` is rounding noise: one last Newton step is as close as `p` allows.
            let last = x - v / d;
            return if last >= a && last <= b { last } else { x };
        }
        if (v < 0.0) == neg_a {
            a = x;
        } else {
            b = x;
        }
        // Halley: x − p·p' / (p'² − p·p''/2); Schröder: x − p·p' / (p'² − p·p'').
        let den = if HALLEY {
            d * d - v * h
        } else {
            d * d - 2.0 * v * h
        };
        let mut next = if den > 0.0 {
            x - v * d / den
        } else {
            x - v / d
        };
        if (next - x).abs() > 0.5 * step_before || !(next > a && next < b) {
            next = 0.5 * (a + b);
            if next <= a || next >= b {
                return x;
            }
        }
        step_before = step;
        step = (next - x).abs();
        if step <= 2.0 * f64::EPSILON * next.abs() {
            return next;
        }
        x = next;
    }
    x
}
