//! Two processes over NIC's TCP protocol: `oddball simulate --nic` serves the simulated
//! Starstim, `oddball demo --source nic:…` calibrates and draws the letter G from it, and the
//! session's `.easy` recording re-evaluates to the same decisions.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

#[test]
fn a_demo_over_nic_from_another_process_draws_the_g() {
    for mode in ["binary", "ascii"] {
        let mut sim = Command::new(env!("CARGO_BIN_EXE_oddball"))
            .args(["simulate", "--nic", "127.0.0.1:0", "--nic-mode", mode])
            .stdout(Stdio::piped())
            .spawn()
            .expect("simulator starts");
        let mut first = String::new();
        BufReader::new(sim.stdout.as_mut().unwrap())
            .read_line(&mut first)
            .unwrap();
        // "serving NIC binary data on 127.0.0.1:PORT, panel on 127.0.0.1:PORT+1"
        let addr = first
            .split_whitespace()
            .nth(5)
            .unwrap()
            .trim_end_matches(',')
            .to_string();
        let dir = oddball_testkit::TempDir::new(&format!("nic-{mode}"));
        let source = format!("nic:{addr}");
        let (ok, out, err) = common::oddball(&[
            "demo",
            "--source",
            &source,
            "--nic-mode",
            mode,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        assert!(sim.wait().unwrap().success());
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert!(
            summary["result"]["accuracy"].as_f64().unwrap() >= 0.95,
            "{out}"
        );
        assert!(
            summary["pen"]["drew_intended_path"].as_bool().unwrap(),
            "{out}"
        );
        let (ok, out, err) = common::oddball(&[
            "evaluate",
            "--model",
            dir.join("model.json").to_str().unwrap(),
            "--test",
            dir.join("session.easy").to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        assert!(out.contains("20 online decisions: 20 identical"), "{out}");
        // The .easy reads as a labelled recording (attended triggers are targets): 40
        // calibration and 20 online trials of 5 rounds of 4 flashes.
        let (ok, out, err) =
            common::oddball(&["inspect", dir.join("session.easy").to_str().unwrap()]);
        assert!(ok, "{err}");
        assert!(
            out.contains("targets    300 target, 900 non-target"),
            "{out}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn nothing_listening_is_a_clear_error() {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = l.local_addr().unwrap();
    drop(l);
    let dir = oddball_testkit::TempDir::new("nic-none");
    let source = format!("nic:{addr}");
    let (ok, _, err) =
        common::oddball(&["demo", "--source", &source, "--out", dir.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("connect"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue #30: the NIC simulator's listeners are loopback only unless --allow-remote, as the
/// panel's are.
#[test]
fn the_simulator_binds_loopback_unless_told_otherwise() {
    let (ok, _, err) = common::oddball(&["simulate", "--nic", "0.0.0.0:0"]);
    assert!(
        !ok && err.contains("--nic 0.0.0.0:0") && err.contains("loopback"),
        "{err}"
    );
}
