//! Equations that are a torus about the z axis: `k·((x² + y² + z² + a)² − b·(x² + y²))` with
//! `k ≠ 0` and `b > 0` (the `torus R r` preset has `a = R² − r²`, `b = 4R²`; spindle and horn
//! tori too). Their ray polynomial has a closed form, cheaper than the general composition:
//! along `m + s·e`, `q(s) = |m + s·e|² + a` and `w(s) = (m_x + s·e_x)² + (m_y + s·e_y)²` are
//! quadratics and the quartic is `k·(q² − b·w)`.
//!
//! Rounding: every coefficient is a sum of at most a few products of `m`, `e`, `a` and `b`,
//! each rounded a few times; its error is a few `ε` times `(|m|² + |a|)²`-sized terms, within
//! the few-times-`ε`-per-unit-of-`Σ|terms|` the generic composition is assumed to have (the
//! expanded torus's `Σ|terms|` at a point is within a factor 3 of `(|p|² + |a|)² + b·(x² +
//! y²)`), so the solver's and the re-solve's bounds hold unchanged.

use super::coef::Coef;
use super::poly::{Exps, Lanes, Poly, Uni, LANES};
use std::ops::{Add, Mul, Sub};

/// The torus of an equation: its polynomial is `k·((x² + y² + z² + a)² − b·(x² + y²))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorusForm {
    /// The constant inside the square (`R² − r²` for a ring torus).
    pub a: f64,
    /// The factor of `x² + y²` (`4R²`; greater than 0).
    pub b: f64,
    /// The overall factor (not 0).
    pub k: f64,
}

impl TorusForm {
    /// The ray polynomial along `m + s·e` (object space), ascending, into `out[..=4]`
    /// (entries above are left as they are).
    #[inline(always)]
    pub fn compose(&self, m: [f64; 3], e: [f64; 3], out: &mut Uni) {
        out[..5].copy_from_slice(&self.coefficients(m, e));
    }

    /// [`TorusForm::compose`] of [`LANES`] rays (ray `i` is `m[axis][i] + s·e[axis][i]`)
    /// into `out[..=4]` by power (the same bits as one at a time; entries above are left as
    /// they are). One operation across the lanes at a time, so that each coefficient is
    /// stored whole.
    #[inline(always)]
    pub fn compose_lanes(
        &self,
        m: &[[f64; LANES]; 3],
        e: &[[f64; LANES]; 3],
        out: &mut [[f64; LANES]],
    ) {
        let constants = [self.a, self.b, self.k].map(Lanes::splat);
        let c = quartic(m.map(Lanes), e.map(Lanes), constants, Lanes::splat(2.0));
        for (o, c) in out.iter_mut().zip(c) {
            *o = c.0;
        }
    }

    /// The ray polynomial's five coefficients along `m + s·e`, ascending.
    #[inline(always)]
    fn coefficients(&self, m: [f64; 3], e: [f64; 3]) -> [f64; 5] {
        quartic(m, e, [self.a, self.b, self.k], 2.0)
    }
}

/// The torus `[a, b, k]`'s ray quartic along `m + s·e`, ascending, in the arithmetic `T`
/// (`f64`, or lanes of `f64` with the same bits in each lane); `two` is 2.
#[inline(always)]
fn quartic<T>(m: [T; 3], e: [T; 3], [a, b, k]: [T; 3], two: T) -> [T; 5]
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let q0 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2] + a;
    let q1 = two * (m[0] * e[0] + m[1] * e[1] + m[2] * e[2]);
    let q2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    let w0 = m[0] * m[0] + m[1] * m[1];
    let w1 = two * (m[0] * e[0] + m[1] * e[1]);
    let w2 = e[0] * e[0] + e[1] * e[1];
    [
        k * (q0 * q0 - b * w0),
        k * (two * q0 * q1 - b * w1),
        k * (q1 * q1 + two * q0 * q2 - b * w2),
        k * (two * q1 * q2),
        k * (q2 * q2),
    ]
}

impl TorusForm {
    /// `∇f` at the object-space point `p` and, for each component, a bound on the size of
    /// the terms it sums (which its rounding is a few `ε` of).
    #[inline]
    pub fn gradient_with_bound(&self, p: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let s = r2 + self.a;
        let side = self.k * (4.0 * s - 2.0 * self.b);
        let up = self.k * (4.0 * s);
        let s_size = r2 + self.a.abs();
        let side_size = self.k.abs() * (4.0 * s_size + 2.0 * self.b);
        let up_size = self.k.abs() * (4.0 * s_size);
        (
            [side * p[0], side * p[1], up * p[2]],
            [
                side_size * p[0].abs(),
                side_size * p[1].abs(),
                up_size * p[2].abs(),
            ],
        )
    }
}

