//! Multivariate polynomials in x, y, z: exact expansion of a syntax tree, then a compiled
//! `f64` form for ray tracing (composition with a ray, value, gradient).

use super::coef::Coef;
use super::dd::Dd;
use super::equation::{Expr, Node, Span};
use super::{EquationError, MAX_DEGREE};
use std::collections::BTreeMap;
use std::ops::{Add, Mul, Sub};

/// Exponents `[i, j, k]` of the monomial `xⁱ yʲ zᵏ`.
pub type Exps = [u8; 3];

/// A polynomial being expanded: monomial exponents → non-zero coefficient.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Poly {
    /// The non-zero terms.
    pub terms: BTreeMap<Exps, Coef>,
}

fn degree_of(e: &Exps) -> usize {
    e.iter().map(|&k| k as usize).sum()
}

/// A folded value as a coefficient: exact when it is a whole number, else its `f64`.
fn folded(v: f64) -> Coef {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        Coef::int(v as i128)
    } else {
        Coef::Approx(v)
    }
}

/// `k^c` for constants: exact for a whole exponent (a negative one inverts), by `powf` for
/// any other, with an error where the power has no real value.
fn constant_power(k: Coef, c: Coef, whole: Span, exp: Span) -> Result<Coef, EquationError> {
    if let Some(n) = c.as_integer() {
        let m =
            u32::try_from(n.unsigned_abs()).map_err(|_| exp.error("this exponent is too large"))?;
        if n >= 0 {
            return Ok(k.pow(m));
        }
        if k.is_zero() {
            return Err(whole.error(format!("0 to a negative power ({n}) divides by zero")));
        }
        return Ok(Coef::ONE.over(k.pow(m)));
    }
    let (kv, cv) = (k.to_f64(), c.to_f64());
    if kv < 0.0 {
        return Err(whole.error(format!(
            "a negative number ({kv}) to the non-whole power {cv} has no real value \
             (for an odd root write cbrt)"
        )));
    }
    if kv == 0.0 && cv < 0.0 {
        return Err(whole.error(format!("0 to a negative power ({cv}) divides by zero")));
    }
    let v = kv.powf(cv);
    if !v.is_finite() {
        return Err(whole.error(format!("{kv}^{cv} is too large")));
    }
    Ok(folded(v))
}

impl Poly {
    /// The constant `c`.
    pub fn constant(c: Coef) -> Poly {
        let mut p = Poly::default();
        if !c.is_zero() {
            p.terms.insert([0, 0, 0], c);
        }
        p
    }

    /// The monomial `c·xⁱ yʲ zᵏ` of exponents `e` (the zero polynomial when `c` is zero).
    pub(super) fn monomial(e: Exps, c: Coef) -> Poly {
        let mut p = Poly::default();
        p.add_term(e, c);
        p
    }

    /// The sum of `parts`.
    pub(super) fn sum(parts: &[Poly]) -> Poly {
        parts
            .iter()
            .fold(Poly::default(), |acc, part| acc.add(part, false))
    }

    /// The variable with index `v` (0 = x, 1 = y, 2 = z).
    pub fn var(v: usize) -> Poly {
        let mut e = [0u8; 3];
        e[v] = 1;
        let mut p = Poly::default();
        p.terms.insert(e, Coef::ONE);
        p
    }

    /// Total degree (0 for constants and for the zero polynomial).
    pub fn degree(&self) -> usize {
        self.terms.keys().map(degree_of).max().unwrap_or(0)
    }

    /// The constant value, if the polynomial has no x, y or z.
    pub fn as_constant(&self) -> Option<Coef> {
        match self.terms.len() {
            0 => Some(Coef::ZERO),
            1 => self.terms.get(&[0, 0, 0]).copied(),
            _ => None,
        }
    }

    fn add_term(&mut self, e: Exps, c: Coef) {
        let sum = match self.terms.get(&e) {
            Some(&old) => old.plus(c),
            None => c,
        };
        if sum.is_zero() {
            self.terms.remove(&e);
        } else {
            self.terms.insert(e, sum);
        }
    }

    /// `self + sign·o`.
    pub(super) fn add(mut self, o: &Poly, negate: bool) -> Poly {
        for (&e, &c) in &o.terms {
            self.add_term(e, if negate { c.negated() } else { c });
        }
        self
    }

    /// `self · o` (the caller checks the degree first).
    pub(super) fn mul(&self, o: &Poly) -> Poly {
        let mut r = Poly::default();
        for (a, &ca) in &self.terms {
            for (b, &cb) in &o.terms {
                r.add_term([a[0] + b[0], a[1] + b[1], a[2] + b[2]], ca.times(cb));
            }
        }
        r
    }

    /// `c·self`.
    pub(super) fn scale(&self, c: Coef) -> Poly {
        let mut r = Poly::default();
        for (&e, &v) in &self.terms {
            r.add_term(e, v.times(c));
        }
        r
    }

    /// Expands a syntax tree, checking every rule of the equation language on the way:
    /// division only by constants, whole non-negative exponents on anything holding x, y or z,
    /// functions only of constants (folded to their `f64` value, as are powers of constants
    /// with a negative or non-whole exponent), total degree ≤ 16 for every sub-expression.
    pub fn expand(e: &Expr) -> Result<Poly, EquationError> {
        let too_high = |d: i128| {
            e.span.error(format!(
                "this part has degree {d}, above the maximum of {MAX_DEGREE}"
            ))
        };
        Ok(match &e.node {
            Node::Num(c) => Poly::constant(*c),
            Node::Var(v) => Poly::var(*v),
            Node::Neg(a) => Poly::default().add(&Poly::expand(a)?, true),
            Node::Sum(terms) => {
                let mut acc = Poly::default();
                for (minus, t) in terms {
                    acc = acc.add(&Poly::expand(t)?, *minus);
                }
                acc
            }
            Node::Product(factors) => {
                let mut acc = Poly::constant(Coef::ONE);
                let start = factors[0].1.span.start;
                for (div, f) in factors {
                    let pf = Poly::expand(f)?;
                    if *div {
                        let Some(c) = pf.as_constant() else {
                            return Err(f.span.error(
                                "division is only allowed by a constant (this contains x, y or z)",
                            ));
                        };
                        if c.is_zero() {
                            return Err(f.span.error("division by zero"));
                        }
                        acc = acc.scale(Coef::ONE.over(c));
                    } else {
                        let d = acc.degree() + pf.degree();
                        if d > MAX_DEGREE && !acc.terms.is_empty() && !pf.terms.is_empty() {
                            let span = Span {
                                start,
                                end: f.span.end,
                            };
                            return Err(span.error(format!(
                                "this part has degree {d}, above the maximum of {MAX_DEGREE}"
                            )));
                        }
                        acc = acc.mul(&pf);
                    }
                }
                acc
            }
            Node::Pow(a, b) => {
                let pa = Poly::expand(a)?;
                let pb = Poly::expand(b)?;
                let Some(c) = pb.as_constant() else {
                    return Err(b.span.error(
                        "the exponent must be a whole number, not an expression in x, y or z",
                    ));
                };
                if let Some(k) = pa.as_constant() {
                    return constant_power(k, c, e.span, b.span).map(Poly::constant);
                }
                let Some(n) = c.as_integer() else {
                    return Err(b.span.error(format!(
                        "the exponent of an expression in x, y or z must be a whole number, not {} \
                         (a root of x, y or z is not a polynomial: raise both sides to a power instead)",
                        c.to_f64()
                    )));
                };
                if n < 0 {
                    return Err(b.span.error(format!(
                        "the exponent of an expression in x, y or z must not be negative ({n}): \
                         multiply both sides by the denominator instead"
                    )));
                }
                let d = (pa.degree() as i128).saturating_mul(n);
                if d > MAX_DEGREE as i128 {
                    return Err(too_high(d));
                }
                let mut r = Poly::constant(Coef::ONE);
                for _ in 0..n {
                    r = r.mul(&pa);
                }
                r
            }
            Node::Call(f, a) => {
                let pa = Poly::expand(a)?;
                let Some(c) = pa.as_constant() else {
                    return Err(a.span.error(format!(
                        "{}(…) of x, y or z is not a polynomial: only constants may go inside \
                         (such as {}(2)); write the surface without it, e.g. square both sides",
                        f.name(),
                        f.name()
                    )));
                };
                let v = f.apply(c.to_f64()).map_err(|m| e.span.error(m))?;
                Poly::constant(folded(v))
            }
        })
    }

