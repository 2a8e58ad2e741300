//! Robust isolation of every distinct root by certain-sign Bernstein subdivision, with
//! numerically multiple roots and unresolvable clusters detected as *zero regions*.
//!
//! # The rounding bound
//!
//! The coefficients of `P` are only known to a relative rounding error, so `P(t)` is only
//! known up to `δ(t) = 4·(n+1)·ε·A(|t|)`, `A(x) = Σ|cⱼ|·xʲ`: this is the rounding bound, and
//! it also bounds the error of every Bernstein coefficient computed here (each piece's
//! coefficients are computed from `P` itself, by a Taylor shift to the piece's end nearer to
//! zero, so the bound on a piece `[a, b]` is `δ` at `min(|a|, |b|) + (b − a)`, about `δ` at
//! the piece).
//!
//! # The decisions
//!
//! A piece is halved (slightly off the middle) until one of these holds, with `M` its bound:
//!
//! * every Bernstein coefficient is at most `2M` in magnitude: `P` is indistinguishable from
//!   zero on the piece, a *zero piece*;
//! * every coefficient exceeds `M` in magnitude with no sign variation: no root (Descartes);
//! * at most one sign variation whatever the signs of the uncertain coefficients, and both
//!   end values (`P` at the piece's ends) beyond `3M`: exactly one simple root, with a sign
//!   change of `P` to refine it (the `3M` keeps such a piece from touching a zero piece);
//! * the piece can no longer be halved usefully: it counts as a zero piece.
//!
//! Pieces come out left to right; consecutive zero pieces form one *cluster*, reported as one
//! root. So two roots are merged exactly when their zero regions `{|P| ≤ ~2δ}` touch: for a
//! root `r` of multiplicity `m` that region has radius `ρ = (2δ·m!/|P⁽ᵐ⁾(r)|)^(1/m)`, and two
//! roots merge when `|rᵢ − rⱼ|` is below about `ρᵢ + ρⱼ` (the bounds `M`, `2M`, `3M` make the
//! border a band of a factor of a few, not a line).
//!
//! # Locating a cluster
//!
//! A root of multiplicity `m` is a simple root of `P⁽ᵐ⁻¹⁾`, which locates it far better than
//! `P` can: the first derivative with exactly one certain sign change over the cluster gives
//! the point (refined on that derivative). Failing that, a sign change of `P` over the
//! cluster, else its middle. A cluster at an end of the interval is examined on a span
//! reflected past that end, and reported only when its point lies in `(lo, hi]`; `P(lo) = 0`
//! exactly excludes it, `P(hi) = 0` exactly reports `hi`.
//!
//! # Roots far smaller than the interval
//!
//! A piece still undecided after `MAX_DEPTH` halvings is usually one `f64` cannot resolve
//! (it counts as a zero piece). But near 0 the rounding bound shrinks with `|t|`, and a
//! piece there may be tiny only relative to the interval (roots near 10⁻⁷⁰ in an interval of
//! size 1): such a piece, below `2⁻⁴⁰` of the interval's reach, is first cut at 0 if it
//! spans it (roots of opposite signs are never one cluster), then examined again at its own
//! scale: `P(s·U)` with `s` a power of two about the piece's reach, its coefficients scaled
//! exactly by powers of two (so that the values near the small roots neither underflow nor
//! lose bits), and with a root exactly at 0 divided out (`P = Tᵐ·R`, 0 reported once, at the
//! right end of the piece `[a, 0]`). Scaling by powers of two changes no rounding, so this
//! answers as the full interval would with unlimited exponent range; each level shrinks the
//! scale by at least `2⁴⁰`, so at most `MAX_LEVELS` levels.

use super::bernstein::bernstein_fixed;
use super::prep::{exponent, horner, mul_pow2, Prepared, MAX_COEFFS};
use super::refine::refine;
use super::trace::Observer;
use std::mem::MaybeUninit;

/// Halvings after which a piece counts as a zero piece.
const MAX_DEPTH: usize = 100;

/// Pieces examined at most (over every level); what is left after that counts as zero
/// pieces.
const MAX_NODES: usize = 40_000;

/// A piece undecided at `MAX_DEPTH` whose reach is below this fraction of the interval's is
/// examined again at its own scale.
const TINY: f64 = 1.0 / (1u64 << 40) as f64;

/// Most levels of examination at a smaller scale (the `f64` range over factors of `2⁴⁰`).
const MAX_LEVELS: usize = 64;

