//! `oddball benchmark`: every preset on every subject of dataset manifests, with MOABB's
//! protocols, its files (JSON, CSV, plot), and its checks before any work.

mod common;

use std::path::Path;

use common::{data_dir, oddball, oddball_ok, tmp_dir};

/// Three synthetic subjects of two 8-channel CSV runs each (markers 1 = non-target, 2 =
/// target), and a manifest naming them with the event mapping; subject s1's runs are two
/// sessions.
fn synthetic_dataset(dir: &Path) -> std::path::PathBuf {
    let mut subjects = String::new();
    for (s, seed) in [("s1", 11u64), ("s2", 22), ("s3", 33)] {
        for run in 0..2 {
            let (data, markers, sfreq) = oddball_testkit::synthetic_oddball(8, seed + run);
            oddball_testkit::write_codes_csv(
                &dir.join(format!("{s}_run{run}.csv")),
                &data,
                &markers,
                sfreq,
            );
        }
        subjects.push_str(&format!(
            "\n[[subject]]\nid = \"{s}\"\ntrain = [\"{s}_run0.csv\"]\ntest = [\"{s}_run1.csv\"]\n"
        ));
        if s == "s1" {
            subjects.push_str(
                "[subject.sessions]\n\"a\" = [\"s1_run0.csv\"]\n\"b\" = [\"s1_run1.csv\"]\n",
            );
        }
    }
    let manifest = dir.join("synthetic.toml");
    std::fs::write(
        &manifest,
        format!("name = \"synthetic\"\n[events]\ntarget = [2]\nnontarget = [1]\n{subjects}"),
    )
    .unwrap();
    manifest
}

