//! `oddball online` without a browser: the simulated subject paced by the wall clock, flashes
//! on schedule, recorded to XDF as it runs. A recording cut by `kill -9` opens and holds every
//! sample up to the last flushed block.

mod common;

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use oddball_session::subject::{SubjectParams, SubjectPreset};

fn tmp(name: &str) -> oddball_testkit::TempDir {
    common::tmp_dir(&format!("online-{name}"))
}

/// A model from a (fast, unpaced) demo run, with the folder that holds it (removed on drop).
fn model() -> (oddball_testkit::TempDir, PathBuf) {
    let dir = tmp("model");
    let model = common::demo_model(&dir);
    (dir, model)
}

#[test]
fn a_recording_cut_by_kill_9_opens_and_holds_every_flushed_sample() {
    let (_model_dir, model) = model();
    let out = tmp("kill");
    let mut child = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["online", "--model", model.to_str().unwrap(), "--seed", "7"])
        .args(["--sim-latency-ms", "20", "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("oddball online starts");
    let mut first = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("oddball online: source sim"), "{first}");
    let started = Instant::now();
    std::thread::sleep(Duration::from_millis(3500));
    child.kill().expect("SIGKILL"); // kill -9: no destructor, no footer
    child.wait().unwrap();
    let ran = started.elapsed().as_secs_f64();

    let path = out.join("session.xdf");
    let rec = oddball_io::read(&path).expect("the cut recording opens");
    let info = rec.xdf().expect("an XDF recording");
    assert!(!info.finished(), "no footers after kill -9");
    let n = rec.raw.n_times();
    // Samples are flushed per 20-sample block as the wall clock passes: all but the last
    // block(s) of the ~3.5 s are there (start-up and the 20 ms latency cost a little).
    assert!(
        n as f64 >= (ran - 1.0) * 500.0 && n as f64 <= (ran + 0.1) * 500.0,
        "{n} samples after {ran:.2} s"
    );
    assert_eq!(n % 20, 0, "whole blocks only: {n}");
    // The first trial's countdown (5 s) has no flash: the recording equals a fresh subject of
    // the same seed, sample for sample (float32 on disk).
    let mut sim = SubjectParams::preset(SubjectPreset::Typical)
        .with_seed(7)
        .build()
        .unwrap();
    let fresh = sim.render(n);
    let data = rec.raw.data();
    for c in 0..fresh.nrows() {
        for t in 0..n {
            assert_eq!(
                data[[c, t]],
                f64::from(fresh[[c, t]] as f32),
                "channel {c}, sample {t}"
            );
        }
    }
    // pyxdf, a standard reader, opens it too (when ODDBALL_PYXDF names a python with pyxdf).
    if let Some(py) =
        oddball_testkit::tool("ODDBALL_PYXDF", "the pyxdf check", "a python with pyxdf")
    {
        let script = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tools/golden/xdf/pyxdf_read.py"
        );
        let o = Command::new(py).arg(script).arg(&path).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = String::from_utf8_lossy(&o.stdout);
        assert!(s.contains(&format!("{n}")), "pyxdf sees {n} samples: {s}");
    }
}

#[test]
fn online_says_what_is_wrong_before_it_starts() {
    let (_model_dir, model) = model();
    let m = model.to_str().unwrap();
    let out = tmp("errors");
    let o = out.to_str().unwrap();
    let (ok, _, err) =
        common::oddball(&["online", "--model", m, "--serve", "0.0.0.0:0", "--out", o]);
    assert!(!ok && err.contains("loopback"), "{err}");
    let (ok, _, err) = common::oddball(&["online", "--model", m, "--source", "nope", "--out", o]);
    assert!(
        !ok && err.contains("expected sim, nic:HOST:PORT, lsl:NAME or replay:FILE"),
        "{err}"
    );
    let (ok, _, err) = common::oddball(&["online", "--source", "sim"]);
    assert!(!ok && err.contains("--model"), "{err}");
    let (ok, _, err) =
        common::oddball(&["online", "--model", "/nonexistent/model.json", "--out", o]);
    assert!(!ok && err.contains("/nonexistent/model.json"), "{err}");
    let (ok, _, err) = common::oddball(&[
        "online",
        "--model",
        m,
        "--serve",
        "127.0.0.1:0",
        "--wait-page",
        "0.3",
        "--out",
        o,
    ]);
    assert!(!ok && err.contains("no page opened the panel"), "{err}");
}

