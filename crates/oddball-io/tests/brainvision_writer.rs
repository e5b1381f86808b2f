//! The BrainVision writer: round trips through the reader (every sample the given value rounded
//! to f32, names with commas, every event code, the rate), what MNE 1.13.2 reads from a file it
//! wrote (`tools/golden/brainvision/check_writer.py`, `oddball_written.*`, with pybv 0.8.1's
//! header for the same data), and refusals (non-finite samples, names a header cannot carry).

mod common;

use common::{fixture, golden, TempDir};
use ndarray::Array2;
use oddball_io::brainvision::{BvBinaryFormat, BvOrientation};
use oddball_io::{read, write_brainvision, Details, Format, IoError};
use oddball_signal::{Event, Events, Raw};

/// The recording of the committed fixture `oddball_written.*`: 4 channels (one name with a
/// comma, one not ASCII) × 60 samples at 240 Hz (an interval of 4166.666666666667 µs), values
/// from 10⁻⁷ to 3·10⁵ µV, both signs, and events of codes 1, 12, 255, 1003 (a response) and 0.
fn fixture_raw() -> Raw {
    let names = ["Fp1", "Cz,ref", "µV-probe", "EOG"];
    let n = 60;
    let data = Array2::from_shape_fn((names.len(), n), |(c, t)| {
        let (c, tf) = (c as f64, t as f64);
        let x = 37.5 * (0.37 * tf + c).sin() * (1.0 + c) + 1e-3 * tf - 1.0 / 3.0;
        match (c as usize, t) {
            (0, 5) => 1e-7,
            (1, 6) => -3e5,
            (2, 7) => 0.1,
            (3, 8) => 0.0,
            _ => x,
        }
    });
    let events = Events::new(vec![
        Event::new(3, 1),
        Event::new(10, 12),
        Event::new(20, 255),
        Event::new(30, 1003),
        Event::new(59, 0),
    ]);
    Raw::new(
        data,
        240.0,
        names.iter().map(|s| s.to_string()).collect(),
        events,
    )
    .unwrap()
}

fn f32_rounded(x: f64) -> f64 {
    f64::from(x as f32)
}

#[test]
fn round_trip_through_the_reader() {
    let tmp = TempDir::new("bvw-round");
    let raw = fixture_raw();
    let path = tmp.path().join("run.vhdr");
    let s = write_brainvision(&path, &raw).unwrap();
    assert_eq!(s.vmrk, tmp.path().join("run.vmrk"));
    assert_eq!(s.eeg, tmp.path().join("run.eeg"));
    assert_eq!((s.n_channels, s.n_times, s.n_markers), (4, 60, 5));
    assert_eq!(std::fs::metadata(&s.eeg).unwrap().len(), 4 * 60 * 4);
    let back = read(&path).unwrap();
    assert_eq!(back.format, Format::BrainVision);
    assert_eq!(back.raw.ch_names(), raw.ch_names());
    assert_eq!(back.raw.sfreq(), 240.0, "the interval reads back as 240 Hz");
    let mut max_rounding = 0.0f64;
    for ((c, t), &x) in raw.data().indexed_iter() {
        let y = back.raw.data()[[c, t]];
        assert_eq!(y, f32_rounded(x), "[{c}, {t}]");
        assert!((y - x).abs() <= x.abs() * f64::from(f32::EPSILON) / 2.0);
        max_rounding = max_rounding.max((y - x).abs());
    }
    assert_eq!(s.max_rounding, max_rounding);
    let key =
        |r: &Raw| -> Vec<(usize, u32)> { r.events().iter().map(|e| (e.onset, e.code)).collect() };
    assert_eq!(key(&back.raw), key(&raw));
    let labels: Vec<&str> = back
        .raw
        .events()
        .iter()
        .map(|e| e.label.as_deref().unwrap())
        .collect();
    assert_eq!(
        labels,
        [
            "Stimulus/S  1",
            "Stimulus/S 12",
            "Stimulus/S255",
            "Response/R  3",
            "Stimulus/S  0"
        ]
    );
    let Details::BrainVision(info) = &back.details else {
        panic!("BrainVision details")
    };
    assert_eq!(info.binary_format, BvBinaryFormat::Float32);
    assert_eq!(info.orientation, BvOrientation::Multiplexed);
    assert!(info
        .channels
        .iter()
        .all(|c| c.resolution == 1.0 && c.unit == "µV"));
    assert_eq!(info.encoding, "UTF-8");

    // Codes a recording may carry beyond MNE's three digits still read back as themselves.
    let events = Events::new(vec![Event::new(0, 2000), Event::new(1, 70001)]);
    let big = Raw::new(Array2::zeros((1, 4)), 512.0, vec!["Pz".into()], events).unwrap();
    let p = tmp.path().join("big.vhdr");
    write_brainvision(&p, &big).unwrap();
    let back = read(&p).unwrap();
    let codes: Vec<u32> = back.raw.events().iter().map(|e| e.code).collect();
    assert_eq!(codes, [2000, 70001]);

    // Written again over itself: replaced, and a data file cut short is an error, never a
    // shorter recording (DataPoints is in the header).
    write_brainvision(&path, &raw).unwrap();
    let bytes = std::fs::read(&s.eeg).unwrap();
    std::fs::write(&s.eeg, &bytes[..bytes.len() - 16]).unwrap();
    let e = read(&path).unwrap_err();
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
}

