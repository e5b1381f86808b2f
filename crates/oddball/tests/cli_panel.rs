//! The stimulus panel in a real browser: `oddball online --serve` with headless Chromium driven
//! by Playwright (tools/panel-test/panel.mjs). The page loads, counts down, flashes with on-times
//! of 100 ms within one frame, shows the decisions and moves the arm; a screenshot is saved
//! to target/panel-test.png (and the operator view's decisions to
//! target/panel-test-operator.png). Meanwhile a second client sends malformed, oversized and
//! binary messages and an abort on the subject's socket, and disconnects: the server refuses
//! them and the session goes on.
//!
//! Both views at once (tools/panel-test/views.mjs): the subject view full screen and the
//! operator view during a live calibration, screenshots of each (target/panel-subject.png,
//! target/panel-operator.png); pause, resume and abort from the operator view.
//!
//! Needs Chromium and Node with playwright-core: runs when ODDBALL_CHROMIUM names the browser
//! (CI: `apt-get install chromium`, `npm ci` in tools/panel-test), otherwise says it skips.

mod common;

use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// Chromium's path from ODDBALL_CHROMIUM, or `None` with a skip message.
fn chromium() -> Option<std::ffi::OsString> {
    oddball_testkit::tool(
        "ODDBALL_CHROMIUM",
        "the browser test",
        "e.g. /usr/bin/chromium, and npm ci in tools/panel-test",
    )
}

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// Reads a session's stdout up to its `panel: URL` line and returns the URL.
fn panel_url(stdout: &mut impl BufRead) -> String {
    let mut head = String::new();
    for _ in 0..10 {
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        head.push_str(&line);
        if let Some(u) = line.trim().strip_prefix("panel: ") {
            return u.to_string();
        }
    }
    panic!("no panel line in:\n{head}");
}

/// Drives the page at `url` with tools/panel-test/panel.mjs until `n` decisions (screenshot to
/// target/`shot`), then reads the rest of the session's stdout and waits for it; both must
/// succeed. Returns (page stdout, session stdout).
fn drive(
    chromium: &std::ffi::OsStr,
    url: &str,
    shot: &str,
    n: usize,
    stdout: &mut impl Read,
    child: &mut std::process::Child,
) -> (String, String) {
    let page = Command::new("node")
        .current_dir(root().join("tools/panel-test"))
        .env("CHROMIUM", chromium)
        .args([
            "panel.mjs",
            url,
            root().join("target").join(shot).to_str().unwrap(),
        ])
        .arg(n.to_string())
        .output()
        .expect("node runs");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    let page_out = String::from_utf8_lossy(&page.stdout).into_owned();
    println!(
        "page: {page_out}\n{}\nsession:\n{rest}",
        String::from_utf8_lossy(&page.stderr)
    );
    assert!(page.status.success(), "the page checks failed");
    assert!(status.success(), "the session failed:\n{rest}");
    (page_out, rest)
}

