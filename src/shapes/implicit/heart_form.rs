//! Equations that are the paper's heart in other coordinates.
//!
//! `k·((a·x² + b·y² + z² − 1)³ − (p·x² + q·y²)·z³)` with `k, a, b > 0` is the paper's heart
//! `(2X² + Y² + Z² − 1)³ − (0.1X² + Y²)·Z³` stretched along x and y when `p = a/20` and
//! `q = b` (`x = √(2/a)·X`, `y = Y/√b`, `z = Z`), and stretched with x and y swapped when
//! `p = a` and `q = b/20` (`x = Y/√a`, `y = √(2/b)·X`): Taubin's heart
//! `(x² + 9/4·y² + z² − 1)³ − x²z³ − 9/80·y²z³` is the second kind. Such a surface is traced
//! through the heart's own path (its factorisation `g = A − ∛B·Z` has no multiple roots
//! where `f` has them), in heart space.

use super::coef::Coef;
use super::poly::{Exps, Poly};
use crate::geometry::DMat3;

/// How an equation's polynomial is the paper's heart: `f(p) = scale · heart(H)` at the
/// heart-space point `H` with `p = to_object · H`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeartForm {
    /// The object-space (equation) point of a heart-space point: an invertible map that
    /// stretches the axes (and may swap x and y).
    pub to_object: DMat3,
    /// The factor between the equation's polynomial and the heart's (greater than 0).
    pub scale: f64,
}

impl HeartForm {
    /// True when the equation is the paper's heart itself (no change of coordinates, factor 1).
    pub fn is_identity(&self) -> bool {
        self.to_object == DMat3::IDENTITY && self.scale == 1.0
    }
}

