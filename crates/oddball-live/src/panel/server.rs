//! The panel's HTTP/WebSocket server (axum on a one-worker tokio runtime, on its own thread):
//! the subject view and the operator view, each page with its own socket.
//!
//! The panel belongs to its session: each view has its own secret key, in the addresses the
//! session prints ([`PanelServer::subject_url`], [`PanelServer::operator_url`]); a page or a
//! socket without its view's key gets nothing. Every request's `Host` must name the server
//! (a loopback server answers only to loopback names, against DNS rebinding) and a socket's
//! `Origin`, when a browser sends one, must be the panel itself (against cross-site
//! WebSockets). One subject page at a time owns the flashes' stamps: a second one is refused,
//! counted and announced to the operator view. A pause left by an operator view that closed
//! ends once no operator has been connected for [`ORPHANED_PAUSE_S`].
//!
//! What the subject page says of itself (hidden or visible, its frames) is hostile input like
//! any other: only its one keyed socket may say it, each message bounded and checked
//! ([`super::protocol::parse_client`]), and the server keeps counters, not a queue, so however
//! fast a page reports it costs nothing more ([`PanelServer::subject_view`]). The signal, the
//! averages and the alarms go to operator views only ([`PanelServer::send_operator`]).

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::{header, HeaderMap, StatusCode, Uri};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use tokio::sync::{broadcast, watch};

use super::assets::{COMMON_JS, INDEX_HTML, OPERATOR_HTML, OPERATOR_JS, PANEL_JS};
use super::monitor::SubjectView;
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
        /// The page had said it was hidden: nobody saw the flash, whatever it stamps.
        hidden: bool,
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
    /// Requests refused at the door (no or a wrong key, a foreign `Host` or `Origin`), with the
    /// last reason.
    pub refused: usize,
    pub last_refusal: Option<String>,
    /// Subject pages refused because one was already open.
    pub refused_subjects: usize,
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
    /// Who may come in.
    access: Access,
    /// Whether a subject page owns the panel now.
    subject_taken: AtomicBool,
    /// Since when no operator view has been connected (`None`: one is).
    operatorless_since: Mutex<Option<Instant>>,
    /// Messages for operator views only, and what a late one needs of them.
    op_tx: broadcast::Sender<Arc<str>>,
    op_backlog: Mutex<OperatorBacklog>,
    /// What the subject page said of itself.
    page: Mutex<PageState>,
}

/// What the subject page reported of itself: counters, never a queue.
#[derive(Debug)]
struct PageState {
    hidden: bool,
    /// Its last frame report, or when it connected.
    frames_at: Instant,
    last_max_gap_ms: f64,
    /// Since the session last looked.
    dropped: u64,
    dropped_gap_ms: f64,
    multi_lit: u64,
}

impl PageState {
    fn fresh() -> Self {
        Self {
            hidden: false,
            frames_at: Instant::now(),
            last_max_gap_ms: 0.0,
            dropped: 0,
            dropped_gap_ms: 0.0,
            multi_lit: 0,
        }
    }
}

/// What a late operator view needs of the operator-only messages.
#[derive(Debug, Default)]
struct OperatorBacklog {
    scope: Option<Arc<str>>,
    alarms: std::collections::VecDeque<Arc<str>>,
    faults: Option<Arc<str>>,
    average: Option<Arc<str>>,
}

/// Alarm messages kept for operator views that connect late.
const ALARM_BACKLOG: usize = 200;

/// A pause whose operator views have all been gone this long ends by itself, s.
pub const ORPHANED_PAUSE_S: f64 = 120.0;

/// The keys of the two views and the `Host` names the server answers to.
#[derive(Debug)]
struct Access {
    subject_key: String,
    operator_key: String,
    /// `None`: any host (a server that allows remote pages; the keys still hold).
    hosts: Option<Vec<String>>,
}

impl Access {
    fn new(addr: SocketAddr, allow_remote: bool) -> Self {
        let port = addr.port();
        let hosts = (!allow_remote || addr.ip().is_loopback()).then(|| {
            let mut h = vec![
                addr.to_string(),
                format!("localhost:{port}"),
                format!("127.0.0.1:{port}"),
                format!("[::1]:{port}"),
            ];
            h.dedup();
            h
        });
        Self {
            subject_key: secret(),
            operator_key: secret(),
            hosts,
        }
    }

