//! A whole session over NIC's TCP protocol: a simulated Starstim serves the stream on loopback,
//! the session reads it as it would read NIC, calibrates and draws the letter G.

use oddball_session::decoder::Preset;
use std::net::TcpListener;
use std::thread;

use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_io::nic::{encode, NicFormat, NicMode, NicSample};
use oddball_live::clock::Clock;
use oddball_live::live::LiveSubject;
use oddball_live::nic::{serve_simulated, NicSource, Reconnect, ServeReport};
use oddball_live::LiveError;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::record::{read_session, reevaluate, save_session_easy};
use oddball_session::subject::{SubjectParams, SubjectPreset};

fn names() -> Vec<String> {
    SubjectParams::preset(SubjectPreset::Typical).ch_names
}

fn listeners() -> (TcpListener, TcpListener) {
    (
        TcpListener::bind("127.0.0.1:0").unwrap(),
        TcpListener::bind("127.0.0.1:0").unwrap(),
    )
}

fn nic_session(
    mode: NicMode,
    seed: u64,
) -> (
    Session<LiveSubject<NicSource>>,
    thread::JoinHandle<Result<ServeReport, LiveError>>,
) {
    let (data, panel) = listeners();
    let (data_addr, panel_addr) = (data.local_addr().unwrap(), panel.local_addr().unwrap());
    let format = NicFormat::starstim(mode);
    let params = SubjectParams::preset(SubjectPreset::Typical).with_seed(seed);
    let ch_names = params.ch_names.clone();
    let sim = params.build().unwrap();
    let server =
        thread::spawn(move || serve_simulated(data, panel, sim, format, 1_700_000_000_000));
    let clock = Clock::new();
    let source = NicSource::connect(
        data_addr,
        format,
        500.0,
        ch_names,
        Reconnect::default(),
        clock,
    )
    .unwrap()
    .with_panel_port(panel_addr)
    .unwrap();
    let subject = LiveSubject::new(source, FourBulbParams::paper(), clock);
    let mut p = SessionParams::paper(Preset::Lda);
    p.decoder.seed = seed;
    let arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
    (Session::new(p, subject, Some(arm)).unwrap(), server)
}

