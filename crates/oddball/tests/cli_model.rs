//! One model offline and live: a model `oddball train` fits from a session's recording decides
//! in `demo`, `task` and `online` without calibration; a live recording carries its flashes'
//! flags, so it inspects, trains and evaluates like any labelled file, and replayed with its own
//! model it gives the live run's decisions exactly (its calibration passed over, not played).

mod common;

use std::path::Path;

fn tmp(name: &str) -> oddball_testkit::TempDir {
    common::tmp_dir(&format!("model-{name}"))
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json written");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// At least 5 of every 6 decisions of the run in `dir` right.
fn mostly_right(dir: &Path) -> bool {
    let s = summary(dir);
    let n = s["result"]["decisions"].as_u64().unwrap();
    n > 0 && 6 * s["result"]["correct"].as_u64().unwrap() >= 5 * n
}

/// `evaluate --model … --test session` found every online decision identical.
fn all_identical(stdout: &str) -> bool {
    stdout.lines().any(|l| {
        let mut w = l.split_whitespace();
        match (w.next(), w.next(), w.next(), w.next(), w.next()) {
            (Some(n), Some("online"), Some("decisions:"), Some(m), Some("identical")) => {
                n == m.trim_end_matches(',') && n != "0"
            }
            _ => false,
        }
    })
}

fn decisions(stdout: &str) -> Vec<&str> {
    stdout
        .lines()
        .filter(|l| l.starts_with("decision "))
        .collect()
}

#[test]
fn a_model_trained_offline_decides_in_demo_task_and_online_without_calibration() {
    let dir = tmp("offline");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let m = dir.join("m.json");
    common::oddball_ok(&["demo", "--out", a.to_str().unwrap()]);
    let out = common::oddball_ok(&[
        "train",
        a.join("session.dat").to_str().unwrap(),
        "--pipeline",
        "lda",
        "-o",
        m.to_str().unwrap(),
    ]);
    assert!(
        out.contains("decision models from 5-fold cross-validated scores"),
        "{out}"
    );
    // The file carries the decision model and the causal fit a session runs.
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    assert_eq!(model["format_version"], 4);
    assert!(model["decision"]["scores"]["std"].as_f64().unwrap() > 0.0);
    assert_eq!(model["preprocess"]["causal"], false);
    assert_eq!(model["live"]["preprocess"]["causal"], true);
    assert!(model["live"]["decision"].is_object());

    let out = common::oddball_ok(&[
        "demo",
        "--model",
        m.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(out.contains("no calibration"), "{out}");
    assert!(!out.contains("calibration: 10 decisions"), "{out}");
    let s = summary(&b);
    let n = s["commands"].as_array().unwrap().len();
    assert_eq!(decisions(&out).len(), n, "{out}");
    assert_eq!(s["calibration"]["trials"], 0, "{s}");
    let right = s["result"]["correct"].as_u64().unwrap() as usize;
    assert!(
        6 * right >= 5 * n,
        "{right}/{n} right from the offline model: {out}"
    );
    // The model the session ran (its causal fit) re-decides the session's own recording.
    let out = common::oddball_ok(&[
        "evaluate",
        "--model",
        b.join("model.json").to_str().unwrap(),
        "--test",
        b.join("session.dat").to_str().unwrap(),
    ]);
    assert!(
        out.contains(&format!(
            "{n} online decisions: {n} identical to the recorded ones"
        )),
        "{out}"
    );

    // task takes it too.
    let out = common::oddball_ok(&[
        "task",
        "track",
        "--targets",
        "1",
        "--model",
        m.to_str().unwrap(),
        "--out",
        dir.join("task").to_str().unwrap(),
    ]);
    assert!(out.contains("no calibration"), "{out}");

    // A model saved before format 4 has no decision model: refused with what fixes it, before
    // any EEG work.
    let mut old = model.clone();
    old["format_version"] = 3.into();
    old.as_object_mut().unwrap().remove("decision");
    old.as_object_mut().unwrap().remove("live");
    let old_path = dir.join("old.json");
    std::fs::write(&old_path, old.to_string()).unwrap();
    for cmd in ["demo", "online"] {
        let (ok, out, err) = common::oddball(&[
            cmd,
            "--model",
            old_path.to_str().unwrap(),
            "--out",
            dir.join("old").to_str().unwrap(),
        ]);
        assert!(!ok, "{out}");
        assert!(
            err.contains("no decision model")
                && err.contains("oddball train")
                && err.contains("--calibrate"),
            "{err}"
        );
        assert!(!out.contains("decision 1"), "{out}");
    }
}

#[test]
fn a_live_recording_evaluates_trains_and_replays_to_the_same_decisions() {
    let dir = tmp("live");
    let (live, again) = (dir.join("live"), dir.join("again"));
    // A short live session (paced by the wall clock: ~55 s): 8 calibration trials, 3 commands.
    let common_args = [
        "--paradigm",
        "fast",
        "--seed",
        "5",
        "--commands",
        "up,left,down",
    ];
    let mut args = vec![
        "online",
        "--calibrate",
        "--calibration-per-bulb",
        "2",
        "--sim-latency-ms",
        "20",
        "--out",
        live.to_str().unwrap(),
    ];
    args.extend(common_args);
    let recorded = common::oddball_ok(&args);
    let recorded_decisions = decisions(&recorded);
    assert_eq!(recorded_decisions.len(), 3, "{recorded}");
    let xdf = live.join("session.xdf");
    let model = live.join("model.json");

    // The recording's flashes carry their flags: 8 calibration + 3 online trials of 5 rounds.
    let out = common::oddball_ok(&["inspect", xdf.to_str().unwrap()]);
    assert!(
        out.contains("targets    55 target, 165 non-target"),
        "{out}"
    );
    // It evaluates with its model: every online decision recomputed, the same.
    let out = common::oddball_ok(&[
        "evaluate",
        "--test",
        xdf.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
    ]);
    assert!(
        out.contains("3 online decisions: 3 identical to the recorded ones"),
        "{out}"
    );
    // It trains like any labelled file.
    common::oddball_ok(&[
        "train",
        xdf.to_str().unwrap(),
        "-o",
        dir.join("m.json").to_str().unwrap(),
    ]);

    // Replayed with its model, as fast as it goes: the calibration passed over, the same
    // decisions (choice, posterior, rounds, time), every flash on a flash of the file.
    let file = format!("replay:{}", xdf.display());
    let mut args = vec![
        "online",
        "--model",
        model.to_str().unwrap(),
        "--source",
        &file,
        "--fast",
        "--out",
        again.to_str().unwrap(),
    ];
    args.extend(common_args);
    let replayed = common::oddball_ok(&args);
    assert!(
        replayed.contains("passing over the recording's calibration: 8 trials"),
        "{replayed}"
    );
    assert_eq!(decisions(&replayed), recorded_decisions, "{replayed}");
    assert!(
        replayed
            .contains("replay: 60 of 60 flashes of this session fall on a flash of the same bulb"),
        "{replayed}"
    );
}

#[test]
fn a_session_picks_a_models_channels_by_name_and_a_montage_renames_them() {
    let dir = tmp("channels");
    let a = dir.join("a");
    common::oddball_ok(&["demo", "--commands", "up", "--out", a.to_str().unwrap()]);
    let session = a.join("session.dat");
    // A model of 4 of the 8 channels, in another order: the session epochs just those.
    let m4 = dir.join("m4.json");
    common::oddball_ok(&[
        "train",
        session.to_str().unwrap(),
        "--channels",
        "Pz,Cz,Oz,PO8",
        "-o",
        m4.to_str().unwrap(),
    ]);
    let b = dir.join("b");
    let out = common::oddball_ok(&[
        "demo",
        "--model",
        m4.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(out.contains("4 channels at 500 Hz"), "{out}");
    assert!(mostly_right(&b), "{out}");
    let out = common::oddball_ok(&[
        "evaluate",
        "--model",
        b.join("model.json").to_str().unwrap(),
        "--test",
        b.join("session.dat").to_str().unwrap(),
    ]);
    assert!(all_identical(&out), "{out}");

    // A montage renames every channel: a model trained under those names needs them in the
    // session too, and says so when they are missing.
    let loc = dir.join("a8.loc");
    let text: String = (1..=8).map(|i| format!("{i}\t0\t0.1\tA{i}..\n")).collect();
    std::fs::write(&loc, text).unwrap();
    let m8 = dir.join("m8.json");
    common::oddball_ok(&[
        "train",
        session.to_str().unwrap(),
        "--montage",
        loc.to_str().unwrap(),
        "-o",
        m8.to_str().unwrap(),
    ]);
    let c = dir.join("c");
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--model",
        m8.to_str().unwrap(),
        "--out",
        c.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("no channel named [\"A1\"") && err.contains("--montage"),
        "{err}"
    );
    // Issue #30: an online session that fails to start leaves no empty recording behind.
    let d = dir.join("d");
    let (ok, _, err) = common::oddball(&[
        "online",
        "--model",
        m8.to_str().unwrap(),
        "--fast",
        "--source",
        &format!("replay:{}", session.display()),
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("no channel named"), "{err}");
    assert!(
        !d.join("session.xdf").exists(),
        "an empty recording was left"
    );
    let out = common::oddball_ok(&[
        "demo",
        "--model",
        m8.to_str().unwrap(),
        "--montage",
        loc.to_str().unwrap(),
        "--out",
        c.to_str().unwrap(),
    ]);
    assert!(mostly_right(&c), "{out}");
    let out = common::oddball_ok(&["inspect", c.join("session.dat").to_str().unwrap()]);
    assert!(out.contains("channels   8: A1 A2 A3"), "{out}");
}

#[test]
fn a_model_at_another_rate_runs_on_a_stream_resampled_as_it_streams() {
    let dir = tmp("rate");
    let a = dir.join("a");
    common::oddball_ok(&["demo", "--commands", "up", "--out", a.to_str().unwrap()]);
    // A model at 256 Hz from the 500 Hz session (resampled offline, polyphase).
    let m = dir.join("m256.json");
    common::oddball_ok(&[
        "train",
        a.join("session.dat").to_str().unwrap(),
        "--resample",
        "256",
        "-o",
        m.to_str().unwrap(),
    ]);
    let b = dir.join("b");
    let out = common::oddball_ok(&[
        "demo",
        "--model",
        m.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(
        out.contains("resampling the stream from 500 Hz to the model's 256 Hz as it streams"),
        "{out}"
    );
    assert!(mostly_right(&b), "{out}");
    // The session ran, and recorded, at the model's rate: its recording re-decides the same.
    let out = common::oddball_ok(&["inspect", b.join("session.dat").to_str().unwrap()]);
    assert!(out.contains("sfreq      256 Hz"), "{out}");
    let out = common::oddball_ok(&[
        "evaluate",
        "--model",
        b.join("model.json").to_str().unwrap(),
        "--test",
        b.join("session.dat").to_str().unwrap(),
    ]);
    assert!(all_identical(&out), "{out}");
}
