//! The EDF+ writer: round trips through the reader (within one quantisation step), header
//! contents, and refusals.

mod common;

use common::{bci2000_file, TempDir};
use ndarray::Array2;
use oddball_io::{
    edf::EdfStart, read, read_bci2000, write_edf_plus, write_edf_plus_with, EdfWriteOptions,
    Format, IoError,
};
use oddball_signal::{Event, Events, Raw};

/// Per-channel quantisation step of the writer: the 8-character physical range over 65535.
fn steps(raw: &Raw) -> Vec<f64> {
    raw.data()
        .rows()
        .into_iter()
        .map(|r| {
            let lo = r.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = r.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            // Outward rounding to 8 characters widens the range by at most 2 units in the last
            // written digit; allow 1 % on top of the data range (plus 2 µV for flat channels).
            ((hi - lo) * 1.01 + 2.0) / 65535.0
        })
        .collect()
}

fn round_trip(raw: &Raw, tag: &str) -> (Raw, oddball_io::EdfWriteSummary) {
    let tmp = TempDir::new(tag);
    let path = tmp.path().join("rt.edf");
    let summary = write_edf_plus(&path, raw).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(back.format, Format::EdfPlus);
    assert_eq!(back.raw.ch_names(), raw.ch_names());
    assert_eq!(back.raw.sfreq(), raw.sfreq());
    assert_eq!(back.raw.n_times(), raw.n_times() + summary.padded_samples);
    assert_eq!(back.raw.events(), raw.events(), "{tag}: events");
    let step = steps(raw);
    let (a, b) = (raw.data(), back.raw.data());
    for c in 0..raw.n_channels() {
        for t in 0..back.raw.n_times() {
            let want = a[[c, t.min(raw.n_times() - 1)]];
            let err = (b[[c, t]] - want).abs();
            assert!(
                err <= step[c] * 0.5 + 1e-9 * want.abs().max(1.0),
                "{tag}: channel {c} sample {t}: {} vs {want} (step {})",
                b[[c, t]],
                step[c]
            );
        }
    }
    (back.raw, summary)
}

#[test]
fn synthetic_round_trip() {
    let n = 1003;
    let data = Array2::from_shape_fn((4, n), |(c, t)| {
        let x = t as f64 / 250.0;
        match c {
            0 => 40.0 * (2.0 * std::f64::consts::PI * 7.0 * x).sin(),
            1 => 3.0e6 * (x * 3.0).cos(), // Brain-Invaders-sized transient
            2 => 12.5,                    // flat
            _ => 1e-3 * ((t * 7919) % 101) as f64 - 0.05,
        }
    });
    let events = Events::new(vec![
        Event::new(0, 1),
        Event::new(3, 12).with_target(true),
        Event::new(3, 2).with_target(false).with_label("A b: c"),
        Event::new(249, 7).with_label("x"),
        Event::new(250, 8),
        Event::new(1002, 4_000_000_000).with_target(true),
    ]);
    let names = ["Fz", "Cz", "Flat", "Tiny"].map(String::from).to_vec();
    let raw = Raw::new(data, 250.0, names, events).unwrap();
    let (back, s) = round_trip(&raw, "edfw-synth");
    assert_eq!(
        (
            s.n_records,
            s.samples_per_record,
            s.padded_samples,
            s.record_duration
        ),
        (5, 250, 247, 1.0)
    );
    assert_eq!(back.n_times(), 1250);
}

#[test]
fn record_durations_for_fractional_rates() {
    for (sfreq, duration, spr) in [
        (100.5, 2.0, 201usize),
        (160.0, 1.0, 160),
        (0.5, 2.0, 1),
        (1000.0 / 3.0, 3.0, 1000),
    ] {
        let n = 700;
        let data = Array2::from_shape_fn((1, n), |(_, t)| (t as f64 * 0.37).sin() * 50.0);
        let events = Events::new(vec![
            Event::new(1, 1),
            Event::new(n - 1, 2).with_target(false),
        ]);
        let raw = Raw::new(data, sfreq, vec!["Pz".into()], events).unwrap();
        let (_, s) = round_trip(&raw, "edfw-rates");
        assert_eq!(
            (s.record_duration, s.samples_per_record),
            (duration, spr),
            "{sfreq} Hz"
        );
    }
}

