//! XDF: the live writer and the offline writer read back (double64 bit-exact, float32 within its
//! rounding), interleaved streams, UTF-8 markers, files cut at every byte (every complete chunk
//! kept, also as a proptest), a recorder process killed with SIGKILL, corrupt chunks (byte offset
//! and field), absurd counts, the independent Python-written fixture
//! (`tools/golden/xdf/make_xdf_fixture.py`) and, when `ODDBALL_PYXDF` names a Python with pyxdf,
//! pyxdf reading files written here.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{fixture, golden, Rng, TempDir};
use ndarray::Array2;
use oddball_io::xdf::{BOUNDARY_UUID, MAGIC};
use oddball_io::{
    parse_xdf, parse_xdf_file, parse_xdf_with, read, read_xdf, read_xdf_file, read_xdf_with,
    write_xdf, Format, IoError, XdfFile, XdfFormat, XdfOptions, XdfStream, XdfValues,
    XdfWriteOptions, XdfWriter,
};
use oddball_signal::{Event, Events, Raw};
use proptest::prelude::*;
use serde_json::Value;

fn labels(n: usize) -> Vec<String> {
    (0..n).map(|c| format!("E{}", c + 1)).collect()
}

/// A value that exercises the mantissa (not exact in float32).
fn wiggle(i: usize, c: usize) -> f64 {
    ((i as f64 * 0.37 + c as f64 * 1.91).sin() * 123.456_789_012_345) + c as f64 * 1e-7
}

fn numeric(f: &XdfFile, id: u32) -> &Array2<f64> {
    match &f.stream(id).expect("stream").values {
        XdfValues::Numeric(a) => a,
        other => panic!("not numeric: {other:?}"),
    }
}

