//! The panel server over plain HTTP: the page and its script are served from the binary, the
//! server binds loopback unless told otherwise, and it stops when dropped. It belongs to its
//! session: without a view's key, from a foreign `Host` or a foreign `Origin` nothing is served,
//! and a second subject socket is closed unheard.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use oddball_live::clock::Clock;
use oddball_live::panel::{PanelConfig, PanelServer};
use oddball_live::LiveError;

fn config() -> PanelConfig {
    PanelConfig {
        bulbs: vec![(1, "up".into()), (2, "right".into())],
        flash_ms: 100.0,
        countdown_s: 5.0,
        board_m: [0.0, 1.0, 0.0, 1.0],
        base_m: [0.5, -0.2],
        pose_m: [[0.3, 0.2], [0.5, 0.5]],
        targets_m: vec![],
        plan_m: vec![],
        title: "test".into(),
        undrawn_after_ms: 200.0,
        frames_every_ms: 250.0,
    }
}

/// `GET path` with `Host: host` and extra header lines.
fn get_as(addr: std::net::SocketAddr, host: &str, path: &str, extra: &str) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\n{extra}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    out
}

/// `GET path` as a browser that opened the panel's address would.
fn get(addr: std::net::SocketAddr, path: &str) -> String {
    get_as(addr, &addr.to_string(), path, "")
}

/// The path and query of a panel address (`http://ADDR/operator?key=…` → `/operator?key=…`).
fn path_of(url: &str) -> String {
    let rest = url.strip_prefix("http://").unwrap();
    rest[rest.find('/').unwrap()..].to_string()
}

#[test]
fn serves_the_embedded_page_and_script() {
    let server = PanelServer::start(
        "127.0.0.1:0".parse().unwrap(),
        false,
        config(),
        Clock::new(),
    )
    .unwrap();
    let addr = server.local_addr();
    let page = get(addr, &path_of(&server.subject_url()));
    assert!(page.starts_with("HTTP/1.1 200"), "{page}");
    assert!(page.contains("<script src=\"/panel.js\">"));
    let js = get(addr, "/panel.js");
    assert!(js.starts_with("HTTP/1.1 200"));
    assert!(js
        .to_ascii_lowercase()
        .contains("content-type: text/javascript"));
    assert!(js.contains("requestAnimationFrame"));
    // The operator view and the shared script, which carries the socket paths of the protocol.
    let operator = get(addr, &path_of(&server.operator_url()));
    assert!(operator.starts_with("HTTP/1.1 200"), "{operator}");
    assert!(operator.contains("<script src=\"/operator.js\">"));
    assert!(operator.contains("id=\"pause\"") && operator.contains("id=\"abort\""));
    assert!(get(addr, "/operator.js").contains("\"control\""));
    let common = get(addr, "/common.js");
    assert!(common.starts_with("HTTP/1.1 200"));
    assert!(
        common.contains(r#"const ODDBALL_WS = { subject: "/ws", operator: "/ws/operator" };"#),
        "{common}"
    );
    assert!(!get(addr, "/ws/operator").starts_with("HTTP/1.1 200"));
    assert!(get(addr, "/nothing").starts_with("HTTP/1.1 404"));
    // A plain GET on the WebSocket route is refused, not served.
    assert!(!get(addr, "/ws").starts_with("HTTP/1.1 200"));
    assert_eq!(server.stats().connections, 0);
    let t0 = Instant::now();
    drop(server);
    assert!(t0.elapsed() < Duration::from_secs(2), "stops promptly");
    assert!(
        TcpStream::connect(addr).is_err(),
        "nothing listens after drop"
    );
}

#[test]
fn binds_loopback_unless_told_otherwise() {
    let err = PanelServer::start("0.0.0.0:0".parse().unwrap(), false, config(), Clock::new())
        .unwrap_err();
    assert!(
        matches!(err, LiveError::InvalidParameter { name: "serve", .. }),
        "{err}"
    );
    assert!(err.to_string().contains("loopback"));
    // Told otherwise, it binds.
    let s = PanelServer::start("0.0.0.0:0".parse().unwrap(), true, config(), Clock::new()).unwrap();
    assert!(s.local_addr().ip().is_unspecified());
    // A port already taken is a clear error naming the address.
    let a = PanelServer::start(
        "127.0.0.1:0".parse().unwrap(),
        false,
        config(),
        Clock::new(),
    )
    .unwrap();
    let err = PanelServer::start(a.local_addr(), false, config(), Clock::new()).unwrap_err();
    assert!(
        err.to_string().contains(&a.local_addr().to_string()),
        "{err}"
    );
}

fn loopback_server() -> PanelServer {
    PanelServer::start(
        "127.0.0.1:0".parse().unwrap(),
        false,
        config(),
        Clock::new(),
    )
    .unwrap()
}

/// A WebSocket handshake for `path` with these headers; the HTTP status the server answered.
fn upgrade_status(
    addr: std::net::SocketAddr,
    host: &str,
    path: &str,
    origin: Option<&str>,
) -> String {
    let origin = origin
        .map(|o| format!("Origin: {o}\r\n"))
        .unwrap_or_default();
    let extra = format!(
        "Upgrade: websocket\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{origin}"
    );
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: Upgrade\r\n{extra}\r\n"
    )
    .unwrap();
    let mut buf = [0u8; 512];
    let n = s.read(&mut buf).unwrap();
    String::from_utf8_lossy(&buf[..n])
        .lines()
        .next()
        .unwrap_or("")
        .to_string()
}

