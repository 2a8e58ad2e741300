//! Root count, the [`View::Roots`](super::View::Roots) study view: each pixel shows how many
//! distinct real roots the polynomial of its camera ray has in the interval the surface's
//! root finder searched (the ray's clipped chord; a multiple root counts once), whether the
//! ray hits or not. Where the count changes, the ray grazes the surface or crosses a curve
//! where roots merge: the places the solver's hard cases live. See [`super::solver_view`].

use super::legend::{linear, Legend};
use super::solver_view::{ReportColour, SolverView};
use super::ShadeSetup;
use crate::geometry::DVec3;
use crate::shapes::SolverReport;

/// Colour of 0, 1, … 7 roots and of 8 or more, 8-bit sRGB.
const COLOURS: [[u8; 3]; 9] = [
    [0x3a, 0x3f, 0x4b],
    [0x4c, 0x9b, 0xe8],
    [0x5c, 0xc4, 0x6b],
    [0xf2, 0xc1, 0x4e],
    [0xf0, 0x8a, 0x3c],
    [0xe0, 0x44, 0x5a],
    [0xb0, 0x5c, 0xd6],
    [0xff, 0x8f, 0xd0],
    [0xff, 0xff, 0xff],
];

/// The colour table of the root-count view.
pub struct RootCount;

/// The root-count view.
pub type Roots<'a> = SolverView<'a, RootCount>;

impl<'a> Roots<'a> {
    /// The view of `setup.scene`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        SolverView::with_colours(setup, RootCount)
    }
}

impl ReportColour for RootCount {
    fn colour(&self, report: &SolverReport) -> DVec3 {
        linear(COLOURS[(report.distinct_roots as usize).min(COLOURS.len() - 1)])
    }
}

/// How to read the view.
pub fn legend() -> Legend {
    Legend::new(
        "distinct real roots of the ray's polynomial in its interval",
        COLOURS.iter().enumerate().map(|(k, &c)| {
            let label = match k {
                1 => "1 root".to_string(),
                8 => "8 or more".to_string(),
                _ => format!("{k} roots"),
            };
            (label, c)
        }),
        "black: the ray reaches no root finder",
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
    fn a_ray_through_the_heart_shows_its_root_count() {
        let scene = heart_scene();
        let view = Roots::new(&one_sample_setup(&scene));
        let mut s = Sample::new(0, 0, 1);
        // Through the middle: in and out of the heart, two roots.
        let through = Ray::new(scene.camera.eye, DVec3::new(-1.0, 0.0, 0.0));
        assert_eq!(view.radiance(&through, &mut s), linear(COLOURS[2]));
        // Through both lobes, above the dip at (0, 0, 1): four.
        let lobes = Ray::new(DVec3::new(0.0, -3.0, 1.05), DVec3::Y);
        assert_eq!(view.radiance(&lobes, &mut s), linear(COLOURS[4]));
        assert_eq!(legend().swatches.len(), COLOURS.len());
    }
}
