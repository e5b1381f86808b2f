//! The live subject without a page: flashes on schedule, so a session over a simulated live
//! source decides exactly as the same session over the simulated subject directly, and the
//! recording holds what the session received.

use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_live::clock::Clock;
use oddball_live::live::LiveSubject;
use oddball_live::playback::PlaybackSource;
use oddball_live::record::Recorder;
use oddball_live::sim::SimSource;
use oddball_live::LiveError;
use oddball_session::decoder::Preset;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::roles::EegStream;
use oddball_session::subject::{SubjectParams, SubjectPreset};

fn params() -> SessionParams {
    let mut p = SessionParams::paper(Preset::Lda);
    p.calibration_per_bulb = 3;
    p.decoder.seed = 5;
    p
}

fn sim() -> oddball_session::SimulatedSubject {
    SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(5)
        .build()
        .unwrap()
}

#[test]
fn a_live_session_on_schedule_equals_the_direct_session_and_records_it() {
    let commands = [Command::Up, Command::Left, Command::Down];
    let arm = || ArmSim::from_config(&ArmConfig::default()).unwrap();

    let mut direct = Session::new(params(), sim(), Some(arm())).unwrap();
    direct.calibrate().unwrap();
    let a: Vec<_> = commands
        .iter()
        .map(|&c| direct.decide(Some(c)).unwrap())
        .collect();

    let dir = oddball_testkit::TempDir::new("live");
    let path = dir.join("live.xdf");
    let _ = std::fs::remove_file(&path);
    let clock = Clock::new();
    let source = SimSource::unpaced(sim(), clock);
    let s = sim();
    let recorder = Recorder::create(&path, s.ch_names(), s.sfreq(), "test").unwrap();
    let subject = LiveSubject::new(source, FourBulbParams::paper(), clock).with_recorder(recorder);
    let mut live = Session::new(params(), subject, Some(arm())).unwrap();
    live.calibrate().unwrap();
    let b: Vec<_> = commands
        .iter()
        .map(|&c| live.decide(Some(c)).unwrap())
        .collect();
    assert_eq!(a, b, "same decisions, posteriors, timing");

    let n = live.subject().position() as usize;
    let (log, _, _) = live.finish().unwrap();
    let rec = oddball_io::read(&path).unwrap();
    // The live subject's recorder is still open (not finished): whole blocks are on disk.
    assert_eq!(rec.raw.n_times(), n);
    for (x, y) in rec
        .raw
        .data()
        .iter()
        .zip(log.samples.as_ref().unwrap().to_array().unwrap().iter())
    {
        assert_eq!(*x, f64::from(*y as f32));
    }
    // Markers: a cue per trial, a flash per flash shown, a decision per online trial.
    let info = rec.xdf().unwrap();
    let texts: Vec<&str> = info.markers.iter().map(|m| m.text.as_str()).collect();
    assert_eq!(
        texts.iter().filter(|t| t.starts_with("cue ")).count(),
        log.trials.len()
    );
    assert_eq!(
        texts.iter().filter(|t| t.starts_with("flash ")).count(),
        log.flashes.len()
    );
    assert_eq!(
        texts.iter().filter(|t| t.starts_with("decision ")).count(),
        commands.len()
    );
    // Each flash marker sits on its flash's onset sample.
    let onsets: Vec<u64> = info
        .markers
        .iter()
        .filter(|m| m.text.starts_with("flash "))
        .map(|m| m.sample.expect("inside the EEG") as u64)
        .collect();
    let shown: Vec<u64> = log.flashes.iter().map(|f| f.onset).collect();
    assert_eq!(onsets, shown);
}

#[test]
fn a_recorded_session_played_back_decides_the_same_and_stops_at_the_end_of_the_file() {
    let commands = [Command::Up, Command::Right];
    let arm = || ArmSim::from_config(&ArmConfig::default()).unwrap();
    let dir = oddball_testkit::TempDir::new("playback");
    let path = dir.join("recorded.xdf");
    let _ = std::fs::remove_file(&path);
    let clock = Clock::new();

    let s = sim();
    let recorder = Recorder::create(&path, s.ch_names(), s.sfreq(), "test").unwrap();
    let subject = LiveSubject::new(
        SimSource::unpaced(sim(), clock),
        FourBulbParams::paper(),
        clock,
    )
    .with_recorder(recorder);
    let mut live = Session::new(params(), subject, Some(arm())).unwrap();
    live.calibrate().unwrap();
    let a: Vec<_> = commands
        .iter()
        .map(|&c| live.decide(Some(c)).unwrap())
        .collect();
    let n = live.subject().position() as usize;
    let (recorded, _, _) = live.finish().unwrap();

    let source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    assert_eq!(source.n_times(), n);
    let subject = LiveSubject::new(source, FourBulbParams::paper(), clock);
    let mut replay = Session::new(params(), subject, Some(arm())).unwrap();
    replay.calibrate().unwrap();
    let b: Vec<_> = commands
        .iter()
        .map(|&c| replay.decide(Some(c)).unwrap())
        .collect();
    // float32 on disk: the same choices and rounds, posteriors to float32 precision.
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.decided(), y.decided());
        assert_eq!((x.start, x.end, x.rounds), (y.start, y.end, y.rounds));
        for (p, q) in x.posterior.iter().zip(&y.posterior) {
            assert!(
                (p - q).abs() < 1e-3,
                "{:?} vs {:?}",
                x.posterior,
                y.posterior
            );
        }
    }
    let recorded_flashes: Vec<(u64, u32)> =
        recorded.flashes.iter().map(|f| (f.onset, f.code)).collect();
    let shown: Vec<(u64, u32)> = replay.flashes().iter().map(|f| (f.onset, f.code)).collect();
    assert_eq!(shown, recorded_flashes);
    let source = replay.subject().source();
    assert_eq!(source.coincidence(&shown, 0), shown.len());
    // Another schedule (shifted by a sample) misses every flash at tolerance 0, not at 1.
    let shifted: Vec<(u64, u32)> = shown.iter().map(|&(o, c)| (o + 1, c)).collect();
    assert_eq!(source.coincidence(&shifted, 0), 0);
    assert_eq!(source.coincidence(&shifted, 1), shown.len());
    // A third decision runs past the end of the file: a clear error, nothing invented.
    let err = replay.decide(Some(Command::Down)).unwrap_err();
    match LiveError::from_session(&err) {
        Some(LiveError::RecordingEnded { n_times, .. }) => assert_eq!(*n_times, n),
        other => panic!("expected RecordingEnded, got {other:?}"),
    }
}
