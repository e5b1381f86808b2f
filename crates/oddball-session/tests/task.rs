//! Tracking and drawing with the typical simulated subject.

use oddball_arm::{ArmConfig, ArmSim};
use oddball_decode::preset::Preset;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::subject::{SimulatedSubject, SubjectParams, SubjectPreset};
use oddball_session::tasks::{run_drawing, run_tracking, TrackParams};

fn calibrated(seed: u64) -> Session<SimulatedSubject> {
    let subject = SubjectParams::preset(SubjectPreset::Typical)
        .with_seed(seed)
        .build()
        .unwrap();
    let mut params = SessionParams::paper(Preset::Lda);
    params.decoder.seed = seed;
    let arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
    let mut s = Session::new(params, subject, Some(arm)).unwrap();
    s.calibrate().unwrap();
    s
}

#[test]
fn the_typical_subject_reaches_ten_seeded_targets() {
    let mut s = calibrated(1);
    let report = run_tracking(&mut s, &TrackParams::default()).unwrap();
    assert_eq!(report.targets.len(), 10);
    for t in &report.targets {
        assert!(t.success, "target {}: {t:?}", t.index);
        assert!(t.final_error_m < 1e-3);
        assert!(t.decisions >= t.min_commands);
        assert!((2..=5).contains(&t.min_commands));
        assert!(t.path_efficiency > 0.0 && t.path_efficiency <= 1.0);
        assert!(t.time_to_target_s > 0.0 && t.decisions_per_minute > 0.0);
    }
    assert_eq!((report.n_reached, report.n_attempted), (10, 10));
    assert!(report.totals.itr.bits_per_minute > 0.0);
    assert_eq!(
        report.totals.decisions,
        report.targets.iter().map(|t| t.decisions).sum::<usize>()
    );
}

#[test]
fn drawing_hi_stays_within_a_millimetre_of_the_plan() {
    let mut s = calibrated(2);
    let report = run_drawing(&mut s, "HI", 3, 1.0).unwrap();
    assert!(report.completed, "{report:?}");
    assert!(
        report.max_deviation_m < 1e-3,
        "max deviation {} m",
        report.max_deviation_m
    );
    assert!(report.mean_deviation_m <= report.max_deviation_m);
    assert!(report.decisions >= report.min_decisions);
    // Text that does not fit is refused before anything moves.
    let mut s = calibrated(3);
    assert!(run_drawing(&mut s, "HELLOWORLD", 3, 1.0).is_err());
}