fn strings(f: &XdfFile, id: u32) -> Vec<String> {
    match &f.stream(id).expect("stream").values {
        XdfValues::Strings(v) => v.iter().map(|s| s.join("\t")).collect(),
        other => panic!("not strings: {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------------------------

/// Writes a 4-channel EEG stream in `format` at 250 Hz (4 blocks of 100 samples) and markers.
fn write_session(path: &Path, format: XdfFormat) -> (Array2<f64>, Vec<f64>, Vec<(f64, String)>) {
    let mut w = XdfWriter::create(path).unwrap();
    let mut spec = XdfStream::eeg(
        "Amp",
        vec!["Fz".into(), "Cz".into(), "Pz".into(), "Oz".into()],
        250.0,
    );
    spec.format = format;
    spec.source_id = "serial-42".into();
    let eeg = w.add_stream(&spec).unwrap();
    let mk = w.add_stream(&XdfStream::markers("Flashes")).unwrap();
    assert_eq!((eeg, mk), (1, 2));
    let n = 400;
    let data = Array2::from_shape_fn((4, n), |(c, i)| wiggle(i, c));
    let ts: Vec<f64> = (0..n).map(|i| 5000.0 + i as f64 / 250.0).collect();
    let mut markers = Vec::new();
    for b in 0..4 {
        let r = b * 100..(b + 1) * 100;
        w.push_numeric(eeg, &ts[r.clone()], data.slice(ndarray::s![.., r.clone()]))
            .unwrap();
        let m = [
            (ts[b * 100 + 10], format!("flash {}", b + 1)),
            (ts[b * 100 + 60] + 0.001, format!("{} target: Ä{b}", 7 + b)),
        ];
        let texts: Vec<&str> = m.iter().map(|(_, s)| s.as_str()).collect();
        let mts: Vec<f64> = m.iter().map(|(t, _)| *t).collect();
        w.push_strings(mk, &mts, &texts).unwrap();
        markers.extend(m);
        assert!(w.flush_block().unwrap() > 0);
        assert_eq!(w.pending_bytes(), 0);
    }
    assert_eq!(
        w.flush_block().unwrap(),
        0,
        "nothing buffered, nothing written"
    );
    let size = w.finish().unwrap();
    assert_eq!(size, std::fs::metadata(path).unwrap().len());
    (data, ts, markers)
}

#[test]
fn double64_round_trip_is_bit_exact() {
    let tmp = TempDir::new("xdf-d64");
    let path = tmp.path().join("s.xdf");
    let (data, ts, markers) = write_session(&path, XdfFormat::Double64);
    let rec = read(&path).unwrap();
    assert_eq!(rec.format, Format::Xdf);
    assert_eq!(rec.raw.sfreq(), 250.0);
    assert_eq!(rec.raw.ch_names(), ["Fz", "Cz", "Pz", "Oz"]);
    for (a, b) in rec.raw.data().iter().zip(data.iter()) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
    let info = rec.xdf().unwrap();
    assert!(info.finished() && !info.truncated);
    assert_eq!(info.eeg().source_id, "serial-42");
    assert_eq!(info.eeg().format, XdfFormat::Double64);
    assert_eq!(info.eeg().created_at, Some(ts[0]));
    assert_eq!(info.eeg_timestamps, ts);
    assert_eq!(info.eeg_units, vec!["microvolts"; 4]);
    assert_eq!(info.scale_to_uv, vec![1.0; 4]);
    assert_eq!(info.streams.len(), 2);
    assert_eq!(info.streams[1].stream_type, "Markers");
    let footer = info.eeg().footer.as_ref().unwrap();
    assert_eq!(footer.sample_count, Some(400));
    assert_eq!(footer.first_timestamp, Some(ts[0]));
    assert_eq!(footer.last_timestamp, Some(ts[399]));
    // Markers: "flash b" → code b at the sample; "CODE target: LABEL" → code, target, label.
    let texts: Vec<_> = info.markers.iter().map(|m| m.text.clone()).collect();
    assert_eq!(
        texts,
        markers.iter().map(|m| m.1.clone()).collect::<Vec<_>>()
    );
    let ev = rec.raw.events().as_slice();
    assert_eq!(ev.len(), 8);
    for b in 0..4 {
        assert_eq!(
            ev[2 * b],
            Event::new(b * 100 + 10, b as u32 + 1).with_label(format!("flash {}", b + 1))
        );
        assert_eq!(
            ev[2 * b + 1],
            Event::new(b * 100 + 60, 7 + b as u32)
                .with_target(true)
                .with_label(format!("Ä{b}"))
        );
    }
}

#[test]
fn float32_round_trip_is_within_float32_rounding() {
    let tmp = TempDir::new("xdf-f32");
    let path = tmp.path().join("s.xdf");
    let (data, _, _) = write_session(&path, XdfFormat::Float32);
    let rec = read_xdf(&path).unwrap();
    let mut max_rel = 0.0f64;
    for (a, b) in rec.raw.data().iter().zip(data.iter()) {
        assert_eq!(*a, f64::from(*b as f32));
        max_rel = max_rel.max((a - b).abs() / b.abs().max(f64::MIN_POSITIVE));
    }
    assert!(max_rel <= f64::from(f32::EPSILON) / 2.0, "{max_rel}");
    assert!(max_rel > 0.0);
}

#[test]
fn write_xdf_round_trips_a_raw_with_its_events() {
    let n = 1234;
    let data = Array2::from_shape_fn((3, n), |(c, i)| wiggle(i, c) * 10.0);
    let events = Events::new(vec![
        Event::new(0, 1),
        Event::new(17, 3).with_target(true),
        Event::new(17, 9).with_target(false).with_label("B: grüß"),
        Event::new(600, 70_000).with_label("x"),
        Event::new(n - 1, 2),
    ]);
    let raw = Raw::new(
        data,
        512.0,
        vec!["Cz".into(), "Pz".into(), "Ωz".into()],
        events,
    )
    .unwrap();
    let tmp = TempDir::new("xdf-raw");
    let path = tmp.path().join("r.xdf");
    let s = write_xdf(
        &path,
        &raw,
        &XdfWriteOptions {
            start_time: 123.456,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((s.n_samples, s.n_channels, s.n_markers), (n, 3, 5));
    assert_eq!(s.max_rounding_uv, 0.0);
    assert_eq!(s.bytes, std::fs::metadata(&path).unwrap().len());
    let back = read(&path).unwrap();
    assert_eq!(back.raw, raw);
    assert!(back.xdf().unwrap().finished());
    // No temporary file left behind.
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);

    // Float32, and found by its magic code under another extension.
    let p32 = tmp.path().join("r.rec");
    let o = XdfWriteOptions {
        format: XdfFormat::Float32,
        markers: false,
        samples_per_chunk: 100,
        ..Default::default()
    };
    let s = write_xdf(&p32, &raw, &o).unwrap();
    assert!(s.max_rounding_uv > 0.0 && s.max_rounding_uv < 1e-4);
    let back = read(&p32).unwrap();
    assert_eq!(back.format, Format::Xdf);
    assert!(back.raw.events().is_empty());
    let max = back
        .raw
        .data()
        .iter()
        .zip(raw.data().iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert_eq!(max, s.max_rounding_uv);

    // Refusals: a non-finite sample, a string format.
    let mut bad = raw.clone();
    bad.data_mut()[[1, 5]] = f64::NAN;
    match write_xdf(
        tmp.path().join("bad.xdf"),
        &bad,
        &XdfWriteOptions::default(),
    ) {
        Err(IoError::UnwritableSample {
            channel_index: 1,
            sample: 5,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let o = XdfWriteOptions {
        format: XdfFormat::String,
        ..Default::default()
    };
    assert!(matches!(
        write_xdf(tmp.path().join("s.xdf"), &raw, &o),
        Err(IoError::Unsupported { .. })
    ));
    assert!(!tmp.path().join("bad.xdf").exists());
}

#[test]
fn interleaved_streams_keep_their_own_order() {
    let tmp = TempDir::new("xdf-inter");
    let path = tmp.path().join("i.xdf");
    let mut w = XdfWriter::create(&path).unwrap();
    let a = w
        .add_stream(&XdfStream::eeg("A", labels(3), 100.0))
        .unwrap();
    let mut bs = XdfStream::eeg("B", labels(2), 30.0);
    bs.format = XdfFormat::Int16;
    bs.stream_type = "ACC".into();
    let b = w.add_stream(&bs).unwrap();
    let m = w.add_stream(&XdfStream::markers("M")).unwrap();
    let mut rng = Rng(7);
    let (mut na, mut nb, mut nm) = (0usize, 0usize, 0usize);
    for round in 0..60 {
        // Streams pushed in random order, several times per block, flushed at random.
        for _ in 0..3 {
            match rng.below(3) {
                0 => {
                    let k = 1 + rng.below(9);
                    let ts: Vec<f64> = (na..na + k).map(|i| i as f64 / 100.0).collect();
                    let d = Array2::from_shape_fn((3, k), |(c, i)| ((na + i) * 3 + c) as f64);
                    w.push_numeric(a, &ts, d.view()).unwrap();
                    na += k;
                }
                1 => {
                    let ts = [nb as f64 / 30.0];
                    let d = Array2::from_shape_fn((2, 1), |(c, _)| -(nb as f64) * (c as f64 + 1.0));
                    w.push_numeric(b, &ts, d.view()).unwrap();
                    nb += 1;
                }
                _ => {
                    w.push_strings(m, &[nm as f64 * 0.05], &[&format!("m{nm}")])
                        .unwrap();
                    nm += 1;
                }
            }
        }
        if round % 4 == 3 || rng.below(2) == 0 {
            w.flush_block().unwrap();
        }
    }
    assert_eq!(w.sample_count(a), Some(na as u64));
    w.finish().unwrap();
    let f = read_xdf_file(&path).unwrap();
    let ea = Array2::from_shape_fn((3, na), |(c, i)| (i * 3 + c) as f64);
    assert_eq!(numeric(&f, a), &ea);
    assert_eq!(
        f.stream(a).unwrap().timestamps,
        (0..na).map(|i| i as f64 / 100.0).collect::<Vec<_>>()
    );
    let eb = Array2::from_shape_fn((2, nb), |(c, i)| -(i as f64) * (c as f64 + 1.0));
    assert_eq!(numeric(&f, b), &eb);
    assert_eq!(
        strings(&f, m),
        (0..nm).map(|i| format!("m{i}")).collect::<Vec<_>>()
    );
    assert_eq!(
        f.stream(m)
            .unwrap()
            .info
            .footer
            .as_ref()
            .unwrap()
            .sample_count,
        Some(nm as u64)
    );
    assert!(f.stream(a).unwrap().info.n_sample_chunks > 1);
    // The EEG is A (type EEG); B is type ACC.
    let rec = read_xdf(&path).unwrap();
    assert_eq!(rec.raw.n_channels(), 3);
    assert_eq!(rec.xdf().unwrap().markers.len(), nm);
    // Chosen by name instead.
    let o = XdfOptions {
        eeg_stream: Some("B".into()),
        ..Default::default()
    };
    assert_eq!(read_xdf_with(&path, &o).unwrap().raw.sfreq(), 30.0);
    let o = XdfOptions {
        eeg_stream: Some("nope".into()),
        ..Default::default()
    };
    assert!(matches!(
        read_xdf_with(&path, &o),
        Err(IoError::Missing { .. })
    ));
}

#[test]
fn utf8_markers_and_their_codes() {
    let tmp = TempDir::new("xdf-utf8");
    let path = tmp.path().join("u.xdf");
    let mut w = XdfWriter::create(&path).unwrap();
    let e = w
        .add_stream(&XdfStream::eeg("EEG ü", labels(1), 10.0))
        .unwrap();
    let m = w.add_stream(&XdfStream::markers("Märker <&>")).unwrap();
    let ts: Vec<f64> = (0..100).map(|i| i as f64 / 10.0).collect();
    w.push_numeric(e, &ts, Array2::zeros((1, 100)).view())
        .unwrap();
    let long = "ß".repeat(200); // 400 bytes: a 4-byte string length
    let texts = [
        "Grüße 🎉",
        "flash 3",
        "12",
        "",
        &long,
        "Grüße 🎉",
        "nontarget",
        "4 nontarget",
        "late",
    ];
    let mts = [0.0, 1.0, 2.04, 3.0, 4.0, 5.0, 6.0, 7.0, 99.0];
    w.push_strings(m, &mts, &texts).unwrap();
    w.finish().unwrap();
    let f = read_xdf_file(&path).unwrap();
    assert_eq!(f.stream(m).unwrap().info.name, "Märker <&>");
    assert_eq!(strings(&f, m), texts);
    let rec = read_xdf(&path).unwrap();
    let info = rec.xdf().unwrap();
    let got: Vec<_> = info
        .markers
        .iter()
        .map(|m| (m.text.as_str(), m.code, m.target, m.sample))
        .collect();
    // Numeric codes 3, 12, 4; texts from 13 in order of first appearance.
    assert_eq!(
        got,
        vec![
            ("Grüße 🎉", 13, None, Some(0)),
            ("flash 3", 3, None, Some(10)),
            ("12", 12, None, Some(20)),
            ("", 14, None, Some(30)),
            (long.as_str(), 15, None, Some(40)),
            ("Grüße 🎉", 13, None, Some(50)),
            ("nontarget", 16, None, Some(60)),
            ("4 nontarget", 4, Some(false), Some(70)),
            ("late", 17, None, None),
        ]
    );
    assert_eq!(rec.raw.events().len(), 8);
    assert_eq!(
        rec.raw.events().as_slice()[0].label.as_deref(),
        Some("Grüße 🎉")
    );
}

#[test]
fn units_clock_offsets_and_boundaries() {
    let tmp = TempDir::new("xdf-units");
    let path = tmp.path().join("v.xdf");
    let mut w = XdfWriter::create(&path).unwrap();
    let mut spec = XdfStream::eeg("Volts", labels(2), 100.0);
    spec.unit = "volts".into();
    spec.format = XdfFormat::Double64;
    let e = w.add_stream(&spec).unwrap();
    let m = w.add_stream(&XdfStream::markers("M")).unwrap();
    // 25 s of data: two Boundary chunks.
    for b in 0..25 {
        let ts: Vec<f64> = (0..100).map(|i| b as f64 + i as f64 / 100.0).collect();
        let d = Array2::from_elem((2, 100), 2.5e-5);
        w.push_numeric(e, &ts, d.view()).unwrap();
        w.flush_block().unwrap();
    }
    // The marker stream's clock is 0.5 s behind: the marker at 1.0 belongs at 1.5 s.
    w.push_strings(m, &[1.0], &["flash 1"]).unwrap();
    w.push_clock_offset(m, 10.0, 0.5).unwrap();
    w.push_clock_offset(m, 20.0, 0.5).unwrap();
    assert!(w.push_clock_offset(m, f64::NAN, 0.5).is_err());
    w.finish().unwrap();
    let rec = read_xdf(&path).unwrap();
    assert!(rec.raw.data().iter().all(|&x| x == 2.5e-5 * 1e6));
    let info = rec.xdf().unwrap();
    assert_eq!(info.scale_to_uv, vec![1e6, 1e6]);
    assert_eq!(info.n_boundaries, 2);
    assert_eq!(
        info.streams[1].clock_offsets,
        vec![(10.0, 0.5), (20.0, 0.5)]
    );
    assert_eq!(info.streams[1].clock_fit, Some((0.5, 0.0)));
    assert_eq!(
        rec.raw.events().as_slice(),
        [Event::new(150, 1).with_label("flash 1")]
    );
    let o = XdfOptions {
        synchronize_clocks: false,
        ..Default::default()
    };
    assert_eq!(
        read_xdf_with(&path, &o).unwrap().raw.events().as_slice()[0].onset,
        100
    );
}

/// Unit strings as LSL outlets, LabRecorder and careless writers put them in a stream header,
/// with the µV factor the one rule (`oddball_io::units`) gives a live LSL inlet; `None`: the
/// inlet refuses the stream.
const STREAM_UNITS: [(&str, Option<f64>); 24] = [
    ("", Some(1.0)),
    ("microvolts", Some(1.0)),
    ("Microvolt", Some(1.0)),
    ("micro volts", Some(1.0)),
    ("uV", Some(1.0)),
    ("UV", Some(1.0)),
    ("µV", Some(1.0)),
    ("μV", Some(1.0)),
    ("muV", Some(1.0)),
    ("volts", Some(1e6)),
    ("V", Some(1e6)),
    ("millivolts", Some(1e3)),
    ("mV", Some(1e3)),
    ("MV", Some(1e3)),
    ("Mv", Some(1e3)),
    ("nanovolts", Some(1e-3)),
    ("nV", Some(1e-3)),
    ("NV", Some(1e-3)),
    ("kV", Some(1e9)),
    ("kilovolts", Some(1e9)),
    ("counts", None),
    ("degC", None),
    ("uvs", None),
    ("mvolts", None),
];

/// An XDF recording of a stream reads back scaled by the factor a live inlet applies to the
/// same stream (an `MV` stream is millivolts both live and read back), with no unit as µV and a
/// unit the inlet refuses kept unscaled.
#[test]
fn every_stream_unit_reads_back_as_the_live_inlet_scales_it() {
    let tmp = TempDir::new("xdf-unit-rule");
    for (k, (unit, live)) in STREAM_UNITS.into_iter().enumerate() {
        assert_eq!(
            oddball_io::units::stream_microvolts_per(unit),
            live,
            "{unit:?}"
        );
        let path = tmp.path().join(format!("u{k}.xdf"));
        let mut w = XdfWriter::create(&path).unwrap();
        let mut spec = XdfStream::eeg("Amp", labels(2), 100.0);
        spec.unit = unit.to_string();
        spec.format = XdfFormat::Double64;
        let e = w.add_stream(&spec).unwrap();
        let ts: Vec<f64> = (0..10).map(|i| i as f64 / 100.0).collect();
        w.push_numeric(e, &ts, Array2::from_elem((2, 10), 2.5).view())
            .unwrap();
        w.finish().unwrap();
        let rec = read_xdf(&path).unwrap();
        let f = live.unwrap_or(1.0);
        let info = rec.xdf().unwrap();
        assert_eq!(info.scale_to_uv, vec![f, f], "{unit:?}");
        assert_eq!(info.eeg_units, vec![unit.to_string(); 2], "{unit:?}");
        assert!(rec.raw.data().iter().all(|&x| x == 2.5 * f), "{unit:?}");
    }
}

#[test]
fn the_writer_refuses_bad_input_and_buffers_nothing_then() {
    let tmp = TempDir::new("xdf-refuse");
    let path = tmp.path().join("w.xdf");
    let mut w = XdfWriter::create(&path).unwrap();
    // Never replaces an existing file.
    assert!(matches!(
        XdfWriter::create(&path),
        Err(IoError::Io {
            action: "create",
            ..
        })
    ));
    let mut i16s = XdfStream::eeg("I", labels(2), 10.0);
    i16s.format = XdfFormat::Int16;
    let e = w.add_stream(&XdfStream::eeg("E", labels(2), 10.0)).unwrap();
    let i = w.add_stream(&i16s).unwrap();
    let m = w.add_stream(&XdfStream::markers("M")).unwrap();
    let ok = Array2::<f64>::zeros((2, 3));
    let unsupported = |r: Result<(), IoError>, needle: &str| match r {
        Err(IoError::Unsupported { what, .. }) => assert!(what.contains(needle), "{what}"),
        other => panic!("{needle}: {other:?}"),
    };
    unsupported(
        w.push_numeric(e, &[0.0, f64::NAN, 2.0], ok.view()),
        "timestamp 1 is NaN",
    );
    unsupported(
        w.push_numeric(e, &[0.0, 1.0, f64::INFINITY], ok.view()),
        "timestamp 2 is inf",
    );
    unsupported(
        w.push_numeric(e, &[0.0, 1.0, 2.0], Array2::zeros((3, 3)).view()),
        "has 2 channels, but the data has 3 rows",
    );
    unsupported(
        w.push_numeric(e, &[0.0, 1.0], ok.view()),
        "2 timestamps for 3 samples",
    );
    unsupported(
        w.push_numeric(m, &[0.0, 1.0, 2.0], ok.view()),
        "use push_strings",
    );
    unsupported(w.push_strings(e, &[0.0], &["x"]), "use push_numeric");
    assert!(matches!(
        w.push_numeric(99, &[0.0, 1.0, 2.0], ok.view()),
        Err(IoError::Missing { .. })
    ));
    let mut big = ok.clone();
    big[[1, 2]] = 1e39;
    match w.push_numeric(e, &[0.0, 1.0, 2.0], big.view()) {
        Err(IoError::UnwritableSample {
            channel,
            channel_index: 1,
            sample: 2,
            reason,
            ..
        }) => {
            assert_eq!(channel, "E2");
            assert!(reason.contains("float32"));
        }
        other => panic!("{other:?}"),
    }
    let mut v = ok.clone();
    v[[0, 1]] = 40_000.0;
    assert!(matches!(
        w.push_numeric(i, &[0.0, 1.0, 2.0], v.view()),
        Err(IoError::UnwritableSample { sample: 1, .. })
    ));
    v[[0, 1]] = f64::NAN;
    assert!(matches!(
        w.push_numeric(i, &[0.0, 1.0, 2.0], v.view()),
        Err(IoError::UnwritableSample { .. })
    ));
    assert_eq!(w.pending_bytes(), 0);
    assert_eq!(w.sample_count(e), Some(0));
    // Stream definitions.
    let mut s = XdfStream::eeg("Z", vec![], 10.0);
    assert!(w.add_stream(&s).is_err());
    s.channel_labels = labels(10_001);
    assert!(w.add_stream(&s).is_err());
    s.channel_labels = vec!["a\tb".into()];
    assert!(w.add_stream(&s).is_err());
    s.channel_labels = labels(1);
    for r in [-1.0, f64::NAN, f64::INFINITY] {
        s.nominal_srate = r;
        assert!(w.add_stream(&s).is_err());
    }
    let mut two = XdfStream::markers("two");
    two.channel_labels = labels(2);
    assert!(w.add_stream(&two).is_err());
    // Good values still go in; NaN is stored as it is in a float stream.
    let mut nan = ok.clone();
    nan[[0, 0]] = f64::NAN;
    w.push_numeric(e, &[0.0, 0.1, 0.2], nan.view()).unwrap();
    w.push_numeric(
        i,
        &[0.0, 0.1, 0.2],
        Array2::from_elem((2, 3), -32768.4).view(),
    )
    .unwrap();
    w.finish().unwrap();
    let f = read_xdf_file(&path).unwrap();
    assert_eq!(f.streams.len(), 3);
    assert!(numeric(&f, e)[[0, 0]].is_nan());
    assert!(numeric(&f, i).iter().all(|&x| x == -32768.0));
}

#[test]
fn a_dropped_writer_flushes_its_last_block_without_footers() {
    let tmp = TempDir::new("xdf-drop");
    let path = tmp.path().join("d.xdf");
    {
        let mut w = XdfWriter::create(&path).unwrap();
        let e = w.add_stream(&XdfStream::eeg("E", labels(2), 10.0)).unwrap();
        w.push_numeric(e, &[0.0, 0.1], Array2::ones((2, 2)).view())
            .unwrap();
    }
    let rec = read_xdf(&path).unwrap();
    assert_eq!(rec.raw.n_times(), 2);
    let info = rec.xdf().unwrap();
    assert!(!info.truncated && !info.finished());
    assert!(info.eeg().footer.is_none());
}

// ---------------------------------------------------------------------------------------------
// Cut files
// ---------------------------------------------------------------------------------------------

/// A file whose every block is one chunk: the FileHeader (with the magic code), a StreamHeader
/// for each of the two streams, then Samples chunks of one stream each, then the footers. The
/// timestamps stay below 10 s, so no Boundary chunk joins a block.
struct Written {
    bytes: Vec<u8>,
    /// `(end offset, stream, samples)` per block; `stream` = None for the FileHeader, samples =
    /// None for a StreamHeader.
    blocks: Vec<(usize, Option<usize>, Option<usize>)>,
    footer_start: usize,
    eeg: Vec<(f64, Vec<f64>)>,
    markers: Vec<(f64, String)>,
    format: XdfFormat,
    n_ch: usize,
}

fn write_plan(path: &Path, format: XdfFormat, n_ch: usize, plan: &[(bool, usize)]) -> Written {
    let mut w = XdfWriter::create(path).unwrap();
    let mut blocks = vec![(w.bytes_written() as usize, None, None)];
    let mut spec = XdfStream::eeg("EEG", labels(n_ch), 100.0);
    spec.format = format;
    let e = w.add_stream(&spec).unwrap();
    w.flush_block().unwrap();
    blocks.push((w.bytes_written() as usize, Some(0), None));
    let m = w.add_stream(&XdfStream::markers("Markers")).unwrap();
    w.flush_block().unwrap();
    blocks.push((w.bytes_written() as usize, Some(1), None));
    let (mut eeg, mut markers) = (Vec::new(), Vec::new());
    for &(is_eeg, n) in plan {
        if is_eeg {
            let i0 = eeg.len();
            let ts: Vec<f64> = (i0..i0 + n).map(|i| i as f64 / 100.0).collect();
            let d = Array2::from_shape_fn((n_ch, n), |(c, i)| {
                (wiggle(i0 + i, c) * 100.0).round() / 4.0
            });
            w.push_numeric(e, &ts, d.view()).unwrap();
            for (k, t) in ts.iter().enumerate() {
                eeg.push((*t, d.column(k).to_vec()));
            }
            blocks.push((0, Some(0), Some(n)));
        } else {
            let texts: Vec<String> = (0..n)
                .map(|k| format!("flash {} ü", markers.len() + k))
                .collect();
            let ts: Vec<f64> = (0..n).map(|k| (markers.len() + k) as f64 * 0.01).collect();
            let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
            w.push_strings(m, &ts, &refs).unwrap();
            markers.extend(ts.into_iter().zip(texts));
            blocks.push((0, Some(1), Some(n)));
        }
        w.flush_block().unwrap();
        blocks.last_mut().unwrap().0 = w.bytes_written() as usize;
    }
    let footer_start = w.bytes_written() as usize;
    w.finish().unwrap();
    Written {
        bytes: std::fs::read(path).unwrap(),
        blocks,
        footer_start,
        eeg,
        markers,
        format,
        n_ch,
    }
}

/// What must be read from the first `cut` bytes of `w`; `Err` names the first difference.
fn check_cut(w: &Written, cut: usize) -> Result<(), String> {
    let f = parse_xdf_file(&w.bytes[..cut], Path::new("cut.xdf"))
        .map_err(|e| format!("cut {cut}: {e}"))?;
    let done = |stream: usize| {
        w.blocks
            .iter()
            .filter(move |b| b.0 <= cut && b.1 == Some(stream))
    };
    let has_header = |s: usize| done(s).any(|b| b.2.is_none()) || cut >= w.footer_start;
    let n_of = |s: usize| -> usize { done(s).filter_map(|b| b.2).sum() };
    let want_streams = usize::from(has_header(0)) + usize::from(has_header(1));
    if f.streams.len() != want_streams {
        return Err(format!(
            "cut {cut}: {} streams, want {want_streams}",
            f.streams.len()
        ));
    }
    // Truncation: known inside every single-chunk block (the footer block holds two chunks).
    if cut < w.footer_start {
        let at_end = cut == 4 || w.blocks.iter().any(|b| b.0 == cut);
        if f.truncated == at_end {
            return Err(format!("cut {cut}: truncated {}", f.truncated));
        }
    } else if cut == w.bytes.len() && f.truncated {
        return Err("whole file truncated".into());
    }
    if has_header(0) {
        let n = n_of(0);
        let s = f.stream(1).ok_or("no EEG")?;
        if s.timestamps.len() != n {
            return Err(format!(
                "cut {cut}: {} EEG samples, want {n}",
                s.timestamps.len()
            ));
        }
        let XdfValues::Numeric(a) = &s.values else {
            return Err("EEG not numeric".into());
        };
        for (k, (t, v)) in w.eeg[..n].iter().enumerate() {
            if s.timestamps[k].to_bits() != t.to_bits() {
                return Err(format!("cut {cut}: timestamp {k}"));
            }
            for c in 0..w.n_ch {
                let want = match w.format {
                    XdfFormat::Float32 => f64::from(v[c] as f32),
                    XdfFormat::Int16 => v[c].round(),
                    _ => v[c],
                };
                if a[[c, k]].to_bits() != want.to_bits() {
                    return Err(format!(
                        "cut {cut}: value [{c}, {k}] {} != {want}",
                        a[[c, k]]
                    ));
                }
            }
        }
    }
    if has_header(1) {
        let n = n_of(1);
        let got = strings(&f, 2);
        let want: Vec<String> = w.markers[..n].iter().map(|m| m.1.clone()).collect();
        if got != want {
            return Err(format!("cut {cut}: markers {got:?} != {want:?}"));
        }
    }
    // The recording reads whenever the EEG header is complete.
    if has_header(0) {
        let rec = parse_xdf(&w.bytes[..cut], Path::new("cut.xdf"))
            .map_err(|e| format!("cut {cut}: recording: {e}"))?;
        if rec.raw.n_times() != n_of(0) || rec.xdf().unwrap().truncated != f.truncated {
            return Err(format!("cut {cut}: recording"));
        }
    }
    Ok(())
}

#[test]
fn every_cut_of_a_written_file_keeps_every_complete_chunk() {
    let tmp = TempDir::new("xdf-cuts");
    let plan = [
        (true, 7),
        (false, 2),
        (true, 1),
        (true, 30),
        (false, 1),
        (false, 3),
        (true, 5),
    ];
    let w = write_plan(&tmp.path().join("c.xdf"), XdfFormat::Double64, 3, &plan);
    for cut in 0..=w.bytes.len() {
        if let Err(e) = check_cut(&w, cut) {
            panic!("{e}");
        }
    }
    // Strict reading refuses a cut file, naming where its last chunk starts.
    let cut = w.blocks[4].0 - 3;
    let o = XdfOptions {
        allow_truncated: false,
        ..Default::default()
    };
    match parse_xdf_with(&w.bytes[..cut], Path::new("cut.xdf"), &o) {
        Err(IoError::Truncated {
            offset, file_len, ..
        }) => {
            assert_eq!(offset as usize, w.blocks[3].0);
            assert_eq!(file_len as usize, cut);
        }
        other => panic!("{other:?}"),
    }
    // A file cut before its EEG header has no EEG.
    assert!(matches!(
        parse_xdf(&w.bytes[..w.blocks[1].0 - 1], Path::new("x.xdf")),
        Err(IoError::Missing { .. })
    ));
}

fn arb_plan() -> impl Strategy<Value = (XdfFormat, usize, Vec<(bool, usize)>)> {
    (
        prop_oneof![
            Just(XdfFormat::Float32),
            Just(XdfFormat::Double64),
            Just(XdfFormat::Int16)
        ],
        1usize..6,
        prop::collection::vec((any::<bool>(), 1usize..40), 1..12),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn any_cut_reads_without_panic((format, n_ch, plan) in arb_plan(), cut_frac in 0.0f64..=1.0) {
        let tmp = TempDir::new("xdf-prop");
        let w = write_plan(&tmp.path().join("p.xdf"), format, n_ch, &plan);
        let cut = ((w.bytes.len() as f64) * cut_frac).round() as usize;
        prop_assert_eq!(check_cut(&w, cut.min(w.bytes.len())), Ok(()));
        // And a few cuts near block ends, where mistakes hide.
        for b in &w.blocks {
            for d in [0usize, 1, 2, 3, 9] {
                if b.0 >= d {
                    prop_assert_eq!(check_cut(&w, b.0 - d), Ok(()));
                }
            }
        }
    }
}

const CHILD_ENV: &str = "ODDBALL_XDF_RECORDER_CHILD";

fn kill_value(i: usize, c: usize) -> f64 {
    ((i * 31 + c * 7) % 2001) as f64 * 0.5 - 500.0
}

/// Not a test of its own: the recorder process of `a_killed_recorder_leaves_a_readable_file`
/// (does nothing unless `ODDBALL_XDF_RECORDER_CHILD` names the file to record to).
#[test]
fn recorder_child_process() {
    let Some(path) = std::env::var_os(CHILD_ENV) else {
        return;
    };
    let mut w = XdfWriter::create(PathBuf::from(path)).unwrap();
    let e = w
        .add_stream(&XdfStream::eeg("Amp", labels(8), 500.0))
        .unwrap();
    let m = w.add_stream(&XdfStream::markers("M")).unwrap();
    let start = Instant::now();
    let n = 25;
    let mut i = 0;
    // Records until killed (at most 60 s or 64 MiB, should the parent be gone).
    while start.elapsed() < Duration::from_secs(60) && w.bytes_written() < 64 << 20 {
        let ts: Vec<f64> = (i..i + n).map(|k| k as f64 / 500.0).collect();
        let d = Array2::from_shape_fn((8, n), |(c, k)| kill_value(i + k, c));
        w.push_numeric(e, &ts, d.view()).unwrap();
        if (i / n) % 4 == 0 {
            w.push_strings(m, &[ts[3]], &[&format!("flash {}", (i / n) % 12 + 1)])
                .unwrap();
        }
        w.flush_block().unwrap();
        i += n;
    }
}

#[test]
fn a_killed_recorder_leaves_a_readable_file() {
    let tmp = TempDir::new("xdf-kill");
    let path = tmp.path().join("live.xdf");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "recorder_child_process",
            "--exact",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &path)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while std::fs::metadata(&path).map_or(0, |m| m.len()) < 400_000
        && t0.elapsed() < Duration::from_secs(30)
    {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL
    let status = child.wait().unwrap();
    let rec = read_xdf(&path).unwrap();
    let info = rec.xdf().unwrap();
    let n = rec.raw.n_times();
    eprintln!(
        "killed recorder ({status}): {} bytes, {n} samples, {} markers, truncated {}",
        std::fs::metadata(&path).unwrap().len(),
        info.markers.len(),
        info.truncated
    );
    assert!(!info.finished());
    assert!(n >= 25 && n % 25 == 0, "{n}");
    for ((c, i), &x) in rec.raw.data().indexed_iter() {
        assert_eq!(x, kill_value(i, c), "[{c}, {i}]");
    }
    assert_eq!(info.eeg_timestamps[n - 1], (n - 1) as f64 / 500.0);
    for (k, m) in info.markers.iter().enumerate() {
        assert_eq!(m.code as usize, (4 * k) % 12 + 1);
        assert_eq!(m.sample, Some(100 * k + 3));
    }
}

// ---------------------------------------------------------------------------------------------
// Corrupt files
// ---------------------------------------------------------------------------------------------

fn chunk(tag: u16, content: &[u8]) -> Vec<u8> {
    let mut b = vec![4];
    b.extend_from_slice(&(2 + content.len() as u32).to_le_bytes());
    b.extend_from_slice(&tag.to_le_bytes());
    b.extend_from_slice(content);
    b
}

fn with_id(id: u32, rest: &[u8]) -> Vec<u8> {
    let mut b = id.to_le_bytes().to_vec();
    b.extend_from_slice(rest);
    b
}

fn eeg_xml(cc: &str, srate: &str, fmt: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?><info><name>E</name><type>EEG</type><channel_count>{cc}</channel_count>\
         <nominal_srate>{srate}</nominal_srate><channel_format>{fmt}</channel_format></info>"
    )
}

/// Magic, FileHeader, a 2-channel double64 EEG header; returns the bytes.
fn start_file() -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.extend(chunk(1, b"<info><version>1.0</version></info>"));
    b.extend(chunk(
        2,
        &with_id(1, eeg_xml("2", "100", "double64").as_bytes()),
    ));
    b
}

fn sample(ts: Option<f64>, v: [f64; 2]) -> Vec<u8> {
    let mut b = Vec::new();
    match ts {
        Some(t) => {
            b.push(8);
            b.extend_from_slice(&t.to_le_bytes());
        }
        None => b.push(0),
    }
    for x in v {
        b.extend_from_slice(&x.to_le_bytes());
    }
    b
}

fn samples_chunk(id: u32, n: &[u8], body: &[u8]) -> Vec<u8> {
    let mut c = id.to_le_bytes().to_vec();
    c.extend_from_slice(n);
    c.extend_from_slice(body);
    chunk(3, &c)
}

/// `(offset, field)` of the error parsing `bytes`.
fn invalid(bytes: &[u8]) -> (u64, String, String) {
    match parse_xdf_file(bytes, Path::new("bad.xdf")) {
        Err(IoError::InvalidField {
            offset,
            field,
            expected,
            ..
        }) => (offset, field, expected),
        other => panic!("{other:?}"),
    }
}

#[test]
fn corrupt_chunks_are_errors_naming_offset_and_field() {
    let good = {
        let mut b = start_file();
        let mut body = sample(Some(1.0), [1.0, 2.0]);
        body.extend(sample(None, [3.0, 4.0]));
        b.extend(samples_chunk(1, &[1, 2], &body));
        b
    };
    let f = parse_xdf_file(&good, Path::new("g.xdf")).unwrap();
    assert_eq!(f.stream(1).unwrap().timestamps, [1.0, 1.01]);
    assert_eq!(numeric(&f, 1), &ndarray::array![[1.0, 3.0], [2.0, 4.0]]);
    let samples_at = start_file().len();

    // The magic code.
    let (off, field, _) = invalid(b"XDG:\x01\x02");
    assert_eq!((off, field.as_str()), (0, "magic code"));
    assert!(parse_xdf_file(b"XD", Path::new("x")).unwrap().truncated);

    // NumLengthBytes 3 in the middle.
    let mut b = good.clone();
    b[samples_at] = 3;
    assert_eq!(invalid(&b).0 as usize, samples_at);
    assert_eq!(invalid(&b).1, "chunk NumLengthBytes");

    // Length 1.
    let mut b = start_file();
    b.extend([1u8, 1, 0]);
    b.extend(chunk(5, &BOUNDARY_UUID));
    assert_eq!(invalid(&b).0 as usize, samples_at + 1);

    // NumSamples 10^12 in a 40-byte chunk: refused before allocating.
    let mut n = vec![8u8];
    n.extend_from_slice(&1_000_000_000_000u64.to_le_bytes());
    let mut b = start_file();
    b.extend(samples_chunk(1, &n, &sample(Some(1.0), [1.0, 2.0])));
    let (off, field, expected) = invalid(&b);
    assert_eq!(
        (off as usize, field.as_str()),
        (samples_at + 7 + 4, "Samples (stream 1) NumSamples")
    );
    assert!(expected.starts_with("at most 1 samples"), "{expected}");

    // TimeStampBytes 5 in the second sample.
    let mut body = sample(Some(1.0), [1.0, 2.0]);
    let second = body.len();
    body.extend(sample(None, [3.0, 4.0]));
    body[second] = 5;
    let mut b = start_file();
    b.extend(samples_chunk(1, &[1, 2], &body));
    let (off, field, _) = invalid(&b);
    assert_eq!(
        (off as usize, field.as_str()),
        (
            samples_at + 7 + 4 + 2 + second,
            "Samples (stream 1) sample 1 TimeStampBytes"
        )
    );

    // Extra bytes after the samples; fewer samples than NumSamples.
    let mut b = start_file();
    let mut body = sample(Some(1.0), [1.0, 2.0]);
    body.push(0);
    b.extend(samples_chunk(1, &[1, 1], &body));
    assert_eq!(invalid(&b).1, "Samples (stream 1) end");
    let mut b = start_file();
    b.extend(samples_chunk(
        1,
        &[1, 2],
        &[sample(Some(1.0), [1.0, 2.0]), vec![0; 10]].concat(),
    ));
    assert!(invalid(&b).1.starts_with("Samples (stream 1) sample 1"));

    // Samples, clock offsets, footers of a stream without header.
    let mut b = start_file();
    b.extend(samples_chunk(9, &[1, 1], &sample(Some(1.0), [1.0, 2.0])));
    assert_eq!(
        invalid(&b),
        (
            (samples_at + 7) as u64,
            "Samples StreamId".into(),
            "the id of a stream whose StreamHeader came before".into()
        )
    );
    let mut b = start_file();
    b.extend(chunk(4, &with_id(2, &[0; 16])));
    assert_eq!(invalid(&b).1, "ClockOffset StreamId");
    let mut b = start_file();
    b.extend(chunk(4, &with_id(1, &[0; 15])));
    assert_eq!(invalid(&b).1, "ClockOffset chunk Length");
    let mut b = start_file();
    b.extend(chunk(6, &with_id(3, b"<info/>")));
    assert_eq!(invalid(&b).1, "StreamFooter StreamId");

    // A second header for one stream; a wrong Boundary.
    let mut b = start_file();
    b.extend(chunk(
        2,
        &with_id(1, eeg_xml("2", "100", "double64").as_bytes()),
    ));
    assert_eq!(invalid(&b).1, "StreamHeader StreamId");
    let mut b = start_file();
    b.extend(chunk(5, &[0x43; 16]));
    assert_eq!(invalid(&b).1, "Boundary chunk");

    // Header values: offset of the value's text.
    let header_xml_at = MAGIC.len() + 7 + "<info><version>1.0</version></info>".len() + 7 + 4;
    for (cc, sr, fmt, field, bad) in [
        ("0", "100", "double64", "channel_count", "0"),
        ("10001", "100", "double64", "channel_count", "10001"),
        ("two", "100", "double64", "channel_count", "two"),
        (
            "99999999999999999999",
            "100",
            "double64",
            "channel_count",
            "9999",
        ),
        ("2", "-1", "double64", "nominal_srate", "-1"),
        ("2", "NaN", "double64", "nominal_srate", "NaN"),
        ("2", "inf", "double64", "nominal_srate", "inf"),
        ("2", "100", "float16", "channel_format", "float16"),
    ] {
        let mut b = MAGIC.to_vec();
        b.extend(chunk(1, b"<info><version>1.0</version></info>"));
        b.extend(chunk(2, &with_id(1, eeg_xml(cc, sr, fmt).as_bytes())));
        let (off, f, _) = invalid(&b);
        assert_eq!(f, format!("StreamHeader (stream 1) {field}"));
        assert!(off as usize > header_xml_at);
        assert!(
            b[off as usize..].starts_with(bad.as_bytes()),
            "{field} {bad}"
        );
    }
    // Missing channel_count; XML that is not well-formed; not UTF-8.
    let mut b = MAGIC.to_vec();
    b.extend(chunk(
        2,
        &with_id(1, b"<info><nominal_srate>1</nominal_srate></info>"),
    ));
    assert_eq!(invalid(&b).1, "StreamHeader (stream 1) channel_count");
    let mut b = MAGIC.to_vec();
    b.extend(chunk(2, &with_id(1, b"<info><name>x</info>")));
    let (off, field, _) = invalid(&b);
    assert_eq!(
        (off as usize, field.as_str()),
        (MAGIC.len() + 7 + 4 + 13, "StreamHeader XML")
    );
    let mut b = MAGIC.to_vec();
    b.extend(chunk(2, &with_id(1, b"<info>\xff</info>")));
    assert_eq!(
        invalid(&b),
        (
            (MAGIC.len() + 7 + 4 + 6) as u64,
            "StreamHeader XML".into(),
            "UTF-8 text".into()
        )
    );

    // A string length beyond its chunk.
    let mut b = MAGIC.to_vec();
    b.extend(chunk(
        2,
        &with_id(1, eeg_xml("1", "0", "string").as_bytes()),
    ));
    let mut body = vec![8];
    body.extend_from_slice(&1.0f64.to_le_bytes());
    body.extend([4, 0xff, 0xff, 0xff, 0x7f, b'a']);
    b.extend(samples_chunk(1, &[1, 1], &body));
    assert_eq!(
        invalid(&b).1,
        "Samples (stream 1) sample 0 channel 0 string length"
    );

    // A Length beyond the end of the file is a cut file: read up to it.
    let mut b = good.clone();
    b.extend([8u8, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x7f, 3, 0]);
    let f = parse_xdf_file(&b, Path::new("cut.xdf")).unwrap();
    assert!(f.truncated);
    assert_eq!(f.truncated_at, Some(good.len() as u64));
    assert_eq!(f.stream(1).unwrap().timestamps.len(), 2);

    // Unknown tags are skipped.
    let mut b = good.clone();
    b.extend(chunk(77, b"future"));
    assert_eq!(
        parse_xdf_file(&b, Path::new("u.xdf"))
            .unwrap()
            .n_unknown_chunks,
        1
    );
}

#[test]
fn mutated_files_never_panic() {
    let tmp = TempDir::new("xdf-mut");
    let plan = [(true, 5), (false, 2), (true, 3)];
    let w = write_plan(&tmp.path().join("m.xdf"), XdfFormat::Float32, 2, &plan);
    let interesting: &[&[u8]] = &[
        b"\x08",
        b"\x04",
        b"\x01",
        b"\xff\xff\xff\xff",
        b"<",
        b"&",
        b"\x00",
        b"\x03",
    ];
    let n: usize = std::env::var("ODDBALL_FUZZ_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4000);
    let mut rng = Rng(0x05ee_d0dd_ba11);
    let (mut ok, mut err) = (0, 0);
    for _ in 0..n {
        let b = common::mutate(&mut rng, &w.bytes, interesting);
        match parse_xdf(&b, Path::new("m.xdf")) {
            Ok(_) => ok += 1,
            Err(_) => err += 1,
        }
        let _ = parse_xdf_file(&b, Path::new("m.xdf"));
    }
    eprintln!("{n} mutations: {ok} read, {err} refused");
}

// ---------------------------------------------------------------------------------------------
// The Python-written fixture
// ---------------------------------------------------------------------------------------------

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn python_written_fixture() {
    let g = golden("xdf/python_small.json");
    let path = fixture("xdf/python_small.xdf");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len() as u64, g["file_len"].as_u64().unwrap());
    let f = read_xdf_file(&path).unwrap();
    assert_eq!(f.version.as_deref(), Some("1.0"));
    assert!(!f.truncated);
    assert_eq!(f.n_chunks, g["chunks"].as_array().unwrap().len());
    assert_eq!(f.n_boundaries as u64, g["n_boundaries"].as_u64().unwrap());
    assert_eq!(
        f.n_unknown_chunks as u64,
        g["n_unknown_chunks"].as_u64().unwrap()
    );
    let gs = g["streams"].as_array().unwrap();
    assert_eq!(f.streams.len(), gs.len());
    for (s, e) in f.streams.iter().zip(gs) {
        let i = &s.info;
        assert_eq!(u64::from(i.id), e["id"].as_u64().unwrap());
        assert_eq!(i.name, e["name"].as_str().unwrap());
        assert_eq!(i.stream_type, e["type"].as_str().unwrap());
        assert_eq!(i.format.name(), e["format"].as_str().unwrap());
        assert_eq!(i.nominal_srate, e["nominal_srate"].as_f64().unwrap());
        assert_eq!(i.channel_count as u64, e["channel_count"].as_u64().unwrap());
        assert_eq!(i.n_samples as u64, e["n_samples"].as_u64().unwrap());
        assert_eq!(
            serde_json::to_value(&i.channel_labels).unwrap(),
            e["labels"]
        );
        assert_eq!(serde_json::to_value(&i.channel_units).unwrap(), e["units"]);
        let ts = f64s(&e["timestamps"]);
        assert_eq!(s.timestamps.len(), ts.len());
        for (a, b) in s.timestamps.iter().zip(&ts) {
            assert_eq!(a.to_bits(), b.to_bits(), "stream {} timestamps", i.id);
        }
        assert_eq!(
            i.footer.as_ref().unwrap().sample_count,
            Some(ts.len() as u64)
        );
        match &s.values {
            XdfValues::Numeric(a) => {
                for (c, row) in e["values"].as_array().unwrap().iter().enumerate() {
                    for (k, x) in f64s(row).iter().enumerate() {
                        assert_eq!(
                            a[[c, k]].to_bits(),
                            x.to_bits(),
                            "stream {} [{c}, {k}]",
                            i.id
                        );
                    }
                }
            }
            XdfValues::Strings(v) => {
                let want: Vec<Vec<String>> = serde_json::from_value(e["values"].clone()).unwrap();
                assert_eq!(v, &want);
            }
        }
    }
    let clock: Vec<(f64, f64)> = serde_json::from_value(g["clock_offsets"]["7"].clone()).unwrap();
    assert_eq!(f.stream(7).unwrap().info.clock_offsets, clock);

    // The recording.
    let rec = read(&path).unwrap();
    let eg = &g["eeg"];
    let info = rec.xdf().unwrap();
    assert_eq!(info.eeg_stream as u64, eg["stream_index"].as_u64().unwrap());
    assert_eq!(
        serde_json::to_value(rec.raw.ch_names()).unwrap(),
        eg["ch_names"]
    );
    assert_eq!(rec.raw.sfreq(), eg["sfreq"].as_f64().unwrap());
    assert_eq!(info.scale_to_uv, f64s(&eg["scale_to_uv"]));
    assert_eq!(info.eeg().source_id, eg["source_id"].as_str().unwrap());
    assert_eq!(info.eeg().created_at, eg["created_at"].as_f64());
    for (c, row) in eg["data_uv"].as_array().unwrap().iter().enumerate() {
        for (k, x) in f64s(row).iter().enumerate() {
            assert_eq!(
                rec.raw.data()[[c, k]].to_bits(),
                x.to_bits(),
                "µV [{c}, {k}]"
            );
        }
    }
    let gm = g["markers"].as_array().unwrap();
    assert_eq!(info.markers.len(), gm.len());
    for (m, e) in info.markers.iter().zip(gm) {
        assert_eq!(u64::from(m.stream_id), e["stream_id"].as_u64().unwrap());
        assert_eq!(
            m.timestamp.to_bits(),
            e["timestamp"].as_f64().unwrap().to_bits()
        );
        assert_eq!(m.text, e["text"].as_str().unwrap());
        assert_eq!(u64::from(m.code), e["code"].as_u64().unwrap(), "{}", m.text);
        assert_eq!(m.target, e["target"].as_bool(), "{}", m.text);
        assert_eq!(
            m.sample.map(|s| s as u64),
            e["sample"].as_u64(),
            "{}",
            m.text
        );
    }
    let ge = g["events"].as_array().unwrap();
    let ev = rec.raw.events().as_slice();
    assert_eq!(ev.len(), ge.len());
    for (a, e) in ev.iter().zip(ge) {
        assert_eq!(a.onset as u64, e["onset"].as_u64().unwrap());
        assert_eq!(u64::from(a.code), e["code"].as_u64().unwrap());
        assert_eq!(a.target, e["target"].as_bool());
        assert_eq!(a.label.as_deref(), e["label"].as_str());
    }
}

#[test]
fn every_cut_of_the_python_fixture_keeps_its_complete_chunks() {
    let g = golden("xdf/python_small.json");
    let bytes = std::fs::read(fixture("xdf/python_small.xdf")).unwrap();
    let chunks = g["chunks"].as_array().unwrap();
    let ends: Vec<usize> = chunks
        .iter()
        .map(|c| c["end"].as_u64().unwrap() as usize)
        .collect();
    for cut in 4..=bytes.len() {
        let f = parse_xdf_file(&bytes[..cut], Path::new("cut.xdf"))
            .unwrap_or_else(|e| panic!("cut {cut}: {e}"));
        let complete = chunks
            .iter()
            .take_while(|c| c["end"].as_u64().unwrap() as usize <= cut);
        let mut want: BTreeMap<u64, usize> = BTreeMap::new();
        for c in complete {
            if let Some(id) = c["stream_id"].as_u64() {
                match c["tag"].as_u64().unwrap() {
                    2 => {
                        want.insert(id, 0);
                    }
                    3 => *want.get_mut(&id).unwrap() += c["n_samples"].as_u64().unwrap() as usize,
                    _ => {}
                }
            }
        }
        let got: BTreeMap<u64, usize> = f
            .streams
            .iter()
            .map(|s| (u64::from(s.info.id), s.timestamps.len()))
            .collect();
        assert_eq!(got, want, "cut {cut}");
        assert_eq!(f.truncated, !(cut == 4 || ends.contains(&cut)), "cut {cut}");
    }
}

// ---------------------------------------------------------------------------------------------
// pyxdf
// ---------------------------------------------------------------------------------------------

fn run_pyxdf(python: &std::ffi::OsStr, file: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/golden/xdf/pyxdf_read.py");
    let out = Command::new(python)
        .arg(&script)
        .arg(file)
        .arg("--full")
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "pyxdf_read.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON from pyxdf_read.py")
}

fn compare_with_pyxdf(ours: &XdfFile, py: &Value, what: &str) {
    let ps = py["streams"].as_array().unwrap();
    assert_eq!(ours.streams.len(), ps.len(), "{what}: streams");
    for (s, p) in ours.streams.iter().zip(ps) {
        let i = &s.info;
        let ctx = format!("{what}: stream {} ({})", i.id, i.name);
        assert_eq!(u64::from(i.id), p["stream_id"].as_u64().unwrap(), "{ctx}");
        assert_eq!(i.name, p["name"].as_str().unwrap(), "{ctx}");
        assert_eq!(i.stream_type, p["type"].as_str().unwrap(), "{ctx}");
        assert_eq!(
            i.channel_count as u64,
            p["channel_count"].as_u64().unwrap(),
            "{ctx}"
        );
        assert_eq!(
            i.nominal_srate,
            p["nominal_srate"].as_f64().unwrap(),
            "{ctx}"
        );
        assert_eq!(
            i.format.name(),
            p["channel_format"].as_str().unwrap(),
            "{ctx}"
        );
        assert_eq!(
            s.timestamps.len() as u64,
            p["n_samples"].as_u64().unwrap(),
            "{ctx}: samples"
        );
        assert_eq!(
            i.footer.as_ref().and_then(|f| f.sample_count),
            p["footer_sample_count"].as_u64(),
            "{ctx}"
        );
        let ts = f64s(&p["time_stamps"]);
        assert!(
            s.timestamps
                .iter()
                .zip(&ts)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{ctx}: timestamps"
        );
        match &s.values {
            XdfValues::Numeric(a) => {
                for (c, row) in p["values"].as_array().unwrap().iter().enumerate() {
                    let row = f64s(row);
                    assert!(
                        a.row(c)
                            .iter()
                            .zip(&row)
                            .all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{ctx}: channel {c}"
                    );
                }
            }
            XdfValues::Strings(v) => {
                let want: Vec<Vec<String>> = serde_json::from_value(p["values"].clone()).unwrap();
                assert_eq!(v, &want, "{ctx}");
            }
        }
    }
}

#[test]
fn pyxdf_reads_what_the_writer_writes() {
    let Some(python) = oddball_testkit::tool(
        "ODDBALL_PYXDF",
        "pyxdf_reads_what_the_writer_writes",
        "a python with pyxdf and numpy, see tools/golden/xdf/README.md",
    ) else {
        return;
    };
    let tmp = TempDir::new("xdf-pyxdf");
    let path = tmp.path().join("rust_written.xdf");
    let mut w = XdfWriter::create(&path).unwrap();
    let eeg = w
        .add_stream(&XdfStream::eeg("LiveAmp ü", labels(8), 500.0))
        .unwrap();
    let mut aux = XdfStream::eeg("Aux", labels(2), 100.0);
    aux.format = XdfFormat::Double64;
    aux.stream_type = "Misc".into();
    aux.unit = "degC".into();
    let aux = w.add_stream(&aux).unwrap();
    let mut trig = XdfStream::markers("Triggers");
    trig.format = XdfFormat::Int32;
    let trig = w.add_stream(&trig).unwrap();
    let mk = w.add_stream(&XdfStream::markers("Markers")).unwrap();
    let mut cut = None;
    // 12 s: 24 blocks of 0.5 s (a Boundary chunk after 10 s); block 13 holds only EEG.
    for b in 0..24usize {
        let before = w.bytes_written();
        let i0 = b * 250;
        let ts: Vec<f64> = (i0..i0 + 250)
            .map(|i| 70_000.0 + i as f64 / 500.0)
            .collect();
        let d = Array2::from_shape_fn((8, 250), |(c, i)| wiggle(i0 + i, c));
        w.push_numeric(eeg, &ts, d.view()).unwrap();
        if b != 13 {
            let ta: Vec<f64> = (b * 50..b * 50 + 50)
                .map(|i| 70_000.0 + i as f64 / 100.0)
                .collect();
            w.push_numeric(
                aux,
                &ta,
                Array2::from_shape_fn((2, 50), |(c, i)| wiggle(i, c + 9) * 1e-3).view(),
            )
            .unwrap();
            w.push_strings(
                mk,
                &[ts[17], ts[100]],
                &[&format!("flash {b}"), "Grüße 🎉 ✓"],
            )
            .unwrap();
            w.push_numeric(
                trig,
                &[ts[30]],
                Array2::from_elem((1, 1), b as f64 * 1000.0 - 7.0).view(),
            )
            .unwrap();
        }
        w.flush_block().unwrap();
        if b == 13 {
            cut = Some(before as usize + (w.bytes_written() - before) as usize / 2);
        }
    }
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let cut_path = tmp.path().join("rust_written_cut.xdf");
    std::fs::write(&cut_path, &bytes[..cut.unwrap()]).unwrap();

    let ours = read_xdf_file(&path).unwrap();
    assert_eq!(ours.n_boundaries, 1);
    compare_with_pyxdf(&ours, &run_pyxdf(&python, &path), "whole file");
    let ours_cut = read_xdf_file(&cut_path).unwrap();
    assert!(ours_cut.truncated);
    assert_eq!(ours_cut.stream(eeg).unwrap().timestamps.len(), 13 * 250);
    let py_cut = run_pyxdf(&python, &cut_path);
    compare_with_pyxdf(&ours_cut, &py_cut, "cut file");
    eprintln!(
        "pyxdf {} agrees on {} streams ({} EEG samples) and on the file cut at byte {} ({} EEG samples)",
        py_cut["pyxdf_version"],
        ours.streams.len(),
        ours.stream(eeg).unwrap().timestamps.len(),
        cut.unwrap(),
        ours_cut.stream(eeg).unwrap().timestamps.len()
    );
    // The fixture written by the independent Python writer reads the same in pyxdf.
    let fx = fixture("xdf/python_small.xdf");
    compare_with_pyxdf(
        &read_xdf_file(&fx).unwrap(),
        &run_pyxdf(&python, &fx),
        "python fixture",
    );
}
