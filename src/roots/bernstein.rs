//! A cheap first-root search in the Bernstein basis, tried before any Sturm sequence or
//! derivative splitting is built; it answers only when the answer is certain and otherwise
//! hands the interval to the full method.
//!
//! # Method
//!
//! `P` on `[lo, hi]` is rewritten as `Σ bᵢ·C(n,i)·sⁱ(1−s)ⁿ⁻ⁱ` with `t = lo + (hi − lo)·s`
//! (a Taylor shift, a scaling and a binomial transform: about `n²` flops). By Descartes' rule
//! in this basis the number of sign variations `V` of `b₀ … bₙ` is at least the number of roots
//! in `(lo, hi)`, counted with multiplicity, and has the same parity. `V = 0` means no root;
//! `V = 1` means exactly one, simple, with `P(lo)` and `P(hi)` of opposite signs (`b₀ = P(lo)`,
//! `bₙ = P(hi)`). Otherwise the interval is halved (de Casteljau, slightly off the middle so
//! as not to land on dyadic roots) and the left half searched first: the first `V = 1` piece
//! brackets the first root, which is refined on `P` itself by Halley steps kept inside the
//! bracket, starting where the piece's control polygon crosses zero.
//!
//! # When it declines
//!
//! Every computed `bᵢ` carries a rounding error below `margin = (64 + 2·depth)·(n+1)·ε·S`,
//! `S = Σ|cⱼ|·(|lo| + hi − lo)ʲ` (a bound on `|P|`'s coefficient sizes over the interval; the
//! conversion only forms combinations with positive weights whose absolute sums are at most
//! `S`). A coefficient within that margin of zero has an uncertain sign: an end coefficient so
//! small (a root at or near an end of the interval or of a piece), a piece still ambiguous
//! after `MAX_DEPTH` halvings (a double or multiple root, or roots closer than rounding can
//! separate, which is where the full method's zero regions decide), or a bracket whose end
//! values disagree with the expected signs all make it decline. Where it answers, the signs
//! it used are exact for the given coefficients, so the answer is the exact one: the same
//! hit/miss the full method gives away from numerically multiple roots.

use super::prep::{horner, Fixed, Prepared};
use super::refine::{refine_simple, size_at, Bracket};
use super::trace::Observer;

/// Halvings after which a piece that still has more than one sign variation is left to the
/// full method (a numerically multiple root or an unresolvable cluster). At most 63 (the
/// search keeps its pending pieces as the bits of a `u64`).
const MAX_DEPTH: usize = 40;

/// Pieces examined at most (each costs one de Casteljau split).
const MAX_NODES: usize = 256;

/// Split ratio of a piece: off the middle, like the Sturm bisection.
const SPLIT: f64 = 0.496_858_407_346_410_2;

/// Outcome of the fast search.
pub(crate) enum Fast {
    /// Certainly no root in `(lo, hi]`.
    NoRoot,
    /// The first root, in `t` (already multiplied by the scale).
    Root(f64),
    /// The signs were not certain: use the full method.
    Undecided,
}

/// `INV_BINOMIAL[n][k] = 1 / C(n, k)` for `n ≤ 16` (binomials exact, one rounding each).
pub(crate) const INV_BINOMIAL: [[f64; 17]; 17] = {
    let mut t = [[0.0; 17]; 17];
    let mut n = 0;
    while n < 17 {
        let mut c = 1.0f64;
        let mut k = 0;
        while k <= n {
            t[n][k] = 1.0 / c;
            c = c * (n - k) as f64 / (k + 1) as f64;
            k += 1;
        }
        n += 1;
    }
    t
};

