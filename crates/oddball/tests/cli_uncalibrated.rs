//! Sessions without calibration (`--calibration none`): the simulated typical subject steers the
//! arm from the first trial on while the unsupervised decoder learns from the session itself.

mod common;

use common::{oddball, tmp_dir};

#[test]
fn an_uncalibrated_demo_learns_within_ten_decisions() {
    let tmp = tmp_dir("cli-uncalibrated");
    let out = tmp.join("demo");
    // 40 decisions: up, left, down, right, … (the pen stays near its start).
    let commands = ["up", "left", "down", "right"].repeat(10).join(",");
    let (ok, text, err) = oddball(&[
        "demo",
        "--calibration",
        "none",
        "--commands",
        &commands,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(text.contains("calibration: none"), "{text}");
    // The session says which band its decoder learns from (not the paper's 1–15 Hz).
    assert!(
        text.contains("EEG band-passed 0.5–20 Hz causally"),
        "{text}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["calibration"]["trials"], 0, "no calibration trial");
    let rows = s["decisions"].as_array().unwrap();
    assert_eq!(rows.len(), 40);
    let right = |r: &serde_json::Value| r["decided"] == r["intended"] && !r["decided"].is_null();
    let late = rows[10..].iter().filter(|r| right(r)).count();
    // The aim: 27/30 (90 %). With EM started from the P300 template seeds 1–5 reach
    // 28, 30, 28, 28, 28 (from random starts alone: 28, 29, 26, 28, 29).
    assert!(
        late >= 27,
        "{late}/30 right after the first 10 decisions:\n{text}"
    );
    // The report shows the accuracy over time, 1–10, 11–20, …
    let stretches = s["accuracy_over_time"].as_array().unwrap();
    assert_eq!(stretches.len(), 4);
    assert_eq!(stretches[1]["first"], 11);
    assert!(text.contains("accuracy over time: 1–10 "), "{text}");
    // Every decision re-decided by the last fit: the early mistakes are corrected after the fact.
    let posthoc = s["posthoc_correct"].as_array().unwrap();
    assert_eq!(posthoc[1], 40);
    assert!(posthoc[0].as_u64().unwrap() >= late as u64 + 5, "{text}");
    assert!(
        text.contains("post hoc: the last unsupervised fit re-decides"),
        "{text}"
    );
    // No labelled epochs to draw; the model is the session's last unsupervised fit.
    assert!(!out.join("erp.png").exists());
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("model.json")).unwrap()).unwrap();
    assert!(model["coef"]["data"].as_array().unwrap().len() > 10);
    assert_eq!(model["trials"].as_array().unwrap().len(), 40);
}

#[test]
fn an_uncalibrated_session_draws_the_papers_g_from_the_first_trial() {
    // No calibration, no other person's model: EM starts from the P300 template.
    let tmp = tmp_dir("cli-uncalibrated-g");
    let out = tmp.join("g");
    let (ok, text, err) = oddball(&[
        "demo",
        "--calibration",
        "none",
        "--commands",
        "paper-g",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let rows = s["decisions"].as_array().unwrap();
    let wrong = rows
        .iter()
        .filter(|r| !r["decided"].is_null() && r["decided"] != r["intended"])
        .count();
    let right = rows
        .iter()
        .filter(|r| r["decided"] == r["intended"])
        .count();
    // The aim: at least 5 of the 6 strokes right (abstentions allowed). With learning
    // trials seeds 1, 2, 3, 5 draw 6/6 and seed 4 5/6 (without them seed 5 got 4/6).
    assert!(
        right >= 5 && wrong <= 1,
        "{right} right, {wrong} wrong:\n{text}"
    );
    // The first trial is a learning trial: 3 × the rule's 5 rounds.
    assert_eq!(rows[0]["rounds"], 15, "{text}");
    assert!(
        text.contains("the first trials run 3× the rounds"),
        "{text}"
    );
}

#[test]
fn a_transferred_model_lets_an_uncalibrated_session_draw_the_g() {
    let tmp = tmp_dir("cli-transfer");
    // Another simulated person (seed 2), calibrated with labels: the model to start from.
    let other = tmp.join("other");
    let (ok, _, err) = oddball(&["demo", "--seed", "2", "--out", other.to_str().unwrap()]);
    assert!(ok, "{err}");
    let model = other.join("model.json");
    for (commands, need) in [
        ("paper-g".to_string(), 5),
        (["up", "left", "down", "right"].repeat(10).join(","), 37),
    ] {
        let out = tmp.join("me");
        let args = vec![
            "demo",
            "--calibration",
            "none",
            "--transfer",
            model.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--commands",
            &commands,
        ];
        let (ok, text, err) = oddball(&args);
        assert!(ok, "{err}");
        assert!(text.contains("transfer: starting from"), "{text}");
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let correct = s["result"]["correct"].as_u64().unwrap();
        // The paper's G: at least 5 of its 6 strokes right; 40 decisions: at least 37 right.
        assert!(correct >= need, "{correct} right:\n{text}");
        // From another person's model there are no learning trials: every trial runs 5 rounds.
        let rows = s["decisions"].as_array().unwrap();
        assert!(rows.iter().all(|r| r["rounds"] == 5), "{text}");
        assert!(!text.contains("the first trials run"), "{text}");
    }
    let (ok, _, err) = oddball(&["demo", "--transfer", model.to_str().unwrap()]);
    assert!(!ok && err.contains("needs --calibration none"), "{err}");
    // A model trained offline (`oddball train`: zero-phase 0.5–20 Hz, 0.8 s epochs) starts a
    // session too: the session epochs as it was trained, the band run causally, as `--model`
    // runs it (measured: the G 6/6 on seeds 1, 3, 4 and 5; refused before).
    let trained = tmp.join("trained.json");
    let session = other.join("session.dat");
    let (ok, _, err) = oddball(&[
        "train",
        session.to_str().unwrap(),
        "-o",
        trained.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let out = tmp.join("from-trained");
    let (ok, text, err) = oddball(&[
        "demo",
        "--calibration",
        "none",
        "--transfer",
        trained.to_str().unwrap(),
        "--commands",
        "paper-g",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        text.contains("EEG band-passed 0.5–20 Hz causally"),
        "{text}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["result"]["correct"].as_u64().unwrap() >= 5, "{text}");
}

#[test]
fn calibration_none_is_checked_before_a_session_starts() {
    let (ok, _, err) = oddball(&[
        "demo",
        "--calibration",
        "none",
        "--subject",
        "replay:nowhere_2.dat",
    ]);
    assert!(!ok && err.contains("--calibration none"), "{err}");
    let (ok, _, err) = oddball(&["online", "--calibration", "none", "--model", "m.json"]);
    assert!(!ok && err.contains("not with --model"), "{err}");
    let (ok, _, err) = oddball(&["online"]);
    assert!(!ok && err.contains("--calibration none"), "{err}");
}

#[test]
fn online_adaptation_after_a_labelled_calibration_keeps_the_accuracy() {
    let tmp = tmp_dir("cli-adapt");
    let commands = ["up", "left", "down", "right"].repeat(10).join(",");
    let mut correct = Vec::new();
    for adapt in [false, true] {
        let out = tmp.join(if adapt { "adapt" } else { "static" });
        let mut args = vec![
            "demo",
            "--commands",
            &commands,
            "--out",
            out.to_str().unwrap(),
        ];
        if adapt {
            args.push("--adapt");
        }
        let (ok, text, err) = oddball(&args);
        assert!(ok, "{err}");
        assert_eq!(text.contains("online adaptation: "), adapt, "{text}");
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        correct.push(s["result"]["correct"].as_u64().unwrap());
    }
    // Seed 1, typical subject: 39/40 either way (the simulated person's ERP does not drift).
    assert!(correct[1] >= correct[0], "{correct:?}");
    for (bad, why) in [
        (vec!["--adapt", "--calibration", "none"], "adapts by itself"),
        (
            vec!["--adapt", "--pipeline", "riemann"],
            "needs --pipeline lda",
        ),
    ] {
        let (ok, _, err) = oddball(&[&["demo"], bad.as_slice()].concat());
        assert!(!ok && err.contains(why), "{err}");
    }
}
