//! One page's connection: reads its requests, keeps its view, renders it progressively.
//!
//! The reader task turns messages into jobs on a `watch` channel (only the newest job is
//! kept, so stale requests never queue); the render task runs the passes of the newest job,
//! cancelling the pass in flight when a newer job arrives or the page goes away.

use super::protocol::{
    binary, view_named, ClientMessage, FrameHeader, ProbeReport, SceneProblem, ServerMessage,
};
use super::render::{
    render_pass, render_pass_reporting, share, CancelToken, PassRequest, SharedScene,
};
use super::{gallery, Limits, Shared};
use crate::camera::Camera;
use crate::film::Image;
use crate::pipeline::{Progress, View};
use crate::scene::{self, LoadOptions, Scene};
use axum::extract::ws::{CloseFrame, Message, WebSocket};
use futures_util::{SinkExt, StreamExt};
use glam::Vec3;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, watch};

/// A view to render.
#[derive(Debug, Clone, PartialEq)]
struct ViewJob {
    seq: u64,
    name: String,
    scene: String,
    width: u32,
    height: u32,
    view: View,
}

/// Outgoing messages of a connection (bounded: a slow page slows its renders, never
/// piles frames up in memory).
type Outbox = mpsc::Sender<Message>;

pub(crate) async fn run(socket: WebSocket, shared: Arc<Shared>, admitted: bool) {
    let (mut sink, mut stream) = socket.split();
    let (out, mut outbox) = mpsc::channel::<Message>(4);
    let writer = tokio::spawn(async move {
        while let Some(message) = outbox.recv().await {
            let closing = matches!(message, Message::Close(_));
            if sink.send(message).await.is_err() || closing {
                break;
            }
        }
        let _ = sink.close().await;
    });
    let limits = shared.options.limits.clone();
    if !admitted {
        let _ = out
            .send(error_message(
                None,
                format!(
                    "this server already has {} pages connected (the limit); close one and reload",
                    limits.max_clients
                ),
            ))
            .await;
        let _ = out.send(close(1013, "too many clients")).await;
        drop(out);
        let _ = writer.await;
        return;
    }
    let hello = ServerMessage::Hello {
        version: env!("CARGO_PKG_VERSION"),
        limits: limits.clone(),
        presets: gallery::presets(),
        scenes: gallery::SCENES.to_vec(),
        initial: (
            shared.options.scene_name.clone(),
            shared.options.scene_text.clone(),
        ),
        views: View::ALL.iter().map(|(_, name)| *name).collect(),
        legends: super::protocol::view_legends(),
        start_mode: if shared.options.scene_text == crate::scene::DEFAULT_SCENE {
            "equation"
        } else {
            "scene"
        },
    };
    let _ = out.send(Message::Text(hello.to_json().into())).await;

    let (jobs, job_rx) = watch::channel::<Option<ViewJob>>(None);
    let renderer = tokio::spawn(render_views(job_rx, out.clone(), shared.clone()));
    let mut save_cancel = CancelToken::new();
    let mut save_task: Option<tokio::task::JoinHandle<()>> = None;
    let mut mesh_task: Option<tokio::task::JoinHandle<()>> = None;
    let mut mesh_cancel = Arc::new(AtomicBool::new(false));
    let mut rate = RateLimit::new(limits.max_messages_per_second);
    // The messages over the rate limit, read in order as the window reopens: a burst loses
    // its intermediate views, presets and probes, never the last of each (the state the page
    // settled on).
    let mut deferred = Deferred::default();
    // The scene the last probe asked about (a probe of the same scene re-reads only its
    // CAMERA line).
    let mut probe_cache: Option<SceneCache> = None;

    let mut stopping = shared.stopping.clone();
    loop {
        let reopens = tokio::time::Instant::from_std(rate.next_free());
        // A waiting message is read as soon as the window has room, before any newer one.
        let mut was_waiting = false;
        let received = tokio::select! {
            biased;
            () = tokio::time::sleep_until(reopens), if !deferred.is_empty() => {
                rate.admit(Instant::now());
                was_waiting = true;
                deferred.pop().map(|text| Ok(Message::Text(text.into())))
            }
            received = stream.next() => received,
            _ = stopping.changed() => {
                let _ = out.send(close(1001, "the server is stopping")).await;
                break;
            }
        };
        let Some(received) = received else { break };
        let text = match received {
            Ok(Message::Text(text)) => text,
            Ok(Message::Binary(_)) => {
                let _ = out
                    .send(error_message(
                        None,
                        "binary messages are not understood: send JSON text".into(),
                    ))
                    .await;
                continue;
            }
            Ok(Message::Close(_)) => break,
            Ok(_) => continue,
            Err(e) => {
                // Far over the size limit, or not WebSocket at all: the layer gives up.
                let _ = out
                    .send(error_message(
                        None,
                        format!("the connection is closed: {e}"),
                    ))
                    .await;
                let _ = out.send(close(1009, "message refused")).await;
                break;
            }
        };
        if text.len() > limits.max_message_bytes {
            let _ = out
                .send(error_message(
                    None,
                    format!(
                        "message of {} bytes refused: at most {} bytes (a scene text must fit)",
                        text.len(),
                        limits.max_message_bytes
                    ),
                ))
                .await;
            continue;
        }
        if !was_waiting && (!deferred.is_empty() || !rate.admit(Instant::now())) {
            // Kept for when the window reopens (behind the messages already waiting), in place
            // of a waiting one that it makes stale; refused only when too many others wait.
            if !deferred.push(text.to_string()) {
                let _ = out
                    .send(error_message(
                        None,
                        format!(
                            "too many messages: at most {} a second are read; one was dropped",
                            limits.max_messages_per_second
                        ),
                    ))
                    .await;
            }
            continue;
        }
        let message: ClientMessage = match serde_json::from_str(&text) {
            Ok(m) => m,
            Err(e) => {
                let _ = out
                    .send(error_message(None, format!("malformed request: {e}")))
                    .await;
                continue;
            }
        };
        match message {
            ClientMessage::View {
                seq,
                scene,
                width,
                height,
                view,
            } => match check_size(width, height, limits.max_view_side, limits.max_view_pixels)
                .and_then(|()| view_named(view.as_deref()))
            {
                Ok(view) => {
                    let job = ViewJob {
                        seq,
                        name: "explore.scene".into(),
                        scene,
                        width,
                        height,
                        view,
                    };
                    jobs.send_if_modified(|current| {
                        let same = current.as_ref().is_some_and(|c| {
                            c.scene == job.scene
                                && (c.width, c.height, c.view) == (job.width, job.height, job.view)
                        });
                        if same {
                            false
                        } else {
                            *current = Some(job);
                            true
                        }
                    });
                }
                Err(why) => {
                    let _ = out.send(error_message(Some(seq), why)).await;
                }
            },
            ClientMessage::CancelSave {} => save_cancel.cancel(),
            ClientMessage::CancelMesh {} => mesh_cancel.store(true, Ordering::Relaxed),
            ClientMessage::Mesh { seq, scene, format } => {
                if mesh_task.as_ref().is_some_and(|t| !t.is_finished()) {
                    let _ = out
                        .send(error_message(
                            Some(seq),
                            "a mesh is already being made: wait for it or cancel it".into(),
                        ))
                        .await;
                    continue;
                }
                let file_format = match super::mesh::format_named(&format) {
                    Ok(file_format) => file_format,
                    Err(why) => {
                        let _ = out.send(error_message(Some(seq), why)).await;
                        continue;
                    }
                };
                // The server-wide limit: a permit held until the mesh's work has stopped.
                let Ok(permit) = shared.meshes.clone().try_acquire_owned() else {
                    let _ = out
                        .send(error_message(
                            Some(seq),
                            format!(
                                "the server is already making {} meshes (its limit, all pages \
                                 together): try again when one is done",
                                limits.max_meshes
                            ),
                        ))
                        .await;
                    continue;
                };
                mesh_cancel = Arc::new(AtomicBool::new(false));
                mesh_task = Some(tokio::spawn(make_mesh(
                    seq,
                    scene,
                    (format, file_format),
                    (shared.clone(), permit),
                    mesh_cancel.clone(),
                    out.clone(),
                )));
            }
            ClientMessage::Probe {
                seq,
                scene,
                width,
                height,
                x,
                y,
            } => {
                let reply =
                    match check_size(width, height, limits.max_view_side, limits.max_view_pixels) {
                        Err(why) => error_message(Some(seq), why),
                        Ok(()) if x >= width || y >= height => error_message(
                            Some(seq),
                            format!("pixel {x},{y} is outside the {width}×{height} view"),
                        ),
                        Ok(()) => match load(&mut probe_cache, "explore.scene", &scene).await {
                            Err(problem) => error_message(Some(seq), problem.message),
                            Ok((scene, camera, _)) => {
                                let report = tokio::task::spawn_blocking(move || {
                                    ProbeReport::of_pixel(&scene, &camera, (width, height), (x, y))
                                })
                                .await
                                .ok()
                                .flatten();
                                let message = ServerMessage::Probe { seq, x, y, report };
                                Message::Text(message.to_json().into())
                            }
                        },
                    };
                let _ = out.send(reply).await;
            }
            ClientMessage::Pause {} => {
                // No job: the render task cancels its pass and waits for the next view.
                jobs.send_if_modified(|current| current.take().is_some());
            }
            ClientMessage::Preset { name, params } => {
                let reply = match crate::shapes::implicit::preset(&name, &params) {
                    Ok(p) => ServerMessage::Preset {
                        name,
                        params,
                        equation: p.equation,
                        bound: p.bound,
                    },
                    Err(message) => ServerMessage::Error { seq: None, message },
                };
                let _ = out.send(Message::Text(reply.to_json().into())).await;
            }
            ClientMessage::Save {
                seq,
                scene,
                width,
                height,
                spp,
                view,
                alpha,
            } => {
                if save_task.as_ref().is_some_and(|t| !t.is_finished()) {
                    let _ = out
                        .send(error_message(
                            Some(seq),
                            "a save is already rendering: wait for it".into(),
                        ))
                        .await;
                    continue;
                }
                let view = match check_save(&limits, width, height, spp)
                    .and_then(|()| view_named(view.as_deref()))
                {
                    Ok(view) => view,
                    Err(why) => {
                        let _ = out.send(error_message(Some(seq), why)).await;
                        continue;
                    }
                };
                save_cancel = CancelToken::new();
                save_task = Some(tokio::spawn(save(
                    seq,
                    scene,
                    (width, height, spp, view, alpha),
                    shared.clone(),
                    save_cancel.clone(),
                    out.clone(),
                )));
            }
        }
    }
    // The page is gone: stop its work at once.
    drop(jobs);
    save_cancel.cancel();
    let _ = renderer.await;
    if let Some(task) = save_task {
        let _ = task.await;
    }
    // Its mesh stops within about one layer of the grid (see `make_mesh`); the file is not
    // sent.
    mesh_cancel.store(true, Ordering::Relaxed);
    if let Some(task) = mesh_task {
        task.abort();
    }
    drop(out);
    let _ = writer.await;
}

