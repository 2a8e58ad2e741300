//! The valid range of every numeric parameter of the scene language (the table in
//! docs/scene-format.md is this one). Within these ranges, loading and rendering a scene
//! does no integer overflow, no division by zero, and makes no NaN or infinity that reaches a
//! pixel; a value outside one is refused at load with an error that states the range.

use std::fmt;

/// A closed or half-open interval of accepted values, optionally of whole numbers only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Lower end.
    pub min: f64,
    /// True when `min` itself is excluded.
    pub min_open: bool,
    /// Upper end.
    pub max: f64,
    /// True when `max` itself is excluded.
    pub max_open: bool,
    /// True when only whole numbers are accepted.
    pub whole: bool,
    /// True when a value outside is explained by naming both ends ("between 0 and 1"),
    /// rather than the end it crossed.
    pub between: bool,
}

impl Limits {
    /// `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> Self {
        Self {
            min,
            min_open: false,
            max,
            max_open: false,
            whole: false,
            between: false,
        }
    }

    /// `(min, max)`.
    pub const fn open(min: f64, max: f64) -> Self {
        Self {
            min_open: true,
            max_open: true,
            ..Self::closed(min, max)
        }
    }

    /// A weight in `[min, max]`, explained as "between min and max".
    pub const fn weight(min: f64, max: f64) -> Self {
        Self {
            between: true,
            ..Self::closed(min, max)
        }
    }

    /// Whole numbers in `[min, max]`.
    pub const fn whole(min: u32, max: u32) -> Self {
        Self {
            whole: true,
            ..Self::closed(min as f64, max as f64)
        }
    }

    /// Whether `x` is accepted.
    pub fn contains(&self, x: f64) -> bool {
        let above = if self.min_open {
            x > self.min
        } else {
            x >= self.min
        };
        let below = if self.max_open {
            x < self.max
        } else {
            x <= self.max
        };
        above && below && (!self.whole || x.fract() == 0.0)
    }

    /// Why `x` (not accepted) is wrong, as `(requirement, short label)`: the requirement
    /// completes "… must be …, not x", the label goes under the caret.
    pub fn violation(&self, x: f64) -> (String, String) {
        let (lo, hi) = (show(self.min), show(self.max));
        if self.whole {
            return (
                format!("a whole number from {lo} to {hi}"),
                format!("must be a whole number in {lo}..={hi}"),
            );
        }
        if self.between {
            return (
                format!("between {lo} and {hi}"),
                format!("must be in [{lo}, {hi}]"),
            );
        }
        let low = if self.min_open {
            x <= self.min
        } else {
            x < self.min
        };
        let (side, label) = if low && x <= 0.0 && self.min > 0.0 {
            ("greater than 0".to_string(), "must be > 0".to_string())
        } else if low && self.min_open {
            (format!("greater than {lo}"), format!("must be > {lo}"))
        } else if low {
            (format!("at least {lo}"), format!("must be ≥ {lo}"))
        } else if self.max_open {
            (format!("less than {hi}"), format!("must be < {hi}"))
        } else {
            (format!("at most {hi}"), format!("must be ≤ {hi}"))
        };
        (side, label)
    }
}

impl fmt::Display for Limits {
    /// The range in words, as the documentation's table writes it: `1e-6 to 1e6`,
    /// `greater than 0 and less than 180`, `a whole number from 1 to 1024`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (lo, hi) = (show(self.min), show(self.max));
        if self.max == f64::INFINITY {
            let side = if self.min_open {
                "greater than"
            } else {
                "at least"
            };
            return write!(f, "{side} {lo}");
        }
        match (self.whole, self.min_open, self.max_open) {
            (true, _, _) => write!(f, "a whole number from {lo} to {hi}"),
            (false, false, false) => write!(f, "{lo} to {hi}"),
            (false, true, false) => write!(f, "greater than {lo}, at most {hi}"),
            (false, false, true) => write!(f, "at least {lo}, less than {hi}"),
            (false, true, true) => write!(f, "greater than {lo} and less than {hi}"),
        }
    }
}

