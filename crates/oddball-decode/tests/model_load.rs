//! Saved models (`Model::from_json`): every preset round-trips, and damaged or hostile JSON is an
//! error, never a panic. Inputs the `model` fuzz target (`fuzz/`) found are kept here.
//!
//! `write_model_seeds` also writes the fuzz target's seed corpus when `ODDBALL_MODEL_SEED_DIR`
//! is set (`fuzz/seed.sh` does this).

use ndarray::Array3;
use oddball_decode::decision::{DecisionModel, DecisionRule, ScoreModel};
use oddball_decode::pipeline::{Model, PipelineParams, Preprocess, PRESETS};
use oddball_decode::DecodeError;

/// Synthetic epochs `(n_epochs, 4, 64)` at 64 Hz: a deterministic pseudo-random noise, a 10 Hz
/// sine and, on every fifth epoch (the targets), a bump at 300 ms growing with the channel.
fn synthetic(n_epochs: usize, seed: u64) -> (Array3<f64>, Vec<bool>) {
    oddball_testkit::synthetic_p300(n_epochs, seed, 5, 0, 4.0, 3.0)
}

/// A saved model of every preset (the last two with a decision model), as `(name, JSON)`.
fn preset_models() -> Vec<(String, String)> {
    let (x, y) = synthetic(60, 7);
    PRESETS
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let pipeline = PipelineParams::preset(name, 64.0)
                .unwrap()
                .fit(x.view(), &y)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let names = ["Fz", "Cz", "Pz", "Oz"].map(String::from).to_vec();
            let mut model = Model::new(Preprocess::online(), 64.0, names, pipeline);
            if i % 2 == 1 {
                model.decision = Some(DecisionModel {
                    scores: ScoreModel {
                        mean_target: 1.0,
                        mean_nontarget: -0.5,
                        std: 0.75,
                    },
                    rule: if i == 1 {
                        DecisionRule::Fixed { rounds: 10 }
                    } else {
                        DecisionRule::dynamic(8)
                    },
                });
            }
            (name.to_string(), model.to_json())
        })
        .collect()
}

#[test]
fn write_model_seeds() {
    let models = preset_models();
    for (name, json) in &models {
        let back = Model::from_json(json).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            &back.to_json(),
            json,
            "{name}: a loaded model saves the same"
        );
    }
    if let Some(dir) = std::env::var_os("ODDBALL_MODEL_SEED_DIR") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        for (name, json) in &models {
            std::fs::write(dir.join(format!("{name}.json")), json).unwrap();
        }
        // Small hand-made ones too: other versions, wrong types, deep nesting.
        let small: [(&str, &str); 4] = [
            ("version_only", r#"{"format_version":1}"#),
            ("version_2", r#"{"format_version":2,"sfreq":1}"#),
            ("version_null", r#"{"format_version":null}"#),
            (
                "nested",
                r#"{"format_version":1,"pipeline":[[[[{"a":[1e308,-0.0]}]]]]}"#,
            ),
        ];
        for (name, json) in small {
            std::fs::write(dir.join(format!("{name}.json")), json).unwrap();
        }
        eprintln!(
            "wrote {} model seeds to {}",
            models.len() + 4,
            dir.display()
        );
    }
}

#[test]
fn damaged_models_are_errors() {
    for text in [
        "",
        "{",
        "[]",
        "null",
        r#"{"format_version":-1}"#,
        r#"{"format_version":4294967296}"#,
        r#"{"format_version":1}"#,
        r#"{"format_version":1,"sfreq":"x"}"#,
    ] {
        assert!(Model::from_json(text).is_err(), "{text:?} loads");
    }
    assert!(matches!(
        Model::from_json(r#"{"format_version":7}"#),
        Err(DecodeError::ModelVersion { found: Some(7), .. })
    ));
    // Deep nesting hits serde_json's recursion limit, not the stack.
    let deep = format!(
        r#"{{"format_version":1,"x":{}{}}}"#,
        "[".repeat(100_000),
        "]".repeat(100_000)
    );
    assert!(Model::from_json(&deep).is_err());
}
