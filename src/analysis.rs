//! Image analysis for tests and benchmarks: silhouettes and numerical specks.
//!
//! Works on 8-bit RGB pixels (`[u8; 3]`, row-major from the top-left), the form in which
//! both kardia's and other renderers' PNGs can be compared.

/// An 8-bit RGB image borrowed as rows of pixels.
#[derive(Debug, Clone, Copy)]
pub struct Rgb8<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width·height` pixels, row-major from the top-left.
    pub pixels: &'a [[u8; 3]],
}

impl Rgb8<'_> {
    /// The pixel at column `x`, row `y`.
    pub fn at(&self, x: usize, y: usize) -> [u8; 3] {
        self.pixels[y * self.width + x]
    }

    /// Which pixels show an object: any channel differs from `background` by more than
    /// `threshold` levels. Row-major, like `pixels`.
    pub fn silhouette(&self, background: [u8; 3], threshold: u8) -> Vec<bool> {
        self.pixels
            .iter()
            .map(|p| level_difference(*p, background) > threshold)
            .collect()
    }

    /// The pixels `(x, y)` that are numerical specks: inside the silhouette `mask` together
    /// with their 8 neighbours, and differing by more than [`SPECK_JUMP`] levels from both
    /// neighbours on a line (above and below, or left and right) that agree with each other
    /// to within [`SPECK_AGREE`] levels. Smooth shading, shadow edges and silhouettes do not
    /// count; an isolated dark or bright dot on a smooth surface does.
    pub fn specks(&self, mask: &[bool]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        if self.width < 3 || self.height < 3 {
            return out;
        }
        for y in 1..self.height - 1 {
            for x in 1..self.width - 1 {
                let inside =
                    (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| mask[yy * self.width + xx]));
                if !inside {
                    continue;
                }
                let p = self.at(x, y);
                let isolated = |a: [u8; 3], b: [u8; 3]| {
                    level_difference(a, b) <= SPECK_AGREE
                        && level_difference(p, a) > SPECK_JUMP
                        && level_difference(p, b) > SPECK_JUMP
                };
                if isolated(self.at(x, y - 1), self.at(x, y + 1))
                    || isolated(self.at(x - 1, y), self.at(x + 1, y))
                {
                    out.push((x, y));
                }
            }
        }
        out
    }
}

/// Two neighbours "agree" when no channel differs by more than this many 8-bit levels.
pub const SPECK_AGREE: u8 = 6;
/// A speck differs from both agreeing neighbours by more than this many levels.
pub const SPECK_JUMP: u8 = 20;

/// The largest per-channel difference between two pixels, in 8-bit levels.
pub fn level_difference(a: [u8; 3], b: [u8; 3]) -> u8 {
    (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> [u8; 3]) -> Vec<[u8; 3]> {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect()
    }

    #[test]
    fn a_dark_dot_on_a_gradient_is_a_speck_and_nothing_else_is() {
        let mut px = image(9, 9, |x, y| [100 + 3 * x as u8, 50 + 2 * y as u8, 40]);
        px[4 * 9 + 4] = [10, 10, 10];
        let img = Rgb8 {
            width: 9,
            height: 9,
            pixels: &px,
        };
        let mask = img.silhouette([0, 0, 0], 8);
        assert_eq!(img.specks(&mask), vec![(4, 4)]);
    }

    #[test]
    fn a_hard_shadow_edge_is_not_a_speck() {
        let px = image(
            9,
            9,
            |x, _| if x < 4 { [200, 50, 50] } else { [60, 15, 15] },
        );
        let img = Rgb8 {
            width: 9,
            height: 9,
            pixels: &px,
        };
        let mask = img.silhouette([0, 0, 0], 8);
        assert!(img.specks(&mask).is_empty());
    }

    #[test]
    fn pixels_next_to_the_background_are_not_judged() {
        let px = image(5, 5, |x, y| {
            if (x, y) == (1, 1) {
                [250, 0, 0]
            } else if x == 0 {
                [0, 0, 0]
            } else {
                [90, 20, 20]
            }
        });
        let img = Rgb8 {
            width: 5,
            height: 5,
            pixels: &px,
        };
        let mask = img.silhouette([0, 0, 0], 8);
        assert!(img.specks(&mask).is_empty());
    }
}
