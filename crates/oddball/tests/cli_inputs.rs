//! Inputs checked before any EEG work (issue #20): a mistyped output folder, a picture type, a
//! folder or a missing file given as a recording, text or commands that leave the board,
//! contradictory options. Each fails at once — nothing calibrated or trained first — with a
//! message that says what to change.

mod common;

use common::{oddball, tmp_dir};

/// The run printed nothing of a session or a training: it stopped before any EEG work.
fn stopped_before_work(out: &str) {
    assert!(
        !out.contains("calibration:") && !out.contains("trained "),
        "work was done before the error:\n{out}"
    );
}

#[test]
fn an_output_file_in_a_missing_folder_is_refused_before_training() {
    let dir = tmp_dir("inputs-out");
    let missing = dir.path().join("no/such/m.json");
    let (ok, out, err) = oddball(&["train", "any.dat", "-o", missing.to_str().unwrap()]);
    assert!(!ok);
    stopped_before_work(&out);
    assert!(err.contains("does not exist (create it first"), "{err}");
    // A picture with a type plotters does not write, and a folder given as a file.
    let (ok, _, err) = oddball(&["inspect", "any.dat", "--plot", "x.jpg"]);
    assert!(!ok && err.contains("must end in .png or .svg"), "{err}");
    let (ok, _, err) = oddball(&[
        "evaluate",
        "--train",
        "any.dat",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("is a folder: give a file name inside it"),
        "{err}"
    );
    // A report folder whose name is taken by a file.
    let file = dir.write("taken", b"x");
    let (ok, out, err) = oddball(&["demo", "--out", file.to_str().unwrap()]);
    assert!(!ok && err.contains("is a file, not a folder"), "{err}");
    stopped_before_work(&out);
}

#[test]
fn a_folder_or_a_missing_recording_is_named_as_such() {
    let dir = tmp_dir("inputs-read");
    dir.write("run_1.dat", b"");
    let (ok, _, err) = oddball(&["inspect", dir.path().to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("is a directory, not a recording: give a file inside it, e.g. run_1.dat"),
        "{err}"
    );
    assert!(!err.contains("extension None"), "{err}");
    // A missing replayed file is blamed on itself, not on its calibration sibling.
    let missing = dir.path().join("eeg3_2.dat");
    let (ok, out, err) = oddball(&[
        "demo",
        "--subject",
        &format!("replay:{}", missing.display()),
        "--out",
        dir.path().join("o").to_str().unwrap(),
    ]);
    assert!(!ok);
    stopped_before_work(&out);
    assert!(err.contains("eeg3_2.dat: no such file"), "{err}");
    assert!(!err.contains("calibration"), "{err}");
}

#[test]
fn text_that_does_not_fit_the_board_is_refused_before_calibration_and_step_fixes_it() {
    let dir = tmp_dir("inputs-draw");
    let out_dir = dir.path().join("draw");
    let (ok, out, err) = oddball(&[
        "task",
        "draw",
        "--draw",
        "HELLO",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(!ok);
    stopped_before_work(&out);
    // The option that fixes it, with a value that works.
    let step = err
        .split("use --step ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("no --step hint in: {err}"));
    assert!(err.contains("leaves the board"), "{err}");
    let (ok, out, err) = oddball(&[
        "task",
        "draw",
        "--draw",
        "HELLO",
        "--step",
        step,
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(ok, "--step {step} from the hint: {err}");
    assert!(out.contains("calibration:"), "{out}");
}

#[test]
fn commands_off_the_board_and_contradictory_options_are_refused_up_front() {
    let dir = tmp_dir("inputs-demo");
    let o = dir.path().join("o");
    let o = o.to_str().unwrap();
    // Nine steps up from the middle of the board leave it (it kept refusing moves for minutes).
    let (ok, out, err) = oddball(&[
        "demo",
        "--commands",
        "up,up,up,up,up,up,up,up,up",
        "--out",
        o,
    ]);
    assert!(!ok);
    stopped_before_work(&out);
    assert!(
        err.contains("checking --commands") && err.contains("use --step"),
        "{err}"
    );
    for (args, expect) in [
        (vec!["--threshold", "0.9"], "--dynamic-stopping"),
        (vec!["--max-rounds", "8"], "--dynamic-stopping"),
        (vec!["--round-limit", "8"], "--optimise-stopping"),
        (vec!["--step=-0.01"], "--step"),
    ] {
        let mut a = vec!["demo", "--out", o];
        a.extend(args.iter().copied());
        let (ok, out, err) = oddball(&a);
        assert!(!ok, "{args:?} ran");
        stopped_before_work(&out);
        assert!(err.contains(expect), "{args:?}: {err}");
    }
}
