//! Issue #19, defect 9 (the readers' part) and defect 5's helper: input that used to be
//! accepted without a word, or a write that could destroy an old file.
//!
//! * duplicate channel names pass in EDF, BCI2000 and XDF (CSV refused them already);
//! * an EDF+ record with a bad time stamp, an XDF EEG stream with a NaN first timestamp: every
//!   event was dropped silently;
//! * an error echoed a 20 MB CSV cell whole;
//! * an output written in place was truncated by a failed write.

mod common;

use std::path::{Path, PathBuf};

use common::TempDir;
use ndarray::Array2;
use oddball_io::{
    read, stimulus_states, write_atomic, write_bci2000, write_edf_plus, write_xdf, AtomicFile,
    Bci2000WriteOptions, IoError, XdfWriteOptions,
};
use oddball_signal::{Event, Events, Raw, SignalError};

fn raw() -> Raw {
    let data = Array2::from_shape_fn((2, 512), |(c, t)| ((t * (c + 3)) % 17) as f64 - 8.0);
    let events = Events::new(vec![
        Event::new(100, 1).with_target(true),
        Event::new(300, 2).with_target(false),
    ]);
    Raw::new(data, 256.0, vec!["Fz".into(), "Cz".into()], events).unwrap()
}

/// Replaces the first `from` in the file with `to` (same length).
fn patch(path: &Path, from: &[u8], to: &[u8]) {
    assert_eq!(from.len(), to.len());
    let mut b = std::fs::read(path).unwrap();
    let at = b
        .windows(from.len())
        .position(|w| w == from)
        .unwrap_or_else(|| {
            panic!(
                "{:?} not in {}",
                String::from_utf8_lossy(from),
                path.display()
            )
        });
    b[at..at + from.len()].copy_from_slice(to);
    std::fs::write(path, b).unwrap();
}

fn written(dir: &TempDir, name: &str) -> PathBuf {
    let p = dir.join(name);
    let r = raw();
    match name.rsplit('.').next() {
        Some("edf") => {
            write_edf_plus(&p, &r).unwrap();
        }
        Some("dat") => {
            write_bci2000(
                &p,
                &r,
                &stimulus_states(r.events(), r.n_times(), 2),
                &Bci2000WriteOptions::default(),
            )
            .unwrap();
        }
        Some("xdf") => {
            write_xdf(&p, &r, &XdfWriteOptions::default()).unwrap();
        }
        _ => unreachable!(),
    }
    // The unpatched file reads, with its events.
    assert_eq!(read(&p).unwrap().raw.events().len(), 2, "{name}");
    p
}

fn is_duplicate(e: &IoError) -> bool {
    matches!(
        e,
        IoError::Signal {
            source: SignalError::DuplicateChannel { .. },
            ..
        }
    )
}

#[test]
fn duplicate_channel_names_are_refused_in_edf_bci2000_and_xdf() {
    let dir = TempDir::new("dup-names");
    let edf = written(&dir, "a.edf");
    // EDF labels are 16-byte fields: "Cz" padded.
    patch(&edf, b"Cz              ", b"Fz              ");
    let dat = written(&dir, "a.dat");
    patch(&dat, b"Fz Cz", b"Fz Fz");
    let xdf = written(&dir, "a.xdf");
    patch(&xdf, b"<label>Cz</label>", b"<label>Fz</label>");
    for p in [edf, dat, xdf] {
        let e = read(&p).unwrap_err();
        assert!(is_duplicate(&e), "{}: {e}", p.display());
        assert!(e.to_string().contains("\"Fz\""), "{e}");
    }
}

#[test]
fn an_edf_plus_record_with_a_bad_time_stamp_is_an_error_not_lost_events() {
    let dir = TempDir::new("edf-stamp");
    let edf = written(&dir, "a.edf");
    // The first record's time-keeping TAL "+0\x14\x14" says it starts at 9 s.
    patch(&edf, b"+0\x14\x14", b"+9\x14\x14");
    let e = read(&edf).unwrap_err();
    assert!(
        matches!(&e, IoError::InvalidField { field, .. } if field.contains("time stamp of data record")),
        "{e}"
    );
}

#[test]
fn an_xdf_eeg_stream_with_a_nan_first_timestamp_is_an_error_not_lost_events() {
    let dir = TempDir::new("xdf-nan");
    let xdf = written(&dir, "a.xdf");
    // The first EEG sample's timestamp is start_time = 0.0 (8 zero bytes after its 0x08 tag);
    // the default start time is checked here so the patch hits it.
    assert_eq!(XdfWriteOptions::default().start_time, 0.0);
    let mut tagged_zero = vec![8u8];
    tagged_zero.extend_from_slice(&0.0f64.to_le_bytes());
    let mut tagged_nan = vec![8u8];
    tagged_nan.extend_from_slice(&f64::NAN.to_le_bytes());
    patch(&xdf, &tagged_zero, &tagged_nan);
    let e = read(&xdf).unwrap_err().to_string();
    assert!(e.contains("timestamp NaN is not a finite number"), "{e}");
}

#[test]
fn an_error_echoes_a_bounded_part_of_a_huge_cell() {
    let dir = TempDir::new("huge-cell");
    let cell = "7".repeat(1000) + &"x".repeat(20 << 20);
    let text = format!("time,Cz,marker\n0.0,1.0,0\n0.004,{cell},0\n0.008,1.0,0\n");
    let p = dir.write("big.csv", text.as_bytes());
    let e = read(&p).unwrap_err().to_string();
    assert!(e.len() < 1000, "{} bytes of error", e.len());
    assert!(e.contains("more bytes"), "{e}");
}

#[test]
fn an_atomic_write_that_fails_keeps_the_old_file() {
    let dir = TempDir::new("atomic");
    let p = dir.write("model.json", b"old model");
    // A write abandoned half-way (an error before the commit): the old file is whole, and
    // no temporary file is left behind.
    {
        let mut f = AtomicFile::create(&p).unwrap();
        std::io::Write::write_all(&mut f, b"new and half").unwrap();
        assert_ne!(f.temp_path(), p.as_path());
        assert_eq!(f.temp_path().extension().unwrap(), "json");
    }
    assert_eq!(std::fs::read(&p).unwrap(), b"old model");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    write_atomic(&p, b"new model").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"new model");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // Nowhere to write: an error naming the file, nothing created.
    let e = write_atomic(dir.join("no/such/dir/m.json"), b"x").unwrap_err();
    assert!(e.to_string().contains("no/such/dir"), "{e}");
}