#[test]
fn real_speller_round_trip() {
    let Some(path) = bci2000_file("real_speller_round_trip", "eeg3_1.dat") else {
        return;
    };
    let rec = read_bci2000(&path).unwrap();
    let (back, s) = round_trip(&rec.raw, "edfw-eeg3");
    assert_eq!((s.n_records, s.padded_samples), (223, 223 * 256 - 56840));
    assert_eq!(back.events().len(), 720);
    assert_eq!(back.events().n_targets(), 120);
    assert_eq!(rec.speller.as_ref().unwrap().decode(back.events()), "T3OF");
}

#[test]
fn header_fields_and_options() {
    let tmp = TempDir::new("edfw-header");
    let raw = Raw::new(
        Array2::zeros((2, 10)),
        10.0,
        vec!["C3".into(), "C4".into()],
        Events::default(),
    )
    .unwrap();
    let o = EdfWriteOptions {
        patient: "P7 F 01-JAN-1990 Doe".into(),
        recording: "A1 tech amp".into(),
        start: Some(EdfStart {
            year: 2025,
            month: 11,
            day: 22,
            hour: 9,
            minute: 8,
            second: 7,
        }),
    };
    let path = tmp.path().join("h.edf");
    write_edf_plus_with(&path, &raw, &o).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[0..8], b"0       ");
    assert!(bytes[8..88].starts_with(b"P7 F 01-JAN-1990 Doe "));
    assert!(bytes[88..168].starts_with(b"Startdate 22-NOV-2025 A1 tech amp "));
    assert_eq!(&bytes[168..184], b"22.11.2509.08.07");
    assert!(bytes[192..236].starts_with(b"EDF+C "));
    let back = read(&path).unwrap();
    let h = &back.edf().unwrap().header;
    assert_eq!(h.signals[2].label, "EDF Annotations");
    assert_eq!(h.signals[0].dimension, "uV");
    // All-zero channels get a ±1 µV range and read back as zeros.
    assert!(back.raw.data().iter().all(|&v| v.abs() < 1e-4));

    let bad = EdfWriteOptions {
        start: Some(EdfStart {
            year: 1984,
            month: 1,
            day: 1,
            hour: 0,
            minute: 0,
            second: 0,
        }),
        ..EdfWriteOptions::default()
    };
    assert!(matches!(
        write_edf_plus_with(&path, &raw, &bad),
        Err(IoError::Unsupported { .. })
    ));
}

