//! Feedback on long work (issue #20): a real-time calibration says how far it is.

mod common;

use common::{oddball, tmp_dir};

/// A real-time calibration of eight short decisions (about 20 s) prints "calibration decision k
/// of 8" with the time left, and ends on the training line; an unpaced one, over in a second, does
/// not print them.
#[test]
fn a_real_time_calibration_prints_its_progress() {
    let dir = tmp_dir("progress-rt");
    let out = dir.path().join("rt");
    let (ok, stdout, err) = oddball(&[
        "demo",
        "--realtime",
        "--paradigm",
        "fast",
        "--flash-ms",
        "60",
        "--gap-ms",
        "60",
        "--cue-ms",
        "200",
        "--calibration-per-bulb",
        "2",
        "--commands",
        "up",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("calibration decision "))
        .collect();
    assert!(lines.len() >= 2, "{stdout}");
    assert!(
        lines
            .iter()
            .any(|l| l.contains(" of 8 ") && l.contains("left")),
        "{stdout}"
    );
    assert!(
        lines
            .last()
            .unwrap()
            .starts_with("calibration decision 8 of 8")
            && lines.last().unwrap().ends_with("training"),
        "{stdout}"
    );
    let unpaced = dir.path().join("fast");
    let (ok, stdout, err) = oddball(&[
        "demo",
        "--calibration-per-bulb",
        "2",
        "--commands",
        "up",
        "--out",
        unpaced.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(!stdout.contains("calibration decision "), "{stdout}");
}