/// How a page's scene text is loaded: as the command line loads it, but reading no file (a
/// `MESH` is refused), since the text comes from a web page.
pub(super) fn page_load_options() -> LoadOptions {
    LoadOptions {
        forbid_files: true,
        ..LoadOptions::default()
    }
}

fn error_message(seq: Option<u64>, message: String) -> Message {
    Message::Text(ServerMessage::Error { seq, message }.to_json().into())
}

fn close(code: u16, reason: &'static str) -> Message {
    Message::Close(Some(CloseFrame {
        code,
        reason: reason.into(),
    }))
}

fn check_size(width: u32, height: u32, max_side: u32, max_pixels: u64) -> Result<(), String> {
    if width == 0 || height == 0 || width > max_side || height > max_side {
        return Err(format!(
            "image size {width}×{height} refused: each side must be 1 to {max_side} pixels"
        ));
    }
    if width as u64 * height as u64 > max_pixels {
        return Err(format!(
            "image size {width}×{height} refused: at most {max_pixels} pixels"
        ));
    }
    Ok(())
}

fn check_save(limits: &Limits, width: u32, height: u32, spp: u32) -> Result<(), String> {
    check_size(width, height, limits.max_save_side, limits.max_save_pixels)?;
    if spp == 0 || spp > limits.max_save_spp {
        return Err(format!(
            "{spp} samples per pixel refused: 1 to {} for a saved image",
            limits.max_save_spp
        ));
    }
    let samples = width as u64 * height as u64 * spp as u64;
    if samples > limits.max_save_samples {
        return Err(format!(
            "{width}×{height} at {spp} spp is {samples} samples: at most {} for a saved image",
            limits.max_save_samples
        ));
    }
    Ok(())
}

