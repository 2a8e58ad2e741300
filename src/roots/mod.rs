//! Real roots of univariate polynomials: the paper's Sturm sequences + false position, and a
//! faster alternative. Coefficients are always in ascending powers: `c0 + c1·t + … + cn·tⁿ`.
//!
//! Both strategies share one preparation (`prep`): non-finite input, `lo ≥ hi` and the zero
//! polynomial give no roots; a leading coefficient negligible on the interval is dropped (the
//! rule: `|cₙ|·R^(n−i) ≤ ε·|cᵢ|` for some `i < n`, with `R = max(|lo|, |hi|)` and `ε` the
//! machine epsilon, i.e. the leading term is below one rounding unit of another term all over
//! the interval; an infinite interval trims exact zeros only); the variable is rescaled by a
//! power of two (exactly) so that the interval, or the roots if smaller, has size about one.
//!
//! A multiple root is reported once, at its location. What "distinct" means numerically is
//! set by the rounding bound `δ(t) = 4·(n+1)·ε·Σ|cⱼ||t|ʲ` (the `cluster` module): where `|P|`
//! stays within about `2δ` (a *zero region*), `P` is indistinguishable from zero, and all the
//! roots in one zero region are one root. For a root `r` of multiplicity `m` that region has
//! the radius `ρ = (2δ·m!/|P⁽ᵐ⁾(r)|)^(1/m)`: roots are merged when their radii overlap
//! (within a border band of a factor of a few), whatever the degree, the scale of the
//! variable or an overall factor of the coefficients (`δ` scales with them). No numerical gcd
//! is taken. Simple roots are refined to a few ulps of their magnitude; a root of
//! multiplicity `m` is located as the simple root of `P⁽ᵐ⁻¹⁾` in its zero region.
//!
//! [`sturm_roots`] and [`first_root`] (the paper's method) isolate by a Sturm sequence and
//! refine by false position wherever every sign the sequence needs is certain (`sturm`
//! module: `P` then square-free beyond rounding); otherwise the interval goes to the
//! certain-sign Bernstein subdivision with zero regions (`cluster`), which gives the same
//! answer where both apply.
//!
//! Both first-root queries start with the same cheap test (`bernstein`): the polynomial on
//! the interval in the Bernstein basis, where Descartes' rule of signs (with halving) either
//! proves there is no root, or isolates the first one as a simple root in a sign-change
//! bracket (refined by a safeguarded Newton/Schröder iteration on `P` itself); it answers only
//! when every sign it used is certain (beyond a rounding-error bound larger than the zero
//! regions'), and otherwise leaves the interval to the strategy's own isolation. On the heart
//! corpus it answers for about 98% of the rays; the rest (roots at or near multiple roots, or
//! at the ends) go to the full method.
//!
//! [`Solver::first_root_lanes`] asks four queries of the same length at once (the heart's
//! lanes of four rays): the usual path's fixed part (the fixed-size preparation, the expansion
//! in the Bernstein basis and the whole interval's sign test) runs lane by lane in vector
//! registers (AVX2 where the processor has it, chosen at run time), and each lane that test
//! does not settle goes on alone where the scalar query would, so every lane's answer is the
//! scalar one bit for bit (`lanes` module).
//!
//! Every scale: where one power-of-two scale cannot hold every term on the interval (a
//! coefficient would under- or overflow), [`sturm_roots`] and
//! [`Solver::first_root_at_any_scale`] cut the interval at 0 and into bands of magnitude, each
//! prepared at its own scale (`bands` module); within a part, the subdivision searches a
//! piece near 0 again at the piece's own scale (`cluster` module), so a root is found to a
//! few ulps times its condition wherever it lies (docs/roots.md states the promise).
//!
//! No input makes these functions panic or loop without end (every loop is bounded); none
//! allocates except [`sturm_roots`], for its result.

#[cfg(target_arch = "x86_64")]
#[macro_use]
mod avx2;
mod bands;
mod bernstein;
mod cluster;
mod lanes;
mod prep;
mod refine;
mod sturm;
mod trace;
mod yuksel;

use trace::Observer;
pub use trace::{Path, Trace};

/// Every distinct real root of the polynomial in the half-open interval `(lo, hi]`, ascending.
/// A multiple root is reported once. Degree 0 to 16. Non-finite coefficients, or `lo ≥ hi`,
/// give no roots; so do the zero polynomial and more than 17 coefficients (after dropping
/// trailing zeros). Infinite `lo`/`hi` are allowed.
pub fn sturm_roots(coeffs: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let mut all = Vec::new();
    bands::each(coeffs, lo, hi, &mut |p| {
        all.extend(sturm::all_roots(&p));
        true
    });
    all
}

