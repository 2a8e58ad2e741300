//! Shared preparation of a polynomial before root isolation: validation, the scale-aware
//! leading-coefficient trimming rule, and an exact power-of-two rescaling of the variable so
//! that the roots have magnitude about one.

/// Most coefficients accepted (degree 16).
pub(crate) const MAX_COEFFS: usize = 17;

/// Relative size below which a leading term is rounding noise (one unit of round-off).
const TRIM_EPS: f64 = f64::EPSILON;

/// A validated, trimmed, rescaled polynomial `P(T) = p(scale·T) / norm` with the interval
/// `(lo, hi]` expressed in `T` (exactly: `scale` is a power of two).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Prepared {
    /// Coefficients of `P`, ascending; `c[n]` is the leading one, in `[1, 2)` in magnitude.
    pub c: [f64; MAX_COEFFS],
    /// Degree of `P`, at least 1.
    pub n: usize,
    /// `t = scale · T`; a power of two.
    pub scale: f64,
    /// Lower end of the interval in `T` (excluded), finite.
    pub lo: f64,
    /// Upper end of the interval in `T` (included), finite, `> lo`.
    pub hi: f64,
}

/// [`Prepared`] with exactly `D` coefficients (degree `D − 1`, nothing trimmed): the usual
/// case, made by [`prepare_fixed`] without the 17-entry array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Fixed<const D: usize> {
    /// Coefficients of `P`, ascending; `c[D − 1]`, the leading one, in `[1, 2)` in magnitude.
    pub c: [f64; D],
    /// `t = scale · T`; a power of two.
    pub scale: f64,
    /// Lower end of the interval in `T` (excluded), finite.
    pub lo: f64,
    /// Upper end of the interval in `T` (included), finite, `> lo`.
    pub hi: f64,
}

impl<const D: usize> Fixed<D> {
    /// The same polynomial and interval as a [`Prepared`].
    pub(crate) fn to_prepared(self) -> Prepared {
        let mut c = [0.0; MAX_COEFFS];
        c[..D].copy_from_slice(&self.c);
        Prepared {
            c,
            n: D - 1,
            scale: self.scale,
            lo: self.lo,
            hi: self.hi,
        }
    }
}

/// What [`prepare_fixed`] found.
pub(crate) enum Usual<const D: usize> {
    /// [`prepare`] gives `None` for this input (invalid: a non-finite coefficient or bound,
    /// or `lo ≥ hi`).
    Refused,
    /// The usual case: [`prepare`] gives exactly this (as [`Fixed::to_prepared`]).
    Fixed(Fixed<D>),
    /// Another case: ask [`prepare`].
    Other,
}

