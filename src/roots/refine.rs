//! Refinement of a bracketed root: the safeguarded Newton/Schröder iteration every strategy
//! uses on a sign-change bracket, and its Halley variant for a bracket known to hold exactly
//! one simple root (the Bernstein fast path).

use super::trace::Observer;

/// Steps allowed to the refinement (bisection of a `f64` range needs at most about 2100).
const MAX_ITER: usize = 2200;

/// `(p(x), p'(x), p''(x)/2)` for ascending `c`.
#[inline(always)]
fn eval3(c: &[f64], x: f64) -> (f64, f64, f64) {
    let (mut v, mut d, mut h) = (0.0, 0.0, 0.0);
    for &a in c.iter().rev() {
        h = h * x + d;
        d = d * x + v;
        v = v * x + a;
    }
    (v, d, h)
}

/// `Σ |cⱼ|·xʲ` for `x ≥ 0` by Horner's rule: the size of `c`'s terms at `±x`. Computed in
/// floating point it still grows with `x` (every rounding is monotone).
#[inline(always)]
pub(crate) fn size_at(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |s, a| s * x + a.abs())
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
    refine_with::<false>(c, a, b, fa, start, f64::INFINITY, obs)
}

/// [`refine`] for a bracket known to hold exactly one root, a simple one (the Bernstein fast
/// path's certain single sign variation), from the caller's starting point `start`: Halley's
/// step, cubically convergent at a simple root, where Schröder's is only quadratic. `size` is
/// at least [`size_at`]`(c, x)` for every `x` in `[a, b]` (e.g. at the end farther from
/// zero); it only saves work, the answer is the same for any such bound.
#[inline(always)]
pub(crate) fn refine_simple(
    c: &[f64],
    a: f64,
    b: f64,
    fa: f64,
    start: f64,
    size: f64,
    obs: &mut impl Observer,
) -> f64 {
    refine_with::<true>(c, a, b, fa, start, size, obs)
}

/// The iteration behind [`refine`] (`HALLEY = false`) and [`refine_simple`]; `size` bounds
/// [`size_at`]`(c, |x|)` on `[a, b]` (infinite: no bound known).
#[inline(always)]
fn refine_with<const HALLEY: bool>(
    c: &[f64],
    mut a: f64,
    mut b: f64,
    fa: f64,
    start: f64,
    size: f64,
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
        let (v, d, h) = eval3(c, x);
        if v == 0.0 {
            return x;
        }
        // The rounding-noise test below, first against the bound `size` (which the size at
        // `x` cannot exceed, the products rounding monotonically), so that the size at `x` is
        // computed only near the root.
        let noise = |size: f64| v.abs() <= 4.0 * f64::EPSILON * size;
        if noise(size) && noise(size_at(c, x.abs())) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_size_bound_changes_no_answer() {
        // (t − r)·(t² + q) with a simple root r in [0.1, 0.9] and q > 0, scaled: the answer
        // with the bound at the bracket's far end is the one without a bound, bit for bit.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..5_000 {
            let (r, q, k) = (
                0.1 + 0.8 * next(),
                1e-3 + next(),
                2f64.powi((next() * 40.0) as i32 - 20),
            );
            let c = [-r * q * k, q * k, -r * k, k];
            let (a, b) = (0.0, 1.0);
            let fa = c[0];
            let start = a + (b - a) * next();
            let free = refine_simple(&c, a, b, fa, start, f64::INFINITY, &mut ());
            let bounded = refine_simple(&c, a, b, fa, start, size_at(&c, 1.0), &mut ());
            assert_eq!(free.to_bits(), bounded.to_bits(), "{c:?} from {start}");
            assert!((free - r).abs() <= 1e-12, "{free} against {r}");
        }
    }
}
