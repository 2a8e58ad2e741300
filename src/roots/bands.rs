//! Intervals too wide for one scale: the preparation (`prep`) rescales the variable by one
//! power of two, so that the interval (or the roots, if smaller) has size about one. When the
//! polynomial's terms span more than `f64` can hold at that one scale, some coefficient
//! under- or overflows there (it *loses a term*: `9 − 6·10¹⁴⁰t² + 10²⁸⁰t⁴ + 10¹⁴⁰t⁹` on
//! `(−1.5·10²⁸, 2.25·10²⁸]` loses its constant term, which decides the roots near 10⁻⁷⁰).
//!
//! Such an interval is cut into *parts*, each prepared at its own scale: first at 0 (so roots
//! of opposite signs are never in one part), then each side into bands of magnitude whose
//! ends differ by about 2³², from the far end toward 0, until the part next to 0 loses no
//! term. On a band the terms that fall outside `f64` at its scale are below 2⁻⁴⁰⁰ of the
//! largest one everywhere on it (the band's near end is at least 2⁻³³ of its scale and the
//! degree at most 16), so they change no value. Each cut is a power of two where the
//! polynomial's sign is certain (one of a few near the ideal cut), so no root sits on a cut
//! within rounding. An interval that loses no term is one part: the usual case, unchanged.

use super::prep::{exponent, mul_pow2, prepare, Prepared, MAX_COEFFS};

/// Most parts: the exponent range of `f64` (about 2100 binades) in bands of 32, per side.
const MAX_PARTS: usize = 2 * 72;

/// Binades between the cuts of a side.
const BAND: i32 = 32;

/// Whether the preparation `p` of `coeffs` lost a term: a non-zero coefficient of degree at
/// most `p.n` that became zero or subnormal (overflow cannot happen: see `prep`).
pub(crate) fn loses_terms(coeffs: &[f64], p: &Prepared) -> bool {
    coeffs
        .iter()
        .zip(&p.c[..=p.n])
        .any(|(&c, &s)| c != 0.0 && !s.is_normal())
}

/// Calls `visit` with the preparation of each part of `(lo, hi]` in ascending order (see the
/// module documentation) until it returns `false`; parts that hold no root by `prepare` are
/// skipped. Returns `false` when `visit` stopped. No heap allocation.
pub(crate) fn each(
    coeffs: &[f64],
    lo: f64,
    hi: f64,
    visit: &mut dyn FnMut(Prepared) -> bool,
) -> bool {
    let Some(p) = prepare(coeffs, lo, hi) else {
        return true;
    };
    if !loses_terms(coeffs, &p) {
        return visit(p);
    }
    if lo < 0.0 && hi > 0.0 {
        return side(coeffs, lo, 0.0, visit) && side(coeffs, 0.0, hi, visit);
    }
    side(coeffs, lo, hi, visit)
}

/// [`each`] on an interval that does not contain 0 inside (`lo ≥ 0` or `hi ≤ 0`).
fn side(coeffs: &[f64], lo: f64, hi: f64, visit: &mut dyn FnMut(Prepared) -> bool) -> bool {
    let positive = lo >= 0.0;
    // Cuts from the far end toward 0; `cuts[0]` is the far end itself.
    let mut cuts = [0.0f64; MAX_PARTS + 1];
    cuts[0] = if positive { hi } else { lo };
    let mut count = 1;
    while count <= MAX_PARTS {
        let far = cuts[count - 1];
        // The part from 0's end to the last cut.
        let (a, b) = if positive { (lo, far) } else { (far, hi) };
        match prepare(coeffs, a, b) {
            None => break,
            Some(p) if !loses_terms(coeffs, &p) => break,
            Some(_) => {}
        }
        let Some(cut) = clean_cut(coeffs, far, a, b) else {
            break;
        };
        cuts[count] = cut;
        count += 1;
    }
    // Parts in ascending order: toward 0 on the negative side, away from it on the other.
    for k in 0..count {
        let (a, b) = if positive {
            let i = count - 1 - k;
            (if i + 1 < count { cuts[i + 1] } else { lo }, cuts[i])
        } else {
            (cuts[k], if k + 1 < count { cuts[k + 1] } else { hi })
        };
        let Some(p) = prepare(coeffs, a, b) else {
            continue;
        };
        if !visit(p) {
            return false;
        }
    }
    true
}

