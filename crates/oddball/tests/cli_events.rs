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

/// The same synthetic recording (16 channels, markers 1/2, `oddball_testkit::synthetic_oddball`)
/// written as EDF+ (events as annotations "1"/"2"), XDF (a marker stream) and MAT (`signal` with
/// a per-sample `StimulusCode` and an `fs` variable): each trains and evaluates once the command
/// line says which codes are targets, and a manifest's `[events]` does the same for all three.
#[test]
fn edf_xdf_and_mat_with_plain_codes_train_and_evaluate_with_a_mapping() {
    use oddball_signal::{Event, Events, Raw};

    let dir = tmp_dir("cli-events-formats");
    let (data, markers, sfreq) = oddball_testkit::synthetic_oddball(16, 777);
    let events: Vec<Event> = markers
        .iter()
        .enumerate()
        .filter(|(_, &m)| m != 0)
        .map(|(i, &m)| Event::new(i, m))
        .collect();
    let names: Vec<String> = (0..16).map(|c| format!("ch{c}")).collect();
    let raw = Raw::new(data.clone(), sfreq, names, Events::new(events)).unwrap();
    let edf = dir.join("codes.edf");
    oddball_io::write_edf_plus(&edf, &raw).unwrap();
    let xdf = dir.join("codes.xdf");
    oddball_io::write_xdf(&xdf, &raw, &Default::default()).unwrap();
    let mat = dir.join("codes.mat");
    let n_times = data.ncols();
    // n_times × n_channels, column-major: channel after channel.
    let signal: Vec<f64> = data.iter().copied().collect();
    let codes: Vec<f64> = markers.iter().map(|&m| f64::from(m)).collect();
    oddball_testkit::write_mat_v5(
        &mat,
        &[
            ("signal", n_times, 16, &signal),
            ("StimulusCode", n_times, 1, &codes),
            ("fs", 1, 1, &[sfreq]),
        ],
    );
    let map = ["--target-events", "2", "--nontarget-events", "1"];
    for file in [&edf, &xdf, &mat] {
        let f = file.to_str().unwrap();
        // Unlabelled: the error says how to label.
        let (ok, _, err) = oddball(&["evaluate", "--train", f, "--folds", "3"]);
        assert!(!ok && err.contains("--target-events"), "{f}: {err}");
        let json = dir.join("cv.json");
        let mut args = vec!["evaluate", "--train", f, "--folds", "3", "--out"];
        args.push(json.to_str().unwrap());
        args.extend(map);
        let (ok, out, err) = oddball(&args);
        assert!(ok, "{f}: {err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let auc = v[0]["auc"].as_f64().unwrap();
        assert!(auc > 0.8, "{f}: AUC {auc}: {out}");
        // Not a speller: no character scores.
        assert!(v[0]["speller_accuracy"].is_null(), "{f}: {}", v[0]);
        let model = dir.join("m.json");
        let mut args = vec!["train", f, "-o", model.to_str().unwrap()];
        args.extend(map);
        let (ok, _, err) = oddball(&args);
        assert!(ok, "{f}: {err}");
        let mut args = vec!["evaluate", "--model", model.to_str().unwrap(), "--test", f];
        args.extend(map);
        let (ok, out, err) = oddball(&args);
        assert!(ok && out.contains("AUC"), "{f}: {err}");
    }
    // The same mapping from a manifest.
    let manifest = dir.join("formats.toml");
    std::fs::write(
        &manifest,
        "name = \"formats\"\n[events]\ntarget = [2]\nnontarget = [1]\n\
         [[subject]]\nid = \"edf\"\ntrain = [\"codes.edf\"]\n\
         [[subject]]\nid = \"xdf\"\ntrain = [\"codes.xdf\"]\n\
         [[subject]]\nid = \"mat\"\ntrain = [\"codes.mat\"]\n",
    )
    .unwrap();
    let json = dir.join("bench.json");
    let (ok, out, err) = oddball(&[
        "benchmark",
        manifest.to_str().unwrap(),
        "--protocol",
        "within-session",
        "--folds",
        "3",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}\n{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for r in rows {
        assert_eq!(r["n_epochs"].as_u64(), Some(240), "{r}");
        assert_eq!(r["n_targets"].as_u64(), Some(48), "{r}");
        assert!(r["auc"].as_f64().unwrap() > 0.8, "{r}");
    }
}

/// What a file does not say, said on the command line or in a manifest's `[read]`: a CSV
/// whose columns have unusual names and no time column, a MAT file whose variables are not
/// the BCI Competition's.
#[test]
fn read_options_name_the_columns_variables_and_rate() {
    let dir = tmp_dir("cli-events-read");
    let (data, markers, sfreq) = oddball_testkit::synthetic_oddball(16, 4242);
    let csv = dir.join("odd.csv");
    oddball_testkit::write_codes_csv(&csv, &data, &markers, sfreq);
    let text = std::fs::read_to_string(&csv).unwrap();
    let text = text
        .replacen("time,", "t_s,", 1)
        .replacen(",stim\n", ",trigger\n", 1);
    std::fs::write(&csv, text).unwrap();
    let mat = dir.join("odd.mat");
    let signal: Vec<f64> = data.iter().copied().collect();
    let codes: Vec<f64> = markers.iter().map(|&m| f64::from(m)).collect();
    let n = data.ncols();
    oddball_testkit::write_mat_v5(&mat, &[("eeg", n, 16, &signal), ("trig", n, 1, &codes)]);
    let channels: Vec<String> = (0..16).map(|c| format!("ch{c}")).collect();
    let channels = channels.join(",");
    let map = ["--target-events", "2", "--nontarget-events", "1"];
    for (file, extra) in [
        (
            &csv,
            vec![
                "--channels",
                &channels,
                "--events-from",
                "trigger",
                "--sfreq",
                "256",
            ],
        ),
        (
            &mat,
            vec![
                "--data-from",
                "eeg",
                "--events-from",
                "trig",
                "--sfreq",
                "256",
            ],
        ),
    ] {
        let f = file.to_str().unwrap();
        let json = dir.join("cv.json");
        let mut args = vec!["evaluate", "--train", f, "--folds", "3", "--out"];
        args.push(json.to_str().unwrap());
        args.extend(map);
        args.extend(extra.iter().copied());
        let (ok, out, err) = oddball(&args);
        assert!(ok, "{f}: {err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert!(v[0]["auc"].as_f64().unwrap() > 0.8, "{f}: {out}");
        let (ok, out, _) = oddball(&[&["inspect", f][..], &extra].concat());
        assert!(
            ok && out.contains("256 Hz") && out.contains("ch15") && out.contains("events     240"),
            "{f}: {out}"
        );
    }
    // Without them the MAT file's variables are not found, and the error lists what is there.
    let (ok, _, err) = oddball(&["inspect", mat.to_str().unwrap()]);
    assert!(
        !ok && err.contains("signal") && err.contains("eeg"),
        "{err}"
    );
    // Options for a format that records its own layout are refused, naming them.
    let edf = dir.join("x.edf");
    std::fs::write(&edf, b"0").unwrap();
    let (ok, _, err) = oddball(&["inspect", edf.to_str().unwrap(), "--sfreq", "256"]);
    assert!(!ok && err.contains("a sampling rate given"), "{err}");
    let (ok, _, err) = oddball(&["inspect", csv.to_str().unwrap(), "--sfreq=-1"]);
    assert!(!ok && err.contains("sfreq -1"), "{err}");
    // The same options in a manifest.
    let manifest = dir.join("read.toml");
    std::fs::write(
        &manifest,
        "name = \"read\"\n[events]\ntarget = [2]\nnontarget = [1]\n\
         [read]\nsfreq = 256.0\ndata = \"eeg\"\nevents = \"trig\"\n\
         [[subject]]\nid = \"m\"\ntrain = [\"odd.mat\"]\n",
    )
    .unwrap();
    let (ok, out, err) = oddball(&[
        "benchmark",
        manifest.to_str().unwrap(),
        "--protocol",
        "within-session",
        "--folds",
        "3",
    ]);
    assert!(ok && out.contains("240 epochs, 48 targets"), "{err}\n{out}");
}
