//! The equation's own syntax tree, kept past its expansion and evaluated in `f64` with a
//! running error bound (the a-posteriori bound of Higham, *Accuracy and Stability of
//! Numerical Algorithms*, ch. 3: each node carries its computed value and a bound on that
//! value's distance from the node's exact value, propagated through every operation).
//!
//! Where the expansion cancels by many orders (`(x+y+z+1)^16 − 1`: terms of
//! `(|x|+|y|+|z|+1)^16` summing to values near 1), the tree does not: `(a + b·s)^16 − 1` is a
//! power of one small sum, then one subtraction. So the tree gives a surface's value, its
//! gradient (forward mode: each node its value and three partial derivatives) and a ray's
//! polynomial (each node a polynomial in the ray's parameter, with a bound per coefficient)
//! together with a bound on their error that is as small as the arithmetic allows, where the
//! expansion's own rounding (its terms' magnitudes) would hide them.
//!
//! The bound contains the exact value of the polynomial the equation denotes (its constants
//! taken as [`super::coef::Coef`] holds them; a constant that is not an `f64` carries its own
//! rounding as an initial error), whatever the rounding of every operation, underflow
//! included.

use super::coef::Coef;
use super::equation::{Expr, Node};
use super::poly::{Poly, Uni};
use super::MAX_DEGREE;

/// The unit roundoff of `f64` (round to nearest): `|fl(a ∘ b) − a ∘ b| ≤ UNIT·|a ∘ b|`
/// outside the subnormal range.
const UNIT: f64 = f64::EPSILON / 2.0;

/// Absolute error allowed per product for underflow (the subnormal spacing is `2⁻¹⁰⁷⁴`;
/// this is far above it and far below any value the bounds are compared with).
const TINY: f64 = 1e-300;

/// Factor on every finished bound for the rounding of the bound's own arithmetic (a sum and
/// product of non-negative numbers, each operation within `1 + UNIT`: a relative error of
/// `n·UNIT` for `n` operations, which this covers up to millions of them).
const SLACK: f64 = 1.0 + 1e-9;

/// One node of the compiled tree. Every part without x, y or z is folded into one
/// constant (exactly, as the expansion folds it).
#[derive(Clone, Debug)]
enum Op {
    /// A constant: its nearest `f64` and a bound on the distance to the exact value.
    Const { value: f64, error: f64 },
    /// A variable: 0 = x, 1 = y, 2 = z.
    Var(usize),
    /// `−a`.
    Neg(Box<Op>),
    /// `±a ± b ± …` (`true`: subtracted).
    Sum(Vec<(bool, Op)>),
    /// `a · b · …` (every factor holds a variable, but for at most one constant).
    Product(Vec<Op>),
    /// `aⁿ`, `n ≥ 2`.
    Pow(Box<Op>, u32),
}

/// An equation's syntax tree compiled for evaluation with running error bounds: value,
/// gradient and ray polynomial (see the module's documentation).
#[derive(Clone, Debug)]
pub struct Tree {
    root: Op,
    /// The degree of the expanded polynomial (coefficients above it are exactly zero).
    degree: usize,
}

/// Whether `e` holds x, y or z.
pub(super) fn has_variable(e: &Expr) -> bool {
    match &e.node {
        Node::Num(_) => false,
        Node::Var(_) => true,
        Node::Neg(a) | Node::Call(_, a) => has_variable(a),
        Node::Pow(a, b) => has_variable(a) || has_variable(b),
        Node::Sum(terms) => terms.iter().any(|(_, t)| has_variable(t)),
        Node::Product(factors) => factors.iter().any(|(_, f)| has_variable(f)),
    }
}

/// The exact constant a part without variables folds to (as the expansion folds it).
fn folded(e: &Expr) -> Option<Coef> {
    Poly::expand(e).ok()?.as_constant()
}

/// The constant `c` as a node: its nearest `f64`, and the rest as its error (its
/// double-double form is good to about `2⁻¹⁰⁴` of it, covered by the margin).
fn constant(c: Coef) -> Op {
    let d = c.to_dd();
    let error = if d.lo == 0.0 && matches!(c, Coef::Approx(_) | Coef::Exact(_, 1)) {
        // Exact: an `f64` as the expansion holds it, or an integer within 106 bits.
        0.0
    } else {
        d.lo.abs() + d.hi.abs() * f64::EPSILON.powi(2)
    };
    Op::Const { value: d.hi, error }
}