/// The probe's attacks on the door: no key, another view's key, a wrong key, a foreign Host
/// (DNS rebinding), a foreign Origin (a cross-site WebSocket). None gets a page or a socket;
/// each is counted. The scripts (no session data) are served without a key, to the panel's own
/// Host only.
#[test]
fn only_the_sessions_pages_get_in() {
    let server = loopback_server();
    let addr = server.local_addr();
    let subject = path_of(&server.subject_url());
    let operator = path_of(&server.operator_url());
    let key = |p: &str| p.split("key=").nth(1).unwrap().to_string();
    assert_ne!(key(&subject), key(&operator), "each view has its own key");
    assert_eq!(key(&subject).len(), 32);
    let forbidden = |r: String| assert!(r.starts_with("HTTP/1.1 403"), "{r}");
    forbidden(get(addr, "/"));
    forbidden(get(addr, "/operator"));
    forbidden(get(addr, &format!("/operator?key={}", key(&subject))));
    forbidden(get(addr, &format!("/?key={}", key(&operator))));
    forbidden(get(addr, "/?key=00000000000000000000000000000000"));
    // The right key from a foreign Host: a rebound DNS name.
    forbidden(get_as(
        addr,
        &format!("evil.example:{}", addr.port()),
        &subject,
        "",
    ));
    forbidden(get_as(addr, "evil.example", "/panel.js", ""));
    // Loopback names of this port are the panel's own.
    let ok = get_as(addr, &format!("localhost:{}", addr.port()), &subject, "");
    assert!(ok.starts_with("HTTP/1.1 200"), "{ok}");
    assert!(get(addr, "/panel.js").starts_with("HTTP/1.1 200"));

    let host = addr.to_string();
    let ws_subject = format!("/ws?key={}", key(&subject));
    let ws_operator = format!("/ws/operator?key={}", key(&operator));
    let status = |path: &str, origin: Option<&str>| upgrade_status(addr, &host, path, origin);
    assert!(status("/ws/operator", None).contains("403"));
    assert!(status(&format!("/ws/operator?key={}", key(&subject)), None).contains("403"));
    assert!(status(&ws_operator, Some("http://evil.example")).contains("403"));
    assert!(status(&ws_subject, Some("null")).contains("403"));
    assert!(upgrade_status(addr, "evil.example", &ws_subject, None).contains("403"));
    // The real page's socket: same Origin, its key.
    assert!(status(&ws_operator, Some(&format!("http://{host}"))).contains("101"));
    let stats = server.stats();
    assert_eq!(
        stats.refused, 12,
        "7 pages and 5 sockets refused: {stats:?}"
    );
    assert!(stats.last_refusal.is_some());
}

/// A second subject socket, even with the key, is closed unheard: its stamps never reach the
/// session, the first page keeps the panel, and the operator view is told.
#[test]
fn a_second_subject_page_is_refused_and_announced() {
    let server = loopback_server();
    let addr = server.local_addr();
    let url = format!(
        "ws://{addr}{}",
        path_of(&server.subject_url()).replacen('/', "/ws", 1)
    );
    let connect = || {
        let (ws, _) = tungstenite::client::connect(url.as_str()).expect("handshake");
        ws
    };
    let mut first = connect();
    let t0 = Instant::now();
    while server.stats().connected == 0 {
        assert!(t0.elapsed() < Duration::from_secs(5));
        std::thread::sleep(Duration::from_millis(10));
    }
    let mut second = connect();
    let _ = second.send(tungstenite::Message::text(
        r#"{"t":"on","id":1,"code":1,"on_ms":0}"#,
    ));
    // The second socket is closed by the server with its reason.
    let closed = loop {
        match second.read() {
            Ok(tungstenite::Message::Close(frame)) => break frame,
            Ok(_) => continue,
            Err(e) => panic!("no close frame: {e}"),
        }
    };
    assert_eq!(
        closed.map(|f| f.reason.to_string()).as_deref(),
        Some("another subject view has this panel")
    );
    // The first still stamps; the second's stamp was never heard.
    first
        .send(tungstenite::Message::text(
            r#"{"t":"on","id":2,"code":2,"on_ms":5}"#,
        ))
        .unwrap();
    let t0 = Instant::now();
    let mut drawn = Vec::new();
    while drawn.is_empty() && t0.elapsed() < Duration::from_secs(5) {
        drawn = server.take_drawn();
        std::thread::sleep(Duration::from_millis(10));
    }
    let ids: Vec<u64> = drawn
        .iter()
        .map(|d| match d {
            oddball_live::panel::DrawnReport::On { id, .. } => *id,
            oddball_live::panel::DrawnReport::Off { id, .. } => *id,
        })
        .collect();
    assert_eq!(ids, [2]);
    let stats = server.stats();
    assert_eq!(
        (stats.connected, stats.refused_subjects),
        (1, 1),
        "{stats:?}"
    );
    // Once the first page has gone, a new one may take the panel (a reload).
    let _ = first.close(None);
    let t0 = Instant::now();
    while server.stats().connected > 0 {
        assert!(t0.elapsed() < Duration::from_secs(5));
        std::thread::sleep(Duration::from_millis(10));
    }
    let _third = connect();
    let t0 = Instant::now();
    while server.stats().connected == 0 {
        assert!(t0.elapsed() < Duration::from_secs(5), "a reload is let in");
        std::thread::sleep(Duration::from_millis(10));
    }
}