/// The decision lines of `oddball online`'s output, e.g. `decision 1: up → up ✓ (…)`.
fn decisions(stdout: &str) -> Vec<&str> {
    stdout
        .lines()
        .filter(|l| l.starts_with("decision "))
        .collect()
}

#[test]
fn a_recorded_session_replays_to_the_same_decisions_and_stops_at_the_end_of_the_file() {
    let (_model_dir, model) = model();
    let m = model.to_str().unwrap();
    let out = tmp("replay");
    let (rec_dir, again, other) = (out.join("rec"), out.join("again"), out.join("other"));
    // Recorded in real time (one decision: ~11 s).
    let (ok, recorded, err) = common::oddball(&[
        "online",
        "--model",
        m,
        "--seed",
        "3",
        "--commands",
        "up",
        "--sim-latency-ms",
        "20",
        "--out",
        rec_dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let file = format!("replay:{}", rec_dir.join("session.xdf").display());
    // `oddball online --model M --seed SEED --commands C --source FILE --fast --out DIR`.
    let replay = |seed: &str, commands: &str, out: &std::path::Path| {
        common::oddball(&[
            "online",
            "--model",
            m,
            "--seed",
            seed,
            "--commands",
            commands,
            "--source",
            &file,
            "--fast",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    // Played back as fast as it goes, same seed and commands: the same decision, every flash
    // on a flash of the file.
    let (ok, replayed, err) = replay("3", "up", &again);
    assert!(ok, "{err}");
    assert!(replayed.starts_with("replaying "), "{replayed}");
    let d = decisions(&recorded);
    assert_eq!(d.len(), 1, "{recorded}");
    // The line ends with the posterior and timing; the choice and rounds are what must agree.
    let head = |l: &str| l.split(" (p ").next().unwrap().to_string();
    assert_eq!(
        decisions(&replayed)
            .iter()
            .map(|l| head(l))
            .collect::<Vec<_>>(),
        vec![head(d[0])],
        "{replayed}"
    );
    assert!(
        replayed
            .contains("replay: 20 of 20 flashes of this session fall on a flash of the same bulb"),
        "{replayed}"
    );
    // One command more: the file ends before the second decision: a clean stop with the
    // summary written, exit status 3 (stopped before its end), no error.
    let (ok, short, err) = replay("3", "up,left", &other);
    assert!(!ok && !err.contains("error"), "{err}");
    assert!(short.contains("ended after"), "{short}");
    assert!(
        short.contains("(1 of 2 made before the session stopped)"),
        "{short}"
    );
    let summary = std::fs::read_to_string(other.join("summary.json")).unwrap();
    assert!(summary.contains("\"ended\": \"the recording"), "{summary}");
    // Another seed: its flashes are not the file's. Refused before anything is decided on EEG
    // that holds no response to them (issue #30: such a replay decided with p 1.000).
    let (ok, wrong, err) = replay("4", "up", &out.join("wrong"));
    assert!(
        !ok && err.contains("does not hold this session's flashes"),
        "{err}"
    );
    assert!(decisions(&wrong).is_empty(), "{wrong}");
    // A recording in another format holds no flash as drawn: it plays as EEG under this
    // session's own flashes, and the run says its decisions mean nothing.
    let csv = out.join("foreign.csv");
    let (data, markers, sfreq) = oddball_testkit::synthetic_oddball(8, 5);
    oddball_testkit::write_codes_csv(&csv, &data, &markers, sfreq);
    let (_, said, _) = common::oddball(&[
        "online",
        "--calibrate",
        "--calibration-per-bulb",
        "2",
        "--fast",
        "--commands",
        "up",
        "--source",
        &format!("replay:{}", csv.display()),
        "--out",
        out.join("foreign").to_str().unwrap(),
    ]);
    assert!(
        said.contains("is not an XDF recording") && said.contains("mean nothing"),
        "{said}"
    );
    // Errors: --fast with a live stream, a file that is not there.
    let (ok, _, err) = common::oddball(&[
        "online",
        "--model",
        m,
        "--fast",
        "--source",
        "nic:127.0.0.1:9",
    ]);
    assert!(!ok && err.contains("--fast plays back a file"), "{err}");
    let (ok, _, err) = common::oddball(&[
        "online",
        "--model",
        m,
        "--source",
        "replay:/nonexistent/session.xdf",
    ]);
    assert!(!ok && err.contains("/nonexistent/session.xdf"), "{err}");
}
