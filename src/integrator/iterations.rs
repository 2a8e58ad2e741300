//! Refinement iterations, the [`View::Iterations`](super::View::Iterations) study view: each
//! pixel shows how many refinement steps the root finder took for its camera ray (Halley,
//! Newton/Schröder, false position or bracketed Newton steps, each one evaluation of the
//! polynomial at a new point), summed over the queries the intersection made. See
//! [`super::solver_view`].

use super::legend::{linear, Legend, VIRIDIS9};
use super::solver_view::{ReportColour, SolverView};
use super::ShadeSetup;
use crate::geometry::DVec3;
use crate::shapes::SolverReport;

/// The lowest step count of each bucket (the last is open-ended), matching [`VIRIDIS9`].
const BUCKETS: [u32; 9] = [0, 1, 2, 3, 4, 5, 8, 16, 64];

/// The colour table of the iterations view.
pub struct StepColour;

/// The iterations view.
pub type Iterations<'a> = SolverView<'a, StepColour>;

impl<'a> Iterations<'a> {
    /// The view of `setup.scene`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        SolverView::with_colours(setup, StepColour)
    }
}

/// The bucket of `steps`.
fn bucket(steps: u32) -> usize {
    BUCKETS.iter().rposition(|&lo| steps >= lo).unwrap_or(0)
}

impl ReportColour for StepColour {
    fn colour(&self, report: &SolverReport) -> DVec3 {
        linear(VIRIDIS9[bucket(report.trace.refine_steps)])
    }
}

/// How to read the view.
pub fn legend() -> Legend {
    Legend::new(
        "refinement steps the root finder took",
        (0..BUCKETS.len()).map(|i| {
            let (lo, next) = (BUCKETS[i], BUCKETS.get(i + 1).copied());
            let label = match next {
                None => format!("{lo} or more"),
                Some(n) if n == lo + 1 => lo.to_string(),
                Some(n) => format!("{lo}–{}", n - 1),
            };
            (label, VIRIDIS9[i])
        }),
        "a proved miss refines nothing (0); black: no root finder reached",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_cover_every_count_in_order() {
        assert_eq!(bucket(0), 0);
        assert_eq!(bucket(4), 4);
        assert_eq!(bucket(5), 5);
        assert_eq!(bucket(7), 5);
        assert_eq!(bucket(8), 6);
        assert_eq!(bucket(63), 7);
        assert_eq!(bucket(u32::MAX), 8);
        let labels: Vec<_> = legend().swatches.into_iter().map(|s| s.label).collect();
        assert_eq!(labels[5], "5–7");
        assert_eq!(labels[8], "64 or more");
    }
}
