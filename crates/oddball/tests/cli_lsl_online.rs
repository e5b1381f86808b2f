//! Two processes over Lab Streaming Layer: `oddball simulate --lsl` is the amplifier (it follows
//! the panel's marker stream), `oddball online --source lsl:…` decodes it live and draws the
//! letter G. LSL stays on loopback (tools/lsl/lsl_api.cfg). Both load liblsl at run time: from
//! `ODDBALL_LIBLSL`, else the pylsl of `ODDBALL_PYLSL`, else wherever `oddball_live::lsl`
//! looks; without it the test prints `skipping …` (or fails under `ODDBALL_REQUIRE_DATA=1`).

mod common;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The liblsl the two programs are to load (`ODDBALL_LIBLSL`, else the pylsl's of
/// `ODDBALL_PYLSL`, else the one this process finds), or `None` after a skip line.
fn liblsl(test: &str) -> Option<String> {
    let named = std::env::var_os("ODDBALL_LIBLSL").map(PathBuf::from);
    let python = std::env::var_os("ODDBALL_PYLSL");
    let file =
        named.or_else(|| python.and_then(|p| oddball_live::lsl::liblsl_of_python(Path::new(&p))));
    let candidates = match file {
        Some(f) => vec![oddball_live::lsl::Candidate {
            file: f,
            origin: "this test".into(),
        }],
        None => oddball_live::lsl::candidates(|name| std::env::var_os(name)),
    };
    match oddball_live::lsl::load_from(&candidates) {
        Ok(lib) => Some(lib.place().to_string()),
        Err(e) => {
            oddball_testkit::missing(oddball_testkit::Need::Tool, test, &e.to_string());
            None
        }
    }
}

#[test]
fn simulate_lsl_and_online_lsl_in_two_processes_draw_the_g() {
    let Some(liblsl) = liblsl("simulate_lsl_and_online_lsl_in_two_processes_draw_the_g") else {
        return;
    };
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let cfg = root.join("tools/lsl/lsl_api.cfg");
    let id = std::process::id();
    let dir = oddball_testkit::TempDir::new("lsl-online");
    let model = common::demo_model(&dir);
    let eeg = format!("oddball-test-eeg-{id}");
    let markers = format!("oddball-test-markers-{id}");
    let mut sim = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .env("LSLAPICFG", &cfg)
        .env("ODDBALL_LIBLSL", &liblsl)
        .args([
            "simulate",
            "--lsl",
            &eeg,
            "--markers",
            &markers,
            "--seed",
            "2",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .expect("the simulator starts");
    let mut sim_out = BufReader::new(sim.stdout.take().unwrap());
    let mut first = String::new();
    sim_out.read_line(&mut first).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_oddball"))
        .env("LSLAPICFG", &cfg)
        .env("ODDBALL_LIBLSL", &liblsl)
        .args([
            "online",
            "--source",
            &format!("lsl:{eeg}"),
            "--markers",
            &markers,
            // The paper's six commands (online's default is the 20-move stroke-font G).
            "--commands",
            "paper-g",
        ])
        .args(["--model", model.to_str().unwrap()])
        .args(["--out", dir.join("online").to_str().unwrap()])
        .output()
        .expect("oddball online runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut rest = String::new();
    sim_out.read_to_string(&mut rest).unwrap();
    let sim_status = sim.wait().unwrap();
    println!(
        "online:\n{stdout}\n{}\nsimulator:\n{first}{rest}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success());
    assert!(sim_status.success(), "the simulator ends at the end marker");
    // ≥ 95 % of the G's six commands: all six.
    assert!(stdout.contains("6/6 decisions right"), "{stdout}");
    assert!(stdout.contains("0 samples lost"), "{stdout}");
    assert!(
        rest.contains(" 0 markers too late"),
        "every flash reached the simulated brain: {rest}"
    );
    assert!(
        rest.contains("(30 attended)"),
        "the cues reached it too: {rest}"
    );
    // The recording holds the session.
    let rec = oddball_io::read(dir.join("online/session.xdf")).unwrap();
    assert!(rec.raw.n_times() > 30_000);
}