/// The torus form of `poly`, when it is exactly (in its exact rational coefficients) one of
/// the module doc's; `None` otherwise.
pub fn recognise(poly: &Poly) -> Option<TorusForm> {
    let coef = |e: Exps| poly.terms.get(&e).copied();
    let k = coef([0, 0, 4])?;
    if k.is_zero() {
        return None;
    }
    // 2a·k·z² and k·(2a − b)·x².
    let a = coef([0, 0, 2])
        .unwrap_or(Coef::ZERO)
        .over(k.times(Coef::int(2)));
    let two_a = a.times(Coef::int(2));
    let b = two_a.minus(coef([2, 0, 0]).unwrap_or(Coef::ZERO).over(k));
    if !matches!(b, Coef::Exact(n, _) if n > 0) || !matches!(a, Coef::Exact(..)) {
        return None;
    }
    let inner = Poly::sum(&[
        Poly::monomial([2, 0, 0], Coef::ONE),
        Poly::monomial([0, 2, 0], Coef::ONE),
        Poly::monomial([0, 0, 2], Coef::ONE),
        Poly::monomial([0, 0, 0], a),
    ]);
    let ring = Poly::sum(&[Poly::monomial([2, 0, 0], b), Poly::monomial([0, 2, 0], b)]);
    let candidate = inner.mul(&inner).add(&ring, true).scale(k);
    if candidate != *poly {
        return None;
    }
    let form = TorusForm {
        a: a.to_f64(),
        b: b.to_f64(),
        k: k.to_f64(),
    };
    (form.a.is_finite() && form.b.is_finite() && form.k.is_finite() && form.k != 0.0)
        .then_some(form)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::{expand, poly::Compiled, preset_equation};

    fn form(equation: &str) -> Option<TorusForm> {
        recognise(&expand(equation).unwrap())
    }

    #[test]
    fn tori_are_recognised_and_composed_as_the_expansion_composes() {
        let ring = preset_equation("torus", &[1.0, 0.3]).unwrap();
        let horn = preset_equation("torus", &[0.5, 0.7]).unwrap();
        for (equation, scale) in [
            (ring.as_str(), 1.0),
            (horn.as_str(), 1.0),
            ("3*((x^2 + y^2 + z^2 + 0.5)^2 - 2*(x^2 + y^2))", 3.0),
            ("(x^2 + y^2 + z^2)^2 = x^2 + y^2", 1.0),
        ] {
            let found = form(equation).unwrap_or_else(|| panic!("{equation}"));
            assert_eq!(found.k, scale, "{equation}");
            let f = Compiled::new(&expand(equation).unwrap());
            for (m, e) in [
                ([0.3, -0.4, 0.2], [0.5, 0.1, -0.3]),
                ([1.1, 0.2, -0.1], [-0.2, 0.9, 0.4]),
                ([-0.7, 0.6, 0.05], [0.01, -0.02, 1.3]),
            ] {
                let mut closed = [0.0; crate::shapes::implicit::MAX_DEGREE + 1];
                found.compose(m, e, &mut closed);
                let general = f.compose(m, e);
                for (c, g) in closed.iter().zip(&general) {
                    let size = general.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                    assert!(
                        (c - g).abs() <= 1e-14 * size,
                        "{equation}: {closed:?} {general:?}"
                    );
                }
                // The gradient, against the expansion's partial derivatives.
                let poly = expand(equation).unwrap();
                let (g, bound) = found.gradient_with_bound(m);
                for (v, (gv, bv)) in g.iter().zip(&bound).enumerate() {
                    let partial = Compiled::new(&poly.derivative(v));
                    let (want, size) = partial.eval_with_bound(m);
                    assert!(
                        (gv - want).abs() <= 1e-14 * size.max(1e-300),
                        "{equation}: ∂{v}"
                    );
                    assert!(
                        *bv >= gv.abs() && *bv <= 8.0 * size + 1e-300,
                        "{equation}: ∂{v}"
                    );
                }
            }
        }
    }

    #[test]
    fn four_rays_compose_as_each_alone_bit_for_bit() {
        let form = TorusForm {
            a: 0.91,
            b: 4.0,
            k: -1.5,
        };
        let mut next = crate::testing::uniform_stream(0x4f1b_bd9c_2e8a_57e3);
        for _ in 0..200 {
            let mut v = || 4.0 * next() - 2.0;
            let m: [[f64; LANES]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| v()));
            let e: [[f64; LANES]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| v()));
            let mut out = [[f64::NAN; LANES]; 6];
            form.compose_lanes(&m, &e, &mut out);
            for i in 0..LANES {
                let mut alone = [f64::NAN; crate::shapes::implicit::MAX_DEGREE + 1];
                form.compose(
                    [m[0][i], m[1][i], m[2][i]],
                    [e[0][i], e[1][i], e[2][i]],
                    &mut alone,
                );
                for k in 0..5 {
                    assert_eq!(out[k][i].to_bits(), alone[k].to_bits(), "{k}, {i}");
                }
                // Entries above the degree are left as they were.
                assert!(out[5][i].is_nan() && alone[5].is_nan());
            }
        }
    }

    #[test]
    fn near_misses_are_not_tori() {
        for equation in [
            // x² and y² weighted differently.
            "(x^2 + y^2 + z^2 + 0.91)^2 - 4*x^2 - 3.9*y^2",
            // b ≤ 0: no hole (a sphere-like quartic).
            "(x^2 + y^2 + z^2 - 1)^2 + x^2 + y^2",
            // Another axis.
            "(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + z^2)",
            // An extra term.
            "(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2) + x*y",
            // Not a quartic of this kind.
            "x^2 + y^2 + z^2 - 1",
            "(x^2 + y^2 + z^2)^8 - 1",
        ] {
            assert_eq!(form(equation), None, "{equation}");
        }
    }
}
