//! `oddball evaluate --unsupervised`: real speller recordings played as one session whose labels
//! the decoder never sees (EM over one row + one column per character), scored afterwards —
//! beside the supervised `lda` trained on labels.

mod common;

use common::{data_dir, oddball, tmp_dir};

fn run_json(args: &[&str], json: &std::path::Path) -> (serde_json::Value, String) {
    let (ok, out, err) = oddball(&[args, &["--json", json.to_str().unwrap()]].concat());
    assert!(ok, "{err}");
    let v = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    (v, out)
}

fn right(v: &serde_json::Value) -> usize {
    v["online_correct"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b.as_u64().unwrap() as usize)
        .sum()
}

#[test]
fn eeg3_as_one_unlabelled_session_spells_like_supervised_lda() {
    let Some(d) = data_dir() else { return };
    let d = d.join("bci2000-samplefiles-p300");
    let f = |n: &str| d.join(n).to_str().unwrap().to_string();
    let (e1, e2) = (f("eeg3_1.dat"), f("eeg3_2.dat"));
    let tmp = tmp_dir("cli-unsupervised-eeg3");

    let (v, out) = run_json(
        &["evaluate", "--unsupervised", "--test", &e1, &e2],
        &tmp.join("u.json"),
    );
    println!("{out}");
    let u = &v["unsupervised"];
    assert_eq!(u["online_correct"].as_array().unwrap().len(), 8, "{out}");
    let posthoc = u["posthoc_chars_by_reps"].as_array().unwrap();
    assert_eq!(posthoc.len(), 15);
    assert_eq!(
        posthoc[14].as_f64().unwrap(),
        1.0,
        "post hoc 8/8 at 15 repetitions: {out}"
    );
    assert_eq!(u["posthoc_text"], "T3OF6MK?", "{out}");
    assert!(right(u) >= 7, "online {} of 8: {out}", right(u));

    // Supervised lda trained on the other file, scored on each file.
    let mut sup = Vec::new();
    for (train, test) in [(&e2, &e1), (&e1, &e2)] {
        let (v, _) = run_json(
            &[
                "evaluate",
                "--train",
                train,
                "--test",
                test,
                "--pipeline",
                "lda",
            ],
            &tmp.join("s.json"),
        );
        sup.push(v[0]["auc"].as_f64().unwrap());
    }
    let by_file: Vec<f64> = u["auc_by_recording"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["auc"].as_f64().unwrap())
        .collect();
    println!("unsupervised AUC by file {by_file:?}, supervised lda (other file) {sup:?}");
    for (a, s) in by_file.iter().zip(&sup) {
        assert!(*a >= s - 0.03, "AUC {a} vs supervised {s}: {out}");
    }
}

#[test]
fn bci_competition_iib_six_runs_as_one_unlabelled_session() {
    let Some(d) = data_dir() else { return };
    let d = d.join("bci-competition-ii-iib");
    let runs: Vec<String> = [
        "AAS010R01.mat",
        "AAS010R02.mat",
        "AAS011R01.mat",
        "AAS011R02.mat",
        "AAS012R03.mat",
        "AAS012R04.mat",
    ]
    .iter()
    .map(|n| d.join(n).to_str().unwrap().to_string())
    .collect();
    let tmp = tmp_dir("cli-unsupervised-iib");
    let mut args = vec!["evaluate", "--unsupervised", "--test"];
    args.extend(runs.iter().map(String::as_str));
    // The texts score the runs (the test runs carry no labels); the decoder never sees them.
    args.extend(["--test-text", "CAT,DOG,HAT,HAT,HAM,PIE"]);
    let (v, out) = run_json(&args, &tmp.join("u.json"));
    println!("{out}");
    let u = &v["unsupervised"];
    assert_eq!(u["online_correct"].as_array().unwrap().len(), 18, "{out}");
    let posthoc = u["posthoc_chars_by_reps"].as_array().unwrap();
    let last = posthoc.last().unwrap().as_f64().unwrap();
    assert!(last * 18.0 >= 17.0 - 1e-9, "post hoc {last}: {out}");
    // The issue's aim is 15/18; EM started from the P300 template gets 17/18 (from random
    // starts and the last fit alone, `--em-start random`: 15/18).
    assert!(right(u) >= 17, "online {} of 18: {out}", right(u));
}

