//! The EDF/BDF reader on files written by other tools: pyedflib (EDF+, two annotation signals,
//! mixed units and digital ranges) and an independent numpy writer (BDF+, 24-bit), plus
//! truncated and mangled copies of them.

mod common;

use common::{assert_close, fixture, golden, TempDir};
use oddball_io::{read, read_edf_with, EdfOptions, Format, IoError};
use serde_json::Value;

fn check_data(raw: &oddball_signal::Raw, want: &Value, what: &str) {
    for (c, row) in want.as_array().unwrap().iter().enumerate() {
        let row: Vec<f64> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert_eq!(raw.n_times(), row.len());
        for (t, want) in row.iter().enumerate() {
            assert_close(
                raw.data()[[c, t]],
                *want,
                1e-9,
                scale,
                &format!("{what} channel {c} sample {t}"),
            );
        }
    }
}

fn check_events(raw: &oddball_signal::Raw, want: &Value) {
    let want = want.as_array().unwrap();
    assert_eq!(raw.events().len(), want.len());
    for (e, w) in raw.events().iter().zip(want) {
        assert_eq!(e.onset as u64, w["onset"].as_u64().unwrap(), "{e:?}");
        assert_eq!(e.code as u64, w["code"].as_u64().unwrap(), "{e:?}");
        assert_eq!(e.target, w["target"].as_bool(), "{e:?}");
        assert_eq!(e.label.as_deref(), w["label"].as_str(), "{e:?}");
    }
}

