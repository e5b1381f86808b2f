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
//! A subject tab sent to the background during calibration (tools/panel-test/throttle.mjs):
//! the operator view raises the alarm, the calibration holds while the tab is hidden, and the
//! flashes it did not draw give no calibration epoch (target/panel-throttle-*.png).
//!
//! Needs Chromium and Node with playwright-core: runs when ODDBALL_CHROMIUM names the browser
//! (CI: `apt-get install chromium`, `npm ci` in tools/panel-test), otherwise says it skips.

mod common;

use std::io::{BufReader, Read};
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

/// One browser at a time: four headless Chromiums on a small machine starve each other's
/// frames, and a missed frame is just what these tests measure.
fn one_browser_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static BROWSER: std::sync::Mutex<()> = std::sync::Mutex::new(());
    BROWSER.lock().unwrap_or_else(|e| e.into_inner())
}

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// Drives the page at `url` with tools/panel-test/panel.mjs until `n` decisions (screenshot to
/// target/`shot`; `timing`: the nominal on-time and gap, ms, it checks), then reads the rest of
/// the session's stdout and waits for it; both must succeed. Returns (page stdout, session
/// stdout).
fn drive(
    chromium: &std::ffi::OsStr,
    (url, operator_url): &(String, String),
    shot: &str,
    n: usize,
    timing: &[&str],
    stdout: &mut impl Read,
    child: &mut std::process::Child,
) -> (String, String) {
    let page = Command::new("node")
        .current_dir(root().join("tools/panel-test"))
        .env("CHROMIUM", chromium)
        .args([
            "panel.mjs",
            url,
            operator_url,
            root().join("target").join(shot).to_str().unwrap(),
        ])
        .arg(n.to_string())
        .args(timing)
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
    let _browser = one_browser_at_a_time();
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
    let url = common::panel_urls(&mut stdout);
    let (_, rest) = drive(
        &chromium,
        &url,
        "panel-test.png",
        2,
        &[],
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
    // "panel: N connection(s), M message(s) rejected, R request(s) refused at the door, S other
    // subject view(s) refused": the rogue client, keyless, was refused at the door, and with the
    // page's key, as a second subject view, closed unheard; the session made both decisions.
    let figures: Vec<usize> = rest
        .lines()
        .find_map(|l| {
            l.strip_prefix("panel: ")?
                .contains("refused at the door")
                .then_some(l)
        })
        .expect("panel stats line")
        .split(", ")
        .filter_map(|part| {
            part.trim_start_matches("panel: ")
                .split(' ')
                .next()?
                .parse()
                .ok()
        })
        .collect();
    assert_eq!(figures.len(), 4, "{rest}");
    assert!(figures[2] >= 1 && figures[3] >= 1, "{rest}");
}

/// The first number after `prefix` on a line of `text`, e.g. the mean of `flash on-time 99.9 ms …`.
fn figure(text: &str, prefix: &str) -> Option<f64> {
    text.lines()
        .find_map(|l| l.strip_prefix(prefix)?.split(' ').next()?.parse().ok())
}

/// Issue #22: the `fast` timing (100 ms on, 75 ms off, rounds not padded, 1 s cue) on the
/// panel. Measured at 60 Hz: on-times 99.9–100.1 ms, gaps 66.6–83.4 ms (worst 8.4 ms off 75,
/// half a frame), no flash late. The page checks that every flash of a trial is scheduled
/// 100 ms on and 75 ms off, and
/// that the frames that drew them kept both within one frame (the measured on-time from the
/// frame that lit a bulb to the one that put it out, and the gap from there to the frame that lit
/// the next); the session's own figure of the stamped on-times agrees.
#[test]
fn the_panel_runs_the_fast_timing_with_on_times_and_gaps_within_a_frame_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let _browser = one_browser_at_a_time();
    let dir = common::tmp_dir("panel-fast");
    let model = common::demo_model(&dir);
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--serve", "127.0.0.1:0", "--paradigm", "fast"])
        .args(["--commands", "up,left", "--seed", "3"])
        .args(["--model", model.to_str().unwrap()])
        .args(["--out", dir.join("online").to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let url = common::panel_urls(&mut stdout);
    let (page_out, rest) = drive(
        &chromium,
        &url,
        "panel-fast.png",
        2,
        &["100", "75"],
        &mut stdout,
        &mut online,
    );
    let page: serde_json::Value = serde_json::from_str(
        page_out
            .lines()
            .find(|l| l.starts_with('{'))
            .expect("the page's measurements"),
    )
    .unwrap();
    // The page measured what the schedule said (its own checks failed the run otherwise): 75 ms
    // off, onsets on the 500 Hz sample clock (a 175 ms pitch is 174 or 176 ms).
    for g in page["gap_ms_scheduled"].as_array().unwrap() {
        assert!((g.as_f64().unwrap() - 75.0).abs() <= 2.0, "{page}");
    }
    // Two trials of 5 rounds of 4 flashes: 19 gaps each.
    assert!(page["gaps"].as_u64().unwrap() >= 30, "{page}");
    let frame = page["frame_ms"].as_f64().unwrap();
    for (key, nominal) in [
        ("on_ms_min", 100.0),
        ("on_ms_max", 100.0),
        ("gap_ms_min", 75.0),
        ("gap_ms_max", 75.0),
    ] {
        let v = page[key].as_f64().unwrap();
        assert!((v - nominal).abs() <= frame, "{key} {v} ms: {page}");
    }
    let on_time =
        figure(&rest, "flash on-time ").unwrap_or_else(|| panic!("no flash on-time line:\n{rest}"));
    assert!(
        (on_time - 100.0).abs() < frame,
        "mean on-time {on_time} ms:\n{rest}"
    );
}

#[test]
fn the_panel_shows_a_tracking_task_and_its_target_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let _browser = one_browser_at_a_time();
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
    let url = common::panel_urls(&mut stdout);
    let (page_out, rest) = drive(
        &chromium,
        &url,
        "panel-task.png",
        2,
        &[],
        &mut stdout,
        &mut task,
    );
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
/// resume restarts the flashing, and abort stops the session as SIGTERM does: it exits 3 (stopped before its end) with
/// its recording complete and readable (the pause and resume marked in it) and its summary
/// written.
#[test]
fn the_operator_view_pauses_resumes_and_aborts_a_live_calibration_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let _browser = one_browser_at_a_time();
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
    let url = common::panel_urls(&mut stdout);
    let shots = ["panel-subject.png", "panel-operator.png"].map(|s| root().join("target").join(s));
    for s in &shots {
        let _ = std::fs::remove_file(s);
    }
    let page = Command::new("node")
        .current_dir(root().join("tools/panel-test"))
        .env("CHROMIUM", &chromium)
        .arg("views.mjs")
        .args([&url.0, &url.1])
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
    assert_eq!(
        status.code(),
        Some(3),
        "aborted: stopped before its end:\n{rest}"
    );
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

/// Issue #30, presentation faults: the probe's background-throttled subject tab (hidden, one
/// frame a second) during a live calibration. The operator view raises an alarm naming the
/// fault and when at once, the calibration holds between trials while the tab is hidden (no
/// trial starts, nothing is announced) and goes on by itself when it is back, and calibration
/// trains on no flash the page did not draw: the calibration's epochs are at most the flashes
/// recorded as drawn, which fall short of those scheduled by exactly the undrawn flashes the
/// operator view counted.
#[test]
fn a_throttled_subject_tab_raises_the_alarm_and_calibration_uses_no_undrawn_flash_in_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let _browser = one_browser_at_a_time();
    let dir = common::tmp_dir("panel-throttle");
    let out = dir.join("online");
    // 2 calibration decisions per bulb, the fast timing: 8 trials of 5 rounds of 4 flashes.
    let mut online = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--serve", "127.0.0.1:0", "--calibrate"])
        .args(["--calibration-per-bulb", "2", "--paradigm", "fast"])
        .args(["--commands", "up,left", "--seed", "3"])
        .args(["--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let url = common::panel_urls(&mut stdout);
    let prefix = root().join("target/panel-throttle");
    let page = Command::new("node")
        .current_dir(root().join("tools/panel-test"))
        .env("CHROMIUM", &chromium)
        .arg("throttle.mjs")
        .args([&url.0, &url.1])
        .arg(&prefix)
        .output()
        .expect("node runs");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = online.wait().unwrap();
    let page_out = String::from_utf8_lossy(&page.stdout).into_owned();
    println!(
        "page: {page_out}\n{}\nsession:\n{rest}",
        String::from_utf8_lossy(&page.stderr)
    );
    assert!(page.status.success(), "the page checks failed");
    assert!(status.success(), "the session failed:\n{rest}");
    let seen: serde_json::Value = serde_json::from_str(
        page_out
            .lines()
            .find(|l| l.starts_with('{'))
            .expect("what the pages saw"),
    )
    .unwrap();
    // The calibration's epochs, as it reported them.
    let (trials, epochs): (usize, usize) = rest
        .lines()
        .find_map(|l| {
            let l = l.strip_prefix("calibration: ")?;
            let (t, l) = l.split_once(" decisions, ")?;
            let (e, _) = l.split_once(" epochs")?;
            Some((t.parse().ok()?, e.parse().ok()?))
        })
        .unwrap_or_else(|| panic!("no calibration line:\n{rest}"));
    assert_eq!(trials, 8, "{rest}");
    let scheduled = trials * 5 * 4;
    // The flashes the recording holds as drawn during calibration: those after a calibration
    // cue and before the first online one.
    let rec = oddball_io::read(out.join("session.xdf")).expect("the recording opens");
    let markers = &rec.xdf().expect("an XDF recording").markers;
    let mut calibrating = false;
    let mut drawn = 0;
    for m in markers {
        use oddball_io::xdf::session_markers::{parse_cue_marker, parse_flash_marker};
        if let Some((_, calibration)) = parse_cue_marker(&m.text) {
            calibrating = calibration;
        } else if calibrating && parse_flash_marker(&m.text).is_some() {
            drawn += 1;
        }
    }
    let undrawn = seen["faults"]["calibration_undrawn_flashes"]
        .as_u64()
        .expect("the operator view's fault counts") as usize;
    assert!(undrawn > 0, "the hidden tab left no flash undrawn: {seen}");
    assert_eq!(
        drawn + undrawn,
        scheduled,
        "every scheduled calibration flash is drawn or counted undrawn: {seen}"
    );
    assert!(
        epochs <= drawn,
        "calibration trained on {epochs} epochs of {drawn} drawn flashes ({undrawn} undrawn):\n{rest}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary["undrawn_flashes"].as_u64().unwrap() as usize >= undrawn,
        "{summary}"
    );
    // The hold is in the recording, as an operator's pause would be.
    let bytes = std::fs::read(out.join("session.xdf")).unwrap();
    for marker in [&b"pause"[..], b"resume"] {
        assert!(
            bytes.windows(marker.len()).any(|w| w == marker),
            "no {} marker in the recording",
            String::from_utf8_lossy(marker)
        );
    }
}
