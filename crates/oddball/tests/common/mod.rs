//! Shared helpers of the CLI tests: where the real EEG is, and running the binary.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

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
