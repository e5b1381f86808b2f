//! `oddball decode` without LSL: a recording played back with its own events as the stimulus
//! program's markers (`--markers recording`), the causal path the LSL runs are compared with.

mod common;

use std::path::Path;

use common::decode::{choices as text, decisions, decode_file, paradigm};
use common::{data_dir, oddball, oddball_ok, tmp_dir};

fn decode(file: &str, paradigm: &str, start: &[&str], extra: &[&str]) -> Vec<serde_json::Value> {
    decode_file(Path::new(file), paradigm, &[start, extra].concat())
}

#[test]
fn eeg3_spells_its_text_with_a_model_and_stops_early_with_the_same_characters() {
    let Some(d) = data_dir() else { return };
    let d = d.join("bci2000-samplefiles-p300");
    let tmp = tmp_dir("cli-decode-eeg3");
    let model = tmp.join("eeg3.json");
    let (train, test) = (d.join("eeg3_1.dat"), d.join("eeg3_2.dat"));
    oddball_ok(&[
        "train",
        train.to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
    ]);
    let p = paradigm("speller-6x6-rows-first.toml");
    let m = ["--model", model.to_str().unwrap()];
    let full = decode(test.to_str().unwrap(), &p, &m, &[]);
    assert_eq!(text(&full), "6MK?");
    for d in decisions(&full) {
        assert_eq!(d["flashes"], 180, "{d}");
        let p: f64 = d["posterior"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_f64().unwrap())
            .sum();
        assert!((p - 1.0).abs() < 1e-9, "{d}");
    }
    let fast = decode(test.to_str().unwrap(), &p, &m, &["--dynamic-stopping"]);
    assert_eq!(text(&fast), "6MK?");
    let used: u64 = decisions(&fast)
        .iter()
        .map(|d| d["flashes"].as_u64().unwrap())
        .sum();
    println!("dynamic stopping: {used} flashes for 4 characters (720 without)");
    assert!(used < 720 / 2, "{used}");
    // Each stop comes right before its trial's decision.
    for (i, v) in fast.iter().enumerate() {
        if v["type"] == "stop" {
            assert_eq!(fast[i + 1]["type"], "decision");
            assert_eq!(fast[i + 1]["trial"], v["trial"]);
        }
    }
}

/// A quick demo session of six commands (after its 40 calibration trials): the temporary
/// folder and the demo's report folder in it.
fn demo_session(tag: &str) -> (oddball_testkit::TempDir, std::path::PathBuf) {
    let tmp = tmp_dir(tag);
    let out = tmp.join("demo");
    oddball_ok(&[
        "demo",
        "--commands",
        "up,right,down,left,left,up",
        "--out",
        out.to_str().unwrap(),
    ]);
    (tmp, out)
}

#[test]
fn a_demo_session_played_as_a_foreign_four_choice_paradigm_decides_as_the_demo_did() {
    let (_tmp, out) = demo_session("cli-decode-demo");
    let session = out.join("session.dat");
    let model = out.join("model.json");
    let v = decode(
        session.to_str().unwrap(),
        &paradigm("four-bulb.toml"),
        &["--model", model.to_str().unwrap()],
        &[],
    );
    let csv = std::fs::read_to_string(out.join("decisions.csv")).unwrap();
    let demo: Vec<(String, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[2].to_string(), f[5].parse().unwrap())
        })
        .collect();
    let ds = decisions(&v);
    // The session's calibration trials come first (decided too: a foreign program's session
    // has no calibration phase oddball knows of); its online trials are the last ones.
    assert!(ds.len() > demo.len(), "{} decisions", ds.len());
    for (d, (decided, confidence)) in ds[ds.len() - demo.len()..].iter().zip(&demo) {
        assert_eq!(d["choice"].as_str().unwrap(), decided, "{d}");
        let p = d["posterior"][decided].as_f64().unwrap();
        assert!(
            (p - confidence).abs() < 1e-6,
            "{p} vs the demo's {confidence}"
        );
    }
}

/// In-stream calibration: the session's first 40 trials (its calibration, their flashes flagged
/// Target/NonTarget) fit the decoder, which then decides the rest as the demo's own model did.
#[test]
fn a_demo_session_calibrated_in_stream_decides_its_commands() {
    let (_tmp, out) = demo_session("cli-decode-calibrate");
    let session = out.join("session.dat");
    let v = decode(
        session.to_str().unwrap(),
        &paradigm("four-bulb.toml"),
        &["--calibration", "40"],
        &[],
    );
    let calibrated = v
        .iter()
        .find(|o| o["type"] == "calibrated")
        .expect("a calibration");
    assert_eq!(calibrated["trials"], 40, "{calibrated}");
    assert_eq!(calibrated["epochs"], 40 * 20, "{calibrated}");
    assert!(calibrated["cv_auc"].as_f64().unwrap() > 0.8, "{calibrated}");
    let ds = decisions(&v);
    let choices: Vec<&str> = ds.iter().map(|d| d["choice"].as_str().unwrap()).collect();
    assert_eq!(choices, ["up", "right", "down", "left", "left", "up"]);
    assert_eq!(ds[0]["trial"], 41);
}

#[test]
fn a_broken_paradigm_or_a_wrong_start_is_refused_before_any_stream() {
    let tmp = tmp_dir("cli-decode-refused");
    let bad = tmp.join("bad.toml");
    std::fs::write(
        &bad,
        "name = \"x\"\n[choices]\nlabels = [\"a\", \"b\"]\ncodes = [1, 1]\n[markers]\nflash = \"{code}\"\ntrial_end = \"end\"\n",
    )
    .unwrap();
    let (ok, _, err) = oddball(&[
        "decode",
        "--source",
        "lsl:nobody-streams-this",
        "--paradigm",
        bad.to_str().unwrap(),
        "--calibration",
        "none",
    ]);
    assert!(!ok);
    assert!(
        err.contains("choices.codes") && err.contains("listed twice"),
        "{err}"
    );
    let (ok, _, err) = oddball(&[
        "decode",
        "--source",
        "lsl:nobody-streams-this",
        "--paradigm",
        &paradigm("four-bulb.toml"),
    ]);
    assert!(!ok);
    assert!(
        err.contains("--calibration") || err.contains("--model"),
        "{err}"
    );
}

/// Without calibration, a recording's characters as `decode` decides them online are the ones
/// `evaluate --unsupervised --causal` decides online from the file: the same unsupervised
/// refits, on the same causally band-passed epochs.
#[test]
fn without_calibration_decode_decides_as_evaluate_unsupervised_causal() {
    let Some(d) = data_dir() else { return };
    let file = d.join("bci2000-samplefiles-p300/eeg3_2.dat");
    let f = file.to_str().unwrap();
    let v = decode(
        f,
        &paradigm("speller-6x6-rows-first.toml"),
        &["--calibration", "none"],
        &[],
    );
    let best: String = decisions(&v)
        .iter()
        .map(|d| d["best"].as_str().unwrap().to_string())
        .collect();
    let out = oddball_ok(&["evaluate", "--unsupervised", "--causal", "--test", f]);
    let online = out
        .split("online ")
        .nth(1)
        .and_then(|s| s.split('(').nth(1))
        .and_then(|s| s.split(')').next())
        .unwrap_or_else(|| panic!("{out}"));
    assert_eq!(best, online, "{out}");
}