/// A speller run whose file has row and column codes but no geometry (here a CSV) is refused as
/// not a speller alone; `--manifest` gives it the data set's [speller] table, as
/// `oddball benchmark` does for its runs, and the replay decodes it without labels.
#[test]
fn a_manifest_gives_a_run_without_geometry_its_speller() {
    let tmp = tmp_dir("cli-unsupervised-manifest");
    let (sfreq, n_ch, step) = (128.0, 4, 32);
    let text = "HATPIE";
    let matrix = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"];
    let at = |c: char| {
        let r = matrix.iter().position(|m| m.contains(c)).unwrap();
        (r, matrix[r].find(c).unwrap())
    };
    // Columns 1–6, rows 7–12 (IIb's codes); 5 rounds of the 12 codes per character.
    let mut onsets = Vec::new();
    let mut state = 7u64;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for c in text.chars() {
        let (r, col) = at(c);
        for round in 0..5u32 {
            for k in 0..12u32 {
                let code = 1 + (k * 5 + round * 7) % 12;
                let target = code == col as u32 + 1 || code == r as u32 + 7;
                onsets.push((code, target));
            }
        }
    }
    let n = onsets.len() * step + 2 * sfreq as usize;
    let mut data = ndarray::Array2::from_shape_fn((n_ch, n), |_| 0.0);
    data.mapv_inplace(|_| 6.0 * uniform());
    let mut markers = vec![0u32; n];
    for (i, &(code, target)) in onsets.iter().enumerate() {
        let t0 = i * step;
        markers[t0] = code;
        if target {
            for s in 0..(sfreq as usize) {
                let t = s as f64 / sfreq;
                let bump = 6.0 * (-((t - 0.35) / 0.08f64).powi(2)).exp();
                for ch in 0..n_ch {
                    data[[ch, t0 + s]] += bump;
                }
            }
        }
    }
    let csv = tmp.join("run.csv");
    oddball_testkit::write_codes_csv(&csv, &data, &markers, sfreq);
    let manifest = tmp.join("m.toml");
    std::fs::write(
        &manifest,
        format!(
            "name = \"m\"\n[speller]\nmatrix = {matrix:?}\ncolumns = [1, 2, 3, 4, 5, 6]\n\
             rows = [7, 8, 9, 10, 11, 12]\nrepetitions = 5\n\n[[subject]]\nid = \"s\"\n\
             train = [\"run.csv\"]\n"
        ),
    )
    .unwrap();
    let base = [
        "evaluate",
        "--unsupervised",
        "--test",
        csv.to_str().unwrap(),
    ];
    let base = [&base[..], &["--test-text", text]].concat();
    let (ok, out, err) = oddball(&base);
    assert!(!ok && err.contains("speller"), "{out}\n{err}");
    let (v, out) = run_json(
        &[&base[..], &["--manifest", manifest.to_str().unwrap()]].concat(),
        &tmp.join("u.json"),
    );
    let u = &v["unsupervised"];
    assert_eq!(u["n_characters"], 6, "{out}");
    assert_eq!(u["posthoc_text"], text, "{out}");
}

/// `--transfer`: the shipped pooled start beside the template on eeg3 (it names eeg3's
/// channels), and a pooled start from a file is outside input, checked where it enters.
#[test]
fn a_pooled_start_is_shipped_and_a_file_is_checked() {
    let tmp = tmp_dir("cli-unsupervised-transfer");
    let bad = tmp.join("bad.json");
    std::fs::write(&bad, r#"{"version": 99, "patterns": []}"#).unwrap();
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--unsupervised",
        "--test",
        bad.to_str().unwrap(),
        "--transfer",
        bad.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("version 99"), "{err}");
    let Some(d) = data_dir() else { return };
    let d = d.join("bci2000-samplefiles-p300");
    let f = |n: &str| d.join(n).to_str().unwrap().to_string();
    let (v, out) = run_json(
        &[
            "evaluate",
            "--unsupervised",
            "--test",
            &f("eeg3_1.dat"),
            &f("eeg3_2.dat"),
            "--transfer",
            "pooled",
        ],
        &tmp.join("u.json"),
    );
    let u = &v["unsupervised"];
    assert_eq!(right(u), 8, "{out}");
    assert_eq!(u["online_inits"].as_array().unwrap().len(), 8, "{out}");
}
