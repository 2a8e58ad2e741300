//! What the root finder did for one ray against a polynomial surface: the data behind the
//! study views `roots`, `path`, `iterations` and `conditioning` (see `integrator`), taken
//! from the very queries the shape's intersection makes ([`Shape::solver_report`]).
//!
//! [`Shape::solver_report`]: super::Shape::solver_report

use crate::roots::{sturm_roots, Path, Solver, Trace};

/// How the first hit of a ray (or its miss) was settled: by one of the root finder's methods,
/// or by the shape's own accuracy work on the solver's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettledBy {
    /// The root finder's answer stood as it was (polished by at most rounding).
    Solver(Path),
    /// The heart's checks on `g = A − ∛B·Z` changed the answer: the solver's root was moved
    /// (the equator's triple root, where `f`'s root is good to ~1e-5 only), replaced by an
    /// earlier crossing, or skipped as a near-tangency or the ray's own origin.
    HeartPolish,
    /// The typed surface's ill-conditioned root was re-solved on the polynomial recentred
    /// and recomputed in double-double arithmetic.
    Recentred,
}

impl SettledBy {
    /// Every way of settling with its short name, in legend order.
    pub const ALL: &'static [(SettledBy, &'static str)] = &[
        (SettledBy::Solver(Path::Bernstein), "Bernstein test"),
        (SettledBy::Solver(Path::Sturm), "Sturm sequence"),
        (
            SettledBy::Solver(Path::Subdivision),
            "multiple-root subdivision",
        ),
        (SettledBy::Solver(Path::Derivatives), "derivative splitting"),
        (SettledBy::HeartPolish, "heart's polish"),
        (SettledBy::Recentred, "double-double re-solve"),
        (SettledBy::Solver(Path::Refused), "refused"),
    ];

    /// The short name of this way of settling.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map_or("?", |(_, n)| n)
    }
}

/// What the root finder did for one ray against one polynomial surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverReport {
    /// The ray parameter of the hit (as [`super::Shape::intersect`] returns it), if any.
    pub hit: Option<f64>,
    /// Distinct real roots of the ray's polynomial in the interval of the shape's first
    /// query (the ray's clipped chord; a multiple root counts once), as `sturm_roots` finds
    /// them.
    pub distinct_roots: u32,
    /// Degree of the ray's polynomial.
    pub degree: u32,
    /// How the hit or miss was settled.
    pub settled_by: SettledBy,
    /// The solver's work over all the queries the intersection made.
    pub trace: Trace,
    /// `|∇f|` at the hit, in object space, for `f` as written (the heart's `f` for `HEART`):
    /// small where the surface is ill-conditioned (near singular points and curves, where a
    /// ray's root is sensitive to rounding). `None` for a miss.
    pub gradient_norm: Option<f64>,
}

/// Collects a [`SolverReport`] while a shape's intersection runs: its first-root queries go
/// through [`Recorder::first_root`], and the shape tells it about its own steps.
#[derive(Debug)]
pub(crate) struct Recorder {
    solver: Solver,
    trace: Trace,
    /// The first query: its coefficients, degree and interval.
    first: Option<([f64; 17], usize, f64, f64)>,
    /// The first query's answer.
    first_answer: Option<f64>,
    recentred: bool,
}

impl Recorder {
    /// A recorder for queries by `solver`.
    pub(crate) fn new(solver: Solver) -> Self {
        Recorder {
            solver,
            trace: Trace::default(),
            first: None,
            first_answer: None,
            recentred: false,
        }
    }

    /// The solver's first root of `c` in `(lo, hi]`, as the untraced query gives it, recorded.
    pub(crate) fn first_root(&mut self, c: &[f64], lo: f64, hi: f64) -> Option<f64> {
        let root = self.solver.first_root_traced(c, lo, hi, &mut self.trace);
        if self.first.is_none() && c.len() <= 17 {
            let mut copy = [0.0; 17];
            copy[..c.len()].copy_from_slice(c);
            self.first = Some((copy, c.len(), lo, hi));
            self.first_answer = root;
        }
        root
    }

    /// The shape re-solved an ill-conditioned root in double-double arithmetic.
    pub(crate) fn recentred(&mut self) {
        self.recentred = true;
    }

    /// The first query's answer (in its own variable), if it made one.
    pub(crate) fn first_answer(&self) -> Option<f64> {
        self.first_answer
    }

    /// The report, given the hit, whether the shape's own checks changed the first query's
    /// answer, and `|∇f|` at the hit; `None` when no query was made (the ray missed the
    /// shape's bounds).
    pub(crate) fn finish(
        self,
        hit: Option<f64>,
        polished: bool,
        gradient_norm: Option<f64>,
    ) -> Option<SolverReport> {
        let (c, len, lo, hi) = self.first?;
        let settled_by = if self.recentred {
            SettledBy::Recentred
        } else if polished {
            SettledBy::HeartPolish
        } else {
            SettledBy::Solver(self.trace.path)
        };
        Some(SolverReport {
            hit,
            distinct_roots: sturm_roots(&c[..len], lo, hi).len() as u32,
            degree: len.saturating_sub(1) as u32,
            settled_by,
            trace: self.trace,
            gradient_norm: hit.and(gradient_norm),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{DVec3, Ray};
    use crate::shapes::{Heart, Shape};

    fn heart() -> Heart {
        Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap()
    }

    #[test]
    fn reports_agree_with_the_intersection() {
        let h = heart();
        for (o, d) in [
            (DVec3::new(3.0, 0.0, 0.1), DVec3::new(-1.0, 0.0, 0.0)),
            (DVec3::new(0.0, -3.0, 1.05), DVec3::Y),
            (DVec3::new(0.3, -3.0, 1.3), DVec3::new(0.0, 1.0, -0.05)),
            (DVec3::new(1.0 / 2f64.sqrt(), -3.0, 0.0), DVec3::Y),
        ] {
            let ray = Ray::new(o, d);
            let r = h.solver_report(&ray, 0.0, f64::INFINITY).expect("queried");
            assert_eq!(r.hit, h.intersect(&ray, 0.0, f64::INFINITY), "{o} {d}");
            assert_eq!(r.degree, 6);
            assert!(r.trace.queries >= 1);
            assert_eq!(r.gradient_norm.is_some(), r.hit.is_some());
        }
    }

    #[test]
    fn hard_rays_are_settled_past_the_bernstein_test() {
        // A camera ray from above through a point 1e-5 below the equator curve (found by
        // scanning rays from this eye towards points around the curve; the equator's triple
        // root leaves `f`'s root off by more than the polish's visible threshold).
        let h = heart();
        let d = DVec3::new(-1.4424285765478733, 1.6150026142213854, -1.50001);
        let grazing = Ray::new(DVec3::new(2.0, -1.0, 1.5), d);
        let r = h
            .solver_report(&grazing, 0.0, f64::INFINITY)
            .expect("queried");
        assert!(r.hit.is_some());
        assert_eq!(r.settled_by, SettledBy::HeartPolish, "{r:?}");
        // The sixfold root where the plane Z = 0 touches the equator curve.
        let equator = Ray::new(DVec3::new(1.0 / 2f64.sqrt(), -3.0, 0.0), DVec3::Y);
        let r = h.solver_report(&equator, 0.0, f64::INFINITY).unwrap();
        assert_ne!(r.settled_by, SettledBy::Solver(Path::Bernstein), "{r:?}");
        assert_eq!(r.distinct_roots, 1, "{r:?}");
    }
}