/// The heart form of `poly`, when it is exactly (in its exact rational coefficients) one of
/// the two kinds of stretched heart in the module doc; `None` otherwise.
pub fn recognise(poly: &Poly) -> Option<HeartForm> {
    let coef = |e: Exps| poly.terms.get(&e).copied();
    let positive = |c: Coef| matches!(c, Coef::Exact(n, _) if n > 0);
    let k = coef([0, 0, 0])?.negated();
    if !positive(k) {
        return None;
    }
    // (a x² + b y² + z² − 1)³ has 3a·x², 3b·y² and 3·z²; the z³ part gives −p·x²z³, −q·y²z³.
    let k3 = k.times(Coef::int(3));
    let a = coef([2, 0, 0])?.over(k3);
    let b = coef([0, 2, 0])?.over(k3);
    let p = coef([2, 0, 3])?.over(k).negated();
    let q = coef([0, 2, 3])?.over(k).negated();
    if coef([0, 0, 2])?.over(k3) != Coef::ONE || ![a, b, p, q].into_iter().all(positive) {
        return None;
    }
    let big_a = Poly::sum(&[
        Poly::monomial([2, 0, 0], a),
        Poly::monomial([0, 2, 0], b),
        Poly::monomial([0, 0, 2], Coef::ONE),
        Poly::monomial([0, 0, 0], Coef::int(-1)),
    ]);
    let big_b = Poly::sum(&[Poly::monomial([2, 0, 0], p), Poly::monomial([0, 2, 0], q)]);
    let cubed = big_a.mul(&big_a).mul(&big_a);
    let candidate = cubed
        .add(&big_b.mul(&Poly::monomial([0, 0, 3], Coef::ONE)), true)
        .scale(k);
    if candidate != *poly {
        return None;
    }
    let twentieth = Coef::Exact(1, 20);
    let (a_f, b_f) = (a.to_f64(), b.to_f64());
    let to_object = if p.over(a) == twentieth && q == b {
        // x = √(2/a)·X, y = Y/√b.
        DMat3::from_diagonal([(2.0 / a_f).sqrt(), 1.0 / b_f.sqrt(), 1.0].into())
    } else if p == a && q.over(b) == twentieth {
        // x = Y/√a, y = √(2/b)·X: the columns are the images of X, Y and Z.
        DMat3::from_cols(
            [0.0, (2.0 / b_f).sqrt(), 0.0].into(),
            [1.0 / a_f.sqrt(), 0.0, 0.0].into(),
            [0.0, 0.0, 1.0].into(),
        )
    } else {
        return None;
    };
    let scale = k.to_f64();
    (to_object.is_finite() && scale.is_finite() && to_object.determinant() != 0.0)
        .then_some(HeartForm { to_object, scale })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DVec3;
    use crate::shapes::heart::heart_fn;
    use crate::shapes::implicit::{expand, poly::Compiled};

    fn form(equation: &str) -> Option<HeartForm> {
        recognise(&expand(equation).unwrap())
    }

    #[test]
    fn stretched_and_swapped_hearts_are_recognised_with_their_map() {
        let heart = form(crate::shapes::implicit::HEART_EQUATION).unwrap();
        assert!(heart.is_identity());
        for (equation, scale) in [
            // Taubin's heart (x and y swapped), as its preset writes it and scaled.
            ("(x^2 + 9/4*y^2 + z^2 - 1)^3 - x^2*z^3 - 9/80*y^2*z^3", 1.0),
            (
                "3*(x^2 + 9/4*y^2 + z^2 - 1)^3 = 3*(x^2 + 9/80*y^2)*z^3",
                3.0,
            ),
            // The heart half as wide in x and twice as deep in y.
            ("(8x^2 + 0.25y^2 + z^2 - 1)^3 - (0.4x^2 + 0.25y^2)*z^3", 1.0),
            // The same, x and y swapped.
            ("(0.25x^2 + 8y^2 + z^2 - 1)^3 - (0.25x^2 + 0.4y^2)*z^3", 1.0),
            // The paper's heart typed otherwise.
            ("(2x^2 + y^2 + z^2 - 1)^3 = (0.1x^2 + y^2) z^3", 1.0),
        ] {
            let found = form(equation).unwrap_or_else(|| panic!("{equation}"));
            assert_eq!(found.scale, scale, "{equation}");
            // f(L·H) = scale · heart(H) at heart-space points.
            let f = Compiled::new(&expand(equation).unwrap());
            for h in [
                DVec3::new(0.3, -0.4, 0.2),
                DVec3::new(-0.6, 0.9, 1.1),
                DVec3::new(0.1, 0.2, -0.8),
            ] {
                let (lhs, rhs) = (
                    f.eval((found.to_object * h).to_array()),
                    scale * heart_fn(h),
                );
                assert!(
                    (lhs - rhs).abs() < 1e-12 * (1.0 + rhs.abs()),
                    "{equation}: {lhs} {rhs}"
                );
            }
        }
    }

    #[test]
    fn near_misses_are_not_hearts() {
        for equation in [
            // p/a not 1/20 (nor p = a).
            "(2x^2 + y^2 + z^2 - 1)^3 - (0.1001x^2 + y^2)*z^3",
            // q ≠ b.
            "(2x^2 + y^2 + z^2 - 1)^3 - (0.1x^2 + 1.5y^2)*z^3",
            // z² not with coefficient 1 inside the cube.
            "(2x^2 + y^2 + 2z^2 - 1)^3 - (0.1x^2 + y^2)*z^3",
            // A negative factor (inside and outside swapped).
            "-(2x^2 + y^2 + z^2 - 1)^3 + (0.1x^2 + y^2)*z^3",
            // The z³ part with the other sign.
            "(2x^2 + y^2 + z^2 - 1)^3 + (0.1x^2 + y^2)*z^3",
            // An extra term.
            "(2x^2 + y^2 + z^2 - 1)^3 - (0.1x^2 + y^2)*z^3 + x*y*z",
            // z along another axis.
            "(2x^2 + z^2 + y^2 - 1)^3 - (0.1x^2 + z^2)*y^3",
            // Not a sextic at all.
            "x^2 + y^2 + z^2 - 1",
        ] {
            assert_eq!(form(equation), None, "{equation}");
        }
    }
}