#[test]
fn pyedflib_edf_plus() {
    let g = golden("pyedflib_small.json");
    let rec = read(fixture("pyedflib_small.edf")).unwrap();
    assert_eq!(rec.format, Format::EdfPlus);
    let raw = &rec.raw;
    assert_eq!(raw.sfreq(), g["sfreq"].as_f64().unwrap());
    assert_eq!(raw.n_times() as u64, g["n_times"].as_u64().unwrap());
    let names: Vec<&str> = g["ch_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(raw.ch_names(), names.as_slice());
    check_data(raw, &g["data_uv"], "pyedflib EDF+");
    check_events(raw, &g["events"]);

    let info = rec.edf().unwrap();
    let ann = g["annotations"].as_array().unwrap();
    assert_eq!(info.annotations.len(), ann.len());
    for (a, w) in info.annotations.iter().zip(ann) {
        assert_eq!(a.onset, w["onset"].as_f64().unwrap());
        assert_eq!(a.duration, w["duration"].as_f64());
        assert_eq!(a.text, w["text"].as_str().unwrap());
    }
    assert_eq!(info.label_codes.get("stim"), Some(&8));
    assert_eq!(info.label_codes.get("blink"), Some(&9));
    assert_eq!(info.label_codes.len(), 2);
    assert_eq!(info.start_offset, 0.0);
    assert!(info.non_voltage_signals.is_empty());
    let h = &info.header;
    assert_eq!(h.signals.len(), 5);
    assert_eq!(h.signals.iter().filter(|s| s.is_annotation()).count(), 2);
    assert_eq!(h.signals[1].dimension, "mV");
    assert_eq!(
        (h.signals[2].digital_min, h.signals[2].digital_max),
        (-2048, 2047)
    );
    assert_eq!(h.signals[0].transducer, "AgAgCl");
    assert_eq!(h.signals[0].prefiltering, "HP:0.1Hz");
    assert!(h.patient.starts_with("P001"), "{}", h.patient);
    assert_eq!(
        (h.start_date.as_str(), h.start_time.as_str()),
        ("02.01.20", "03.04.05")
    );
    assert_eq!(
        (h.n_records, h.record_duration, h.header_bytes),
        (3, 1.0, 1536)
    );
    assert!(h.reserved.starts_with("EDF+C"));
}

#[test]
fn numpy_bdf_plus() {
    let g = golden("numpy_small.json");
    let rec = read(fixture("numpy_small.bdf")).unwrap();
    assert_eq!(rec.format, Format::BdfPlus);
    let raw = &rec.raw;
    assert_eq!(raw.sfreq(), 64.0);
    assert_eq!(raw.ch_names(), ["Fp1", "Oz", "Status"]);
    check_data(raw, &g["data_uv"], "numpy BDF+");
    check_events(raw, &g["events"]);
    // The extremes of the 24-bit range map to the ends of the physical range exactly.
    assert_eq!(raw.data()[[0, 5]], -262144.0);
    assert_eq!(raw.data()[[0, 6]], 262143.0);
    let info = rec.edf().unwrap();
    assert_eq!(info.non_voltage_signals, ["Status"]);
    assert_eq!(info.label_codes.get("stim"), Some(&4));
    assert_eq!(info.header.version, "BIOSEMI");

    let o = EdfOptions {
        exclude: vec!["Status".into()],
        ..EdfOptions::default()
    };
    let rec = read_edf_with(fixture("numpy_small.bdf"), &o).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Fp1", "Oz"]);
    assert!(rec.edf().unwrap().non_voltage_signals.is_empty());
}

fn offset_of(e: &IoError) -> (String, u64) {
    match e {
        IoError::Truncated { field, offset, .. } | IoError::InvalidField { field, offset, .. } => {
            (field.clone(), *offset)
        }
        other => panic!("expected an error with a byte offset, got {other}"),
    }
}

#[test]
fn truncated_copies_name_the_offset() {
    let tmp = TempDir::new("edf-trunc");
    // pyedflib file: header 1536 bytes, records of (3×32 + 2×57) × 2 = 420 bytes.
    let edf = std::fs::read(fixture("pyedflib_small.edf")).unwrap();
    assert_eq!(edf.len(), 1536 + 3 * 420);
    // numpy BDF: header 1280 bytes, records of (3×64 + 20) × 3 = 636 bytes.
    let bdf = std::fs::read(fixture("numpy_small.bdf")).unwrap();
    assert_eq!(bdf.len(), 1280 + 2 * 636);
    let cases: Vec<(&[u8], &str, usize, &str, u64)> = vec![
        (&edf, "edf", 0, "fixed header", 0),
        (&edf, "edf", 100, "fixed header", 0),
        (&edf, "edf", 700, "signal headers", 256),
        (&edf, "edf", 1536, "data record 0 of 3", 1536),
        (&edf, "edf", 1536 + 421, "data record 1 of 3", 1536 + 420),
        (&edf, "edf", edf.len() - 1, "data record 2 of 3", 1536 + 840),
        (&bdf, "bdf", 255, "fixed header", 0),
        (&bdf, "bdf", 1280 + 1000, "data record 1 of 2", 1280 + 636),
        (&bdf, "bdf", bdf.len() - 2, "data record 1 of 2", 1280 + 636),
    ];
    for (bytes, ext, cut, field, offset) in cases {
        let file = tmp.write(&format!("cut.{ext}"), &bytes[..cut]);
        let e = read(&file).unwrap_err();
        assert!(matches!(e, IoError::Truncated { .. }), "cut {cut}: {e}");
        let (f, o) = offset_of(&e);
        assert!(f.starts_with(field), "cut {cut}: {f:?} vs {field:?}");
        assert_eq!(o, offset, "cut {cut}: {e}");
        assert!(e.to_string().contains(&format!("cut.{ext}")), "{e}");
    }
}

/// The file with `text` (space-padded to `width`) written at `at`.
fn patch(bytes: &[u8], at: usize, width: usize, text: &[u8]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let mut field = text.to_vec();
    field.resize(width, b' ');
    b[at..at + width].copy_from_slice(&field);
    b
}

#[test]
fn mangled_fields_are_named() {
    let tmp = TempDir::new("edf-mangle");
    let edf = std::fs::read(fixture("pyedflib_small.edf")).unwrap();
    let ns = 5;
    // Offsets of signal fields: 256 + ns × (widths before) + i × width.
    let phys_min = |i: usize| 256 + ns * (16 + 80 + 8) + i * 8;
    let dig_max = |i: usize| 256 + ns * (16 + 80 + 8 + 8 + 8 + 8) + i * 8;
    let spr = |i: usize| 256 + ns * (16 + 80 + 8 + 8 + 8 + 8 + 8 + 80) + i * 8;
    let cases: Vec<(Vec<u8>, &str, usize)> = vec![
        (patch(&edf, 0, 8, b"1"), "version", 0),
        (
            patch(&edf, 184, 8, b"1537"),
            "number of bytes in header",
            184,
        ),
        (patch(&edf, 236, 8, b"2"), "number of data records", 236),
        (patch(&edf, 236, 8, b"-5"), "number of data records", 236),
        (patch(&edf, 236, 8, b"three"), "number of data records", 236),
        (patch(&edf, 244, 8, b"0"), "duration of a data record", 244),
        (patch(&edf, 252, 4, b"x"), "number of signals", 252),
        (patch(&edf, 252, 4, b"0"), "number of signals", 252),
        (
            patch(&edf, phys_min(1), 8, b"abc"),
            "signal 2 (Cz) physical minimum",
            phys_min(1),
        ),
        (
            patch(&edf, phys_min(1), 8, b"0.25"),
            "signal 2 (Cz) physical maximum",
            phys_min(1) + ns * 8,
        ),
        (
            patch(&edf, dig_max(2), 8, b"-4000"),
            "signal 3 (Pz) digital maximum",
            dig_max(2),
        ),
        (
            patch(&edf, dig_max(0), 8, b"40000"),
            "signal 1 (Fz) digital maximum",
            dig_max(0),
        ),
        (
            patch(&edf, spr(0), 8, b"0"),
            "signal 1 (Fz) samples per data record",
            spr(0),
        ),
        (
            patch(&edf, spr(0), 8, b"3\xff"),
            "signal 1 (Fz) samples per data record",
            spr(0),
        ),
    ];
    for (bytes, field, offset) in cases {
        let e = read(tmp.write("m.edf", &bytes)).unwrap_err();
        let (f, o) = offset_of(&e);
        assert_eq!((f.as_str(), o), (field, offset as u64), "{e}");
    }
    // Declaring more records than the file holds is a truncation at the first missing record.
    let e = read(tmp.write("m.edf", &patch(&edf, 236, 8, b"99999999"))).unwrap_err();
    assert_eq!(
        offset_of(&e),
        ("data record 3 of 99999999 (420 bytes)".into(), 2796)
    );
    // Absurd signal counts are refused against the file length before allocating.
    let e = read(tmp.write(
        "m.edf",
        &patch(&patch(&edf, 252, 4, b"9999"), 184, 8, b"2560000"),
    ))
    .unwrap_err();
    assert_eq!(
        offset_of(&e),
        ("signal headers (9999 signals × 256 bytes)".into(), 256)
    );
    // -1 records (still recording): the count comes from the file length.
    let rec = read(tmp.write("m.edf", &patch(&edf, 236, 8, b"-1"))).unwrap();
    assert_eq!(rec.raw.n_times(), 96);
    // A broken TAL: the onset of the first annotation after the time stamp.
    let at = edf.windows(4).position(|w| w == b"+0.5").unwrap();
    let e = read(tmp.write("m.edf", &patch(&edf, at, 4, b"+0.x"))).unwrap_err();
    assert_eq!(
        offset_of(&e),
        ("annotation in data record 0".into(), at as u64)
    );
    // A record without its time stamp.
    let at = edf.windows(5).position(|w| w == b"+1\x14\x14\x00").unwrap();
    let e = read(tmp.write("m.edf", &patch(&edf, at, 5, b"+1\x14x\x14"))).unwrap_err();
    assert_eq!(offset_of(&e).0, "time-keeping annotation of data record 1");
}

#[test]
fn mixed_rates_are_rejected_or_dropped() {
    // The BDF fixture with Oz at 32 samples per record instead of 64 (and records shortened to
    // match): an error by default, dropped on request.
    let bdf = std::fs::read(fixture("numpy_small.bdf")).unwrap();
    let ns = 4;
    let spr_oz = 256 + ns * (16 + 80 + 8 + 8 + 8 + 8 + 8 + 80) + 8;
    let mut header = patch(&bdf[..1280], spr_oz, 8, b"32");
    let mut body = Vec::new();
    for r in 0..2 {
        let rec = &bdf[1280 + r * 636..1280 + (r + 1) * 636];
        body.extend_from_slice(&rec[..192]); // Fp1
        body.extend_from_slice(&rec[192..192 + 96]); // Oz, first half
        body.extend_from_slice(&rec[384..]); // Status + annotations
    }
    header.extend(body);
    let tmp = TempDir::new("edf-rates");
    let file = tmp.write("mixed.bdf", &header);
    let e = read(&file).unwrap_err();
    assert!(
        matches!(&e, IoError::Unsupported { what, .. } if what.contains("Oz")),
        "{e}"
    );
    let o = EdfOptions {
        drop_mismatched_rates: true,
        ..EdfOptions::default()
    };
    let rec = read_edf_with(&file, &o).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Fp1", "Status"]);
    assert_eq!(rec.edf().unwrap().dropped_signals, ["Oz"]);
    assert_eq!(rec.raw.events().len(), 3);
}
