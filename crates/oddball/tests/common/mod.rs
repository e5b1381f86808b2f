//! Shared helpers of the CLI tests: where the real EEG is, and running the binary.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

pub mod decode;

/// `../shared/data` beside the checkout (or `ODDBALL_DATA`); `None`, with a message, when absent
/// (a failure under `ODDBALL_REQUIRE_DATA=1`, see `oddball_testkit`).
pub fn data_dir() -> Option<PathBuf> {
    oddball_testkit::data_dir("this CLI test (real EEG)")
}

/// Runs `oddball ARGS…`: (exit status success, stdout, stderr).
pub fn oddball(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(args)
        .output()
        .expect("oddball runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A fresh temporary folder for one test, removed when dropped.
/// Runs the binary, asserts it succeeded (showing its stderr) and returns its stdout.
pub fn oddball_ok(args: &[&str]) -> String {
    let (ok, out, err) = oddball(args);
    assert!(ok, "oddball {}: {err}", args.join(" "));
    out
}

pub fn tmp_dir(name: &str) -> oddball_testkit::TempDir {
    oddball_testkit::TempDir::new(name)
}

/// A model fitted in a quick (unpaced) one-command demo session, for `oddball online`.
pub fn demo_model(dir: &std::path::Path) -> PathBuf {
    let out = dir.join("demo");
    let (ok, _, err) = oddball(&["demo", "--commands", "up", "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    out.join("model.json")
}

/// How [`write_csv_with`] shapes the synthetic recording.
#[derive(Debug, Clone)]
pub struct CsvSpec {
    /// The channels' names, in column order (16 for the default).
    pub names: Vec<String>,
    /// Seconds between rows (1/256 by default).
    pub step_s: f64,
    /// Samples made NaN (CSV refuses them: written by [`write_xdf_with`] only): (column
    /// index among the channels, rows).
    pub nan: Option<(usize, std::ops::Range<usize>)>,
}

impl Default for CsvSpec {
    fn default() -> Self {
        Self {
            names: (0..16).map(|c| format!("ch{c}")).collect(),
            step_s: 1.0 / 256.0,
            nan: None,
        }
    }
}

/// A 16-channel CSV at 256 Hz (`time` column, `stim` markers): 240 flashes every 0.4 s, every
/// fifth marked 2 (target, with a 2 µV P300-like bump 300–500 ms later on every channel), the
/// others 1; noise from a fixed linear congruential generator.
pub fn write_csv(path: &std::path::Path) {
    write_csv_with(path, &CsvSpec::default());
}

/// [`write_csv`] with the channels named (and so ordered) by `spec.names`: channel `chK`
/// carries the same samples whatever column it is in, so a permuted montage is the same data
/// (the samples are `oddball_testkit::synthetic_oddball(16, 12345)`'s).
pub fn write_csv_with(path: &std::path::Path, spec: &CsvSpec) {
    use std::fmt::Write as _;
    let (data, markers, _) = oddball_testkit::synthetic_oddball(16, 12345);
    let cols: Vec<usize> = spec
        .names
        .iter()
        .map(|n| {
            n.strip_prefix("ch")
                .and_then(|k| k.parse().ok())
                .unwrap_or(0)
        })
        .collect();
    let mut text = String::from("time");
    for n in &spec.names {
        let _ = write!(text, ",{n}");
    }
    text.push_str(",stim\n");
    for (i, m) in markers.iter().enumerate() {
        let _ = write!(text, "{}", i as f64 * spec.step_s);
        for &k in &cols {
            let _ = write!(text, ",{:.4}", data[[k, i]]);
        }
        let _ = writeln!(text, ",{m}");
    }
    std::fs::write(path, text).unwrap();
}

/// Runs `oddball ARGS…` with a watchdog: `None` for the exit code when it was still running
/// after `seconds` (a hang; it is killed). (exit code, stdout, stderr).
pub fn oddball_within(args: &[&str], seconds: u64) -> (Option<i32>, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("oddball runs");
    let t0 = std::time::Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status.code();
        }
        if t0.elapsed().as_secs() >= seconds {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let out = child.wait_with_output().expect("output");
    (
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The recording of [`write_csv_with`] as an XDF (float32 EEG, markers "1"/"2"), with
/// `spec.nan`'s samples NaN, as the live recorder writes samples an LSL stream lost.
pub fn write_xdf_with(path: &std::path::Path, spec: &CsvSpec) {
    use oddball_io::xdf::{XdfStream, XdfWriter};
    let csv = path.with_extension("csv");
    write_csv_with(
        &csv,
        &CsvSpec {
            nan: None,
            ..spec.clone()
        },
    );
    let rec = oddball_io::read(&csv).unwrap();
    std::fs::remove_file(&csv).unwrap();
    let raw = &rec.raw;
    let mut data = raw.data().clone();
    if let Some((c, rows)) = &spec.nan {
        for t in rows.start..rows.end.min(raw.n_times()) {
            data[[*c, t]] = f64::NAN;
        }
    }
    let ts: Vec<f64> = (0..raw.n_times()).map(|i| i as f64 / raw.sfreq()).collect();
    let mut w = XdfWriter::create(path).unwrap();
    let eeg = w
        .add_stream(&XdfStream::eeg("EEG", raw.ch_names().to_vec(), raw.sfreq()))
        .unwrap();
    let markers = w.add_stream(&XdfStream::markers("markers")).unwrap();
    w.push_numeric(eeg, &ts, data.view()).unwrap();
    let mts: Vec<f64> = raw.events().iter().map(|e| ts[e.onset]).collect();
    let texts: Vec<String> = raw.events().iter().map(|e| e.code.to_string()).collect();
    let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
    w.push_strings(markers, &mts, &refs).unwrap();
    w.flush_block().unwrap();
    w.finish().unwrap();
}

/// Reads a session's stdout up to its `panel: URL` and `operator view: URL` lines and returns
/// the two addresses (each with its view's key).
#[allow(dead_code)] // not every test binary serves the panel
pub fn panel_urls(stdout: &mut impl std::io::BufRead) -> (String, String) {
    let mut head = String::new();
    let mut subject = None;
    for _ in 0..10 {
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        head.push_str(&line);
        if let Some(u) = line.trim().strip_prefix("panel: ") {
            subject = Some(u.to_string());
        }
        if let (Some(s), Some(o)) = (&subject, line.trim().strip_prefix("operator view: ")) {
            assert!(s.contains("?key=") && o.contains("?key="), "{head}");
            return (s.clone(), o.to_string());
        }
    }
    panic!("no panel lines in:\n{head}");
}

/// `stderr` without the plain progress lines a long command writes when stderr is not a
/// terminal (`what: pos/len (pct%) h:mm:ss`): what is left are warnings and errors.
pub fn without_progress(stderr: &str) -> String {
    let is_progress = |l: &str| {
        l.rsplit_once(": ").is_some_and(|(_, rest)| {
            let parts: Vec<&str> = rest.split(' ').collect();
            parts.len() == 3
                && parts[0].split_once('/').is_some()
                && parts[1].starts_with('(')
                && parts[1].ends_with("%)")
                && parts[2].split(':').count() == 3
        })
    };
    stderr
        .lines()
        .filter(|l| !is_progress(l))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// A WebSocket to a session's panel.
pub type Socket = tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<std::net::TcpStream>>;

/// A subject page in a script: says hello, keeps the server's clock by ping/pong, and stamps
/// every flash on `late_ms(id)` after its schedule and off its duration later (a `cancel`
/// drops the flashes from its time on), until the session ends (at most 240 s).
pub fn scripted_page(ws: &mut Socket, late_ms: impl Fn(u64) -> f64) {
    use std::time::{Duration, Instant};
    use tungstenite::Message;
    let t0 = Instant::now();
    let local = || t0.elapsed().as_secs_f64() * 1e3;
    match ws.get_mut() {
        tungstenite::stream::MaybeTlsStream::Plain(s) => {
            s.set_read_timeout(Some(Duration::from_millis(2))).unwrap()
        }
        _ => unreachable!(),
    }
    let send = |ws: &mut Socket, v: serde_json::Value| {
        ws.send(Message::text(v.to_string())).unwrap();
    };
    send(
        ws,
        serde_json::json!({"t": "ping", "id": 1, "page_ms": local()}),
    );
    send(
        ws,
        serde_json::json!({"t": "hello", "frame_ms": 16.7, "agent": "scripted page"}),
    );
    let mut offset = None; // server − local, ms
                           // (send at, the flash's scheduled time, message), server ms.
    let mut due: Vec<(f64, f64, serde_json::Value)> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(240);
    while Instant::now() < deadline {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let m: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
                match m["t"].as_str().unwrap_or("") {
                    "pong" => offset = Some(m["server_ms"].as_f64().unwrap() - local()),
                    "flash" => {
                        let id = m["id"].as_u64().unwrap();
                        let at = m["at_ms"].as_f64().unwrap();
                        let on = at + late_ms(id);
                        let off = on + m["dur_ms"].as_f64().unwrap();
                        let code = m["code"].clone();
                        due.push((
                            on,
                            at,
                            serde_json::json!({"t": "on", "id": id, "code": code, "on_ms": on}),
                        ));
                        due.push((
                            off,
                            at,
                            serde_json::json!({"t": "off", "id": id, "off_ms": off}),
                        ));
                    }
                    "cancel" => {
                        let after = m["after_ms"].as_f64().unwrap();
                        due.retain(|d| d.1 < after);
                    }
                    "end" => return,
                    _ => {}
                }
            }
            Ok(Message::Close(_)) => return,
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return,
        }
        let Some(off) = offset else { continue };
        let now = local() + off;
        due.sort_by(|a, b| a.0.total_cmp(&b.0));
        while due.first().is_some_and(|d| d.0 <= now) {
            let (_, _, m) = due.remove(0);
            send(ws, m);
        }
    }
    panic!("the session did not end within 240 s");
}
