//! Issue #19: what came from outside and crashed, hung or silently corrupted a run, through the
//! command line. Each test names the defect it covers.

mod common;

use common::{
    oddball, oddball_within, tmp_dir, write_csv, write_csv_with, write_xdf_with, CsvSpec,
};

const EVENTS: [&str; 4] = ["--target-events", "2", "--nontarget-events", "1"];

fn args<'a>(head: &[&'a str], tail: &[&'a str]) -> Vec<&'a str> {
    head.iter().chain(tail).copied().collect()
}

/// Defect 9: two argument combinations hung (found by trying demo/task/online options): a
/// simulated amplifier 10¹² ms late with --realtime, and a tracking target far off the board;
/// so did absurd counts of rounds, targets and calibration decisions. Each is now refused at
/// once, naming the option; `--wait-page nan` panicked.
#[test]
fn argument_combinations_that_hung_are_refused_at_once() {
    let dir = tmp_dir("cli-hangs");
    let out = dir.join("o");
    let out = out.to_str().unwrap();
    for (cmd, needle) in [
        (
            vec!["demo", "--realtime", "--sim-latency-ms", "1e12"],
            "--sim-latency-ms",
        ),
        (vec!["task", "track", "--target", "100,100"], "target"),
        (vec!["task", "track", "--targets", "100000000"], "targets"),
        (
            vec!["demo", "--dynamic-stopping", "--max-rounds", "100000000"],
            "max_rounds",
        ),
        (
            vec!["demo", "--calibration-per-bulb", "100000000"],
            "calibration_per_bulb",
        ),
        (
            vec![
                "online",
                "--calibrate",
                "--serve",
                "127.0.0.1:0",
                "--wait-page",
                "nan",
            ],
            "--wait-page",
        ),
    ] {
        let (code, _, err) = oddball_within(&args(&cmd, &["--out", out]), 60);
        assert_eq!(
            code,
            Some(1),
            "{cmd:?} (None: still running after 60 s): {err}"
        );
        assert!(err.contains(needle), "{cmd:?}: {err}");
    }
}

/// Defect 5: `train -o` over an existing model on a full disk destroyed the old model. A file
/// size limit (RLIMIT_FSIZE, SIGXFSZ ignored) makes the write fail the way a full disk does.
#[cfg(unix)]
#[test]
fn train_over_an_existing_model_keeps_it_when_the_write_fails() {
    let dir = tmp_dir("cli-full-disk");
    let csv = dir.join("codes.csv");
    write_csv(&csv);
    let model = dir.write("model.json", b"{\"the old model\": true}");
    let mut cmd = vec![
        env!("CARGO_BIN_EXE_oddball").to_string(),
        "train".into(),
        csv.to_str().unwrap().into(),
        "-o".into(),
        model.to_str().unwrap().into(),
    ];
    cmd.extend(EVENTS.iter().map(|s| s.to_string()));
    // A 64 KiB limit on files written (`ulimit -f` counts 512- or 1024-byte blocks).
    let script = "trap '' XFSZ; ulimit -f 64; exec \"$@\"";
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg("sh")
        .args(&cmd)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "the model (> 64 KiB) was written: {err}"
    );
    assert!(err.contains("model.json"), "{err}");
    assert_eq!(
        std::fs::read(&model).unwrap(),
        b"{\"the old model\": true}",
        "the old model is whole"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 2, "no temporary file left: {left:?}");
    // Without the limit the same command replaces it.
    let (ok, _, err) = oddball(&cmd[1..].iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{err}");
    assert!(
        oddball_decode::pipeline::Model::from_json(&std::fs::read_to_string(&model).unwrap())
            .is_ok()
    );
}

/// Defect 4: CSV rates from timestamps of 10³⁰⁰ Hz panicked the filter design (exit 101), of
/// 10⁹ Hz aborted on allocation (exit 134); plot and model windows of ±10⁹ s aborted too;
/// `evaluate --model` filtered before checking the data fits the model.
#[test]
fn absurd_rates_and_windows_are_refused_before_any_work() {
    let dir = tmp_dir("cli-absurd");
    for (step, name) in [(1e-300, "fast300.csv"), (1e-9, "fast9.csv")] {
        let p = dir.join(name);
        write_csv_with(
            &p,
            &CsvSpec {
                step_s: step,
                ..CsvSpec::default()
            },
        );
        let p = p.to_str().unwrap();
        for cmd in [
            vec!["inspect", p],
            args(&["train", p, "-o", "/dev/null"], &EVENTS),
        ] {
            let (code, _, err) = oddball_within(&cmd, 120);
            assert_eq!(code, Some(1), "{cmd:?}: {err}");
            assert!(err.contains("plausible"), "{cmd:?}: {err}");
        }
    }
    let csv = dir.join("codes.csv");
    write_csv(&csv);
    let csv = csv.to_str().unwrap();
    let png = dir.join("erp.png");
    let png = png.to_str().unwrap();
    let (code, _, err) = oddball_within(
        &args(
            &[
                "inspect",
                csv,
                "--plot",
                png,
                "--tmin=-1e9",
                "--tmax",
                "1e9",
            ],
            &EVENTS,
        ),
        120,
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("time window"), "{err}");

    // A model whose window reaches 10⁹ s is refused at load.
    let model = dir.join("m.json");
    let (ok, _, err) = oddball(&args(
        &["train", csv, "-o", model.to_str().unwrap()],
        &EVENTS,
    ));
    assert!(ok, "{err}");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    v["preprocess"]["tmax"] = serde_json::json!(1e9);
    let wide = dir.write("wide.json", v.to_string().as_bytes());
    let (code, _, err) = oddball_within(
        &args(
            &["evaluate", "--model", wide.to_str().unwrap(), "--test", csv],
            &EVENTS,
        ),
        120,
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("epoch window"), "{err}");

    // Data with other channels than the model's: refused naming the missing one.
    let other = dir.join("other.csv");
    let mut names = CsvSpec::default().names;
    names[3] = "Fp1".into();
    write_csv_with(
        &other,
        &CsvSpec {
            names,
            ..CsvSpec::default()
        },
    );
    let (code, _, err) = oddball_within(
        &args(
            &[
                "evaluate",
                "--model",
                model.to_str().unwrap(),
                "--test",
                other.to_str().unwrap(),
            ],
            &EVENTS,
        ),
        120,
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("without [\"ch3\"]"), "{err}");
}

/// Defect 3: one NaN sample spread through the zero-phase filter, every epoch was lost, and the
/// error blamed the labels ("got 0 targets and 0 non-targets"). Now a short gap costs only the
/// epochs over it, and a channel that is NaN throughout is named as the cause.
#[test]
fn nan_offline_costs_only_its_epochs_and_errors_name_the_real_cause() {
    let dir = tmp_dir("cli-nan");
    let gap = dir.join("gap.xdf");
    write_xdf_with(
        &gap,
        &CsvSpec {
            nan: Some((5, 5000..5010)),
            ..CsvSpec::default()
        },
    );
    let json = dir.join("cv.json");
    let (ok, out, err) = oddball(&args(
        &[
            "evaluate",
            "--train",
            gap.to_str().unwrap(),
            "--folds",
            "3",
            "--out",
            json.to_str().unwrap(),
        ],
        &EVENTS,
    ));
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let auc = v[0]["auc"].as_f64().unwrap();
    assert!(auc > 0.8, "AUC {auc}: {out}");

    let dead = dir.join("dead.xdf");
    write_xdf_with(
        &dead,
        &CsvSpec {
            nan: Some((5, 0..usize::MAX)),
            ..CsvSpec::default()
        },
    );
    let (ok, _, err) = oddball(&args(
        &["train", dead.to_str().unwrap(), "-o", "/dev/null"],
        &EVENTS,
    ));
    assert!(!ok);
    assert!(
        err.contains("non-finite") && err.contains("ch5") && !err.contains("0 targets"),
        "{err}"
    );
}

/// Defect 9: `evaluate --train A --test B` never compared channel names (a permuted montage
/// scored AUC 0.937). Channels are matched by name: a permuted test file scores exactly as the
/// unpermuted one, and a missing channel is named.
#[test]
fn test_data_is_matched_to_the_training_data_by_channel_name() {
    let dir = tmp_dir("cli-montage");
    let train = dir.join("train.csv");
    write_csv(&train);
    let same = dir.join("same.csv");
    write_csv(&same);
    let permuted = dir.join("permuted.csv");
    let mut names = CsvSpec::default().names;
    names.reverse();
    write_csv_with(
        &permuted,
        &CsvSpec {
            names,
            ..CsvSpec::default()
        },
    );
    let auc = |test: &std::path::Path| {
        let json = dir.join("r.json");
        let (ok, _, err) = oddball(&args(
            &[
                "evaluate",
                "--train",
                train.to_str().unwrap(),
                "--test",
                test.to_str().unwrap(),
                "--out",
                json.to_str().unwrap(),
            ],
            &EVENTS,
        ));
        assert!(ok, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        v[0]["auc"].as_f64().unwrap()
    };
    assert_eq!(auc(&same), auc(&permuted));

    let renamed = dir.join("renamed.csv");
    let mut names = CsvSpec::default().names;
    names[0] = "Cz".into();
    write_csv_with(
        &renamed,
        &CsvSpec {
            names,
            ..CsvSpec::default()
        },
    );
    let (ok, _, err) = oddball(&args(
        &[
            "evaluate",
            "--train",
            train.to_str().unwrap(),
            "--test",
            renamed.to_str().unwrap(),
        ],
        &EVENTS,
    ));
    assert!(!ok);
    assert!(err.contains("without [\"ch0\"]"), "{err}");
}

/// Defect 8: `online` never closed its recording: no XDF stream footers, no fsync, and SIGINT
/// or SIGTERM killed it (exit 130/143) without `summary.json`. Now the signal stops the session:
/// exit 3 (stopped before its end, issue #30: not 0 like a completed one), the XDF has every
/// stream's footer, and the summary says why it ended.
#[cfg(unix)]
#[test]
fn sigterm_stops_online_with_the_recording_closed_and_summarised() {
    let dir = tmp_dir("cli-sigterm");
    let out = dir.join("online");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--calibrate", "--commands", "up,left", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Let it record a few seconds of (paced) calibration.
    std::thread::sleep(std::time::Duration::from_secs(4));
    let killed = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let t0 = std::time::Instant::now();
    let output = child.wait_with_output().unwrap();
    assert!(t0.elapsed().as_secs() < 30, "it took long to stop");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    assert_eq!(
        output.status.code(),
        Some(3),
        "{:?}: {stdout}\n{stderr}",
        output.status
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary["ended"].as_str().unwrap().contains("SIGTERM"),
        "{summary}"
    );
    let rec = oddball_io::read(out.join("session.xdf")).unwrap();
    let xdf = rec.xdf().unwrap();
    assert!(!xdf.truncated, "{xdf:?}");
    assert!(rec.raw.n_times() > 500, "{} samples", rec.raw.n_times());
    for s in &xdf.streams {
        assert!(s.footer.is_some(), "stream {:?} has no footer", s.name);
    }
}
