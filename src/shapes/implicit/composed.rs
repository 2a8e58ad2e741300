//! Equations that are a power of one sub-expression shifted by a constant, `f = a·Pⁿ + c`
//! (`(x^2+y^2-1)^8 - 1e-12`, `(x+y+z+1)^16 = 1`, `2 - 3*(x^2+y^2+z^2)^4`), recognised from
//! the syntax tree at load, with the real roots `r` of `h(s) = a·sⁿ + c`.
//!
//! Such a surface is the union of the level sets `P = r`, and those are what a ray should
//! meet: along a ray, each real root of `h(P(t))` is a root of `P(t) = r`, and the other
//! `n − 1` (complex) roots of `h` near `r` make a cluster of near-roots of `f` about it,
//! which any root isolation of the expanded ray polynomial must subdivide, and which the
//! expansion's cancellation hides in its rounding. The level sets have `P`'s low degree and
//! simple roots.
//!
//! The roots of `h` are `r = ±|q|^(1/n)`, `q = −c/a` (both signs for an even `n`, the sign of
//! `q` for an odd one), each the `f64` nearest the exact root (correctly rounded) when a
//! double-double check brackets the exact root within half an ulp of it, else within one
//! ulp of it (also checked; see [`nth_root`]). The level set `P = r` then lies within
//! `ulp(r) / |∇P|` of the exact surface.

use super::dd::Dd;
use super::equation::{Expr, Node};
use super::poly::Poly;
use super::tree::has_variable;

/// A recognised composition `f = a·Pⁿ + c` with the real roots of `a·sⁿ + c`.
#[derive(Clone, Debug)]
pub struct Composition {
    /// `P`, the repeated sub-expression (as written in the equation).
    pub inner: Expr,
    /// `a`, the factor on the power (rounded to `f64`).
    pub scale: f64,
    /// `n ≥ 2`.
    pub power: u32,
    /// `c`, the constant (rounded to `f64`; not zero).
    pub constant: f64,
    /// The real roots `r` of `a·sⁿ + c`, ascending, each with whether `h′(r) < 0` (`f`
    /// then grows where `P` falls, so the outward normal is `−∇P`).
    pub levels: Vec<Level>,
}

/// One level set `P = value` of a [`Composition`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Level {
    /// The root of `h` (see the module's documentation for its accuracy).
    pub value: f64,
    /// True when `h′(value) < 0`: the outward normal of `f` there is `−∇P`.
    pub descending: bool,
}

impl Composition {
    /// `h(P) = a·Pⁿ + c` for the value `p` of `P`, in `f64`.
    pub fn outer(&self, p: f64) -> f64 {
        self.scale * p.powi(self.power as i32) + self.constant
    }

    /// `h′(P) = a·n·Pⁿ⁻¹` for the value `p` of `P`, in `f64`.
    pub fn outer_derivative(&self, p: f64) -> f64 {
        self.scale * f64::from(self.power) * p.powi(self.power as i32 - 1)
    }
}

/// Whether `a` and `b` are the same expression (spans aside).
fn same(a: &Expr, b: &Expr) -> bool {
    match (&a.node, &b.node) {
        (Node::Num(x), Node::Num(y)) => x == y,
        (Node::Var(x), Node::Var(y)) => x == y,
        (Node::Neg(x), Node::Neg(y)) => same(x, y),
        (Node::Call(f, x), Node::Call(g, y)) => f == g && same(x, y),
        (Node::Pow(x, m), Node::Pow(y, n)) => same(x, y) && same(m, n),
        (Node::Sum(x), Node::Sum(y)) | (Node::Product(x), Node::Product(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|((p, u), (q, v))| p == q && same(u, v))
        }
        _ => false,
    }
}

/// The bases holding a variable of every power in `e` (outermost first).
fn power_bases<'a>(e: &'a Expr, out: &mut Vec<&'a Expr>) {
    match &e.node {
        Node::Num(_) | Node::Var(_) => {}
        Node::Neg(a) | Node::Call(_, a) => power_bases(a, out),
        Node::Pow(a, b) => {
            if has_variable(a) {
                out.push(a);
            }
            power_bases(a, out);
            power_bases(b, out);
        }
        Node::Sum(terms) | Node::Product(terms) => {
            for (_, t) in terms {
                power_bases(t, out);
            }
        }
    }
}