    /// `∂/∂x_v` of the polynomial.
    pub fn derivative(&self, v: usize) -> Poly {
        let mut r = Poly::default();
        for (&e, &c) in &self.terms {
            if e[v] > 0 {
                let mut f = e;
                f[v] -= 1;
                r.add_term(f, c.times(Coef::int(e[v] as i128)));
            }
        }
        r
    }
}

/// One term of a compiled polynomial.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// Exponents of x, y, z.
    pub e: Exps,
    /// Coefficient, rounded to the nearest `f64`.
    pub c: f64,
    /// What the rounding of `c` lost: `c + lo` is the exact coefficient to about 106 bits.
    pub lo: f64,
}

/// A polynomial compiled for evaluation: `f64` terms sorted by descending x-exponent, then
/// descending y-exponent, so a ray composition can run nested Horner schemes in x and y over
/// precomputed powers of z.
#[derive(Clone, Debug, PartialEq)]
pub struct Compiled {
    /// The terms, sorted as described.
    pub terms: Vec<Term>,
    /// Total degree.
    pub degree: usize,
    /// Highest exponent of z in any term.
    max_z: usize,
    /// `Σ |c|` over the terms of each total degree (index the degree), for
    /// [`Compiled::magnitude_bound`].
    magnitude_by_degree: [f64; MAX_DEGREE + 1],
    /// The steps of a ray composition (see [`Compiled::compose_into`]), fixed by the terms'
    /// exponents alone.
    steps: Vec<Step>,
}

/// One step of a ray composition, in the order the nested Horner scheme takes them. Which
/// steps a polynomial needs, and the degree of every partial result, depend only on its
/// terms' exponents, so they are worked out once; a ray then runs straight through them with
/// kernels of constant trip count.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    /// `h ← h + c·Z(s)ᵏ` for the next term in order (`c` its coefficient, `k` its z-exponent).
    Term(u8),
    /// `h ← h·Y(s)`, `h` of the given degree.
    TimesY(u8),
    /// `h ← h·Y(s)·Y(s)` (two [`Step::TimesY`] in one), `h` of the given degree.
    TimesY2(u8),
    /// `f ← f + h` over `h`'s degree (given), then `h ← 0`.
    Flush(u8),
    /// `f ← f·X(s)`, `f` of the given degree.
    TimesX(u8),
    /// `f ← f·X(s)·X(s)` (two [`Step::TimesX`] in one), `f` of the given degree.
    TimesX2(u8),
}

/// Runs `$body` with `$d` bound to the value of `$v` (at most [`MAX_DEGREE`]) as a constant,
/// so that kernels written for one degree get constant trip counts.
macro_rules! with_degree {
    ($v:expr, $d:ident => $body:expr) => {
        match $v {
            0 => {
                const $d: usize = 0;
                $body
            }
            1 => {
                const $d: usize = 1;
                $body
            }
            2 => {
                const $d: usize = 2;
                $body
            }
            3 => {
                const $d: usize = 3;
                $body
            }
            4 => {
                const $d: usize = 4;
                $body
            }
            5 => {
                const $d: usize = 5;
                $body
            }
            6 => {
                const $d: usize = 6;
                $body
            }
            7 => {
                const $d: usize = 7;
                $body
            }
            8 => {
                const $d: usize = 8;
                $body
            }
            9 => {
                const $d: usize = 9;
                $body
            }
            10 => {
                const $d: usize = 10;
                $body
            }
            11 => {
                const $d: usize = 11;
                $body
            }
            12 => {
                const $d: usize = 12;
                $body
            }
            13 => {
                const $d: usize = 13;
                $body
            }
            14 => {
                const $d: usize = 14;
                $body
            }
            15 => {
                const $d: usize = 15;
                $body
            }
            _ => {
                const $d: usize = 16;
                $body
            }
        }
    };
}

/// The powers `xᵏ, yᵏ, zᵏ` of a point's coordinates for `k` up to the degree it was made
/// for, each the previous one times the coordinate (so every polynomial evaluated on the
/// table sees the same values).
#[derive(Clone, Copy, Debug)]
pub struct Powers([[f64; MAX_DEGREE + 1]; 3]);

impl Powers {
    /// The powers of `p`'s coordinates up to `degree` (at most [`MAX_DEGREE`]).
    #[inline]
    pub fn new(p: [f64; 3], degree: usize) -> Powers {
        // Entries above the degree are never read; zero is the cheapest fill.
        let mut pw = [[0.0; MAX_DEGREE + 1]; 3];
        with_degree!(degree, D => {
            for (row, x) in pw.iter_mut().zip(p) {
                powers_into::<D>(row, x);
            }
        });
        Powers(pw)
    }
}

