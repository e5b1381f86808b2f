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

/// A socket of `server`'s `view` ("" for the subject's, "/operator"), with its key.
fn socket(
    server: &PanelServer,
    operator: bool,
) -> tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>> {
    let (page, ws) = if operator {
        (server.operator_url(), "/ws/operator")
    } else {
        (server.subject_url(), "/ws")
    };
    let key = page.split("key=").nth(1).unwrap();
    let url = format!("ws://{}{ws}?key={key}", server.local_addr());
    let (mut s, _) = tungstenite::client::connect(url.as_str()).expect("handshake");
    if let tungstenite::stream::MaybeTlsStream::Plain(t) = s.get_mut() {
        t.set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
    }
    s
}

/// Waits (5 s at most) until `done` holds of the server.
fn until(server: &PanelServer, what: &str, done: impl Fn(&PanelServer) -> bool) {
    let t0 = Instant::now();
    while !done(server) {
        assert!(t0.elapsed() < Duration::from_secs(5), "never: {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Issue #30: what the subject page says of itself (hidden, its frames) is hostile input like
/// its stamps. Oversized, malformed and out-of-range reports are refused and change nothing; an
/// operator view cannot say the subject page is hidden, nor can a second subject socket; a
/// flood of reports is kept as counters (nothing queues up); a stamp sent while the page said
/// it was hidden is marked so (the session voids it).
#[test]
fn presentation_reports_are_checked_and_only_the_subject_page_makes_them() {
    use tungstenite::Message;
    let server = loopback_server();
    let mut subject = socket(&server, false);
    until(&server, "the subject page connected", |s| {
        s.stats().connected == 1
    });
    let view = server.subject_view();
    assert!(view.connected && !view.hidden, "{view:?}");

    // Refused, and without effect: too large, not JSON, out of range, fields wrong, binary.
    let big = format!(
        r#"{{"t":"visibility","hidden":true,"pad":"{}"}}"#,
        "x".repeat(2000)
    );
    let bad = [
        big.as_str(),
        "{\"t\":\"visibility\",\"hidden\":true",
        r#"{"t":"visibility","hidden":1}"#,
        r#"{"t":"frames","frames":10,"max_gap_ms":-1,"dropped":1,"multi_lit":0}"#,
        r#"{"t":"frames","frames":10,"max_gap_ms":1e300,"dropped":1,"multi_lit":0}"#,
        r#"{"t":"frames","frames":10,"max_gap_ms":20,"dropped":99,"multi_lit":0}"#,
        r#"{"t":"frames","frames":10,"max_gap_ms":20,"dropped":1,"multi_lit":99}"#,
        r#"{"t":"frames","frames":10,"max_gap_ms":20,"dropped":1}"#,
    ];
    for text in bad {
        subject.send(Message::text(text)).unwrap();
    }
    subject.send(Message::binary(vec![0u8; 64])).unwrap();
    until(&server, "every bad report refused", |s| {
        s.stats().rejected == bad.len() + 1
    });
    let view = server.subject_view();
    assert!(
        !view.hidden && view.dropped == 0 && view.multi_lit == 0,
        "{view:?}"
    );

    // The operator view may not speak for the subject page.
    let mut operator = socket(&server, true);
    until(&server, "the operator view connected", |s| {
        s.stats().operators == 1
    });
    operator
        .send(Message::text(r#"{"t":"visibility","hidden":true}"#))
        .unwrap();
    operator
        .send(Message::text(
            r#"{"t":"frames","frames":10,"max_gap_ms":900,"dropped":5,"multi_lit":5}"#,
        ))
        .unwrap();
    until(&server, "the operator's reports refused", |s| {
        s.stats().rejected == bad.len() + 3
    });
    assert!(server
        .stats()
        .last_rejection
        .unwrap()
        .contains("Operator page may not send"));
    // Nor may a second subject socket: it is closed unheard.
    let mut second = socket(&server, false);
    let _ = second.send(Message::text(r#"{"t":"visibility","hidden":true}"#));
    until(&server, "the second subject socket refused", |s| {
        s.stats().refused_subjects == 1
    });
    std::thread::sleep(Duration::from_millis(100));
    let view = server.subject_view();
    assert!(
        !view.hidden && view.dropped == 0 && view.last_max_gap_ms == 0.0,
        "{view:?}"
    );

    // The page's own reports count; a flood is counters, not a queue.
    for _ in 0..2000 {
        subject
            .send(Message::text(
                r#"{"t":"frames","frames":15,"max_gap_ms":120,"dropped":1,"multi_lit":1}"#,
            ))
            .unwrap();
    }
    subject
        .send(Message::text(r#"{"t":"visibility","hidden":true}"#))
        .unwrap();
    subject
        .send(Message::text(r#"{"t":"on","id":7,"code":2,"on_ms":5}"#))
        .unwrap();
    // Messages of one socket are handled in order: once the stamp is in, so is the rest.
    let t0 = Instant::now();
    let mut drawn = Vec::new();
    while drawn.is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the stamp never came"
        );
        drawn = server.take_drawn();
        std::thread::sleep(Duration::from_millis(10));
    }
    let view = server.subject_view();
    assert!(view.hidden, "{view:?}");
    assert_eq!(
        (view.dropped, view.multi_lit, view.dropped_gap_ms),
        (2000, 2000, 120.0)
    );
    // Read once: the next look starts from zero.
    assert_eq!(server.subject_view().dropped, 0);
    // Nobody saw a flash the page stamped while it said it was hidden.
    assert!(
        matches!(
            drawn[..],
            [oddball_live::panel::DrawnReport::On {
                id: 7,
                hidden: true,
                ..
            }]
        ),
        "{drawn:?}"
    );
    assert_eq!(server.stats().rejected, bad.len() + 3);
}

/// The signal, the averages and the alarms go to operator views only: the subject page (and
/// whoever holds its key) never gets the EEG.
#[test]
fn the_signal_reaches_operator_views_only() {
    use oddball_live::panel::{ServerMsg, SignalState};
    let server = loopback_server();
    let mut subject = socket(&server, false);
    let mut operator = socket(&server, true);
    until(&server, "both views connected", |s| {
        s.stats().connected == 1 && s.stats().operators == 1
    });
    server.send(&ServerMsg::Signal {
        t_ms: 1.0,
        lo: vec![vec![-1.5]],
        hi: vec![vec![2.5]],
        state: vec![SignalState::Flat],
    });
    server.send(&ServerMsg::Cancel { after_ms: 2.0 });
    // Everything each socket reads within a second.
    let read_all = |ws: &mut tungstenite::WebSocket<_>| {
        let mut texts = Vec::new();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(1) {
            if let Ok(tungstenite::Message::Text(t)) = ws.read() {
                texts.push(t.to_string());
            }
        }
        texts
    };
    let to_subject = read_all(&mut subject);
    let to_operator = read_all(&mut operator);
    let has = |texts: &[String], tag: &str| texts.iter().any(|t| t.contains(tag));
    assert!(has(&to_operator, r#""t":"signal""#), "{to_operator:?}");
    assert!(has(&to_operator, r#""t":"cancel""#));
    assert!(has(&to_subject, r#""t":"cancel""#), "{to_subject:?}");
    assert!(!has(&to_subject, r#""t":"signal""#), "{to_subject:?}");
}

/// The first server message of each kind in `tags` the page reads within 5 s, in the order of
/// `tags` (operator-only messages come on their own channel: their order against the others'
/// is not kept).
fn next_msgs(
    ws: &mut tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    tags: &[&str],
) -> Vec<serde_json::Value> {
    let t0 = Instant::now();
    let mut found: Vec<Option<serde_json::Value>> = vec![None; tags.len()];
    while found.iter().any(Option::is_none) {
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "not all of {tags:?}: {found:?}"
        );
        if let Ok(tungstenite::Message::Text(t)) = ws.read() {
            let v: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
            if let Some(k) = tags.iter().position(|tag| v["t"] == *tag) {
                found[k].get_or_insert(v);
            }
        }
    }
    found.into_iter().flatten().collect()
}

/// Issue #30: a calibration holds between trials while its subject view says it is hidden,
/// and goes on once it is back and drawing; a flash the page stamps while hidden gives no
/// epoch; once calibration is over a hidden view raises the alarm but holds nothing (online an
/// undrawn flash adds no evidence and the decision abstains).
#[test]
fn a_hidden_subject_view_holds_a_calibration_and_its_stamps_are_void() {
    use oddball_live::live::LiveSubject;
    use oddball_live::sim::SimSource;
    use oddball_session::decision::Phase;
    use oddball_session::paradigm::FourBulbParams;
    use oddball_session::roles::{EegStream, Presenter};
    use oddball_session::subject::{SubjectParams, SubjectPreset};
    use tungstenite::Message;

    let clock = Clock::new();
    let sim = SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(5)
        .build()
        .unwrap();
    let server =
        PanelServer::start("127.0.0.1:0".parse().unwrap(), false, config(), clock).unwrap();
    let mut page = socket(&server, false);
    let mut operator = socket(&server, true);
    until(&server, "both views", |s| {
        s.stats().connected == 1 && s.stats().operators == 1
    });
    let frames = r#"{"t":"frames","frames":15,"max_gap_ms":17,"dropped":0,"multi_lit":0}"#;
    page.send(Message::text(frames)).unwrap();
    let mut subject = LiveSubject::new(
        SimSource::new(sim, clock, 0.0),
        FourBulbParams::paper(),
        clock,
    )
    .with_panel(server);
    subject.set_plan(Some(4), Some(2));
    // Renders 50 ms blocks (the page reporting its frames) until `held` is what hold() says.
    let run_until = |subject: &mut LiveSubject<SimSource>,
                     page: &mut tungstenite::WebSocket<_>,
                     held: bool,
                     report: &str| {
        let t0 = Instant::now();
        loop {
            assert!(t0.elapsed() < Duration::from_secs(5), "hold() never {held}");
            page.send(Message::text(report)).unwrap();
            subject.render(25).unwrap();
            if subject.hold().unwrap() == held {
                return;
            }
        }
    };
    run_until(&mut subject, &mut page, false, frames);
    assert!(!subject.presentation_faults().any());

    page.send(Message::text(r#"{"t":"visibility","hidden":true}"#))
        .unwrap();
    // A hidden page sends no frames.
    run_until(
        &mut subject,
        &mut page,
        true,
        r#"{"t":"ping","id":1,"page_ms":0}"#,
    );
    let f = subject.presentation_faults();
    assert_eq!((f.hidden, f.calibration_holds), (1, 1), "{f:?}");
    // The operator view is told, with the alarm and the hold.
    let told = next_msgs(&mut operator, &["alarm", "paused"]);
    let (alarm, held) = (&told[0], &told[1]);
    assert_eq!(
        (alarm["kind"].as_str(), alarm["active"].as_bool()),
        (Some("hidden"), Some(true))
    );
    assert_eq!(held["fault"], "hidden", "{held}");

    // A flash the page stamps while it says it is hidden: void.
    let onset = subject.position() + subject.lead();
    subject.show(onset, 2, true).unwrap();
    let flash = next_msgs(&mut page, &["flash"]).remove(0);
    page.send(Message::text(format!(
        r#"{{"t":"on","id":{},"code":2,"on_ms":{}}}"#,
        flash["id"], flash["at_ms"]
    )))
    .unwrap();
    let t0 = Instant::now();
    let drawn = loop {
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "the stamp never came"
        );
        subject.render(25).unwrap();
        let d = subject.drawn();
        if !d.is_empty() {
            break d;
        }
    };
    assert_eq!(drawn[0].onset, None, "{drawn:?}");
    let f = subject.presentation_faults();
    assert_eq!(
        (f.undrawn_flashes, f.calibration_undrawn_flashes),
        (1, 0),
        "no calibration trial under way: {f:?}"
    );
    assert_eq!(subject.timing.refused_stamps, 1);

    // Back and drawing: the calibration goes on.
    page.send(Message::text(r#"{"t":"visibility","hidden":false}"#))
        .unwrap();
    run_until(&mut subject, &mut page, false, frames);
    assert!(subject.presentation_faults().calibration_held_s > 0.0);

    // Calibration over: hidden again raises the alarm, and holds nothing.
    for _ in 0..4 {
        let at = subject.position();
        subject
            .trial_started(at, Phase::Calibration, Some(1))
            .unwrap();
    }
    page.send(Message::text(r#"{"t":"visibility","hidden":true}"#))
        .unwrap();
    let t0 = Instant::now();
    while subject.presentation_faults().hidden < 2 {
        assert!(t0.elapsed() < Duration::from_secs(5), "no second alarm");
        subject.render(25).unwrap();
        assert!(!subject.hold().unwrap(), "online holds for no fault");
    }
}
