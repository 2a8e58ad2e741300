//! The paper's method: isolation by a Sturm sequence, refinement by Anderson–Björck false
//! position with a bisection safeguard — used where the sequence's signs are certain.
//!
//! # When the Sturm sequence is used
//!
//! `P` (already rescaled by `prep`) is re-expressed on its interval, `Q(u) = P(mid + half·u)`,
//! so that `(lo, hi]` is `(−1, 1]`. The sequence is `p₀ = Q`, `p₁ = Q'`,
//! `pₖ₊₁ = −rem(pₖ₋₁, pₖ)`, every member scaled to a largest coefficient of 1, with a running
//! bound on each member's coefficient error (the input's rounding, `4·(n+1)·ε` times the size
//! of `P` on the interval, propagated through each division with a safety factor, plus the
//! division's own rounding). The rule:
//!
//! * the sequence is used only when it is *certain*: the leading coefficient of every
//!   remainder exceeds 16 times its error bound, down to a non-zero constant (no numerical
//!   gcd is ever taken: `P` is then square-free beyond rounding, every root simple);
//! * a count `V(x)` is used only when it is certain: `Q(x)` beyond its error, and every other
//!   member whose value at `x` is within its error has certain neighbours of opposite signs
//!   (so that its sign does not matter);
//! * each root isolated by bisection on the counts must have values of `P` at the bracket's
//!   ends beyond three times the rounding bound, of opposite signs; false position on `P`
//!   then refines it to a few ulps.
//!
//! When any of these fails (multiple or clustered roots, a root at or near an end or a split
//! point), the whole interval goes to the certain-sign Bernstein subdivision (`cluster`),
//! which decides multiple roots and clusters by zero regions. Either way the answer is the
//! same set of roots; the Sturm sequence is the paper's method for the simple roots.
//!
//! Sign changes are counted with zero members skipped, the standard convention that makes the
//! count `V(a) − V(b)` the number of distinct roots in the half-open `(a, b]`. Bisection
//! splits slightly off the middle so as not to land exactly on dyadic roots.

use super::cluster::{abs_horner, bound};
use super::prep::{horner, max_abs, Prepared, MAX_COEFFS};
use super::trace::{Observer, Path};

/// Safety factor on the propagated error of each remainder.
const ERR_SAFETY: f64 = 4.0;

/// A remainder's leading coefficient must exceed its error bound this many times over for
/// the sequence to be certain.
const CERTAIN: f64 = 16.0;

/// Tolerance, relative to `Σ|cⱼ||x|ʲ`, under which a value at a critical point is zero.
pub(crate) const CRIT_TOL: f64 = 64.0 * f64::EPSILON;

/// A root closer to 0 than this fraction of its bracket's width is bracketed from 0 itself.
const NEAR_ZERO: f64 = 1.0 / (1u64 << 40) as f64;

/// Most iterations of any loop (bisection of a `f64` range needs at most about 2100).
const MAX_ITER: usize = 2200;

/// Most count evaluations of one isolation (each bracket needs about 50 halvings at most
/// before the roots' separation, certain by then, is resolved).
const MAX_COUNTS: usize = 4096;

/// A certain Sturm sequence of `Q` (at most `M` members of degree below `M`).
struct Chain<const M: usize> {
    p: [[f64; M]; M],
    deg: [usize; M],
    /// Bound on each member's coefficient errors.
    err: [f64; M],
    len: usize,
}

