//! A recording replays as it was recorded: a live session over the simulated subject paced by
//! the wall clock, its flashes drawn and stamped by a page (this test's WebSocket client, each
//! stamp 8 to 75 ms after the schedule) and paused by the operator between two decisions, is
//! recorded; played back, it decides the same, its flashes at the stamped onsets and its trials
//! where the paused session started them. A replay whose flashes are not the recording's
//! (another seed, a file without flashes) is refused before it decides.

use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_live::clock::Clock;
use oddball_live::live::{EegSource, LiveSubject};
use oddball_live::panel::{PanelConfig, PanelServer};
use oddball_live::playback::PlaybackSource;
use oddball_live::record::Recorder;
use oddball_live::sim::SimSource;
use oddball_live::LiveError;
use oddball_session::decision::TrialRecord;
use oddball_session::decoder::{Preset, Start};
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::FourBulbParams;

use oddball_session::subject::{SubjectParams, SubjectPreset};
use oddball_session::SessionError;
use serde_json::{json, Value};
use tungstenite::{Message, WebSocket};

const COMMANDS: [Command; 4] = [Command::Up, Command::Left, Command::Down, Command::Right];

fn paradigm() -> FourBulbParams {
    FourBulbParams {
        n_rounds: 3,
        ..FourBulbParams::fast()
    }
}

fn params(seed: u64) -> SessionParams {
    let mut p = SessionParams::paper(Preset::Lda);
    p.paradigm = paradigm();
    p.decoder = oddball_session::decoder::DecoderParams::paper(Preset::Lda, &p.paradigm);
    p.decoder.seed = seed;
    p.calibration_per_bulb = 3;
    p
}

fn sim() -> oddball_session::SimulatedSubject {
    SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(11)
        .build()
        .unwrap()
}

fn arm() -> ArmSim {
    ArmSim::from_config(&ArmConfig::default()).unwrap()
}

/// A start with the model of an unpaced calibration of the same simulated subject.
fn model() -> Start {
    let mut s = Session::new(params(1), sim(), None).unwrap();
    s.calibrate().unwrap();
    Start::Model(s.model().unwrap().clone())
}

fn socket(addr: std::net::SocketAddr, url: &str) -> WebSocket<TcpStream> {
    let rest = url.strip_prefix("http://").unwrap();
    let path = &rest[rest.find('/').unwrap()..];
    let ws_path = if let Some(q) = path.strip_prefix("/operator") {
        format!("/ws/operator{q}")
    } else {
        format!("/ws{}", &path[1..])
    };
    let stream = TcpStream::connect(addr).unwrap();
    let (ws, _) =
        tungstenite::client::client(format!("ws://{addr}{ws_path}"), stream).expect("handshake");
    // Reads wait a little once connected: the page answers stamps when they fall due.
    ws.get_ref()
        .set_read_timeout(Some(Duration::from_millis(5)))
        .unwrap();
    ws
}

/// How late the page draws flash `id`, ms: a frame or more, never the same twice in a row.
fn late_ms(id: u64) -> f64 {
    [7.3, 24.9, 41.2, 58.6, 75.1][(id % 5) as usize]
}

/// The subject page: stamps every flash `late_ms` after its schedule, when that time comes.
fn page(mut ws: WebSocket<TcpStream>, clock: Clock, stop: Arc<AtomicBool>) {
    let mut due: Vec<(f64, Value)> = Vec::new();
    let hello = json!({"t": "hello", "frame_ms": 16.7, "agent": "the test's page"});
    ws.send(Message::text(hello.to_string())).unwrap();
    while !stop.load(Ordering::SeqCst) {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let m: Value = serde_json::from_str(&t).unwrap();
                if m["t"] == "flash" {
                    let (id, at) = (m["id"].as_u64().unwrap(), m["at_ms"].as_f64().unwrap());
                    let on = at + late_ms(id);
                    due.push((
                        on,
                        json!({"t": "on", "id": id, "code": m["code"], "on_ms": on}),
                    ));
                    due.push((
                        on + 100.0,
                        json!({"t": "off", "id": id, "off_ms": on + 100.0}),
                    ));
                }
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return,
        }
        let now = clock.now_ms();
        due.sort_by(|a, b| a.0.total_cmp(&b.0));
        while due.first().is_some_and(|d| d.0 <= now) {
            let (_, m) = due.remove(0);
            if ws.send(Message::text(m.to_string())).is_err() {
                return;
            }
        }
    }
}

fn operator(ws: &mut WebSocket<TcpStream>, action: &str) {
    ws.send(Message::text(
        json!({"t": "control", "action": action}).to_string(),
    ))
    .unwrap();
    ws.flush().unwrap();
}