    /// Why a request for `role`'s view (`None`: a script, which needs no key) is refused, if it
    /// is: its `Host`, its `Origin` (sockets only: `socket`), its key.
    fn refusal(
        &self,
        headers: &HeaderMap,
        uri: &Uri,
        role: Option<Role>,
        socket: bool,
    ) -> Option<String> {
        let host = headers
            .get(header::HOST)
            .and_then(|h| h.to_str().ok())
            .unwrap_or("");
        if let Some(hosts) = &self.hosts {
            if !hosts.iter().any(|h| h.eq_ignore_ascii_case(host)) {
                return Some(format!("Host {host:?} is not this panel"));
            }
        }
        if socket {
            if let Some(origin) = headers.get(header::ORIGIN) {
                let origin = origin.to_str().unwrap_or("");
                if !origin.eq_ignore_ascii_case(&format!("http://{host}")) {
                    return Some(format!("a socket from Origin {origin:?}, not this panel"));
                }
            }
        }
        let want = match role? {
            Role::Subject => &self.subject_key,
            Role::Operator => &self.operator_key,
        };
        let given = uri
            .query()
            .unwrap_or("")
            .split('&')
            .find_map(|kv| kv.strip_prefix("key="))
            .unwrap_or("");
        (!constant_time_eq(given.as_bytes(), want.as_bytes()))
            .then(|| format!("no or a wrong key for the {role:?} view"))
    }
}

