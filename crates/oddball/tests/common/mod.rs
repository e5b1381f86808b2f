//! Shared helpers of the CLI tests: where the real EEG is, and running the binary.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// `../shared/data` beside the checkout (or `ODDBALL_DATA`); `None`, with a message, when absent.
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("ODDBALL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        });
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: real EEG folder {} not found", dir.display());
        None
    }
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

/// A fresh temporary folder for one test (removed first if a previous run left it).
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("oddball-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A model fitted in a quick (unpaced) one-command demo session, for `oddball online`.
pub fn demo_model(dir: &std::path::Path) -> PathBuf {
    let out = dir.join("demo");
    let (ok, _, err) = oddball(&["demo", "--commands", "up", "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    out.join("model.json")
}