/// `e` with every occurrence of `inner` replaced by the variable x, or `None` when a
/// variable of `e` lies outside every occurrence.
fn substituted(e: &Expr, inner: &Expr) -> Option<Expr> {
    if same(e, inner) {
        return Some(Expr {
            node: Node::Var(0),
            span: e.span,
        });
    }
    let node = match &e.node {
        Node::Num(_) | Node::Call(..) => e.node.clone(),
        Node::Var(_) => return None,
        Node::Neg(a) => Node::Neg(Box::new(substituted(a, inner)?)),
        Node::Pow(a, b) => Node::Pow(
            Box::new(substituted(a, inner)?),
            Box::new(substituted(b, inner)?),
        ),
        Node::Sum(terms) => Node::Sum(
            terms
                .iter()
                .map(|(minus, t)| Some((*minus, substituted(t, inner)?)))
                .collect::<Option<_>>()?,
        ),
        Node::Product(factors) => Node::Product(
            factors
                .iter()
                .map(|(divide, f)| Some((*divide, substituted(f, inner)?)))
                .collect::<Option<_>>()?,
        ),
    };
    Some(Expr { node, span: e.span })
}

/// The composition `e = a·Pⁿ + c` (`n ≥ 2`, `c ≠ 0`, `h` with a real root), `P` the power
/// base of lowest degree for which `e` has that form; `None` when there is none.
pub fn recognise(e: &Expr) -> Option<Composition> {
    let mut bases = Vec::new();
    power_bases(e, &mut bases);
    let mut candidates: Vec<(usize, &Expr)> = bases
        .into_iter()
        .filter_map(|b| Some((Poly::expand(b).ok()?.degree(), b)))
        .filter(|&(degree, _)| degree >= 1)
        .collect();
    // The lowest degree first: `((x+y)^2)^8 - 1` is the 16th power of `x + y`.
    candidates.sort_by_key(|&(degree, _)| degree);
    candidates.into_iter().find_map(|(_, inner)| {
        let h = Poly::expand(&substituted(e, inner)?).ok()?;
        binomial(inner, &h)
    })
}

/// The composition of `inner` by `h` (a polynomial in x alone) when `h = a·xⁿ + c` with
/// `n ≥ 2`, `c ≠ 0` and a real root.
fn binomial(inner: &Expr, h: &Poly) -> Option<Composition> {
    if h.terms.len() != 2 {
        return None;
    }
    let constant = *h.terms.get(&[0, 0, 0])?;
    let (&[n, 0, 0], &scale) = h.terms.iter().find(|(e, _)| **e != [0, 0, 0])? else {
        return None;
    };
    let power = u32::from(n);
    if power < 2 || constant.is_zero() || scale.is_zero() {
        return None;
    }
    // sⁿ = q.
    let q = constant.negated().over(scale);
    let q_value = q.to_f64();
    if !q_value.is_finite() || q_value == 0.0 {
        return None;
    }
    let even = power % 2 == 0;
    if even && q_value < 0.0 {
        // No real root: an empty surface, left to the general path.
        return None;
    }
    let magnitude = nth_root(q.to_dd().abs(), power)?;
    let values: Vec<f64> = if even {
        vec![-magnitude, magnitude]
    } else {
        vec![magnitude.copysign(q_value)]
    };
    let scale_value = scale.to_f64();
    let levels = values
        .into_iter()
        .map(|value| {
            // h′(r) = a·n·rⁿ⁻¹: negative when exactly one of `a` and `rⁿ⁻¹` is (`rⁿ⁻¹ < 0`
            // for an even `n` and `r < 0`).
            let power_negative = even && value < 0.0;
            let descending = (scale_value < 0.0) != power_negative;
            Level { value, descending }
        })
        .collect();
    Some(Composition {
        inner: inner.clone(),
        scale: scale_value,
        power,
        constant: constant.to_f64(),
        levels,
    })
}

/// `xⁿ` in double-double arithmetic (relative error about `n·2⁻¹⁰⁴`).
fn dd_pow(x: Dd, n: u32) -> Dd {
    let mut acc = Dd::from_f64(1.0);
    for _ in 0..n {
        acc = acc * x;
    }
    acc
}

/// Whether the exact root of `sⁿ = q` (`q > 0`) lies in `[lo, hi]` by the signs of `sⁿ − q`
/// at the ends, read in double-double where they are clear of its rounding.
fn brackets(q: Dd, n: u32, lo: Dd, hi: Dd) -> bool {
    let tolerance = 1e-28 * q.hi;
    let below = (dd_pow(lo, n) - q).to_f64();
    let above = (dd_pow(hi, n) - q).to_f64();
    below < -tolerance && above > tolerance
}

