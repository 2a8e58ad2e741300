//! Legends: how to read a view's colours, from the same tables the views colour pixels
//! with, so that the explorer's key and the image cannot disagree.

use crate::film::srgb8_to_linear;
use crate::geometry::DVec3;

/// One swatch of a legend: an 8-bit sRGB colour (as it appears in an 8-bit PNG of the view,
/// for a pixel whose samples all agree) and what it means.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Swatch {
    /// What the colour means ("2 roots", "Sturm sequence").
    pub label: String,
    /// The colour, 8-bit sRGB.
    pub srgb: [u8; 3],
}

/// How to read one view's colours.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Legend {
    /// What the view shows, one line.
    pub title: &'static str,
    /// The colours in the order to list them.
    pub swatches: Vec<Swatch>,
    /// Anything else a reader needs (misses, shading of the colours); may be empty.
    pub note: &'static str,
}

impl Legend {
    /// A legend from `(label, colour)` pairs.
    pub(crate) fn new(
        title: &'static str,
        swatches: impl IntoIterator<Item = (String, [u8; 3])>,
        note: &'static str,
    ) -> Self {
        Legend {
            title,
            swatches: swatches
                .into_iter()
                .map(|(label, srgb)| Swatch { label, srgb })
                .collect(),
            note,
        }
    }
}

/// The linear colour that an 8-bit sRGB encoder writes back as `srgb` exactly.
pub(crate) fn linear(srgb: [u8; 3]) -> DVec3 {
    DVec3::new(
        srgb8_to_linear(srgb[0]),
        srgb8_to_linear(srgb[1]),
        srgb8_to_linear(srgb[2]),
    )
}

/// `srgb` darkened to `percent` % of its 8-bit values, for a second meaning of one hue.
pub(crate) const fn darker(srgb: [u8; 3], percent: u16) -> [u8; 3] {
    [
        (srgb[0] as u16 * percent / 100) as u8,
        (srgb[1] as u16 * percent / 100) as u8,
        (srgb[2] as u16 * percent / 100) as u8,
    ]
}

/// Nine steps of the viridis ramp (dark violet to yellow), 8-bit sRGB: a ramp whose
/// lightness rises evenly, readable in grey and by the colour-blind.
pub(crate) const VIRIDIS9: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_colours_encode_back_to_their_swatch() {
        for c in VIRIDIS9 {
            let l = linear(c);
            let back = [l.x, l.y, l.z].map(crate::film::linear_to_srgb8);
            assert_eq!(back, c);
        }
        assert_eq!(darker([200, 100, 10], 50), [100, 50, 5]);
    }
}
