//! Solver path, the [`View::Path`](super::View::Path) study view: each pixel shows which
//! method settled its camera ray's first root (or proved there is none): the Bernstein test,
//! the Sturm sequence, the multiple-root subdivision, the derivative splitting (the `yuksel`
//! solver), the heart's polish on `g`, or the typed surfaces' double-double re-solve (see
//! [`crate::shapes::SettledBy`]). A darker shade of the same colour is a proved miss. See
//! [`super::solver_view`].

use super::legend::{darker, linear, Legend};
use super::solver_view::{ReportColour, SolverView};
use super::ShadeSetup;
use crate::geometry::DVec3;
use crate::roots::Path;
use crate::shapes::{SettledBy, SolverReport};

/// Brightness of a proved miss against a hit of the same path, in percent of the 8-bit value.
const MISS_PERCENT: u16 = 40;

/// The colour (8-bit sRGB) of a hit settled by `how`.
const fn colour_of(how: SettledBy) -> [u8; 3] {
    match how {
        SettledBy::Solver(Path::Bernstein) => [0x4c, 0x9b, 0xe8],
        SettledBy::Solver(Path::Sturm) => [0x5c, 0xc4, 0x6b],
        SettledBy::Solver(Path::Subdivision) => [0xe0, 0x44, 0x5a],
        SettledBy::Solver(Path::Derivatives) => [0xf2, 0xc1, 0x4e],
        SettledBy::HeartPolish => [0xb0, 0x5c, 0xd6],
        SettledBy::Recentred => [0xf0, 0x8a, 0x3c],
        SettledBy::Solver(Path::Refused) => [0x80, 0x80, 0x80],
    }
}

/// The colour table of the path view.
pub struct SettledColour;

/// The path view.
pub type PathView<'a> = SolverView<'a, SettledColour>;

impl<'a> PathView<'a> {
    /// The view of `setup.scene`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        SolverView::with_colours(setup, SettledColour)
    }
}

impl ReportColour for SettledColour {
    fn colour(&self, report: &SolverReport) -> DVec3 {
        let c = colour_of(report.settled_by);
        linear(if report.hit.is_some() {
            c
        } else {
            darker(c, MISS_PERCENT)
        })
    }
}

/// How to read the view.
pub fn legend() -> Legend {
    Legend::new(
        "which method settled the ray's first root",
        SettledBy::ALL
            .iter()
            .map(|&(how, name)| (name.to_string(), colour_of(how))),
        "darker (40 %): the same method proved the ray misses; black: no root finder reached",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::integrator::solver_view::tests::heart_scene;
    use crate::integrator::tests::one_sample_setup;
    use crate::integrator::{Sample, Shader};

    #[test]
    fn the_heart_is_mostly_the_bernstein_test_and_misses_are_darker() {
        let scene = heart_scene();
        let view = PathView::new(&one_sample_setup(&scene));
        let mut s = Sample::new(0, 0, 1);
        let through = Ray::new(scene.camera.eye, DVec3::new(-1.0, 0.0, 0.0));
        let bernstein = colour_of(SettledBy::Solver(Path::Bernstein));
        assert_eq!(view.radiance(&through, &mut s), linear(bernstein));
        // Along the equator curve's tangent plane, where f has a triple root: not the
        // Bernstein test's case.
        let equator = Ray::new(DVec3::new(1.0 / 2f64.sqrt(), -3.0, 0.0), DVec3::Y);
        assert_ne!(view.radiance(&equator, &mut s), linear(bernstein));
        let names: Vec<_> = legend().swatches.into_iter().map(|s| s.label).collect();
        assert!(names.contains(&"heart's polish".to_string()), "{names:?}");
        assert_ne!(darker(bernstein, MISS_PERCENT), bernstein);
    }
}
