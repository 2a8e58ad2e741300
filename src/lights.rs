//! Light sources.

use crate::geometry::DVec3;

/// A point light, or with `radius > 0` a spherical light that casts soft shadows.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    /// World position (the centre for a spherical light).
    pub position: DVec3,
    /// Linear RGB intensity; not attenuated with distance.
    pub colour: DVec3,
    /// Radius of a spherical light in world units; 0 for a point light.
    pub radius: f64,
    /// Shadow rays sent to a spherical light for each pixel sample (≥ 1; 0 counts as 1),
    /// at stratified points of its disc: more give smoother soft shadows at a given `spp`.
    /// A point light always gets one.
    pub samples: u32,
}

impl Light {
    /// Most shadow samples a light may ask for per pixel sample.
    pub const MAX_SAMPLES: u32 = 1024;
}