impl<const M: usize> Chain<M> {
    /// The sequence of `q` (degree `n ≥ 1`) whose coefficients carry absolute errors up to
    /// `input_err`, or `None` when it is not certain (see the module documentation).
    fn build(q: &[f64], input_err: f64) -> Option<Self> {
        let n = q.len() - 1;
        let mut ch = Chain {
            p: [[0.0; M]; M],
            deg: [0; M],
            err: [0.0; M],
            len: 2,
        };
        let s = 1.0 / max_abs(q);
        for (d, &a) in ch.p[0].iter_mut().zip(q) {
            *d = a * s;
        }
        ch.deg[0] = n;
        ch.err[0] = input_err * s;
        let mut m = 0.0f64;
        for (j, (d, &a)) in ch.p[1].iter_mut().zip(&q[1..]).enumerate() {
            *d = a * (j + 1) as f64;
            m = m.max(d.abs());
        }
        for d in &mut ch.p[1][..n] {
            *d /= m;
        }
        ch.deg[1] = n - 1;
        ch.err[1] = input_err * n as f64 / m;
        while ch.deg[ch.len - 1] > 0 {
            let k = ch.len;
            let (da, db) = (ch.deg[k - 2], ch.deg[k - 1]);
            let mut r = ch.p[k - 2];
            let b = ch.p[k - 1];
            let lb = b[db];
            let mut qsum = 0.0f64;
            for i in (0..=da - db).rev() {
                let quot = r[i + db] / lb;
                qsum += quot.abs();
                r[i + db] = 0.0;
                for j in 0..db {
                    r[i + j] -= quot * b[j];
                }
            }
            let rounding = 4.0 * f64::EPSILON * (db + 2) as f64 * (1.0 + qsum);
            let err = ERR_SAFETY * (ch.err[k - 2] + qsum * ch.err[k - 1]) + rounding;
            let dr = db - 1;
            let certain = r[dr].abs() > CERTAIN * err; // false for NaN too
            if !certain {
                return None;
            }
            let s = -1.0 / max_abs(&r[..=dr]);
            for (d, &a) in ch.p[k].iter_mut().zip(&r[..=dr]) {
                *d = a * s;
            }
            ch.deg[k] = dr;
            ch.err[k] = err * s.abs();
            ch.len = k + 1;
        }
        Some(ch)
    }

    /// Number of sign changes of the sequence at `x` (`|x| ≤ 1`), or `None` when it is not
    /// certain.
    fn changes(&self, x: f64) -> Option<i32> {
        let ax = x.abs();
        let mut vals = [0.0f64; M];
        let mut sure = [false; M];
        for k in 0..self.len {
            let c = &self.p[k][..=self.deg[k]];
            let v = horner(c, x);
            let e =
                (self.deg[k] + 1) as f64 * (self.err[k] + 2.0 * f64::EPSILON * abs_horner(c, ax));
            vals[k] = v;
            sure[k] = v.abs() > e;
        }
        if !sure[0] {
            return None;
        }
        let mut count = 0;
        let mut last = vals[0] < 0.0;
        for k in 1..self.len {
            if !sure[k] {
                // Its sign does not matter when its neighbours are certain and opposite.
                let ok = k + 1 < self.len
                    && sure[k + 1]
                    && (vals[k - 1] < 0.0) != (vals[k + 1] < 0.0)
                    && sure[k - 1];
                if !ok {
                    return None;
                }
                continue;
            }
            let neg = vals[k] < 0.0;
            count += i32::from(neg != last);
            last = neg;
        }
        Some(count)
    }
}

/// True when `[a, b]` can no longer shrink usefully: no double strictly between the ends, or
/// a width of a few ulps of the larger end plus `floor`.
#[inline]
fn converged(a: f64, b: f64, floor: f64) -> bool {
    let mid = 0.5 * (a + b);
    mid <= a || mid >= b || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) + floor
}

/// The isolation split point of `(a, b)`: slightly off the middle, so that the dyadic points
/// where exactly representable roots tend to sit are not hit exactly.
#[inline]
fn split(a: f64, b: f64) -> f64 {
    a + (b - a) * 0.496_858_407_346_410_2
}

/// The kept end's value `f` scaled by Anderson–Björck's factor `m` (or `1/2` when `m ≤ 0`),
/// unless that would leave the normal numbers: a value scaled toward underflow over hundreds
/// of steps (a root far smaller than the bracket) would lose its sign at zero.
#[inline]
fn anderson_bjorck(f: f64, m: f64) -> f64 {
    let scaled = f * if m > 0.0 { m } else { 0.5 };
    if scaled.is_normal() {
        scaled
    } else {
        f
    }
}

