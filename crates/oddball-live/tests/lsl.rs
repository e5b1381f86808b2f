//! Lab Streaming Layer on loopback: EEG and marker streams between this crate's outlets and
//! inlets, and with real peers (Python pylsl, when `ODDBALL_PYLSL` names a python that has it;
//! see tools/lsl/requirements.txt).
//!
//! Every stream name carries the process id, and liblsl is kept on this machine by
//! tools/lsl/lsl_api.cfg (`LSLAPICFG`, set before the first LSL call).
#![cfg(feature = "lsl")]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Once;
use std::time::{Duration, Instant};

use ndarray::Array2;
use oddball_live::lsl::{
    local_clock, EegInlet, EegOutlet, MarkerInlet, MarkerOutlet, StreamQuery, DECISION_TYPE,
};
use oddball_live::LiveError;

fn lsl_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tools/lsl/lsl_api.cfg")
        .canonicalize()
        .expect("tools/lsl/lsl_api.cfg")
}

/// Points liblsl at the loopback configuration before any test makes an LSL call.
fn setup() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| std::env::set_var("LSLAPICFG", lsl_config()));
}

fn unique(what: &str) -> String {
    format!("oddball-test-{what}-{}", std::process::id())
}

fn labels(n: usize) -> Vec<String> {
    (1..=n).map(|c| format!("E{c}")).collect()
}

#[test]
fn eeg_round_trip_keeps_values_timestamps_and_labels() {
    setup();
    let name = unique("eeg");
    let chs = labels(8);
    let outlet = EegOutlet::new(&name, &chs, 500.0, &name).unwrap();
    let mut inlet = EegInlet::resolve(&StreamQuery::Name(name.clone()), 10.0).unwrap();
    assert_eq!(inlet.name(), name);
    assert_eq!(inlet.sfreq(), 500.0);
    assert_eq!(inlet.ch_names(), &chs[..]);
    assert!(outlet.have_consumers());

    // Float32-exact values: row c, column i = 100 c + i / 4 - 30.
    let n = 300;
    let data = Array2::from_shape_fn((8, n), |(c, i)| 100.0 * c as f64 + i as f64 / 4.0 - 30.0);
    let t0 = local_clock();
    outlet.push_chunk(data.view(), t0);
    let (got, ts) = inlet.read(n).unwrap();
    assert_eq!(got, data);
    assert_eq!(ts.len(), n);
    for (i, t) in ts.iter().enumerate() {
        let want = t0 + i as f64 / 500.0;
        assert!((t - want).abs() < 1e-3, "sample {i}: {t} vs {want}");
    }
    assert_eq!(inlet.lost_samples(), 0);

    // A chunk 10 samples late: 10 lost. Read on another thread (the inlet is Send).
    let later = t0 + (n + 10) as f64 / 500.0;
    outlet.push_chunk(data.view(), later);
    let reader = std::thread::spawn(move || {
        let r = inlet.read(n);
        (r, inlet)
    });
    let (r, inlet) = reader.join().unwrap();
    let (got, ts) = r.unwrap();
    assert_eq!(got, data);
    assert!((ts[0] - later).abs() < 1e-3);
    assert_eq!(inlet.lost_samples(), 10);
}

#[test]
fn volts_millivolts_and_nanovolts_arrive_in_microvolts() {
    setup();
    for (unit, per_uv) in [("volts", 1e-6), ("millivolts", 1e-3), ("nanovolts", 1e3)] {
        let name = unique(&format!("unit-{unit}"));
        let outlet = EegOutlet::with_unit(&name, &labels(2), 100.0, &name, unit).unwrap();
        let mut inlet = EegInlet::resolve(&StreamQuery::Name(name.clone()), 10.0).unwrap();
        let uv = Array2::from_shape_fn((2, 50), |(c, i)| (c as f64 + 1.0) * (i as f64 - 20.0));
        outlet.push_chunk((&uv * per_uv).view(), local_clock());
        let (got, _) = inlet.read(50).unwrap();
        for (g, w) in got.iter().zip(&uv) {
            assert!(
                (g - w).abs() <= 1e-5 * w.abs().max(1.0),
                "{unit}: {g} vs {w}"
            );
        }
    }
    // Not a voltage: refused, naming the unit.
    let name = unique("unit-counts");
    let _outlet = EegOutlet::with_unit(&name, &labels(2), 100.0, &name, "counts").unwrap();
    match EegInlet::resolve(&StreamQuery::Name(name), 10.0) {
        Err(e @ LiveError::InvalidParameter { .. }) => {
            assert!(e.to_string().contains("counts"), "{e}")
        }
        other => panic!("expected a unit error, got {other:?}"),
    }
}