#[test]
fn a_session_over_nic_binary_draws_the_letter_g() {
    let (mut s, server) = nic_session(NicMode::Binary, 1);
    let cal = s.calibrate().unwrap();
    assert!(cal.cv_auc > 0.85, "{cal:?}");
    let mut right = 0;
    for &c in &Command::LETTER_G {
        let t = s.decide(Some(c)).unwrap();
        right += usize::from(t.decided() == Some(s.params().paradigm.code_of(c)));
    }
    assert!(right >= 6, "{right}/6");
    // Every flash came back in the stream's trigger column at its onset sample.
    let triggers = s.subject().source().triggers.clone();
    let paradigm = s.params().paradigm;
    let (log, model, _) = s.finish().unwrap();
    let shown: Vec<(u64, i32)> = log
        .flashes
        .iter()
        .filter(|f| (f.onset as usize) < log.n_times)
        .map(|f| (f.onset, f.code as i32))
        .collect();
    assert_eq!(triggers, shown);
    let report = server.join().unwrap().unwrap();
    assert_eq!(report.flashes, log.flashes.len());

    // The session as NIC .easy + .info: read back, it re-evaluates to the same decisions.
    let dir = oddball_testkit::TempDir::new("nic");
    let path = dir.join("session.easy");
    let summary = save_session_easy(&path, &log, &paradigm, 1_700_000_000_000).unwrap();
    assert_eq!(summary.max_rounding_uv, 0.0, "NIC delivers whole nV");
    let rec = oddball_io::read(&path).unwrap();
    assert_eq!(
        rec.raw.data(),
        &log.samples.as_ref().unwrap().to_array().unwrap()
    );
    let saved = read_session(&rec).unwrap();
    let again = reevaluate(&rec, &saved, &model.unwrap()).unwrap();
    let online: Vec<_> = log
        .trials
        .iter()
        .filter(|t| t.phase == oddball_session::decision::Phase::Online)
        .collect();
    assert_eq!(again.len(), 6);
    for (a, o) in again.iter().zip(online) {
        assert_eq!((a.outcome, a.rounds), (o.outcome, o.rounds));
        assert_eq!(a.posterior, o.posterior);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn ascii_mode_carries_the_same_stream() {
    let (mut s, server) = nic_session(NicMode::Ascii, 2);
    s.calibrate().unwrap();
    let t = s.decide(Some(Command::Up)).unwrap();
    assert!(t.decided().is_some());
    let (log, _, _) = s.finish().unwrap();
    assert!(log.n_times > 200_000);
    server.join().unwrap().unwrap();
}

#[test]
fn a_server_that_vanishes_is_a_clear_error_and_keeps_what_arrived() {
    use std::io::Write;
    let data = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = data.local_addr().unwrap();
    let format = NicFormat::starstim(NicMode::Binary);
    let server = thread::spawn(move || {
        let (mut c, _) = data.accept().unwrap();
        let mut bytes = Vec::new();
        for k in 0..1000 {
            encode(
                &format,
                &NicSample {
                    nv: vec![k * 10; 8],
                    trigger: Some(0),
                    timestamp_ms: Some(2 * i64::from(k)),
                },
                &mut bytes,
            );
        }
        // A partial sample, then the server is gone (listener dropped with the thread).
        c.write_all(&bytes).unwrap();
        c.write_all(&[1, 2, 3]).unwrap();
    });
    let quick = Reconnect {
        attempts: 2,
        delay: std::time::Duration::from_millis(20),
        ..Reconnect::default()
    };
    let mut src = NicSource::connect(addr, format, 500.0, names(), quick, Clock::new()).unwrap();
    let first = src.read(1000).unwrap();
    assert_eq!(first.len(), 1000);
    assert_eq!(first[999].nv[0], 9990);
    server.join().unwrap();
    let err = src.read(1).unwrap_err();
    assert!(
        matches!(err, LiveError::Reconnect { attempts: 2, .. }),
        "{err}"
    );
}

#[test]
fn timestamp_gaps_count_lost_samples() {
    use std::io::Write;
    let data = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = data.local_addr().unwrap();
    let format = NicFormat::starstim(NicMode::Binary);
    let server = thread::spawn(move || {
        let (mut c, _) = data.accept().unwrap();
        let mut bytes = Vec::new();
        // 10 samples missing after sample 99; then the clock jumps back once.
        for k in (0..100).chain(110..120).chain(115..116) {
            encode(
                &format,
                &NicSample {
                    nv: vec![0; 8],
                    trigger: Some(0),
                    timestamp_ms: Some(2 * k),
                },
                &mut bytes,
            );
        }
        c.write_all(&bytes).unwrap();
    });
    let mut src = NicSource::connect(
        addr,
        format,
        500.0,
        names(),
        Reconnect::default(),
        Clock::new(),
    )
    .unwrap();
    src.read(111).unwrap();
    assert_eq!(src.lost_samples, 10);
    assert_eq!(src.timestamp_regressions, 1);
    server.join().unwrap();
}

/// A stream that pauses for 2 s: with a longer stall timeout the read waits and resumes with
/// every sample; with a shorter one it stops cleanly with `StreamStalled`.
#[test]
fn a_two_second_pause_waits_or_stops_cleanly() {
    use std::io::Write;
    use std::time::{Duration, Instant};
    let format = NicFormat::starstim(NicMode::Binary);
    let serve = |data: TcpListener| {
        thread::spawn(move || {
            let (mut c, _) = data.accept().unwrap();
            for part in 0..2 {
                let mut bytes = Vec::new();
                for k in 0..500 {
                    encode(
                        &format,
                        &NicSample {
                            nv: vec![part * 1000 + k; 8],
                            trigger: Some(0),
                            timestamp_ms: Some(2 * i64::from(part * 500 + k)),
                        },
                        &mut bytes,
                    );
                }
                if c.write_all(&bytes).is_err() {
                    return;
                }
                if part == 0 {
                    thread::sleep(Duration::from_secs(2));
                }
            }
            thread::sleep(Duration::from_millis(200));
        })
    };
    for (timeout_s, resumes) in [(4.0, true), (0.5, false)] {
        let data = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = data.local_addr().unwrap();
        let server = serve(data);
        let r = Reconnect {
            stall_timeout: Some(Duration::from_secs_f64(timeout_s)),
            ..Reconnect::default()
        };
        let mut src = NicSource::connect(addr, format, 500.0, names(), r, Clock::new()).unwrap();
        let first = src.read(500).unwrap();
        assert_eq!(first.len(), 500);
        let t0 = Instant::now();
        let rest = src.read(500);
        if resumes {
            let rest = rest.unwrap();
            assert!(t0.elapsed() >= Duration::from_millis(1500));
            assert_eq!(rest[0].nv[0], 1000);
            assert_eq!(src.lost_samples, 0, "a pause is not a loss");
        } else {
            let err = rest.unwrap_err();
            assert!(matches!(err, LiveError::StreamStalled { .. }), "{err}");
        }
        server.join().unwrap();
    }
}

fn samples(format: &NicFormat, from: i32, n: i32) -> Vec<u8> {
    let mut bytes = Vec::new();
    for k in from..from + n {
        encode(
            format,
            &NicSample {
                nv: vec![k * 10; 8],
                trigger: Some(0),
                timestamp_ms: Some(2 * i64::from(k)),
            },
            &mut bytes,
        );
    }
    bytes
}

/// Issue #19, defect 6: `--source nic:` always needed the simulator's extra panel port, so a
/// real NIC (which has none) could not be read at all. Now the port is used when it is there.
#[test]
fn a_real_amplifier_without_a_panel_port_is_read() {
    use oddball_live::source::{OpenOptions, SourceSpec};
    use std::io::Write;
    // A data port whose port + 1 nobody listens on (bound and released to find one).
    let (data, addr) = loop {
        let d = TcpListener::bind("127.0.0.1:0").unwrap();
        let a = d.local_addr().unwrap();
        let next = std::net::SocketAddr::new(a.ip(), a.port().wrapping_add(1));
        if TcpListener::bind(next).is_ok() {
            break (d, a);
        }
    };
    let format = NicFormat::starstim(NicMode::Binary);
    let server = thread::spawn(move || {
        let (mut c, _) = data.accept().unwrap();
        c.write_all(&samples(&format, 0, 600)).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(200));
    });
    let opts = OpenOptions {
        subject: SubjectParams::preset(SubjectPreset::Typical)
            .build()
            .unwrap(),
        paced: false,
        sim_latency_ms: 0.0,
        nic: format,
        nic_sfreq: 500.0,
        markers: String::new(),
    };
    let spec: SourceSpec = format!("nic:{addr}").parse().unwrap();
    let (source, _) = spec
        .open(opts, Clock::new())
        .unwrap_or_else(|e| panic!("a NIC without a panel port: {e}"));
    let oddball_live::source::AnySource::Nic(mut nic) = source else {
        panic!("not a NIC source")
    };
    assert!(!nic.has_panel_port());
    use oddball_live::live::EegSource;
    nic.wait(500).unwrap();
    let d = nic.take(500).unwrap();
    assert_eq!(d[[0, 499]], 4.99 * 1000.0 / 1000.0 * 1.0);
    server.join().unwrap();
}

/// Issue #19, defect 6: an amplifier that dropped out ended the session with "cannot connect
/// to panel port: Broken pipe", and restarting it did not help. Now the stream reconnects (and
/// finds the restarted simulator's panel port again); the panel port's loss is not an error.
#[test]
fn an_amplifier_that_restarts_is_reconnected_with_its_panel_port() {
    use oddball_live::live::EegSource;
    use std::io::Write;
    let (data, panel) = listeners();
    let (data_addr, panel_addr) = (data.local_addr().unwrap(), panel.local_addr().unwrap());
    let format = NicFormat::starstim(NicMode::Binary);
    let server = thread::spawn(move || {
        // First run: 300 samples, then the amplifier (and its panel port) goes away.
        let (p1, _) = panel.accept().unwrap();
        let (mut c, _) = data.accept().unwrap();
        c.write_all(&samples(&format, 0, 300)).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(100));
        drop((c, p1));
        // Restarted 300 ms later.
        std::thread::sleep(std::time::Duration::from_millis(300));
        let (mut c, _) = data.accept().unwrap();
        let (_p2, _) = panel.accept().unwrap();
        c.write_all(&samples(&format, 300, 300)).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(300));
    });
    let patient = Reconnect {
        attempts: 20,
        delay: std::time::Duration::from_millis(50),
        ..Reconnect::default()
    };
    let mut src = NicSource::connect(data_addr, format, 500.0, names(), patient, Clock::new())
        .unwrap()
        .with_panel_port(panel_addr)
        .unwrap();
    for _ in 0..6 {
        src.wait(100)
            .unwrap_or_else(|e| panic!("the restart was not survived: {e}"));
        src.take(100).unwrap();
        src.saw(0, 1, false).unwrap();
    }
    assert_eq!(src.reconnects, 1);
    assert!(src.has_panel_port(), "the restarted panel port was found");
    server.join().unwrap();
}
