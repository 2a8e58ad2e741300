//! Real roots of univariate polynomials: the paper's Sturm sequences + false position, and a
//! faster alternative. Coefficients are always in ascending powers: `c0 + c1·t + … + cn·tⁿ`.

/// Every distinct real root of the polynomial in the half-open interval `(lo, hi]`, ascending.
/// A multiple root is reported once. Degree 0 to 16. Non-finite coefficients, or `lo ≥ hi`,
/// give no roots.
pub fn sturm_roots(coeffs: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let _ = (coeffs, lo, hi);
    Vec::new() // TODO: roots work
}

/// The smallest real root in `(lo, hi]`, found without computing the others.
pub fn first_root(coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
    sturm_roots(coeffs, lo, hi).first().copied()
}

/// Which root-isolation strategy a shape uses for its first-root queries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// The paper's method: Sturm sequence isolation, false-position refinement.
    #[default]
    Sturm,
}

impl Solver {
    /// Every strategy with its command-line name, default first.
    pub const ALL: &'static [(Solver, &'static str)] = &[(Solver::Sturm, "sturm")];

    /// The command-line name of this strategy.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map_or("?", |(_, n)| n)
    }

    /// The smallest real root in `(lo, hi]` by this strategy.
    #[inline]
    pub fn first_root(self, coeffs: &[f64], lo: f64, hi: f64) -> Option<f64> {
        match self {
            Solver::Sturm => first_root(coeffs, lo, hi),
        }
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