/// The positive `n`-th root of `q > 0`: the `f64` nearest the exact root when a
/// double-double check brackets the exact root within half an ulp of the answer, else one
/// within an ulp of it (also checked); `None` when neither check holds (never seen: the
/// double-double Newton step is good to about `2⁻¹⁰⁰` relative).
pub fn nth_root(q: Dd, n: u32) -> Option<f64> {
    let start = q.to_f64().powf(1.0 / f64::from(n));
    if !(start.is_finite() && start > 0.0) {
        return None;
    }
    // Two Newton steps in double-double from a start within a few ulps.
    let mut r = Dd::from_f64(start);
    for _ in 0..2 {
        let step = (dd_pow(r, n) - q) / (Dd::from_f64(f64::from(n)) * dd_pow(r, n - 1));
        r = r - step;
    }
    let r = r.to_f64();
    // The neighbouring `f64`s (`r > 0`).
    let (below, above) = (
        f64::from_bits(r.to_bits() - 1),
        f64::from_bits(r.to_bits() + 1),
    );
    let half_down = Dd::from_f64(r) - Dd::from_f64((r - below) / 2.0);
    let half_up = Dd::from_f64(r) + Dd::from_f64((above - r) / 2.0);
    if brackets(q, n, half_down, half_up) {
        return Some(r);
    }
    brackets(q, n, Dd::from_f64(below), Dd::from_f64(above)).then_some(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::equation;

    fn of(text: &str) -> Option<Composition> {
        recognise(&equation::parse(text).unwrap())
    }

    #[test]
    fn powers_shifted_by_a_constant_are_recognised() {
        let c = of("(x^2+y^2-1)^8 - 1e-12").expect("tube8");
        assert_eq!(c.power, 8);
        let r = 10f64.powf(-1.5);
        let values: Vec<f64> = c.levels.iter().map(|l| l.value).collect();
        assert!((values[0] + r).abs() <= 1e-17 && (values[1] - r).abs() <= 1e-17);
        // h′ < 0 at the negative root (even power, a > 0), > 0 at the positive one.
        assert!(c.levels[0].descending && !c.levels[1].descending);
        let inner = Poly::expand(&c.inner).unwrap();
        assert_eq!(
            inner,
            Poly::expand(&equation::parse("x^2+y^2-1").unwrap()).unwrap()
        );

        // `P^n = c`, `c − a·P^n`, odd powers and nested powers.
        let c = of("((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1").expect("sphere16_off");
        assert_eq!(c.levels.len(), 2);
        let c = of("2 - 3*(x+y)^5").expect("odd");
        assert_eq!(c.levels.len(), 1);
        assert!((c.levels[0].value - (2.0f64 / 3.0).powf(0.2)).abs() < 1e-15);
        // a < 0 and r > 0 with an odd power: h′ = −15·r⁴ < 0.
        assert!(c.levels[0].descending);
        let c = of("-(x+y)^3 - 8").expect("odd, negative root");
        assert_eq!(c.levels[0].value, -2.0);
        // h′ = −3·r² < 0.
        assert!(c.levels[0].descending);
        let c = of("((x+y+z+1)^2)^8 - 1").expect("nested");
        assert_eq!(c.power, 16);
        assert_eq!(Poly::expand(&c.inner).unwrap().degree(), 1);
    }

    #[test]
    fn other_equations_are_not_compositions() {
        for text in [
            "x^2 + y^2 + z^2 - 1",
            "(x^2+y^2+z^2+0.91)^2 - 4*(x^2+y^2)",
            "(x+y+z+1)^16",
            "(x^2+y^2-1)^8 + 1e-12",
            "(x^2+y^2-1)^8 + 1e-9*x - 1e-12",
            "(x+y)^8 + (x+y)^2 - 1",
            "x*y*z - 1",
        ] {
            assert!(of(text).is_none(), "{text}");
        }
    }

    #[test]
    fn roots_are_correctly_rounded() {
        // Integers' roots are exact; others against the exact rational bracket in
        // double-double at half an ulp.
        assert_eq!(nth_root(Dd::from_f64(65536.0), 16), Some(2.0));
        assert_eq!(nth_root(Dd::from_f64(1.0), 8), Some(1.0));
        for (q, n) in [(1e-12, 8), (1e-5, 8), (3.0, 16), (2.0, 2), (0.7, 5)] {
            let r = nth_root(Dd::from_f64(q), n).unwrap();
            let up = f64::from_bits(r.to_bits() + 1);
            let down = f64::from_bits(r.to_bits() - 1);
            let q = Dd::from_f64(q);
            let mid_up = Dd::from_f64(r) + Dd::from_f64((up - r) / 2.0);
            let mid_down = Dd::from_f64(r) - Dd::from_f64((r - down) / 2.0);
            assert!((dd_pow(mid_down, n) - q).to_f64() < 0.0, "{q:?} {n}");
            assert!((dd_pow(mid_up, n) - q).to_f64() > 0.0, "{q:?} {n}");
        }
    }
}