/// The committed `oddball_written.*` is what the writer writes today (set
/// `ODDBALL_WRITE_FIXTURES=1` to write it again, then run `check_writer.py`).
#[test]
fn the_committed_fixture_is_what_the_writer_writes() {
    let raw = fixture_raw();
    let dir = fixture("brainvision");
    if std::env::var_os("ODDBALL_WRITE_FIXTURES").is_some() {
        write_brainvision(dir.join("oddball_written.vhdr"), &raw).unwrap();
    }
    let tmp = TempDir::new("bvw-fixture");
    write_brainvision(tmp.path().join("oddball_written.vhdr"), &raw).unwrap();
    for ext in ["vhdr", "vmrk", "eeg"] {
        let name = format!("oddball_written.{ext}");
        let ours = std::fs::read(tmp.path().join(&name)).unwrap();
        let committed = std::fs::read(dir.join(&name)).unwrap();
        assert!(ours == committed, "{name} differs from the committed one");
    }
}

/// MNE 1.13.2's reading of the fixture: the data rounded to f32 (to 10⁻⁶ µV, and relatively to
/// 10⁻¹² of the value: MNE scales float32 × 10⁻⁶ to volts, the script back to µV), the names,
/// the rate, the annotations and `events_from_annotations`; and pybv 0.8.1's files for the same
/// data: the same data bytes, and headers that differ only where expected.
#[test]
fn mne_reads_what_the_writer_writes() {
    let g = golden("brainvision/oddball_written.json");
    let raw = fixture_raw();
    let m = &g["mne"];
    let names: Vec<&str> = m["ch_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(raw.ch_names(), names);
    let sfreq = m["sfreq"].as_f64().unwrap();
    assert!((sfreq - 240.0).abs() <= 1e-12 * 240.0, "MNE's rate {sfreq}");
    let data = m["data"].as_array().unwrap();
    assert_eq!(data.len(), raw.n_channels());
    let mut worst = 0.0f64;
    for (c, row) in data.iter().enumerate() {
        let row = row.as_array().unwrap();
        assert_eq!(row.len(), raw.n_times());
        for (t, v) in row.iter().enumerate() {
            let (mne, ours) = (v.as_f64().unwrap(), f32_rounded(raw.data()[[c, t]]));
            let d = (mne - ours).abs();
            assert!(
                d <= 1e-6 && d <= 1e-12 * ours.abs().max(1e-6),
                "[{c}, {t}]: MNE {mne} vs f32 {ours}"
            );
            worst = worst.max(d);
        }
    }
    eprintln!("MNE vs oddball's f32: max |diff| {worst:.3e} µV");
    let ours = read(fixture("brainvision/oddball_written.vhdr")).unwrap();
    let ann: Vec<(u64, &str)> = m["annotations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            (
                a["sample"].as_u64().unwrap(),
                a["description"].as_str().unwrap(),
            )
        })
        .collect();
    let labels: Vec<(u64, &str)> = ours
        .raw
        .events()
        .iter()
        .map(|e| (e.onset as u64, e.label.as_deref().unwrap()))
        .collect();
    assert_eq!(ann, labels, "MNE's annotations are the reader's labels");
    let events: Vec<(u64, u64)> = m["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e[0].as_u64().unwrap(), e[1].as_u64().unwrap()))
        .collect();
    let given: Vec<(u64, u64)> = raw
        .events()
        .iter()
        .map(|e| (e.onset as u64, u64::from(e.code)))
        .collect();
    assert_eq!(events, given, "MNE's events_from_annotations are the codes");

    // pybv writing MNE's reading of the same file: byte for byte the same data, and a header and
    // marker file that differ only in what pybv leaves out or adds.
    let p = &g["pybv"];
    assert_eq!(p["data_bytes_equal"], true, "{p}");
    let strs = |v: &serde_json::Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(strs(&p["vhdr_only_ours"]), ["DataPoints=60"], "{p}");
    assert_eq!(strs(&p["vhdr_only_pybv"]), ["[Comment]"], "{p}");
    assert!(strs(&p["vmrk_only_ours"]).is_empty(), "{p}");
    assert!(strs(&p["vmrk_only_pybv"]).is_empty(), "{p}");
}