/// [`prepare`] for `D` coefficients (`2 ≤ D ≤ 17`) in its usual case: a non-zero leading
/// coefficient that the trimming rule keeps, on a bounded interval that sets the scale (the
/// shortcut of `scale`), with every power of two of the rescaling a normal number. The same
/// operations as [`prepare`]'s, so the same bits (tested).
#[inline(always)]
pub(crate) fn prepare_fixed<const D: usize>(coeffs: &[f64; D], lo: f64, hi: f64) -> Usual<D> {
    // Every coefficient finite, as `prepare`'s sum of `c·0` tests, without its chain of
    // dependent additions.
    let valid = lo < hi && coeffs.iter().fold(true, |ok, &c| ok & c.is_finite());
    if !valid {
        return Usual::Refused;
    }
    let n = D - 1;
    let r = lo.abs().max(hi.abs());
    let cn = coeffs[n];
    if cn == 0.0 || !r.is_finite() {
        return Usual::Other;
    }
    let er = exponent(r) + 1;
    let en = exponent(cn);
    let reaches = if r == 1.0 {
        // `trimmed_degree`'s and `scale`'s shortcuts for an interval reaching 1 (then
        // `e_R = 1`) test the same largest lower coefficient.
        let big = max_abs(&coeffs[..n]);
        if cn.abs() <= TRIM_EPS * big {
            return Usual::Other;
        }
        big != 0.0 && exponent(big) - en + 1 > 0
    } else {
        // `trimmed_degree(coeffs, n, r) != n`: the rule finds the leading term negligible
        // against some lower one (the same products, every term tested, no early exit).
        let (an, mut pow, mut negligible) = (cn.abs(), 1.0, false);
        for i in (0..n).rev() {
            pow *= r;
            negligible |= (coeffs[i] != 0.0) & (an * pow <= TRIM_EPS * coeffs[i].abs());
        }
        if negligible || !(-1000..=999).contains(&er) {
            return Usual::Other;
        }
        let reaches_at = |k: usize| {
            let ck = coeffs[n - k];
            (ck != 0.0) & (exponent(ck) - en + 1 > k as i32 * (er - 1))
        };
        if D > 5 {
            // Usually the first lower coefficient already reaches: stop there (a plain loop:
            // `Iterator::any` was left out of line).
            let mut reaches = false;
            for k in 1..D {
                if reaches_at(k) {
                    reaches = true;
                    break;
                }
            }
            reaches
        } else {
            // A few terms: all of them, without branches.
            let mut reaches = false;
            for k in 1..D {
                reaches |= reaches_at(k);
            }
            reaches
        }
    };
    // As in `rescale`, with both ends of the exponents normal.
    let (first, last) = (-(n as i32) * er - en, -en);
    if !reaches || !(-1022..=1023).contains(&first) || !(-1022..=1023).contains(&last) {
        return Usual::Other;
    }
    let mut c = *coeffs;
    for (j, cj) in c.iter_mut().enumerate() {
        let k = j as i32 * er + first;
        *cj *= f64::from_bits(((k + 1023) as u64) << 52);
    }
    // `1 / scale` is exact (a power of two of normal exponent), so multiplying by it rounds
    // like dividing by `scale`.
    let (scale, inv) = (mul_pow2(1.0, er), mul_pow2(1.0, -er));
    Usual::Fixed(Fixed {
        c,
        scale,
        lo: lo * inv,
        hi: hi * inv,
    })
}

/// The binary exponent of a finite non-zero `x` (`floor(log2 |x|)`, clamped for subnormals).
#[inline]
pub(crate) fn exponent(x: f64) -> i32 {
    (((x.to_bits() >> 52) & 0x7ff) as i32) - 1023
}

/// `x · 2^k`, exact unless the result under- or overflows, without intermediate overflow.
#[inline]
pub(crate) fn mul_pow2(mut x: f64, mut k: i32) -> f64 {
    if (-1022..=1023).contains(&k) {
        return x * f64::from_bits(((k + 1023) as u64) << 52);
    }
    while k != 0 {
        let step = k.clamp(-1000, 1000);
        x *= f64::from_bits(((step + 1023) as u64) << 52);
        k -= step;
    }
    x
}

/// `⌈d / k⌉` for `k > 0`, exact for either sign of `d`.
#[inline(always)]
fn ceil_div(d: i32, k: i32) -> i32 {
    -(-d).div_euclid(k)
}

/// `p(x)` by Horner's rule for ascending coefficients.
#[inline]
pub(crate) fn horner(c: &[f64], x: f64) -> f64 {
    let mut acc = 0.0;
    for &a in c.iter().rev() {
        acc = acc * x + a;
    }
    acc
}

/// Largest absolute value among the coefficients.
#[inline]
pub(crate) fn max_abs(c: &[f64]) -> f64 {
    // A plain comparison instead of `f64::max` (whose NaN rule costs a few instructions per
    // element): the same result, a NaN being skipped by both.
    c.iter()
        .fold(0.0f64, |m, &a| if a.abs() > m { a.abs() } else { m })
}

