//! The panel's HTTP/WebSocket server (axum on a one-worker tokio runtime, on its own thread):
//! the subject view and the operator view, each page with its own socket.

use std::net::{SocketAddr, TcpListener};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use tokio::sync::{broadcast, watch};

use super::assets::{COMMON_JS, INDEX_HTML, OPERATOR_HTML, OPERATOR_JS, PANEL_JS};
use super::protocol::{
    parse_client, ClientMsg, Control, PanelConfig, Role, ServerMsg, MAX_CLIENT_MESSAGE,
    OPERATOR_PAGE, OPERATOR_WS, SUBJECT_PAGE, SUBJECT_WS,
};
use crate::clock::Clock;
use crate::LiveError;

/// A flash the page drew: its on frame (reported at once) or its off frame, on the server
/// clock, and when the report arrived.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DrawnReport {
    On {
        id: u64,
        code: u32,
        on_ms: f64,
        received_ms: f64,
    },
    Off {
        id: u64,
        off_ms: f64,
    },
}

/// What the server saw of its clients.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PanelStats {
    /// Subject pages connected now, ever, and gone.
    pub connected: usize,
    pub connections: usize,
    pub disconnects: usize,
    /// Operator views connected now, and ever.
    pub operators: usize,
    pub operator_connections: usize,
    /// Pause, resume and abort requests received from operator views.
    pub controls: usize,
    /// Client messages refused (malformed, oversized, binary), with the last reason.
    pub rejected: usize,
    pub last_rejection: Option<String>,
    /// The page's refresh interval as it measured it, ms, and its user agent.
    pub frame_ms: Option<f64>,
    pub agent: Option<String>,
    /// The page's clock offset to the server's (server − page, ms) and the round trip that
    /// set it (ms).
    pub clock_offset_ms: Option<f64>,
    pub clock_rtt_ms: Option<f64>,
}

#[derive(Debug)]
struct Shared {
    clock: Clock,
    tx: broadcast::Sender<Arc<str>>,
    /// What a page that connects late needs: config, the current trial, decisions, arm trail.
    backlog: Mutex<Backlog>,
    drawn: Mutex<Vec<DrawnReport>>,
    stats: Mutex<PanelStats>,
    /// The operator's requests: hold before the next trial; stop the session.
    pause: AtomicBool,
    abort: AtomicBool,
}

#[derive(Debug, Default)]
struct Backlog {
    config: Option<Arc<str>>,
    trial: Option<Arc<str>>,
    decisions: Vec<Arc<str>>,
    arm: Vec<Arc<str>>,
    diag: Option<Arc<str>>,
    quality: Option<Arc<str>>,
    paused: Option<Arc<str>>,
    pages: Option<Arc<str>>,
    end: Option<Arc<str>>,
}