/// The three partial derivatives of a polynomial (each a [`Compiled`]) evaluated in one
/// pass over a shared table of powers: row `r` holds term `r` of each partial, in that
/// partial's own order, so that each sum takes its terms in the order
/// [`Compiled::eval_with_bound_on`] takes them and gets the same bits. A partial with fewer
/// terms is padded with `−0·1·1·1`, which adds nothing to either sum (`v + (−0) = v`, and the
/// magnitude sum is never `−0`).
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// Per row, the coefficient of each partial's term.
    coefs: Vec<[f64; 3]>,
    /// Per row, the exponents of each partial's term.
    exps: Vec<[Exps; 3]>,
    /// Highest total degree of the three partials.
    pub degree: usize,
    /// Most terms of any of the three partials.
    pub most_terms: usize,
}

impl Gradient {
    /// The gradient made of the three partial derivatives `parts` (x, y, z).
    pub fn new(parts: &[Compiled; 3]) -> Gradient {
        let most_terms = parts.iter().map(|g| g.terms.len()).max().unwrap_or(0);
        let (mut coefs, mut exps) = (Vec::new(), Vec::new());
        for r in 0..most_terms {
            let term = |k: usize| parts[k].terms.get(r).map_or((-0.0, [0; 3]), |t| (t.c, t.e));
            let row = [term(0), term(1), term(2)];
            coefs.push(row.map(|t| t.0));
            exps.push(row.map(|t| t.1));
        }
        Gradient {
            coefs,
            exps,
            degree: parts.iter().map(|g| g.degree).max().unwrap_or(0),
            most_terms,
        }
    }

    /// For each partial, [`Compiled::eval_with_bound_on`] on `pw` (a table of powers up to
    /// at least [`Gradient::degree`]): the values and the sums of the terms' magnitudes, the
    /// same bits.
    #[inline]
    pub fn eval_with_bound_on(&self, pw: &Powers) -> ([f64; 3], [f64; 3]) {
        let pw = &pw.0;
        let (mut v, mut m) = ([0.0f64; 3], [0.0f64; 3]);
        for (c, e) in self.coefs.iter().zip(&self.exps) {
            for k in 0..3 {
                let x = c[k]
                    * pw[0][e[k][0] as usize]
                    * pw[1][e[k][1] as usize]
                    * pw[2][e[k][2] as usize];
                v[k] += x;
                m[k] += x.abs();
            }
        }
        (v, m)
    }

    /// [`Gradient::eval_with_bound_on`] at [`LANES`] points at once, from their table of
    /// powers: entry `[k][i]` of each half is component `k` at point `i`, the same bits as
    /// point `i` alone. Compiled for AVX2 as well, chosen at run time.
    #[inline]
    pub fn eval_with_bound_lanes(
        &self,
        pw: &PowersLanes,
    ) -> ([[f64; LANES]; 3], [[f64; LANES]; 3]) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.eval_with_bound_lanes_avx2(pw) };
        }
        self.eval_with_bound_lanes_in(pw)
    }

    /// [`Gradient::eval_with_bound_lanes`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn eval_with_bound_lanes_avx2(
        &self,
        pw: &PowersLanes,
    ) -> ([[f64; LANES]; 3], [[f64; LANES]; 3]) {
        self.eval_with_bound_lanes_in(pw)
    }

    /// [`Gradient::eval_with_bound_lanes`] for the baseline instruction set (and inlined into
    /// the AVX2 version): each lane's sums take their terms in
    /// [`Gradient::eval_with_bound_on`]'s order and operations.
    #[inline(always)]
    fn eval_with_bound_lanes_in(&self, pw: &PowersLanes) -> ([[f64; LANES]; 3], [[f64; LANES]; 3]) {
        let pw = &pw.0;
        let (mut v, mut m) = ([[0.0f64; LANES]; 3], [[0.0f64; LANES]; 3]);
        for (c, e) in self.coefs.iter().zip(&self.exps) {
            for k in 0..3 {
                let (a, b, d) = (
                    &pw[0][e[k][0] as usize],
                    &pw[1][e[k][1] as usize],
                    &pw[2][e[k][2] as usize],
                );
                for i in 0..LANES {
                    let x = c[k] * a[i] * b[i] * d[i];
                    v[k][i] += x;
                    m[k][i] += x.abs();
                }
            }
        }
        (v, m)
    }
}

/// The powers of the coordinates of [`LANES`] points, for [`Gradient::eval_with_bound_lanes`]:
/// entry `[v][k][i]` is coordinate `v` of point `i` to the power `k`, the same bits as
/// [`Powers::new`] of that point.
pub struct PowersLanes([[[f64; LANES]; MAX_DEGREE + 1]; 3]);

impl PowersLanes {
    /// The powers of the points' coordinates up to `degree` (at most [`MAX_DEGREE`]).
    #[inline]
    pub fn new(points: &[[f64; 3]; LANES], degree: usize) -> PowersLanes {
        // Entries above the degree are never read; zero is the cheapest fill.
        let mut pw = [[[0.0; LANES]; MAX_DEGREE + 1]; 3];
        with_degree!(degree, D => {
            for (v, row) in pw.iter_mut().enumerate() {
                powers_lanes_into::<D>(row, std::array::from_fn(|i| points[i][v]));
            }
        });
        PowersLanes(pw)
    }
}

/// [`powers_into`] for [`LANES`] values at once: `row[k][i] ← x[i]ᵏ` for `k ≤ D`.
#[inline(always)]
fn powers_lanes_into<const D: usize>(row: &mut [[f64; LANES]; MAX_DEGREE + 1], x: [f64; LANES]) {
    row[0] = [1.0; LANES];
    for k in 1..=D {
        row[k] = std::array::from_fn(|i| row[k - 1][i] * x[i]);
    }
}

/// `row[k] ← xᵏ` for `k ≤ D`, each the previous one times `x`.
#[inline(always)]
fn powers_into<const D: usize>(row: &mut [f64; MAX_DEGREE + 1], x: f64) {
    row[0] = 1.0;
    for k in 1..=D {
        row[k] = row[k - 1] * x;
    }
}

/// Univariate coefficients (ascending) in fixed storage.
pub type Uni = [f64; MAX_DEGREE + 1];

/// The arithmetic a ray composition runs in: `f64`, or [`Dd`] where `f64` cannot resolve
/// the polynomial.
pub trait Scalar: Copy + Add<Output = Self> + Mul<Output = Self> {
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// The coefficient of a term in this arithmetic.
    fn coef(t: &Term) -> Self;
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    #[inline]
    fn coef(t: &Term) -> f64 {
        t.c
    }
}

impl Scalar for Dd {
    const ZERO: Dd = Dd::ZERO;
    const ONE: Dd = Dd::from_f64(1.0);
    #[inline]
    fn coef(t: &Term) -> Dd {
        Dd { hi: t.c, lo: t.lo }
    }
}

/// How many rays [`Compiled::compose_lanes`] composes at once.
pub const LANES: usize = crate::shapes::LANES;

