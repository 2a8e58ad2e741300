//! `kardia explore`: a local web server with one embedded page that renders scenes
//! progressively as the view changes (see docs/explorer.md).
//!
//! The page talks to the server over one WebSocket ([`protocol`]); every connection gets its
//! own view and its own progressive render, which a new request or a disconnect cancels.
//! Requests whose `Host` or `Origin` is not this server's own are refused (DNS rebinding),
//! and every message is checked against [`Limits`]. No message names a file: the scenes that
//! can be opened are embedded in the binary ([`gallery::SCENES`]).

pub mod gallery;
pub mod mesh;
pub mod protocol;
pub mod render;
mod session;

use axum::extract::{ws::WebSocketUpgrade, Request, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use serde::Serialize;
use std::future::Future;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// What one client may ask for; each refusal is answered with a message saying which limit.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Limits {
    /// Largest text message accepted, in bytes (a scene text travels in one).
    pub max_message_bytes: usize,
    /// Largest view side, in pixels.
    pub max_view_side: u32,
    /// Largest view, in pixels (width·height).
    pub max_view_pixels: u64,
    /// Samples per pixel a view refines to while nothing changes.
    pub max_view_spp: u32,
    /// Largest side of a saved image, in pixels.
    pub max_save_side: u32,
    /// Largest saved image, in pixels.
    pub max_save_pixels: u64,
    /// Most samples per pixel of a saved image.
    pub max_save_spp: u32,
    /// Most samples (pixels·spp) of a saved image.
    pub max_save_samples: u64,
    /// Most messages a client may send per second; more are refused.
    pub max_messages_per_second: u32,
    /// Most clients connected at once.
    pub max_clients: usize,
    /// Most meshes (Download STL / 3MF) made at once on the server, all pages together; a
    /// page asking for one more is refused until one is done. (A page makes one at a time.)
    pub max_meshes: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 256 * 1024,
            max_view_side: 4096,
            max_view_pixels: 2560 * 1600,
            max_view_spp: 64,
            max_save_side: 8192,
            max_save_pixels: 4096 * 4096,
            max_save_spp: 1024,
            max_save_samples: 1 << 28,
            max_messages_per_second: 200,
            max_clients: 16,
            max_meshes: 2,
        }
    }
}

/// How to run the explorer.
#[derive(Debug, Clone)]
pub struct Options {
    /// Name of the initial scene, for messages.
    pub scene_name: String,
    /// Text of the initial scene.
    pub scene_text: String,
    /// Address to listen on (127.0.0.1 unless the user asked for another).
    pub host: IpAddr,
    /// Port (0: any free port).
    pub port: u16,
    /// Render threads, shared by every page (0: one per core).
    pub threads: usize,
    /// Limits per client.
    pub limits: Limits,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            scene_name: "scenes/heart.scene".into(),
            scene_text: crate::scene::DEFAULT_SCENE.into(),
            host: IpAddr::from([127, 0, 0, 1]),
            port: 0,
            threads: 0,
            limits: Limits::default(),
        }
    }
}

/// Why the explorer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ExploreError {
    /// The address could not be bound.
    #[error("cannot listen on {addr}: {reason}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// The operating system's reason.
        reason: String,
    },
    /// The render threads could not be started.
    #[error(transparent)]
    Pool(#[from] crate::pipeline::PoolError),
    /// The server failed while running.
    #[error("the server stopped: {0}")]
    Serve(String),
}

/// What every connection shares.
#[derive(Debug)]
pub(crate) struct Shared {
    pub(crate) options: Options,
    pub(crate) renderer: Arc<crate::pipeline::Renderer>,
    pub(crate) port: u16,
    pub(crate) clients: AtomicUsize,
    pub(crate) renders: AtomicUsize,
    /// One permit per mesh that may be made at once ([`Limits::max_meshes`]); a mesh holds
    /// its permit until its work has really stopped (finished or cancelled).
    pub(crate) meshes: Arc<tokio::sync::Semaphore>,
    /// Becomes `true` when the server stops: every session closes its page.
    pub(crate) stopping: tokio::sync::watch::Receiver<bool>,
    /// The gallery's thumbnails rendered so far (PNG files, by entry id); the lock is held
    /// while one renders, so thumbnails render one at a time.
    pub(crate) thumbnails: tokio::sync::Mutex<std::collections::HashMap<String, Arc<Vec<u8>>>>,
}

