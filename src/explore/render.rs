//! The explorer's one seam to the renderer: a pass of the progressive render (a size, a
//! camera, some samples, a seed, a view) of a loaded scene, cancellable. Everything else in
//! the explorer calls [`render_pass`] and never the integrator directly.

use crate::camera::Camera;
use crate::film::Image;
use crate::pipeline::{Control, Priority, Progress, RenderError, RenderRequest, Renderer, View};
use crate::scene::Scene;
use std::sync::Arc;
use std::time::Duration;

pub use crate::pipeline::CancelToken;

/// A loaded scene shared by a client's passes (its own camera and size are only defaults:
/// a pass overrides both).
pub type SharedScene = Arc<Scene>;

/// Wraps a freshly parsed scene for [`render_pass`].
pub fn share(scene: Scene) -> SharedScene {
    Arc::new(scene)
}

/// A render stopped by its [`CancelToken`] before it finished (or refused by the renderer).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct NotRendered(pub String);

/// One pass: what to render.
#[derive(Debug, Clone)]
pub struct PassRequest {
    /// Image width in pixels (≥ 1).
    pub width: u32,
    /// Image height in pixels (≥ 1).
    pub height: u32,
    /// Camera to render through.
    pub camera: Camera,
    /// Samples per pixel (≥ 1).
    pub spp: u32,
    /// Seed of the jitter and light sampling.
    pub seed: u64,
    /// Which image to make.
    pub view: View,
    /// A transparent background (the image gets alpha: see [`RenderRequest::alpha`]).
    pub alpha: bool,
    /// A pass of the live view: one shadow ray per spherical light and sample (see
    /// [`RenderRequest::max_shadow_rays`]), so a frame costs fewer rays and its soft shadows
    /// converge as the passes accumulate. `false` (a saved image): each light's `SAMPLES`,
    /// exactly as `kardia render`.
    pub preview: bool,
    /// A person waits for this pass (a view's first frames after a change): it goes ahead of
    /// every other render on the server ([`Priority::Interactive`]); `false`: it shares the
    /// threads with the others ([`Priority::Batch`]).
    pub interactive: bool,
}

/// One finished pass.
#[derive(Debug, Clone)]
pub struct PassResult {
    /// The image, `width × height` linear RGB (premultiplied, with alpha, when asked for).
    pub image: Image,
    /// Rays traced (primary, secondary and shadow rays).
    pub rays: u64,
    /// Wall time of the render.
    pub elapsed: Duration,
}

/// Renders one pass of `scene`; fails when `cancel` was set before or during the render.
pub fn render_pass(
    renderer: &Renderer,
    scene: &SharedScene,
    request: &PassRequest,
    cancel: &CancelToken,
) -> Result<PassResult, NotRendered> {
    render_pass_reporting(renderer, scene, request, cancel, |_| {})
}

/// [`render_pass`], telling `progress` the pixels done after every tile (from the render's
/// threads: keep it short).
pub fn render_pass_reporting(
    renderer: &Renderer,
    scene: &SharedScene,
    request: &PassRequest,
    cancel: &CancelToken,
    progress: impl Fn(Progress) + Send + Sync,
) -> Result<PassResult, NotRendered> {
    let render_request = RenderRequest {
        width: Some(request.width.max(1)),
        height: Some(request.height.max(1)),
        camera: Some(request.camera.clone()),
        spp: request.spp.max(1),
        seed: request.seed,
        view: request.view,
        alpha: request.alpha,
        max_shadow_rays: request.preview.then_some(1),
        ..RenderRequest::default()
    };
    let priority = if request.interactive {
        Priority::Interactive
    } else {
        Priority::Batch
    };
    let control = Control::new(cancel.clone(), progress).with_priority(priority);
    let rendered = renderer
        .render(scene, &render_request, &control)
        .map_err(|e: RenderError| NotRendered(e.to_string()))?;
    Ok(PassResult {
        image: rendered.image,
        rays: rendered.stats.rays,
        elapsed: rendered.stats.elapsed,
    })
}