/// [`Compiled::magnitude_bound`] at `p` from the terms' magnitudes summed per degree,
/// `by_degree[d]` for degree `d`.
#[inline(always)]
fn magnitude_bound_from(by_degree: &[f64], p: [f64; 3]) -> f64 {
    let r = p[0].abs().max(p[1].abs()).max(p[2].abs());
    let b = by_degree.iter().rev().fold(0.0f64, |b, &a| b * r + a);
    // Every rounding of both sums is a factor within (1 ± ε); a thousand terms and degree 16
    // stay far below this margin.
    b * (1.0 + 1e-9)
}

/// One `f64` per ray, with lane-wise `+`, `−` and `·`: each lane of a composition in this
/// arithmetic gets exactly the bits the `f64` composition of its ray alone gets.
#[derive(Clone, Copy, Debug)]
pub(super) struct Lanes(pub(super) [f64; LANES]);

impl Lanes {
    /// `x` in every lane.
    #[inline(always)]
    pub(super) const fn splat(x: f64) -> Lanes {
        Lanes([x; LANES])
    }
}

impl Sub for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn sub(self, o: Lanes) -> Lanes {
        Lanes(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}

impl Add for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn add(self, o: Lanes) -> Lanes {
        Lanes(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl Mul for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn mul(self, o: Lanes) -> Lanes {
        Lanes(std::array::from_fn(|i| self.0[i] * o.0[i]))
    }
}

impl Scalar for Lanes {
    const ZERO: Lanes = Lanes::splat(0.0);
    const ONE: Lanes = Lanes::splat(1.0);
    #[inline(always)]
    fn coef(t: &Term) -> Lanes {
        Lanes::splat(t.c)
    }
}

/// Offset of row `k` (the `k + 1` coefficients of `Z(s)ᵏ`) in the triangular table of powers.
#[inline(always)]
const fn tri(k: usize) -> usize {
    k * (k + 1) / 2
}

impl Compiled {
    /// Rounds the exact coefficients once (keeping the remainders for [`Dd`] work) and sorts
    /// the terms.
    pub fn new(p: &Poly) -> Compiled {
        let terms: Vec<Term> = p
            .terms
            .iter()
            .map(|(&e, &c)| {
                let d = c.to_dd();
                Term {
                    e,
                    c: d.hi,
                    lo: d.lo,
                }
            })
            .filter(|t| t.c != 0.0)
            .collect();
        Compiled::from_terms(terms, p.degree())
    }

    /// A compiled polynomial from terms given directly (any order), of the given total
    /// degree (at least that of every term, at most [`MAX_DEGREE`]).
    pub fn from_terms(mut terms: Vec<Term>, degree: usize) -> Compiled {
        terms.sort_by(|a, b| (b.e[0], b.e[1], a.e[2]).cmp(&(a.e[0], a.e[1], b.e[2])));
        let max_z = terms.iter().map(|t| t.e[2] as usize).max().unwrap_or(0);
        let steps = schedule(&terms);
        let mut magnitude_by_degree = [0.0; MAX_DEGREE + 1];
        for t in &terms {
            magnitude_by_degree[degree_of(&t.e)] += t.c.abs();
        }
        Compiled {
            terms,
            degree,
            max_z,
            magnitude_by_degree,
            steps,
        }
    }

    /// The value at `p`.
    #[inline]
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        self.eval_with_bound(p).0
    }

    /// The value at `p` and `Σ |c|·|xⁱ yʲ zᵏ|` over the terms (the scale of the rounding
    /// error of the value: it is within a few `(degree + terms)·ε` of that).
    #[inline]
    pub fn eval_with_bound(&self, p: [f64; 3]) -> (f64, f64) {
        self.eval_with_bound_on(&Powers::new(p, self.degree))
    }

    /// An upper bound of the second part of [`Compiled::eval_with_bound`] at `p` (the
    /// computed `Σ |c|·|xⁱ yʲ zᵏ|`, its rounding included), from the terms' magnitudes per
    /// degree and the largest coordinate alone: cheaper, and at most a few times larger
    /// (`+∞` or NaN where it overflows).
    #[inline]
    pub fn magnitude_bound(&self, p: [f64; 3]) -> f64 {
        magnitude_bound_from(&self.magnitude_by_degree[..=self.degree], p)
    }

    /// [`Compiled::magnitude_bound`] at [`LANES`] points (`p[axis][i]`), for a polynomial of
    /// `D` coefficients (`D = degree + 1`; the loop's length fixed): the same bits as one at
    /// a time.
    #[inline(always)]
    pub fn magnitude_bound_lanes<const D: usize>(&self, p: &[[f64; LANES]; 3]) -> [f64; LANES] {
        debug_assert_eq!(D, self.degree + 1);
        let by_degree: &[f64; D] = self.magnitude_by_degree[..D]
            .try_into()
            .expect("D is the degree plus one");
        std::array::from_fn(|i| magnitude_bound_from(by_degree, [p[0][i], p[1][i], p[2][i]]))
    }

    /// [`Compiled::eval_with_bound`] from a table of the point's coordinate powers (at least
    /// up to this polynomial's degree), so that several polynomials at one point share it.
    #[inline]
    pub fn eval_with_bound_on(&self, pw: &Powers) -> (f64, f64) {
        let pw = &pw.0;
        let (mut v, mut m) = (0.0, 0.0);
        for t in &self.terms {
            let x = t.c * pw[0][t.e[0] as usize] * pw[1][t.e[1] as usize] * pw[2][t.e[2] as usize];
            v += x;
            m += x.abs();
        }
        (v, m)
    }

    /// The value at `p` (exact `f64` coordinates) in double-double arithmetic, with the
    /// exact coefficients: accurate to about `1e-31` of `Σ |terms|`. Compiled with fused
    /// multiply-adds in hardware as well, chosen at run time (the same bits either way).
    pub fn eval_dd(&self, p: [f64; 3]) -> Dd {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::fma() {
            // SAFETY: the processor has FMA, checked just above.
            return unsafe { self.eval_dd_fma(p) };
        }
        self.eval_dd_in(p)
    }

    /// [`Compiled::eval_dd`] compiled for FMA.
    ///
    /// # Safety
    /// The processor must have FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn eval_dd_fma(&self, p: [f64; 3]) -> Dd {
        self.eval_dd_in(p)
    }

    /// [`Compiled::eval_dd`] for the baseline instruction set (and inlined into the FMA
    /// version).
    #[inline(always)]
    fn eval_dd_in(&self, p: [f64; 3]) -> Dd {
        let mut pw = [[Dd::from_f64(1.0); MAX_DEGREE + 1]; 3];
        for (v, row) in pw.iter_mut().enumerate() {
            for k in 1..=self.degree {
                row[k] = row[k - 1] * Dd::from_f64(p[v]);
            }
        }
        // A plain loop (not a closure), so that it is compiled with the caller's FMA.
        let mut acc = Dd::ZERO;
        for t in &self.terms {
            acc = acc
                + Dd::coef(t)
                    * pw[0][t.e[0] as usize]
                    * pw[1][t.e[1] as usize]
                    * pw[2][t.e[2] as usize];
        }
        acc
    }

