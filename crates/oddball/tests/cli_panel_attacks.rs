//! Issue #30: the panel belongs to its session. A real `oddball online --serve` runs twice with a
//! scripted subject page (a WebSocket client that stamps every flash at its scheduled time): once
//! alone, once while hostile clients try the probe's attacks — pages and sockets without the
//! key, from a foreign `Host` (DNS rebinding) or a foreign `Origin` (a cross-site WebSocket), an
//! abort from such an operator socket, and a second subject socket with the key stamping every
//! flash at 0 ms and at +190 ms. The attacks change nothing: the same decisions, the session
//! not aborted, every attack refused and counted. No browser needed.

mod common;

use std::io::{BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::Duration;

use tungstenite::client::IntoClientRequest;
use tungstenite::Message;

/// `http://ADDR/PATH?key=K` → (`ADDR`, `?key=K`).
fn split(url: &str) -> (String, String) {
    let rest = url.strip_prefix("http://").unwrap();
    let slash = rest.find('/').unwrap();
    let query = &rest[slash..];
    (
        rest[..slash].to_string(),
        query[query.find('?').unwrap()..].to_string(),
    )
}

use common::Socket;

fn socket(url: &str, headers: &[(&str, &str)]) -> Result<Socket, tungstenite::Error> {
    let mut req = url.into_client_request().unwrap();
    for (k, v) in headers {
        req.headers_mut().insert(
            tungstenite::http::HeaderName::from_bytes(k.as_bytes()).unwrap(),
            v.parse().unwrap(),
        );
    }
    tungstenite::client::connect(req).map(|(ws, _)| ws)
}

/// The HTTP status of `GET path` with `Host: host`.
fn status(addr: &str, host: &str, path: &str) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    let _ = s.read_to_string(&mut out);
    out.lines().next().unwrap_or("").to_string()
}

/// Runs `oddball online --serve` with the scripted page; `attack` runs against the panel once
/// the page is connected. Returns the session's summary.json and stdout.
fn session(
    dir: &std::path::Path,
    model: &std::path::Path,
    attack: bool,
) -> (serde_json::Value, String) {
    let out = dir.join(if attack { "attacked" } else { "alone" });
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--serve", "127.0.0.1:0", "--paradigm", "fast"])
        .args(["--commands", "up,left,down", "--seed", "3"])
        .args(["--model", model.to_str().unwrap()])
        .args(["--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let (subject, operator) = common::panel_urls(&mut stdout);
    let (addr, key) = split(&subject);
    let (_, operator_key) = split(&operator);
    let mut page = socket(&format!("ws://{addr}/ws{key}"), &[]).expect("the page connects");
    let hostile = attack.then(|| {
        let addr = addr.clone();
        let key = key.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(1500));
            let mut refused = 0;
            // Pages: no key, the other view's key, a rebound DNS name with the right key.
            for (host, path) in [
                (addr.clone(), "/operator".to_string()),
                (addr.clone(), format!("/{}", operator_key)),
                ("evil.example".to_string(), format!("/{key}")),
            ] {
                assert!(status(&addr, &host, &path).contains("403"), "{host} {path}");
                refused += 1;
            }
            // Sockets: an operator socket from a foreign Origin would abort; a keyless one;
            // one whose Host is a rebound name.
            for (url, headers) in [
                (
                    format!("ws://{addr}/ws/operator{operator_key}"),
                    vec![("Origin", "http://evil.example")],
                ),
                (format!("ws://{addr}/ws/operator"), vec![]),
                (
                    format!("ws://{addr}/ws{key}"),
                    vec![("Host", "evil.example")],
                ),
            ] {
                match socket(&url, &headers) {
                    Ok(mut ws) => {
                        let _ = ws.send(Message::text(r#"{"t":"control","action":"abort"}"#));
                        panic!("{url} {headers:?} was let in");
                    }
                    Err(_) => refused += 1,
                }
            }
            // A second subject socket with the key, stamping every flash at 0 and at +190 ms.
            let mut second = socket(&format!("ws://{addr}/ws{key}"), &[]).expect("handshake");
            for id in 0..200u64 {
                for on_ms in [0.0, 190.0] {
                    let _ = second.send(Message::text(format!(
                        r#"{{"t":"on","id":{id},"code":{},"on_ms":{on_ms}}}"#,
                        id % 4 + 1
                    )));
                }
            }
            refused
        })
    });
    common::scripted_page(&mut page, |_| 0.0);
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = online.wait().unwrap();
    assert!(status.success(), "{rest}");
    if let Some(h) = hostile {
        assert_eq!(h.join().unwrap(), 6);
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // decisions.csv as demo writes it: a header and one row per decision.
    let csv = std::fs::read_to_string(out.join("decisions.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + summary["decisions"].as_array().unwrap().len(),
        "{csv}"
    );
    (summary, rest)
}

#[test]
fn the_probes_panel_attacks_change_nothing_in_the_session() {
    let dir = common::tmp_dir("panel-attacks");
    let model = common::demo_model(&dir);
    let (alone, _) = session(&dir, &model, false);
    let (attacked, said) = session(&dir, &model, true);
    let decided = |s: &serde_json::Value| {
        s["decisions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| {
                (
                    d["intended"].clone(),
                    d["decided"].clone(),
                    d["rounds"].clone(),
                )
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(decided(&alone).len(), 3, "{alone}");
    assert_eq!(
        decided(&alone),
        decided(&attacked),
        "the attacks changed the decisions"
    );
    assert!(attacked["ended"].is_null(), "not aborted: {attacked}");
    for s in [&alone, &attacked] {
        assert_eq!(
            s["undrawn_flashes"], 0,
            "every flash stamped by the page: {s}"
        );
        assert_eq!(s["refused_stamps"], 0, "{s}");
    }
    // Six requests refused at the door and one other subject view refused, all counted.
    let panel = said
        .lines()
        .find(|l| l.starts_with("panel: ") && l.contains("refused at the door"))
        .expect("panel line");
    assert!(
        panel.contains("6 request(s) refused at the door, 1 other subject view(s) refused"),
        "{panel}"
    );
}
