//! `oddball simulate --lsl` as a live Lab Streaming Layer amplifier in another process: this test
//! is the panel (a marker outlet: `cue 2`, then flashes at real times, then `end`) and the
//! session (an EEG inlet). The flashes must show in the EEG exactly at their onset samples,
//! attended ones with a P300 at Pz. Everything stays on loopback (tools/lsl/lsl_api.cfg).
//!
//! liblsl is loaded at run time, by this test and by the program: from `ODDBALL_LIBLSL`, else
//! the pylsl of `ODDBALL_PYLSL`, else wherever `oddball_live::lsl` looks. Without it the live
//! test prints `skipping …` (or fails under `ODDBALL_REQUIRE_DATA=1`); the command-line checks
//! and what a build without liblsl says always run.

use std::path::Path;
use std::process::Command;

/// Runs `oddball ARGS…` with `env` added: (exit code, stdout, stderr).
fn oddball_with(args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("oddball runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `oddball ARGS…`: (exit code, stderr).
fn oddball(args: &[&str]) -> (Option<i32>, String) {
    let (code, _, err) = oddball_with(args, &[]);
    (code, err)
}

/// Sets `ODDBALL_LIBLSL` for this process and the programs it starts to the pylsl's liblsl of
/// `ODDBALL_PYLSL` (unless it is set), and `LSLAPICFG` to the loopback settings, before the
/// first LSL call; the liblsl this process loads, or `None` after a skip line (a failure under
/// `ODDBALL_REQUIRE_DATA=1`).
fn liblsl(test: &str) -> Option<&'static oddball_live::lsl::Liblsl> {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        std::env::set_var("LSLAPICFG", live::lsl_config());
        if std::env::var_os("ODDBALL_LIBLSL").is_none() {
            let python = std::env::var_os("ODDBALL_PYLSL");
            let found = python.and_then(|p| oddball_live::lsl::liblsl_of_python(Path::new(&p)));
            if let Some(lib) = found {
                std::env::set_var("ODDBALL_LIBLSL", lib);
            }
        }
    });
    match oddball_live::lsl::library() {
        Ok(lib) => Some(lib),
        Err(e) => {
            oddball_testkit::missing(oddball_testkit::Need::Tool, test, &e.to_string());
            None
        }
    }
}

const NO_LIBLSL: &str = "/nonexistent/liblsl.so";

