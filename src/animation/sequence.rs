//! A run of frames rendered in order: each to its own file (a still is the run of frame 0
//! alone), or all into one animated file. What `kardia render` does once it has read its
//! arguments, whatever they ask for: a still, frames, a turntable, a tile or a region.

use std::path::Path;

use super::animated::{AnimatedEncoder, AnimatedFormat};
use super::{frame_path, is_complete_animation, FrameError, FrameJob, FrameRange};
use crate::film::{AtomicFile, ImageFormat, Region};
use crate::pipeline::{Control, RenderSummary, Renderer};
use crate::scene::Scene;

/// What a run did: frames rendered, frames skipped as already complete (`--resume`), and
/// the summary of the last frame rendered (`None` when none was).
#[derive(Debug, Clone, Default)]
pub struct Done {
    /// Frames rendered and written.
    pub rendered: u32,
    /// Frames whose file was already complete with this render's key.
    pub skipped: u32,
    /// The last rendered frame's size, region and statistics.
    pub last: Option<RenderSummary>,
}

/// What a run tells its caller about each frame, before the frame's pixels (for progress).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameEvent {
    /// The frame starts rendering.
    Rendering(u32),
    /// The frame's file is already complete with this render's key: not rendered.
    Skipped(u32),
}

/// Renders each frame of `range` to its own file, `pattern` with its `####` filled in (a
/// pattern without `#` names one file: the run of one frame). With `resume`, a frame whose
/// file is already complete with its render key ([`FrameJob::is_done`]) is skipped. `still`,
/// when given, is the job's scene read as a still: a job of one frame (`job.count == 1`)
/// renders it instead of reading the text again. Stops at the first frame that fails (a
/// cancelled render is [`crate::pipeline::RenderError::Cancelled`]); the frames before it
/// stay written.
#[allow(clippy::too_many_arguments)]
pub fn render_frames_to_files(
    job: &FrameJob,
    renderer: &Renderer,
    control: &Control,
    range: FrameRange,
    format: ImageFormat,
    pattern: &Path,
    resume: bool,
    still: Option<&Scene>,
    on_frame: &dyn Fn(FrameEvent),
) -> Result<Done, FrameError> {
    let mut done = Done::default();
    for frame in range.frames() {
        let path = frame_path(pattern, frame);
        if resume && job.is_done(frame, &path) {
            on_frame(FrameEvent::Skipped(frame));
            done.skipped += 1;
            continue;
        }
        on_frame(FrameEvent::Rendering(frame));
        let summary = match still {
            Some(scene) if job.count == 1 => {
                job.render_scene_to_file(renderer, frame, scene, control, format, &path)?
            }
            _ => job.render_to_file(renderer, frame, control, format, &path)?,
        };
        done.rendered += 1;
        done.last = Some(summary);
    }
    Ok(done)
}

/// Renders every frame of `range` (each `region` of its frame) into one animated file at
/// `output`, written atomically, at `fps` frames per second. With `resume`, an `output`
/// that is already a complete animation of this job (its render key: the scene, the
/// settings, the frames, the rate and the region) is kept and every frame counted as
/// skipped; any other file there is rendered anew.
#[allow(clippy::too_many_arguments)]
pub fn render_animated_file(
    job: &FrameJob,
    renderer: &Renderer,
    control: &Control,
    range: FrameRange,
    kind: AnimatedFormat,
    output: &Path,
    fps: f64,
    region: Region,
    resume: bool,
    on_frame: &dyn Fn(FrameEvent),
) -> Result<Done, FrameError> {
    let key = job.animation_key(range, kind, fps, region)?;
    if resume
        && is_complete_animation(output)
        && super::animated::read_key(output).as_deref() == Some(key.as_str())
    {
        range
            .frames()
            .for_each(|f| on_frame(FrameEvent::Skipped(f)));
        return Ok(Done {
            skipped: range.len(),
            ..Done::default()
        });
    }
    let mut file = AtomicFile::create(output)?;
    let mut encoder = AnimatedEncoder::new(
        kind,
        &mut file,
        region.width,
        region.height,
        range.len(),
        fps,
        job.request.alpha,
        &key,
    )?;
    let mut last = None;
    for frame in range.frames() {
        on_frame(FrameEvent::Rendering(frame));
        let (scene, request) = job.frame(frame)?;
        let rendered = renderer.render(&scene, &request, control)?;
        encoder.add_frame(&rendered.image)?;
        last = Some(rendered.summary());
    }
    encoder.finish()?;
    file.commit()?;
    Ok(Done {
        rendered: range.len(),
        skipped: 0,
        last,
    })
}