/// Split ratio of a piece: off the middle, so that dyadic roots are not hit exactly.
const SPLIT: f64 = 0.496_858_407_346_410_2;

type Coeffs = [f64; MAX_COEFFS];

/// What a piece holds, as far as the rounding bound lets one tell.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Empty,
    Simple,
    Zero,
    Split,
}

/// `A(x) = Σ|cⱼ|·xʲ` for `x ≥ 0`.
#[inline]
pub(crate) fn abs_horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |s, a| s * x + a.abs())
}

/// The rounding bound `δ` of `c` (degree `c.len() − 1`) at `|t| = x`.
#[inline]
pub(crate) fn bound(c: &[f64], x: f64) -> f64 {
    4.0 * c.len() as f64 * f64::EPSILON * abs_horner(c, x)
}

/// Bernstein coefficients of `c` on `[a, b]` (`b[0] = P(a)`, `b[n] = P(b)`) and their error
/// bound: a Taylor shift to the end nearer to zero, a scaling and a binomial transform.
fn bernstein(c: &[f64], a: f64, b: f64) -> (Coeffs, f64) {
    let n = c.len() - 1;
    let mut full = [0.0; MAX_COEFFS];
    full[..=n].copy_from_slice(c);
    macro_rules! fixed {
        ($($d:literal)*) => {
            match n + 1 {
                $($d => {
                    let cd: [f64; $d] = full[..$d].try_into().expect("size");
                    let (bz, m) = bernstein_fixed::<$d>(&cd, a, b);
                    full[..$d].copy_from_slice(&bz);
                    (full, m)
                })*
                _ => (full, f64::INFINITY),
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17)
}

/// Most sign variations of `b` over every choice of sign for its coefficients within `m` of
/// zero (those are uncertain): a run of `f` uncertain coefficients between two certain ones
/// allows up to `f + 1` variations of the right parity, at either end up to `f`.
#[inline(always)]
fn max_variations(b: &[f64], m: f64) -> u32 {
    let mut v = 0;
    let mut last: Option<bool> = None;
    let mut free = 0u32;
    for &x in b {
        if x.abs() <= m {
            free += 1;
            continue;
        }
        let neg = x < 0.0;
        v += match last {
            None => free,
            Some(l) if l != neg => 2 * (free / 2) + 1,
            Some(_) => 2 * free.div_ceil(2),
        };
        last = Some(neg);
        free = 0;
    }
    match last {
        None => u32::MAX,
        Some(_) => v + free,
    }
}

/// The decision for the piece `[a, b]` of `c` with Bernstein coefficients `bz` and bound `m`.
/// A zero piece needs each `|bᵢ|` below `2δ` at its own abscissa `a + (b − a)·i/n` (where
/// the control polygon approximates `P`), not only below `2m`: on a long piece `m` is `δ` at
/// its far end, larger than `δ` inside.
#[inline(always)]
fn classify(c: &[f64], a: f64, b: f64, bz: &[f64], m: f64) -> Kind {
    let n = bz.len() - 1;
    if bz.iter().all(|x| x.abs() <= 2.0 * m) {
        let step = (b - a) / n as f64;
        let zero = bz.iter().enumerate().all(|(i, x)| {
            let t = if i == n { b } else { a + step * i as f64 };
            x.abs() <= 2.0 * bound(c, t.abs())
        });
        if zero {
            return Kind::Zero;
        }
    }
    let b = bz;
    // With every sign certain (the usual piece) the count is that of the sign changes.
    let uncertain = b.iter().fold(false, |u, x| u | (x.abs() <= m));
    let variations = if uncertain {
        max_variations(b, m)
    } else {
        let negative = b
            .iter()
            .enumerate()
            .fold(0u32, |bits, (i, &x)| bits | u32::from(x < 0.0) << i);
        ((negative ^ (negative >> 1)) & ((1 << n) - 1)).count_ones()
    };
    match variations {
        0 => Kind::Empty,
        1 if b[0].abs() > 3.0 * m && b[n].abs() > 3.0 * m => Kind::Simple,
        _ => Kind::Split,
    }
}

/// Coefficients of `P⁽ᵏ⁾` (a positive multiple of it is not needed: exact factors `j!/(j−k)!`).
fn derivative(c: &[f64], k: usize) -> (Coeffs, usize) {
    let n = c.len() - 1;
    let mut d = [0.0; MAX_COEFFS];
    d[..=n].copy_from_slice(c);
    for step in 0..k {
        for j in 0..n - step {
            d[j] = d[j + 1] * (j + 1) as f64;
        }
        d[n - step] = 0.0;
    }
    (d, n - k)
}

/// The simple root of `c` in the certain-sign bracket `[a, b]`.
fn simple_root(c: &[f64], a: f64, b: f64, obs: &mut impl Observer) -> f64 {
    let (fa, fb) = (horner(c, a), horner(c, b));
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 || (fa < 0.0) == (fb < 0.0) {
        return b;
    }
    refine(c, a, b, fa, fb, obs)
}

/// The point of a cluster spanning `[a, b]`: see the module documentation.
fn locate(c: &[f64], a: f64, b: f64, obs: &mut impl Observer) -> f64 {
    let n = c.len() - 1;
    for k in 1..n {
        let (d, dn) = derivative(c, k);
        let d = &d[..=dn];
        let (bz, m) = bernstein(d, a, b);
        let bz = &bz[..=dn];
        match max_variations(bz, m) {
            0 => break,
            1 if bz[0].abs() > m && bz[dn].abs() > m => return simple_root(d, a, b, obs),
            _ => {}
        }
    }
    let (fa, fb) = (horner(c, a), horner(c, b));
    if fa != 0.0 && fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
        return refine(c, a, b, fa, fb, obs);
    }
    0.5 * (a + b)
}

/// Every distinct root of `P` in `(lo, hi]`, ascending, in `T` (unscaled), passed to `emit`
/// until it returns `false`.
pub(crate) fn roots<O: Observer>(p: &Prepared, emit: &mut dyn FnMut(f64) -> bool, obs: &mut O) {
    macro_rules! fixed {
        ($($d:literal)*) => {
            match p.n + 1 {
                $($d => {
                    let c: &[f64; $d] = p.c[..$d].try_into().expect("degree D - 1");
                    roots_fixed(c, p.lo, p.hi, emit, obs, &mut Budget { nodes: 0, level: 0 });
                })*
                _ => {}
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17)
}

/// What one search may still spend: pieces examined (over every level), and the current
/// level of examination at a smaller scale.
struct Budget {
    nodes: usize,
    level: usize,
}

/// [`roots_fixed`] for any degree (`c.len()` from 2 to 17); nothing for a constant.
fn roots_any<O: Observer>(
    c: &[f64],
    lo: f64,
    hi: f64,
    emit: &mut dyn FnMut(f64) -> bool,
    obs: &mut O,
    budget: &mut Budget,
) -> bool {
    macro_rules! fixed {
        ($($d:literal)*) => {
            match c.len() {
                $($d => {
                    let c: &[f64; $d] = c.try_into().expect("D coefficients");
                    roots_fixed(c, lo, hi, emit, obs, budget)
                })*
                _ => true,
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17)
}

/// The roots of `c` in the piece `(a, b]` (one sign: `a ≥ 0` or `b ≤ 0`), examined at the
/// piece's own scale (see the module documentation); `false` when `emit` asks to stop.
fn at_own_scale<O: Observer>(
    c: &[f64],
    a: f64,
    b: f64,
    emit: &mut dyn FnMut(f64) -> bool,
    obs: &mut O,
    budget: &mut Budget,
) -> bool {
    // A root exactly at 0: `P = Tᵐ·R`; R has the other roots.
    let m = c.iter().position(|&x| x != 0.0).unwrap_or(c.len());
    let r = &c[m.min(c.len())..];
    if r.len() < 2 {
        // R is a non-zero constant (or P is zero, which `prepare` refuses).
        return !(m > 0 && b == 0.0) || emit(0.0);
    }
    // `s = 2^e` just above the piece's reach; R(s·U) scaled by `2^-top`, exactly.
    let e = exponent(a.abs().max(b.abs())) + 1;
    let top = r
        .iter()
        .enumerate()
        .filter(|(_, x)| **x != 0.0)
        .map(|(j, x)| exponent(*x) + j as i32 * e)
        .max()
        .expect("a non-zero coefficient");
    let mut scaled = [0.0; MAX_COEFFS];
    for (j, (d, &x)) in scaled.iter_mut().zip(r).enumerate() {
        *d = mul_pow2(x, j as i32 * e - top);
    }
    let s = mul_pow2(1.0, e);
    let (inv, n) = (mul_pow2(1.0, -e), r.len());
    budget.level += 1;
    let go_on = roots_any(
        &scaled[..n],
        a * inv,
        b * inv,
        &mut |u| emit(u * s),
        obs,
        budget,
    );
    budget.level -= 1;
    go_on && (!(m > 0 && b == 0.0) || emit(0.0))
}

/// [`roots`] for a polynomial of degree `D − 1` (a fixed size, so that every piece's
/// Bernstein coefficients are made and classified with unrolled loops, without copies).
fn roots_fixed<const D: usize, O: Observer>(
    c: &[f64; D],
    lo: f64,
    hi: f64,
    emit: &mut dyn FnMut(f64) -> bool,
    obs: &mut O,
    budget: &mut Budget,
) -> bool {
    let p_lo_zero = horner(c, lo) == 0.0;
    let p_hi_zero = horner(c, hi) == 0.0;
    // An open cluster: its span.
    let mut open: Option<(f64, f64)> = None;
    // Closes the open cluster; false when `emit` asks to stop.
    let close = |span: (f64, f64), emit: &mut dyn FnMut(f64) -> bool, obs: &mut O| -> bool {
        let (a, b) = span;
        let at_lo = a <= lo;
        let at_hi = b >= hi;
        if at_lo && p_lo_zero {
            return true; // the root is lo, which is excluded
        }
        if at_hi && p_hi_zero {
            return emit(hi);
        }
        let w = b - a;
        let (sa, sb) = (if at_lo { a - w } else { a }, if at_hi { b + w } else { b });
        let r = locate(c, sa, sb, obs);
        if r > lo && r <= hi {
            emit(r)
        } else {
            true
        }
    };
    // The pending right halves (range and depth), below `top`; not zeroed (2.4 kB for a
    // query that usually pushes a few entries).
    // One more entry than the halvings: the cut at 0 of a tiny piece (once per search).
    let mut stack = [MaybeUninit::<(f64, f64, usize)>::uninit(); MAX_DEPTH + 2];
    let mut top = 0;
    let (mut a, mut b, mut depth) = (lo, hi, 0usize);
    let tiny = TINY * lo.abs().max(hi.abs());
    loop {
        budget.nodes += 1;
        let (bz, m) = bernstein_fixed(c, a, b);
        let mut kind = classify(c, a, b, &bz, m);
        let mid = a + SPLIT * (b - a);
        if kind == Kind::Split
            && depth >= MAX_DEPTH
            && budget.nodes < MAX_NODES
            && budget.level < MAX_LEVELS
            && a.abs().max(b.abs()) < tiny
        {
            if a < 0.0 && b > 0.0 {
                // Cut at 0: the right part waits, the left goes on.
                stack[top].write((0.0, b, depth));
                top += 1;
                b = 0.0;
                continue;
            }
            if let Some(span) = open.take() {
                if !close(span, emit, obs) {
                    return false;
                }
            }
            if !at_own_scale(c, a, b, emit, obs, budget) {
                return false;
            }
            kind = Kind::Empty;
        } else if kind == Kind::Split
            && (depth >= MAX_DEPTH
                || budget.nodes >= MAX_NODES
                || !(mid > a && mid < b)
                || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs()))
        {
            kind = Kind::Zero;
        }
        match kind {
            Kind::Split => {
                obs.split();
                stack[top].write((mid, b, depth + 1));
                top += 1;
                b = mid;
                depth += 1;
                continue;
            }
            Kind::Zero => {
                open = Some(match open {
                    Some((s, _)) => (s, b),
                    None => (a, b),
                });
            }
            Kind::Empty | Kind::Simple => {
                if let Some(span) = open.take() {
                    if !close(span, emit, obs) {
                        return false;
                    }
                }
                if kind == Kind::Simple && !emit(simple_root(c, a, b, obs)) {
                    return false;
                }
            }
        }
        if top == 0 {
            break;
        }
        top -= 1;
        // SAFETY: every entry below the old `top` was written by a push (above) and not
        // popped since.
        (a, b, depth) = unsafe { stack[top].assume_init() };
    }
    match open {
        Some(span) => close(span, emit, obs),
        None => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::prep::prepare;

    fn all(c: &[f64], lo: f64, hi: f64) -> Vec<f64> {
        let p = prepare(c, lo, hi).expect("a polynomial");
        let mut out = Vec::new();
        roots(
            &p,
            &mut |t| {
                out.push(t * p.scale);
                true
            },
            &mut (),
        );
        out
    }

    #[test]
    fn pieces_are_classified_by_certain_signs() {
        // (t − 1)(t − 2) on [0, 1.5]: one certain sign change, clean ends.
        let c = [2.0, -3.0, 1.0];
        let (b, m) = bernstein(&c, 0.0, 1.5);
        assert_eq!(classify(&c, 0.0, 1.5, &b[..3], m), Kind::Simple);
        // On [2.5, 3]: no root.
        let (b, m) = bernstein(&c, 2.5, 3.0);
        assert_eq!(classify(&c, 2.5, 3.0, &b[..3], m), Kind::Empty);
        // (t − 1)² on a tiny piece around 1: indistinguishable from zero.
        let c = [1.0, -2.0, 1.0];
        let (b, m) = bernstein(&c, 1.0 - 1e-9, 1.0 + 1e-9);
        assert_eq!(classify(&c, 1.0 - 1e-9, 1.0 + 1e-9, &b[..3], m), Kind::Zero);
        // ... and undecided on a larger one.
        let (b, m) = bernstein(&c, 0.5, 1.5);
        assert_eq!(classify(&c, 0.5, 1.5, &b[..3], m), Kind::Split);
        assert_eq!(max_variations(&[1.0, 0.0, 1.0], 0.5), 2);
        assert_eq!(max_variations(&[1.0, 0.0, -1.0], 0.5), 1);
        assert_eq!(max_variations(&[0.0, 1.0, 1.0], 0.5), 1);
        assert_eq!(max_variations(&[-1.0, 0.0, 0.0, 1.0], 0.5), 3);
        assert_eq!(max_variations(&[-1.0, 0.0, 0.0, -1.0], 0.5), 2);
        assert_eq!(max_variations(&[0.0, 0.0, 1.0], 0.5), 2);
    }

    #[test]
    fn a_piece_near_zero_is_searched_again_at_its_own_scale() {
        // (t² − a²)(t − 1) with a = 2⁻⁴⁰⁰ on (−2, 2]: ±a lie far below what 100 halvings of
        // the interval reach; they are found apart, each to a few ulps.
        let a = 2f64.powi(-400);
        let c = [a * a, -a * a, -1.0, 1.0];
        let r = all(&c, -2.0, 2.0);
        assert_eq!(r.len(), 3, "{r:?}");
        for (got, want) in r.iter().zip([-a, a, 1.0]) {
            assert!(
                (got - want).abs() <= 8.0 * f64::EPSILON * want.abs(),
                "{r:?}"
            );
        }
        // t·(t² − t + a): 0 exactly (divided out, reported once), then a (to a relative
        // 2⁻⁴⁰⁰) and 1; 0 is excluded as the interval's lower end.
        let c = [0.0, a, -1.0, 1.0];
        let r = all(&c, -1.0, 2.0);
        assert_eq!(r.len(), 3, "{r:?}");
        assert_eq!(r[0], 0.0);
        assert!((r[1] - a).abs() <= 8.0 * f64::EPSILON * a, "{r:?}");
        assert!((r[2] - 1.0).abs() <= 8.0 * f64::EPSILON, "{r:?}");
        assert_eq!(all(&c, 0.0, 2.0).len(), 2);
    }

    #[test]
    fn zero_regions_are_one_root_at_the_multiple_root() {
        // (t − 1)³(t − 2): the triple root once, located on P''.
        let c = [-2.0, 7.0, -9.0, 5.0, -1.0];
        let r = all(&c, 0.0, 3.0);
        assert_eq!(r.len(), 2, "{r:?}");
        assert!((r[0] - 1.0).abs() <= 1e-12, "{r:?}");
        assert!((r[1] - 2.0).abs() <= 1e-14, "{r:?}");
        // (t − 1)² + 1e-20 is (t − 1)² up to rounding: one root.
        let r = all(&[1.0 + 1e-20, -2.0, 1.0], 0.0, 3.0);
        assert_eq!(r.len(), 1, "{r:?}");
        // (t − 1)² + 1e-3 is not.
        assert!(all(&[1.001, -2.0, 1.0], 0.0, 3.0).is_empty());
        // A multiple root at lo is excluded, at hi included.
        assert_eq!(all(&c, 1.0, 1.5), Vec::<f64>::new());
        assert_eq!(all(&c, 0.5, 1.0), vec![1.0]);
    }
}