/// A bound explorer server, not yet serving.
#[derive(Debug)]
pub struct Server {
    listener: tokio::net::TcpListener,
    shared: Arc<Shared>,
    stop: tokio::sync::watch::Sender<bool>,
}

impl Server {
    /// Binds `options.host:options.port` (port 0 picks a free one). Must be called inside a
    /// tokio runtime.
    pub async fn bind(options: Options) -> Result<Self, ExploreError> {
        let addr = SocketAddr::new(options.host, options.port);
        let listener =
            tokio::net::TcpListener::bind(addr)
                .await
                .map_err(|e| ExploreError::Bind {
                    addr,
                    reason: e.to_string(),
                })?;
        let port = listener
            .local_addr()
            .map_err(|e| ExploreError::Bind {
                addr,
                reason: e.to_string(),
            })?
            .port();
        let renderer = Arc::new(crate::pipeline::Renderer::new(options.threads)?);
        let (stop, stopping) = tokio::sync::watch::channel(false);
        Ok(Self {
            listener,
            stop,
            shared: Arc::new(Shared {
                stopping,
                renderer,
                port,
                clients: AtomicUsize::new(0),
                renders: AtomicUsize::new(0),
                meshes: Arc::new(tokio::sync::Semaphore::new(options.limits.max_meshes)),
                thumbnails: Default::default(),
                options,
            }),
        })
    }

    /// The address actually bound.
    pub fn local_addr(&self) -> SocketAddr {
        SocketAddr::new(self.shared.options.host, self.shared.port)
    }

    /// The page's URL (`http://127.0.0.1:PORT/` for a loopback or unspecified address).
    pub fn url(&self) -> String {
        let host = self.shared.options.host;
        let shown = if host.is_unspecified() {
            "127.0.0.1".to_string()
        } else if host.is_ipv6() {
            format!("[{host}]")
        } else {
            host.to_string()
        };
        format!("http://{shown}:{}/", self.shared.port)
    }

    /// How many pages are connected and how many renders are running now.
    pub fn monitor(&self) -> Monitor {
        Monitor(self.shared.clone())
    }

    /// Serves until `shutdown` completes; then stops accepting, closes every page (cancelling
    /// its renders) and returns.
    pub async fn serve(
        self,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> Result<(), ExploreError> {
        let app = router(self.shared);
        let stop = self.stop;
        axum::serve(self.listener, app)
            .with_graceful_shutdown(async move {
                shutdown.await;
                let _ = stop.send(true);
            })
            .await
            .map_err(|e| ExploreError::Serve(e.to_string()))
    }
}

/// A view of a running server's load, for tests and monitoring.
#[derive(Debug, Clone)]
pub struct Monitor(Arc<Shared>);

impl Monitor {
    /// Pages connected now.
    pub fn clients(&self) -> usize {
        self.0.clients.load(Ordering::SeqCst)
    }

    /// Renders (view passes and saves) running now.
    pub fn renders(&self) -> usize {
        self.0.renders.load(Ordering::SeqCst)
    }

    /// Meshes being made now, all pages together (their work still running, though a page
    /// that cancelled it or left no longer waits for it).
    pub fn meshes(&self) -> usize {
        let limit = self.0.options.limits.max_meshes;
        limit.saturating_sub(self.0.meshes.available_permits())
    }
}

/// Runs the explorer until `shutdown` completes (the CLI: Ctrl-C): builds a runtime, binds,
/// calls `ready(url)` once it listens, serves, closes every page. Returns when stopped or on
/// failure.
pub fn run(
    options: Options,
    ready: impl FnOnce(&str),
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> Result<(), ExploreError> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| ExploreError::Serve(e.to_string()))?;
    runtime.block_on(async move {
        let server = Server::bind(options).await?;
        ready(&server.url());
        server.serve(shutdown).await
    })
}

