//! The seed paper's own benchmark, BCI Competition II data set IIb (MATLAB files), through the
//! command line: inspect a training run, and score an unlabelled test run given its text.

mod common;

use common::{data_dir, oddball, tmp_dir};

#[test]
fn a_competition_run_inspects_and_an_unlabelled_test_run_scores_from_its_text() {
    let Some(d) = data_dir() else { return };
    let d = d.join("bci-competition-ii-iib");
    let run = |name: &str| d.join(name).to_str().unwrap().to_string();

    let (ok, out, err) = oddball(&["inspect", &run("AAS010R01.mat")]);
    assert!(ok, "{err}");
    for want in [
        "channels   64",
        "sfreq      240 Hz",
        "events     540",
        "90 target",
        "text       CAT",
    ] {
        assert!(out.contains(want), "no {want:?} in:\n{out}");
    }

    // The test run has no StimulusType: without its text it cannot be scored, and says how.
    let tmp = tmp_dir("cli-mat");
    let json = tmp.join("ham.json");
    let train = [run("AAS010R01.mat"), run("AAS010R02.mat")];
    let mut args = vec!["evaluate", "--train", &train[0], &train[1]];
    let test = run("AAS012R03.mat");
    args.extend(["--test", &test, "--pipeline", "lda"]);
    let (ok, _, err) = oddball(&args);
    assert!(!ok && err.contains("--test-text"), "{err}");
    let (ok, _, err) = oddball(&[args.as_slice(), &["--test-text", "HA"]].concat());
    assert!(
        !ok && err.contains("has 2 symbols but the recording has 3"),
        "{err}"
    );

    let (ok, out, err) = oddball(
        &[
            args.as_slice(),
            &["--test-text", "HAM", "--out", json.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v[0]["speller_text"], "HAM", "{out}");
    let auc = v[0]["auc"].as_f64().unwrap();
    assert!(auc > 0.85, "AUC {auc}: {out}");
}