/// The smallest real root in `(lo, hi]` (normally the first element [`sturm_roots`] returns),
/// found by the Sturm method without computing the others (only the leftmost bracket is
/// isolated and refined), after the Bernstein test (see the module documentation). No heap
/// allocation.
pub fn first_root(coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
    observed(Solver::Sturm, coeffs, lo, hi, &mut ())
}

/// The smallest real root in `(lo, hi]` by the derivative-splitting method (Yuksel 2022):
/// same contract as [`first_root`], including multiple roots reported at the root. The
/// Bernstein test runs first, as for [`first_root`]. No heap allocation.
pub fn first_root_yuksel(coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
    observed(Solver::Yuksel, coeffs, lo, hi, &mut ())
}

/// The first root by `solver`, telling `obs` what it does: the Bernstein test, then the
/// strategy's own isolation where the test declines. The usual polynomial (`D` coefficients,
/// nothing to trim, a bounded interval) is prepared into a fixed-size copy for the test, and
/// the full preparation is made only if the test declines.
#[inline(always)]
fn observed(
    solver: Solver,
    coeffs: &[f64],
    lo: f64,
    hi: f64,
    obs: &mut impl Observer,
) -> Option<f64> {
    macro_rules! fixed {
        ($($d:literal)*) => {
            match coeffs.len() {
                $($d => {
                    let c: &[f64; $d] = coeffs.try_into().expect("length");
                    match prep::prepare_fixed(c, lo, hi) {
                        prep::Usual::Refused => return None,
                        prep::Usual::Fixed(f) => {
                            let fast = bernstein::search(&f, obs);
                            return settle(solver, fast, || f.to_prepared(), obs);
                        }
                        prep::Usual::Other => {}
                    }
                })*
                _ => {}
            }
        };
    }
    fixed!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
    let p = prep::prepare(coeffs, lo, hi)?;
    let fast = bernstein::first_root(&p, obs);
    settle(solver, fast, || p, obs)
}

/// [`observed`] for an interval too wide for one scale (the `bands` module): the first root
/// of the first part, in ascending order, that has one.
fn by_parts(
    solver: Solver,
    coeffs: &[f64],
    lo: f64,
    hi: f64,
    obs: &mut impl Observer,
) -> Option<f64> {
    let mut first = None;
    bands::each(coeffs, lo, hi, &mut |p| {
        let fast = bernstein::first_root(&p, obs);
        first = settle(solver, fast, || p, obs);
        first.is_none()
    });
    first
}

/// The answer of the Bernstein test `fast` when it has one, else `solver`'s on the prepared
/// polynomial.
#[inline(always)]
fn settle(
    solver: Solver,
    fast: bernstein::Fast,
    prepared: impl FnOnce() -> prep::Prepared,
    obs: &mut impl Observer,
) -> Option<f64> {
    match fast {
        bernstein::Fast::NoRoot => {
            obs.settled(Path::Bernstein);
            None
        }
        bernstein::Fast::Root(t) => {
            obs.settled(Path::Bernstein);
            Some(t)
        }
        bernstein::Fast::Undecided => match solver {
            Solver::Sturm => sturm::first_root(&prepared(), obs),
            Solver::Yuksel => {
                obs.settled(Path::Derivatives);
                yuksel::first_root(&prepared(), obs)
            }
        },
    }
}

/// Which root-isolation strategy a shape uses for its first-root queries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// The paper's method: Sturm sequence isolation, false-position refinement, behind the
    /// shared Bernstein test; where the sequence's signs are not certain (multiple or
    /// clustered roots), the zero-region Bernstein subdivision (see the module
    /// documentation). The default: on the heart ray corpus (see `benches/roots.rs`) it
    /// measured about as fast as [`Solver::Yuksel`] (the Bernstein test answers for about 98%
    /// of the rays with both), with the same hit/miss on every ray. A tight interval (the
    /// ray's span inside the shape's bounding box) is best.
    #[default]
    Sturm,
    /// Yuksel 2022: split at the derivative's roots (recursively) into monotonic pieces,
    /// then a bracketed Newton iteration per piece.
    Yuksel,
}