const INDEX_HTML: &str = include_str!("page/index.html");
const APP_JS: &str = include_str!("page/app.js");
const STYLE_CSS: &str = include_str!("page/style.css");

fn router(shared: Arc<Shared>) -> Router {
    let page = |body: &'static str, mime: &'static str| {
        move || async move {
            (
                [
                    (header::CONTENT_TYPE, mime),
                    (header::CACHE_CONTROL, "no-store"),
                    (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
                ],
                body,
            )
        }
    };
    Router::new()
        .route("/", get(page(INDEX_HTML, "text/html; charset=utf-8")))
        .route(
            "/app.js",
            get(page(APP_JS, "text/javascript; charset=utf-8")),
        )
        .route(
            "/style.css",
            get(page(STYLE_CSS, "text/css; charset=utf-8")),
        )
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/thumbnail/{id}", get(thumbnail))
        .route("/ws", get(websocket))
        .layer(middleware::from_fn_with_state(
            shared.clone(),
            same_origin_only,
        ))
        .with_state(shared)
}

async fn websocket(State(shared): State<Arc<Shared>>, upgrade: WebSocketUpgrade) -> Response {
    // Messages a little over the limit are read and refused with a message; far over it,
    // the connection is closed by the WebSocket layer.
    let hard_limit = shared.options.limits.max_message_bytes * 4 + 1024;
    upgrade
        .max_message_size(hard_limit)
        .max_frame_size(hard_limit)
        .on_upgrade(move |socket| async move {
            let admitted =
                shared.clients.fetch_add(1, Ordering::SeqCst) < shared.options.limits.max_clients;
            session::run(socket, shared.clone(), admitted).await;
            shared.clients.fetch_sub(1, Ordering::SeqCst);
        })
}

/// Size of a gallery thumbnail, in pixels, and its samples per pixel.
pub const THUMBNAIL: (u32, u32, u32) = (160, 120, 2);

/// `GET /thumbnail/ID`: the gallery entry's default view rendered by kardia
/// ([`gallery::scene_text`] at [`THUMBNAIL`]), as a PNG; rendered on first request, then kept.
async fn thumbnail(
    State(shared): State<Arc<Shared>>,
    axum::extract::Path(id): axum::extract::Path<String>,
) -> Response {
    let Some(entry) = gallery::presets().into_iter().find(|g| g.id == id) else {
        return (StatusCode::NOT_FOUND, "no such gallery entry\n").into_response();
    };
    let mut cache = shared.thumbnails.lock().await;
    let png = match cache.get(&id) {
        Some(png) => png.clone(),
        None => {
            let renderer = shared.renderer.clone();
            let work = tokio::task::spawn_blocking(move || render_thumbnail(&renderer, &entry));
            match work.await {
                Ok(Ok(png)) => {
                    let png = Arc::new(png);
                    cache.insert(id, png.clone());
                    png
                }
                Ok(Err(why)) => return (StatusCode::INTERNAL_SERVER_ERROR, why).into_response(),
                Err(e) => {
                    return (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response()
                }
            }
        }
    };
    drop(cache);
    (
        [
            (header::CONTENT_TYPE, "image/png"),
            (header::CACHE_CONTROL, "max-age=3600"),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        ],
        png.as_ref().clone(),
    )
        .into_response()
}

/// Renders a gallery entry's thumbnail PNG (opaque, seed 0, as `kardia render`).
pub fn render_thumbnail(
    renderer: &crate::pipeline::Renderer,
    entry: &gallery::GalleryPreset,
) -> Result<Vec<u8>, String> {
    let text = gallery::scene_text(entry);
    let scene =
        crate::scene::parse(&text, entry.id, &Default::default()).map_err(|e| e.to_string())?;
    let (width, height, spp) = THUMBNAIL;
    let request = crate::pipeline::RenderRequest {
        width: Some(width),
        height: Some(height),
        spp,
        ..crate::pipeline::RenderRequest::default()
    };
    let image = renderer
        .render(&scene, &request, &crate::pipeline::Control::default())
        .map_err(|e| e.to_string())?
        .image;
    let mut png = vec![];
    crate::film::encode_png(&image, &mut png).map_err(|e| e.to_string())?;
    Ok(png)
}

/// Refuses a request whose `Host` is not this server's own, or whose `Origin` (when sent)
/// is not a page of this server: a page elsewhere (or a rebound DNS name) cannot talk to it.
async fn same_origin_only(
    State(shared): State<Arc<Shared>>,
    request: Request,
    next: Next,
) -> Response {
    match check_host_and_origin(request.headers(), shared.port) {
        Ok(()) => next.run(request).await,
        Err(why) => (
            StatusCode::FORBIDDEN,
            format!("kardia explore refused this request: {why}\n"),
        )
            .into_response(),
    }
}

/// Whether `authority` (`host[:port]`) names this server: `localhost` or an IP literal, at
/// `port`. A DNS name other than localhost is refused (a rebound name is how a foreign page
/// would reach a local server).
pub fn is_own_authority(authority: &str, port: u16) -> bool {
    let (host, authority_port) = match authority.rsplit_once(':') {
        Some((h, p)) if !h.is_empty() && (!h.contains(':') || h.ends_with(']')) => {
            (h, p.parse::<u16>().ok())
        }
        _ => (authority, None),
    };
    let port_ok = authority_port.map_or(port == 80, |p| p == port);
    let host = host.trim_start_matches('[').trim_end_matches(']');
    port_ok && (host.eq_ignore_ascii_case("localhost") || host.parse::<IpAddr>().is_ok())
}

fn check_host_and_origin(headers: &HeaderMap, port: u16) -> Result<(), String> {
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .ok_or("no Host header")?;
    if !is_own_authority(host, port) {
        return Err(format!(
            "Host '{}' is not this server",
            host.chars().take(80).collect::<String>()
        ));
    }
    if let Some(origin) = headers.get(header::ORIGIN) {
        let origin = origin.to_str().unwrap_or("");
        let own = origin
            .strip_prefix("http://")
            .is_some_and(|authority| is_own_authority(authority, port));
        if !own {
            return Err(format!(
                "Origin '{}' is not this server",
                origin.chars().take(80).collect::<String>()
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn own_authorities() {
        assert!(is_own_authority("127.0.0.1:8080", 8080));
        assert!(is_own_authority("localhost:8080", 8080));
        assert!(is_own_authority("LOCALHOST:8080", 8080));
        assert!(is_own_authority("[::1]:8080", 8080));
        assert!(is_own_authority("192.168.1.5:8080", 8080));
        assert!(!is_own_authority("127.0.0.1:8081", 8080));
        assert!(!is_own_authority("127.0.0.1", 8080));
        assert!(is_own_authority("127.0.0.1", 80));
        assert!(!is_own_authority("evil.example:8080", 8080));
        assert!(!is_own_authority("localhost.evil.example:8080", 8080));
        assert!(!is_own_authority("", 8080));
        assert!(!is_own_authority(":8080", 8080));
    }

    #[test]
    fn origin_must_be_a_page_of_this_server() {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, "127.0.0.1:9000".parse().unwrap());
        assert!(check_host_and_origin(&h, 9000).is_ok());
        h.insert(header::ORIGIN, "http://127.0.0.1:9000".parse().unwrap());
        assert!(check_host_and_origin(&h, 9000).is_ok());
        for bad in [
            "http://evil.example",
            "http://127.0.0.1:9001",
            "null",
            "https://127.0.0.1:9000",
        ] {
            h.insert(header::ORIGIN, bad.parse().unwrap());
            assert!(check_host_and_origin(&h, 9000).is_err(), "{bad}");
        }
        h.remove(header::ORIGIN);
        h.insert(header::HOST, "attacker.example:9000".parse().unwrap());
        assert!(check_host_and_origin(&h, 9000).is_err());
    }
}
