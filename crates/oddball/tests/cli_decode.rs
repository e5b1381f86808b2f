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
    let tmp = oddball_testkit::TempDir::new("decode");
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
    let v2 = evaluate_saved_model(&model, &test, &tmp.join("loaded.json"));
    assert_eq!(field(&v2[0], "auc"), field(r, "auc"));
    assert_eq!(
        field(&v2[0], "speller_accuracy"),
        field(r, "speller_accuracy")
    );

    // A file without the model's channel names is refused naming them and the option that
    // fixes it; named by BCI2000's montage, its channels are picked and it is resampled from
    // 160 to 256 Hz (polyphase) to meet the model.
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        d.join("eeg2_1.dat").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("without [\"Fz\", \"Cz\"") && err.contains("--montage"),
        "{err}"
    );
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        d.join("eeg2_1.dat").to_str().unwrap(),
        "--montage",
        d.join("eeg64.loc").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("resampled from 160 Hz to 256 Hz (polyphase)"),
        "{err}"
    );
    assert!(out.contains("AUC"), "{out}");
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

fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `oddball evaluate --model MODEL --test TEST --json JSON`, its JSON.
fn evaluate_saved_model(
    model: &std::path::Path,
    test: &std::path::Path,
    json: &std::path::Path,
) -> serde_json::Value {
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        test.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    read_json(json)
}

/// A copy of `src` written as float32 BCI2000, its target flags flipped when `flip` is set.
fn rewrite(src: &std::path::Path, dst: &std::path::Path, flip: bool) {
    use oddball_signal::{Event, Events};
    let mut rec = oddball_io::read(src).unwrap();
    let events: Vec<Event> = rec
        .raw
        .events()
        .iter()
        .map(|e| Event {
            target: e.target.map(|t| t != flip),
            ..e.clone()
        })
        .collect();
    rec.raw.set_events(Events::new(events)).unwrap();
    let states = oddball_io::stimulus_states(rec.raw.events(), rec.raw.n_times(), 8);
    oddball_io::write_bci2000(
        dst,
        &rec.raw,
        &states,
        &oddball_io::Bci2000WriteOptions::default(),
    )
    .unwrap();
}