/// What a message over the rate limit stands for, judged by its `type`: a newer message of
/// the same kind makes it stale (a view or a pause: the page's current view; a preset's
/// expansion; a probe). `None`: a message that must not be lost (a save, a mesh, a cancel,
/// or a text that is not a message at all, which is answered in its turn).
fn stale_kind(text: &str) -> Option<&'static str> {
    #[derive(serde::Deserialize)]
    struct Kind {
        #[serde(rename = "type")]
        kind: String,
    }
    match serde_json::from_str::<Kind>(text).ok()?.kind.as_str() {
        "view" | "pause" => Some("view"),
        "preset" => Some("preset"),
        "probe" => Some("probe"),
        _ => None,
    }
}

/// Messages over the rate limit, waiting in the order they came: at most one of each stale
/// kind (the newest; see [`stale_kind`]) and at most [`Deferred::MAX_KEPT`] others.
#[derive(Default)]
struct Deferred {
    waiting: std::collections::VecDeque<(Option<&'static str>, String)>,
}

impl Deferred {
    /// Most waiting messages that no newer one replaces (saves, meshes, cancels).
    const MAX_KEPT: usize = 8;

    fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }

    /// Queues `text` behind the others, dropping a waiting message of its stale kind.
    /// `false`: refused (too many messages that cannot be replaced are waiting).
    fn push(&mut self, text: String) -> bool {
        let kind = stale_kind(&text);
        match kind {
            Some(kind) => self.waiting.retain(|(k, _)| *k != Some(kind)),
            None => {
                if self.waiting.iter().filter(|(k, _)| k.is_none()).count() >= Self::MAX_KEPT {
                    return false;
                }
            }
        }
        self.waiting.push_back((kind, text));
        true
    }

