//! A second strategy after C. Yuksel, "High-Performance Polynomial Root Finding for Graphics"
//! (HPG 2022): the roots of `P⁽ᵏ⁾` split the interval into pieces on which `P⁽ᵏ⁻¹⁾` is
//! monotonic, so each piece holds at most one of its roots, found by a Newton iteration kept
//! inside a shrinking sign-change bracket. Working up from the linear `P⁽ⁿ⁻¹⁾` gives the
//! critical points of `P`, and then the first root of `P` itself.
//!
//! Multiple roots: at a critical point `x` (a root of the derivative), `P(x)` is compared with
//! `64·ε·Σ|cⱼ||x|ʲ`, a bound on the rounding error of evaluating it; within it, `x` is a root
//! (a double root of a tangent ray, the triple roots of the heart's `Z = 0` plane), reported
//! once. Critical points are found to full relative precision, as a multiple root found at
//! one is only as good as it. A piece starting at `lo` with `P(lo) = 0` takes its sign from
//! the first non-zero derivative there, so a root at `lo` is excluded as `(lo, hi]` says.

use super::prep::Prepared;
use super::sturm::CRIT_TOL;
use super::trace::Observer;

/// Precision, relative to the interval's magnitude, of critical points (roots of derivatives):
/// they only split the interval, and a multiple root found at one is off by at most this.
const CRIT_PRECISION: f64 = 0.0;

/// Newton/bisection steps allowed per piece (bisection alone needs at most ~2100).
const MAX_ITER: usize = 2200;

/// `(p(x), Σ|cⱼ||x|ʲ)` for ascending `c`.
#[inline(always)]
fn eval_with_bound(c: &[f64], x: f64) -> (f64, f64) {
    let ax = x.abs();
    let (mut v, mut s) = (0.0, 0.0);
    for &a in c.iter().rev() {
        v = v * x + a;
        s = s * ax + a.abs();
    }
    (v, s)
}

/// `(p(x), p'(x))` for ascending `c`.
#[inline(always)]
fn eval_with_derivative(c: &[f64], x: f64) -> (f64, f64) {
    let mut v = 0.0;
    let mut d = 0.0;
    for &a in c.iter().rev() {
        d = d * x + v;
        v = v * x + a;
    }
    (v, d)
}

