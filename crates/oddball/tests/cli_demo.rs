//! `oddball demo`: the closed loop through the command line, its report folder, its
//! determinism, and the saved session re-evaluated by `oddball evaluate`.

mod common;

use std::path::Path;

fn tmp(name: &str) -> oddball_testkit::TempDir {
    oddball_testkit::TempDir::new(&format!("demo-{name}"))
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json written");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

#[test]
fn demo_draws_the_g_deterministically_and_its_session_re_evaluates_to_the_same_decisions() {
    let (a, b) = (tmp("a"), tmp("b"));
    let (ok, out_a, err) = common::oddball(&["demo", "--out", a.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, out_b, err) = common::oddball(&["demo", "--out", b.to_str().unwrap()]);
    assert!(ok, "{err}");
    // Stdout and every file depend only on the options (wall time goes to stderr).
    assert_eq!(
        out_a.replace(a.to_str().unwrap(), "DIR"),
        out_b.replace(b.to_str().unwrap(), "DIR")
    );
    assert!(err.contains("wall time"), "{err}");
    for f in [
        "decisions.csv",
        "summary.json",
        "model.json",
        "erp.png",
        "pen_trace.png",
        "session.dat",
    ] {
        let (x, y) = (std::fs::read(a.join(f)), std::fs::read(b.join(f)));
        assert!(x.is_ok(), "{f} written");
        assert!(
            x.unwrap() == y.unwrap(),
            "{f} differs between two runs of one seed"
        );
    }
    // The G of the stroke font: 20 decisions, each printed with intended, decided, rounds and
    // confidence.
    let lines: Vec<&str> = out_a
        .lines()
        .filter(|l| l.starts_with("decision "))
        .collect();
    assert_eq!(lines.len(), 20, "{out_a}");
    let s = summary(&a);
    assert!(s["result"]["accuracy"].as_f64().unwrap() >= 0.95, "{out_a}");
    assert!(s["pen"]["drew_intended_path"].as_bool().unwrap());
    assert!(s["pen"]["max_corner_error_mm"].as_f64().unwrap() < 0.5);
    assert_eq!(s["pen"]["corners_m"].as_array().unwrap().len(), 20);
    // The pen's corners trace a G: back, top, bottom, the right side's two corners and the
    // spur's tip (not the 4 corners of a square).
    let corners = pen_corners(&s);
    assert!(corners.len() >= 6, "{corners:?}\n{out_a}");
    // Every decision right: nothing marked, the executed path is the intended one.
    assert_eq!(s["pen"]["missed"].as_array().unwrap().len(), 0);
    assert_eq!(s["pen"]["intended_m"], s["pen"]["executed_m"]);
    assert!(s["result"]["itr"]["bits_per_minute"].as_f64().unwrap() > 5.0);
    let csv = std::fs::read_to_string(a.join("decisions.csv")).unwrap();
    assert_eq!(csv.lines().count(), 21);
    assert!(csv.starts_with("decision,intended,decided,"));

    // The saved raw session, re-evaluated offline with the saved model: the same decisions.
    let (ok, out, err) = common::oddball(&[
        "evaluate",
        "--model",
        a.join("model.json").to_str().unwrap(),
        "--test",
        a.join("session.dat").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("20 online decisions: 20 identical to the recorded ones"),
        "{out}"
    );
    // The session file is a recording like any other.
    let (ok, out, err) = common::oddball(&["inspect", a.join("session.dat").to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("500"), "{out}");
    std::fs::remove_dir_all(&a).ok();
    std::fs::remove_dir_all(&b).ok();
}

/// The distinct corners of the pen's path in a demo's summary (to the millimetre): its start,
/// its end and every point where it turns, each counted once however often it is visited.
fn pen_corners(s: &serde_json::Value) -> Vec<(i64, i64)> {
    let xz = |p: &serde_json::Value| {
        let mm = |v: &serde_json::Value| (v.as_f64().unwrap() * 1e3).round() as i64;
        (mm(&p[0]), mm(&p[1]))
    };
    // Where the pen was at the first decision, then after each executed command.
    let mut path = vec![xz(&s["decisions"][0]["pen_m"])];
    path.extend(s["pen"]["corners_m"].as_array().unwrap().iter().map(xz));
    path.dedup();
    let heading = |a: (i64, i64), b: (i64, i64)| ((b.0 - a.0).signum(), (b.1 - a.1).signum());
    let mut corners: Vec<(i64, i64)> = Vec::new();
    for (i, &p) in path.iter().enumerate() {
        let turns =
            i == 0 || i + 1 == path.len() || heading(path[i - 1], p) != heading(p, path[i + 1]);
        if turns && !corners.contains(&p) {
            corners.push(p);
        }
    }
    corners
}

#[test]
fn the_papers_six_commands_are_one_option_away_and_trace_a_square() {
    let dir = tmp("paper-g");
    let (ok, out, err) = common::oddball(&[
        "demo",
        "--commands",
        "paper-g",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let s = summary(&dir);
    assert_eq!(s["result"]["decisions"].as_u64(), Some(6), "{out}");
    assert!(s["pen"]["drew_intended_path"].as_bool().unwrap(), "{out}");
    // Up, left, down, right, up, left on equal steps: a square's 4 corners, one and a half
    // times round. The help says why.
    assert_eq!(pen_corners(&s).len(), 4, "{out}");
    let (ok, help, _) = common::oddball(&["demo", "--help"]);
    assert!(
        ok && help.contains("paper-g") && help.contains("square"),
        "{help}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn dynamic_stopping_is_reported_beside_fixed_rounds() {
    let dir = tmp("dyn");
    let (ok, out, err) = common::oddball(&[
        "demo",
        "--dynamic-stopping",
        "--subject",
        "easy",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("dynamic stopping"), "{out}");
    assert!(out.contains("fixed 5 rounds"), "{out}");
    let s = summary(&dir);
    let dynamic = s["result"]["mean_rounds"].as_f64().unwrap();
    let fixed = s["fixed_rounds_for_comparison"]["mean_rounds"]
        .as_f64()
        .unwrap();
    assert_eq!(fixed, 5.0);
    assert!(dynamic < fixed, "{out}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn replay_of_real_speller_eeg_reports_accuracy_and_itr() {
    let Some(data) = common::data_dir() else {
        return;
    };
    let file = data.join("bci2000-samplefiles-p300/eeg3_2.dat");
    let dir = tmp("replay");
    let subject = format!("replay:{}", file.display());
    let (ok, out, err) = common::oddball(&[
        "demo",
        "--subject",
        &subject,
        "--dynamic-stopping",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("eeg3_1.dat"),
        "calibrates on the sibling file: {out}"
    );
    let s = summary(&dir);
    assert_eq!(s["result"]["decisions"].as_u64().unwrap(), 24);
    // Measured: 23/24 with dynamic stopping, 24/24 with fixed 5 rounds (lda).
    assert!(s["result"]["accuracy"].as_f64().unwrap() >= 0.75, "{out}");
    assert!(
        s["fixed_rounds_for_comparison"]["accuracy"]
            .as_f64()
            .unwrap()
            >= 0.75
    );
    assert!(!dir.join("session.dat").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_options_are_clear_errors() {
    let base = tmp("sleepy");
    let out = base.join("out");
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--subject",
        "sleepy",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("sleepy"), "{err}");
    assert!(!out.exists(), "nothing written for a refused subject");
    let (ok, _, err) = common::oddball(&["demo", "--commands", "up,jump"]);
    assert!(!ok);
    assert!(err.contains("jump"), "{err}");
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--subject",
        "replay:/nonexistent/eeg9_2.dat",
        "--out",
        tmp("bad").to_str().unwrap(),
    ]);
    assert!(!ok);
    // A missing replayed file is named itself (it used to be blamed on its calibration file).
    assert!(err.contains("eeg9_2.dat: no such file"), "{err}");
    // One that exists without an _1 sibling needs --calibration.
    let lone = tmp("lone");
    std::fs::create_dir_all(&lone).unwrap();
    std::fs::write(lone.join("eeg9_2.dat"), b"").unwrap();
    let (ok, _, err) = common::oddball(&[
        "demo",
        "--subject",
        &format!("replay:{}", lone.join("eeg9_2.dat").display()),
        "--out",
        tmp("bad").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("--calibration"), "{err}");
}