/// Validates and prepares `coeffs` on `(lo, hi]`; `None` when there can be no reportable root:
/// a non-finite coefficient or bound, `lo ≥ hi` (or NaN), the zero polynomial (every `t` is a
/// root; none is reported), a non-zero constant, more than 17 coefficients after dropping
/// trailing zeros, or an interval that holds no root by the Cauchy or Fujiwara bounds (the
/// interval is clipped to them).
///
/// Trimming rule (scale-aware): with `R = max(|lo|, |hi|)`, the leading coefficient `cₙ` is
/// treated as zero when, for some lower coefficient `cᵢ ≠ 0`, `|cₙ|·R^(n−i) ≤ ε·|cᵢ|`
/// (`ε` = `f64::EPSILON`): the leading term is then smaller than one rounding unit of another
/// term everywhere on the interval, so dropping it changes `p` by less than evaluating `p`
/// already does. The rule is repeated on the new leading coefficient. An infinite interval
/// trims only exact zeros (a tiny `cₙ` then means a huge but real root).
pub(crate) fn prepare(coeffs: &[f64], lo: f64, hi: f64) -> Option<Prepared> {
    // The sextic (the heart's ray polynomial) gets its own copy with every loop bound fixed,
    // so that the loops unroll and the divisions by `k` become multiplications.
    match <&[f64; 7]>::try_from(coeffs) {
        Ok(sextic) => prepare_in(sextic, lo, hi),
        Err(_) => prepare_in(coeffs, lo, hi),
    }
}

/// [`prepare`]'s body, inlined into each caller so that a fixed-size `coeffs` fixes its loops.
#[inline(always)]
fn prepare_in(coeffs: &[f64], lo: f64, hi: f64) -> Option<Prepared> {
    // `!(lo < hi)` also rejects NaN bounds. `c·0` is 0 for a finite `c` and NaN otherwise,
    // so one sum without branches tests every coefficient.
    let valid = lo < hi && coeffs.iter().fold(0.0, |acc, &c| acc + c * 0.0) == 0.0;
    if !valid {
        return None;
    }
    let n = coeffs.iter().rposition(|&c| c != 0.0)?;
    if n >= MAX_COEFFS {
        return None;
    }
    let r = lo.abs().max(hi.abs());
    let n = trimmed_degree(coeffs, n, r);
    if n == 0 {
        return None;
    }
    // The usual case, nothing trimmed from a sextic: a constant degree unrolls what follows.
    if coeffs.len() == 7 && n == 6 {
        return scale(&coeffs[..7], 6, r, lo, hi);
    }
    scale(coeffs, n, r, lo, hi)
}

/// The degree left of `coeffs[..=n]` (`coeffs[n] ≠ 0`) after the trimming rule of
/// [`prepare`] on an interval reaching `r = max(|lo|, |hi|)`; 0 when only a constant is left.
#[inline(always)]
fn trimmed_degree(coeffs: &[f64], mut n: usize, r: f64) -> usize {
    while n > 0 && r.is_finite() {
        let cn = coeffs[n].abs();
        let negligible = if r == 1.0 {
            // Every power of `r` is 1 (a chord parametrised over `[0, 1]`, the heart's
            // query): the rule compares `cₙ` with the largest lower coefficient only.
            cn <= TRIM_EPS * max_abs(&coeffs[..n])
        } else {
            let mut pow = 1.0;
            let mut negligible = false;
            for i in (0..n).rev() {
                pow *= r;
                if coeffs[i] != 0.0 && cn * pow <= TRIM_EPS * coeffs[i].abs() {
                    negligible = true;
                    break;
                }
            }
            negligible
        };
        if !negligible {
            break;
        }
        n -= 1;
        while n > 0 && coeffs[n] == 0.0 {
            n -= 1;
        }
    }
    n
}

