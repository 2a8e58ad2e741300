//! Refinement of a bracketed root: the safeguarded Newton/Schröder iteration every strategy
//! uses on a sign-change bracket, and its Halley variant for a bracket known to hold exactly
//! one simple root (the Bernstein fast path).

use super::trace::Observer;
use crate::geometry::LANES;

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
    a: f64,
    b: f64,
    fa: f64,
    start: f64,
    size: f64,
    obs: &mut impl Observer,
) -> f64 {
    let mut state = Refinement::new(a, b, fa, start, size);
    for _ in 0..MAX_ITER {
        obs.refine_step();
        if let Some(root) = state.step::<HALLEY>(c) {
            return root;
        }
    }
    state.x
}

/// A bracket `[ta, tb]` of one simple root for [`refine_simple`], with `fa = P(ta)`, the
/// starting point and the bound on the size of `P`'s terms that function takes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bracket {
    pub ta: f64,
    pub tb: f64,
    pub fa: f64,
    pub start: f64,
    pub size: f64,
}

/// [`refine_simple`] of up to [`LANES`] brackets at once, lane `l` on `c[l]` where
/// `bracket[l]` is `Some` (other lanes' answers are meaningless): each lane's answer is
/// `refine_simple`'s bit for bit (the same steps), the lanes' steps taken in turn so that
/// their chains of dependent operations (evaluation, division) overlap instead of following
/// one another.
#[inline(always)]
pub(crate) fn refine_simple_lanes<const D: usize>(
    c: [&[f64; D]; LANES],
    bracket: [Option<Bracket>; LANES],
) -> [f64; LANES] {
    let mut state = bracket.map(|b| b.map(|b| Refinement::new(b.ta, b.tb, b.fa, b.start, b.size)));
    let mut out = [0.0; LANES];
    for _ in 0..MAX_ITER {
        let mut running = false;
        for l in 0..LANES {
            if let Some(s) = &mut state[l] {
                match s.step::<true>(c[l]) {
                    Some(root) => {
                        out[l] = root;
                        state[l] = None;
                    }
                    None => running = true,
                }
            }
        }
        if !running {
            return out;
        }
    }
    for l in 0..LANES {
        if let Some(s) = &state[l] {
            out[l] = s.x;
        }
    }
    out
}

/// The state of one refinement between its steps (see [`Refinement::step`]).
#[derive(Clone, Copy, Debug)]
struct Refinement {
    /// The bracket `[a, b]`, with `P(a) < 0` when `neg_a`.
    a: f64,
    b: f64,
    neg_a: bool,
    /// The bound on the size of `P`'s terms in the bracket.
    size: f64,
    /// The current point.
    x: f64,
    /// The last two steps' lengths.
    step: f64,
    step_before: f64,
}

impl Refinement {
    #[inline(always)]
    fn new(a: f64, b: f64, fa: f64, start: f64, size: f64) -> Self {
        let x = if start > a && start < b {
            start
        } else {
            0.5 * (a + b)
        };
        Self {
            a,
            b,
            neg_a: fa < 0.0,
            size,
            x,
            step: b - a,
            step_before: b - a,
        }
    }

    /// One step from `x`: `Some(root)` when the refinement ends there, else `None` with the
    /// state moved on.
    #[inline(always)]
    fn step<const HALLEY: bool>(&mut self, c: &[f64]) -> Option<f64> {
        let Self { a, b, x, .. } = *self;
        let (v, d, h) = eval3(c, x);
        if v == 0.0 {
            return Some(x);
        }
        // The rounding-noise test below, first against the bound `size` (which the size at
        // `x` cannot exceed, the products rounding monotonically), so that the size at `x` is
        // computed only near the root.
        let noise = |size: f64| v.abs() <= 4.0 * f64::EPSILON * size;
        if noise(self.size) && noise(size_at(c, x.abs())) {
            // `p(x)` is rounding noise: one last Newton step is as close as `p` allows.
            let last = x - v / d;
            return Some(if last >= a && last <= b { last } else { x });
        }
        if (v < 0.0) == self.neg_a {
            self.a = x;
        } else {
            self.b = x;
        }
        let (a, b) = (self.a, self.b);
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
        if (next - x).abs() > 0.5 * self.step_before || !(next > a && next < b) {
            next = 0.5 * (a + b);
            if next <= a || next >= b {
                return Some(x);
            }
        }
        self.step_before = self.step;
        self.step = (next - x).abs();
        if self.step <= 2.0 * f64::EPSILON * next.abs() {
            return Some(next);
        }
        self.x = next;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_size_bound_changes_no_answer() {
        // (t − r)·(t² + q) with a simple root r in [0.1, 0.9] and q > 0, scaled: the answer
        // with the bound at the bracket's far end is the one without a bound, bit for bit.
        let mut next = crate::testing::uniform_stream(0x2545_f491_4f6c_dd1d);
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