/// The node of `e` and its degree in x, y, z counted without cancellation (at least the
/// expanded degree); `None` when that exceeds [`MAX_DEGREE`] or the tree breaks a rule the
/// expansion enforces (it is compiled only after a successful expansion).
fn compile(e: &Expr) -> Option<(Op, usize)> {
    if !has_variable(e) {
        return Some((constant(folded(e)?), 0));
    }
    let (op, degree) = match &e.node {
        Node::Num(_) | Node::Call(..) => return None,
        Node::Var(v) => (Op::Var(*v), 1),
        Node::Neg(a) => {
            let (a, d) = compile(a)?;
            (Op::Neg(Box::new(a)), d)
        }
        Node::Sum(terms) => {
            let mut parts = Vec::with_capacity(terms.len());
            let mut degree = 0;
            for (minus, t) in terms {
                let (op, d) = compile(t)?;
                degree = degree.max(d);
                parts.push((*minus, op));
            }
            (Op::Sum(parts), degree)
        }
        Node::Product(factors) => {
            // The constant factors (and divisors) folded into one, exactly.
            let mut scale = Coef::ONE;
            let mut parts = Vec::with_capacity(factors.len());
            let mut degree = 0;
            for (divide, f) in factors {
                if has_variable(f) {
                    if *divide {
                        return None;
                    }
                    let (op, d) = compile(f)?;
                    degree += d;
                    parts.push(op);
                } else {
                    let c = folded(f)?;
                    scale = if *divide {
                        if c.is_zero() {
                            return None;
                        }
                        scale.over(c)
                    } else {
                        scale.times(c)
                    };
                }
            }
            if scale.is_zero() {
                return Some((constant(Coef::ZERO), 0));
            }
            if scale != Coef::ONE {
                parts.insert(0, constant(scale));
            }
            if parts.len() == 1 {
                return parts.pop().map(|op| (op, degree));
            }
            (Op::Product(parts), degree)
        }
        Node::Pow(a, b) => {
            let n = u32::try_from(folded(b)?.as_integer()?).ok()?;
            match n {
                0 => return Some((constant(Coef::ONE), 0)),
                1 => compile(a)?,
                _ => {
                    let (a, d) = compile(a)?;
                    (Op::Pow(Box::new(a), n), d.checked_mul(n as usize)?)
                }
            }
        }
    };
    (degree <= MAX_DEGREE).then_some((op, degree))
}

/// A number type carried through the tree with its error bound.
trait Tracked: Sized {
    /// A constant with its error.
    fn constant(value: f64, error: f64) -> Self;
    /// `−self`.
    fn negated(self) -> Self;
    /// `self ± o` (`negate`: minus).
    fn plus(self, o: &Self, negate: bool) -> Self;
    /// `self · o`.
    fn times(&self, o: &Self) -> Self;
}

/// A value and a bound on its error.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounded {
    v: f64,
    e: f64,
}

impl Tracked for Bounded {
    #[inline]
    fn constant(value: f64, error: f64) -> Self {
        Bounded { v: value, e: error }
    }

    #[inline]
    fn negated(self) -> Self {
        Bounded {
            v: -self.v,
            e: self.e,
        }
    }

    #[inline]
    fn plus(self, o: &Self, negate: bool) -> Self {
        let v = if negate { self.v - o.v } else { self.v + o.v };
        Bounded {
            v,
            e: self.e + o.e + UNIT * v.abs(),
        }
    }

    #[inline]
    fn times(&self, o: &Self) -> Self {
        let v = self.v * o.v;
        Bounded {
            v,
            e: self.v.abs() * o.e + self.e * o.v.abs() + self.e * o.e + UNIT * v.abs() + TINY,
        }
    }
}

/// A value and its three partial derivatives, each with its error bound (forward mode).
#[derive(Clone, Copy, Debug)]
struct WithGradient {
    v: Bounded,
    g: [Bounded; 3],
}

impl Tracked for WithGradient {
    #[inline]
    fn constant(value: f64, error: f64) -> Self {
        WithGradient {
            v: Bounded::constant(value, error),
            g: [Bounded::constant(0.0, 0.0); 3],
        }
    }

    #[inline]
    fn negated(self) -> Self {
        WithGradient {
            v: self.v.negated(),
            g: self.g.map(Bounded::negated),
        }
    }

    #[inline]
    fn plus(self, o: &Self, negate: bool) -> Self {
        WithGradient {
            v: self.v.plus(&o.v, negate),
            g: std::array::from_fn(|i| self.g[i].plus(&o.g[i], negate)),
        }
    }

    #[inline]
    fn times(&self, o: &Self) -> Self {
        WithGradient {
            v: self.v.times(&o.v),
            g: std::array::from_fn(|i| self.v.times(&o.g[i]).plus(&self.g[i].times(&o.v), false)),
        }
    }
}