#[test]
fn every_protocol_on_a_synthetic_dataset_writes_rows_summary_tests_and_files() {
    let dir = tmp_dir("cli-benchmark");
    let manifest = synthetic_dataset(dir.path());
    let (json, csv, plot) = (
        dir.join("bench.json"),
        dir.join("bench.csv"),
        dir.join("bench.png"),
    );
    let (ok, out, err) = oddball(&[
        "benchmark",
        manifest.to_str().unwrap(),
        "--pipeline",
        "lda,mdm",
        "--protocol",
        "all",
        "--folds",
        "3",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(ok, "{err}\n{out}");
    // stderr is a pipe here: progress comes as plain lines, the last one at 100%.
    let last = err.lines().rev().find(|l| l.contains('/')).unwrap_or("");
    assert!(
        last.starts_with("reading ") && last.contains(" (100%) "),
        "{err}"
    );
    assert!(common::without_progress(&err).trim().is_empty(), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["results"].as_array().unwrap();
    let count = |protocol: &str| rows.iter().filter(|r| r["protocol"] == protocol).count();
    // 3 subjects × 2 presets; within session s1 has 2 sessions, the others one each.
    assert_eq!(count("train-test"), 6, "{out}");
    assert_eq!(count("within-session"), 8, "{out}");
    assert_eq!(count("cross-subject"), 6, "{out}");
    for r in rows {
        for key in [
            "dataset",
            "subject",
            "protocol",
            "preset",
            "auc",
            "n_epochs",
            "n_targets",
            "n_chars",
            "chars_by_reps",
            "itr_bits_per_min",
        ] {
            assert!(r.get(key).is_some(), "row without {key}: {r}");
        }
        assert!(r["chars_by_reps"].is_null(), "not a speller: {r}");
        assert_eq!(r["dataset"], "synthetic");
        let auc = r["auc"].as_f64().unwrap();
        // The 2 µV bump under 10 µV noise separates well on every split.
        assert!(auc > 0.75, "{r}");
        let n = r["n_epochs"].as_u64().unwrap();
        let expected = match r["protocol"].as_str().unwrap() {
            // one test run
            "train-test" => 240,
            // all runs of the left-out subject
            "cross-subject" => 480,
            _ if r["subject"] == "s1" => 240,
            _ => 480,
        };
        assert_eq!(n, expected, "{r}");
        assert_eq!(r["n_targets"].as_u64().unwrap() * 5, n, "{r}");
    }
    // Summary: one line per protocol and preset, over 3 subjects (4 subject-sessions).
    let summary = v["summary"].as_array().unwrap();
    assert_eq!(summary.len(), 6);
    for s in summary {
        let n = s["n"].as_u64().unwrap();
        let want = if s["protocol"] == "within-session" {
            4
        } else {
            3
        };
        assert_eq!(n, want, "{s}");
        assert!(s["auc_sd"].as_f64().unwrap() >= 0.0);
    }
    // Paired tests for both orders of the two presets, per protocol.
    let comparisons = v["comparisons"].as_array().unwrap();
    assert_eq!(comparisons.len(), 6);
    for c in comparisons {
        assert_eq!(
            c["n"].as_u64(),
            Some(if c["protocol"] == "within-session" {
                4
            } else {
                3
            })
        );
        // No p-value only when the two presets tie on every subject.
        match c["pvalue"].as_f64() {
            Some(p) => assert!((0.0..=1.0).contains(&p), "{c}"),
            None => assert_eq!(c["mean_auc_diff"].as_f64(), Some(0.0), "{c}"),
        }
    }
    // The CSV: a header and one line per row.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), rows.len() + 1);
    assert!(text.starts_with("dataset,subject,session,protocol,preset,auc"));
    // The plot is a PNG.
    let png = std::fs::read(&plot).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // The printed report: per-subject blocks, means, the test table.
    assert!(
        out.contains("synthetic / subject s2 (cross-subject)"),
        "{out}"
    );
    assert!(out.contains("mean ± sd over subjects"), "{out}");
    assert!(out.contains("one-sided Wilcoxon"), "{out}");
}

#[test]
fn mistakes_are_refused_before_any_eeg_is_read() {
    let dir = tmp_dir("cli-benchmark-bad");
    let manifest = synthetic_dataset(dir.path());
    let m = manifest.to_str().unwrap();
    let (ok, _, err) = oddball(&["benchmark", m, "--protocol", "loso"]);
    assert!(!ok && err.contains("cross-subject"), "{err}");
    let (ok, _, err) = oddball(&["benchmark", m, "--pipeline", "nope"]);
    assert!(!ok && err.contains("unknown pipeline"), "{err}");
    let missing = dir.join("no/such/dir/x.json");
    let (ok, _, err) = oddball(&["benchmark", m, "--json", missing.to_str().unwrap()]);
    assert!(!ok && err.contains("does not exist"), "{err}");
    let (ok, _, err) = oddball(&["benchmark", m, "--plot", "x.jpg"]);
    assert!(!ok && err.contains(".png or .svg"), "{err}");
    // A run the manifest names but the folder lacks.
    std::fs::remove_file(dir.join("s3_run1.csv")).unwrap();
    let (ok, _, err) = oddball(&["benchmark", m]);
    assert!(
        !ok && err.contains("s3_run1.csv") && err.contains("does not exist"),
        "{err}"
    );
    // Cross-subject on a one-subject data set is skipped with the reason; nothing else to run
    // is an error that says why.
    let one = dir.join("one.toml");
    std::fs::write(
        &one,
        "name = \"one\"\n[events]\ntarget = [2]\nnontarget = [1]\n[[subject]]\nid = \"s1\"\ntrain = [\"s1_run0.csv\"]\n",
    )
    .unwrap();
    let (ok, _, err) = oddball(&[
        "benchmark",
        one.to_str().unwrap(),
        "--protocol",
        "cross-subject",
    ]);
    assert!(!ok && err.contains("one subject"), "{err}");
}

/// The paths of the shipped manifests of the BCI2000, Muse and BCI II IIb data.
fn shipped_manifests() -> Vec<String> {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    [
        "bci2000-eeg3",
        "bci2000-eeg2",
        "muse-visual-p300",
        "bci-competition-ii-iib",
    ]
    .iter()
    .map(|m| {
        repo.join(format!("datasets/{m}.toml"))
            .display()
            .to_string()
    })
    .collect()
}

/// The shipped manifests on the real data: every data set reads, labels and scores.
#[test]
fn shipped_manifests_score_the_real_recordings() {
    let Some(data) = data_dir() else { return };
    let dir = tmp_dir("cli-benchmark-real");
    let json = dir.join("real.json");
    let manifests = shipped_manifests();
    let mut args: Vec<&str> = vec!["benchmark"];
    args.extend(manifests.iter().map(String::as_str));
    // --data replaces each manifest's root (../../shared/data), as ODDBALL_DATA does for tests.
    let data = data.display().to_string();
    args.extend(["--data", &data, "--json", json.to_str().unwrap()]);
    let (ok, out, err) = oddball(&args);
    assert!(ok, "{err}\n{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "{out}");
    let row = |d: &str| rows.iter().find(|r| r["dataset"] == d).unwrap();
    // The peer's shrinkage LDA on the same splits: eeg3 0.937, eeg2 0.969, Muse 0.721, IIb 0.942.
    for (d, min_auc, chars) in [
        ("bci2000-eeg3", 0.93, Some(4)),
        ("bci2000-eeg2", 0.96, None),
        ("muse-visual-p300", 0.70, None),
        ("bci-competition-ii-iib", 0.935, Some(6)),
    ] {
        let r = row(d);
        let auc = r["auc"].as_f64().unwrap();
        assert!(auc >= min_auc, "{d}: AUC {auc} < {min_auc}");
        assert_eq!(r["n_chars"].as_u64(), chars, "{r}");
        if let Some(n) = chars {
            let by_reps = r["chars_by_reps"].as_array().unwrap();
            assert_eq!(by_reps.len(), 15);
            assert_eq!(
                by_reps[14].as_u64(),
                Some(n),
                "{d}: all right at 15 repetitions"
            );
            assert!(r["itr_bits_per_min"].as_f64().unwrap() > 0.0);
        }
    }
    // The IIb test runs are labelled from the manifest's words: 540 flashes each, 90 targets.
    let iib = row("bci-competition-ii-iib");
    assert_eq!(iib["n_epochs"].as_u64(), Some(1080));
    assert_eq!(iib["n_targets"].as_u64(), Some(180));
    // A character's time counts the ~5 s pause between characters as well as its flashes
    // (12 × 175 ms per repetition): with all 6 right from 3 repetitions, log2(36) bits per
    // 3 × 2.1 s + 5 s is 27 bits/min, where the flashes alone would give 49.
    let itr = iib["itr_bits_per_min"].as_f64().unwrap();
    assert!((20.0..35.0).contains(&itr), "IIb ITR {itr}");
}

/// BCI Competition II IIb, train runs → HAM PIE, beside the Python peer run on this machine
/// (`../shared/peer/peer_bci2b.py`): its best AUC is shrinkage LDA's 0.942, and all four of its
/// pipelines spell 6/6 from 3 repetitions and 5/6 at 2. `lda+riemann` is above that AUC (0.950)
/// and spells as the peer does. 6/6 from 2 repetitions (issue #18) is not reached by any preset,
/// nor by any decoder chosen on the training runs in `tools/experiments/iib-two-reps`.
#[test]
fn iib_best_preset_is_above_the_peer_auc() {
    let Some(data) = data_dir() else { return };
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tmp_dir("cli-benchmark-iib");
    let json = dir.join("iib.json");
    let manifest = repo.join("datasets/bci-competition-ii-iib.toml");
    let data = data.display().to_string();
    oddball_ok(&[
        "benchmark",
        manifest.to_str().unwrap(),
        "--pipeline",
        "lda+riemann",
        "--data",
        &data,
        "--json",
        json.to_str().unwrap(),
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let r = &v["results"][0];
    assert_eq!(r["preset"], "lda+riemann", "{r}");
    let auc = r["auc"].as_f64().unwrap();
    assert!(auc >= 0.942, "AUC {auc} below the peer's best 0.942");
    let by_reps: Vec<u64> = r["chars_by_reps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    assert_eq!(by_reps.len(), 15);
    assert!(
        by_reps[1] >= 5,
        "{by_reps:?}: 5/6 at 2 repetitions as the peer"
    );
    assert!(
        by_reps[2..].iter().all(|&c| c == 6),
        "{by_reps:?}: 6/6 from 3 repetitions on"
    );
}

/// The OpenViBE GDF run (issue #33) within session, 5 folds that keep its 5 characters whole, beside
/// MNE 1.13.2 + scikit-learn 1.9.1's shrinkage LDA on the same epochs and folds
/// (`tools/peer/openvibe_gdf_lda.py`, run on this machine: AUC 0.9803, per fold 0.9896, 0.9900, 0.9492,
/// 0.9804, 0.9925).
#[test]
fn openvibe_gdf_within_session_is_the_mne_scikit_learn_auc() {
    let Some(data) = data_dir() else { return };
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tmp_dir("cli-benchmark-gdf");
    let json = dir.join("gdf.json");
    let manifest = repo.join("datasets/openvibe-p300-gdf.toml");
    let data = data.display().to_string();
    let (ok, out, err) = oddball(&[
        "benchmark",
        manifest.to_str().unwrap(),
        "--protocol",
        "within-session",
        "--pipeline",
        "lda",
        "--data",
        &data,
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}\n{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let r = &v["results"][0];
    assert_eq!(r["n_epochs"].as_u64(), Some(700), "{r}");
    assert_eq!(r["n_targets"].as_u64(), Some(100), "{r}");
    let auc = r["auc"].as_f64().unwrap();
    println!("oddball lda within session: AUC {auc:.4} (MNE + scikit-learn: 0.9803)");
    assert!((auc - 0.9803).abs() < 0.002, "AUC {auc}");
}

/// `--protocol unsupervised` on the shipped manifests: each speller subject's runs in order as
/// one unlabelled session (the speller geometry and texts from the manifests, as for the other
/// protocols); the non-spellers (eeg2's oddball, the Muse's) are listed as skipped.
#[test]
fn shipped_spellers_decoded_without_labels_per_subject() {
    let Some(data) = data_dir() else { return };
    let dir = tmp_dir("cli-benchmark-unsupervised");
    let (json, csv) = (dir.join("u.json"), dir.join("u.csv"));
    let manifests = shipped_manifests();
    let mut args: Vec<&str> = vec!["benchmark"];
    args.extend(manifests.iter().map(String::as_str));
    let data = data.display().to_string();
    args.extend(["--data", &data, "--protocol", "unsupervised"]);
    args.extend([
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let (ok, out, err) = oddball(&args);
    assert!(ok, "{err}\n{out}");
    for d in ["bci2000-eeg2", "muse-visual-p300"] {
        assert!(
            out.lines()
                .any(|l| l.starts_with("skipped: unsupervised on") && l.contains(d)),
            "{d} not skipped:\n{out}"
        );
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{out}");
    assert_eq!(v["skipped"].as_array().unwrap().len(), 2, "{out}");
    let row = |d: &str| rows.iter().find(|r| r["dataset"] == d).unwrap();
    // What `evaluate --unsupervised` gets on the same runs (README): eeg3_1 + eeg3_2 online 8/8,
    // post hoc 8/8 from 3 repetitions, AUC 0.967; the six IIb runs online 17/18, post hoc 17/18.
    for (d, n, online, posthoc, min_auc) in [
        ("bci2000-eeg3", 8, 8, 8, 0.95),
        ("bci-competition-ii-iib", 18, 17, 17, 0.97),
    ] {
        let r = row(d);
        assert_eq!(r["protocol"], "unsupervised");
        assert_eq!(r["preset"], "unsupervised");
        assert_eq!(r["n_chars"].as_u64(), Some(n), "{r}");
        assert!(r["online_chars"].as_u64().unwrap() >= online, "{d}: {r}");
        let by_reps = r["chars_by_reps"].as_array().unwrap();
        assert_eq!(by_reps.len(), 15);
        assert!(by_reps[14].as_u64().unwrap() >= posthoc, "{d}: {r}");
        assert!(r["auc"].as_f64().unwrap() >= min_auc, "{d}: {r}");
        assert!(
            out.contains(&format!("online {}/{n}", r["online_chars"])),
            "{out}"
        );
    }
    // Every run of the subject, labelled from the manifest: IIb's six runs, 540 flashes each.
    assert_eq!(
        row("bci-competition-ii-iib")["n_epochs"].as_u64(),
        Some(3240)
    );
    let csv = std::fs::read_to_string(&csv).unwrap();
    assert!(
        csv.lines().next().unwrap().ends_with(",online_chars"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), 3, "{csv}");
}