/// Bit `i` of the first mask set when `b[i] < 0`, of the second when `|b[i]| ≤ margin`
/// (both false for a NaN, as the comparisons are).
#[inline(always)]
fn sign_masks<const D: usize>(b: &[f64; D], margin: f64) -> (u32, u32) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    // SAFETY: SSE2 is enabled for this build (the cfg above), and these intrinsics only
    // compute on registers.
    unsafe {
        // Two coefficients a comparison: the same IEEE comparisons as the scalar ones, a mask
        // of two bits each.
        use std::arch::x86_64::{
            _mm_and_pd, _mm_castsi128_pd, _mm_cmple_pd, _mm_cmplt_pd, _mm_movemask_pd,
            _mm_set1_epi64x, _mm_set1_pd, _mm_set_pd, _mm_setzero_pd,
        };
        let zero = _mm_setzero_pd();
        let m = _mm_set1_pd(margin);
        let magnitude = _mm_castsi128_pd(_mm_set1_epi64x(i64::MAX));
        let (mut neg, mut small) = (0u32, 0u32);
        let mut i = 0;
        while i + 1 < D {
            let v = _mm_set_pd(b[i + 1], b[i]);
            neg |= (_mm_movemask_pd(_mm_cmplt_pd(v, zero)) as u32) << i;
            let abs = _mm_and_pd(v, magnitude);
            small |= (_mm_movemask_pd(_mm_cmple_pd(abs, m)) as u32) << i;
            i += 2;
        }
        if i < D {
            neg |= u32::from(b[i] < 0.0) << i;
            small |= u32::from(b[i].abs() <= margin) << i;
        }
        (neg, small)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    b.iter().enumerate().fold((0, 0), |(neg, small), (i, &x)| {
        (
            neg | u32::from(x < 0.0) << i,
            small | u32::from(x.abs() <= margin) << i,
        )
    })
}

/// Bit `i` set when `b[i]` and `b[i + 1]` differ in sign (`< 0` or not), for `i < D − 1`,
/// from the first mask of [`sign_masks`].
#[inline(always)]
fn sign_changes<const D: usize>(neg: u32) -> u32 {
    (neg ^ (neg >> 1)) & ((1 << (D - 1)) - 1)
}

/// Number of sign variations of `b` (0, 1, or 2 for two or more: all the search needs to
/// know), or `None` when an interior coefficient (or the last one) is within `margin` of zero
/// (its sign uncertain).
#[inline(always)]
fn variations<const D: usize>(b: &[f64; D], margin: f64) -> Option<u32> {
    // Branch-free over the whole array; the same answer as stopping at the first uncertain
    // coefficient.
    let (neg, small) = sign_masks(b, margin);
    let uncertain = small & !1 != 0;
    let changes = sign_changes::<D>(neg);
    // No bit, one bit (clearing the lowest leaves none), or more.
    let count = if changes == 0 {
        0
    } else if changes & (changes - 1) == 0 {
        1
    } else {
        2
    };
    (!uncertain).then_some(count)
}

/// De Casteljau in place, both parts at once: `b` (a piece `[0, 1]`) becomes the Bernstein
/// coefficients of its part `[0, λ]` (the first entries of the triangle's rows), and those of
/// its part `[λ, 1]` are returned (the last entries).
#[inline(always)]
fn split_at<const D: usize>(
    b: &mut [f64; D],
    lambda: f64,
    right: &mut std::mem::MaybeUninit<[f64; D]>,
) {
    // Row k of the triangle shrinks by one each level. Working on a copy with fixed bounds
    // lets the loops unroll into registers.
    let mut row = *b;
    let out = right.as_mut_ptr().cast::<f64>();
    // SAFETY: `out` points to `D` writable `f64`s (the slot); each index below is < D.
    unsafe { out.add(D - 1).write(row[D - 1]) };
    for k in 1..D {
        for j in 0..D - k {
            row[j] += lambda * (row[j + 1] - row[j]);
        }
        b[k] = row[0];
        // SAFETY: as above.
        unsafe { out.add(D - 1 - k).write(row[D - 1 - k]) };
    }
}

