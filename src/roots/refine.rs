//! Refinement of a bracketed root: the safeguarded Newton/Schröder iteration every strategy
//! uses on a sign-change bracket, and its Halley variant for a bracket known to hold exactly
//! one simple root (the Bernstein fast path), also for four brackets at once (in turn, or
//! four lanes a register with AVX2).

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

/// [`refine_simple_lanes`] in AVX2 intrinsics, the lanes' polynomials given by power
/// (`c[j][l]` is lane `l`'s coefficient of `xʲ`): every lane takes the steps of
/// [`Refinement::step`] in the same IEEE operations and order, four lanes a register, each
/// `if` a blend on the comparison's mask, until every lane has ended (a lane that has ended
/// keeps its answer while the others go on). The same answers bit for bit (tested).
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn refine_simple_lanes_avx2<const D: usize>(
    c: &[[f64; LANES]; D],
    bracket: [Option<Bracket>; LANES],
) -> [f64; LANES] {
    use std::arch::x86_64::*;
    // The lane operations are `roots::avx2`'s macros.
    let lanes_of = |f: &dyn Fn(&Bracket) -> f64| {
        let v: [f64; LANES] = std::array::from_fn(|l| bracket[l].as_ref().map_or(0.0, f));
        v
    };
    macro_rules! load {
        ($v:expr) => {{
            let v: [f64; LANES] = $v;
            _mm256_set_pd(v[3], v[2], v[1], v[0])
        }};
    }
    let mut coeff = [_mm256_setzero_pd(); D];
    for (cj, given) in coeff.iter_mut().zip(c) {
        *cj = _mm256_loadu_pd(given.as_ptr());
    }
    // `Refinement::new`, lane by lane.
    let (mut a, mut b) = (load!(lanes_of(&|r| r.ta)), load!(lanes_of(&|r| r.tb)));
    let fa = load!(lanes_of(&|r| r.fa));
    let start = load!(lanes_of(&|r| r.start));
    let size = load!(lanes_of(&|r| r.size));
    let zero = _mm256_setzero_pd();
    let neg_a = lt!(fa, zero);
    let mut x = pick!(
        and!(gt!(start, a), lt!(start, b)),
        start,
        mul!(splat!(0.5), add!(a, b))
    );
    let mut step = sub!(b, a);
    let mut step_before = step;
    // Lanes still stepping (all ones) and their answers so far.
    let mut running = _mm256_castsi256_pd(_mm256_set_epi64x(
        -i64::from(bracket[3].is_some()),
        -i64::from(bracket[2].is_some()),
        -i64::from(bracket[1].is_some()),
        -i64::from(bracket[0].is_some()),
    ));
    let mut out = zero;
    for _ in 0..MAX_ITER {
        if _mm256_movemask_pd(running) == 0 {
            break;
        }
        // `eval3` and `size_at(c, |x|)`.
        let (mut v, mut d, mut h) = (zero, zero, zero);
        let ax = abs!(x);
        let mut size_x = zero;
        for &cj in coeff.iter().rev() {
            h = add!(mul!(h, x), d);
            d = add!(mul!(d, x), v);
            v = add!(mul!(v, x), cj);
            size_x = add!(mul!(size_x, ax), abs!(cj));
        }
        // Ends at x: p(x) is zero.
        let at_zero = eq!(v, zero);
        // Ends with one last Newton step: p(x) is rounding noise.
        let noise_bound = splat!(4.0 * f64::EPSILON);
        let noise = and!(
            le!(abs!(v), mul!(noise_bound, size)),
            le!(abs!(v), mul!(noise_bound, size_x))
        );
        let last = sub!(x, div!(v, d));
        let last_answer = pick!(and!(ge!(last, a), le!(last, b)), last, x);
        let noise = _mm256_andnot_pd(at_zero, noise);
        // The bracket moves to x.
        let same_sign = not!(_mm256_xor_pd(lt!(v, zero), neg_a));
        let na = pick!(same_sign, x, a);
        let nb = pick!(same_sign, b, x);
        let den = sub!(mul!(d, d), mul!(v, h));
        // `x − v/d` is `last` again; written out, the compiler schedules the two divisions
        // better (using `last` measured 1.025 on Barth's sextic).
        let mut next = pick!(
            gt!(den, zero),
            sub!(x, div!(mul!(v, d), den)),
            sub!(x, div!(v, d))
        );
        let away = or!(
            gt!(abs!(sub!(next, x)), mul!(splat!(0.5), step_before)),
            not!(and!(gt!(next, na), lt!(next, nb)))
        );
        let mid = mul!(splat!(0.5), add!(na, nb));
        next = pick!(away, mid, next);
        // Ends at x: the bisection cannot split the bracket.
        let stuck = and!(away, or!(le!(mid, na), ge!(mid, nb)));
        let new_step = abs!(sub!(next, x));
        // Ends at next: the step is below an ulp or two.
        let small = le!(new_step, mul!(splat!(2.0 * f64::EPSILON), abs!(next)));
        // The answers of the lanes that end here, in the scalar step's order of tests.
        let ended_zero = and!(running, at_zero);
        let ended_noise = and!(running, noise);
        let going = _mm256_andnot_pd(or!(at_zero, noise), running);
        let ended_stuck = and!(going, stuck);
        let ended_small = and!(_mm256_andnot_pd(stuck, going), small);
        out = pick!(ended_zero, x, out);
        out = pick!(ended_noise, last_answer, out);
        out = pick!(ended_stuck, x, out);
        out = pick!(ended_small, next, out);
        // The lanes that go on take the new state.
        let on = _mm256_andnot_pd(or!(stuck, small), going);
        a = pick!(on, na, a);
        b = pick!(on, nb, b);
        step_before = pick!(on, step, step_before);
        step = pick!(on, new_step, step);
        x = pick!(on, next, x);
        running = on;
    }
    // Lanes still stepping after `MAX_ITER` steps answer their current point.
    out = pick!(running, x, out);
    let mut answers = [0.0; LANES];
    _mm256_storeu_pd(answers.as_mut_ptr(), out);
    answers
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
    use super::super::lanes::by_power;
    use super::super::prep::horner;
    use super::*;

    /// Random brackets of one simple root for polynomials of `D` coefficients, four at a
    /// time (some lanes empty): the lanes' AVX2 refinement against `refine_simple`, bit for
    /// bit, and the interleaved scalar lanes too.
    fn lanes_match<const D: usize>(seed: u64) {
        let mut next = crate::testing::uniform_stream(seed);
        let mut refined = 0;
        for group in 0..3000 {
            let mut c = [[0.0; D]; LANES];
            let mut brackets = [None; LANES];
            for l in 0..LANES {
                if group % 5 == 0 && l == 2 {
                    continue;
                }
                // (x − r)·Π(x − s) with r in the bracket and the other roots outside it.
                let (a, b) = (next() * 0.5, 0.5 + next() * 0.5);
                let r = a + (b - a) * (0.05 + 0.9 * next());
                let mut degree = 0;
                // Ascending coefficients, scaled by a power of two; multiplying by (x − root)
                // shifts them up and subtracts root times them.
                let mut q = [0.0; D];
                q[0] = 2f64.powi((next() * 40.0) as i32 - 20);
                let mul = |q: &mut [f64; D], root: f64| {
                    for j in (1..D).rev() {
                        q[j] = q[j - 1] - root * q[j];
                    }
                    q[0] *= -root;
                };
                mul(&mut q, r);
                degree += 1;
                while degree < D - 1 {
                    let outside = if next() < 0.5 {
                        b + 0.01 + next() * 2.0
                    } else {
                        a - 0.01 - next() * 2.0
                    };
                    mul(&mut q, outside);
                    degree += 1;
                }
                c[l] = q;
                let (fa, fb) = (horner(&q, a), horner(&q, b));
                if fa == 0.0 || fb == 0.0 || (fa < 0.0) == (fb < 0.0) {
                    continue;
                }
                let start = match (next() * 4.0) as u32 {
                    0 => a - 1.0,
                    1 => r,
                    _ => a + (b - a) * next(),
                };
                let size = if next() < 0.5 {
                    size_at(&q, a.abs().max(b.abs()))
                } else {
                    f64::INFINITY
                };
                brackets[l] = Some(Bracket {
                    ta: a,
                    tb: b,
                    fa,
                    start,
                    size,
                });
            }
            let want: [Option<f64>; LANES] = std::array::from_fn(|l| {
                brackets[l]
                    .map(|r| refine_simple(&c[l], r.ta, r.tb, r.fa, r.start, r.size, &mut ()))
            });
            let check = |got: [f64; LANES], refined: &mut usize| {
                for l in 0..LANES {
                    if let Some(w) = want[l] {
                        let what = (c[l], brackets[l]);
                        assert_eq!(got[l].to_bits(), w.to_bits(), "{what:?}");
                        *refined += 1;
                    }
                }
            };
            check(
                refine_simple_lanes(std::array::from_fn(|l| &c[l]), brackets),
                &mut refined,
            );
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2, checked just above.
                let fast = unsafe { refine_simple_lanes_avx2(&by_power(&c), brackets) };
                check(fast, &mut 0);
            }
        }
        assert!(refined > 9000, "{refined}");
    }

    #[test]
    fn the_lanes_refinements_are_the_scalar_one_bit_for_bit() {
        lanes_match::<3>(0x1234_5678);
        lanes_match::<5>(0x9abc_def0);
        lanes_match::<7>(0x0f1e_2d3c);
        lanes_match::<9>(0x4b5a_6978);
        lanes_match::<17>(0x8796_a5b4);
    }

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