/// Largest arm trail kept for late pages (thinned by half when full).
const ARM_BACKLOG: usize = 4000;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panicked client task cannot leave these plain records half-written in a harmful way.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The running panel server; stops when dropped.
#[derive(Debug)]
pub struct PanelServer {
    addr: SocketAddr,
    shared: Arc<Shared>,
    shutdown: watch::Sender<bool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl PanelServer {
    /// Binds `addr` (refused unless loopback, or `allow_remote`) and serves the page.
    pub fn start(
        addr: SocketAddr,
        allow_remote: bool,
        config: PanelConfig,
        clock: Clock,
    ) -> Result<Self, LiveError> {
        if !allow_remote && !addr.ip().is_loopback() {
            return Err(LiveError::InvalidParameter {
                name: "serve",
                value: addr.to_string(),
                reason: "not a loopback address: the panel would be reachable from the network \
                         (allow it explicitly to do so)"
                    .into(),
            });
        }
        let listener = TcpListener::bind(addr).map_err(|e| LiveError::Bind {
            addr: addr.to_string(),
            reason: e.to_string(),
        })?;
        let addr = listener.local_addr().map_err(|e| LiveError::Bind {
            addr: addr.to_string(),
            reason: e.to_string(),
        })?;
        listener
            .set_nonblocking(true)
            .map_err(|e| LiveError::Bind {
                addr: addr.to_string(),
                reason: e.to_string(),
            })?;
        let (tx, _) = broadcast::channel(4096);
        let shared = Arc::new(Shared {
            clock,
            tx,
            backlog: Mutex::new(Backlog::default()),
            drawn: Mutex::new(Vec::new()),
            stats: Mutex::new(PanelStats::default()),
            pause: AtomicBool::new(false),
            abort: AtomicBool::new(false),
        });
        let (shutdown, shutdown_rx) = watch::channel(false);
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("oddball-panel")
            .enable_all()
            .build()
            .map_err(|e| LiveError::Bind {
                addr: addr.to_string(),
                reason: format!("cannot start the server runtime: {e}"),
            })?;
        let app = Router::new()
            .route(SUBJECT_PAGE, get(index))
            .route("/panel.js", get(script))
            .route(OPERATOR_PAGE, get(operator))
            .route("/operator.js", get(operator_script))
            .route("/common.js", get(common_script))
            .route("/favicon.ico", get(no_icon))
            .route(SUBJECT_WS, get(subject_ws))
            .route(OPERATOR_WS, get(operator_ws))
            .with_state((shared.clone(), shutdown_rx.clone()));
        let thread = std::thread::Builder::new()
            .name("oddball-panel-server".into())
            .spawn(move || {
                runtime.block_on(async move {
                    let Ok(listener) = tokio::net::TcpListener::from_std(listener) else {
                        return;
                    };
                    let mut stop = shutdown_rx;
                    let _ = axum::serve(listener, app)
                        .with_graceful_shutdown(async move {
                            let _ = stop.wait_for(|s| *s).await;
                        })
                        .await;
                });
                runtime.shutdown_timeout(Duration::from_millis(500));
            })
            .map_err(|e| LiveError::Bind {
                addr: addr.to_string(),
                reason: format!("cannot start the server thread: {e}"),
            })?;
        let server = Self {
            addr,
            shared,
            shutdown,
            thread: Some(thread),
        };
        server.send(&ServerMsg::Config(config));
        Ok(server)
    }

    /// The address actually bound (port 0 picks one).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    pub fn clock(&self) -> Clock {
        self.shared.clock
    }

    /// Sends `msg` to every page (never blocks; a page too slow to keep up skips messages).
    pub fn send(&self, msg: &ServerMsg) {
        let text: Arc<str> = serde_json::to_string(msg)
            .expect("server messages serialise")
            .into();
        {
            let mut b = lock(&self.shared.backlog);
            match msg {
                ServerMsg::Config(_) => b.config = Some(text.clone()),
                ServerMsg::Trial { .. } => b.trial = Some(text.clone()),
                ServerMsg::Decision { .. } => b.decisions.push(text.clone()),
                ServerMsg::Arm { .. } => {
                    if b.arm.len() >= ARM_BACKLOG {
                        let kept: Vec<_> = b.arm.iter().step_by(2).cloned().collect();
                        b.arm = kept;
                    }
                    b.arm.push(text.clone());
                }
                ServerMsg::Diag { .. } => b.diag = Some(text.clone()),
                ServerMsg::Quality { .. } => b.quality = Some(text.clone()),
                ServerMsg::Paused { .. } => b.paused = Some(text.clone()),
                ServerMsg::Pages { .. } => b.pages = Some(text.clone()),
                ServerMsg::End { .. } => b.end = Some(text.clone()),
                ServerMsg::Flash { .. } | ServerMsg::Cancel { .. } | ServerMsg::Pong { .. } => {}
            }
        }
        // No receiver (no page yet) is not an error.
        let _ = self.shared.tx.send(text);
    }

    /// Flash stamps reported since the last call.
    pub fn take_drawn(&self) -> Vec<DrawnReport> {
        std::mem::take(&mut *lock(&self.shared.drawn))
    }

    pub fn stats(&self) -> PanelStats {
        lock(&self.shared.stats).clone()
    }