/// 128 random bits from the operating system, as hex.
fn secret() -> String {
    use rand::RngCore;
    let mut bytes = [0u8; 16];
    rand::rngs::OsRng.fill_bytes(&mut bytes);
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Equality that takes as long whatever the first differing byte.
fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
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
        let listener = crate::listen::bind(addr, allow_remote, "serve")?;
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
        let (op_tx, _) = broadcast::channel(1024);
        let shared = Arc::new(Shared {
            clock,
            tx,
            backlog: Mutex::new(Backlog::default()),
            drawn: Mutex::new(Vec::new()),
            stats: Mutex::new(PanelStats::default()),
            pause: AtomicBool::new(false),
            abort: AtomicBool::new(false),
            access: Access::new(addr, allow_remote),
            subject_taken: AtomicBool::new(false),
            operatorless_since: Mutex::new(Some(Instant::now())),
            op_tx,
            op_backlog: Mutex::new(OperatorBacklog::default()),
            page: Mutex::new(PageState::fresh()),
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

    /// The subject view's address, with its key: the page the person watches.
    pub fn subject_url(&self) -> String {
        format!(
            "http://{}{SUBJECT_PAGE}?key={}",
            self.addr, self.shared.access.subject_key
        )
    }

    /// The operator view's address, with its key.
    pub fn operator_url(&self) -> String {
        format!(
            "http://{}{OPERATOR_PAGE}?key={}",
            self.addr, self.shared.access.operator_key
        )
    }

    pub fn clock(&self) -> Clock {
        self.shared.clock
    }

    /// Sends `msg` to every page (never blocks; a page too slow to keep up skips messages).
    /// What only operators may see (the signal, the averages, the alarms) goes to operator
    /// views only ([`PanelServer::send_operator`]).
    pub fn send(&self, msg: &ServerMsg) {
        if msg.operator_only() {
            return self.send_operator(msg);
        }
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
                ServerMsg::Alarm(_)
                | ServerMsg::Faults { .. }
                | ServerMsg::Scope { .. }
                | ServerMsg::Signal { .. }
                | ServerMsg::Average { .. } => unreachable!("sent to operator views only"),
            }
        }
        // No receiver (no page yet) is not an error.
        let _ = self.shared.tx.send(text);
    }

    /// Sends `msg` to operator views only (the signal, the averages, the alarms: the subject
    /// page never gets them). Never blocks.
    pub fn send_operator(&self, msg: &ServerMsg) {
        let text: Arc<str> = serde_json::to_string(msg)
            .expect("server messages serialise")
            .into();
        {
            let mut b = lock(&self.shared.op_backlog);
            match msg {
                ServerMsg::Scope { .. } => b.scope = Some(text.clone()),
                ServerMsg::Alarm(_) => {
                    if b.alarms.len() >= ALARM_BACKLOG {
                        b.alarms.pop_front();
                    }
                    b.alarms.push_back(text.clone());
                }
                ServerMsg::Faults { .. } => b.faults = Some(text.clone()),
                ServerMsg::Average { .. } => b.average = Some(text.clone()),
                _ => {}
            }
        }
        let _ = self.shared.op_tx.send(text);
    }

    /// The subject view now, and what it reported since the last call (whose counters this
    /// resets): the one reader is the session.
    pub fn subject_view(&self) -> SubjectView {
        let connected = lock(&self.shared.stats).connected > 0;
        let mut p = lock(&self.shared.page);
        let v = SubjectView {
            connected,
            hidden: p.hidden,
            since_frames_ms: p.frames_at.elapsed().as_secs_f64() * 1e3,
            last_max_gap_ms: p.last_max_gap_ms,
            dropped: p.dropped,
            dropped_gap_ms: p.dropped_gap_ms,
            multi_lit: p.multi_lit,
        };
        p.dropped = 0;
        p.dropped_gap_ms = 0.0;
        p.multi_lit = 0;
        v
    }

    /// Flash stamps reported since the last call.
    pub fn take_drawn(&self) -> Vec<DrawnReport> {
        std::mem::take(&mut *lock(&self.shared.drawn))
    }

    pub fn stats(&self) -> PanelStats {
        lock(&self.shared.stats).clone()
    }

    /// Whether the operator asked to pause (and has not resumed since). A pause whose operator
    /// views have all been gone for [`ORPHANED_PAUSE_S`] ends here.
    pub fn pause_requested(&self) -> bool {
        if !self.shared.pause.load(Ordering::SeqCst) {
            return false;
        }
        let orphaned = lock(&self.shared.operatorless_since)
            .is_some_and(|t| t.elapsed().as_secs_f64() >= ORPHANED_PAUSE_S);
        if orphaned {
            self.shared.pause.store(false, Ordering::SeqCst);
            return false;
        }
        true
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

/// A refused request, counted: 403 with a word of why (no session data).
fn refuse(shared: &Shared, why: String) -> Response {
    {
        let mut s = lock(&shared.stats);
        s.refused += 1;
        s.last_refusal = Some(why.clone());
    }
    (
        StatusCode::FORBIDDEN,
        format!("refused: {why}; open the address the session printed\n"),
    )
        .into_response()
}

/// `body` if the request may have it (`role`: the view whose key it needs; `None`: a script).
fn admitted(
    (shared, _): &AppState,
    headers: &HeaderMap,
    uri: &Uri,
    role: Option<Role>,
    body: impl FnOnce() -> Response,
) -> Response {
    match shared.access.refusal(headers, uri, role, false) {
        Some(why) => refuse(shared, why),
        None => body(),
    }
}

async fn index(State(state): State<AppState>, headers: HeaderMap, uri: Uri) -> Response {
    admitted(&state, &headers, &uri, Some(Role::Subject), || {
        Html(INDEX_HTML).into_response()
    })
}

fn javascript(text: &'static str) -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        text,
    )
        .into_response()
}

async fn script(State(state): State<AppState>, headers: HeaderMap, uri: Uri) -> Response {
    admitted(&state, &headers, &uri, None, || javascript(PANEL_JS))
}

async fn operator(State(state): State<AppState>, headers: HeaderMap, uri: Uri) -> Response {
    admitted(&state, &headers, &uri, Some(Role::Operator), || {
        Html(OPERATOR_HTML).into_response()
    })
}

async fn operator_script(State(state): State<AppState>, headers: HeaderMap, uri: Uri) -> Response {
    admitted(&state, &headers, &uri, None, || javascript(OPERATOR_JS))
}

/// The shared script, headed by the socket paths of [`super::protocol`] (their one home).
static COMMON: LazyLock<String> = LazyLock::new(|| {
    format!(
        "// Generated by the server from oddball_live::panel::protocol.\n\
         const ODDBALL_WS = {{ subject: {SUBJECT_WS:?}, operator: {OPERATOR_WS:?} }};\n{COMMON_JS}"
    )
});

async fn common_script(State(state): State<AppState>, headers: HeaderMap, uri: Uri) -> Response {
    admitted(&state, &headers, &uri, None, || javascript(COMMON.as_str()))
}

async fn no_icon() -> StatusCode {
    StatusCode::NO_CONTENT
}

async fn subject_ws(
    ws: WebSocketUpgrade,
    State(state): State<AppState>,
    headers: HeaderMap,
    uri: Uri,
) -> Response {
    upgrade(ws, state, Role::Subject, &headers, &uri)
}

async fn operator_ws(
    ws: WebSocketUpgrade,
    State(state): State<AppState>,
    headers: HeaderMap,
    uri: Uri,
) -> Response {
    upgrade(ws, state, Role::Operator, &headers, &uri)
}

fn upgrade(
    ws: WebSocketUpgrade,
    state: AppState,
    role: Role,
    headers: &HeaderMap,
    uri: &Uri,
) -> Response {
    if let Some(why) = state.0.access.refusal(headers, uri, Some(role), true) {
        return refuse(&state.0, why);
    }
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
            refused_subjects: s.refused_subjects,
        }
    };
    let text: Arc<str> = serde_json::to_string(&msg)
        .expect("server messages serialise")
        .into();
    lock(&shared.backlog).pages = Some(text.clone());
    let _ = shared.tx.send(text);
}