impl Solver {
    /// Every strategy with its command-line name, default first.
    pub const ALL: &'static [(Solver, &'static str)] =
        &[(Solver::Sturm, "sturm"), (Solver::Yuksel, "yuksel")];

    /// The command-line name of this strategy.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map_or("?", |(_, n)| n)
    }

    /// The smallest real root in `(lo, hi]` by this strategy. For a polynomial whose terms
    /// all stay within `f64` once the variable is scaled to the interval (every render's: the
    /// scene limits keep coefficients within far less than the `f64` range of each other, see
    /// docs/roots.md); [`Solver::first_root_at_any_scale`] for any input.
    #[inline]
    pub fn first_root(self, coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
        match self {
            Solver::Sturm => first_root(coeffs, lo, hi),
            Solver::Yuksel => first_root_yuksel(coeffs, lo, hi),
        }
    }

    /// [`Solver::first_root`] for any input: where one scale cannot hold every term of the
    /// polynomial on `(lo, hi]` (a coefficient would under- or overflow, e.g. roots near
    /// `1e-70` in an interval `1e28` wide), the interval is searched in parts of their own
    /// scale, as [`sturm_roots`] does, and the answer is the first of [`sturm_roots`]'s list
    /// (to the accuracy both promise). Otherwise exactly [`Solver::first_root`]. The check
    /// costs one full preparation; no heap allocation.
    pub fn first_root_at_any_scale(self, coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
        match prep::prepare(coeffs, lo, hi) {
            Some(p) if bands::loses_terms(coeffs, &p) => by_parts(self, coeffs, lo, hi, &mut ()),
            _ => self.first_root(coeffs, lo, hi),
        }
    }

    /// [`Solver::first_root`] of [`LANES`](crate::geometry::LANES) polynomials of the same
    /// length `D` at once, each on its own interval `(lo[i], hi[i]]`: lane `i` of the answer
    /// is always exactly `self.first_root(&coeffs[i], lo[i], hi[i])` (bit for bit), and
    /// `None` without any work where `active[i]` is false. Faster per query than one at a
    /// time for the usual polynomial (see the `lanes` module). No heap allocation.
    #[inline]
    pub fn first_root_lanes<const D: usize>(
        self,
        coeffs: &[[f64; D]; crate::geometry::LANES],
        lo: [f64; crate::geometry::LANES],
        hi: [f64; crate::geometry::LANES],
        active: [bool; crate::geometry::LANES],
    ) -> [Option<f64>; crate::geometry::LANES] {
        lanes::first_roots(self, coeffs, lo, hi, active, lanes::Code::Detected)
    }

    /// [`Solver::first_root_lanes`] with the coefficients given by power: `coeffs[j][i]` is
    /// lane `i`'s coefficient of `tʲ` (the same answers, without rearranging them first).
    #[inline]
    pub fn first_root_lanes_by_power<const D: usize>(
        self,
        coeffs: &[[f64; crate::geometry::LANES]; D],
        lo: [f64; crate::geometry::LANES],
        hi: [f64; crate::geometry::LANES],
        active: [bool; crate::geometry::LANES],
    ) -> [Option<f64>; crate::geometry::LANES] {
        lanes::first_roots_by_power(self, coeffs, lo, hi, active, lanes::Code::Detected)
    }

    /// [`Solver::first_root_lanes`] (the same answers) by the code that processors without
    /// AVX2 run, whatever this one has: for tests and benchmarks.
    pub fn first_root_lanes_baseline<const D: usize>(
        self,
        coeffs: &[[f64; D]; crate::geometry::LANES],
        lo: [f64; crate::geometry::LANES],
        hi: [f64; crate::geometry::LANES],
        active: [bool; crate::geometry::LANES],
    ) -> [Option<f64>; crate::geometry::LANES] {
        lanes::first_roots(self, coeffs, lo, hi, active, lanes::Code::Baseline)
    }

    /// [`Solver::first_root`] with the same answer, also adding what the query did to
    /// `trace`: its counts grow, and its path becomes this query's (see [`Trace`]).
    pub fn first_root_traced(
        self,
        coeffs: &[f64],
        lo: f64,
        hi: f64,
        trace: &mut Trace,
    ) -> Option<f64> {
        trace.queries = trace.queries.saturating_add(1);
        trace.path = Path::Refused;
        observed(self, coeffs, lo, hi, trace)
    }
}

impl std::str::FromStr for Solver {
    type Err = String;

    /// Parses a strategy's command-line name (see [`Solver::ALL`]).
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(s))
            .map(|(solver, _)| *solver)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|(_, n)| *n).collect();
                format!("unknown solver '{s}': expected one of {}", names.join(", "))
            })
    }
}
