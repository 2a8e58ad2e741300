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
}
