//! The Whitted integrator: shading, shadows, reflection, refraction, supersampling, tiles.

use crate::film::Image;
use crate::scene::Scene;

/// How to render: everything not in the scene text.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel (≥ 1), stratified and jittered.
    pub spp: u32,
    /// Maximum recursion depth for reflection and refraction (0 = primary hits only).
    pub max_depth: u32,
    /// Seed for the jitter; the same seed gives the same image.
    pub seed: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            spp: 4,
            max_depth: 8,
            seed: 0x6b61_7264_6961,
        }
    }
}

/// Renders the scene to a linear-RGB image.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Image {
    let _ = (scene, settings);
    todo!("renderer work")
}
