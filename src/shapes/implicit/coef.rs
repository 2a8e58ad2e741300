//! Coefficients of the expanded polynomial: exact rationals (`i128 / i128`) as long as the
//! arithmetic fits, `f64` from the first operation that would overflow.
//!
//! Every integer and decimal written in an equation is a rational with a power-of-ten
//! denominator, so expansion is exact in most equations of interest; the single rounding to
//! `f64` happens when the surface is compiled for ray tracing.

use super::dd::Dd;
use std::cmp::Ordering;

/// A coefficient: an exact reduced fraction, or a floating-point approximation once exact
/// arithmetic would overflow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coef {
    /// `num / den`, reduced, `den > 0`.
    Exact(i128, i128),
    /// An approximation (exact arithmetic overflowed somewhere upstream).
    Approx(f64),
}

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The reduced fraction `n / d` (`d ≠ 0`), or `None` if normalising the sign overflows.
fn reduced(n: i128, d: i128) -> Option<Coef> {
    let g = gcd(n, d).max(1);
    let (mut n, mut d) = (n / g, d / g);
    if d < 0 {
        n = n.checked_neg()?;
        d = d.checked_neg()?;
    }
    Some(Coef::Exact(n, d))
}

impl Coef {
    /// Zero.
    pub const ZERO: Coef = Coef::Exact(0, 1);
    /// One.
    pub const ONE: Coef = Coef::Exact(1, 1);

    /// The integer `n`.
    pub fn int(n: i128) -> Coef {
        Coef::Exact(n, 1)
    }

    /// The nearest `f64`.
    pub fn to_f64(self) -> f64 {
        match self {
            Coef::Approx(v) => v,
            Coef::Exact(n, d) => {
                // One rounding when both parts have at most 53 bits (the usual case),
                // at most three otherwise.
                n as f64 / d as f64
            }
        }
    }

    /// The value to about 106 bits as a double-double (`hi` is the nearest `f64`, as
    /// [`Coef::to_f64`] gives when numerator and denominator fit in 53 bits).
    pub fn to_dd(self) -> Dd {
        match self {
            Coef::Approx(v) => Dd::from_f64(v),
            Coef::Exact(n, 1) => Dd::from_i128(n),
            Coef::Exact(n, d) => Dd::from_i128(n) / Dd::from_i128(d),
        }
    }

    /// True for an exact zero or a floating-point zero.
    pub fn is_zero(self) -> bool {
        match self {
            Coef::Exact(n, _) => n == 0,
            Coef::Approx(v) => v == 0.0,
        }
    }

    /// The value as an exact integer, if it is one.
    pub fn as_integer(self) -> Option<i128> {
        match self {
            Coef::Exact(n, 1) => Some(n),
            Coef::Exact(..) => None,
            Coef::Approx(v) => (v.fract() == 0.0 && v.abs() < 1e18).then_some(v as i128),
        }
    }

    /// The sign of the value.
    pub fn signum(self) -> Ordering {
        match self {
            Coef::Exact(n, _) => n.cmp(&0),
            Coef::Approx(v) => v.partial_cmp(&0.0).unwrap_or(Ordering::Equal),
        }
    }

    /// `-self`.
    pub fn negated(self) -> Coef {
        match self {
            Coef::Exact(n, d) => match n.checked_neg() {
                Some(m) => Coef::Exact(m, d),
                None => Coef::Approx(-self.to_f64()),
            },
            Coef::Approx(v) => Coef::Approx(-v),
        }
    }

    /// `self + o`.
    pub fn plus(self, o: Coef) -> Coef {
        if let (Coef::Exact(a, b), Coef::Exact(c, d)) = (self, o) {
            let g = gcd(b, d);
            let exact = (|| {
                let (bg, dg) = (b / g, d / g);
                let num = a.checked_mul(dg)?.checked_add(c.checked_mul(bg)?)?;
                let den = b.checked_mul(dg)?;
                reduced(num, den)
            })();
            if let Some(r) = exact {
                return r;
            }
        }
        Coef::Approx(self.to_f64() + o.to_f64())
    }

    /// `self − o`.
    pub fn minus(self, o: Coef) -> Coef {
        self.plus(o.negated())
    }

