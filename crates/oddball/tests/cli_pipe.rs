//! `oddball inspect FILE… | head -1` exits 0: a reader that closes the pipe early is not an error
//! (println! would otherwise panic on the broken pipe and exit with 101).

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use oddball_testkit::TempDir;

#[test]
fn inspect_into_a_pipe_closed_after_one_line_exits_0() {
    let dir = TempDir::new("cli-pipe");
    // 400 long channel names: each summary is over 4 kB, so 100 of them overflow any pipe buffer
    // and the program is still writing when the pipe closes.
    let names: Vec<String> = (0..400)
        .map(|k| format!("channel_with_a_long_name_{k}"))
        .collect();
    let mut csv = format!("time,{}\n", names.join(","));
    for t in 0..8 {
        let row = vec!["1.5"; names.len()].join(",");
        csv.push_str(&format!("{},{row}\n", t as f64 / 100.0));
    }
    let file = dir.write("wide.csv", csv.as_bytes());
    let mut child = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .arg("inspect")
        .args(std::iter::repeat_n(&file, 100))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("oddball runs");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    // The reader (and with it the pipe) is dropped here, like `head -1` exiting.
    assert!(first.starts_with("wide.csv"), "{first}");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `oddball demo | head -1` (issue #20: it exited 101).
#[test]
fn demo_into_a_pipe_closed_after_one_line_exits_0() {
    let dir = TempDir::new("cli-pipe-demo");
    let mut child = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["demo", "--out"])
        .arg(dir.path().join("demo"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("oddball runs");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("oddball demo:"), "{first}");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}