    /// The oldest waiting message.
    fn pop(&mut self) -> Option<String> {
        self.waiting.pop_front().map(|(_, text)| text)
    }
}

/// At most `per_second` messages in any one-second window.
struct RateLimit {
    per_second: u32,
    window_start: Instant,
    count: u32,
}

impl RateLimit {
    fn new(per_second: u32) -> Self {
        Self {
            per_second,
            window_start: Instant::now(),
            count: 0,
        }
    }

    /// When the next message can be read: at once (the window's start, already past) while
    /// the window has room, else when the window ends.
    fn next_free(&self) -> Instant {
        if self.count < self.per_second {
            self.window_start
        } else {
            self.window_start + Duration::from_secs(1)
        }
    }

    fn admit(&mut self, now: Instant) -> bool {
        if now.duration_since(self.window_start) >= Duration::from_secs(1) {
            self.window_start = now;
            self.count = 0;
        }
        self.count += 1;
        self.count <= self.per_second
    }
}

/// The text with every line that is not a CAMERA statement blanked (same length and line
/// breaks, so positions stay those of the full text).
fn camera_lines_only(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        if is_camera_line(line) {
            out.push_str(line);
        } else {
            for c in line.chars() {
                match c {
                    '\r' => out.push('\r'),
                    c => out.extend(std::iter::repeat_n(' ', c.len_utf8())),
                }
            }
        }
    }
    out
}

/// The text with every CAMERA statement blanked.
fn without_camera_lines(text: &str) -> String {
    text.split('\n')
        .map(|line| if is_camera_line(line) { "" } else { line })
        .collect::<Vec<_>>()
        .join("\n")
}

fn is_camera_line(line: &str) -> bool {
    let line = line.trim_start_matches('\u{feff}').trim_start();
    let word: String = line
        .chars()
        .take_while(|c| c.is_ascii_alphabetic())
        .collect();
    word.eq_ignore_ascii_case("camera")
}

/// The last scene parsed for this page, keyed by its text without the CAMERA line: a view
/// change that only moves the camera re-reads only that line.
struct SceneCache {
    key: String,
    scene: SharedScene,
}

/// The world-space box holding every object of `scene` with a finite box, as
/// `(min, max)`; `None` when no object has one.
fn extent(scene: &Scene) -> Option<([f64; 3], [f64; 3])> {
    let finite = |v: glam::DVec3| v.is_finite();
    let mut boxes = scene
        .objects
        .iter()
        .map(|o| o.bounds)
        .filter(|b| finite(b.min) && finite(b.max) && b.min.cmple(b.max).all());
    let first = boxes.next()?;
    let (min, max) = boxes.fold((first.min, first.max), |(lo, hi), b| {
        (lo.min(b.min), hi.max(b.max))
    });
    Some((min.to_array(), max.to_array()))
}