fn same_decisions(live: &[TrialRecord], replay: &[TrialRecord]) {
    assert_eq!(live.len(), replay.len());
    for (x, y) in live.iter().zip(replay) {
        assert_eq!(x.decided(), y.decided());
        assert_eq!((x.start, x.end, x.rounds), (y.start, y.end, y.rounds));
        // float32 on disk: posteriors to its precision.
        for (p, q) in x.posterior.iter().zip(&y.posterior) {
            assert!(
                (p - q).abs() < 1e-3,
                "{:?} vs {:?}",
                x.posterior,
                y.posterior
            );
        }
    }
}

#[test]
fn a_paused_live_session_with_stamped_flashes_replays_to_the_same_decisions() {
    let dir = oddball_testkit::TempDir::new("replay-paused");
    let path = dir.join("live.xdf");
    let model = model();
    let clock = Clock::new();
    let arm_config = arm();
    let config = PanelConfig::for_arm(&arm_config, &paradigm(), vec![], vec![], "test".into());
    let panel = PanelServer::start("127.0.0.1:0".parse().unwrap(), false, config, clock).unwrap();
    let addr = panel.local_addr();
    let stop = Arc::new(AtomicBool::new(false));
    let page_ws = socket(addr, &panel.subject_url());
    let page = {
        let stop = stop.clone();
        std::thread::spawn(move || page(page_ws, clock, stop))
    };
    let operator_url = panel.operator_url();
    assert!(panel.wait_for_page(Duration::from_secs(5)));

    let s = sim();
    let recorder = Recorder::create(&path, s.ch_names(), s.sfreq(), "test").unwrap();
    let source = SimSource::new(sim(), clock, 20.0);
    let subject = LiveSubject::new(source, paradigm(), clock)
        .with_recorder(recorder)
        .with_panel(panel);
    let mut live = Session::new(params(7), subject, Some(arm())).unwrap();
    live.subject_mut().source_mut().start_now();
    live.start(model.clone(), &mut |_| {}).unwrap();
    let mut decided = Vec::new();
    for (i, &c) in COMMANDS.iter().enumerate() {
        if i == 2 {
            // The operator pauses after the second decision and resumes 1.5 s later.
            let mut op = socket(addr, &operator_url);
            operator(&mut op, "pause");
            let t0 = Instant::now();
            while !live.subject().panel().unwrap().pause_requested() {
                assert!(t0.elapsed() < Duration::from_secs(5));
                std::thread::sleep(Duration::from_millis(5));
            }
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(1500));
                operator(&mut op, "resume");
                std::thread::sleep(Duration::from_millis(500));
            });
        }
        decided.push(live.decide(Some(c)).unwrap());
    }
    stop.store(true, Ordering::SeqCst);
    page.join().unwrap();
    let timing = live.subject().timing.clone();
    assert_eq!(timing.undrawn, 0, "{}", timing.report());
    let live_flashes: Vec<(u64, u32)> = live.flashes().iter().map(|f| (f.onset, f.code)).collect();
    let planned_gap = decided[2].start - decided[1].end;
    live.into_subject().finish().unwrap();
    // The live session works (the easy subject: 4 of 4 right in the runs made), and the pause
    // held the third trial back by about 1.5 s.
    let right = decided
        .iter()
        .zip(&COMMANDS)
        .filter(|(d, &c)| d.decided() == Some(paradigm().code_of(c)))
        .count();
    assert!(right >= 3, "{decided:?}");
    assert!(
        planned_gap as f64 >= 1.2 * 500.0,
        "pause of {planned_gap} samples"
    );
    let rec = oddball_io::read(&path).unwrap();
    let texts: Vec<&str> = rec
        .xdf()
        .unwrap()
        .markers
        .iter()
        .map(|m| m.text.as_str())
        .collect();
    assert!(
        texts.contains(&"pause") && texts.contains(&"resume"),
        "{texts:?}"
    );

    // Played back as fast as it goes: the same decisions, trials where the live ones were,
    // flashes at the stamped onsets, every one found in the recording.
    let source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    assert_eq!(source.holds().len(), 1);
    let subject = LiveSubject::new(source, paradigm(), clock);
    let mut replay = Session::new(params(7), subject, Some(arm())).unwrap();
    replay.start(model.clone(), &mut |_| {}).unwrap();
    let again: Vec<TrialRecord> = COMMANDS
        .iter()
        .map(|&c| replay.decide(Some(c)).unwrap())
        .collect();
    let replay_flashes: Vec<(u64, u32)> =
        replay.flashes().iter().map(|f| (f.onset, f.code)).collect();
    assert_eq!(replay_flashes, live_flashes);
    same_decisions(&decided, &again);
    let (found, asked) = replay.subject().source().matched();
    assert_eq!((found, asked), (live_flashes.len(), live_flashes.len()));
    eprintln!(
        "live: {:?}; replay: {:?}; {found} of {asked} flashes at their recorded onsets, pause of {planned_gap} samples replayed",
        decided.iter().map(TrialRecord::decided).collect::<Vec<_>>(),
        again.iter().map(TrialRecord::decided).collect::<Vec<_>>()
    );

    // Another seed: other flashes; refused before the first decision is made.
    let source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    let subject = LiveSubject::new(source, paradigm(), clock);
    let mut other = Session::new(params(8), subject, Some(arm())).unwrap();
    other.start(model, &mut |_| {}).unwrap();
    let err = other.decide(Some(Command::Up)).unwrap_err();
    mismatch(&err);
    assert!(other.trials().iter().all(|t| t.decided().is_none()));
}