    /// `self · o`.
    pub fn times(self, o: Coef) -> Coef {
        if let (Coef::Exact(a, b), Coef::Exact(c, d)) = (self, o) {
            let exact = (|| {
                let g1 = gcd(a, d).max(1);
                let g2 = gcd(c, b).max(1);
                let num = (a / g1).checked_mul(c / g2)?;
                let den = (b / g2).checked_mul(d / g1)?;
                reduced(num, den)
            })();
            if let Some(r) = exact {
                return r;
            }
        }
        Coef::Approx(self.to_f64() * o.to_f64())
    }

    /// `self / o`, `o ≠ 0`.
    pub fn over(self, o: Coef) -> Coef {
        match o {
            Coef::Exact(n, d) => {
                let inv = if n < 0 {
                    n.checked_neg()
                        .and_then(|m| d.checked_neg().map(|e| Coef::Exact(e, m)))
                } else {
                    Some(Coef::Exact(d, n))
                };
                match inv {
                    Some(i) => self.times(i),
                    None => Coef::Approx(self.to_f64() / o.to_f64()),
                }
            }
            Coef::Approx(v) => Coef::Approx(self.to_f64() / v),
        }
    }

    /// `self^e` by repeated squaring.
    pub fn pow(self, mut e: u32) -> Coef {
        let mut base = self;
        let mut acc = Coef::ONE;
        while e > 0 {
            if e & 1 == 1 {
                acc = acc.times(base);
            }
            e >>= 1;
            if e > 0 {
                base = base.times(base);
            }
        }
        acc
    }

    /// The decimal literal `text` (digits, optional `.` fraction, optional `e±n` exponent),
    /// exactly when it fits, else as the nearest `f64`. `None` if it is not a number.
    pub fn parse_decimal(text: &str) -> Option<Coef> {
        let approx = text.parse::<f64>().ok().filter(|v| v.is_finite())?;
        let (mantissa, exp) = match text.find(['e', 'E']) {
            Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
            None => (text, 0),
        };
        let (int_part, frac_part) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        let exact = (|| {
            let digits = format!("{int_part}{frac_part}");
            let digits = digits.trim_start_matches('0');
            let mut n: i128 = if digits.is_empty() {
                0
            } else {
                digits.parse().ok()?
            };
            let scale = exp.checked_sub(i32::try_from(frac_part.len()).ok()?)?;
            let mut d: i128 = 1;
            if scale >= 0 {
                n = n.checked_mul(10i128.checked_pow(u32::try_from(scale).ok()?)?)?;
            } else {
                d = 10i128.checked_pow(u32::try_from(-scale).ok()?)?;
            }
            reduced(n, d)
        })();
        Some(exact.unwrap_or(Coef::Approx(approx)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_arithmetic_and_overflow_fallback() {
        let tenth = Coef::parse_decimal("0.1").unwrap();
        assert_eq!(tenth, Coef::Exact(1, 10));
        assert_eq!(tenth.plus(tenth).plus(tenth), Coef::Exact(3, 10));
        assert_eq!(Coef::parse_decimal("2.5e2").unwrap(), Coef::int(250));
        assert_eq!(Coef::parse_decimal("125e-3").unwrap(), Coef::Exact(1, 8));
        assert_eq!(Coef::parse_decimal(".5").unwrap(), Coef::Exact(1, 2));
        assert_eq!(Coef::int(9).over(Coef::int(-6)), Coef::Exact(-3, 2));
        let big = tenth.pow(40);
        assert!(matches!(big, Coef::Approx(_)));
        assert!((big.to_f64() - 1e-40).abs() < 1e-54);
        assert_eq!(Coef::int(3).pow(4), Coef::int(81));
        assert_eq!(Coef::int(3).pow(0), Coef::ONE);
        let ninth = Coef::int(9).over(Coef::int(80)).to_dd();
        assert_eq!(ninth.hi, 9.0 / 80.0);
        assert!(
            (ninth * Dd::from_f64(80.0) - Dd::from_f64(9.0))
                .to_f64()
                .abs()
                < 1e-30
        );
    }
}
