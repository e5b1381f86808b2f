//! `oddball train` / `oddball evaluate` on the real BCI2000 recordings (skipped when absent).

mod common;

use std::path::PathBuf;

use common::oddball;

fn data_dir() -> Option<PathBuf> {
    common::data_dir().map(|d| d.join("bci2000-samplefiles-p300"))
}

fn field<'a>(json: &'a serde_json::Value, key: &str) -> &'a serde_json::Value {
    json.get(key)
        .unwrap_or_else(|| panic!("no {key} in {json}"))
}

#[test]
fn speller_forward_split_spells_6mk_and_a_saved_model_scores_the_same() {
    let Some(d) = data_dir() else { return };
    let tmp = std::env::temp_dir().join(format!("oddball-decode-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let (train, test) = (d.join("eeg3_1.dat"), d.join("eeg3_2.dat"));
    let json = tmp.join("lda.json");
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        train.to_str().unwrap(),
        "--test",
        test.to_str().unwrap(),
        "--pipeline",
        "lda",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let r = &v[0];
    assert_eq!(field(r, "speller_text"), "6MK?", "{out}");
    let reps = field(r, "reps_for_all_correct")
        .as_u64()
        .expect("every character right at some point");
    assert!(
        reps <= 2,
        "shrinkage LDA spells all 4 characters within 2 repetitions: {out}"
    );
    let auc = field(r, "auc").as_f64().unwrap();
    assert!(auc > 0.92, "AUC {auc}");

    // Train, save, load, score: the same AUC.
    let model = tmp.join("model.json");
    let (ok, _, err) = oddball(&[
        "train",
        train.to_str().unwrap(),
        "--pipeline",
        "lda",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let json2 = tmp.join("loaded.json");
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        test.to_str().unwrap(),
        "--json",
        json2.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json2).unwrap()).unwrap();
    assert_eq!(field(&v2[0], "auc"), field(r, "auc"));
    assert_eq!(
        field(&v2[0], "speller_accuracy"),
        field(r, "speller_accuracy")
    );

    // A model of another channel layout is refused with the reason.
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        d.join("eeg2_1.dat").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("layout differs"), "{err}");
    let _ = std::fs::remove_dir_all(tmp);
}

#[test]
fn riemann_on_the_oddball_split_and_cross_validation() {
    let Some(d) = data_dir() else { return };
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        d.join("eeg2_1.dat").to_str().unwrap(),
        "--test",
        d.join("eeg2_2.dat").to_str().unwrap(),
        "--pipeline",
        "riemann",
    ]);
    assert!(ok, "{err}");
    let auc: f64 = out.split("AUC ").nth(1).unwrap()[..5].parse().unwrap();
    assert!(auc >= 0.97, "xDAWN + tangent space on eeg2 1->2: AUC {auc}");
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        d.join("eeg3_1.dat").to_str().unwrap(),
        "--pipeline",
        "lda",
        "--folds",
        "4",
    ]);
    assert!(ok, "{err}");
    let auc: f64 = out.split("AUC ").nth(1).unwrap()[..5].parse().unwrap();
    assert!(auc > 0.8, "4-fold CV on eeg3_1: AUC {auc}");
}
