//! `oddball decode` behind another program over real LSL streams on loopback: the reference
//! stimulus program (`tools/lsl/play_recording.py`, its own marker texts, pylsl's outlets) plays
//! a recording in real time in one process, `oddball decode` listens in another, and its
//! decisions must be the ones the same causal path decides from the file without LSL
//! (`--markers recording`): the transport loses nothing.
//!
//! Needs `ODDBALL_PLAY_PYTHON`: a Python with pylsl, numpy and oddball's package (`pip install
//! ./python -r tools/lsl/requirements.txt`); CI sets it. Without it the tests print `skipping …`
//! (or fail under `ODDBALL_REQUIRE_DATA=1`). EEG goes out as double64 so that the values arrive
//! exactly; the stamps are the stimulus program's.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::decode::{
    choices as text, decisions, decode_file as offline, json_lines as lines, paradigm, repo,
};
use common::{data_dir, oddball_ok, tmp_dir};

/// The player's Python, and the liblsl its pylsl carries for oddball (set for every child).
fn python(test: &str) -> Option<(String, String)> {
    let py = oddball_testkit::tool(
        "ODDBALL_PLAY_PYTHON",
        test,
        "a Python with pylsl, numpy and oddball's package (pip install ./python -r tools/lsl/requirements.txt)",
    )?;
    let py = py.to_str().unwrap().to_string();
    let lib = oddball_live::lsl::liblsl_of_python(Path::new(&py))
        .expect("the player's Python has pylsl with its liblsl");
    Some((py, lib.to_str().unwrap().to_string()))
}

/// One decode process and one player, started together.
struct Run {
    tag: String,
    decode: Child,
    player: Child,
    out: PathBuf,
    summary: PathBuf,
    played: PathBuf,
}

#[allow(clippy::too_many_arguments)]
fn start(
    (py, lib): &(String, String),
    dir: &Path,
    tag: &str,
    file: &Path,
    paradigm: &str,
    decode_args: &[&str],
    player_args: &[&str],
) -> Run {
    let name = |what: &str| format!("{tag}-{what}-{}", std::process::id());
    let (eeg, markers, outlet) = (name("eeg"), name("markers"), name("decisions"));
    let out = dir.join(format!("{tag}.jsonl"));
    let summary = dir.join(format!("{tag}-summary.json"));
    let played = dir.join(format!("{tag}-played.json"));
    let cfg = repo().join("tools/lsl/lsl_api.cfg");
    let log = |s: &str| std::fs::File::create(dir.join(format!("{tag}-{s}.log"))).unwrap();
    let decode = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["decode", "--source", &format!("lsl:{eeg}")])
        .args(["--markers", &format!("lsl:{markers}")])
        .args(["--paradigm", paradigm, "--outlet", &outlet])
        .args(["--out", out.to_str().unwrap()])
        .args(["--summary", summary.to_str().unwrap()])
        .args(["--resolve-timeout", "120"])
        .args(decode_args)
        .env("LSLAPICFG", &cfg)
        .env("ODDBALL_LIBLSL", lib)
        .stdout(Stdio::null())
        .stderr(log("decode"))
        .spawn()
        .expect("oddball decode starts");
    let player = Command::new(py)
        .arg(repo().join("tools/lsl/play_recording.py"))
        .arg(file)
        .args(["--eeg", &eeg, "--markers", &markers, "--listen", &outlet])
        .args(["--channel-format", "double64", "--wait", "120"])
        .args(["--json-summary", played.to_str().unwrap()])
        .args(player_args)
        .env("LSLAPICFG", &cfg)
        .stdout(log("player"))
        .stderr(Stdio::inherit())
        .spawn()
        .expect("the player starts");
    Run {
        tag: tag.to_string(),
        decode,
        player,
        out,
        summary,
        played,
    }
}