#[test]
fn the_panel_flashes_decides_and_moves_the_arm_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    assert!(
        root()
            .join("tools/panel-test/node_modules/playwright-core")
            .is_dir(),
        "run `npm ci` in tools/panel-test"
    );
    let dir = common::tmp_dir("panel");
    let model = common::demo_model(&dir);
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args([
            "online",
            "--serve",
            "127.0.0.1:0",
            "--commands",
            "up,left",
            "--seed",
            "3",
        ])
        .args(["--model", model.to_str().unwrap()])
        .args(["--out", dir.join("online").to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let url = panel_url(&mut stdout);
    let (_, rest) = drive(
        &chromium,
        &url,
        "panel-test.png",
        2,
        &mut stdout,
        &mut online,
    );
    assert!(root().join("target/panel-test.png").is_file());
    // The session heard the page: every flash stamped and timed; the rogue client refused.
    // Measured on-times of 100 ms within one frame (the mean may print as 99.99).
    let on_time: f64 = rest
        .lines()
        .find_map(|l| {
            l.strip_prefix("flash on-time ")?
                .split(' ')
                .next()?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no flash on-time line:\n{rest}"));
    assert!(
        (on_time - 100.0).abs() < 16.7,
        "mean on-time {on_time} ms:\n{rest}"
    );
    // A flash the page drew more than 200 ms late (a starved machine) is voided, as it should
    // be; on an idle machine there are none.
    let undrawn: usize = rest
        .lines()
        .find_map(|l| l.strip_prefix("undrawn ")?.split(',').next()?.parse().ok())
        .expect("undrawn line");
    assert!(undrawn <= 4, "{undrawn} of 40 flashes undrawn:\n{rest}");
    let rejected: usize = rest
        .lines()
        .find_map(|l| {
            l.strip_prefix("panel: ")?
                .split(", ")
                .nth(1)?
                .split(' ')
                .next()?
                .parse()
                .ok()
        })
        .expect("panel stats line");
    // Malformed, oversized, binary, a bad code, and an abort on the subject's socket (refused:
    // the session made both decisions).
    assert!(rejected >= 5, "{rest}");
}

#[test]
fn the_panel_shows_a_tracking_task_and_its_target_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = common::tmp_dir("panel-task");
    // One explicit target two steps right of the start: two decisions in front of the page.
    let mut task = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args([
            "task",
            "track",
            "--target",
            "0.39,0.05",
            "--calibration-per-bulb",
            "5",
        ])
        .args(["--serve", "127.0.0.1:0", "--seed", "4"])
        .args(["--out", dir.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball task starts");
    let mut stdout = BufReader::new(task.stdout.take().unwrap());
    let url = panel_url(&mut stdout);
    let (page_out, rest) = drive(&chromium, &url, "panel-task.png", 2, &mut stdout, &mut task);
    assert!(
        page_out.contains("\"targets\":1"),
        "the page shows the target: {page_out}"
    );
    assert!(rest.contains("reached 1/1 targets"), "{rest}");
}

/// Issue #20, part 3: the operator view shows calibration progress ("calibration: decision 2 of
/// 8"), flash timing and channel quality (a recording played back live with one dead channel and
/// one far too noisy: "flat or saturated" and "noisy", the others "ok") while the subject view,
/// full screen, shows only the task; a pause holds the session (no flash drawn for 3 s), a
/// resume restarts the flashing, and abort stops the session as SIGTERM does: it exits 0 with
/// its recording complete and readable (the pause and resume marked in it) and its summary
/// written.
#[test]
fn the_operator_view_pauses_resumes_and_aborts_a_live_calibration_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = common::tmp_dir("panel-views");
    // 4 channels at 256 Hz: ch1 dead (0 µV), ch2 with ±500 µV of noise.
    let (mut data, markers, sfreq) = oddball_testkit::synthetic_oddball(4, 7);
    data.row_mut(1).fill(0.0);
    data.row_mut(2).mapv_inplace(|v| 100.0 * v);
    let faulty = dir.join("faulty.csv");
    oddball_testkit::write_codes_csv(&faulty, &data, &markers, sfreq);
    let out = dir.join("online");
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--serve", "127.0.0.1:0", "--calibrate"])
        .arg(format!("--source=replay:{}", faulty.display()))
        .args(["--calibration-per-bulb", "2", "--paradigm", "fast"])
        .args(["--commands", "up,left", "--seed", "3"])
        .args(["--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let url = panel_url(&mut stdout);
    let shots = ["panel-subject.png", "panel-operator.png"].map(|s| root().join("target").join(s));
    for s in &shots {
        let _ = std::fs::remove_file(s);
    }
    let page = Command::new("node")
        .current_dir(root().join("tools/panel-test"))
        .env("CHROMIUM", &chromium)
        .arg("views.mjs")
        .arg(&url)
        .args(&shots)
        .arg(r#"{"ch0":"ok","ch1":"flat or saturated","ch2":"noisy","ch3":"ok"}"#)
        .output()
        .expect("node runs");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = online.wait().unwrap();
    println!(
        "page: {}\n{}\nsession:\n{rest}",
        String::from_utf8_lossy(&page.stdout),
        String::from_utf8_lossy(&page.stderr)
    );
    assert!(page.status.success(), "the page checks failed");
    for s in &shots {
        assert!(s.is_file(), "no screenshot {}", s.display());
    }
    // Aborted during calibration: a clean stop, not an error.
    assert!(status.success(), "the session failed:\n{rest}");
    assert!(
        rest.contains("calibration: aborted from the operator view"),
        "{rest}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ended"], "aborted from the operator view");
    // The recording is complete: it opens, and holds every sample the session printed.
    let printed: usize = rest
        .lines()
        .find_map(|l| {
            l.strip_prefix("recording: ")?
                .rsplit_once(" (")?
                .1
                .strip_suffix(" samples)")?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no recording line:\n{rest}"));
    let path = out.join("session.xdf");
    let rec = oddball_io::read(&path).expect("the aborted session's recording opens");
    assert_eq!(rec.raw.n_times(), printed);
    // Several trials' worth of EEG, the pause included.
    assert!(
        rec.raw.n_times() as f64 / rec.raw.sfreq() > 10.0,
        "{} samples",
        rec.raw.n_times()
    );
    let bytes = std::fs::read(&path).unwrap();
    for marker in [&b"pause"[..], b"resume"] {
        assert!(
            bytes.windows(marker.len()).any(|w| w == marker),
            "no {} marker in the recording",
            String::from_utf8_lossy(marker)
        );
    }
}