fn mismatch(err: &SessionError) {
    match LiveError::from_session(err) {
        Some(LiveError::ReplayMismatch { found, asked, .. }) => {
            assert!(2 * found < *asked && *asked >= 4, "{err}");
        }
        other => panic!("expected a replay mismatch, got {other:?} ({err})"),
    }
}

/// A recording without flashes (EEG alone) is refused once a round of flashes finds none.
#[test]
fn a_recording_without_flashes_is_refused() {
    let dir = oddball_testkit::TempDir::new("replay-noflash");
    let path = dir.join("eeg.xdf");
    let mut s = sim();
    let data = s.render(30 * 500);
    let raw = oddball_signal::Raw::new(
        data,
        s.sfreq(),
        s.ch_names().to_vec(),
        oddball_signal::Events::new(vec![]),
    )
    .unwrap();
    oddball_io::write_xdf(&path, &raw, &oddball_io::XdfWriteOptions::default()).unwrap();
    let clock = Clock::new();
    let source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    let subject = LiveSubject::new(source, paradigm(), clock);
    let mut session = Session::new(params(7), subject, None).unwrap();
    session.start(model(), &mut |_| {}).unwrap();
    let err = session.decide(Some(Command::Up)).unwrap_err();
    mismatch(&err);
    assert!(err.to_string().contains("0 of the 4 flashes"), "{err}");
}

/// The matching rule on a file of flashes every 88 samples (the fast timing at 500 Hz), each
/// stamped 45 samples (90 ms, more than half the period) after its schedule and every seventh
/// never drawn: each planned flash finds its own, the undrawn ones none and no neighbour's; a
/// schedule of other bulbs at the same times is refused after its first round.
#[test]
fn late_stamps_find_their_own_flash_and_other_bulbs_none() {
    let dir = oddball_testkit::TempDir::new("replay-match");
    let path = dir.join("flashes.xdf");
    let planned: Vec<(u64, u32)> = (0..40)
        .map(|k| (500 + 88 * k, (k % 4) as u32 + 1))
        .collect();
    let drawn = |k: usize| k % 7 != 3;
    let events = planned
        .iter()
        .enumerate()
        .filter(|&(k, _)| drawn(k))
        .map(|(_, &(o, c))| oddball_signal::Event::new(o as usize + 45, c))
        .collect();
    let mut s = sim();
    let raw = oddball_signal::Raw::new(
        s.render(5000),
        s.sfreq(),
        s.ch_names().to_vec(),
        oddball_signal::Events::new(events),
    )
    .unwrap();
    oddball_io::write_xdf(&path, &raw, &oddball_io::XdfWriteOptions::default()).unwrap();
    let clock = Clock::new();
    let mut source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    for (k, &(o, c)) in planned.iter().enumerate() {
        let d = source.recorded_flash(o, c).unwrap().expect("a recording");
        assert_eq!(d.onset, drawn(k).then_some(o + 45), "flash {k}");
    }
    let n_drawn = (0..40).filter(|&k| drawn(k)).count();
    assert_eq!(source.matched(), (n_drawn, 40));
    // The same times, other bulbs (each round's order turned by one): refused at the 4th.
    let mut source = PlaybackSource::open(&path, clock).unwrap().unpaced();
    let mut refused = None;
    for (k, &(o, c)) in planned.iter().enumerate() {
        if let Err(e) = source.recorded_flash(o, c % 4 + 1) {
            refused = Some((k, e));
            break;
        }
    }
    let (k, e) = refused.expect("refused");
    assert_eq!(k, 3, "{e}");
    assert!(
        matches!(
            e,
            LiveError::ReplayMismatch {
                found: 0,
                asked: 4,
                ..
            }
        ),
        "{e}"
    );
}