    /// The coefficients (ascending in `s`) of `f(o + s·e)`, computed without expanding any
    /// symbol: powers of `Z(s) = o_z + s·e_z` once, then a Horner scheme in `Y(s)` inside a
    /// Horner scheme in `X(s)`; every step is a multiplication by a linear polynomial, so the
    /// cost is O(terms × degree) and nothing is allocated.
    pub fn compose(&self, o: [f64; 3], e: [f64; 3]) -> Uni {
        let mut out = [0.0; MAX_DEGREE + 1];
        self.compose_into(o, e, &mut out);
        out
    }

    /// [`Compiled::compose`] of [`LANES`] rays at once (ray `i` is `o[axis][i] + s·e[axis][i]`)
    /// into `out` by power (at least `degree + 1` entries): `out[k][i]` for `k ≤ degree`
    /// becomes exactly `self.compose(…)[k]` of ray `i`, bit for bit (the entries above the
    /// degree, zero in `compose`, are left as they are). Compiled for AVX2 as well, chosen
    /// at run time.
    pub fn compose_lanes(
        &self,
        o: &[[f64; LANES]; 3],
        e: &[[f64; LANES]; 3],
        out: &mut [[f64; LANES]],
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.compose_lanes_avx2(o, e, out) };
        }
        self.compose_lanes_in(o, e, out)
    }

    /// [`Compiled::compose_lanes`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn compose_lanes_avx2(
        &self,
        o: &[[f64; LANES]; 3],
        e: &[[f64; LANES]; 3],
        out: &mut [[f64; LANES]],
    ) {
        self.compose_lanes_in(o, e, out)
    }

    /// [`Compiled::compose_lanes`] for the baseline instruction set (and inlined into the
    /// AVX2 version).
    #[inline(always)]
    fn compose_lanes_in(
        &self,
        o: &[[f64; LANES]; 3],
        e: &[[f64; LANES]; 3],
        out: &mut [[f64; LANES]],
    ) {
        let mut lanes = [Lanes::ZERO; MAX_DEGREE + 1];
        self.compose_in(o.map(Lanes), e.map(Lanes), &mut lanes);
        // Only the coefficients up to the degree: the rest are zero, and left as they are.
        for (o, c) in out.iter_mut().zip(&lanes).take(self.degree + 1) {
            *o = c.0;
        }
    }

    /// [`Compiled::compose_into`] in double-double arithmetic, compiled with fused
    /// multiply-adds in hardware as well, chosen at run time (the same bits either way).
    pub fn compose_dd(&self, o: [Dd; 3], e: [Dd; 3], out: &mut [Dd; MAX_DEGREE + 1]) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::fma() {
            // SAFETY: the processor has FMA, checked just above.
            return unsafe { self.compose_dd_fma(o, e, out) };
        }
        self.compose_in(o, e, out)
    }

    /// [`Compiled::compose_dd`] compiled for FMA.
    ///
    /// # Safety
    /// The processor must have FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn compose_dd_fma(&self, o: [Dd; 3], e: [Dd; 3], out: &mut [Dd; MAX_DEGREE + 1]) {
        self.compose_in(o, e, out)
    }

    /// [`Compiled::compose`] into `out` (all `MAX_DEGREE + 1` entries are written; those
    /// above the degree are zero), in the arithmetic `T`: `f64`, or [`Dd`] with the exact
    /// coefficients for the few rays where `f64` cannot resolve the surface.
    #[inline]
    pub fn compose_into<T: Scalar>(&self, o: [T; 3], e: [T; 3], out: &mut [T; MAX_DEGREE + 1]) {
        self.compose_in(o, e, out);
    }

    /// [`Compiled::compose_into`], always inlined.
    #[inline(always)]
    fn compose_in<T: Scalar>(&self, o: [T; 3], e: [T; 3], out: &mut [T; MAX_DEGREE + 1]) {
        // The table of powers of Z, no larger than the surface needs (it is zeroed per ray).
        match self.max_z {
            0..=4 => self.compose_with_table::<T, { tri(5) }>(o, e, out),
            5..=8 => self.compose_with_table::<T, { tri(9) }>(o, e, out),
            _ => self.compose_with_table::<T, { tri(MAX_DEGREE + 1) }>(o, e, out),
        }
    }

    /// [`Compiled::compose_into`] with a table of `ZN ≥ tri(max_z + 1)` entries for the
    /// powers of `Z(s)`.
    #[inline(always)]
    fn compose_with_table<T: Scalar, const ZN: usize>(
        &self,
        o: [T; 3],
        e: [T; 3],
        out: &mut [T; MAX_DEGREE + 1],
    ) {
        // Z(s)^k for k ≤ max_z, row k at tri(k).
        let mut zp = [T::ZERO; ZN];
        zp[0] = T::ONE;
        for k in 1..=self.max_z {
            let (prev, cur) = zp.split_at_mut(tri(k));
            let prev = &prev[tri(k - 1)..];
            with_degree!(k - 1, D => times_linear_from::<T, D>(prev, cur, o[2], e[2]));
        }
        out.fill(T::ZERO);
        let mut hy = [T::ZERO; MAX_DEGREE + 1];
        let mut terms = self.terms.iter();
        for &step in &self.steps {
            match step {
                Step::Term(k) => {
                    let c = T::coef(terms.next().expect("one term per Term step"));
                    with_degree!(k as usize, D => add_scaled::<T, D>(&mut hy, c, &zp[tri(D)..]));
                }
                Step::TimesY(d) => {
                    with_degree!(d as usize, D => times_linear::<T, D>(&mut hy, o[1], e[1]))
                }
                Step::TimesY2(d) => with_degree!(d as usize, D => {
                    times_linear::<T, D>(&mut hy, o[1], e[1]);
                    times_linear::<T, { D + 1 }>(&mut hy, o[1], e[1]);
                }),
                Step::Flush(d) => with_degree!(d as usize, D => flush::<T, D>(out, &mut hy)),
                Step::TimesX(d) => {
                    with_degree!(d as usize, D => times_linear::<T, D>(out, o[0], e[0]))
                }
                Step::TimesX2(d) => with_degree!(d as usize, D => {
                    times_linear::<T, D>(out, o[0], e[0]);
                    times_linear::<T, { D + 1 }>(out, o[0], e[0]);
                }),
            }
        }
    }
}