#[test]
fn refusals_name_the_fault_and_write_nothing() {
    let tmp = TempDir::new("bvw-refuse");
    let path = tmp.path().join("r.vhdr");
    let nothing_written = || {
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert!(left.is_empty(), "{left:?}");
    };
    let names = vec!["Cz".to_string(), "Pz".to_string()];
    for (bad, what) in [
        (f64::NAN, "not a finite number"),
        (f64::INFINITY, "not a finite number"),
        (1e39, "float32"),
    ] {
        let mut data = Array2::zeros((2, 20));
        data[[1, 7]] = bad;
        let raw = Raw::new(data, 10.0, names.clone(), Events::default()).unwrap();
        let e = write_brainvision(&path, &raw).unwrap_err();
        let text = e.to_string();
        assert!(
            matches!(
                e,
                IoError::UnwritableSample {
                    channel_index: 1,
                    sample: 7,
                    ..
                }
            ) && text.contains("\"Pz\"")
                && text.contains(what),
            "{text}"
        );
        nothing_written();
    }
    for name in ["a\\1b", " Cz", "Cz\n", "tab\there"] {
        let raw = Raw::new(
            Array2::zeros((1, 4)),
            10.0,
            vec![name.to_string()],
            Events::default(),
        )
        .unwrap();
        let e = write_brainvision(&path, &raw).unwrap_err();
        assert!(
            matches!(e, IoError::Unsupported { .. }) && e.to_string().contains("channel 0"),
            "{name:?}: {e}"
        );
        nothing_written();
    }
    let raw = Raw::new(
        Array2::zeros((1, 4)),
        10.0,
        vec!["Cz".into()],
        Events::default(),
    )
    .unwrap();
    for p in ["r.edf", "a,b.vhdr", ".vhdr"] {
        let e = write_brainvision(tmp.path().join(p), &raw).unwrap_err();
        assert!(matches!(e, IoError::Unsupported { .. }), "{p}: {e}");
    }
    nothing_written();
    let e = write_brainvision(tmp.path().join("no/such/dir/x.vhdr"), &raw).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
}
