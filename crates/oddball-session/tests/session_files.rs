//! Issue #19, defects 7 and 9 (session files): corrupt trial lines and four bulbs of one
//! meaning were accepted; a `.info` of 50,000 trial lines took minutes to read (each line was
//! looked up by scanning the whole `.info`, each trial's flashes by scanning every event).

use oddball_decode::preset::Preset;
use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use oddball_arm::Command;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::record::{read_session, save_session_easy};
use oddball_session::subject::{SubjectParams, SubjectPreset};
use oddball_session::SessionError;

/// A short real session (3 calibration decisions per bulb, one online) saved as `.easy`.
fn saved(dir: &Path) -> std::path::PathBuf {
    let sim = SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(2)
        .build()
        .unwrap();
    let mut p = SessionParams::paper(Preset::Lda);
    p.calibration_per_bulb = 3;
    p.decoder.seed = 2;
    let mut s = Session::new(p, sim, None).unwrap();
    s.calibrate().unwrap();
    s.decide(Some(Command::Up)).unwrap();
    // A free tail of EEG after the last trial (for the many-lines test).
    s.idle(120.0).unwrap();
    let paradigm = s.params().paradigm;
    let (log, _, _) = s.finish().unwrap();
    let path = dir.join("s.easy");
    save_session_easy(&path, &log, &paradigm, 0).unwrap();
    path
}

fn info_of(easy: &Path) -> std::path::PathBuf {
    easy.with_extension("info")
}

/// Reads the session with `.info` edited by `edit`, on a watchdog thread (a hang fails).
fn read_edited(easy: &Path, edit: impl Fn(String) -> String) -> Result<usize, SessionError> {
    let info = info_of(easy);
    let text = std::fs::read_to_string(&info).unwrap();
    std::fs::write(&info, edit(text.clone())).unwrap();
    let (tx, rx) = mpsc::channel();
    let p = easy.to_path_buf();
    std::thread::spawn(move || {
        let rec = oddball_io::read(&p).unwrap();
        let _ = tx.send(read_session(&rec).map(|s| s.trials.len()));
    });
    let out = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("reading the session hung (more than 60 s)");
    std::fs::write(&info, text).unwrap();
    out
}

#[test]
fn corrupt_trial_lines_and_four_bulbs_of_one_meaning_are_refused() {
    let dir = oddball_testkit::TempDir::new("session-files");
    let easy = saved(&dir);
    let n = read_edited(&easy, |t| t).unwrap();
    assert_eq!(n, 13);
    let line = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("Oddball trial 13:"))
            .unwrap()
            .to_string()
    };
    for (what, make) in [
        (
            "start after end",
            (|f: &[&str]| format!("{} {} {} 1 1", f[0], f[2], f[1])) as fn(&[&str]) -> String,
        ),
        ("past the end", |f| {
            format!("{} {} 999999999 1 1", f[0], f[1])
        }),
        ("intended code 9", |f| {
            format!("{} {} {} 9 1", f[0], f[1], f[2])
        }),
        ("decided code 2^32 + 1", |f| {
            format!("{} {} {} 1 4294967297", f[0], f[1], f[2])
        }),
        ("overlapping the trial before", |f| {
            format!("{} 0 {} 1 1", f[0], f[2])
        }),
    ] {
        let e = read_edited(&easy, |t| {
            let old = line(&t);
            let fields: Vec<&str> = old.split_once(':').unwrap().1.split_whitespace().collect();
            t.replace(&old, &format!("Oddball trial 13: {}", make(&fields)))
        })
        .expect_err(what);
        assert!(matches!(e, SessionError::NotASession { .. }), "{what}: {e}");
    }
    let e = read_edited(&easy, |t| {
        let bulbs = t
            .lines()
            .find(|l| l.starts_with("Oddball bulb commands:"))
            .unwrap()
            .to_string();
        t.replace(&bulbs, "Oddball bulb commands: up up up up")
    })
    .unwrap_err();
    assert!(e.to_string().contains("exactly one bulb"), "{e}");
}

#[test]
fn fifty_thousand_trial_lines_are_read_in_linear_time() {
    let dir = oddball_testkit::TempDir::new("session-lines");
    let easy = saved(&dir);
    // 50,000 trials of one sample each after the real ones: the reader must get through them
    // (it took 183 s when each line was found by scanning the whole .info).
    let n_times = oddball_io::read(&easy).unwrap().raw.n_times();
    let n = read_edited(&easy, |mut t| {
        let last = 13;
        let first_free = n_times - 50_001;
        for k in 0..50_000 {
            let s = first_free + k;
            t.push_str(&format!(
                "Oddball trial {}: online {} {} 1 0\n",
                last + 1 + k,
                s,
                s + 1
            ));
        }
        t
    });
    assert_eq!(n.unwrap(), 50_013);
}
