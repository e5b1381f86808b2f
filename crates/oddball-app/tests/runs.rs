//! A front end other than the command line runs a demo from plain settings, its output in a
//! buffer: the report folder is written, the decisions said, and settings that contradict each
//! other are refused as facts (no command-line flag named) before any EEG work.

use oddball_app::demo::Demo;
use oddball_app::error::{AppError, SettingError};
use oddball_app::settings::{CalibrationSpec, SessionSettings, SourceSettings, SubjectSpec};
use oddball_arm::Command;
use oddball_decode::preset::Preset;
use oddball_io::nic::{NicFormat, NicMode};
use oddball_live::source::SourceSpec;
use oddball_session::paradigm::{ParadigmPreset, TimingOverrides};
use oddball_session::subject::SubjectPreset;

fn settings() -> SessionSettings {
    SessionSettings {
        subject: SubjectSpec::Preset(SubjectPreset::Easy),
        calibration: CalibrationSpec::Labelled,
        transfer: None,
        model: None,
        montage: None,
        adapt: false,
        test_text: Vec::new(),
        seed: 4,
        realtime: false,
        dynamic_stopping: false,
        threshold: 0.95,
        max_rounds: 5,
        pipeline: Preset::Lda,
        calibration_per_bulb: 4,
        paradigm: ParadigmPreset::Fast,
        timing: TimingOverrides::default(),
        optimise_stopping: false,
        round_limit: 12,
        min_accuracy: 0.0,
        step: None,
    }
}

fn source() -> SourceSettings {
    SourceSettings {
        source: SourceSpec::Sim,
        nic: NicFormat {
            mode: NicMode::Binary,
            n_channels: 8,
            trigger: true,
            timestamp: true,
        },
        markers: "oddball-markers".into(),
        sim_latency_ms: 250.0,
    }
}

#[test]
fn a_demo_runs_from_plain_settings_into_a_buffer() {
    let dir = oddball_testkit::TempDir::new("app-demo");
    let demo = Demo {
        settings: settings(),
        source: source(),
        commands: vec![Command::Up, Command::Left, Command::Down],
        out: dir.join("demo"),
    };
    let mut said = Vec::new();
    demo.run(&mut said).expect("the demo runs");
    let said = String::from_utf8(said).unwrap();
    assert!(
        said.starts_with("oddball demo: easy simulated subject (seed 4)"),
        "{said}"
    );
    assert_eq!(
        said.lines().filter(|l| l.starts_with("decision ")).count(),
        3,
        "one line per decision: {said}"
    );
    assert!(said
        .trim_end()
        .ends_with(&format!("report in {}", dir.join("demo").display())));
    for f in [
        "decisions.csv",
        "summary.json",
        "model.json",
        "pen_trace.png",
        "erp.png",
        "session.dat",
    ] {
        assert!(dir.join("demo").join(f).is_file(), "{f} written");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("demo/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["decisions"].as_array().unwrap().len(), 3);
}

#[test]
fn contradicting_settings_are_refused_before_any_eeg_work() {
    let dir = oddball_testkit::TempDir::new("app-refused");
    let mut s = settings();
    s.adapt = true;
    s.pipeline = Preset::Riemann;
    let demo = Demo {
        settings: s,
        source: source(),
        commands: vec![Command::Up],
        out: dir.join("demo"),
    };
    let mut said = Vec::new();
    let e = demo.run(&mut said).unwrap_err();
    assert!(
        matches!(
            e,
            AppError::Setting(SettingError::AdaptNeedsLda {
                pipeline: Preset::Riemann
            })
        ),
        "{e:?}"
    );
    assert!(!e.to_string().contains("--"), "no flag named: {e}");
    assert!(said.is_empty() && !dir.join("demo").exists(), "nothing run");
}
