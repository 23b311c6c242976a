//! The web server: a fixed set of routes over embedded assets, server-sent events for the
//! image and status, and the render thread that owns the [`Viewer`].
//!
//! Routes (nothing else is served; no part of a request path reaches the file system):
//! - `GET /`: the page (`assets/index.html`, compiled into the binary);
//! - `GET /api/scene`: the scene's nodes, materials and clip, with the current edits;
//! - `GET /api/events`: server-sent events, one `frame` event per new image, whose data is
//!   `{"status": Status, "image": "data:image/png;base64,…"}`;
//! - `POST /api/edit`: one [`Edit`] as JSON; answers `{"id": N}` (the id that
//!   `status.edit` reports once the edit is applied) or 400 with `{"error": …}`.
//!
//! Anything else is 404.

use crate::engine::{Frame, ViewOptions, Viewer};
use crate::scene::{Edit, EditableScene, Limits};
use anyhow::{Context, Result};
use axum::Router;
use axum::extract::{Json, State};
use axum::http::{StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use base64::Engine as _;
use chronolux_core::scene::frame::FrameScene;
use futures_util::Stream;
use serde_json::{Value, json};
use std::convert::Infallible;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::watch;

/// The page, compiled into the binary.
pub const INDEX_HTML: &str = include_str!("../assets/index.html");

/// The address the viewer listens on unless told otherwise: the loopback interface only.
pub const DEFAULT_BIND: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

/// Binds `addr`, with a one-line error (e.g. the port in use).
pub fn bind(addr: SocketAddr) -> Result<TcpListener> {
    TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))
}

/// What the request handlers share.
pub struct App {
    limits: Limits,
    edits: Mutex<mpsc::Sender<(u64, Edit)>>,
    next_edit: AtomicU64,
    frames: watch::Receiver<Option<Arc<String>>>,
    info: Arc<Mutex<Value>>,
}

/// The router over `app`: the routes of the module documentation, 404 for anything else.
pub fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/api/scene", get(scene_info))
        .route("/api/events", get(events))
        .route("/api/edit", post(edit))
        .fallback(not_found)
        .with_state(app)
}

async fn index() -> Html<&'static str> {
    Html(INDEX_HTML)
}

async fn not_found() -> Response {
    (StatusCode::NOT_FOUND, "not found\n").into_response()
}

async fn scene_info(State(app): State<Arc<App>>) -> Response {
    let v = app.info.lock().expect("scene info lock").clone();
    ([(header::CACHE_CONTROL, "no-store")], Json(v)).into_response()
}

async fn edit(State(app): State<Arc<App>>, Json(e): Json<Edit>) -> Response {
    if let Err(msg) = app.limits.check(&e) {
        return (StatusCode::BAD_REQUEST, Json(json!({ "error": msg }))).into_response();
    }
    let id = app.next_edit.fetch_add(1, Ordering::SeqCst);
    let sent = app.edits.lock().expect("edit channel lock").send((id, e));
    if sent.is_err() {
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            Json(json!({ "error": "the render loop has stopped" })),
        )
            .into_response();
    }
    Json(json!({ "id": id })).into_response()
}

