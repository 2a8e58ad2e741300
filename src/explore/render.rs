//! The explorer's one seam to the renderer: a pass of the progressive render (a size, a
//! camera, some samples, a seed) of a loaded scene, cancellable. Everything else in the
//! explorer calls [`render_pass`] and never the integrator directly.

use crate::camera::Camera;
use crate::film::Image;
use crate::integrator::{self, RenderSettings};
use crate::scene::Scene;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A loaded scene shared by a client's passes. (The scene's own camera and size are the
/// defaults; a pass may override both.)
pub type SharedScene = Arc<Mutex<Scene>>;

/// Wraps a freshly parsed scene for [`render_pass`].
pub fn share(scene: Scene) -> SharedScene {
    Arc::new(Mutex::new(scene))
}

/// A cheap, cloneable flag that asks a render in flight to stop.
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token not yet cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every holder of a clone to stop; idempotent.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`cancel`](Self::cancel) was called on any clone.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// A render stopped by its [`CancelToken`] before it finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the render was cancelled")]
pub struct Cancelled;

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
    /// Worker threads (0: one per core).
    pub threads: usize,
}

/// One finished pass.
#[derive(Debug, Clone)]
pub struct PassResult {
    /// The image, `width × height` linear RGB.
    pub image: Image,
    /// Rays traced (primary, secondary and shadow rays).
    pub rays: u64,
    /// Wall time of the render.
    pub elapsed: Duration,
}

/// Renders one pass of `scene`; returns [`Cancelled`] when `cancel` was set before or
/// during the render.
pub fn render_pass(
    scene: &SharedScene,
    request: &PassRequest,
    cancel: &CancelToken,
) -> Result<PassResult, Cancelled> {
    if cancel.is_cancelled() {
        return Err(Cancelled);
    }
    let mut scene = scene.lock().unwrap_or_else(|e| e.into_inner());
    scene.camera = request.camera.clone();
    scene.width = request.width.max(1);
    scene.height = request.height.max(1);
    let settings = RenderSettings {
        spp: request.spp.max(1),
        seed: request.seed,
        threads: request.threads,
        ..RenderSettings::default()
    };
    let (image, stats) = integrator::render_with_progress(&scene, &settings, &|_| {});
    if cancel.is_cancelled() {
        return Err(Cancelled);
    }
    Ok(PassResult {
        image,
        rays: stats.rays,
        elapsed: stats.elapsed,
    })
}