#[test]
fn one_of_nic_and_lsl_is_required() {
    let (code, err) = oddball(&["simulate"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--nic") && err.contains("--lsl"), "{err}");
    let (code, err) = oddball(&["simulate", "--nic", "127.0.0.1:0", "--lsl", "x"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("cannot be used with"), "{err}");
}

#[test]
fn without_liblsl_lsl_says_where_it_looked_and_how_to_get_it() {
    let (code, _, err) = oddball_with(
        &["simulate", "--lsl", "eeg"],
        &[("ODDBALL_LIBLSL", NO_LIBLSL)],
    );
    assert_eq!(code, Some(1), "{err}");
    for part in [
        "creating the LSL stream eeg",
        "/nonexistent/liblsl.so (ODDBALL_LIBLSL): ",
        "pip install pylsl",
        "set ODDBALL_LIBLSL",
    ] {
        assert!(err.contains(part), "{part:?} not in {err}");
    }
}

#[test]
fn the_version_says_what_lsl_can_do() {
    let version = env!("CARGO_PKG_VERSION");
    let (code, out, err) = oddball_with(&["--version"], &[("ODDBALL_LIBLSL", NO_LIBLSL)]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(
        out.trim_end(),
        format!(
            "oddball {version} (LSL: liblsl not found — pip install pylsl, or set ODDBALL_LIBLSL)"
        )
    );
    let Some(lib) = liblsl("the_version_says_what_lsl_can_do") else {
        return;
    };
    let (code, out, err) = oddball_with(&["-V"], &[("ODDBALL_LIBLSL", lib.place())]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(
        out.trim_end(),
        format!(
            "oddball {version} (LSL: liblsl {} loaded from {})",
            lib.version_text(),
            lib.place()
        )
    );
    assert!(
        lib.version_text().starts_with("1."),
        "{}",
        lib.version_text()
    );
}

/// The simulator as a live LSL amplifier, driven by this test as the panel.
mod live {
    use std::io::{BufRead, BufReader};
    use std::path::PathBuf;
    use std::process::{Child, Command, Stdio};
    use std::time::{Duration, Instant};

    use oddball_live::lsl::{local_clock, EegInlet, MarkerOutlet, StreamQuery};
    use oddball_session::subject::{SubjectParams, SubjectPreset};

    const SFREQ: f64 = 500.0;
    /// Channel of Pz in the simulated montage.
    const PZ: usize = 3;

    pub(super) fn lsl_config() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../tools/lsl/lsl_api.cfg")
            .canonicalize()
            .expect("tools/lsl/lsl_api.cfg")
    }

    /// Kills the simulator on drop, so a failing test leaves nothing running.
    struct Sim(Child);

    impl Drop for Sim {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }

    fn sleep_until(t: f64) {
        let dt = t - local_clock();
        if dt > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(dt));
        }
    }

    #[test]
    fn the_simulator_follows_the_panel_markers_with_a_p300() {
        // Sets LSLAPICFG before the first LSL call of this process.
        if super::liblsl("the_simulator_follows_the_panel_markers_with_a_p300").is_none() {
            return;
        }
        let pid = std::process::id();
        let (name, markers) = (
            format!("oddball-cli-eeg-{pid}"),
            format!("oddball-cli-markers-{pid}"),
        );
        let panel = MarkerOutlet::new(&markers, &markers).unwrap();
        let mut sim = Sim(Command::new(env!("CARGO_BIN_EXE_oddball"))
            .args([
                "simulate",
                "--lsl",
                &name,
                "--markers",
                &markers,
                "--subject",
                "typical",
                "--seed",
                "1",
                "--latency-ms",
                "250",
                "--duration-s",
                "120",
            ])
            .env("LSLAPICFG", lsl_config())
            .stdout(Stdio::piped())
            .spawn()
            .expect("oddball simulate starts"));
        let mut out = BufReader::new(sim.0.stdout.take().unwrap());
        let mut first = String::new();
        out.read_line(&mut first).unwrap();
        assert!(first.contains(&name), "{first}");
        // "... from t0 = T (LSL clock) ...": sample i is stamped t0 + i / 500.
        let t0: f64 = first
            .split("t0 = ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("no t0 in {first:?}"));

        let mut inlet = EegInlet::resolve(&StreamQuery::Name(name.clone()), 20.0).unwrap();
        assert_eq!(inlet.sfreq(), SFREQ);
        assert_eq!(inlet.ch_names()[PZ], "Pz");
        // A ceiling, not a timing check: on a loaded 2-core machine discovery has taken > 20 s.
        assert!(
            panel.wait_for_consumers(60.0),
            "the simulator never connected to the marker stream within 60 s"
        );

        // The schedule, relative to t0 (so the EEG it produces is the same every run when the
        // set-up takes less than 3 s): cue 2, then 6 rounds of the four bulbs, one flash every
        // 250 ms, no bulb twice in a row.
        let start = t0 + (local_clock() - t0 + 0.5).ceil().max(3.0);
        let rounds = [
            [3, 1, 2, 4],
            [1, 3, 4, 2],
            [1, 4, 3, 2],
            [4, 2, 1, 3],
            [2, 4, 3, 1],
            [2, 3, 1, 4],
        ];
        let flashes: Vec<(u32, f64)> = rounds
            .iter()
            .flatten()
            .enumerate()
            .map(|(k, &c)| (c, start + 0.25 * k as f64))
            .collect();
        panel.push("cue 2", start - 0.5);
        for &(c, t) in &flashes {
            sleep_until(t);
            panel.push(&format!("flash {c}"), t);
        }
        let last = flashes.last().unwrap().1;

        // The EEG up to 700 ms after the last flash (the inlet buffered it all along).
        let (mut data, mut stamps) = (Vec::new(), Vec::new());
        while stamps.last().is_none_or(|&t| t < last + 0.7) {
            let (x, ts) = inlet.read(100).unwrap();
            data.push(x);
            stamps.extend(ts);
        }
        let x = ndarray::concatenate(
            ndarray::Axis(1),
            &data.iter().map(|d| d.view()).collect::<Vec<_>>(),
        )
        .unwrap();
        assert_eq!(inlet.lost_samples(), 0);
        let index = |t: f64| ((t - t0) * SFREQ).round() as i64;
        let first_index = index(stamps[0]);
        assert!(first_index >= 0);
        for (k, &t) in stamps.iter().enumerate() {
            assert_eq!(index(t), first_index + k as i64, "sample {k} off the clock");
            assert!((t - (t0 + (first_index + k as i64) as f64 / SFREQ)).abs() < 1e-3);
        }

        panel.push("end", 0.0);
        let deadline = Instant::now() + Duration::from_secs(15);
        let status = loop {
            if let Some(s) = sim.0.try_wait().unwrap() {
                break s;
            }
            assert!(
                Instant::now() < deadline,
                "the simulator did not stop at `end`"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(status.success());
        let rest: Vec<String> = out.lines().map(|l| l.unwrap()).collect();
        let summary = rest.last().cloned().unwrap_or_default();
        assert!(
            summary.contains("24 flashes (6 attended), 0 markers too late"),
            "{rest:?}"
        );

        // The P300: at Pz, 250-500 ms after the attended flashes minus after the others, each
        // epoch against its 100 ms before the flash.
        let onset = |t: f64| (index(t) - first_index) as usize;
        let mean = |from: usize, to: usize| x.row(PZ).slice(ndarray::s![from..to]).mean().unwrap();
        let (mut attended, mut others) = (Vec::new(), Vec::new());
        for &(c, t) in &flashes {
            let o = onset(t);
            let v = mean(o + 125, o + 250) - mean(o - 50, o);
            if c == 2 {
                attended.push(v)
            } else {
                others.push(v)
            }
        }
        let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let p300 = avg(&attended) - avg(&others);
        println!("P300 at Pz, attended - others, 250-500 ms: {p300:.2} µV");
        assert!(
            p300 > 2.0,
            "no P300: {p300} µV ({attended:?} vs {others:?})"
        );

        // And exactly so: the same subject offline, with each flash at round((t - t0) · 500).
        let mut offline = SubjectParams::preset(SubjectPreset::Typical)
            .with_seed(1)
            .build()
            .unwrap();
        for &(c, t) in &flashes {
            offline.flash(index(t) as u64, c == 2).unwrap();
        }
        let expected = offline.render(first_index as usize + x.ncols());
        assert_eq!(
            x,
            expected.slice(ndarray::s![.., first_index as usize..]),
            "the streamed EEG is not the simulated subject with the flashes at their onsets"
        );
    }
}