/// The root of `c` (monotonic on `[a, b]`) in the open bracket where `fa`, `fb` have opposite
/// signs, by Newton steps that fall back to bisection whenever they leave the bracket, until
/// a step is below an ulp of the root plus `floor`.
fn newton_in_bracket(
    c: &[f64],
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    floor: f64,
    obs: &mut impl Observer,
) -> f64 {
    // One copy of the iteration for each length of `c`, so that its evaluations unroll.
    macro_rules! fixed {
        ($($d:literal)*) => {
            match c.len() {
                $($d => {
                    let c: &[f64; $d] = c.try_into().expect("length");
                    newton_in(c, a, b, fa, fb, floor, obs)
                })*
                _ => newton_in(c, a, b, fa, fb, floor, obs),
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17)
}

/// [`newton_in_bracket`]'s body, inlined into each caller so that a fixed-size `c` fixes
/// its loops.
#[inline(always)]
fn newton_in(
    c: &[f64],
    mut a: f64,
    mut b: f64,
    fa: f64,
    fb: f64,
    floor: f64,
    obs: &mut impl Observer,
) -> f64 {
    let neg_at_a = fa < 0.0;
    // Start from the secant of the bracket: exact for a linear piece, close for a flat one.
    let mut x = a - fa * ((b - a) / (fb - fa));
    if !(x > a && x < b) {
        x = 0.5 * (a + b);
    }
    for _ in 0..MAX_ITER {
        obs.refine_step();
        let (v, d) = eval_with_derivative(c, x);
        if v == 0.0 {
            return x;
        }
        if (v < 0.0) == neg_at_a {
            a = x;
        } else {
            b = x;
        }
        let mut next = x - v / d;
        if !(next > a && next < b) {
            next = 0.5 * (a + b);
        }
        let step = (next - x).abs();
        if step <= 2.0 * f64::EPSILON * next.abs() + floor || next <= a || next >= b {
            return next.clamp(a, b);
        }
        x = next;
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            return x;
        }
    }
    x
}

/// Sign just right of `x` of the polynomial `ders[0]`, from its first non-zero derivative.
fn sign_right_of<const M: usize>(ders: &[[f64; M]], degs: &[usize], x: f64) -> f64 {
    for (d, &n) in ders.iter().zip(degs) {
        let v = super::prep::horner(&d[..=n], x);
        if v != 0.0 {
            return v;
        }
    }
    0.0
}

/// Roots of `ders[0]` in `(lo, hi]`, given its critical points `crit` (ascending, inside
/// `(lo, hi)`), written to `out` (ascending); stops after the first when `first_only`.
#[allow(clippy::too_many_arguments)]
fn roots_in_pieces<const M: usize>(
    ders: &[[f64; M]],
    degs: &[usize],
    crit: &[f64],
    lo: f64,
    hi: f64,
    first_only: bool,
    out: &mut [f64; M],
    obs: &mut impl Observer,
) -> usize {
    // Critical points (roots of derivatives) only split intervals: an ulp of the interval's
    // magnitude is precision enough for them; roots of `P` itself get full relative precision.
    let floor = if first_only {
        0.0
    } else {
        CRIT_PRECISION * lo.abs().max(hi.abs())
    };
    let c = &ders[0][..=degs[0]];
    let mut count = 0;
    let mut a = lo;
    let mut fa = super::prep::horner(c, lo);
    if fa == 0.0 {
        fa = sign_right_of(ders, degs, lo);
    }
    let mut a_is_root = false;
    for i in 0..=crit.len() {
        let (b, fb, b_is_root) = if i < crit.len() {
            let x = crit[i];
            let (v, s) = eval_with_bound(c, x);
            (x, v, v.abs() <= CRIT_TOL * s)
        } else {
            (hi, super::prep::horner(c, hi), false)
        };
        if b_is_root {
            if count < M {
                out[count] = b;
                count += 1;
            }
            if first_only {
                return count;
            }
        } else if !a_is_root && fa != 0.0 {
            let root = if fb == 0.0 {
                Some(b)
            } else if (fa < 0.0) != (fb < 0.0) {
                Some(newton_in_bracket(c, a, b, fa, fb, floor, obs))
            } else {
                None
            };
            if let Some(r) = root {
                if count < M {
                    out[count] = r;
                    count += 1;
                }
                if first_only {
                    return count;
                }
            }
        }
        a = b;
        fa = fb;
        a_is_root = b_is_root;
    }
    count
}

fn first_impl<const M: usize>(p: &Prepared, obs: &mut impl Observer) -> Option<f64> {
    let n = p.n;
    // ders[k] = k-th derivative of P divided by a positive constant (degree n - k).
    let mut ders = [[0.0; M]; M];
    let mut degs = [0usize; M];
    ders[0][..=n].copy_from_slice(&p.c[..=n]);
    degs[0] = n;
    for k in 1..=n {
        let dn = n - k;
        let mut m = 0.0f64;
        for j in 0..=dn {
            let v = ders[k - 1][j + 1] * (j + 1) as f64;
            ders[k][j] = v;
            m = m.max(v.abs());
        }
        let inv = 1.0 / m;
        for v in &mut ders[k][..=dn] {
            *v *= inv;
        }
        degs[k] = dn;
    }
    let mut crit = [0.0; M];
    let mut ncrit = 0;
    if n >= 2 {
        // The linear derivative P^(n-1).
        let l = &ders[n - 1];
        let x = -l[0] / l[1];
        if x > p.lo && x < p.hi {
            obs.split();
            crit[0] = x;
            ncrit = 1;
        }
        for k in (1..n - 1).rev() {
            let mut next = [0.0; M];
            let found = roots_in_pieces(
                &ders[k..=n],
                &degs[k..=n],
                &crit[..ncrit],
                p.lo,
                p.hi,
                false,
                &mut next,
                obs,
            );
            // Roots at `hi` are not interior critical points.
            ncrit = 0;
            for &r in &next[..found] {
                if r > p.lo && r < p.hi {
                    obs.split();
                    crit[ncrit] = r;
                    ncrit += 1;
                }
            }
        }
    }
    let mut out = [0.0; M];
    let found = roots_in_pieces(
        &ders[..=n],
        &degs[..=n],
        &crit[..ncrit],
        p.lo,
        p.hi,
        true,
        &mut out,
        obs,
    );
    (found > 0).then(|| out[0] * p.scale)
}

/// See [`super::Solver::Yuksel`].
pub(crate) fn first_root(p: &Prepared, obs: &mut impl Observer) -> Option<f64> {
    if p.n < 8 {
        first_impl::<8>(p, obs)
    } else {
        first_impl::<17>(p, obs)
    }
}
