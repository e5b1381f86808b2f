//! Lab Streaming Layer on loopback: EEG and marker streams between this crate's outlets and
//! inlets, and with real peers (Python pylsl, when `ODDBALL_PYLSL` names a python that has it;
//! see tools/lsl/requirements.txt); and where liblsl is looked for.
//!
//! liblsl is loaded at run time: from `ODDBALL_LIBLSL`, else (in these tests) from the pylsl of
//! `ODDBALL_PYLSL`, else wherever `oddball_live::lsl` looks. A test that needs it and cannot load
//! it prints `skipping …`, or fails under `ODDBALL_REQUIRE_DATA=1` (CI).
//!
//! Every stream name carries the process id, and liblsl is kept on this machine by
//! tools/lsl/lsl_api.cfg (`LSLAPICFG`, set before the first LSL call).

use std::ffi::OsString;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Once;
use std::time::{Duration, Instant};

use ndarray::Array2;
use oddball_live::lsl::{
    candidates, liblsl_of_python, library, load_from, local_clock, Candidate, EegInlet, EegOutlet,
    MarkerInlet, MarkerOutlet, StreamQuery, DECISION_TYPE,
};
use oddball_live::LiveError;
use oddball_testkit::Need;

fn lsl_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tools/lsl/lsl_api.cfg")
        .canonicalize()
        .expect("tools/lsl/lsl_api.cfg")
}

/// Points liblsl at the loopback configuration, and this process at the pylsl's liblsl of
/// `ODDBALL_PYLSL` unless `ODDBALL_LIBLSL` names one, before any test makes an LSL call.
/// Whether liblsl loads; when not, `test` is skipped (or fails, see the module documentation).
fn setup(test: &str) -> bool {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        std::env::set_var("LSLAPICFG", lsl_config());
        if std::env::var_os("ODDBALL_LIBLSL").is_none() {
            let python = std::env::var_os("ODDBALL_PYLSL");
            if let Some(lib) = python.and_then(|p| liblsl_of_python(Path::new(&p))) {
                std::env::set_var("ODDBALL_LIBLSL", lib);
            }
        }
    });
    match library() {
        Ok(_) => true,
        Err(e) => {
            oddball_testkit::missing(Need::Tool, test, &e.to_string());
            false
        }
    }
}

fn unique(what: &str) -> String {
    format!("oddball-test-{what}-{}", std::process::id())
}

fn labels(n: usize) -> Vec<String> {
    (1..=n).map(|c| format!("E{c}")).collect()
}