/// Anderson–Björck false position for the root of `q` in `[a, b]`, where `fa`, `fb` have
/// opposite signs (neither zero); a step that fails to halve the bracket is followed by a
/// bisection step. Returns a point of the final bracket.
pub(crate) fn false_position(
    q: &[f64],
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
    floor: f64,
    obs: &mut impl Observer,
) -> f64 {
    let a0 = a;
    // `side` is the end replaced last: -1 left, 1 right, 0 none yet.
    let mut side = 0;
    let mut force_bisect = false;
    for _ in 0..MAX_ITER {
        if converged(a, b, floor) {
            break;
        }
        let width = b - a;
        let mut x = if force_bisect {
            0.5 * (a + b)
        } else {
            b - fb * (width / (fb - fa))
        };
        if !(x > a && x < b) {
            x = 0.5 * (a + b);
        }
        obs.refine_step();
        let fx = horner(q, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == (fa < 0.0) {
            if side == -1 {
                let m = 1.0 - fx / fa;
                fb = anderson_bjorck(fb, m);
            }
            a = x;
            fa = fx;
            side = -1;
        } else {
            if side == 1 {
                let m = 1.0 - fx / fb;
                fa = anderson_bjorck(fa, m);
            }
            b = x;
            fb = fx;
            side = 1;
        }
        force_bisect = b - a > 0.5 * width;
    }
    if a > a0 && fa.abs() < fb.abs() {
        a
    } else {
        b
    }
}

/// `P` re-expressed on its interval: `Q(u) = P(mid + half·u)`, so that `(lo, hi]` becomes
/// `(−1, 1]`, with a bound on its coefficients' errors.
struct Shifted {
    q: [f64; MAX_COEFFS],
    mid: f64,
    half: f64,
    err: f64,
}

impl Shifted {
    fn new(p: &Prepared) -> Self {
        let n = p.n;
        let mid = 0.5 * p.lo + 0.5 * p.hi;
        let half = 0.5 * p.hi - 0.5 * p.lo;
        let mut q = [0.0; MAX_COEFFS];
        q[..=n].copy_from_slice(&p.c[..=n]);
        for i in 0..n {
            for j in (i..n).rev() {
                q[j] += mid * q[j + 1];
            }
        }
        let mut w = 1.0;
        for c in q.iter_mut().take(n + 1) {
            *c *= w;
            w *= half;
        }
        // The rounding bound of `P` on the interval, whatever the basis.
        let err = bound(&p.c[..=n], p.lo.abs().max(p.hi.abs()));
        Shifted { q, mid, half, err }
    }

    /// `u` in `T`, the ends exactly.
    fn to_t(&self, p: &Prepared, u: f64) -> f64 {
        if u <= -1.0 {
            p.lo
        } else if u >= 1.0 {
            p.hi
        } else {
            (self.mid + self.half * u).clamp(p.lo, p.hi)
        }
    }
}

/// A bracket `[a, b]` (in `T`) of a simple root of `P`, checked: `P` beyond three times its
/// rounding bound at both ends, with opposite signs. The refined root, or `None`.
///
/// A bracket around 0 whose root lies far closer to 0 than to its ends (`|P(0)|` below
/// `2⁻⁴⁰·|P′(0)|` times its width) is first cut at 0, where `P(0) = c₀` exactly: false
/// position, which stops on a width relative to the bracket's ends, cannot otherwise reach a
/// root at `1e-177` from ends near 1 (it would stop near `1e-153`).
fn checked_root(c: &[f64], mut a: f64, mut b: f64, obs: &mut impl Observer) -> Option<f64> {
    let (mut fa, mut fb) = (horner(c, a), horner(c, b));
    let sure = |f: f64, t: f64| f.abs() > 3.0 * bound(c, t.abs());
    if !(sure(fa, a) && sure(fb, b)) || (fa < 0.0) == (fb < 0.0) {
        return None;
    }
    if a < 0.0 && b > 0.0 && c[0].abs() < NEAR_ZERO * c[1].abs() * (b - a) {
        let f0 = c[0];
        if f0 == 0.0 {
            return Some(0.0);
        }
        if (f0 < 0.0) == (fa < 0.0) {
            (a, fa) = (0.0, f0);
        } else {
            (b, fb) = (0.0, f0);
        }
    }
    Some(false_position(c, a, b, fa, fb, 0.0, obs))
}

/// The roots of `P` in `(lo, hi]` (in `T`) by the Sturm sequence, written to `out`
/// (ascending; only the first when `first_only`): their number, or `None` when some sign it
/// needs is not certain.
fn isolate(
    p: &Prepared,
    first_only: bool,
    out: &mut [f64; MAX_COEFFS],
    obs: &mut impl Observer,
) -> Option<usize> {
    if p.n < 8 {
        isolate_in::<8>(p, first_only, out, obs)
    } else {
        isolate_in::<MAX_COEFFS>(p, first_only, out, obs)
    }
}

/// [`isolate`] with a sequence of at most `M` members.
fn isolate_in<const M: usize>(
    p: &Prepared,
    first_only: bool,
    out: &mut [f64; MAX_COEFFS],
    obs: &mut impl Observer,
) -> Option<usize> {
    let c = &p.c[..=p.n];
    let sh = Shifted::new(p);
    let ch = Chain::<M>::build(&sh.q[..=p.n], sh.err)?;
    let (va, vb) = (ch.changes(-1.0)?, ch.changes(1.0)?);
    let mut found = 0;
    // Depth-first, left half first, so roots come out ascending.
    let mut stack = [(0.0f64, 0.0f64, 0i32, 0i32); 64];
    stack[0] = (-1.0, 1.0, va, vb);
    let mut top = 1;
    let mut counts = 0;
    while top > 0 {
        top -= 1;
        let (a, b, va, vb) = stack[top];
        match va - vb {
            0 => continue,
            1 => {
                let root = checked_root(c, sh.to_t(p, a), sh.to_t(p, b), obs)?;
                out[found] = root;
                found += 1;
                if first_only || found == out.len() {
                    return Some(found);
                }
                continue;
            }
            k if k < 0 => return None,
            _ => {}
        }
        let m = split(a, b);
        counts += 1;
        if counts > MAX_COUNTS || !(m > a && m < b) || top + 2 > stack.len() {
            return None;
        }
        obs.split();
        let vm = ch.changes(m)?;
        stack[top] = (m, b, vm, vb);
        stack[top + 1] = (a, m, va, vm);
        top += 2;
    }
    Some(found)
}

/// See [`super::first_root`]: the Sturm isolation of the first root, for a polynomial the
/// Bernstein test left undecided (it is not tried again here).
pub(crate) fn first_root(p: &Prepared, obs: &mut impl Observer) -> Option<f64> {
    let mut out = [0.0; MAX_COEFFS];
    if let Some(found) = isolate(p, true, &mut out, obs) {
        obs.settled(Path::Sturm);
        return (found > 0).then(|| out[0] * p.scale);
    }
    obs.settled(Path::Subdivision);
    let mut first = None;
    super::cluster::roots(
        p,
        &mut |t| {
            first = Some(t * p.scale);
            false
        },
        obs,
    );
    first
}

/// See [`super::sturm_roots`].
pub(crate) fn all_roots(p: &Prepared) -> Vec<f64> {
    let mut out = [0.0; MAX_COEFFS];
    if let Some(found) = isolate(p, false, &mut out, &mut ()) {
        return out[..found].iter().map(|t| t * p.scale).collect();
    }
    let mut all = Vec::new();
    super::cluster::roots(
        p,
        &mut |t| {
            all.push(t * p.scale);
            true
        },
        &mut (),
    );
    all
}