/// The steps [`Compiled::compose_into`] takes for `terms` (sorted by descending x-exponent,
/// then descending y-exponent, then ascending z-exponent): `h_i(s) = Σ_j Y^j Σ_k c_ijk Z^k`
/// by Horner in `Y` for each x-exponent `i`, summed into `f` by Horner in `X`.
fn schedule(terms: &[Term]) -> Vec<Step> {
    let mut steps = Vec::new();
    let mut fx_deg = 0usize;
    let mut cur_i: Option<u8> = None;
    let mut t = 0;
    while t < terms.len() {
        let i = terms[t].e[0];
        if let Some(ci) = cur_i {
            for _ in i..ci {
                steps.push(Step::TimesX(fx_deg as u8));
                fx_deg += 1;
            }
        }
        cur_i = Some(i);
        let mut hy_deg = 0usize;
        let mut cur_j: Option<u8> = None;
        while t < terms.len() && terms[t].e[0] == i {
            let j = terms[t].e[1];
            if let Some(cj) = cur_j {
                for _ in j..cj {
                    steps.push(Step::TimesY(hy_deg as u8));
                    hy_deg += 1;
                }
            }
            cur_j = Some(j);
            while t < terms.len() && terms[t].e[0] == i && terms[t].e[1] == j {
                let k = terms[t].e[2];
                steps.push(Step::Term(k));
                hy_deg = hy_deg.max(k as usize);
                t += 1;
            }
        }
        for _ in 0..cur_j.unwrap_or(0) {
            steps.push(Step::TimesY(hy_deg as u8));
            hy_deg += 1;
        }
        steps.push(Step::Flush(hy_deg as u8));
        fx_deg = fx_deg.max(hy_deg);
    }
    for _ in 0..cur_i.unwrap_or(0) {
        steps.push(Step::TimesX(fx_deg as u8));
        fx_deg += 1;
    }
    // Two multiplications by the same factor in a row become one step.
    let mut fused: Vec<Step> = Vec::with_capacity(steps.len());
    for step in steps {
        match (fused.last(), step) {
            (Some(&Step::TimesY(d)), Step::TimesY(n)) if n == d + 1 => {
                *fused.last_mut().unwrap() = Step::TimesY2(d)
            }
            (Some(&Step::TimesX(d)), Step::TimesX(n)) if n == d + 1 => {
                *fused.last_mut().unwrap() = Step::TimesX2(d)
            }
            _ => fused.push(step),
        }
    }
    fused
}

/// `p ← p · (a + b·s)` for `p` of degree `D` (the result has degree `D + 1`; `D < MAX_DEGREE`).
#[inline(always)]
fn times_linear<T: Scalar, const D: usize>(p: &mut [T; MAX_DEGREE + 1], a: T, b: T) {
    times_linear_row::<T, D>(&mut p[..], a, b);
}

/// [`times_linear`] on a slice of at least `D + 2` entries.
#[inline(always)]
fn times_linear_row<T: Scalar, const D: usize>(p: &mut [T], a: T, b: T) {
    let p = &mut p[..D + 2];
    p[D + 1] = b * p[D];
    let mut k = D;
    while k > 0 {
        p[k] = a * p[k] + b * p[k - 1];
        k -= 1;
    }
    p[0] = a * p[0];
}

/// `to[..D + 2] ← from[..=D] · (a + b·s)`: [`times_linear`] of a copy, without the copy.
#[inline(always)]
fn times_linear_from<T: Scalar, const D: usize>(from: &[T], to: &mut [T], a: T, b: T) {
    let (p, to) = (&from[..=D], &mut to[..D + 2]);
    to[D + 1] = b * p[D];
    let mut k = D;
    while k > 0 {
        to[k] = a * p[k] + b * p[k - 1];
        k -= 1;
    }
    to[0] = a * p[0];
}

/// `h[..=D] ← h[..=D] + c·z[..=D]`.
#[inline(always)]
fn add_scaled<T: Scalar, const D: usize>(h: &mut [T; MAX_DEGREE + 1], c: T, z: &[T]) {
    let z = &z[..=D];
    for m in 0..=D {
        h[m] = h[m] + c * z[m];
    }
}

/// `f[..=D] ← f[..=D] + h[..=D]`, then `h[..=D] ← 0` (the rest of `h` is zero already).
#[inline(always)]
fn flush<T: Scalar, const D: usize>(f: &mut [T; MAX_DEGREE + 1], h: &mut [T; MAX_DEGREE + 1]) {
    for m in 0..=D {
        f[m] = f[m] + h[m];
        h[m] = T::ZERO;
    }
}

/// Largest `|value|` of the homogeneous part of degree `k` on the unit sphere, bounded above
/// by the sum of its coefficients' magnitudes (|xⁱyʲzᵏ| ≤ 1 there).
fn part_bound(c: &Compiled, k: usize) -> f64 {
    c.terms
        .iter()
        .filter(|t| degree_of(&t.e) == k)
        .map(|t| t.c.abs())
        .sum()
}

