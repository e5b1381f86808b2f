//! One set of session options, honoured everywhere: each command lists what it honours, and
//! its errors name its own options.

mod common;

/// `online --help` offers neither replayed speller subjects nor their texts (a live session's
/// subject is simulated or real), and says its commands default to the letter G of `demo`.
#[test]
fn online_offers_only_what_it_honours() {
    let (ok, help, err) = common::oddball(&["online", "--help"]);
    assert!(ok, "{err}");
    assert!(!help.contains("--test-text"), "{help}");
    assert!(!help.contains("replay:FILE[,FILE"), "{help}");
    assert!(!help.contains("--realtime"), "{help}");
    assert!(help.contains("[default: letter-g]"), "{help}");
    // Given anyway, they are refused by name before anything runs.
    let (ok, _, err) = common::oddball(&["online", "--subject", "replay:x.dat", "--calibrate"]);
    assert!(!ok && err.contains("--source replay:FILE"), "{err}");
    let (ok, _, err) = common::oddball(&["online", "--realtime", "--calibrate"]);
    assert!(!ok && err.contains("--realtime"), "{err}");
    // demo's help still offers both.
    let (ok, help, _) = common::oddball(&["demo", "--help"]);
    assert!(ok && help.contains("--test-text") && help.contains("replay:FILE"));
}

/// `online` draws the same G as `demo` by default: the stroke font's, 20 one-step moves.
#[test]
fn online_draws_the_same_g_as_demo_by_default() {
    let dir = common::tmp_dir("online-default-g");
    // demo's session (calibration and one command) played back to `online`, as fast as it goes.
    let model = common::demo_model(dir.path());
    let file = format!(
        "replay:{}",
        dir.path().join("demo").join("session.dat").display()
    );
    let out = dir.path().join("online");
    let (_, stdout, err) = common::oddball(&[
        "online",
        "--model",
        model.to_str().unwrap(),
        "--source",
        &file,
        "--fast",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stdout.contains(", 20 commands, "), "{stdout}\n{err}");
}

/// A replayed speller run without target labels: `demo`'s error names `demo`'s options
/// (`--test-text`), not `evaluate`'s `--target-events`.
#[test]
fn demo_errors_name_demos_options() {
    let Some(d) = common::data_dir() else {
        return;
    };
    let iib = d.join("bci-competition-ii-iib");
    let test = iib.join("AAS012R03.mat");
    let cal = iib.join("AAS010R01.mat");
    if !test.exists() || !cal.exists() {
        return;
    }
    let dir = common::tmp_dir("demo-unlabelled");
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--subject",
        &format!("replay:{}", test.display()),
        "--calibration",
        cal.to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
    ]);
    assert!(!ok, "an unlabelled run replays only with its text");
    assert!(
        err.contains("--test-text") && !err.contains("--target-events"),
        "{err}"
    );
}