/// A univariate polynomial (ascending, `deg + 1` coefficients used) with a bound per
/// coefficient.
#[derive(Clone, Copy, Debug)]
struct BoundedPoly {
    c: Uni,
    e: Uni,
    deg: usize,
}

impl Tracked for BoundedPoly {
    #[inline]
    fn constant(value: f64, error: f64) -> Self {
        let mut p = BoundedPoly {
            c: [0.0; MAX_DEGREE + 1],
            e: [0.0; MAX_DEGREE + 1],
            deg: 0,
        };
        p.c[0] = value;
        p.e[0] = error;
        p
    }

    #[inline]
    fn negated(mut self) -> Self {
        for c in &mut self.c[..=self.deg] {
            *c = -*c;
        }
        self
    }

    #[inline]
    fn plus(mut self, o: &Self, negate: bool) -> Self {
        self.deg = self.deg.max(o.deg);
        for k in 0..=self.deg {
            // Entries above a polynomial's degree are zero, with zero error.
            let c = if negate {
                self.c[k] - o.c[k]
            } else {
                self.c[k] + o.c[k]
            };
            self.c[k] = c;
            self.e[k] += o.e[k] + UNIT * c.abs();
        }
        self
    }

    #[inline]
    fn times(&self, o: &Self) -> Self {
        // Structural degrees stay within MAX_DEGREE (checked when compiling).
        let deg = (self.deg + o.deg).min(MAX_DEGREE);
        let mut r = BoundedPoly::constant(0.0, 0.0);
        r.deg = deg;
        for k in 0..=deg {
            let (mut sum, mut magnitude, mut carried) = (0.0f64, 0.0f64, 0.0f64);
            let mut count = 0usize;
            for i in k.saturating_sub(o.deg)..=k.min(self.deg) {
                let (a, ea, b, eb) = (self.c[i], self.e[i], o.c[k - i], o.e[k - i]);
                sum += a * b;
                magnitude += (a * b).abs();
                carried += a.abs() * eb + ea * b.abs() + ea * eb;
                count += 1;
            }
            // A sum of `count` products: within γ_count = count·u/(1 − count·u) of their
            // magnitudes (`count ≤ 17`, so the denominator is covered by the margin).
            r.c[k] = sum;
            r.e[k] = carried + (count as f64) * UNIT * magnitude * (1.0 + 1e-12) + TINY;
        }
        r
    }
}

/// `op` evaluated in the arithmetic `T`, the variables given by `var`.
fn run<T: Tracked + Clone>(op: &Op, var: &impl Fn(usize) -> T) -> T {
    match op {
        Op::Const { value, error } => T::constant(*value, *error),
        Op::Var(v) => var(*v),
        Op::Neg(a) => run(a, var).negated(),
        Op::Sum(terms) => {
            let mut acc: Option<T> = None;
            for (minus, t) in terms {
                let t = run(t, var);
                acc = Some(match acc {
                    None if *minus => t.negated(),
                    None => t,
                    Some(a) => a.plus(&t, *minus),
                });
            }
            acc.unwrap_or_else(|| T::constant(0.0, 0.0))
        }
        Op::Product(factors) => {
            let mut acc: Option<T> = None;
            for f in factors {
                let f = run(f, var);
                acc = Some(match acc {
                    None => f,
                    Some(a) => a.times(&f),
                });
            }
            acc.unwrap_or_else(|| T::constant(1.0, 0.0))
        }
        Op::Pow(a, n) => {
            // Repeated squaring.
            let mut base = run(a, var);
            let mut acc: Option<T> = None;
            let mut n = *n;
            loop {
                if n & 1 == 1 {
                    acc = Some(match acc {
                        None => base.clone(),
                        Some(a) => a.times(&base),
                    });
                }
                n >>= 1;
                if n == 0 {
                    break;
                }
                base = base.times(&base);
            }
            acc.expect("an exponent of at least 2")
        }
    }
}

/// The value of a node evaluated in `f64` and a bound on its distance from the exact value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The computed value.
    pub value: f64,
    /// `|value − exact| ≤ error` (`+∞` or NaN where the arithmetic overflowed).
    pub error: f64,
}

impl From<Bounded> for Estimate {
    fn from(b: Bounded) -> Estimate {
        Estimate {
            value: b.v,
            error: b.e * SLACK,
        }
    }
}

impl Tree {
    /// The tree of the equation `e` (already expanded without error to a polynomial of
    /// `degree`), or `None` when some part of it, counted without cancellation, has a degree
    /// above [`MAX_DEGREE`] (such as `((x+1)^2 − x^2)^16`).
    pub fn new(e: &Expr, degree: usize) -> Option<Tree> {
        let (root, _) = compile(e)?;
        Some(Tree { root, degree })
    }