#[test]
fn refusals() {
    let tmp = TempDir::new("edfw-refuse");
    let path = tmp.path().join("r.edf");
    let mut data = Array2::zeros((1, 20));
    data[[0, 3]] = f64::NAN;
    let raw = Raw::new(data, 10.0, vec!["Cz".into()], Events::default()).unwrap();
    let e = write_edf_plus(&path, &raw).unwrap_err();
    assert!(e.to_string().contains("sample 3"), "{e}");
    let raw = Raw::new(
        Array2::zeros((1, 20)),
        10.0,
        vec!["a-very-long-channel-name".into()],
        Events::default(),
    )
    .unwrap();
    assert!(matches!(
        write_edf_plus(&path, &raw),
        Err(IoError::Unsupported { .. })
    ));
    let raw = Raw::new(
        Array2::zeros((1, 20)),
        std::f64::consts::PI,
        vec!["Cz".into()],
        Events::default(),
    )
    .unwrap();
    assert!(matches!(
        write_edf_plus(&path, &raw),
        Err(IoError::Unsupported { .. })
    ));
    let ev = Events::new(vec![Event::new(2, 1).with_label("bad\u{14}label")]);
    let raw = Raw::new(Array2::zeros((1, 20)), 10.0, vec!["Cz".into()], ev).unwrap();
    assert!(matches!(
        write_edf_plus(&path, &raw),
        Err(IoError::Unsupported { .. })
    ));
    let mut data = Array2::zeros((1, 20));
    data[[0, 0]] = 1e12;
    let raw = Raw::new(data, 10.0, vec!["Cz".into()], Events::default()).unwrap();
    assert!(matches!(
        write_edf_plus(&path, &raw),
        Err(IoError::Unsupported { .. })
    ));
    let e = write_edf_plus(
        tmp.path().join("no/such/dir/x.edf"),
        &Raw::new(
            Array2::zeros((1, 2)),
            1.0,
            vec!["Cz".into()],
            Events::default(),
        )
        .unwrap(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            IoError::Io {
                action: "create",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn written_files_truncated_are_reported() {
    let tmp = TempDir::new("edfw-trunc");
    let data = Array2::from_shape_fn((2, 300), |(c, t)| (c * 300 + t) as f64);
    let raw = Raw::new(
        data,
        100.0,
        vec!["A".into(), "B".into()],
        Events::new(vec![Event::new(10, 1)]),
    )
    .unwrap();
    let path = tmp.path().join("w.edf");
    let s = write_edf_plus(&path, &raw).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = 256 * 4;
    let record = 2 * 100 * 2 + s.annotation_bytes;
    assert_eq!(bytes.len(), header + 3 * record);
    let cut = tmp.write("cut.edf", &bytes[..header + record + 17]);
    match read(&cut).unwrap_err() {
        IoError::Truncated { offset, field, .. } => {
            assert_eq!(offset as usize, header + record);
            assert!(field.starts_with("data record 1 of 3"), "{field}");
        }
        e => panic!("{e}"),
    }
}

/// Rewrites the annotation signal of every record of a file written by `write_edf_plus` (one
/// data channel, 10 samples per record) with `tals(record)`, and the reserved field.
fn rewrite_annotations(bytes: &[u8], reserved: &str, tals: impl Fn(usize) -> Vec<u8>) -> Vec<u8> {
    let header = 256 * 3;
    let ann_spr: usize =
        std::str::from_utf8(&bytes[256 + 2 * (16 + 80 + 8 + 8 + 8 + 8 + 8 + 80) + 8..][..8])
            .unwrap()
            .trim()
            .parse()
            .unwrap();
    let record = 10 * 2 + ann_spr * 2;
    let mut out = bytes.to_vec();
    let mut field = reserved.as_bytes().to_vec();
    field.resize(44, b' ');
    out[192..236].copy_from_slice(&field);
    for r in 0..(bytes.len() - header) / record {
        let at = header + r * record + 20;
        let mut t = tals(r);
        assert!(t.len() <= ann_spr * 2);
        t.resize(ann_spr * 2, 0);
        out[at..at + ann_spr * 2].copy_from_slice(&t);
    }
    out
}

#[test]
fn subsecond_start_and_discontinuous_files() {
    let tmp = TempDir::new("edfw-start");
    let data = Array2::from_shape_fn((1, 30), |(_, t)| t as f64);
    // Two events in record 0 so that the annotation signal has room for the rewrites below.
    let ev = Events::new(vec![Event::new(2, 9), Event::new(5, 1), Event::new(12, 2)]);
    let raw = Raw::new(data, 10.0, vec!["Cz".into()], ev).unwrap();
    let path = tmp.path().join("s.edf");
    write_edf_plus(&path, &raw).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let stamp = |r: usize, start: f64| format!("+{}\x14\x14\x00", start + r as f64).into_bytes();
    let with_events = |r: usize, start: f64| {
        let mut t = stamp(r, start);
        if r == 0 {
            t.extend(format!("+{}\x145\x14\x00", start + 0.5).bytes());
        }
        if r == 1 {
            t.extend(format!("+{}\x14stim\x14\x00", start + 1.2).bytes());
        }
        t
    };

    // EDF+C starting 0.25 s after the start second: onsets are relative to that second.
    let f = tmp.write(
        "c.edf",
        &rewrite_annotations(&bytes, "EDF+C", |r| with_events(r, 0.25)),
    );
    let rec = read(&f).unwrap();
    let info = rec.edf().unwrap();
    assert_eq!(info.start_offset, 0.25);
    let ev: Vec<_> = rec.raw.events().iter().map(|e| (e.onset, e.code)).collect();
    assert_eq!(ev, vec![(5, 5), (12, 6)]);
    assert_eq!(info.annotations[0].onset, 0.75);

    // EDF+D whose records are contiguous reads like EDF+C; a gap is refused.
    let f = tmp.write(
        "d.edf",
        &rewrite_annotations(&bytes, "EDF+D", |r| with_events(r, 0.0)),
    );
    assert_eq!(read(&f).unwrap().format, Format::EdfPlus);
    let f = tmp.write(
        "gap.edf",
        &rewrite_annotations(&bytes, "EDF+D", |r| {
            stamp(r, if r == 2 { 5.0 } else { 0.0 })
        }),
    );
    let e = read(&f).unwrap_err();
    assert!(
        matches!(&e, IoError::Unsupported { what, .. } if what.contains("record 2")),
        "{e}"
    );
    // Annotations outside the recording are kept as annotations but are not events.
    let f = tmp.write(
        "out.edf",
        &rewrite_annotations(&bytes, "EDF+C", |r| {
            let mut t = stamp(r, 0.0);
            if r == 2 {
                t.extend(b"+3.5\x14late\x14\x00");
            }
            t
        }),
    );
    let rec = read(&f).unwrap();
    assert!(rec.raw.events().is_empty());
    assert_eq!(rec.edf().unwrap().annotations.len(), 1);
}