/// Parses `text`, or only its CAMERA line when the rest equals the cached scene's; the
/// flag is true when the scene was parsed anew.
async fn load(
    cache: &mut Option<SceneCache>,
    name: &str,
    text: &str,
) -> Result<(SharedScene, Camera, bool), SceneProblem> {
    let key = without_camera_lines(text);
    let reuse = cache
        .as_ref()
        .filter(|c| c.key == key)
        .map(|c| c.scene.clone());
    let options = page_load_options();
    if let Some(scene) = reuse {
        let camera_text = camera_lines_only(text);
        let parsed =
            scene::parse(&camera_text, name, &options).map_err(|e| SceneProblem::new(&e, text))?;
        return Ok((scene, parsed.camera, false));
    }
    let (name, owned) = (name.to_string(), text.to_string());
    let parsed = tokio::task::spawn_blocking(move || {
        let result = scene::parse(&owned, &name, &options);
        result.map_err(|e| SceneProblem::new(&e, &owned))
    })
    .await
    .unwrap_or_else(|e| Err(internal_problem(&e.to_string())))?;
    let camera = parsed.camera.clone();
    let scene = share(parsed);
    *cache = Some(SceneCache {
        key,
        scene: scene.clone(),
    });
    Ok((scene, camera, true))
}

fn internal_problem(what: &str) -> SceneProblem {
    SceneProblem {
        message: format!("internal error while loading the scene: {what}"),
        report: String::new(),
        line: 1,
        column: 1,
        length: 0,
    }
}

/// One pass of a view's progressive plan.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pass {
    width: u32,
    height: u32,
    /// Samples this pass adds.
    spp: u32,
    seed: u64,
    /// Whether it adds to the previous full-size passes (else it replaces the image).
    accumulate: bool,
}

/// The passes of a `width × height` view: 1/8 of the size at 1 sample (skipped when it
/// would be tiny), the full size at 1 sample, then doublings of the samples accumulated up
/// to `max_spp`. (A 1/4 pass between the first two cost the full frame about 6 % more
/// work and a frame's overhead for an image shown for a fraction of a second.)
fn plan(width: u32, height: u32, max_spp: u32) -> Vec<Pass> {
    let mut passes = vec![];
    if width >= 64 && height >= 64 {
        passes.push(Pass {
            width: width.div_ceil(8),
            height: height.div_ceil(8),
            spp: 1,
            seed: 0,
            accumulate: false,
        });
    }
    passes.push(Pass {
        width,
        height,
        spp: 1,
        seed: 0,
        accumulate: false,
    });
    let mut total = 1;
    let mut seed = 1;
    while total < max_spp {
        let add = total.min(max_spp - total);
        passes.push(Pass {
            width,
            height,
            spp: add,
            seed,
            accumulate: true,
        });
        total += add;
        seed += 1;
    }
    passes
}

/// How long a page may go without a frame before a view's first pass is finished although a
/// newer view is waiting (so a page dragging faster than the server renders still gets a
/// frame about this often).
const STARVED: Duration = Duration::from_millis(100);