/// The rest of [`prepare`] once the degree `n` is known (`coeffs[n] ≠ 0`, `n ≥ 1`; `r` is
/// `max(|lo|, |hi|)`): the power-of-two rescaling and the root bounds.
#[inline(always)]
fn scale(coeffs: &[f64], n: usize, r: f64, lo: f64, hi: f64) -> Option<Prepared> {
    // The common case on a bounded interval: some root may lie as far out as the interval
    // reaches (Fujiwara's exponent e_F is at least the interval's e_R = exponent(r) + 1). Then
    // e = e_R, and neither bound can clip: |lo|, |hi| < 2^e_R, while in T the Fujiwara bound
    // is at least 2 and Cauchy's at least 1. Testing ⌈d/k⌉ ≥ e_R as d > k·(e_R − 1) needs no
    // division. The result is the one `scale_general` gives (tested).
    if r.is_finite() {
        let er = exponent(r) + 1;
        if (-1000..=999).contains(&er) {
            let en = exponent(coeffs[n]);
            let reaches = if er == 1 {
                // Every threshold `k·(e_R − 1)` is 0: the largest lower coefficient decides
                // (the exponent grows with the magnitude).
                let big = max_abs(&coeffs[..n]);
                big != 0.0 && exponent(big) - en + 1 > 0
            } else {
                let mut reaches = false;
                for k in 1..=n {
                    let ck = coeffs[n - k];
                    reaches |= ck != 0.0 && exponent(ck) - en + 1 > k as i32 * (er - 1);
                }
                reaches
            };
            if reaches {
                let (c, scale) = rescale(coeffs, n, en, er);
                return Some(Prepared {
                    c,
                    n,
                    scale,
                    lo: lo / scale,
                    hi: hi / scale,
                });
            }
        }
    }
    scale_general(coeffs, n, r, lo, hi)
}

/// [`scale`] for every input: Fujiwara's estimate of the roots' size and both root bounds.
#[inline(always)]
fn scale_general(coeffs: &[f64], n: usize, r: f64, lo: f64, hi: f64) -> Option<Prepared> {
    // Fujiwara-style root-size estimate, in binary exponents only: 2^e ≳ max |c_{n-k}/c_n|^(1/k).
    let en = exponent(coeffs[n]);
    let mut e = i32::MIN;
    for k in 1..=n {
        let ck = coeffs[n - k];
        if ck != 0.0 {
            let d = exponent(ck) - en + 1;
            e = e.max(ceil_div(d, k as i32));
        }
    }
    if e == i32::MIN {
        e = 0; // p = cₙ·tⁿ: every root is 0; any scale works.
    }
    // Every root has |t| < 2^(e+1) (Fujiwara's bound, rounded up to a power of two).
    let bound_exp = e.saturating_add(1).clamp(-1000, 1000);
    // Use the interval's size instead when it is smaller: the Sturm sequence's coefficient
    // norms then measure the members' size where it matters, on the interval.
    if r.is_finite() {
        e = e.min(exponent(r) + 1);
    }
    let e = e.clamp(-1000, 1000);
    let (c, scale) = rescale(coeffs, n, en, e);
    let mut lo = lo / scale;
    let mut hi = hi / scale;
    // Cauchy's and Fujiwara's bounds: every root has |T| below both.
    let fujiwara = mul_pow2(1.0, bound_exp - e);
    let bound = (1.0 + max_abs(&c[..n]) / c[n].abs()).min(fujiwara);
    lo = lo.max(-bound);
    hi = hi.min(bound);
    if lo >= hi {
        return None;
    }
    Some(Prepared {
        c,
        n,
        scale,
        lo,
        hi,
    })
}