/// Waits for both processes (at most `limit`), then reads the decisions, decode's summary and
/// the player's.
fn finish(
    mut r: Run,
    limit: Duration,
) -> (Vec<serde_json::Value>, serde_json::Value, serde_json::Value) {
    let t0 = Instant::now();
    let wait = |c: &mut Child, what: &str, tag: &str| loop {
        if let Some(s) = c.try_wait().unwrap() {
            return s;
        }
        if t0.elapsed() > limit {
            let _ = c.kill();
            panic!("{tag}: {what} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    let p = wait(&mut r.player, "the player", &r.tag);
    let d = wait(&mut r.decode, "oddball decode", &r.tag);
    let log = |s: &str| {
        let dir = r.out.parent().unwrap();
        std::fs::read_to_string(dir.join(format!("{}-{s}.log", r.tag))).unwrap_or_default()
    };
    assert!(p.success(), "{}: player {p}: {}", r.tag, log("player"));
    assert!(d.success(), "{}: decode {d}: {}", r.tag, log("decode"));
    println!("{}: decode said\n{}", r.tag, log("decode"));
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    (
        lines(&std::fs::read_to_string(&r.out).unwrap()),
        read(&r.summary),
        read(&r.played),
    )
}

/// The same decisions: trials, choices and flashes equal, every posterior within `tol`.
fn assert_same(tag: &str, live: &[serde_json::Value], reference: &[serde_json::Value], tol: f64) {
    let (a, b) = (decisions(live), decisions(reference));
    assert_eq!(
        a.len(),
        b.len(),
        "{tag}: {} vs {} decisions",
        a.len(),
        b.len()
    );
    let mut worst: f64 = 0.0;
    for (x, y) in a.iter().zip(&b) {
        for key in ["trial", "choice", "flashes"] {
            assert_eq!(x[key], y[key], "{tag}: {key}: {x} vs {y}");
        }
        let (px, py) = (
            x["posterior"].as_object().unwrap(),
            y["posterior"].as_object().unwrap(),
        );
        for (k, v) in px {
            worst = worst.max((v.as_f64().unwrap() - py[k].as_f64().unwrap()).abs());
        }
    }
    println!(
        "{tag}: {} decisions equal to the file's; largest posterior difference {worst:e}",
        a.len()
    );
    assert!(worst <= tol, "{tag}: posteriors differ by {worst:e}");
}

fn latency(tag: &str, summary: &serde_json::Value) {
    let (l, s) = (&summary["latency_ms"], &summary["latency_from_stamp_ms"]);
    println!(
        "{tag}: latency from the block taken: median {} ms, 99th percentile {} ms; from the \
         sample's stamp: median {} ms, 99th percentile {} ms; markers {}",
        l[0], l[1], s[0], s[1], summary["markers"]
    );
}

#[test]
fn eeg3_played_in_real_time_spells_6mk_as_from_the_file_also_30_ms_off() {
    let test = "eeg3 decoded over LSL";
    let Some(py) = python(test) else { return };
    let Some(d) = data_dir() else { return };
    let d = d.join("bci2000-samplefiles-p300");
    let tmp = tmp_dir("cli-decode-lsl-eeg3");
    let model = tmp.join("eeg3.json");
    oddball_ok(&[
        "train",
        d.join("eeg3_1.dat").to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
    ]);
    let file = d.join("eeg3_2.dat");
    let p = paradigm("speller-6x6-rows-first.toml");
    let m = ["--model", model.to_str().unwrap()];
    let reference = offline(&file, &p, &m);
    assert_eq!(text(&reference), "6MK?");
    let plain = start(&py, tmp.path(), "eeg3", &file, &p, &m, &[]);
    let off = start(
        &py,
        tmp.path(),
        "eeg3-30ms",
        &file,
        &p,
        &m,
        &["--clock-offset-ms", "30"],
    );
    let limit = Duration::from_secs(222 + 240);
    for (tag, run) in [("eeg3", plain), ("eeg3 30 ms off", off)] {
        let (live, summary, _) = finish(run, limit);
        assert_eq!(text(&live), "6MK?", "{tag}");
        assert_same(tag, &live, &reference, 1e-12);
        latency(tag, &summary);
        assert_eq!(summary["markers"]["unknown"], 0, "{tag}");
        assert_eq!(summary["markers"]["too_old"], 0, "{tag}");
    }
}

#[test]
fn bci_competition_iib_test_runs_over_lsl_with_a_model_and_without_calibration() {
    let test = "IIb decoded over LSL";
    let Some(py) = python(test) else { return };
    let Some(d) = data_dir() else { return };
    let d = d.join("bci-competition-ii-iib");
    let tmp = tmp_dir("cli-decode-lsl-iib");
    let model = tmp.join("iib.json");
    let train: Vec<String> = ["AAS010R01", "AAS010R02", "AAS011R01", "AAS011R02"]
        .iter()
        .map(|r| d.join(format!("{r}.mat")).to_str().unwrap().to_string())
        .collect();
    let mut args = vec!["train"];
    args.extend(train.iter().map(String::as_str));
    args.extend(["-o", model.to_str().unwrap()]);
    oddball_ok(&args);
    let p = paradigm("speller-6x6.toml");
    let m = ["--model", model.to_str().unwrap()];
    let none = ["--calibration", "none"];
    let mut runs = Vec::new();
    for (run, word) in [("AAS012R03", "HAM"), ("AAS012R04", "PIE")] {
        let file = d.join(format!("{run}.mat"));
        let with_model = offline(&file, &p, &m);
        assert_eq!(text(&with_model), word, "{run} from the file");
        let unlabelled = offline(&file, &p, &none);
        runs.push((
            start(&py, tmp.path(), &format!("{run}-model"), &file, &p, &m, &[]),
            with_model,
        ));
        runs.push((
            start(
                &py,
                tmp.path(),
                &format!("{run}-none"),
                &file,
                &p,
                &none,
                &[],
            ),
            unlabelled,
        ));
    }
    for (run, reference) in runs {
        let tag = run.tag.clone();
        let (live, summary, _) = finish(run, Duration::from_secs(110 + 300));
        println!(
            "{tag}: {} over LSL, {} from the file",
            text(&live),
            text(&reference)
        );
        assert_same(&tag, &live, &reference, 1e-12);
        latency(&tag, &summary);
    }
}

#[test]
fn a_demo_session_as_a_foreign_paradigm_decides_as_the_demo_and_stops_early_when_sure() {
    let test = "a demo session decoded over LSL";
    let Some(py) = python(test) else { return };
    let tmp = tmp_dir("cli-decode-lsl-demo");
    let out = tmp.join("demo");
    oddball_ok(&[
        "demo",
        "--commands",
        "up,right,down,left",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (session, model) = (out.join("session.dat"), out.join("model.json"));
    let p = paradigm("four-bulb.toml");
    let m = ["--model", model.to_str().unwrap()];
    let reference = offline(&session, &p, &m);
    // Four times real time (the session is over 7 minutes); after a stop the program resumes
    // 5 s (the paper's countdown) before the next trial's first flash, so a stop saves flashing
    // time only.
    let speed = ["--speed", "4", "--resume-before", "5"];
    let plain = start(&py, tmp.path(), "demo", &session, &p, &m, &speed);
    let mut dynamic: Vec<&str> = m.to_vec();
    dynamic.push("--dynamic-stopping");
    let stopping = start(&py, tmp.path(), "demo-stop", &session, &p, &dynamic, &speed);
    let limit = Duration::from_secs(600);
    let (live, _, played) = finish(plain, limit);
    assert_same("demo", &live, &reference, 1e-12);
    // The demo's own decisions are the session's last ones (after its calibration trials).
    let csv = std::fs::read_to_string(out.join("decisions.csv")).unwrap();
    let demo: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().to_string())
        .collect();
    let all = text(&live);
    let ours: Vec<String> = decisions(&live)[decisions(&live).len() - demo.len()..]
        .iter()
        .map(|d| d["choice"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(ours, demo, "{all}");
    let (fast, summary, fast_played) = finish(stopping, limit);
    let (a, b) = (decisions(&live), decisions(&fast));
    assert_eq!(a.len(), b.len());
    let right = |v: &[serde_json::Value]| {
        v.iter()
            .zip(&a)
            .filter(|(x, y)| x["choice"] == y["choice"])
            .count()
    };
    let flashes = |v: &[serde_json::Value]| -> u64 {
        v.iter().map(|d| d["flashes_shown"].as_u64().unwrap()).sum()
    };
    let minutes = |p: &serde_json::Value| p["total_seconds"].as_f64().unwrap() / 60.0;
    let n = a.len() as f64;
    let bits = |p: f64| {
        let k = 4.0f64;
        if p >= 1.0 {
            k.log2()
        } else {
            k.log2() + p * p.log2() + (1.0 - p) * ((1.0 - p) / (k - 1.0)).log2()
        }
    };
    let acc = right(&b) as f64 / n;
    println!(
        "demo over LSL: {} flashes per decision, {:.2} bits/min; with stop: {} flashes per decision, {} of {} as without, {:.2} bits/min (stream minutes {:.2} vs {:.2})",
        flashes(&a) as f64 / n,
        n * bits(1.0) / minutes(&played),
        flashes(&b) as f64 / n,
        right(&b),
        b.len(),
        n * bits(acc) / minutes(&fast_played),
        minutes(&played),
        minutes(&fast_played),
    );
    latency("demo with stop", &summary);
    assert!(flashes(&b) < flashes(&a), "stopping saved no flash");
    assert!(
        acc >= 0.95,
        "{} of {} decided as without stopping",
        right(&b),
        b.len()
    );
    assert!(summary["stops"].as_u64().unwrap() > 0);
}

/// A stimulus program that misbehaves: unknown texts, a code no choice has, flashes stamped
/// 100 s ahead and 100 s back, then its marker stream disappears, then its EEG stops. Nothing is
/// fatal: the bad markers are counted, the lost marker stream is reported, and the run ends
/// cleanly when the EEG stalls, with the trials decided before written.
const BAD_PROGRAM: &str = r#"
import sys, time, numpy as np, pylsl
name = sys.argv[1]
info = pylsl.StreamInfo(name + "-eeg", "EEG", 4, 250, "float32", name + "-e")
ch = info.desc().append_child("channels")
for label in ["Pz", "Oz", "P3", "P4"]:
    c = ch.append_child("channel"); c.append_child_value("label", label); c.append_child_value("unit", "microvolts")
eeg = pylsl.StreamOutlet(info)
mk = pylsl.StreamOutlet(pylsl.StreamInfo(name + "-markers", "Markers", 1, 0, "string", name + "-m"))
deadline = time.monotonic() + 120
while not (eeg.have_consumers() and mk.have_consumers()) and time.monotonic() < deadline:
    time.sleep(0.05)
rng = np.random.default_rng(1)
t0 = pylsl.local_clock()
k = 0
def until(t):
    global k
    while k / 250 < t:
        n = 5
        x = rng.uniform(-5, 5, (n, 4)).astype(np.float32)
        stamps = [t0 + (k + j) / 250 for j in range(n)]
        while pylsl.local_clock() < stamps[-1]:
            time.sleep(0.002)
        eeg.push_chunk(x, stamps)
        k += n
t = 1.0
for trial in range(3):
    until(t)
    if trial == 2:
        mk = None  # the marker stream disappears
        time.sleep(1.0)
    if mk is not None:
        mk.push_sample(["TrialStart"], t0 + t - 0.1)
        mk.push_sample(["Hello"], t0 + t)
        mk.push_sample(["Stim/9"], t0 + t)
        mk.push_sample(["Stim/1"], t0 + t + 100)
        mk.push_sample(["Stim/2"], t0 + t - 100)
    for r in range(5):
        for code in [1, 2, 3, 4]:
            until(t)
            if mk is not None:
                mk.push_sample([f"Stim/{code}"], t0 + t)
            t += 0.24
    if mk is not None:
        mk.push_sample(["TrialEnd"], t0 + t - 0.24)
    t += 1.0
until(t + 2.0)
"#;

#[test]
fn a_misbehaving_program_costs_counts_not_the_session() {
    let test = "decode against a misbehaving program";
    let Some((py, lib)) = python(test) else {
        return;
    };
    let tmp = tmp_dir("cli-decode-lsl-bad");
    let name = format!("bad-{}", std::process::id());
    let cfg = repo().join("tools/lsl/lsl_api.cfg");
    let out = tmp.join("d.jsonl");
    let summary = tmp.join("s.json");
    let decode = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(["decode", "--source", &format!("lsl:{name}-eeg")])
        .args(["--markers", &format!("lsl:{name}-markers")])
        .args(["--paradigm", &paradigm("four-bulb.toml")])
        .args(["--calibration", "none", "--outlet", "none"])
        .args(["--out", out.to_str().unwrap()])
        .args(["--summary", summary.to_str().unwrap()])
        .env("LSLAPICFG", &cfg)
        .env("ODDBALL_LIBLSL", &lib)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let program = Command::new(&py)
        .args(["-c", BAD_PROGRAM, &name])
        .env("LSLAPICFG", &cfg)
        .status()
        .unwrap();
    assert!(program.success());
    let t0 = Instant::now();
    let mut decode = decode;
    while decode.try_wait().unwrap().is_none() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "decode did not stop"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let o = decode.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    println!("{err}\n{s}");
    let m = &s["markers"];
    assert_eq!(m["unknown"], 4, "{m}"); // Hello and Stim/9, twice
    assert_eq!(m["future"], 2, "{m}");
    assert_eq!(m["too_old"], 2, "{m}");
    assert_eq!(m["flashes"], 40, "{m}");
    // The marker stream's end is reported (its outlet closed), and the session went on.
    assert!(s["marker_stream"].as_str().unwrap().contains("gone"), "{s}");
    let ended = s["ended"].as_str().unwrap();
    assert!(ended.contains("nothing") || ended.contains("lost"), "{s}");
    // The two trials with markers are decided and written.
    let v = lines(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(decisions(&v).len(), 2, "{v:?}");
}