/// Polls `inlet` until `n` markers have come (10 s at most).
fn pull_n(inlet: &mut MarkerInlet, n: usize) -> Vec<(String, f64)> {
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut got = Vec::new();
    while got.len() < n && Instant::now() < deadline {
        got.extend(inlet.pull().unwrap());
        std::thread::sleep(Duration::from_millis(5));
    }
    got
}

#[test]
fn markers_and_decisions_round_trip() {
    setup();
    let name = unique("markers");
    let outlet = MarkerOutlet::new(&name, &name).unwrap();
    let mut inlet = MarkerInlet::resolve(&StreamQuery::Name(name.clone()), 10.0).unwrap();
    assert_eq!(inlet.name(), name);
    assert!(outlet.have_consumers());
    assert!(inlet.pull().unwrap().is_empty());
    let t = local_clock();
    let sent = [
        ("cue 2", t),
        ("flash 1", t + 0.125),
        ("flash 2", t + 0.25),
        ("end", t + 0.5),
    ];
    for (m, ts) in sent {
        outlet.push(m, ts);
    }
    let got = pull_n(&mut inlet, sent.len());
    assert_eq!(got.len(), sent.len(), "{got:?}");
    for ((m, ts), (gm, gts)) in sent.iter().zip(&got) {
        assert_eq!(m, gm);
        assert!((ts - gts).abs() < 1e-3, "{m}: {gts} vs {ts}");
    }

    // The decision stream: another type, found by name; timestamp 0 = now.
    let dname = unique("decisions");
    let decisions = MarkerOutlet::with_type(&dname, DECISION_TYPE, &dname).unwrap();
    let mut dinlet = MarkerInlet::resolve(&StreamQuery::Name(dname), 10.0).unwrap();
    let before = local_clock();
    decisions.push("decision 3", 0.0);
    let got = pull_n(&mut dinlet, 1);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].0, "decision 3");
    assert!(got[0].1 >= before - 1e-3 && got[0].1 <= local_clock() + 1e-3);
}

#[test]
fn a_stream_that_goes_away_stalls_the_reader() {
    setup();
    let name = unique("stall");
    let outlet = EegOutlet::new(&name, &labels(4), 250.0, &name).unwrap();
    let mut inlet = EegInlet::resolve(&StreamQuery::Name(name.clone()), 10.0).unwrap();
    inlet.set_stall_timeout(0.5);
    outlet.push_chunk(Array2::zeros((4, 25)).view(), local_clock());
    assert_eq!(inlet.read(25).unwrap().0.dim(), (4, 25));
    drop(outlet);
    let start = Instant::now();
    match inlet.read(25) {
        Err(LiveError::StreamStalled { name: n, seconds }) => {
            assert_eq!(n, name);
            assert_eq!(seconds, 0.5);
        }
        other => panic!("expected StreamStalled, got {other:?}"),
    }
    let waited = start.elapsed().as_secs_f64();
    assert!((0.45..3.0).contains(&waited), "{waited} s");
}

#[test]
fn resolving_nothing_times_out_naming_the_query() {
    setup();
    let name = unique("nobody");
    let start = Instant::now();
    let err = EegInlet::resolve(&StreamQuery::Name(name.clone()), 0.5).unwrap_err();
    // Bounded (liblsl cancels the search at the timeout); generous for a loaded machine.
    assert!(
        start.elapsed() < Duration::from_secs(15),
        "{:?}",
        start.elapsed()
    );
    assert!(
        matches!(&err, LiveError::StreamNotFound { query, timeout_s }
            if query == &format!("name={name}") && *timeout_s == 0.5),
        "{err:?}"
    );
    assert!(err.to_string().contains(&name), "{err}");
    let ty = unique("no-such-type");
    let err = MarkerInlet::resolve(&StreamQuery::Type(ty.clone()), 0.3).unwrap_err();
    assert!(err.to_string().contains(&format!("type={ty}")), "{err}");
}

// ---- real peers: Python pylsl ----

/// The python with pylsl, or `None` (and a skip line) when `ODDBALL_PYLSL` is not set.
fn pylsl(test: &str) -> Option<String> {
    oddball_testkit::tool(
        "ODDBALL_PYLSL",
        test,
        "a python with pylsl: python3 -m venv /tmp/pylsl-venv && /tmp/pylsl-venv/bin/pip install -r \
         tools/lsl/requirements.txt; ODDBALL_PYLSL=/tmp/pylsl-venv/bin/python",
    )
    .map(|p| p.to_string_lossy().into_owned())
}

fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tools/lsl")
        .join(name)
}

/// Kills the child on drop (a failing test leaves no python behind).
struct Peer(Child);

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn spawn_python(python: &str, script_name: &str, args: &[&str]) -> Peer {
    Peer(
        Command::new(python)
            .arg(script(script_name))
            .args(args)
            .env("LSLAPICFG", lsl_config())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("starting {python} {script_name}: {e}")),
    )
}

#[test]
fn pylsl_eeg_is_read_with_its_values_timestamps_units_and_gap() {
    setup();
    let Some(python) = pylsl("pylsl_eeg_is_read_with_its_values_timestamps_units_and_gap") else {
        return;
    };
    let name = unique("pylsl-eeg");
    let mut peer = spawn_python(
        &python,
        "push_eeg.py",
        &[
            "--name",
            &name,
            "--seconds",
            "3",
            "--unit",
            "millivolts",
            "--gap-at",
            "700",
            "--gap",
            "25",
        ],
    );
    let mut inlet = EegInlet::resolve(&StreamQuery::Name(name.clone()), 20.0).unwrap();
    let mut out = BufReader::new(peer.0.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let head: serde_json::Value = serde_json::from_str(&line).expect(&line);
    let t0 = head["t0"].as_f64().unwrap();
    let n = head["samples"].as_u64().unwrap() as usize;
    assert_eq!(n, 1500 - 25);
    assert_eq!(inlet.sfreq(), 500.0);
    assert_eq!(inlet.ch_names()[0], "EEG1");
    assert_eq!(inlet.ch_names()[7], "EEG8");

    let (x, ts) = inlet.read(n).unwrap();
    assert_eq!(x.dim(), (8, n));
    let mut seen = Vec::with_capacity(n);
    for (k, t) in ts.iter().enumerate() {
        let i = ((t - t0) * 500.0).round();
        assert!(
            ((t - t0) * 500.0 - i).abs() < 0.5e-3 * 500.0,
            "sample {k}: off the grid"
        );
        let i = i as usize;
        seen.push(i);
        for c in 0..8 {
            let (f, a) = ((c + 1) as f64, 10.0 * (c + 1) as f64);
            let want = a * (std::f64::consts::TAU * f * i as f64 / 500.0).sin();
            // float32 in millivolts: ~1e-7 relative.
            assert!(
                (x[[c, k]] - want).abs() < 1e-4 * a,
                "ch{c} i{i}: {} vs {want}",
                x[[c, k]]
            );
        }
    }
    let expected: Vec<usize> = (0..1500).filter(|i| !(700..725).contains(i)).collect();
    assert_eq!(seen, expected);
    assert_eq!(inlet.lost_samples(), 25);
    assert!(peer.0.wait().unwrap().success());
}

#[test]
fn pylsl_reads_our_markers() {
    setup();
    let Some(python) = pylsl("pylsl_reads_our_markers") else {
        return;
    };
    let name = unique("pylsl-markers");
    let outlet = MarkerOutlet::new(&name, &name).unwrap();
    let mut peer = spawn_python(
        &python,
        "read_markers.py",
        &["--name", &name, "--type", "Markers"],
    );
    let mut out = BufReader::new(peer.0.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let ready: serde_json::Value = serde_json::from_str(&line).expect(&line);
    assert_eq!(ready["ready"], true, "{line}");
    assert!(outlet.have_consumers());

    let t = local_clock();
    let sent: Vec<(String, f64)> = std::iter::once(("cue 3".to_string(), t))
        .chain((0..8).map(|k| (format!("flash {}", k % 4 + 1), t + 0.1 + 0.125 * k as f64)))
        .chain([
            ("decision 3".to_string(), t + 1.5),
            ("abstain".to_string(), t + 1.6),
            ("end".to_string(), t + 1.7),
        ])
        .collect();
    for (m, ts) in &sent {
        outlet.push(m, *ts);
    }
    let mut got = Vec::new();
    for line in out.lines() {
        let v: serde_json::Value = serde_json::from_str(&line.unwrap()).unwrap();
        if let Some(m) = v["marker"].as_str() {
            got.push((m.to_string(), v["timestamp"].as_f64().unwrap()));
        } else {
            assert_eq!(v["count"].as_u64(), Some(sent.len() as u64), "{v}");
        }
    }
    assert!(peer.0.wait().unwrap().success());
    assert_eq!(got.len(), sent.len(), "{got:?}");
    for ((m, ts), (gm, gts)) in sent.iter().zip(&got) {
        assert_eq!(m, gm);
        assert!((ts - gts).abs() < 1e-3, "{m}: {gts} vs {ts}");
    }
}