/// The coefficients of `p(2^e·T) / 2^en` (`en` the exponent of `coeffs[n]`, so the leading
/// one lands in `[1, 2)` in magnitude) and `2^e`; exact powers of two throughout.
#[inline(always)]
fn rescale(coeffs: &[f64], n: usize, en: i32, e: i32) -> ([f64; MAX_COEFFS], f64) {
    let mut c = [0.0; MAX_COEFFS];
    // c_j = coeffs_j · 2^(j·e − n·e − en); the exponent moves linearly in j, so when both
    // ends are normal exponents every factor is a plain power of two.
    let (first, last) = (-(n as i32) * e - en, -en);
    if (-1022..=1023).contains(&first) && (-1022..=1023).contains(&last) {
        for (j, cj) in c.iter_mut().enumerate().take(n + 1) {
            let k = j as i32 * e + first;
            *cj = coeffs[j] * f64::from_bits(((k + 1023) as u64) << 52);
        }
    } else {
        for (j, cj) in c.iter_mut().enumerate().take(n + 1) {
            *cj = mul_pow2(coeffs[j], j as i32 * e + first);
        }
    }
    (c, mul_pow2(1.0, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform_stream;

    #[test]
    fn mul_pow2_is_exact_and_safe() {
        assert_eq!(mul_pow2(3.0, 4), 48.0);
        assert_eq!(
            mul_pow2(1e-300, 1500),
            1e-300 * 2f64.powi(1000) * 2f64.powi(500)
        );
        assert_eq!(exponent(1.0), 0);
        assert_eq!(exponent(-3.0), 1);
        assert_eq!(exponent(0.75), -1);
    }

    #[test]
    fn ceil_div_rounds_up_for_both_signs() {
        for d in -40..=40 {
            for k in 1..=16 {
                assert_eq!(ceil_div(d, k), (f64::from(d) / f64::from(k)).ceil() as i32);
            }
        }
    }

    #[test]
    fn shortcut_agrees_with_the_general_scaling() {
        // Random polynomials of random degree, coefficient sizes and intervals (some holding
        // all the roots, some far smaller or larger than the roots' scale).
        let mut next = uniform_stream(0x2545_f491_4f6c_dd1d);
        let mut answered = 0;
        for _ in 0..20_000 {
            let n = 1 + (next() * 16.0) as usize;
            let mut c = [0.0; MAX_COEFFS];
            for cj in c.iter_mut().take(n + 1) {
                let size = 2f64.powi((next() * 40.0) as i32 - 20);
                *cj = if next() < 0.1 {
                    0.0
                } else {
                    (next() - 0.5) * size
                };
            }
            c[n] = if c[n] == 0.0 { 1.0 } else { c[n] };
            let (lo, hi) = match (next() * 4.0) as u32 {
                // The heart's chord (r = 1) and other intervals with r in [1, 2), which
                // take the shortcuts of `prepare_in` and `scale`.
                0 => (next() * 0.99, 1.0),
                1 => (-1.0 - next() * 0.99, next()),
                _ => {
                    let lo = (next() - 0.7) * 2f64.powi((next() * 30.0) as i32 - 15);
                    (lo, lo + next() * 2f64.powi((next() * 30.0) as i32 - 15))
                }
            };
            if lo >= hi {
                continue;
            }
            let r = lo.abs().max(hi.abs());
            let (fast, general) = (
                scale(&c[..=n], n, r, lo, hi),
                scale_general(&c[..=n], n, r, lo, hi),
            );
            assert_eq!(fast, general, "{:?} on ({lo}, {hi}]", &c[..=n]);
            answered += usize::from(fast.is_some());
        }
        assert!(answered > 1000);
    }

    /// `prepare_fixed::<D>` on `c` (of length `D`) against `prepare`.
    fn check_fixed<const D: usize>(c: &[f64], lo: f64, hi: f64) -> bool {
        let general = prepare(c, lo, hi);
        match prepare_fixed::<D>(c.try_into().expect("D coefficients"), lo, hi) {
            Usual::Refused => assert_eq!(general, None, "{c:?} on ({lo}, {hi}]"),
            Usual::Fixed(f) => {
                assert_eq!(Some(f.to_prepared()), general, "{c:?} on ({lo}, {hi}]");
                return true;
            }
            Usual::Other => {}
        }
        false
    }

    #[test]
    fn the_fixed_size_preparation_is_the_general_one() {
        // As above, with exact powers of two, zeros, non-finite values and empty intervals
        // mixed in; every length the fixed path takes.
        let mut next = uniform_stream(0x5851_f42d_4c95_7f2d);
        let mut fixed = 0;
        for i in 0..40_000 {
            let n = 1 + i % 16;
            let mut c = [0.0; MAX_COEFFS];
            for cj in c.iter_mut().take(n + 1) {
                let size = 2f64.powi((next() * 80.0) as i32 - 40);
                *cj = match (next() * 20.0) as u32 {
                    0 => 0.0,
                    1 => size,
                    2 if i % 7 == 0 => f64::NAN,
                    3 if i % 11 == 0 => f64::INFINITY,
                    _ => (next() - 0.5) * size,
                };
            }
            if next() < 0.1 {
                c[n] *= 1e-20;
            }
            let (lo, hi) = match (next() * 5.0) as u32 {
                0 => (0.0, 1.0),
                1 => (next() * 0.99, 1.0),
                2 => (next(), next()),
                3 => (0.0, f64::INFINITY),
                _ => {
                    let lo = (next() - 0.7) * 2f64.powi((next() * 60.0) as i32 - 30);
                    (lo, lo + next() * 2f64.powi((next() * 60.0) as i32 - 30))
                }
            };
            let c = &c[..=n];
            macro_rules! lengths {
                ($($d:literal)*) => {
                    match n + 1 {
                        $($d => check_fixed::<$d>(c, lo, hi),)*
                        _ => unreachable!(),
                    }
                };
            }
            fixed += usize::from(lengths!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17));
        }
        assert!(fixed > 8_000 && fixed < 36_000, "{fixed}");
    }

    #[test]
    fn trimming_on_the_unit_interval_follows_the_rule() {
        // Leading coefficients around ε times another one, on an interval reaching 1 (where
        // the powers of r are skipped): the degree left is the rule's, term by term.
        let mut next = uniform_stream(0x9e37_79b9_7f4a_7c15);
        let mut trimmed = 0;
        for _ in 0..20_000 {
            let n = 1 + (next() * 16.0) as usize;
            let mut c = [0.0; MAX_COEFFS];
            for cj in c.iter_mut().take(n) {
                *cj = if next() < 0.2 { 0.0 } else { next() - 0.5 };
            }
            let big = max_abs(&c[..n]);
            c[n] = (next() - 0.5) * 4.0 * f64::EPSILON * big.max(1e-300);
            let mut want = n;
            while want > 0 {
                let cn = c[want].abs();
                let negligible = (0..want).any(|i| c[i] != 0.0 && cn <= TRIM_EPS * c[i].abs());
                if cn != 0.0 && !negligible {
                    break;
                }
                want -= 1;
            }
            let got = trimmed_degree(&c[..=n], n, 1.0);
            assert_eq!(got, want, "{:?}", &c[..=n]);
            trimmed += usize::from(want < n);
        }
        assert!(trimmed > 1000 && trimmed < 19_000, "{trimmed}");
    }

    #[test]
    fn rejects_bad_input() {
        assert!(prepare(&[1.0, 1.0], 1.0, 1.0).is_none());
        assert!(prepare(&[1.0, 1.0], f64::NAN, 1.0).is_none());
        assert!(prepare(&[f64::NAN, 1.0], 0.0, 1.0).is_none());
        assert!(prepare(&[1.0, f64::INFINITY], 0.0, 1.0).is_none());
        let mut sextic = [1.0, -2.0, 0.5, 0.0, 3.0, -1.0, 2.0];
        assert!(prepare(&sextic, 0.0, 1.0).is_some());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for j in 0..7 {
                let keep = sextic[j];
                sextic[j] = bad;
                assert!(prepare(&sextic, 0.0, 1.0).is_none(), "{j}: {bad}");
                sextic[j] = keep;
            }
        }
        assert!(prepare(&[0.0, 0.0], 0.0, 1.0).is_none());
        assert!(prepare(&[2.0], 0.0, 1.0).is_none());
    }

    #[test]
    fn trims_a_negligible_leading_term_only_on_a_bounded_interval() {
        let p = prepare(&[-1.0, 1.0, 1e-30], 0.0, 10.0).unwrap();
        assert_eq!(p.n, 1);
        let p = prepare(&[-1.0, 1.0, 1e-30], 0.0, f64::INFINITY).unwrap();
        assert_eq!(p.n, 2);
    }
}