/// Runs the newest view job's passes; a newer job (or the page leaving) cancels the pass in
/// flight.
async fn render_views(
    mut jobs: watch::Receiver<Option<ViewJob>>,
    out: Outbox,
    shared: Arc<Shared>,
) {
    let limits = &shared.options.limits;
    let mut cache: Option<SceneCache> = None;
    // When the last frame went out (see `STARVED`).
    let mut last_frame = Instant::now();
    // A refinement pass cancelled by a newer view, left to end on its own: it runs on the
    // batch threads, which may be in the middle of another render's band (a save's, seconds
    // long), and the newer view's first passes must not wait for it. The next refinement
    // pass waits for it, so a page has at most one such pass and one running.
    let mut draining: Option<tokio::task::JoinHandle<()>> = None;
    loop {
        let job = jobs.borrow_and_update().clone();
        let Some(job) = job else {
            if jobs.changed().await.is_err() {
                return;
            }
            continue;
        };
        let loaded = tokio::select! {
            loaded = load(&mut cache, &job.name, &job.scene) => loaded,
            changed = jobs.changed() => {
                if changed.is_err() { return; }
                continue;
            }
        };
        let (scene, camera) = match loaded {
            Ok((scene, camera, fresh)) => {
                if fresh {
                    if let Some((min, max)) = extent(&scene) {
                        let message = ServerMessage::Extent {
                            seq: job.seq,
                            min,
                            max,
                        };
                        let _ = out.send(Message::Text(message.to_json().into())).await;
                    }
                }
                (scene, camera)
            }
            Err(problem) => {
                let message = ServerMessage::SceneError {
                    seq: job.seq,
                    problem,
                };
                let _ = out.send(Message::Text(message.to_json().into())).await;
                if !wait_for_next(&mut jobs).await {
                    return;
                }
                continue;
            }
        };
        let passes = plan(job.width, job.height, limits.max_view_spp);
        let mut sum: Vec<Vec3> = vec![];
        let mut total_spp = 0;
        let mut changed = false;
        for (index, pass) in passes.iter().enumerate() {
            if pass.accumulate {
                if let Some(mut previous) = draining.take() {
                    tokio::select! {
                        _ = &mut previous => {}
                        next = jobs.changed() => {
                            draining = Some(previous);
                            if next.is_err() {
                                return;
                            }
                            changed = true;
                            break;
                        }
                    }
                }
            }
            let cancel = CancelToken::new();
            let request = PassRequest {
                width: pass.width,
                height: pass.height,
                camera: camera.clone(),
                spp: pass.spp,
                seed: pass.seed,
                view: job.view,
                alpha: false,
                preview: true,
                // The first frames of a change: a person waits for them.
                interactive: !pass.accumulate,
            };
            let (scene_ref, cancel_ref, busy) = (scene.clone(), cancel.clone(), Busy::new(&shared));
            let mut task = tokio::task::spawn_blocking(move || {
                render_pass(&busy.0.renderer, &scene_ref, &request, &cancel_ref)
            });
            // A page whose views come faster than their first pass renders (a drag on a busy
            // server) would see no frame at all if each view cancelled the one before: once
            // no frame has gone out for STARVED, the first pass in flight is finished and
            // sent although a newer view is waiting, and then the newest view is rendered.
            let finish_anyway = index == 0 && last_frame.elapsed() >= STARVED;
            let mut superseded = false;
            let result = tokio::select! {
                result = &mut task => result,
                next = jobs.changed() => {
                    if next.is_err() {
                        cancel.cancel();
                        let _ = task.await;
                        return;
                    }
                    changed = true;
                    if !finish_anyway {
                        cancel.cancel();
                        if pass.accumulate {
                            draining = Some(tokio::spawn(async move {
                                let _ = task.await;
                            }));
                        } else {
                            let _ = task.await;
                        }
                        break;
                    }
                    superseded = true;
                    task.await
                }
            };
            let Ok(Ok(result)) = result else {
                break;
            };
            let image = if pass.accumulate {
                for (acc, p) in sum.iter_mut().zip(&result.image.pixels) {
                    *acc += *p * pass.spp as f32;
                }
                total_spp += pass.spp;
                let scale = 1.0 / total_spp as f32;
                Image {
                    width: pass.width,
                    height: pass.height,
                    pixels: sum.iter().map(|p| *p * scale).collect(),
                    alpha: None,
                }
            } else {
                if pass.width == job.width && pass.height == job.height {
                    sum = result.image.pixels.clone();
                    total_spp = pass.spp;
                }
                result.image
            };
            let header = FrameHeader::Frame {
                seq: job.seq,
                width: pass.width,
                height: pass.height,
                view_width: job.width,
                view_height: job.height,
                spp: if pass.accumulate { total_spp } else { pass.spp },
                pass: index as u32,
                ms: result.elapsed.as_secs_f64() * 1e3,
                rays: result.rays,
                done: index + 1 == passes.len(),
            };
            if !finish_anyway && jobs.has_changed().unwrap_or(true) {
                changed = true;
                break;
            }
            if out
                .send(Message::Binary(binary(&header, &rgba(&image)).into()))
                .await
                .is_err()
            {
                return;
            }
            last_frame = Instant::now();
            if superseded || jobs.has_changed().unwrap_or(true) {
                changed = true;
                break;
            }
        }
        if !changed && !wait_for_next(&mut jobs).await {
            return;
        }
    }
}

/// Waits until a job newer than the one last seen is there (at once if it already is);
/// `false` when the page is gone.
async fn wait_for_next(jobs: &mut watch::Receiver<Option<ViewJob>>) -> bool {
    match jobs.has_changed() {
        Err(_) => false,
        Ok(true) => true,
        Ok(false) => jobs.changed().await.is_ok(),
    }
}

/// Counts a render as running for as long as it lives (moved into the render's thread).
struct Busy(Arc<Shared>);

