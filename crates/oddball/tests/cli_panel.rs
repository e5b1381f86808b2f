//! The stimulus panel in a real browser: `oddball online --serve` with headless Chromium driven
//! by Playwright (tools/panel-test/panel.mjs). The page loads, counts down, flashes with on-times
//! of 100 ms within one frame, shows the decisions and moves the arm; a screenshot is saved
//! to target/panel-test.png. Meanwhile a second client sends malformed, oversized and binary
//! messages and disconnects: the server refuses them and the session goes on.
//!
//! Needs Chromium and Node with playwright-core: runs when ODDBALL_CHROMIUM names the browser
//! (CI: `apt-get install chromium`, `npm ci` in tools/panel-test), otherwise says it skips.

mod common;

use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Command, Stdio};

#[test]
fn the_panel_flashes_decides_and_moves_the_arm_in_chromium() {
    let Some(chromium) = std::env::var_os("ODDBALL_CHROMIUM") else {
        eprintln!("skipping the browser test: set ODDBALL_CHROMIUM=/usr/bin/chromium (and npm ci in tools/panel-test)");
        return;
    };
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let tool = root.join("tools/panel-test");
    assert!(
        tool.join("node_modules/playwright-core").is_dir(),
        "run `npm ci` in {}",
        tool.display()
    );
    let dir = std::env::temp_dir().join(format!("oddball-panel-{}", std::process::id()));
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--commands",
        "up",
        "--out",
        dir.join("demo").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
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
        .args(["--model", dir.join("demo/model.json").to_str().unwrap()])
        .args(["--out", dir.join("online").to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut stdout = BufReader::new(online.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    let url = first
        .trim()
        .strip_prefix("panel: ")
        .expect("panel line")
        .to_string();
    let shot = root.join("target/panel-test.png");
    let page = Command::new("node")
        .current_dir(&tool)
        .env("CHROMIUM", &chromium)
        .args(["panel.mjs", &url, shot.to_str().unwrap(), "2"])
        .output()
        .expect("node runs");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = online.wait().unwrap();
    let page_out = String::from_utf8_lossy(&page.stdout);
    let page_err = String::from_utf8_lossy(&page.stderr);
    println!("page: {page_out}\n{page_err}\noddball online:\n{first}{rest}");
    assert!(page.status.success(), "the page checks failed: {page_err}");
    assert!(status.success(), "oddball online failed:\n{rest}");
    assert!(shot.is_file());
    // The session heard the page: every flash stamped and timed; the rogue client refused.
    assert!(rest.contains("flash on-time 10"), "{rest}");
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
    assert!(rejected >= 3, "{rest}");
}

#[test]
fn the_panel_shows_a_tracking_task_and_its_target_in_chromium() {
    let Some(chromium) = std::env::var_os("ODDBALL_CHROMIUM") else {
        eprintln!("skipping the browser test: set ODDBALL_CHROMIUM=/usr/bin/chromium (and npm ci in tools/panel-test)");
        return;
    };
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let dir = std::env::temp_dir().join(format!("oddball-panel-task-{}", std::process::id()));
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
    let mut url = None;
    let mut head = String::new();
    for _ in 0..10 {
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        head.push_str(&line);
        if let Some(u) = line.trim().strip_prefix("panel: ") {
            url = Some(u.to_string());
            break;
        }
    }
    let url = url.unwrap_or_else(|| panic!("no panel line in:\n{head}"));
    let shot = root.join("target/panel-task.png");
    let page = Command::new("node")
        .current_dir(root.join("tools/panel-test"))
        .env("CHROMIUM", &chromium)
        .args(["panel.mjs", &url, shot.to_str().unwrap(), "2"])
        .output()
        .expect("node runs");
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).unwrap();
    let status = task.wait().unwrap();
    let page_out = String::from_utf8_lossy(&page.stdout);
    println!(
        "page: {page_out}\n{}\n{head}{rest}",
        String::from_utf8_lossy(&page.stderr)
    );
    assert!(page.status.success(), "the page checks failed");
    assert!(status.success(), "{rest}");
    assert!(
        page_out.contains("\"targets\":1"),
        "the page shows the target: {page_out}"
    );
    assert!(rest.contains("reached 1/1 targets"), "{rest}");
}