/// A number as the messages write it: `0`, `1.5`, `32768`, `100000`, `1e6`, `1e-6`.
pub fn show(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e6).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Each coordinate of a point (positions, centres, corners, vertices, eye, look-at), and
/// each component of a direction or basis vector.
pub const COORDINATE: Limits = Limits::closed(-1e6, 1e6);
/// The length of a direction or basis vector (plane normal, up, edges, u v w).
pub const DIRECTION_LENGTH: Limits = Limits::closed(1e-6, f64::INFINITY);
/// Image width and height in pixels.
pub const IMAGE_SIDE: Limits = Limits::whole(1, super::Scene::MAX_SIDE);
/// The camera's full horizontal field of view in degrees.
pub const FIELD_OF_VIEW: Limits = Limits::open(0.0, 180.0);
/// Each component of a colour: diffuse, checker, inside, background, ambient.
pub const COLOUR: Limits = Limits::closed(0.0, 1e6);
/// Each component of a light's intensity.
pub const INTENSITY: Limits = Limits::closed(0.0, 1e6);
/// A sphere's radius, a checker's cell size, an implicit surface's BOUND, a torus radius, an
/// orthographic camera's view height.
pub const LENGTH: Limits = Limits::closed(1e-6, 1e6);
/// A light's radius (0: a point light).
pub const LIGHT_RADIUS: Limits = Limits::closed(0.0, 1e6);
/// A spherical light's shadow rays per pixel sample.
pub const LIGHT_SAMPLES: Limits = Limits::whole(1, crate::lights::Light::MAX_SAMPLES);
/// The specular weight ks.
pub const SPECULAR_WEIGHT: Limits = Limits::closed(0.0, 1e6);
/// The specular (Blinn–Phong) exponent.
pub const SPECULAR_EXPONENT: Limits = Limits::closed(1.0, 1e6);
/// The reflection weight kr and the transmission weight kt.
pub const WEIGHT: Limits = Limits::weight(0.0, 1.0);
/// The index of refraction.
pub const IOR: Limits = Limits::closed(0.01, 100.0);
/// Each component of the Beer–Lambert attenuation, per unit length.
pub const ATTENUATION: Limits = Limits::closed(0.0, 1e6);
/// A polygon's vertex count.
pub const POLYGON_VERTICES: Limits = Limits::whole(3, 100_000);
/// The Kummer preset's μ (μ² = 3 is refused: λ would be infinite).
pub const KUMMER_MU: Limits = Limits::closed(-1e3, 1e3);
/// The Chmutov preset's degree n.
pub const CHMUTOV_DEGREE: Limits = Limits::whole(1, 16);

/// `FRAMES` n, the number of frames of an animation.
pub const FRAME_COUNT: Limits = Limits::whole(1, 1_000_000);
/// `FRAMES … FPS f`, frames per second of an animated output.
pub const FRAME_RATE: Limits = Limits::closed(0.01, 1000.0);

/// Every range with the parameters it applies to, in the order of the documentation's table.
pub const TABLE: &[(&str, Limits)] = &[
    ("`SIZE` width and height (pixels)", IMAGE_SIDE),
    (
        "each coordinate of a point (`eye`, `look_at`, centres, corners, positions, vertices) \
         and each component of a direction or basis vector",
        COORDINATE,
    ),
    (
        "the length of a direction or basis vector (`up`, plane normal, BOX edges, `u v w`)",
        DIRECTION_LENGTH,
    ),
    ("`CAMERA` fov (degrees)", FIELD_OF_VIEW),
    (
        "each component of a colour (diffuse, `CHECKER`, `INSIDE`, `BACKGROUND`, `AMBIENT`)",
        COLOUR,
    ),
    ("each component of a `LIGHT`'s intensity", INTENSITY),
    ("`LIGHT` radius (0: a point light)", LIGHT_RADIUS),
    ("`LIGHT` … `SAMPLES n`", LIGHT_SAMPLES),
    (
        "`SPHERE` radius, `CHECKER` cell size, `BOUND r`, `torus` R and r, `ORTHOGRAPHIC` height",
        LENGTH,
    ),
    ("`POLYGON` vertex count n", POLYGON_VERTICES),
    ("`SPECULAR` weight ks", SPECULAR_WEIGHT),
    ("`SPECULAR` exponent", SPECULAR_EXPONENT),
    ("`REFLECT` kr, `TRANSMIT` kt", WEIGHT),
    ("`IOR` n", IOR),
    (
        "each component of `ATTENUATION` (per unit length)",
        ATTENUATION,
    ),
    ("`kummer` μ (μ² ≠ 3)", KUMMER_MU),
    ("`chmutov` degree n", CHMUTOV_DEGREE),
    ("`FRAMES` n", FRAME_COUNT),
    ("`FRAMES` … `FPS f`", FRAME_RATE),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_beyond() {
        assert!(LENGTH.contains(1e-6) && LENGTH.contains(1e6));
        assert!(!LENGTH.contains(1e6_f64.next_up()) && !LENGTH.contains(1e-6_f64.next_down()));
        assert!(!FIELD_OF_VIEW.contains(0.0) && !FIELD_OF_VIEW.contains(180.0));
        assert!(FIELD_OF_VIEW.contains(5e-324) && FIELD_OF_VIEW.contains(180f64.next_down()));
        assert!(LIGHT_SAMPLES.contains(1024.0) && !LIGHT_SAMPLES.contains(2.5));
        assert!(!COLOUR.contains(f64::NAN) && COLOUR.contains(-0.0));
    }

    #[test]
    fn numbers_are_shown_short() {
        assert_eq!(show(1e6), "1e6");
        assert_eq!(show(1e-6), "1e-6");
        assert_eq!(show(32768.0), "32768");
        assert_eq!(show(0.01), "0.01");
        assert_eq!(show(-1e3), "-1000");
        assert_eq!(LENGTH.to_string(), "1e-6 to 1e6");
        assert_eq!(
            FIELD_OF_VIEW.to_string(),
            "greater than 0 and less than 180"
        );
    }

    #[test]
    fn the_documentation_has_the_table() {
        let doc = include_str!("../../docs/scene-format.md");
        for (what, limits) in TABLE {
            let row = format!("| {what} | {limits} |");
            assert!(
                doc.contains(&row),
                "docs/scene-format.md lacks the row\n{row}"
            );
        }
    }
}
