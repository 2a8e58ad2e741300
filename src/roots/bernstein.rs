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
//! brackets the first root, which is refined by false position on `P` itself.
//!
//! # When it declines
//!
//! Every computed `bᵢ` carries a rounding error below `margin = (64 + 2·depth)·(n+1)·ε·S`,
//! `S = Σ|cⱼ|·(|lo| + hi − lo)ʲ` (a bound on `|P|`'s coefficient sizes over the interval; the
//! conversion only forms combinations with positive weights whose absolute sums are at most
//! `S`). A coefficient within that margin of zero has an uncertain sign: an end coefficient so
//! small (a root at or near an end of the interval or of a piece), a piece still ambiguous
//! after `MAX_DEPTH` halvings (a double or multiple root, or roots closer than rounding can
//! separate, which is where the full method's numerical gcd decides), or a bracket whose end
//! values disagree with the expected signs all make it decline. Where it answers, the signs
//! it used are exact for the given coefficients, so the answer is the exact one: the same
//! hit/miss the full method gives away from numerically multiple roots.

use super::prep::{horner, Prepared};
use super::sturm::false_position;

/// Halvings after which a piece that still has more than one sign variation is left to the
/// full method (a numerically multiple root or an unresolvable cluster).
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

/// `1 / C(n, k)` for `n ≤ 16`, computed on first use of each row (exact binomials, one
/// rounding each).
#[inline]
fn inv_binomial(n: usize, k: usize) -> f64 {
    let mut c = 1.0f64;
    for j in 0..k {
        c = c * (n - j) as f64 / (j + 1) as f64;
    }
    1.0 / c
}

/// Number of sign variations of `b[..=n]`, or `None` when an interior coefficient is within
/// `margin` of zero (its sign uncertain).
#[inline]
fn variations(b: &[f64], margin: f64) -> Option<u32> {
    let mut v = 0;
    let mut neg = b[0] < 0.0;
    for &x in &b[1..] {
        if x.abs() <= margin {
            return None;
        }
        let xn = x < 0.0;
        v += u32::from(xn != neg);
        neg = xn;
    }
    Some(v)
}

/// See the module documentation.
pub(crate) fn first_root<const M: usize>(p: &Prepared) -> Fast {
    let n = p.n;
    let c = &p.c[..=n];
    let (lo, hi) = (p.lo, p.hi);
    let w = hi - lo;
    // Taylor shift to `lo`, then scale by `w^k / C(n, k)`.
    let mut b = [0.0; M];
    b[..=n].copy_from_slice(c);
    for i in 0..n {
        for j in (i..n).rev() {
            b[j] += lo * b[j + 1];
        }
    }
    let mut wk = 1.0;
    for (k, x) in b.iter_mut().enumerate().take(n + 1) {
        *x *= wk * inv_binomial(n, k);
        wk *= w;
    }
    // Binomial transform: bᵢ = Σₖ C(i, k)·dₖ.
    for i in 1..=n {
        for j in (i..=n).rev() {
            b[j] += b[j - 1];
        }
    }
    let r = lo.abs() + w;
    let size = c.iter().rev().fold(0.0, |s, a| s * r + a.abs());
    let unit = (n + 1) as f64 * f64::EPSILON * size;
    if !unit.is_finite() || b[0].abs() <= 64.0 * unit || b[n].abs() <= 64.0 * unit {
        return Fast::Undecided;
    }
    // Depth-first over pieces `[s0, s1]` of `[0, 1]`, left first; pending right halves wait
    // on a stack.
    let mut stack = [([0.0; M], 0.0f64, 0.0f64, 0usize); MAX_DEPTH];
    let mut top = 0;
    let (mut s0, mut s1, mut depth) = (0.0f64, 1.0f64, 0usize);
    for _ in 0..MAX_NODES {
        let margin = (64.0 + 2.0 * depth as f64) * unit;
        match variations(&b[..=n], margin) {
            Some(0) => {
                // No root here: the next pending piece.
                if top == 0 {
                    return Fast::NoRoot;
                }
                top -= 1;
                (b, s0, s1, depth) = stack[top];
                continue;
            }
            Some(1) => {
                let ta = if s0 == 0.0 { lo } else { lo + w * s0 };
                let tb = if s1 == 1.0 { hi } else { lo + w * s1 };
                let (fa, fb) = (horner(c, ta), horner(c, tb));
                if fb == 0.0 {
                    return Fast::Root(tb * p.scale);
                }
                if fa == 0.0 || (fa < 0.0) == (fb < 0.0) || (fa < 0.0) != (b[0] < 0.0) {
                    return Fast::Undecided;
                }
                return Fast::Root(false_position(c, ta, tb, fa, fb, 0.0) * p.scale);
            }
            _ => {}
        }
        if depth + 1 >= MAX_DEPTH {
            return Fast::Undecided;
        }
        // de Casteljau at SPLIT: the left half is the first entry of each row of the
        // triangle, the right half the last one.
        let mut tri = b;
        let mut right = [0.0; M];
        right[n] = tri[n];
        for k in 1..=n {
            for j in 0..=n - k {
                tri[j] += SPLIT * (tri[j + 1] - tri[j]);
            }
            b[k] = tri[0];
            right[n - k] = tri[n - k];
        }
        let sm = s0 + SPLIT * (s1 - s0);
        if b[n].abs() <= margin || !(sm > s0 && sm < s1) {
            return Fast::Undecided;
        }
        depth += 1;
        stack[top] = (right, sm, s1, depth);
        top += 1;
        s1 = sm;
    }
    Fast::Undecided
}
