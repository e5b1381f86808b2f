//! Recordings whose markers are plain codes: the event mapping on the command line
//! (`--target-events` / `--nontarget-events`, MNE's `event_id`).

mod common;

use common::{oddball, tmp_dir, write_csv};

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