#[test]
fn eeg_round_trip_keeps_values_timestamps_and_labels() {
    if !setup("eeg_round_trip_keeps_values_timestamps_and_labels") {
        return;
    }
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
    if !setup("volts_millivolts_and_nanovolts_arrive_in_microvolts") {
        return;
    }
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
    if !setup("markers_and_decisions_round_trip") {
        return;
    }
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

/// Pulls `inlet` until liblsl gives its stream up: the pull fails with
/// [`LiveError::StreamLost`] naming it within `within` s, and never blocks meanwhile.
fn wait_lost(inlet: &mut MarkerInlet, name: &str, within: f64) {
    let start = Instant::now();
    loop {
        let pulled_at = Instant::now();
        let r = inlet.pull();
        assert!(pulled_at.elapsed() < Duration::from_secs(1), "pull waited");
        match r {
            Err(LiveError::StreamLost { name: n }) => {
                assert_eq!(n, name);
                return;
            }
            Ok(m) => assert!(m.is_empty(), "{m:?}"),
            Err(e) => panic!("expected StreamLost, got {e}"),
        }
        let waited = start.elapsed().as_secs_f64();
        assert!(waited < within, "{name} still not lost after {waited:.1} s");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_marker_stream_that_goes_away_is_lost_not_waited_for() {
    if !setup("a_marker_stream_that_goes_away_is_lost_not_waited_for") {
        return;
    }
    let name = unique("lost-markers");
    let outlet = MarkerOutlet::new(&name, &name).unwrap();
    let mut inlet = MarkerInlet::resolve(&StreamQuery::Name(name.clone()), 10.0).unwrap();
    outlet.push("cue 1", 0.0);
    let got = pull_n(&mut inlet, 1);
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!(got[0].0, "cue 1");
    // One machine: no clock offset, and a host name to report.
    assert!(
        inlet.time_correction().abs() < 1e-2,
        "{}",
        inlet.time_correction()
    );
    assert!(!inlet.hostname().is_empty());
    drop(outlet);
    wait_lost(&mut inlet, &name, 15.0);
}

#[test]
fn a_stream_that_goes_away_stalls_the_reader() {
    if !setup("a_stream_that_goes_away_stalls_the_reader") {
        return;
    }
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
    if !setup("resolving_nothing_times_out_naming_the_query") {
        return;
    }
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
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("starting {python} {script_name}: {e}")),
    )
}

#[test]
fn pylsl_eeg_is_read_with_its_values_timestamps_units_and_gap() {
    if !setup("pylsl_eeg_is_read_with_its_values_timestamps_units_and_gap") {
        return;
    }
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
    if !setup("pylsl_reads_our_markers") {
        return;
    }
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

#[test]
fn pylsl_numeric_markers_arrive_as_their_decimal_text() {
    if !setup("pylsl_numeric_markers_arrive_as_their_decimal_text") {
        return;
    }
    let Some(python) = pylsl("pylsl_numeric_markers_arrive_as_their_decimal_text") else {
        return;
    };
    for (format, want) in [
        ("int32", ["1", "2", "3", "-4", "100"]),
        ("float32", ["3", "0.25", "-1.5", "12", "100"]),
        ("int64", ["1", "2", "3", "-4", "100"]),
        ("double64", ["3", "0.1", "-1.5", "12", "1000000"]),
    ] {
        let name = unique(&format!("pylsl-{format}-markers"));
        let mut peer = spawn_python(
            &python,
            "push_markers.py",
            &["--name", &name, "--format", format],
        );
        let mut inlet = MarkerInlet::resolve(&StreamQuery::Name(name.clone()), 20.0).unwrap();
        let mut out = BufReader::new(peer.0.stdout.take().unwrap());
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        let head: serde_json::Value = serde_json::from_str(&line).expect(&line);
        let t0 = head["t0"].as_f64().expect(&line);
        let got = pull_n(&mut inlet, want.len());
        let texts: Vec<&str> = got.iter().map(|(m, _)| m.as_str()).collect();
        assert_eq!(texts, want, "{format}");
        for (k, (m, ts)) in got.iter().enumerate() {
            let sent = t0 + 0.1 * k as f64;
            assert!((ts - sent).abs() < 1e-3, "{format} {m}: {ts} vs {sent}");
        }
        assert_eq!(
            Some(inlet.hostname()),
            head["hostname"].as_str(),
            "{format}"
        );
        assert!(inlet.time_correction().abs() < 1e-2, "{format}");
        // The peer exits when its standard input closes: the stream is lost, not waited for.
        drop(peer.0.stdin.take());
        assert!(peer.0.wait().unwrap().success(), "{format}");
        wait_lost(&mut inlet, &name, 15.0);
    }
}

// ---- where liblsl is looked for (no liblsl needed) ----

#[test]
fn a_named_file_that_is_not_liblsl_is_refused_naming_it_and_the_fix() {
    let tmp = oddball_testkit::TempDir::new("liblsl-named");
    let fake = tmp.write("liblsl.so", b"not a library");
    let env = |name: &str| (name == "ODDBALL_LIBLSL").then(|| OsString::from(&fake));
    // ODDBALL_LIBLSL alone: the user chose that file.
    let found = candidates(env);
    assert_eq!(
        found,
        vec![Candidate {
            file: fake.clone(),
            origin: "ODDBALL_LIBLSL".into()
        }]
    );
    let err = load_from(&found).unwrap_err();
    let shown = fake.display().to_string();
    match &err {
        LiveError::LiblslNotFound { tried } => {
            assert_eq!(tried.len(), 1, "{tried:?}");
            assert!(
                tried[0].starts_with(&format!("{shown} (ODDBALL_LIBLSL): ")),
                "{tried:?}"
            );
        }
        other => panic!("expected LiblslNotFound, got {other:?}"),
    }
    let text = err.to_string();
    for part in [shown.as_str(), "pip install pylsl", "set ODDBALL_LIBLSL"] {
        assert!(text.contains(part), "{part:?} not in {text}");
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_library_that_is_not_liblsl_is_refused_naming_the_function_missing() {
    let c = Candidate {
        file: "libm.so.6".into(),
        origin: "a test".into(),
    };
    match load_from(&[c]) {
        Err(LiveError::LiblslNotFound { tried }) => {
            assert_eq!(tried.len(), 1);
            assert!(
                tried[0].starts_with("libm.so.6 (a test): it has no lsl_library_version"),
                "{tried:?}"
            );
        }
        other => panic!("expected LiblslNotFound, got {other:?}"),
    }
}

#[cfg(target_os = "linux")]
#[test]
fn pylsl_lib_then_the_system_then_a_virtual_envs_pylsl_are_tried() {
    let tmp = oddball_testkit::TempDir::new("liblsl-venv");
    let site = tmp.join("venv/lib/python3.11/site-packages/pylsl/lib");
    std::fs::create_dir_all(&site).unwrap();
    std::fs::create_dir_all(tmp.join("custom")).unwrap();
    let bundled = site.join("liblsl.so");
    std::fs::write(&bundled, b"x").unwrap();
    let custom = tmp.write("custom/liblsl.so", b"x");
    let venv = tmp.join("venv");
    let env = |name: &str| match name {
        "PYLSL_LIB" => Some(OsString::from(&custom)),
        "VIRTUAL_ENV" => Some(OsString::from(&venv)),
        _ => None,
    };
    let found: Vec<(String, String)> = candidates(env)
        .into_iter()
        .map(|c| (c.file.display().to_string(), c.origin))
        .collect();
    let pair = |f: &Path, o: &str| (f.display().to_string(), o.to_string());
    assert_eq!(
        found,
        vec![
            pair(&custom, "PYLSL_LIB"),
            pair(Path::new("liblsl.so"), "the system"),
            pair(Path::new("liblsl.so.2"), "the system"),
            pair(Path::new("liblsl64.so"), "the system"),
            pair(&bundled, "pylsl in $VIRTUAL_ENV"),
        ]
    );
    // A PYLSL_LIB that names no file is passed over, as pylsl does.
    let missing = tmp.join("nothing.so");
    let env = |name: &str| (name == "PYLSL_LIB").then(|| OsString::from(&missing));
    assert_eq!(candidates(env)[0].origin, "the system");
}

#[test]
fn a_python_without_pylsl_has_no_liblsl() {
    assert_eq!(liblsl_of_python(Path::new("/nonexistent/python3")), None);
    let tmp = oddball_testkit::TempDir::new("liblsl-python");
    assert_eq!(liblsl_of_python(&tmp.join("python")), None);
}

#[test]
fn the_pylsl_of_oddball_pylsl_carries_a_liblsl_that_loads() {
    let Some(python) = pylsl("the_pylsl_of_oddball_pylsl_carries_a_liblsl_that_loads") else {
        return;
    };
    let file = liblsl_of_python(Path::new(&python)).expect("pylsl ≥ 1.16 bundles liblsl");
    let c = Candidate {
        file: file.clone(),
        origin: "ODDBALL_PYLSL".into(),
    };
    let lib = load_from(&[c]).unwrap();
    assert_eq!(lib.place(), file.display().to_string());
    assert!(lib.version() >= 113, "{}", lib.version());
    let short = format!("{}.{}", lib.version() / 100, lib.version() % 100);
    assert!(
        lib.version_text().starts_with(&short),
        "{}",
        lib.version_text()
    );
    assert!(lib.local_clock() > 0.0);
}
