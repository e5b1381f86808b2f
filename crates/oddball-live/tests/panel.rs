//! The panel server over plain HTTP: the page and its script are served from the binary, the
//! server binds loopback unless told otherwise, and it stops when dropped.

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
    }
}

fn get(addr: std::net::SocketAddr, path: &str) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    out
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
    let page = get(addr, "/");
    assert!(page.starts_with("HTTP/1.1 200"), "{page}");
    assert!(page.contains("<script src=\"/panel.js\">"));
    let js = get(addr, "/panel.js");
    assert!(js.starts_with("HTTP/1.1 200"));
    assert!(js
        .to_ascii_lowercase()
        .contains("content-type: text/javascript"));
    assert!(js.contains("requestAnimationFrame"));
    // The operator view and the shared script, which carries the socket paths of the protocol.
    let operator = get(addr, "/operator");
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