impl Busy {
    fn new(shared: &Arc<Shared>) -> Self {
        shared.renders.fetch_add(1, Ordering::SeqCst);
        Self(shared.clone())
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        self.0.renders.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The image as RGBA8 (sRGB, opaque).
fn rgba(image: &Image) -> Vec<u8> {
    let rgb = image.to_srgb8();
    let mut out = Vec::with_capacity(rgb.len() / 3 * 4);
    for px in rgb.chunks_exact(3) {
        out.extend_from_slice(px);
        out.push(255);
    }
    out
}

/// Renders a scene once and sends it as a PNG (RGBA with straight alpha for a transparent
/// background), with a `save_progress` message about every quarter second while it renders;
/// cancelled by `cancel` (then an error saying so).
async fn save(
    seq: u64,
    text: String,
    (width, height, spp, view, alpha): (u32, u32, u32, View, bool),
    shared: Arc<Shared>,
    cancel: CancelToken,
    out: Outbox,
) {
    let busy = Busy::new(&shared);
    let done = Arc::new(AtomicU64::new(0));
    let total = u64::from(width) * u64::from(height);
    let pixels_done = done.clone();
    let mut work = tokio::task::spawn_blocking(move || -> Result<(Vec<u8>, f64), String> {
        let renderer = &busy.0.renderer;
        let scene: Scene = scene::parse(&text, "explore.scene", &page_load_options())
            .map_err(|e| e.to_string())?;
        let camera = scene.camera.clone();
        let shared = share(scene);
        let request = PassRequest {
            width,
            height,
            camera,
            spp,
            seed: 0,
            view,
            alpha,
            preview: false,
            interactive: false,
        };
        let progress = |p: Progress| pixels_done.store(p.done, Ordering::Relaxed);
        let result = render_pass_reporting(renderer, &shared, &request, &cancel, progress)
            .map_err(|e| e.to_string())?;
        let mut png = vec![];
        crate::film::encode_png(&result.image, &mut png)
            .map_err(|e| format!("cannot encode the PNG: {e}"))?;
        Ok((png, result.elapsed.as_secs_f64() * 1e3))
    });
    let mut ticks = tokio::time::interval(Duration::from_millis(250));
    let work = loop {
        tokio::select! {
            work = &mut work => break work,
            _ = ticks.tick() => {
                let message = ServerMessage::SaveProgress {
                    seq,
                    done: done.load(Ordering::Relaxed),
                    total,
                };
                // Skipped when the page is slow to read: the next one says more.
                let _ = out.try_send(Message::Text(message.to_json().into()));
            }
        }
    };
    let message = match work {
        Ok(Ok((png, ms))) => Message::Binary(
            binary(
                &FrameHeader::Png {
                    seq,
                    width,
                    height,
                    spp,
                    ms,
                },
                &png,
            )
            .into(),
        ),
        Ok(Err(why)) => error_message(Some(seq), format!("save failed: {why}")),
        Err(e) => error_message(Some(seq), format!("save failed: {e}")),
    };
    let _ = out.send(message).await;
}

/// Meshes a scene as `kardia mesh` does and sends the file, with a `mesh_progress` message
/// about every quarter second; `cancel` stops it (then an error saying so). The work keeps
/// `permit` (a place under [`super::Limits::max_meshes`]) until it has really stopped, even
/// when the page has left.
async fn make_mesh(
    seq: u64,
    text: String,
    (format, file_format): (String, crate::mesh::write::MeshFormat),
    (shared, permit): (Arc<Shared>, tokio::sync::OwnedSemaphorePermit),
    cancel: Arc<AtomicBool>,
    out: Outbox,
) {
    let busy = Busy::new(&shared);
    let fraction = Arc::new(AtomicU64::new(0));
    let reported = fraction.clone();
    let start = Instant::now();
    let stop = cancel.clone();
    let mut work = tokio::task::spawn_blocking(move || {
        let _held = (busy, permit);
        let progress = |f: f64| reported.store(f.to_bits(), Ordering::Relaxed);
        super::mesh::mesh_scene(&text, file_format, &progress, &stop)
    });
    let mut ticks = tokio::time::interval(Duration::from_millis(250));
    let work = loop {
        tokio::select! {
            work = &mut work => break work,
            _ = ticks.tick() => {
                let message = ServerMessage::MeshProgress {
                    seq,
                    fraction: f64::from_bits(fraction.load(Ordering::Relaxed)),
                };
                let _ = out.try_send(Message::Text(message.to_json().into()));
            }
        }
    };
    let message = match work {
        Ok(Ok(file)) => Message::Binary(
            binary(
                &FrameHeader::Mesh {
                    seq,
                    format,
                    triangles: file.triangles,
                    ms: start.elapsed().as_secs_f64() * 1e3,
                },
                &file.bytes,
            )
            .into(),
        ),
        Ok(Err(_)) if cancel.load(Ordering::Relaxed) => {
            error_message(Some(seq), "mesh cancelled".into())
        }
        Ok(Err(why)) => error_message(Some(seq), format!("mesh failed: {why}")),
        Err(e) => error_message(Some(seq), format!("mesh failed: {e}")),
    };
    let _ = out.send(message).await;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_coarse_then_full_then_doubling() {
        let p = plan(800, 600, 64);
        let sizes: Vec<_> = p.iter().map(|p| (p.width, p.height, p.spp)).collect();
        assert_eq!(
            sizes,
            vec![
                (100, 75, 1),
                (800, 600, 1),
                (800, 600, 1),
                (800, 600, 2),
                (800, 600, 4),
                (800, 600, 8),
                (800, 600, 16),
                (800, 600, 32)
            ]
        );
        let seeds: Vec<_> = p.iter().skip(1).map(|p| p.seed).collect();
        assert_eq!(seeds, vec![0, 1, 2, 3, 4, 5, 6]);
        assert_eq!(plan(30, 20, 1).len(), 1);
        assert_eq!(plan(800, 600, 5).last().unwrap().spp, 1);
    }

    #[test]
    fn camera_lines() {
        let text = "# é\nSIZE 8 6\n  camera (1,0,0) (0,0,0) (0,0,1) 40\r\nLIGHT (1,1,1) (1,1,1)";
        let only = camera_lines_only(text);
        assert_eq!(only.len(), text.len());
        assert_eq!(only.lines().nth(2), text.lines().nth(2));
        assert!(only.lines().nth(1).unwrap().trim().is_empty());
        let without = without_camera_lines(text);
        assert!(!without.contains("camera"));
        assert_eq!(without.lines().count(), 4);
        assert!(!is_camera_line("# CAMERA"));
        assert!(!is_camera_line("CAMERAS"));
        assert!(is_camera_line("\u{feff}CAMERA (1,0,0)"));
    }

    #[test]
    fn rate_limit_window() {
        let mut r = RateLimit::new(3);
        let t = Instant::now();
        assert!(r.admit(t) && r.admit(t));
        assert!(r.next_free() <= Instant::now(), "room left: at once");
        assert!(r.admit(t));
        assert!(!r.admit(t));
        assert!(
            r.next_free() > Instant::now() + Duration::from_millis(900),
            "full: when the window ends"
        );
        assert!(r.admit(t + Duration::from_millis(1001)));
    }

    #[test]
    fn deferred_messages_keep_the_last_of_each_stale_kind_in_order() {
        let preset =
            |r: f64| json_text("preset", &format!(r#","name":"torus","params":[{r},0.3]"#));
        let view = |seq: u32| json_text("view", &format!(r#","seq":{seq}"#));
        let mut d = Deferred::default();
        for i in 1..=50 {
            assert!(d.push(preset(f64::from(i) / 100.0)));
            assert!(d.push(view(i)));
        }
        assert!(d.push(json_text("save", "")));
        assert!(d.push(json_text("pause", "")));
        let order: Vec<String> = std::iter::from_fn(|| d.pop()).collect();
        assert_eq!(
            order,
            [preset(0.5), json_text("save", ""), json_text("pause", "")]
        );
        // Messages no newer one replaces are kept up to the limit, then refused.
        for _ in 0..Deferred::MAX_KEPT {
            assert!(d.push(json_text("cancel_save", "")));
        }
        assert!(!d.push(json_text("save", "")));
        assert!(d.push(view(1)), "a view still replaces");
        assert!(
            !d.push("not json".into()),
            "a text that is no message is kept, and counted"
        );
    }

    fn json_text(kind: &str, rest: &str) -> String {
        format!(r#"{{"type":"{kind}"{rest}}}"#)
    }

    #[test]
    fn sizes_and_saves_are_bounded() {
        let l = Limits::default();
        assert!(check_size(800, 600, l.max_view_side, l.max_view_pixels).is_ok());
        assert!(check_size(0, 600, l.max_view_side, l.max_view_pixels).is_err());
        assert!(check_size(4096, 4096, l.max_view_side, l.max_view_pixels).is_err());
        assert!(check_save(&l, 800, 600, 16).is_ok());
        assert!(check_save(&l, 800, 600, 0).is_err());
        assert!(check_save(&l, 4096, 4096, 1024).is_err());
    }
}