async fn client(mut socket: WebSocket, (shared, mut stop): AppState, role: Role) {
    // One subject page owns the flashes' stamps: a second one is closed at once, unheard.
    if role == Role::Subject
        && shared
            .subject_taken
            .compare_exchange(false, true, Ordering::SeqCst, Ordering::SeqCst)
            .is_err()
    {
        lock(&shared.stats).refused_subjects += 1;
        announce_pages(&shared);
        let _ = socket
            .send(Message::Close(Some(CloseFrame {
                code: 4409,
                reason: "another subject view has this panel".into(),
            })))
            .await;
        // Its messages are read and dropped, unheard, until it answers the close (a second at
        // most): a socket closed with unread data resets the connection, and the page would
        // read 1006 instead of why it was refused.
        let _ = tokio::time::timeout(Duration::from_secs(1), async {
            while let Some(Ok(m)) = socket.recv().await {
                if matches!(m, Message::Close(_)) {
                    break;
                }
            }
        })
        .await;
        return;
    }
    {
        let mut s = lock(&shared.stats);
        match role {
            Role::Subject => {
                s.connected += 1;
                s.connections += 1;
                *lock(&shared.page) = PageState::fresh();
            }
            Role::Operator => {
                s.operators += 1;
                s.operator_connections += 1;
                *lock(&shared.operatorless_since) = None;
            }
        }
    }
    announce_pages(&shared);
    let mut rx = shared.tx.subscribe();
    let mut op_rx = (role == Role::Operator).then(|| shared.op_tx.subscribe());
    let mut backlog: Vec<Arc<str>> = {
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
    if role == Role::Operator {
        let b = lock(&shared.op_backlog);
        backlog.extend(
            b.scope
                .iter()
                .chain(b.alarms.iter())
                .chain(b.faults.iter())
                .chain(b.average.iter())
                .cloned(),
        );
    }
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
        alive = serve_one(
            &mut socket,
            &shared,
            &mut rx,
            op_rx.as_mut(),
            &mut stop,
            role,
        )
        .await;
    }
    {
        let mut s = lock(&shared.stats);
        match role {
            Role::Subject => {
                s.connected -= 1;
                s.disconnects += 1;
                *lock(&shared.page) = PageState::fresh();
                shared.subject_taken.store(false, Ordering::SeqCst);
            }
            Role::Operator => {
                s.operators -= 1;
                if s.operators == 0 {
                    *lock(&shared.operatorless_since) = Some(Instant::now());
                }
            }
        }
    }
    announce_pages(&shared);
}

/// Forwards one broadcast or handles one client message; `false` when the connection is over.
async fn serve_one(
    socket: &mut WebSocket,
    shared: &Shared,
    rx: &mut broadcast::Receiver<Arc<str>>,
    op_rx: Option<&mut broadcast::Receiver<Arc<str>>>,
    stop: &mut watch::Receiver<bool>,
    role: Role,
) -> bool {
    let operator_only = async {
        match op_rx {
            Some(r) => r.recv().await,
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        out = rx.recv() => match out {
            Ok(text) => socket.send(Message::Text(text.as_ref().into())).await.is_ok(),
            Err(broadcast::error::RecvError::Lagged(_)) => true,
            Err(broadcast::error::RecvError::Closed) => false,
        },
        out = operator_only => match out {
            Ok(text) => socket.send(Message::Text(text.as_ref().into())).await.is_ok(),
            // A view too slow for the signal skips some of it.
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
            let hidden = lock(&shared.page).hidden;
            lock(&shared.drawn).push(DrawnReport::On {
                id,
                code,
                on_ms,
                received_ms: shared.clock.now_ms(),
                hidden,
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
        Ok(ClientMsg::Frames {
            max_gap_ms,
            dropped,
            multi_lit,
            ..
        }) => {
            let mut p = lock(&shared.page);
            p.frames_at = Instant::now();
            p.last_max_gap_ms = max_gap_ms;
            p.dropped = p.dropped.saturating_add(u64::from(dropped));
            if dropped > 0 {
                p.dropped_gap_ms = p.dropped_gap_ms.max(max_gap_ms);
            }
            p.multi_lit = p.multi_lit.saturating_add(u64::from(multi_lit));
            None
        }
        Ok(ClientMsg::Visibility { hidden }) => {
            let mut p = lock(&shared.page);
            p.hidden = hidden;
            // Back in view: its frames are judged afresh from now.
            if !hidden {
                p.frames_at = Instant::now();
                p.last_max_gap_ms = 0.0;
            }
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
