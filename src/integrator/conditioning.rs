//! Conditioning, the [`View::Conditioning`](super::View::Conditioning) study view: each pixel
//! shows `|∇f|` at its camera ray's hit (object space, `f` as written), by decades. Where it
//! is small the surface is ill-conditioned: a small change of `f` (its rounding) moves the
//! surface far, the ray's root is a near-multiple one, and the normal `∇f / |∇f|` is
//! unreliable; the heart's equator curve and singular points, and the singular points of
//! Barth's or Kummer's surfaces, show up as the red end. See [`super::solver_view`].

use super::legend::{linear, Legend};
use super::solver_view::{ReportColour, SolverView};
use super::ShadeSetup;
use crate::geometry::DVec3;
use crate::shapes::SolverReport;

/// The lower decade `log10 |∇f|` of each bucket but the first (everything below), and their
/// colours (red, ill-conditioned, to blue), 8-bit sRGB.
const DECADES: [i32; 7] = [-6, -4, -3, -2, -1, 0, 1];
const COLOURS: [[u8; 3]; 8] = [
    [0xa5, 0x00, 0x26],
    [0xd7, 0x30, 0x27],
    [0xf4, 0x6d, 0x43],
    [0xfd, 0xae, 0x61],
    [0xfe, 0xe0, 0x90],
    [0xab, 0xd9, 0xe9],
    [0x74, 0xad, 0xd1],
    [0x45, 0x75, 0xb4],
];

/// The colour table of the conditioning view.
pub struct GradientColour;

/// The conditioning view.
pub type Conditioning<'a> = SolverView<'a, GradientColour>;

impl<'a> Conditioning<'a> {
    /// The view of `setup.scene`.
    pub fn new(setup: &ShadeSetup<'a>) -> Self {
        SolverView::with_colours(setup, GradientColour)
    }
}

/// The bucket of `|∇f|` (0 and NaN in the first).
fn bucket(gradient_norm: f64) -> usize {
    DECADES
        .iter()
        .rposition(|&d| gradient_norm >= 10f64.powi(d))
        .map_or(0, |i| i + 1)
}

impl ReportColour for GradientColour {
    fn colour(&self, report: &SolverReport) -> DVec3 {
        report
            .gradient_norm
            .map_or(DVec3::ZERO, |g| linear(COLOURS[bucket(g)]))
    }
}

/// How to read the view.
pub fn legend() -> Legend {
    let power = |d: i32| {
        if d == 0 {
            "1".to_string()
        } else {
            format!("1e{d}")
        }
    };
    Legend::new(
        "|∇f| at the hit (object space, f as written)",
        (0..COLOURS.len()).map(|i| {
            let label = match i {
                0 => format!("below {}", power(DECADES[0])),
                i if i == DECADES.len() => format!("{} or more", power(DECADES[i - 1])),
                i => format!("{} to {}", power(DECADES[i - 1]), power(DECADES[i])),
            };
            (label, COLOURS[i])
        }),
        "red: ill-conditioned (near-multiple roots, unreliable normals); black: no hit",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_are_bucketed_in_order() {
        assert_eq!(bucket(0.0), 0);
        assert_eq!(bucket(f64::NAN), 0);
        assert_eq!(bucket(5e-7), 0);
        assert_eq!(bucket(1e-6), 1);
        assert_eq!(bucket(0.5), 5);
        assert_eq!(bucket(1.0), 6);
        assert_eq!(bucket(1e9), 7);
        let labels: Vec<_> = legend().swatches.into_iter().map(|s| s.label).collect();
        assert_eq!(labels[0], "below 1e-6");
        assert_eq!(labels[6], "1 to 1e1");
        assert_eq!(labels[7], "1e1 or more");
    }
}
