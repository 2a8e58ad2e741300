//! Double-double arithmetic: a number is the unevaluated sum `hi + lo` of two `f64`s with
//! `|lo| ≤ ulp(hi)/2`, about 106 bits of precision.
//!
//! Used only where `f64` cannot resolve the surface: around a root of the ray polynomial that
//! is ill-conditioned in `f64` (a multiple root or a cluster of roots, where the polynomial is
//! below its own rounding over a stretch of the ray), and for the gradient where it is below
//! its rounding. The error of a sum or product is at most a small multiple of `2⁻¹⁰⁴` times
//! the magnitudes of the operands (not of the result), which is what the rounding bounds of
//! the callers assume.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// `hi + lo`, normalised so that `hi` is the nearest `f64` to the sum.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd {
    /// The leading part: the value rounded to `f64`.
    pub hi: f64,
    /// The remainder, at most half an ulp of `hi`.
    pub lo: f64,
}

/// `a + b` exactly, as the rounded sum and its error (Knuth's two-sum).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a + b` exactly when `|a| ≥ |b|` (or `a = 0`), as the rounded sum and its error.
#[inline]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// `a · b` exactly, as the rounded product and its error (with a fused multiply-add).
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl Dd {
    /// Zero.
    pub const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };

    /// The `f64` `x`, exactly.
    #[inline]
    pub const fn from_f64(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }

    /// The integer `n` to 106 bits (exactly when `|n| < 2¹⁰⁶`).
    pub fn from_i128(n: i128) -> Dd {
        let hi = n as f64;
        // `hi` rounds `n` to 53 bits; the remainder is exact in i128 unless `hi` is 2¹²⁷.
        let lo = if hi.abs() < 1.7e38 {
            n.wrapping_sub(hi as i128) as f64
        } else {
            0.0
        };
        let (hi, lo) = quick_two_sum(hi, lo);
        Dd { hi, lo }
    }

    /// The value rounded to `f64`.
    #[inline]
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// `|self|`.
    #[inline]
    pub fn abs(self) -> Dd {
        if self.hi < 0.0 {
            -self
        } else {
            self
        }
    }
}

impl Add for Dd {
    type Output = Dd;
    #[inline]
    fn add(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let (s, e) = quick_two_sum(s, e + t);
        let (hi, lo) = quick_two_sum(s, e + f);
        Dd { hi, lo }
    }
}

impl Div for Dd {
    type Output = Dd;
    /// `self / o` to about 106 bits (`o ≠ 0`).
    fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self - o * Dd::from_f64(q1);
        let q2 = r.hi / o.hi;
        let r = r - o * Dd::from_f64(q2);
        let q3 = r.hi / o.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        Dd { hi, lo } + Dd::from_f64(q3)
    }
}

impl Sub for Dd {
    type Output = Dd;
    #[inline]
    fn sub(self, o: Dd) -> Dd {
        self + (-o)
    }
}

impl Neg for Dd {
    type Output = Dd;
    #[inline]
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Mul for Dd {
    type Output = Dd;
    #[inline]
    fn mul(self, o: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, o.hi);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_keeps_about_106_bits() {
        // 1/3 · 3 − 1 vanishes far below f64's rounding.
        let third = Dd::from_f64(1.0) / Dd::from_f64(3.0);
        let r = third * Dd::from_f64(3.0) - Dd::from_f64(1.0);
        assert!(r.to_f64().abs() < 1e-31, "{r:?}");
        // (1 + 2⁻³⁰)² − 1 − 2⁻²⁹ = 2⁻⁶⁰, lost by the f64 product.
        let a = Dd::from_f64(1.0 + 2f64.powi(-30));
        let r = a * a - Dd::from_f64(1.0) - Dd::from_f64(2f64.powi(-29));
        assert_eq!(r.to_f64(), 2f64.powi(-60));
        assert_eq!(a.hi * a.hi - 1.0 - 2f64.powi(-29), 0.0);
        // Exact integers beyond 2⁵³, and a fraction that f64 cannot hold.
        let n = (1i128 << 80) + 12345;
        let d = Dd::from_i128(n);
        assert_eq!(d.hi as i128 + d.lo as i128, n);
        let tenth = Dd::from_i128(1) / Dd::from_i128(10);
        let back = tenth * Dd::from_f64(10.0) - Dd::from_f64(1.0);
        assert!(back.to_f64().abs() < 1e-31);
        assert_eq!(tenth.hi, 0.1);
        assert!(tenth.lo != 0.0);
        assert_eq!((-tenth).abs(), tenth);
    }
}
