//! What the `oddball decode` tests share: the paradigm files, the JSON lines, a decode run from
//! a file without LSL.

use std::path::{Path, PathBuf};

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A shipped paradigm file (`paradigms/NAME`).
pub fn paradigm(name: &str) -> String {
    repo()
        .join("paradigms")
        .join(name)
        .to_str()
        .unwrap()
        .to_string()
}

/// The JSON lines of a decode run's output.
pub fn json_lines(text: &str) -> Vec<serde_json::Value> {
    text.lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect()
}

/// The decisions among a run's messages.
pub fn decisions(v: &[serde_json::Value]) -> Vec<serde_json::Value> {
    v.iter()
        .filter(|d| d["type"] == "decision")
        .cloned()
        .collect()
}

/// The chosen labels, `-` for an abstention.
pub fn choices(v: &[serde_json::Value]) -> String {
    decisions(v)
        .iter()
        .map(|d| d["choice"].as_str().unwrap_or("-").to_string())
        .collect()
}

/// What `oddball decode` decides from `file` itself: its own events as the markers, no LSL.
pub fn decode_file(file: &Path, paradigm: &str, args: &[&str]) -> Vec<serde_json::Value> {
    let source = format!("replay:{}", file.display());
    let mut all = vec![
        "decode",
        "--source",
        &source,
        "--markers",
        "recording",
        "--paradigm",
        paradigm,
        "--fast",
        "--outlet",
        "none",
    ];
    all.extend(args);
    json_lines(&super::oddball_ok(&all))
}