/// See the module documentation.
pub(crate) fn first_root(p: &Prepared, obs: &mut impl Observer) -> Fast {
    macro_rules! fixed {
        ($($d:literal)*) => {
            match p.n + 1 {
                $($d => search::<$d, _>(&Fixed {
                    c: p.c[..$d].try_into().expect("degree D - 1"),
                    scale: p.scale,
                    lo: p.lo,
                    hi: p.hi,
                }, obs),)*
                _ => Fast::Undecided,
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17)
}

/// The Bernstein coefficients on `[a, b]` of a polynomial of degree `D − 1` (a fixed size, so
/// that the loops unroll), expanded from the end nearer zero (smaller rounding), and a bound
/// on their rounding error.
#[inline(always)]
pub(super) fn bernstein_fixed<const D: usize>(c: &[f64; D], a: f64, b: f64) -> ([f64; D], f64) {
    let n = D - 1;
    let reversed = b.abs() < a.abs();
    let (x0, h) = if reversed { (b, a - b) } else { (a, b - a) };
    let mut d = *c;
    // The Taylor shift to `x0`; none is needed from zero (a chord parametrised from its
    // entry point, the heart's usual query), where every step would add `0·d[j + 1]`.
    if x0 != 0.0 {
        for i in 0..n {
            for j in (i..n).rev() {
                d[j] += x0 * d[j + 1];
            }
        }
    }
    let mut hk = 1.0;
    for (x, ib) in d.iter_mut().zip(&INV_BINOMIAL[n]) {
        *x *= hk * ib;
        hk *= h;
    }
    for i in 1..D {
        for j in (i..D).rev() {
            d[j] += d[j - 1];
        }
    }
    if reversed {
        d.reverse();
    }
    let x = x0.abs() + h.abs();
    let size = c.iter().rev().fold(0.0, |s, a| s * x + a.abs());
    (d, 4.0 * D as f64 * f64::EPSILON * size)
}

/// The search's answer from `bracket`: its root refined on `p`, scaled.
#[inline(always)]
fn refined<const D: usize>(bracket: &Bracket, p: &Fixed<D>, obs: &mut impl Observer) -> Fast {
    let Bracket {
        ta,
        tb,
        fa,
        start,
        size,
    } = *bracket;
    Fast::Root(refine_simple(&p.c, ta, tb, fa, start, size, obs) * p.scale)
}

/// The first search's bracket on a piece `[s0, s1]` of `[0, 1]` (Bernstein coefficients `b`)
/// with one sign variation, or its answer without one: a root at the piece's end, or
/// `Undecided` when the end values do not confirm the bracket.
#[inline(always)]
fn bracket_of_piece<const D: usize>(
    p: &Fixed<D>,
    b: &[f64; D],
    (s0, s1): (f64, f64),
    size: f64,
) -> Result<Bracket, Fast> {
    let n = D - 1;
    let c = &p.c;
    let (lo, hi) = (p.lo, p.hi);
    let w = hi - lo;
    let ta = if s0 == 0.0 { lo } else { lo + w * s0 };
    let tb = if s1 == 1.0 { hi } else { lo + w * s1 };
    // `P(0)` by Horner's rule is `c₀` (or a zero of either sign when `c₀` is zero: all this
    // code asks of it is its comparisons with zero).
    let fa = if ta == 0.0 { c[0] } else { horner(c, ta) };
    let fb = horner(c, tb);
    if fb == 0.0 {
        return Err(Fast::Root(tb * p.scale));
    }
    if fa == 0.0 || (fa < 0.0) == (fb < 0.0) || (fa < 0.0) != (b[0] < 0.0) {
        return Err(Fast::Undecided);
    }
    // Start where the piece's control polygon crosses zero: on a piece with one sign
    // variation it is close to the root, closer than false position on the end values.
    let changes = sign_changes::<D>(sign_masks(b, 0.0).0);
    let i = if changes == 0 {
        0
    } else {
        changes.trailing_zeros() as usize
    };
    // `b[i]` and `b[i + 1]` picked by constant indices: a variable index would keep the
    // search's coefficients in memory, where each split's narrow stores stall the next
    // split's wide loads.
    let (mut bi, mut next) = (b[0], b[1]);
    for j in 1..n {
        if j == i {
            (bi, next) = (b[j], b[j + 1]);
        }
    }
    let s = (i as f64 + bi / (bi - next)) / n as f64;
    let start = ta + (tb - ta) * s;
    // The size of `P`'s terms at every point of `[ta, tb]` is at most its size at the end
    // farther from zero; from `lo = 0` that is at most the search's `size` (at `hi`).
    let size = if lo == 0.0 {
        size
    } else {
        size_at(c, ta.abs().max(tb.abs()))
    };
    Ok(Bracket {
        ta,
        tb,
        fa,
        start,
        size,
    })
}

/// The search for a polynomial of degree `D − 1` (a fixed size, so that the loops unroll and
/// the coefficients stay in registers); see the module documentation. Inlined into the
/// fixed-size preparation's caller, so that the prepared copy stays in registers.
#[inline(always)]
pub(crate) fn search<const D: usize, O: Observer>(p: &Fixed<D>, obs: &mut O) -> Fast {
    let n = D - 1;
    let c = &p.c;
    let (lo, hi) = (p.lo, p.hi);
    let w = hi - lo;
    // On [lo, hi]; the rounding bound below (from |lo| + w) covers either expansion end.
    let (root, _) = bernstein_fixed(c, lo, hi);
    let r = lo.abs() + w;
    let size = size_at(c, r);
    let unit = (n + 1) as f64 * f64::EPSILON * size;
    if !unit.is_finite() || root[0].abs() <= 64.0 * unit || root[n].abs() <= 64.0 * unit {
        return Fast::Undecided;
    }
    let whole = variations(&root, 64.0 * unit);
    match bracket_from(p, &root, size, unit, whole, obs) {
        Ok(bracket) => refined(&bracket, p, obs),
        Err(fast) => fast,
    }
}

/// [`search`] after its first test, up to the refinement: the first root's bracket, or the
/// answer when the search ends without one. `root` holds the Bernstein coefficients on the
/// whole interval, `size` and `unit` are the search's bounds, `whole` the whole interval's
/// [`variations`] (both end coefficients already clear of `64·unit`). The lanes' query
/// (`super::lanes`) computes the first test for four queries at once, goes on here lane by
/// lane, and refines the lanes' brackets together.
#[inline(always)]
pub(crate) fn bracket_from<const D: usize, O: Observer>(
    p: &Fixed<D>,
    root: &[f64; D],
    size: f64,
    unit: f64,
    whole: Option<u32>,
    obs: &mut O,
) -> Result<Bracket, Fast> {
    let n = D - 1;
    let root = *root;
    // The whole interval first: most queries end there. The loop's first piece is this one
    // again, with its variations already counted.
    let mut known = Some(whole);
    match known {
        Some(Some(0)) => return Err(Fast::NoRoot),
        Some(Some(1)) => return bracket_of_piece(p, &root, (0.0, 1.0), size),
        _ => {}
    }
    // Depth-first over pieces `[s0, s1]` of `[0, 1]`, left first. The piece at depth `d` was
    // reached from its parent by the left or the right half; bit `d` of `pending` is set
    // when it was the left one, its right sibling still to search, whose coefficients the
    // same split computed (`right[d]`). The next pending piece is the deepest one, and its
    // range is found again by repeating the same halvings from `[0, 1]` (the same
    // operations, so the same bits). Either half of a split carries the rounding of one more
    // level than its parent, which the margin's `2·depth` allows for.
    let mut pending = 0u64;
    let mut b = root;
    let mut right = [const { std::mem::MaybeUninit::<[f64; D]>::uninit() }; MAX_DEPTH];
    let (mut s0, mut s1, mut depth) = (0.0f64, 1.0f64, 0u32);
    for _ in 0..MAX_NODES {
        let margin = (64.0 + 2.0 * depth as f64) * unit;
        let v = match known.take() {
            Some(v) => v,
            None => variations(&b, margin),
        };
        match v {
            Some(0) => {
                // No root here: the next pending piece.
                if pending == 0 {
                    return Err(Fast::NoRoot);
                }
                depth = 63 - pending.leading_zeros();
                pending &= !(1 << depth);
                (s0, s1) = (0.0, 1.0);
                for level in 1..=depth {
                    let sm = s0 + SPLIT * (s1 - s0);
                    if level < depth && pending & (1 << level) != 0 {
                        s1 = sm;
                    } else {
                        s0 = sm;
                    }
                }
                // SAFETY: written when bit `depth` of `pending` was set (by the split below).
                b = unsafe { right[depth as usize].assume_init() };
                continue;
            }
            Some(1) => return bracket_of_piece(p, &b, (s0, s1), size),
            _ => {}
        }
        if depth as usize + 1 >= MAX_DEPTH {
            return Err(Fast::Undecided);
        }
        obs.split();
        let sm = s0 + SPLIT * (s1 - s0);
        split_at(&mut b, SPLIT, &mut right[depth as usize + 1]);
        if b[n].abs() <= margin || !(sm > s0 && sm < s1) {
            return Err(Fast::Undecided);
        }
        depth += 1;
        pending |= 1 << depth;
        s1 = sm;
    }
    Err(Fast::Undecided)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::prep::prepare;

    fn fast(c: &[f64], lo: f64, hi: f64) -> Fast {
        first_root(&prepare(c, lo, hi).expect("a polynomial"), &mut ())
    }

    #[test]
    fn answers_only_when_the_signs_are_certain() {
        // (t − 1)(t − 2): the first root, to an ulp.
        match fast(&[2.0, -3.0, 1.0], 0.0, 3.0) {
            Fast::Root(t) => assert!((t - 1.0).abs() <= 2.0 * f64::EPSILON, "{t}"),
            _ => panic!("expected a root"),
        }
        // (t − 1)² + 1e-3: no root.
        assert!(matches!(fast(&[1.001, -2.0, 1.0], 0.0, 3.0), Fast::NoRoot));
        // (t − 1)²: a double root has no certain sign pattern; the full method decides.
        assert!(matches!(fast(&[1.0, -2.0, 1.0], 0.0, 3.0), Fast::Undecided));
        // A root exactly at `lo` (excluded): the full method decides.
        assert!(matches!(fast(&[2.0, -3.0, 1.0], 1.0, 3.0), Fast::Undecided));
        // Degree 16 with 16 simple roots 1/4 apart: the first one.
        let mut c = vec![1.0];
        for k in 0..16 {
            let r = -2.0 + 0.25 * f64::from(k);
            let mut next = vec![0.0; c.len() + 1];
            for (j, &a) in c.iter().enumerate() {
                next[j + 1] += a;
                next[j] -= r * a;
            }
            c = next;
        }
        match fast(&c, -2.1, 2.0) {
            Fast::Root(t) => assert!((t + 2.0).abs() <= 1e-12, "{t}"),
            Fast::NoRoot => panic!("expected a root"),
            Fast::Undecided => {}
        }
    }

    /// The value at `s` of the Bernstein coefficients `b` on `[0, 1]` (de Casteljau).
    fn bernstein_value<const D: usize>(b: &[f64; D], s: f64) -> f64 {
        let mut row = *b;
        for k in 1..D {
            for j in 0..D - k {
                row[j] += s * (row[j + 1] - row[j]);
            }
        }
        row[0]
    }

    #[test]
    fn a_split_gives_both_halves_of_the_piece() {
        let b = [0.7, -1.3, 2.1, 0.4, -0.9, 1.6, -0.2];
        let mut left = b;
        let mut slot = std::mem::MaybeUninit::uninit();
        split_at(&mut left, SPLIT, &mut slot);
        // SAFETY: `split_at` writes every entry.
        let right = unsafe { slot.assume_init() };
        assert_eq!(
            left[6].to_bits(),
            right[0].to_bits(),
            "they meet at the split"
        );
        assert_eq!(
            (left[0], right[6]),
            (b[0], b[6]),
            "the ends are the piece's"
        );
        for k in 0..=20 {
            let u = f64::from(k) / 20.0;
            let on_left = bernstein_value(&b, SPLIT * u);
            let on_right = bernstein_value(&b, SPLIT + (1.0 - SPLIT) * u);
            assert!((bernstein_value(&left, u) - on_left).abs() < 1e-14, "{u}");
            assert!((bernstein_value(&right, u) - on_right).abs() < 1e-14, "{u}");
        }
    }

    #[test]
    fn comes_back_to_every_pending_half() {
        // ((t − 0.3)² + 1e-6)·(t − 0.9): the complex pair near 0.3 shows as two sign
        // variations on every piece around it until the pieces are far smaller than 0.3,
        // so the search goes deep on the left and returns to many pending right halves
        // before the root at 0.9 (and, without it, proves there is no root).
        let pair = [0.09 + 1e-6, -0.6, 1.0];
        let c = [-0.9 * pair[0], pair[0] - 0.9 * pair[1], pair[1] - 0.9, 1.0];
        let mut trace = crate::roots::Trace::default();
        let p = prepare(&c, 0.0, 1.0).expect("a polynomial");
        match first_root(&p, &mut trace) {
            Fast::Root(t) => assert!((t - 0.9).abs() <= 4.0 * f64::EPSILON, "{t}"),
            _ => panic!("expected the root at 0.9"),
        }
        assert!(trace.splits >= 8, "{trace:?}");
        assert!(matches!(fast(&pair, 0.0, 1.0), Fast::NoRoot));
    }
}
