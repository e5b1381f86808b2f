//! Recordings whose markers are plain codes: the event mapping on the command line
//! (`--target-events` / `--nontarget-events`, MNE's `event_id`).

mod common;

use std::fmt::Write as _;
use std::path::Path;

use common::{oddball, tmp_dir};

/// A 16-channel CSV at 256 Hz (`time` column, `stim` markers): 240 flashes every 0.4 s, every
/// fifth marked 2 (target, with a 2 µV P300-like bump 300–500 ms later on every channel), the
/// others 1; noise from a fixed linear congruential generator.
fn write_csv(path: &Path) {
    let sfreq = 256.0;
    let n_flash = 240;
    let step = (0.4 * sfreq) as usize;
    let n_times = 256 + n_flash * step + 256;
    let mut markers = vec![0u32; n_times];
    for k in 0..n_flash {
        markers[256 + k * step] = if k % 5 == 2 { 2 } else { 1 };
    }
    let mut state: u64 = 12345;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10.0
    };
    let mut text = String::from("time");
    for c in 0..16 {
        let _ = write!(text, ",ch{c}");
    }
    text.push_str(",stim\n");
    let mut bump = vec![0.0f64; n_times];
    for (i, m) in markers.iter().enumerate() {
        if *m == 2 {
            let (a, b) = (i + (0.3 * sfreq) as usize, i + (0.5 * sfreq) as usize);
            for (j, v) in bump.iter_mut().enumerate().take(b.min(n_times)).skip(a) {
                let x = (j - a) as f64 / (b - a) as f64;
                *v += 2.0 * (std::f64::consts::PI * x).sin();
            }
        }
    }
    for i in 0..n_times {
        let _ = write!(text, "{:.6}", i as f64 / sfreq);
        for _ in 0..16 {
            let _ = write!(text, ",{:.4}", noise() + bump[i]);
        }
        let _ = writeln!(text, ",{}", markers[i]);
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn plain_codes_train_and_evaluate_once_the_mapping_says_which_are_targets() {
    let dir = tmp_dir("cli-events");
    let csv = dir.path().join("codes.csv");
    write_csv(&csv);
    let csv = csv.to_str().unwrap();

    // Without a mapping: the error names the codes present and the options that label them.
    let (ok, _, err) = oddball(&["evaluate", "--train", csv, "--folds", "3"]);
    assert!(!ok);
    assert!(
        err.contains("none is labelled") && err.contains("--target-events"),
        "{err}"
    );
    assert!(
        err.contains("code 1 ×192") && err.contains("code 2 ×48"),
        "{err}"
    );

    // With it: cross-validation finds the bump.
    let json = dir.path().join("cv.json");
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        csv,
        "--folds",
        "3",
        "--target-events",
        "2",
        "--nontarget-events",
        "1",
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let auc = v[0]["auc"].as_f64().unwrap();
    assert!(auc > 0.8, "AUC {auc}: {out}");

    // A half-given or contradictory mapping is refused before any work; a whole one trains.
    let (ok, _, err) = oddball(&["train", csv, "--target-events", "2", "-o", "x.json"]);
    assert!(!ok && err.contains("--nontarget-events"), "{err}");
    let (ok, _, err) = oddball(&[
        "train",
        csv,
        "--target-events",
        "2",
        "--nontarget-events",
        "2,1",
        "-o",
        "x.json",
    ]);
    assert!(!ok && err.contains("both as a target"), "{err}");
    let model = dir.path().join("m.json");
    let (ok, _, err) = oddball(&[
        "train",
        csv,
        "--target-events",
        "2",
        "--nontarget-events",
        "1",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(model.is_file());
}
