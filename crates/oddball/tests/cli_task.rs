//! `oddball task track|draw` through the command line.

mod common;

fn tmp(name: &str) -> oddball_testkit::TempDir {
    oddball_testkit::TempDir::new(&format!("task-{name}"))
}

fn summary(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn tracking_ten_seeded_targets_reports_every_metric() {
    let dir = tmp("track");
    let (ok, out, err) = common::oddball(&["task", "track", "--out", dir.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("reached 10/10 targets"), "{out}");
    let s = summary(&dir);
    let targets = s["report"]["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 10);
    for t in targets {
        for key in [
            "success",
            "min_commands",
            "decisions",
            "wrong_moves",
            "path_efficiency",
            "time_to_target_s",
            "decisions_per_minute",
            "final_error_m",
        ] {
            assert!(!t[key].is_null(), "{key} missing in {t}");
        }
        assert!(t["final_error_m"].as_f64().unwrap() < 1e-3);
    }
    assert!(
        s["report"]["totals"]["itr"]["bits_per_minute"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    for f in [
        "task.png",
        "pen_trace.png",
        "erp.png",
        "decisions.csv",
        "model.json",
        "session.dat",
    ] {
        assert!(dir.join(f).exists(), "{f} written");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn drawing_hi_stays_within_a_millimetre() {
    let dir = tmp("draw");
    let (ok, out, err) = common::oddball(&[
        "task",
        "draw",
        "--draw",
        "HI",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("completed"), "{out}");
    let s = summary(&dir);
    assert!(s["report"]["completed"].as_bool().unwrap());
    assert!(s["report"]["max_deviation_m"].as_f64().unwrap() < 1e-3);
    // The drawing's own picture, beside the arm's.
    for f in ["task.png", "pen_trace.png"] {
        assert!(dir.join(f).exists(), "{f} written");
    }
    // Text the font lacks, and explicit targets that are not numbers, are clear errors.
    let (ok, _, err) = common::oddball(&[
        "task",
        "draw",
        "--draw",
        "H?",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("no glyph"), "{err}");
    let (ok, _, err) = common::oddball(&["task", "track", "--target", "0.3;0.1"]);
    assert!(!ok && err.contains("X,Z"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_replayed_subject_tracks_until_the_recording_runs_out() {
    let Some(data) = common::data_dir() else {
        return;
    };
    let dir = tmp("replay");
    let subject = format!(
        "replay:{}",
        data.join("bci2000-samplefiles-p300/eeg3_2.dat").display()
    );
    let (ok, out, err) = common::oddball(&[
        "task",
        "track",
        "--subject",
        &subject,
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let s = summary(&dir);
    // 24 replayable decisions: measured 8 targets reached before the data ran out.
    assert_eq!(
        s["report"]["totals"]["decisions"].as_u64().unwrap(),
        24,
        "{out}"
    );
    assert!(s["report"]["n_reached"].as_u64().unwrap() >= 4, "{out}");
    std::fs::remove_dir_all(&dir).ok();
}