    /// The polynomial's value at `p` with its error bound.
    pub fn value(&self, p: [f64; 3]) -> Estimate {
        run(&self.root, &|v| Bounded::constant(p[v], 0.0)).into()
    }

    /// The gradient `∇f` at `p`, each partial derivative with its error bound.
    pub fn gradient(&self, p: [f64; 3]) -> [Estimate; 3] {
        let r = run(&self.root, &|v| {
            let mut g = [Bounded::constant(0.0, 0.0); 3];
            g[v] = Bounded::constant(1.0, 0.0);
            WithGradient {
                v: Bounded::constant(p[v], 0.0),
                g,
            }
        });
        r.g.map(Estimate::from)
    }

    /// The coefficients (ascending in `s`) of `f(o + s·e)` into `out` and a bound on each
    /// one's error into `error`, up to the polynomial's degree (entries above it are zero,
    /// exactly: they are zero in the expansion).
    pub fn compose(&self, o: [f64; 3], e: [f64; 3], out: &mut Uni, error: &mut Uni) {
        let r = run(&self.root, &|v| {
            let mut p = BoundedPoly::constant(o[v], 0.0);
            p.c[1] = e[v];
            p.deg = 1;
            p
        });
        for k in 0..=MAX_DEGREE {
            let (c, err) = if k <= self.degree.min(r.deg) {
                (r.c[k], r.e[k] * SLACK)
            } else {
                (0.0, 0.0)
            };
            out[k] = c;
            error[k] = err;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::dd::Dd;
    use crate::shapes::implicit::equation;
    use crate::shapes::implicit::poly::Compiled;

    /// The tree of `text` and its expansion compiled (whose double-double evaluation, with
    /// the exact coefficients, is the reference: good to about `1e-31` of its terms).
    fn parts(text: &str) -> (Tree, Compiled, Poly) {
        let expr = equation::parse(text).unwrap();
        let poly = Poly::expand(&expr).unwrap();
        let tree = Tree::new(&expr, poly.degree()).expect("a tree");
        (tree, Compiled::new(&poly), poly)
    }

    /// The cancelling cases: near their surfaces the expansion's terms are up to 10¹³ times
    /// the value.
    const CANCELLING: [&str; 6] = [
        "(x+y+z+1)^16 - 1",
        "(x+y+z)^16 - 1",
        "(x^2+y^2+z^2-1)^8 - 1e-5",
        "(x^2+y^2-1)^8 - 1e-12",
        "((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1",
        "(x - 1/3)*(y + 2/7)*(x*y - z/3) - 3*(x - 0.1)^3/7",
    ];

    /// Points near the surfaces above and anywhere in the cube of side 4.
    fn points() -> Vec<[f64; 3]> {
        let mut uniform = crate::testing::uniform_stream(0x005e_ed0f_7ee5);
        let mut out = Vec::new();
        for k in 0..400 {
            let mut p = [0.0; 3].map(|_| 4.0 * uniform() - 2.0);
            match k % 4 {
                // On the planes x + y + z = 0 and −2 (to rounding).
                0 => p[2] = -p[0] - p[1],
                1 => p[2] = -2.0 - p[0] - p[1],
                // On the unit sphere and cylinder, and off by 1e-9.
                2 => {
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    p = p.map(|c| c / r * (1.0 + 1e-9 * uniform()));
                }
                _ => {}
            }
            out.push(p);
        }
        out
    }

    /// The bound holds the exact value (the expansion in double-double arithmetic, exact
    /// coefficients) everywhere, and is far tighter than the expansion's own rounding where
    /// that cancels.
    #[test]
    fn the_value_bound_holds_the_exact_value() {
        for (k, text) in CANCELLING.iter().enumerate() {
            let (tree, f, _) = parts(text);
            let mut tighter = 0;
            for p in points() {
                let got = tree.value(p);
                let exact = f.eval_dd(p);
                let (_, magnitude) = f.eval_with_bound(p);
                // The reference's own error is about 1e-31 of the terms' magnitudes.
                let slack = 1e-29 * magnitude;
                let miss = (Dd::from_f64(got.value) - exact).abs().to_f64();
                assert!(
                    miss <= got.error + slack,
                    "{text} at {p:?}: {} off the exact {}, bound {}",
                    miss,
                    exact.to_f64(),
                    got.error
                );
                if got.error < 1e-6 * f64::EPSILON * magnitude {
                    tighter += 1;
                }
            }
            // The first four cancel by many orders at many of the points.
            if k < 4 {
                assert!(tighter > 40, "{text}: {tighter} of 400 far tighter");
            }
        }
    }

    /// A bound made a little smaller than the computed one fails to hold the exact value
    /// somewhere on the cancelling cases: the test above can fail (the bound is not loose by
    /// orders of magnitude).
    #[test]
    fn a_bound_a_tenth_of_the_computed_one_misses() {
        let mut missed = 0;
        for text in CANCELLING {
            let (tree, f, _) = parts(text);
            for p in points() {
                let got = tree.value(p);
                let miss = (Dd::from_f64(got.value) - f.eval_dd(p)).abs().to_f64();
                if miss > 0.1 * got.error {
                    missed += 1;
                }
            }
        }
        assert!(missed > 10, "{missed}");
    }

    /// Each partial derivative's bound holds the exact partial derivative (the expansion's
    /// derivative in double-double arithmetic).
    #[test]
    fn the_gradient_bound_holds_the_exact_gradient() {
        let mut missed_tenth = 0;
        for text in CANCELLING {
            let (tree, _, poly) = parts(text);
            let partials = [0, 1, 2].map(|v| Compiled::new(&poly.derivative(v)));
            for p in points() {
                let got = tree.gradient(p);
                for (v, g) in partials.iter().enumerate() {
                    let exact = g.eval_dd(p);
                    let slack = 1e-29 * g.eval_with_bound(p).1;
                    let miss = (Dd::from_f64(got[v].value) - exact).abs().to_f64();
                    assert!(
                        miss <= got[v].error + slack,
                        "{text} at {p:?}, ∂{v}: {miss} off, bound {}",
                        got[v].error
                    );
                    if miss > 0.1 * got[v].error {
                        missed_tenth += 1;
                    }
                }
            }
        }
        assert!(missed_tenth > 10, "{missed_tenth}");
    }

    /// Each coefficient's bound of a ray polynomial holds the exact coefficient (the
    /// expansion composed in double-double arithmetic with the exact coefficients).
    #[test]
    fn the_composed_bound_holds_the_exact_coefficients() {
        let mut uniform = crate::testing::uniform_stream(0xc041_05ed);
        let mut missed_tenth = 0;
        for text in CANCELLING {
            let (tree, f, _) = parts(text);
            for _ in 0..200 {
                let o = [0.0; 3].map(|_| 4.0 * uniform() - 2.0);
                let e = [0.0; 3].map(|_| 4.0 * uniform() - 2.0);
                let (mut c, mut err) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
                tree.compose(o, e, &mut c, &mut err);
                let mut exact = [Dd::ZERO; MAX_DEGREE + 1];
                f.compose_dd(o.map(Dd::from_f64), e.map(Dd::from_f64), &mut exact);
                // The reference's error: about 1e-31 of the composition's magnitudes, which
                // the composition of |f|'s terms with |o|, |e| bounds.
                let r = o
                    .iter()
                    .zip(&e)
                    .map(|(a, b)| a.abs() + b.abs())
                    .fold(0.0, f64::max);
                let slack = 1e-29 * f.magnitude_bound([r; 3]);
                for k in 0..=MAX_DEGREE {
                    let miss = (Dd::from_f64(c[k]) - exact[k]).abs().to_f64();
                    assert!(
                        miss <= err[k] + slack,
                        "{text} along {o:?} + s·{e:?}, s^{k}: {miss} off, bound {}",
                        err[k]
                    );
                    if miss > 0.1 * err[k] && err[k] > 0.0 {
                        missed_tenth += 1;
                    }
                }
            }
        }
        assert!(missed_tenth > 10, "{missed_tenth}");
    }

    /// Constants folded as the expansion folds them; a rounded constant carries its error.
    #[test]
    fn constants_fold_and_carry_their_rounding() {
        let (tree, f, _) = parts("x*(2/3)*3 + sqrt(4)*y/2 - (1/10)^2 * z^2 * 100");
        for p in points() {
            let got = tree.value(p);
            let miss = (Dd::from_f64(got.value) - f.eval_dd(p)).abs().to_f64();
            assert!(miss <= got.error, "{p:?}: {miss} > {}", got.error);
        }
        // 1/3 is not an f64: its node's error is its rounding, about 1.8e-17.
        let (tree, _, _) = parts("x - 1/3");
        let at0 = tree.value([0.0; 3]);
        assert!(at0.error > 1e-18 && at0.error < 1e-16, "{at0:?}");
        // A degree that counts higher than 16 without cancellation has no tree.
        let expr = equation::parse("((x+1)^2 - x^2)^16").unwrap();
        assert!(Tree::new(&expr, 16).is_none());
    }
}