/// A cut about `2⁻³²·|far|` strictly inside `(a, b)`, with the sign of `far`: the first power
/// of two near it where the polynomial's sign is certain, else the nearest one; `None` when
/// none is inside (the part is then taken whole).
fn clean_cut(coeffs: &[f64], far: f64, a: f64, b: f64) -> Option<f64> {
    let k = exponent(far) - BAND;
    let sign = far.signum();
    let inside = |x: f64| x > a && x < b;
    let mut fallback = None;
    for step in [0, -1, 1, -2, 2, -3, 3, -4, 4] {
        let x = sign * mul_pow2(1.0, k + step);
        if !inside(x) || x == 0.0 {
            continue;
        }
        if certain_sign_at_power_of_two(coeffs, k + step, sign < 0.0) {
            return Some(x);
        }
        fallback.get_or_insert(x);
    }
    fallback
}

/// Whether `p(±2ᵏ)` has a certain sign: its value beyond `8·(n+1)·ε` times the sum of its
/// terms' sizes, the terms computed exactly, scaled together so none overflows.
fn certain_sign_at_power_of_two(coeffs: &[f64], k: i32, negative: bool) -> bool {
    let n = coeffs.len().min(MAX_COEFFS);
    let top = coeffs[..n]
        .iter()
        .enumerate()
        .filter(|(_, c)| **c != 0.0)
        .map(|(j, c)| exponent(*c) + j as i32 * k)
        .max();
    let Some(top) = top else {
        return false;
    };
    let (mut sum, mut size) = (0.0f64, 0.0f64);
    for (j, &c) in coeffs[..n].iter().enumerate() {
        let t = mul_pow2(c, j as i32 * k - top);
        let t = if negative && j % 2 == 1 { -t } else { t };
        sum += t;
        size += t.abs();
    }
    sum.abs() > 8.0 * n as f64 * f64::EPSILON * size
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts `each` visits, as `(lo, hi)` in `t`.
    fn parts(coeffs: &[f64], lo: f64, hi: f64) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        each(coeffs, lo, hi, &mut |p| {
            out.push((p.lo * p.scale, p.hi * p.scale));
            true
        });
        out
    }

    #[test]
    fn an_interval_one_scale_holds_is_one_part() {
        let c = [-6.0, 11.0, -6.0, 1.0];
        assert_eq!(parts(&c, -10.0, 10.0).len(), 1);
        let p = prepare(&c, -10.0, 10.0).unwrap();
        assert!(!loses_terms(&c, &p));
    }

    #[test]
    fn a_term_lost_at_the_interval_scale_cuts_at_zero_and_into_bands() {
        let c = [9.0, 0.0, -6e140, 0.0, 1e280, 0.0, 0.0, 0.0, 0.0, 1e140];
        let p = prepare(&c, -1.5e28, 2.25e28).unwrap();
        assert!(loses_terms(&c, &p), "{p:?}");
        let got = parts(&c, -1.5e28, 2.25e28);
        assert!(got.len() > 2, "{got:?}");
        // Ascending, disjoint, meeting at 0; the parts next to 0 lose no term (the far bands
        // may lose terms that are negligible all over them, as the constant 9 is near 1e28).
        for w in got.windows(2) {
            assert!(w[0].1 <= w[1].0, "{got:?}");
        }
        assert!(got.iter().any(|&(_, b)| b == 0.0), "{got:?}");
        for &(a, b) in got.iter().filter(|&&(a, b)| a == 0.0 || b == 0.0) {
            let p = prepare(&c, a, b).unwrap();
            assert!(!loses_terms(&c, &p), "({a}, {b}]");
        }
    }

    #[test]
    fn a_cut_avoids_a_root() {
        // A root exactly at the ideal cut 2⁻³²·2⁶⁰ = 2²⁸: the cut moves off it.
        let r = 2f64.powi(28);
        let c = [-r, 1.0];
        assert!(!certain_sign_at_power_of_two(&c, 28, false));
        assert!(certain_sign_at_power_of_two(&c, 27, false));
        let cut = clean_cut(&c, 2f64.powi(60), 0.0, 2f64.powi(60)).unwrap();
        assert_eq!(cut, 2f64.powi(27));
        let cut = clean_cut(&[r, 1.0], -(2f64.powi(60)), -(2f64.powi(60)), 0.0).unwrap();
        assert_eq!(cut, -(2f64.powi(27)));
    }
}