async fn events(State(app): State<Arc<App>>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let rx = app.frames.clone();
    // The newest frame at once (if any), then each newer one; a slow client skips frames.
    let stream = futures_util::stream::unfold((rx, false), |(mut rx, wait)| async move {
        if wait && rx.changed().await.is_err() {
            return None;
        }
        loop {
            let current = rx.borrow_and_update().clone();
            if let Some(msg) = current {
                let ev = Event::default().event("frame").data(msg.as_str());
                return Some((Ok(ev), (rx, true)));
            }
            if rx.changed().await.is_err() {
                return None;
            }
        }
    });
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// The SSE data of a frame.
pub fn frame_message(f: &Frame) -> String {
    let png = base64::engine::general_purpose::STANDARD.encode(f.png());
    json!({
        "status": f.status,
        "image": format!("data:image/png;base64,{png}"),
    })
    .to_string()
}

/// A running viewer: the server's address and its threads.
pub struct Running {
    /// The address the server listens on.
    pub addr: SocketAddr,
    server: std::thread::JoinHandle<Result<()>>,
    render: std::thread::JoinHandle<()>,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
}

impl Running {
    /// Blocks until the server stops (it runs until the process is ended).
    pub fn wait(self) -> Result<()> {
        let r = self
            .server
            .join()
            .map_err(|_| anyhow::anyhow!("the web server thread panicked"))?;
        let _ = self.render.join();
        r
    }

    /// Stops the server and the render loop, and waits for both.
    pub fn stop(mut self) -> Result<()> {
        if let Some(s) = self.shutdown.take() {
            let _ = s.send(());
        }
        self.wait()
    }
}

/// Starts serving `scene` on `listener`: the render thread first shoots the pool from
/// `frame` (the page shows "shooting photons" until the first image), then runs the
/// loop of [`Viewer`].
pub fn start(
    listener: TcpListener,
    scene: EditableScene,
    frame: FrameScene,
    options: ViewOptions,
) -> Result<Running> {
    let addr = listener
        .local_addr()
        .context("cannot read the listening address")?;
    listener
        .set_nonblocking(true)
        .context("cannot set up the listening socket")?;
    let (edit_tx, edit_rx) = mpsc::channel();
    let (frame_tx, frame_rx) = watch::channel(None);
    let info = Arc::new(Mutex::new(scene.info()));
    let app = Arc::new(App {
        limits: scene.limits(),
        edits: Mutex::new(edit_tx),
        next_edit: AtomicU64::new(1),
        frames: frame_rx,
        info: info.clone(),
    });
    let render = std::thread::Builder::new()
        .name("chronolux-view-render".into())
        .spawn(move || {
            let viewer = Viewer::from_scene(scene, frame, options);
            render_loop(viewer, edit_rx, frame_tx, info);
        })
        .context("cannot start the render thread")?;
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let server = std::thread::Builder::new()
        .name("chronolux-view-http".into())
        .spawn(move || -> Result<()> {
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
                .context("cannot start the async runtime")?;
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::from_std(listener)
                    .context("cannot use the listening socket")?;
                axum::serve(listener, router(app))
                    .with_graceful_shutdown(async {
                        let _ = stop_rx.await;
                    })
                    .await
                    .context("the web server failed")
            })
        })
        .context("cannot start the web server thread")?;
    Ok(Running {
        addr,
        server,
        render,
        shutdown: Some(stop_tx),
    })
}

/// The render thread: applies pending edits (all of them, then one rebuild), else does
/// one step of work, else waits for an edit. Publishes every image after an edit and
/// every slice while groups are queued; while refining, the images at 1, 2, 4, … samples
/// per pixel and the last one (so idle refinement does not flood the page). Ends when the
/// server has gone (the edit channel or every frame receiver closed).
fn render_loop(
    mut viewer: Viewer,
    rx: mpsc::Receiver<(u64, Edit)>,
    tx: watch::Sender<Option<Arc<String>>>,
    info: Arc<Mutex<Value>>,
) {
    let publish = |f: &Frame| {
        tx.send_replace(Some(Arc::new(frame_message(f))));
    };
    publish(&viewer.frame_after_pass());
    let mut pending: Vec<(u64, Edit)> = Vec::new();
    loop {
        loop {
            match rx.try_recv() {
                Ok(e) => pending.push(e),
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => return,
            }
        }
        if tx.is_closed() {
            return;
        }
        if !pending.is_empty() {
            let (f, errors) = viewer.edit(&pending);
            for e in errors {
                log::warn!("edit refused: {e}");
            }
            pending.clear();
            *info.lock().expect("scene info lock") = viewer.scene().info();
            publish(&f);
            continue;
        }
        match viewer.step() {
            Some(f) => {
                let s = &f.status;
                if s.queued > 0 || s.spp.is_power_of_two() || viewer.idle() {
                    publish(&f);
                }
            }
            None => match rx.recv_timeout(Duration::from_millis(200)) {
                Ok(e) => pending.push(e),
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => return,
            },
        }
    }
}
