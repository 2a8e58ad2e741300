//! What a first-root query did, for the study views and the `roots` command: which method
//! settled it and how much work each stage took. The same code answers traced and untraced
//! queries: every stage takes an [`Observer`], and the untraced queries pass `()`, whose
//! methods are empty and vanish when inlined, so tracing costs nothing unless asked for.

/// The method that settled a first-root query: found its first root, or proved there is none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// The polynomial was refused before any method ran: non-finite coefficients, an empty
    /// interval or the zero polynomial (no roots).
    Refused,
    /// The Bernstein test: sign variations of the Bernstein coefficients on the interval and
    /// its halvings, all certain.
    Bernstein,
    /// The Sturm sequence isolated the root (or proved there is none) with certain signs.
    Sturm,
    /// The zero-region subdivision for multiple or clustered roots (signs the Sturm
    /// sequence needed were not certain).
    Subdivision,
    /// Yuksel's derivative splitting into monotonic pieces.
    Derivatives,
}

impl Path {
    /// Every path with its short name (as the legends and `kardia roots --trace` print it).
    pub const ALL: &'static [(Path, &'static str)] = &[
        (Path::Refused, "refused"),
        (Path::Bernstein, "bernstein"),
        (Path::Sturm, "sturm"),
        (Path::Subdivision, "subdivision"),
        (Path::Derivatives, "derivatives"),
    ];

    /// The short name of this path.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map_or("?", |(_, n)| n)
    }
}

/// The work of one or more first-root queries (counts add up over the queries a shape makes
/// for one ray); `path` is the last query's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trace {
    /// The method that settled the last query.
    pub path: Path,
    /// Iterations of the refinement of a bracketed root (Halley, Newton/Schröder, false
    /// position or the bracketed Newton of the derivative splitting), each one evaluation
    /// of the polynomial (with derivatives) at a new point.
    pub refine_steps: u32,
    /// Isolation steps: pieces split by the Bernstein test or the zero-region subdivision,
    /// Sturm sequence evaluations at split points, and critical points found by the
    /// derivative splitting.
    pub splits: u32,
    /// First-root queries made.
    pub queries: u32,
}

impl Default for Trace {
    fn default() -> Self {
        Trace {
            path: Path::Refused,
            refine_steps: 0,
            splits: 0,
            queries: 0,
        }
    }
}

/// Receives the events of a query as it runs. `()` ignores them at no cost.
pub(crate) trait Observer {
    /// One refinement iteration.
    fn refine_step(&mut self);
    /// One isolation step.
    fn split(&mut self);
    /// The query was settled by `path`.
    fn settled(&mut self, path: Path);
}

impl Observer for () {
    #[inline(always)]
    fn refine_step(&mut self) {}
    #[inline(always)]
    fn split(&mut self) {}
    #[inline(always)]
    fn settled(&mut self, _: Path) {}
}

impl Observer for Trace {
    #[inline]
    fn refine_step(&mut self) {
        self.refine_steps = self.refine_steps.saturating_add(1);
    }
    #[inline]
    fn split(&mut self) {
        self.splits = self.splits.saturating_add(1);
    }
    #[inline]
    fn settled(&mut self, path: Path) {
        self.path = path;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::Solver;

    /// `(t − r₀)(t − r₁)…` in ascending powers.
    fn from_roots(roots: &[f64]) -> Vec<f64> {
        let mut c = vec![1.0];
        for &r in roots {
            let mut next = vec![0.0; c.len() + 1];
            for (i, &a) in c.iter().enumerate() {
                next[i + 1] += a;
                next[i] -= r * a;
            }
            c = next;
        }
        c
    }

    fn traced(solver: Solver, c: &[f64], lo: f64, hi: f64) -> (Option<f64>, Trace) {
        let mut trace = Trace::default();
        let root = solver.first_root_traced(c, lo, hi, &mut trace);
        assert_eq!(
            root,
            solver.first_root(c, lo, hi),
            "tracing changed the answer"
        );
        (root, trace)
    }

    #[test]
    fn well_separated_simple_roots_are_settled_by_the_bernstein_test() {
        for solver in [Solver::Sturm, Solver::Yuksel] {
            let (root, trace) = traced(solver, &from_roots(&[0.3, 0.55, 0.8]), 0.0, 1.0);
            assert!((root.unwrap() - 0.3).abs() < 1e-14);
            assert_eq!(trace.path, Path::Bernstein);
            assert_eq!(trace.queries, 1);
            assert!(trace.refine_steps >= 1, "{trace:?}");
            assert!(trace.splits >= 1, "three roots need halving: {trace:?}");
            // No root on the interval: proved by the same test, with nothing refined.
            let (root, trace) = traced(solver, &from_roots(&[2.0, 3.0]), 0.0, 1.0);
            assert_eq!(
                (root, trace.path, trace.refine_steps),
                (None, Path::Bernstein, 0)
            );
        }
    }

    #[test]
    fn a_triple_root_goes_past_the_bernstein_test() {
        let c = from_roots(&[0.5, 0.5, 0.5, 0.9]);
        let (root, trace) = traced(Solver::Sturm, &c, 0.0, 1.0);
        assert!((root.unwrap() - 0.5).abs() < 1e-9, "{root:?}");
        assert_eq!(trace.path, Path::Subdivision, "{trace:?}");
        assert!(trace.splits > 0);
        let (root, trace) = traced(Solver::Yuksel, &c, 0.0, 1.0);
        assert!((root.unwrap() - 0.5).abs() < 1e-5, "{root:?}");
        assert_eq!(trace.path, Path::Derivatives);
    }

    #[test]
    fn a_root_just_outside_the_interval_is_left_to_the_sturm_sequence() {
        // P(lo) ≈ 5e-14 is within the Bernstein test's margin (it declines) but far above
        // its own rounding, which is all the Sturm sequence needs.
        let c = from_roots(&[-1e-13, 0.5, 2.0]);
        let (root, trace) = traced(Solver::Sturm, &c, 0.0, 1.0);
        assert!((root.unwrap() - 0.5).abs() < 1e-14, "{root:?}");
        assert_eq!(trace.path, Path::Sturm, "{trace:?}");
        assert!(trace.refine_steps > 0);
    }

    #[test]
    fn refused_input_is_its_own_path_and_counts_add_up() {
        let mut trace = Trace::default();
        let c = from_roots(&[0.25]);
        assert_eq!(
            Solver::Sturm.first_root_traced(&c, 1.0, 0.0, &mut trace),
            None
        );
        assert_eq!((trace.path, trace.queries), (Path::Refused, 1));
        Solver::Sturm.first_root_traced(&c, 0.0, 1.0, &mut trace);
        let after_one = trace.refine_steps;
        Solver::Sturm.first_root_traced(&c, 0.0, 1.0, &mut trace);
        assert_eq!(trace.queries, 3);
        assert_eq!(trace.refine_steps, 2 * after_one);
        assert_eq!(trace.path, Path::Bernstein);
    }

    #[test]
    fn names_are_unique() {
        for (i, (p, n)) in Path::ALL.iter().enumerate() {
            assert_eq!(p.name(), *n);
            assert!(Path::ALL[i + 1..].iter().all(|(_, m)| m != n));
        }
    }
}