/// A radius outside which `f` has no zeros, when one can be derived: the highest-degree part
/// `f_n` must keep one sign on the unit sphere (checked on a dense set of directions, with a
/// safety factor of 2 on its smallest magnitude `m`), and then `|f(r·u)| ≥ m rⁿ − Σ_k M_k rᵏ`
/// is positive beyond the returned radius. `None` when the surface may be unbounded.
pub fn derive_bound(c: &Compiled) -> Option<f64> {
    let n = c.degree;
    if n == 0 {
        return None;
    }
    let top = Compiled::from_terms(
        c.terms
            .iter()
            .copied()
            .filter(|t| degree_of(&t.e) == n)
            .collect(),
        n,
    );
    // Fibonacci-sphere directions.
    const SAMPLES: usize = 4000;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in 0..SAMPLES {
        let z = 1.0 - 2.0 * (s as f64 + 0.5) / SAMPLES as f64;
        let r = (1.0 - z * z).sqrt();
        let a = golden * s as f64;
        let v = top.eval([r * a.cos(), r * a.sin(), z]);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let (m_min, m_max) = if lo > 0.0 {
        (lo, hi)
    } else if hi < 0.0 {
        (-hi, -lo)
    } else {
        return None;
    };
    if m_min < 1e-3 * m_max {
        return None;
    }
    let m = 0.5 * m_min;
    let lower: Vec<f64> = (0..n).map(|k| part_bound(c, k)).collect();
    // g(r) = m − Σ M_k r^(k−n) increases with r; find where it turns positive.
    let g = |r: f64| {
        m - lower
            .iter()
            .enumerate()
            .map(|(k, mk)| mk * r.powi(k as i32 - n as i32))
            .sum::<f64>()
    };
    let mut hi_r = 1.0;
    while g(hi_r) <= 0.0 {
        hi_r *= 2.0;
        if hi_r > 1e12 {
            return None;
        }
    }
    let mut lo_r = 0.0;
    for _ in 0..60 {
        let mid = 0.5 * (lo_r + hi_r);
        if g(mid) > 0.0 {
            hi_r = mid;
        } else {
            lo_r = mid;
        }
    }
    Some(hi_r * 1.01)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::expand;

    // The composition as first written (runtime loop bounds, no schedule): the scheduled one
    // must give the same bits, signed zeros included, in both arithmetics.
    /// `p ← p · (a + b·s)` for a polynomial of degree `deg` stored in `p[..=deg]`; the result
    /// has degree `deg + 1` (the caller keeps `deg + 1` within `p`).
    #[inline(always)]
    fn mul_linear<T: Scalar>(p: &mut [T], deg: usize, a: T, b: T) {
        p[deg + 1] = b * p[deg];
        let mut k = deg;
        while k > 0 {
            p[k] = a * p[k] + b * p[k - 1];
            k -= 1;
        }
        p[0] = a * p[0];
    }

    fn compose_reference<T: Scalar>(c: &Compiled, o: [T; 3], e: [T; 3]) -> [T; MAX_DEGREE + 1] {
        let mut out = [T::ZERO; MAX_DEGREE + 1];
        let mut zp = [T::ZERO; tri(MAX_DEGREE + 1)];
        zp[0] = T::ONE;
        for k in 1..=c.max_z {
            let (prev, cur) = zp.split_at_mut(tri(k));
            let row = &mut cur[..=k];
            row[..k].copy_from_slice(&prev[tri(k - 1)..tri(k - 1) + k]);
            mul_linear(row, k - 1, o[2], e[2]);
        }
        let mut fx_deg = 0usize;
        let mut hy = [T::ZERO; MAX_DEGREE + 1];
        let mut cur_i: Option<u8> = None;
        let terms = &c.terms;
        let mut t = 0;
        while t < terms.len() {
            let i = terms[t].e[0];
            if let Some(ci) = cur_i {
                for _ in i..ci {
                    mul_linear(&mut out, fx_deg, o[0], e[0]);
                    fx_deg += 1;
                }
            }
            cur_i = Some(i);
            let mut hy_deg = 0usize;
            hy.fill(T::ZERO);
            let mut cur_j: Option<u8> = None;
            while t < terms.len() && terms[t].e[0] == i {
                let j = terms[t].e[1];
                if let Some(cj) = cur_j {
                    for _ in j..cj {
                        mul_linear(&mut hy, hy_deg, o[1], e[1]);
                        hy_deg += 1;
                    }
                }
                cur_j = Some(j);
                while t < terms.len() && terms[t].e[0] == i && terms[t].e[1] == j {
                    let k = terms[t].e[2] as usize;
                    let c = T::coef(&terms[t]);
                    for (h, &z) in hy[..=k].iter_mut().zip(&zp[tri(k)..=tri(k) + k]) {
                        *h = *h + c * z;
                    }
                    hy_deg = hy_deg.max(k);
                    t += 1;
                }
            }
            for _ in 0..cur_j.unwrap_or(0) {
                mul_linear(&mut hy, hy_deg, o[1], e[1]);
                hy_deg += 1;
            }
            for (f, &h) in out[..=hy_deg].iter_mut().zip(&hy[..=hy_deg]) {
                *f = *f + h;
            }
            fx_deg = fx_deg.max(hy_deg);
        }
        for _ in 0..cur_i.unwrap_or(0) {
            mul_linear(&mut out, fx_deg, o[0], e[0]);
            fx_deg += 1;
        }
        out
    }

    /// Surfaces of every degree from 1 to 16 with gaps in every exponent, and the presets.
    fn composition_surfaces_polys() -> Vec<Poly> {
        let mut eqs: Vec<String> = [
            "x - 2*y + 0.5*z + 3",
            "x^2 + y^2 + z^2 - 1",
            "x*y*z - 0.3",
            "(x^2 + y^2 + z^2)^8 - 1",
            "(x + y + z + 1)^16",
            "(x - 0.25*y)^5 + z^7 - x^3*y*z^2 + 1e-3",
            "x^9*z^2 - y^11 + z^4*y - 2",
            "-(x^2 + 9/4*y^2 + z^2 - 1)^3 + x^2*z^3 + 9/80*y^2*z^3",
            "z^13 - 3*x*z^6 + y^2",
        ]
        .map(String::from)
        .to_vec();
        for (name, params) in [
            ("torus", vec![1.0, 0.3]),
            ("barth_sextic", vec![]),
            ("chmutov", vec![8.0]),
            ("chmutov", vec![16.0]),
            ("taubin_heart", vec![]),
            ("kummer", vec![0.5]),
            ("clebsch", vec![]),
        ] {
            eqs.push(crate::shapes::implicit::preset_equation(name, &params).unwrap());
        }
        eqs.iter().map(|eq| expand(eq).unwrap()).collect()
    }

    /// [`composition_surfaces_polys`] compiled.
    fn composition_surfaces() -> Vec<Compiled> {
        composition_surfaces_polys()
            .iter()
            .map(Compiled::new)
            .collect()
    }

    #[test]
    fn the_scheduled_composition_gives_the_bits_of_the_first_one() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        // Coordinates with exact zeros of both signs (axis-aligned rays, rays through the
        // origin), tiny and large values, besides ordinary ones.
        let coordinate = |r: u64| match r % 8 {
            0 => 0.0,
            1 => -0.0,
            2 => (r >> 8) as f64 * 1e-300 * if r & 256 == 0 { 1.0 } else { -1.0 },
            3 => 1.0,
            _ => ((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 4.0,
        };
        for c in composition_surfaces() {
            for _ in 0..400 {
                let o = [0; 3].map(|_| coordinate(next()));
                let e = [0; 3].map(|_| coordinate(next()));
                let got = c.compose(o, e);
                let want = compose_reference::<f64>(&c, o, e);
                assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{o:?} {e:?}");
                let (od, ed) = (o.map(Dd::from_f64), e.map(|v| Dd::from_f64(v * 0.5)));
                let mut got = [Dd::ZERO; MAX_DEGREE + 1];
                c.compose_into(od, ed, &mut got);
                let want = compose_reference::<Dd>(&c, od, ed);
                let bits = |v: [Dd; MAX_DEGREE + 1]| v.map(|d| (d.hi.to_bits(), d.lo.to_bits()));
                assert_eq!(bits(got), bits(want), "{o:?} {e:?}");
                // The version chosen at run time (with hardware FMA where there is one).
                let mut got = [Dd::ZERO; MAX_DEGREE + 1];
                c.compose_dd(od, ed, &mut got);
                assert_eq!(bits(got), bits(want), "{o:?} {e:?}");
                // Its value in double-double at the ray's origin, on both code paths.
                let (a, b) = (c.eval_dd(o), c.eval_dd_in(o));
                assert_eq!(
                    (a.hi.to_bits(), a.lo.to_bits()),
                    (b.hi.to_bits(), b.lo.to_bits())
                );
            }
        }
    }

    #[test]
    fn four_rays_composed_together_get_the_bits_each_gets_alone() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut coordinate = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            match state % 6 {
                0 => 0.0,
                1 => -0.0,
                _ => ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 4.0,
            }
        };
        for c in composition_surfaces() {
            for _ in 0..100 {
                let o: [[f64; LANES]; 3] = [0; 3].map(|_| [0; LANES].map(|_| coordinate()));
                let e: [[f64; LANES]; 3] = [0; 3].map(|_| [0; LANES].map(|_| coordinate()));
                let ray = |v: &[[f64; LANES]; 3], i: usize| [v[0][i], v[1][i], v[2][i]];
                let alone: [Uni; LANES] =
                    std::array::from_fn(|i| c.compose(ray(&o, i), ray(&e, i)));
                let bits = |v: [[f64; LANES]; MAX_DEGREE + 1]| v.map(|u| u.map(f64::to_bits));
                // The baseline code path, whatever the processor, and the one chosen at run
                // time, into a buffer that holds something else before.
                // Up to the degree; the entries above it are left as they were.
                let want: [[f64; LANES]; MAX_DEGREE + 1] = std::array::from_fn(|k| {
                    std::array::from_fn(|i| if k <= c.degree { alone[i][k] } else { f64::NAN })
                });
                let mut out = [[f64::NAN; LANES]; MAX_DEGREE + 1];
                c.compose_lanes_in(&o, &e, &mut out);
                assert_eq!(bits(out), bits(want));
                let mut out = [[f64::NAN; LANES]; MAX_DEGREE + 1];
                c.compose_lanes(&o, &e, &mut out);
                assert_eq!(bits(out), bits(want));
            }
        }
    }

    #[test]
    fn the_magnitude_bound_is_never_below_the_computed_magnitude_sum() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut coordinate = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            match state % 5 {
                0 => 0.0,
                1 => u * 1e-200,
                2 => u * 1e3,
                _ => u * 5.0,
            }
        };
        for c in composition_surfaces() {
            for _ in 0..2000 {
                let p = [0; 3].map(|_| coordinate());
                let (bound, sum) = (c.magnitude_bound(p), c.eval_with_bound(p).1);
                assert!(bound >= sum, "{p:?}: bound {bound} below {sum}");
            }
        }
    }

    #[test]
    fn the_gradient_in_one_pass_gives_each_partial_exactly() {
        // Partials with different numbers of terms (padding in every column), a partial that
        // is zero, and points with zero and negative coordinates.
        for eq in [
            "(x^2 + y^2 + z^2)^4 - 3*x^5*y*z^2 + x^3 - y*z + 0.25",
            "x^3 + y - 1",
            "x*y*z - 0.3",
        ]
        .map(|eq| expand(eq).unwrap())
        .iter()
        .chain(composition_surfaces_polys().iter())
        {
            let parts: [Compiled; 3] = std::array::from_fn(|v| Compiled::new(&eq.derivative(v)));
            let g = Gradient::new(&parts);
            for p in [
                [0.3, -0.7, 1.1],
                [1e-3, 2.5, -0.25],
                [-1.5, 0.0, 0.9],
                [-0.0, -2.0, 0.0],
                [0.0, 0.0, 0.0],
            ] {
                let powers = Powers::new(p, g.degree);
                let (v, m) = g.eval_with_bound_on(&powers);
                for k in 0..3 {
                    let (a, b) = parts[k].eval_with_bound_on(&powers);
                    assert_eq!((v[k].to_bits(), m[k].to_bits()), (a.to_bits(), b.to_bits()));
                }
            }
        }
    }

    #[test]
    fn the_gradient_in_lanes_gives_each_point_exactly_in_both_copies() {
        // Four points a group (zero and negative coordinates, one point far out), on the
        // surfaces of the test above: each lane as the point alone, in the baseline copy and
        // in the one chosen at run time (AVX2 where the processor has it).
        let points = [
            [0.3, -0.7, 1.1],
            [1e-3, 2.5, -0.25],
            [-1.5, 0.0, 0.9],
            [-0.0, -2.0, 0.0],
            [0.0, 0.0, 0.0],
            [13.0, -0.125, 7.5],
            [0.6, 0.6, -0.6],
            [-1e-7, 3.0, 2.0],
        ];
        for eq in [
            "(x^2 + y^2 + z^2)^4 - 3*x^5*y*z^2 + x^3 - y*z + 0.25",
            "x*y*z - 0.3",
        ]
        .map(|eq| expand(eq).unwrap())
        .iter()
        .chain(composition_surfaces_polys().iter())
        {
            let parts: [Compiled; 3] = std::array::from_fn(|v| Compiled::new(&eq.derivative(v)));
            let g = Gradient::new(&parts);
            for group in points.chunks_exact(LANES) {
                let group: [[f64; 3]; LANES] = std::array::from_fn(|i| group[i]);
                let powers = PowersLanes::new(&group, g.degree);
                for (v, m) in [
                    g.eval_with_bound_lanes_in(&powers),
                    g.eval_with_bound_lanes(&powers),
                ] {
                    for (i, &p) in group.iter().enumerate() {
                        let (want_v, want_m) = g.eval_with_bound_on(&Powers::new(p, g.degree));
                        for k in 0..3 {
                            assert_eq!(
                                (v[k][i].to_bits(), m[k][i].to_bits()),
                                (want_v[k].to_bits(), want_m[k].to_bits()),
                                "{p:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_shared_table_of_powers_gives_each_value_exactly() {
        // The three partial derivatives of a degree-8 surface (degree 7 each, with terms of
        // every exponent) evaluated on one table of the highest degree, and a cubic on it.
        let f = expand("(x^2 + y^2 + z^2)^4 - 3*x^5*y*z^2 + x^3 - y*z + 0.25").unwrap();
        let parts: Vec<Compiled> = (0..3).map(|v| Compiled::new(&f.derivative(v))).collect();
        let cubic = Compiled::new(&expand("x^3 - 2*y^2*z + z - 1").unwrap());
        for p in [[0.3, -0.7, 1.1], [1e-3, 2.5, -0.25], [-1.5, 0.0, 0.9]] {
            let powers = Powers::new(p, 7);
            for c in parts.iter().chain([&cubic]) {
                let (a, b) = (c.eval_with_bound_on(&powers), c.eval_with_bound(p));
                assert_eq!(
                    (a.0.to_bits(), a.1.to_bits()),
                    (b.0.to_bits(), b.1.to_bits())
                );
            }
        }
    }
}
