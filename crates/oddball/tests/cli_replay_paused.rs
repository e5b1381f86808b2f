//! Issue #30's probe: `oddball online --serve` with a page that stamps every flash a few
//! frames late and an operator who pauses between decisions, then the recording played back
//! with `--source replay:… --fast`. The replay draws each flash where the page drew it and
//! holds where the operator held: the same decisions (before: live 4/4, replay 0/4).

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use tungstenite::Message;

use common::Socket;

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

fn socket(url: &str) -> Socket {
    tungstenite::client::connect(url).expect("handshake").0
}

/// How late the page draws flash `id`, ms (a frame to five frames, never a whole sample).
fn late_ms(id: u64) -> f64 {
    [7.3, 24.9, 41.2, 58.6, 75.1][(id % 5) as usize]
}

fn control(ws: &mut Socket, action: &str) {
    ws.send(Message::text(
        serde_json::json!({"t": "control", "action": action}).to_string(),
    ))
    .unwrap();
}

/// The decision lines, up to the posterior (`decision 1: up → up ✓`).
fn decisions(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .filter(|l| l.starts_with("decision "))
        .map(|l| l.split(" (p ").next().unwrap().to_string())
        .collect()
}

#[test]
fn a_paused_live_session_with_late_stamps_replays_to_the_same_decisions() {
    let dir = common::tmp_dir("replay-paused");
    let model = common::demo_model(&dir);
    let m = model.to_str().unwrap();
    let live_dir = dir.join("live");
    let common_args = [
        "--paradigm",
        "fast",
        "--commands",
        "up,left,down,right",
        "--seed",
        "3",
        "--model",
        m,
    ];
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--serve", "127.0.0.1:0"])
        .args(common_args)
        .args(["--out", live_dir.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let (subject, operator) = common::panel_urls(&mut stdout);
    let (addr, key) = split(&subject);
    let (_, operator_key) = split(&operator);
    let mut page_ws = socket(&format!("ws://{addr}/ws{key}"));
    let page = std::thread::spawn(move || common::scripted_page(&mut page_ws, late_ms));
    // The operator pauses once the second decision is out, and resumes 1.5 s later.
    let (lines_tx, lines) = mpsc::channel::<String>();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in stdout.lines() {
            let line = line.unwrap();
            let _ = lines_tx.send(line.clone());
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    let t0 = Instant::now();
    loop {
        let line = lines
            .recv_timeout(Duration::from_secs(120))
            .expect("a second decision");
        if line.starts_with("decision 2:") {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(120));
    }
    // The pause holds before the next trial to start: resumed 1.5 s after the operator view
    // is told the session holds.
    let mut op = socket(&format!("ws://{addr}/ws/operator{operator_key}"));
    control(&mut op, "pause");
    let t0 = Instant::now();
    loop {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the session never held"
        );
        if let Message::Text(t) = op.read().unwrap() {
            let m: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
            if m["t"] == "paused" && m["paused"] == true {
                break;
            }
        }
    }
    std::thread::sleep(Duration::from_millis(1500));
    control(&mut op, "resume");
    page.join().unwrap();
    let said = reader.join().unwrap();
    assert!(online.wait().unwrap().success(), "{said}");
    let live = decisions(&said);
    assert_eq!(live.len(), 4, "{said}");
    let recording = live_dir.join("session.xdf");
    let rec = oddball_io::read(&recording).unwrap();
    let texts: Vec<&str> = rec
        .xdf()
        .unwrap()
        .markers
        .iter()
        .map(|m| m.text.as_str())
        .collect();
    assert!(
        texts.contains(&"pause") && texts.contains(&"resume"),
        "{texts:?}"
    );

    let replay_dir = dir.join("replay");
    let source = format!("replay:{}", recording.display());
    let replayed = common::oddball_ok(
        &[
            &["online", "--source", &source, "--fast"][..],
            &common_args,
            &["--out", replay_dir.to_str().unwrap()],
        ]
        .concat(),
    );
    assert_eq!(decisions(&replayed), live, "{replayed}");
    let n = rec.raw.events().len();
    assert!(
        replayed.contains(&format!(
            "replay: {n} of {n} flashes of this session fall on a flash of the same bulb"
        )),
        "{replayed}"
    );
    let full = |s: &str| -> String {
        s.lines()
            .filter(|l| l.starts_with("decision ") || l.starts_with("replay: "))
            .collect::<Vec<_>>()
            .join("\n")
    };
    eprintln!("live:\n{}\nreplayed:\n{}", full(&said), full(&replayed));
}