    /// Whether the operator asked to pause (and has not resumed since).
    pub fn pause_requested(&self) -> bool {
        self.shared.pause.load(Ordering::SeqCst)
    }

    /// Whether the operator asked to abort the session.
    pub fn abort_requested(&self) -> bool {
        self.shared.abort.load(Ordering::SeqCst)
    }

    /// Waits until a page is connected (and has synchronised its clock: its hello arrived);
    /// `false` after `timeout`.
    pub fn wait_for_page(&self, timeout: Duration) -> bool {
        let t0 = Instant::now();
        loop {
            {
                let s = self.stats();
                if s.connected > 0 && s.frame_ms.is_some() {
                    return true;
                }
            }
            if t0.elapsed() >= timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for PanelServer {
    fn drop(&mut self) {
        let _ = self.shutdown.send(true);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

type AppState = (Arc<Shared>, watch::Receiver<bool>);

async fn index() -> Html<&'static str> {
    Html(INDEX_HTML)
}

fn javascript(text: &'static str) -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        text,
    )
        .into_response()
}

async fn script() -> Response {
    javascript(PANEL_JS)
}

async fn operator() -> Html<&'static str> {
    Html(OPERATOR_HTML)
}

async fn operator_script() -> Response {
    javascript(OPERATOR_JS)
}

/// The shared script, headed by the socket paths of [`super::protocol`] (their one home).
static COMMON: LazyLock<String> = LazyLock::new(|| {
    format!(
        "// Generated by the server from oddball_live::panel::protocol.\n\
         const ODDBALL_WS = {{ subject: {SUBJECT_WS:?}, operator: {OPERATOR_WS:?} }};\n{COMMON_JS}"
    )
});

async fn common_script() -> Response {
    javascript(COMMON.as_str())
}

async fn no_icon() -> axum::http::StatusCode {
    axum::http::StatusCode::NO_CONTENT
}

async fn subject_ws(ws: WebSocketUpgrade, State(state): State<AppState>) -> Response {
    upgrade(ws, state, Role::Subject)
}

async fn operator_ws(ws: WebSocketUpgrade, State(state): State<AppState>) -> Response {
    upgrade(ws, state, Role::Operator)
}

fn upgrade(ws: WebSocketUpgrade, state: AppState, role: Role) -> Response {
    // Frames beyond 16 × the protocol's limit close the connection; anything between is
    // refused message by message.
    ws.max_message_size(16 * MAX_CLIENT_MESSAGE)
        .max_frame_size(16 * MAX_CLIENT_MESSAGE)
        .on_upgrade(move |socket| client(socket, state, role))
}

/// Tells every page how many pages are connected.
fn announce_pages(shared: &Shared) {
    let msg = {
        let s = lock(&shared.stats);
        ServerMsg::Pages {
            subject: s.connected,
            operator: s.operators,
        }
    };
    let text: Arc<str> = serde_json::to_string(&msg)
        .expect("server messages serialise")
        .into();
    lock(&shared.backlog).pages = Some(text.clone());
    let _ = shared.tx.send(text);
}

async fn client(mut socket: WebSocket, (shared, mut stop): AppState, role: Role) {
    {
        let mut s = lock(&shared.stats);
        match role {
            Role::Subject => {
                s.connected += 1;
                s.connections += 1;
            }
            Role::Operator => {
                s.operators += 1;
                s.operator_connections += 1;
            }
        }
    }
    announce_pages(&shared);
    let mut rx = shared.tx.subscribe();
    let backlog: Vec<Arc<str>> = {
        let b = lock(&shared.backlog);
        b.config
            .iter()
            .chain(b.decisions.iter())
            .chain(b.arm.iter())
            .chain(b.trial.iter())
            .chain(b.diag.iter())
            .chain(b.quality.iter())
            .chain(b.paused.iter())
            .chain(b.pages.iter())
            .chain(b.end.iter())
            .cloned()
            .collect()
    };
    let mut alive = true;
    for text in backlog {
        if socket
            .send(Message::Text(text.as_ref().into()))
            .await
            .is_err()
        {
            alive = false;
            break;
        }
    }
    while alive {
        alive = serve_one(&mut socket, &shared, &mut rx, &mut stop, role).await;
    }
    {
        let mut s = lock(&shared.stats);
        match role {
            Role::Subject => {
                s.connected -= 1;
                s.disconnects += 1;
            }
            Role::Operator => s.operators -= 1,
        }
    }
    announce_pages(&shared);
}

/// Forwards one broadcast or handles one client message; `false` when the connection is over.
async fn serve_one(
    socket: &mut WebSocket,
    shared: &Shared,
    rx: &mut broadcast::Receiver<Arc<str>>,
    stop: &mut watch::Receiver<bool>,
    role: Role,
) -> bool {
    tokio::select! {
        out = rx.recv() => match out {
            Ok(text) => socket.send(Message::Text(text.as_ref().into())).await.is_ok(),
            Err(broadcast::error::RecvError::Lagged(_)) => true,
            Err(broadcast::error::RecvError::Closed) => false,
        },
        inc = socket.recv() => match inc {
            Some(Ok(Message::Text(text))) => match handle(shared, text.as_str(), role) {
                Some(reply) => {
                    let reply = serde_json::to_string(&reply).expect("server messages serialise");
                    socket.send(Message::Text(reply.into())).await.is_ok()
                }
                None => true,
            },
            Some(Ok(Message::Binary(_))) => {
                reject(shared, "binary messages are not part of the protocol".into());
                true
            }
            Some(Ok(Message::Close(_))) | None | Some(Err(_)) => false,
            Some(Ok(_)) => true,
        },
        _ = stop.changed() => {
            // Whatever was sent before the stop (the session's end) still goes out.
            while let Ok(text) = rx.try_recv() {
                if socket.send(Message::Text(text.as_ref().into())).await.is_err() {
                    return false;
                }
            }
            let _ = socket.send(Message::Close(None)).await;
            false
        }
    }
}

fn reject(shared: &Shared, reason: String) {
    let mut s = lock(&shared.stats);
    s.rejected += 1;
    s.last_rejection = Some(reason);
}

/// Handles one client message from a page of `role`; returns the reply, if any.
fn handle(shared: &Shared, text: &str, role: Role) -> Option<ServerMsg> {
    match parse_client(text) {
        Ok(msg) if !role.accepts(&msg) => {
            reject(shared, format!("a {role:?} page may not send {msg:?}"));
            None
        }
        Ok(ClientMsg::Ping { id, page_ms }) => Some(ServerMsg::Pong {
            id,
            page_ms,
            server_ms: shared.clock.now_ms(),
        }),
        Ok(ClientMsg::On { id, code, on_ms }) => {
            lock(&shared.drawn).push(DrawnReport::On {
                id,
                code,
                on_ms,
                received_ms: shared.clock.now_ms(),
            });
            None
        }
        Ok(ClientMsg::Off { id, off_ms }) => {
            lock(&shared.drawn).push(DrawnReport::Off { id, off_ms });
            None
        }
        Ok(ClientMsg::Hello { frame_ms, agent }) => {
            let mut s = lock(&shared.stats);
            s.frame_ms = Some(frame_ms);
            s.agent = Some(agent);
            None
        }
        Ok(ClientMsg::Clock { offset_ms, rtt_ms }) => {
            let mut s = lock(&shared.stats);
            s.clock_offset_ms = Some(offset_ms);
            s.clock_rtt_ms = Some(rtt_ms);
            None
        }
        Ok(ClientMsg::Control { action }) => {
            lock(&shared.stats).controls += 1;
            match action {
                Control::Pause => shared.pause.store(true, Ordering::SeqCst),
                Control::Resume => shared.pause.store(false, Ordering::SeqCst),
                Control::Abort => shared.abort.store(true, Ordering::SeqCst),
            }
            None
        }
        Err(e) => {
            reject(shared, e.to_string());
            None
        }
    }
}