#[test]
fn tuning_never_sees_the_test_file_flipped_test_labels_give_the_same_choice() {
    let Some(d) = data_dir() else { return };
    let tmp = oddball_testkit::TempDir::new("tune");
    let (same, flipped) = (tmp.join("same.dat"), tmp.join("flipped.dat"));
    rewrite(&d.join("eeg2_2.dat"), &same, false);
    rewrite(&d.join("eeg2_2.dat"), &flipped, true);
    let run = |test: &std::path::Path, json: &std::path::Path| {
        let plot = tmp.join("acc.png");
        let (ok, out, err) = oddball(&[
            "evaluate",
            "--train",
            d.join("eeg2_1.dat").to_str().unwrap(),
            "--test",
            test.to_str().unwrap(),
            "--pipeline",
            "mdm",
            "--tune",
            "--folds",
            "3",
            "--plot",
            plot.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        // No progress bar (nor anything else) on stderr when it is not a terminal.
        assert!(common::without_progress(&err).is_empty(), "stderr: {err}");
        assert!(!plot.exists(), "no plot for a non-speller test file");
        assert!(out.contains("no accuracy-vs-repetitions plot"), "{out}");
        assert_eq!(out.matches("CV AUC").count(), 3, "{out}");
        assert!(out.contains("folds stratified by label"), "{out}");
        read_json(json)
    };
    let a = run(&same, &tmp.join("a.json"));
    let b = run(&flipped, &tmp.join("b.json"));
    let tuning = field(&a[0], "tuning");
    assert_eq!(field(tuning, "n_folds"), 3);
    assert_eq!(field(tuning, "candidates").as_array().unwrap().len(), 3);
    // The choice and every cross-validated score are the same whatever the test labels …
    assert_eq!(tuning, field(&b[0], "tuning"));
    // … while the test scores do see them: the AUC flips.
    let (auc_a, auc_b) = (
        field(&a[0], "auc").as_f64().unwrap(),
        field(&b[0], "auc").as_f64().unwrap(),
    );
    assert!(auc_a > 0.9, "mdm on eeg2 1->2: AUC {auc_a}");
    assert!((auc_a + auc_b - 1.0).abs() < 1e-12, "{auc_a} + {auc_b}");
    let _ = std::fs::remove_dir_all(tmp);
}

#[test]
fn train_tune_saves_the_choice_and_evaluate_plots_accuracy_by_repetitions() {
    let Some(d) = data_dir() else { return };
    let tmp = oddball_testkit::TempDir::new("tune-lda");
    let (train, test) = (d.join("eeg3_1.dat"), d.join("eeg3_2.dat"));
    let model = tmp.join("model.json");
    let (ok, out, err) = oddball(&[
        "train",
        train.to_str().unwrap(),
        "--pipeline",
        "lda",
        "--tune",
        "--folds",
        "4",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(common::without_progress(&err).is_empty(), "stderr: {err}");
    assert!(
        out.contains("4-fold CV on the training data (folds keep speller characters whole)"),
        "{out}"
    );
    let m = read_json(&model);
    let tuning = field(&m, "tuning");
    let chosen = field(tuning, "chosen").as_str().unwrap();
    assert!(out.contains(&format!("chosen: {chosen}")), "{out}");
    assert_eq!(field(tuning, "grouped"), true);
    // The saved pipeline carries the chosen bin width.
    let bin = field(
        field(
            field(field(field(&m, "pipeline"), "params"), "features"),
            "Amplitude",
        ),
        "reduction",
    )["BinMean"]["bin"]
        .as_u64()
        .unwrap();
    assert!(
        chosen.starts_with(&format!("bin {bin} samples")),
        "{chosen}"
    );

    // evaluate --tune makes the same choice, and scores like the saved model.
    let (json, plot) = (tmp.join("eval.json"), tmp.join("acc.svg"));
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        train.to_str().unwrap(),
        "--test",
        test.to_str().unwrap(),
        "--pipeline",
        "lda",
        "--tune",
        "--folds",
        "4",
        "--plot",
        plot.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(common::without_progress(&err).is_empty(), "stderr: {err}");
    let e = read_json(&json);
    assert_eq!(field(&e[0], "tuning"), tuning, "{out}");
    assert_eq!(field(&e[0], "speller_choices"), 36);
    let acc = field(&e[0], "speller_accuracy").as_array().unwrap();
    assert_eq!(acc.len(), 15);
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.contains("chance (1/36"), "the chance level is marked");
    assert!(
        svg.lines().any(|l| l.trim() == "lda"),
        "one line per preset, in the legend"
    );
    let l = evaluate_saved_model(&model, &test, &tmp.join("loaded.json"));
    assert_eq!(field(&l[0], "auc"), field(&e[0], "auc"));
    assert_eq!(field(&l[0], "tuning"), tuning);

    // Without test files the tuning is nested inside each cross-validation fold.
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        train.to_str().unwrap(),
        "--pipeline",
        "lda",
        "--tune",
        "--folds",
        "4",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let cv = read_json(&json);
    let per_fold = field(&cv[0], "tuning_per_fold").as_array().unwrap();
    assert_eq!(per_fold.len(), 4, "{out}");
    assert!(per_fold.iter().all(|t| field(t, "n_folds") == 3));
    assert!(field(&cv[0], "auc").as_f64().unwrap() > 0.8, "{out}");
    let _ = std::fs::remove_dir_all(tmp);
}

#[test]
fn mdm_preset_spells_the_speller_split() {
    let Some(d) = data_dir() else { return };
    let tmp = oddball_testkit::TempDir::new("mdm");
    let json = tmp.join("mdm.json");
    let (ok, out, err) = oddball(&[
        "evaluate",
        "--train",
        d.join("eeg3_1.dat").to_str().unwrap(),
        "--test",
        d.join("eeg3_2.dat").to_str().unwrap(),
        "--pipeline",
        "mdm",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v = read_json(&json);
    assert_eq!(field(&v[0], "speller_text"), "6MK?", "{out}");
    let auc = field(&v[0], "auc").as_f64().unwrap();
    assert!(auc > 0.88, "XdawnCovariances + MDM on eeg3 1->2: AUC {auc}");
    let reps = field(&v[0], "reps_for_all_correct").as_u64().unwrap();
    assert!(reps <= 4, "{out}");
    let _ = std::fs::remove_file(json);
}

/// The fusion of shrinkage LDA and xDAWN + tangent space: every character of eeg3_2 within 2
/// repetitions when trained on eeg3_1, and of eeg3_1 within 3 when trained on eeg3_2 (every peer
/// pipeline needs 4 there); a saved fused model scores the same.
#[test]
fn lda_riemann_fusion_spells_both_directions_in_2_and_3_repetitions() {
    let Some(d) = data_dir() else { return };
    let tmp = common::tmp_dir("decode-fusion");
    std::fs::create_dir_all(&tmp).unwrap();
    for (train, test, text, most) in [
        ("eeg3_1.dat", "eeg3_2.dat", "6MK?", 2),
        ("eeg3_2.dat", "eeg3_1.dat", "T3OF", 3),
    ] {
        let json = tmp.join(format!("{train}.json"));
        let (ok, out, err) = oddball(&[
            "evaluate",
            "--train",
            d.join(train).to_str().unwrap(),
            "--test",
            d.join(test).to_str().unwrap(),
            "--pipeline",
            "lda+riemann",
            "--json",
            json.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        let v = read_json(&json);
        assert_eq!(field(&v[0], "speller_text"), text);
        let reps = field(&v[0], "reps_for_all_correct").as_u64().unwrap();
        assert!(reps <= most, "{train} → {test}: {reps} repetitions: {out}");
        if train == "eeg3_2.dat" {
            let model = tmp.join("fused.json");
            let (ok, _, err) = oddball(&[
                "train",
                d.join(train).to_str().unwrap(),
                "--pipeline",
                "lda+riemann",
                "-o",
                model.to_str().unwrap(),
            ]);
            assert!(ok, "{err}");
            let loaded = evaluate_saved_model(&model, &d.join(test), &tmp.join("loaded.json"));
            assert_eq!(field(&loaded[0], "auc"), field(&v[0], "auc"));
            assert_eq!(
                field(&loaded[0], "speller_accuracy"),
                field(&v[0], "speller_accuracy")
            );
        }
    }
}

/// Issue #3's bar for the best preset, on the real recordings: `stack` (block-Toeplitz LDA,
/// xDAWN + tangent space and MDM stacked by a logistic regression learned on training-only
/// out-of-fold scores) spells eeg3 in ≤ 2 repetitions forwards and ≤ 3 backwards, and reaches the
/// best peer pipeline's epoch AUC on every binary split (eeg2 1→2 0.983, eeg2 2→1 0.952, Muse
/// sessions 1+2 → 3 0.769). A saved stacked model scores the same as the evaluated one.
#[test]
fn stack_reaches_the_best_peer_on_every_split() {
    let Some(d) = data_dir() else { return };
    let tmp = common::tmp_dir("decode-stack");
    std::fs::create_dir_all(&tmp).unwrap();
    let evaluate = |train: &[PathBuf], test: &[PathBuf], tag: &str| {
        let json = tmp.join(format!("{tag}.json"));
        let mut args = vec!["evaluate".to_string(), "--train".into()];
        args.extend(train.iter().map(|p| p.to_str().unwrap().to_string()));
        args.push("--test".into());
        args.extend(test.iter().map(|p| p.to_str().unwrap().to_string()));
        args.extend(["--pipeline", "stack", "--json"].map(String::from));
        args.push(json.to_str().unwrap().into());
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, out, err) = oddball(&refs);
        assert!(ok, "{tag}: {err}");
        (read_json(&json)[0].clone(), out)
    };
    for (train, test, most) in [
        ("eeg3_1.dat", "eeg3_2.dat", 2),
        ("eeg3_2.dat", "eeg3_1.dat", 3),
    ] {
        let (v, out) = evaluate(&[d.join(train)], &[d.join(test)], train);
        let reps = field(&v, "reps_for_all_correct").as_u64().unwrap();
        assert!(reps <= most, "{train} → {test}: {reps} repetitions: {out}");
    }
    for (train, test, best_peer) in [
        ("eeg2_1.dat", "eeg2_2.dat", 0.983),
        ("eeg2_2.dat", "eeg2_1.dat", 0.952),
    ] {
        let (v, out) = evaluate(&[d.join(train)], &[d.join(test)], train);
        let auc = field(&v, "auc").as_f64().unwrap();
        assert!(
            auc >= best_peer,
            "{train} → {test}: AUC {auc} < {best_peer}: {out}"
        );
    }
    let muse = common::data_dir()
        .unwrap()
        .join("muse-visual-p300-eeg-notebooks/subject1");
    let session = |k: u32| -> Vec<PathBuf> {
        let mut f: Vec<PathBuf> = std::fs::read_dir(muse.join(format!("session{k}")))
            .map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        f.retain(|p| p.extension().is_some_and(|e| e == "csv"));
        f.sort();
        f
    };
    let (s1, s2, s3) = (session(1), session(2), session(3));
    if s1.is_empty() || s3.is_empty() {
        eprintln!(
            "skipping the Muse split: no CSV files under {}",
            muse.display()
        );
    } else {
        let train: Vec<PathBuf> = s1.into_iter().chain(s2).collect();
        let (v, out) = evaluate(&train, &s3, "muse");
        let auc = field(&v, "auc").as_f64().unwrap();
        assert!(auc >= 0.769, "Muse s1+2 → s3: AUC {auc} < 0.769: {out}");
    }
    // Saved and loaded, trained on a speller (inner folds keep characters whole, as evaluate's).
    let model = tmp.join("stack.json");
    let (ok, _, err) = oddball(&[
        "train",
        d.join("eeg3_2.dat").to_str().unwrap(),
        "--pipeline",
        "stack",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (v, _) = evaluate(&[d.join("eeg3_2.dat")], &[d.join("eeg3_1.dat")], "again");
    let loaded = evaluate_saved_model(&model, &d.join("eeg3_1.dat"), &tmp.join("loaded.json"));
    assert_eq!(field(&loaded[0], "auc"), field(&v, "auc"));
}
