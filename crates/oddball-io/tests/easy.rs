//! The NIC `.easy` reader and writer: the golden fixtures written by the independent Python script
//! (`tools/golden/io/make_easy_fixture.py`), write → read round trips (bit-exact for whole nV,
//! also as a proptest), the sampling rate from timestamps, the 10/11/13/14-cell layouts, errors
//! that name line and column, truncation at every byte, writer refusals, and mutated files.

mod common;

use std::path::{Path, PathBuf};

use common::{fixture, golden, Rng, TempDir};
use ndarray::Array2;
use oddball_io::easy::{estimate_sfreq, info_path_for, parse_easy, timestamp_ms};
use oddball_io::{
    read, read_easy, read_easy_with, write_easy, EasyInfoFile, EasyOptions, EasySfreqSource,
    EasyWriteOptions, Format, IoError, Recording,
};
use oddball_signal::{Event, Events, Raw};
use proptest::prelude::*;
use serde_json::Value;

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn u64s(v: &Value) -> Vec<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

fn strs(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect()
}

/// Everything the golden JSON says about one file, compared exactly.
fn check_golden(rec: &Recording, g: &Value) {
    let raw = &rec.raw;
    assert_eq!(rec.format, Format::Easy);
    assert_eq!(raw.ch_names(), strs(&g["ch_names"]).as_slice());
    assert_eq!(raw.sfreq(), g["sfreq"].as_f64().unwrap());
    assert_eq!(raw.n_times() as u64, g["n_times"].as_u64().unwrap());
    for (c, (row_uv, row_nv)) in g["data_uv"]
        .as_array()
        .unwrap()
        .iter()
        .zip(g["data_nv"].as_array().unwrap())
        .enumerate()
    {
        let (uv, nv) = (f64s(row_uv), f64s(row_nv));
        for t in 0..raw.n_times() {
            let x = raw.data()[[c, t]];
            assert_eq!(x, uv[t], "channel {c} sample {t}");
            assert_eq!((x * 1000.0).round(), nv[t], "channel {c} sample {t} in nV");
        }
    }
    let events: Vec<(u64, u64)> = raw
        .events()
        .iter()
        .map(|e| {
            assert_eq!((e.target, e.label.as_deref()), (None, None));
            (e.onset as u64, u64::from(e.code))
        })
        .collect();
    let want: Vec<(u64, u64)> = g["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e["onset"].as_u64().unwrap(), e["code"].as_u64().unwrap()))
        .collect();
    assert_eq!(events, want);

    let info = rec.easy().unwrap();
    assert_eq!(info.layout.n_eeg as u64, g["n_eeg"].as_u64().unwrap());
    assert_eq!(
        info.layout.n_columns() as u64,
        g["n_columns"].as_u64().unwrap()
    );
    assert_eq!(
        info.layout.accelerometer,
        g["accelerometer_present"].as_bool().unwrap()
    );
    assert_eq!(
        info.layout.add_sensor,
        g["add_sensor_present"].as_bool().unwrap()
    );
    let acc = info.accelerometer.as_ref().unwrap();
    for (k, row) in g["accelerometer"].as_array().unwrap().iter().enumerate() {
        assert_eq!(acc.row(k).to_vec(), f64s(row), "accelerometer {k}");
    }
    match g["add_sensor"].as_array() {
        Some(_) => assert_eq!(info.add_sensor.as_ref().unwrap(), &f64s(&g["add_sensor"])),
        None => assert!(info.add_sensor.is_none()),
    }
    let triggers: Vec<u64> = info.triggers.iter().map(|&c| u64::from(c)).collect();
    assert_eq!(triggers, u64s(&g["triggers"]));
    assert_eq!(info.timestamps_ms, u64s(&g["timestamps_ms"]));
    assert_eq!(info.device_class.as_deref(), g["device_class"].as_str());
    let entries: Vec<(String, String)> = g["info_entries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|kv| {
            let kv = strs(kv);
            (kv[0].clone(), kv[1].clone())
        })
        .collect();
    assert_eq!(info.info, entries);
    assert_eq!(info.estimated_sfreq, Some(raw.sfreq()));
}

#[test]
fn golden_file_with_info() {
    let g = &golden("nic_small.json")["with_info"];
    let rec = read(fixture("nic_small.easy")).unwrap();
    check_golden(&rec, g);
    let info = rec.easy().unwrap();
    assert_eq!(info.sfreq_source, EasySfreqSource::Info);
    assert_eq!(info.info_path.as_deref(), Some(&*fixture("nic_small.info")));
    assert_eq!(info.info_value("device   CLASS"), Some("STARSTIM"));
    assert_eq!(info.info_value("Device Mac"), Some("00:07:80:58:9C:1A"));
    assert_eq!(info.info_value("no such key"), None);
    // The lost-packet trigger 255 is in the column but gives no event by default.
    assert_eq!(info.triggers[20], 255);
    assert!(rec.raw.events().iter().all(|e| e.code != 255));
}

#[test]
fn golden_file_without_info() {
    let g = &golden("nic_small.json")["without_info"];
    let rec = read_easy(fixture("nic_small_noinfo.easy")).unwrap();
    check_golden(&rec, g);
    let info = rec.easy().unwrap();
    assert_eq!(info.sfreq_source, EasySfreqSource::Timestamps);
    assert_eq!(info.info_path, None);
    assert!(info.info.is_empty());
}

#[test]
fn options_change_events_info_and_rate() {
    let path = fixture("nic_small.easy");
    let o = EasyOptions {
        ignore_codes: vec![],
        target_codes: vec![1],
        nontarget_codes: vec![2, 3],
        ..Default::default()
    };
    let rec = read_easy_with(&path, &o).unwrap();
    let ev: Vec<_> = rec
        .raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target))
        .collect();
    assert_eq!(
        ev,
        vec![
            (3, 1, Some(true)),
            (10, 2, Some(false)),
            (15, 3, Some(false)),
            (16, 4, None),
            (20, 255, None),
            (25, 1, Some(true)),
            (30, 70_000, None),
            (39, 5, None),
        ]
    );

    // Without the .info: default names, layout from the device sizes, rate from timestamps.
    let o = EasyOptions {
        info: EasyInfoFile::Ignore,
        ..Default::default()
    };
    let rec = read_easy_with(&path, &o).unwrap();
    assert_eq!(rec.raw.ch_names()[0], "Ch1");
    assert_eq!(rec.raw.sfreq(), 500.0);
    let info = rec.easy().unwrap();
    assert_eq!(info.sfreq_source, EasySfreqSource::Timestamps);
    assert!(info.layout.accelerometer && !info.layout.add_sensor);
    assert_eq!(info.device_class, None);

    // An explicit rate wins over the .info; an explicit .info path is used, and its record
    // count (40) is checked against this file's 30 lines.
    let o = EasyOptions {
        sfreq: Some(250.0),
        info: EasyInfoFile::At(fixture("nic_small.info")),
        ..Default::default()
    };
    let e = read_easy_with(fixture("nic_small_noinfo.easy"), &o).unwrap_err();
    assert_eq!(pos(&e), ("nic_small_noinfo.easy".into(), 31, 1));
    assert!(e.to_string().contains("nic_small.info line 10"), "{e}");
    let o = EasyOptions {
        check_record_count: false,
        ..o
    };
    let rec = read_easy_with(fixture("nic_small_noinfo.easy"), &o).unwrap();
    assert_eq!(rec.raw.sfreq(), 250.0);
    assert_eq!(rec.raw.ch_names()[7], "PO8");
    assert_eq!(rec.easy().unwrap().sfreq_source, EasySfreqSource::Options);
    // 8 channels (from the .info) and 14 cells: accelerometer and AddSensor.
    assert!(rec.easy().unwrap().add_sensor.is_some());

    let o = EasyOptions {
        info: EasyInfoFile::At(fixture("missing.info")),
        ..Default::default()
    };
    let e = read_easy_with(&path, &o).unwrap_err();
    assert!(
        matches!(&e, IoError::NotFound { path } if path.ends_with("missing.info")),
        "{e}"
    );
}

/// (file name, line, column) of a line-and-column error.
fn pos(e: &IoError) -> (String, usize, usize) {
    match e {
        IoError::Csv {
            path, line, column, ..
        } => (
            path.file_name().unwrap().to_string_lossy().into_owned(),
            *line,
            *column,
        ),
        other => panic!("not a line/column error: {other}"),
    }
}

fn parse(text: &str, info: Option<&str>, o: &EasyOptions) -> Result<Recording, IoError> {
    parse_easy(
        text.as_bytes(),
        Path::new("t.easy"),
        info.map(|i| (i.as_bytes(), Path::new("t.info"))),
        o,
    )
}

/// `n` lines of `n_eeg` EEG values, `extra` other cells (accelerometer/AddSensor), a trigger and
/// a timestamp `1000 + step × i`.
fn table(n: usize, n_eeg: usize, extra: usize, step: u64) -> String {
    (0..n)
        .map(|i| {
            let mut cells: Vec<String> = (0..n_eeg).map(|c| (i * 10 + c).to_string()).collect();
            cells.extend((0..extra).map(|k| format!("-{}", 100 + k)));
            cells.push(if i == 1 { "3".into() } else { "0".into() });
            cells.push((1000 + step * i as u64).to_string());
            cells.join("\t") + "\n"
        })
        .collect()
}

#[test]
fn truncation_at_every_byte() {
    let easy = std::fs::read(fixture("nic_small.easy")).unwrap();
    let info = std::fs::read(fixture("nic_small.info")).unwrap();
    let path = Path::new("nic_small.easy");
    let info_arg = Some((info.as_slice(), Path::new("nic_small.info")));
    let full = parse_easy(&easy, path, info_arg, &EasyOptions::default()).unwrap();
    let lax = EasyOptions {
        check_record_count: false,
        require_final_newline: false,
        ..Default::default()
    };
    let no_count = EasyOptions {
        check_record_count: false,
        ..Default::default()
    };
    for cut in 0..easy.len() {
        let b = &easy[..cut];
        let complete = b.iter().filter(|&&c| c == b'\n').count();
        let e = parse_easy(b, path, info_arg, &EasyOptions::default())
            .expect_err(&format!("cut at {cut}"));
        let (_, line, _) = pos(&e);
        if b.is_empty() {
            assert_eq!(line, 1, "cut at {cut}: {e}");
        } else if b.ends_with(b"\n") {
            // Cut at a line end: only the .info's record count tells.
            assert_eq!(line, complete + 1, "cut at {cut}: {e}");
            assert!(e.to_string().contains("Number of records of EEG"), "{e}");
            let r = parse_easy(b, path, info_arg, &no_count).unwrap();
            assert_eq!(r.raw.n_times(), complete);
            assert_eq!(
                r.raw.data().view(),
                full.raw.data().slice(ndarray::s![.., ..complete])
            );
        } else {
            // Cut inside a line: that line is named, never dropped.
            assert_eq!(line, complete + 1, "cut at {cut}: {e}");
            assert!(e.to_string().contains("line end"), "{e}");
            // Without the final-newline rule the cut line is read (a shorter number) or is an
            // error naming it; it is never silently left out.
            match parse_easy(b, path, info_arg, &lax) {
                Ok(r) => assert_eq!(r.raw.n_times(), complete + 1, "cut at {cut}"),
                Err(e) => assert_eq!(pos(&e).1, complete + 1, "cut at {cut}: {e}"),
            }
        }
    }
}

fn whole_nv_raw(n_ch: usize, n: usize, sfreq: f64, seed: u64) -> Raw {
    let mut s = seed;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let data = Array2::from_shape_fn((n_ch, n), |_| {
        let k = (next() % 4_000_001) as i64 - 2_000_000; // ±2 mV in nV
        k as f64 / 1000.0
    });
    let names = ["Fz", "Cz", "Pz", "Oz", "P3", "P4", "PO7", "PO8", "C3", "C4"];
    let events = Events::new(vec![
        Event::new(2, 1),
        Event::new(5, 2).with_target(true),
        Event::new(9, 70_000),
        Event::new(n - 1, 3),
    ]);
    Raw::new(
        data,
        sfreq,
        names[..n_ch].iter().map(|s| s.to_string()).collect(),
        events,
    )
    .unwrap()
}

#[test]
fn write_read_round_trip_is_bit_exact_for_whole_nanovolts() {
    let tmp = TempDir::new("easy-rt");
    for (n_ch, n, sfreq) in [(8, 500, 500.0), (3, 77, 256.0), (10, 40, 333.25)] {
        let raw = whole_nv_raw(n_ch, n, sfreq, 42 + n as u64);
        let path = tmp.path().join(format!("rt{n_ch}.easy"));
        let o = EasyWriteOptions {
            start_ms: 1_700_000_000_123,
            ..Default::default()
        };
        let s = write_easy(&path, &raw, &o).unwrap();
        assert_eq!((s.n_samples, s.n_channels), (n, n_ch));
        assert_eq!(s.max_rounding_uv, 0.0);
        assert_eq!((s.n_triggers, s.events_lost), (4, 0));
        assert_eq!(s.info_path, info_path_for(&path));
        assert_eq!(s.bytes, std::fs::metadata(&path).unwrap().len());

        let back = read(&path).unwrap();
        assert_eq!(back.format, Format::Easy);
        assert_eq!(back.raw.data(), raw.data());
        assert_eq!(back.raw.ch_names(), raw.ch_names());
        assert_eq!(back.raw.sfreq().to_bits(), sfreq.to_bits());
        let want: Vec<_> = raw
            .events()
            .iter()
            .map(|e| Event::new(e.onset, e.code))
            .collect();
        assert_eq!(back.raw.events().as_slice(), want.as_slice());
        let info = back.easy().unwrap();
        assert_eq!(info.sfreq_source, EasySfreqSource::Info);
        assert_eq!(info.device_class.as_deref(), Some("STARSTIM"));
        assert_eq!(info.layout.n_columns(), n_ch + 2);
        assert!(info.accelerometer.is_none() && info.add_sensor.is_none());
        let ts: Vec<u64> = (0..n).map(|i| timestamp_ms(o.start_ms, i, sfreq)).collect();
        assert_eq!(info.timestamps_ms, ts);
        assert_eq!(info.timestamps_ms[0], o.start_ms);
        assert_eq!(info.info_value("Accelerometer data"), Some("OFF"));
        assert_eq!(info.info_value("EEG units"), Some("nV"));
        assert_eq!(
            info.info_value("Channel 2"),
            Some(raw.ch_names()[1].as_str())
        );
        assert_eq!(
            info.info_value("StartDate (firstEEGtimestamp)"),
            Some("1700000000123")
        );
    }
    // Only the written files are left: no temporary files.
    let mut names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "rt10.easy",
            "rt10.info",
            "rt3.easy",
            "rt3.info",
            "rt8.easy",
            "rt8.info"
        ]
    );
}

#[test]
fn timestamps_are_rounded_from_the_sample_index() {
    assert_eq!(timestamp_ms(10, 0, 500.0), 10);
    assert_eq!(timestamp_ms(10, 3, 500.0), 16);
    // 256 Hz: 3.90625 ms per sample, rounded to the nearest ms each time.
    let t: Vec<u64> = (0..6).map(|i| timestamp_ms(0, i, 256.0)).collect();
    assert_eq!(t, vec![0, 4, 8, 12, 16, 20]);
    assert_eq!(timestamp_ms(0, 128, 256.0), 500);
    // Halves away from zero: 2 samples at 4000 Hz = 0.5 ms.
    assert_eq!(timestamp_ms(0, 2, 4000.0), 1);
    // The writer's timestamps give back the rate.
    let t: Vec<u64> = (0..1000).map(|i| timestamp_ms(0, i, 256.0)).collect();
    assert_eq!(estimate_sfreq(&t).map(f64::round), Some(256.0));
}

#[test]
fn rounding_to_nanovolts_is_reported() {
    let data = Array2::from_shape_vec(
        (2, 4),
        vec![
            0.0004, 0.0005, -0.0005, 1.2344999, 3.1234567, -2.7654321, 1e-9, 0.0,
        ],
    )
    .unwrap();
    let raw = Raw::new(data, 500.0, vec!["A".into(), "B".into()], Events::default()).unwrap();
    let tmp = TempDir::new("easy-round");
    let path = tmp.path().join("r.easy");
    let s = write_easy(&path, &raw, &EasyWriteOptions::default()).unwrap();
    let back = read(&path).unwrap();
    let mut worst = 0.0f64;
    for ((c, t), &x) in raw.data().indexed_iter() {
        let y = back.raw.data()[[c, t]];
        assert_eq!(y, (x * 1000.0).round() / 1000.0, "channel {c} sample {t}");
        worst = worst.max((y - x).abs());
    }
    assert_eq!(s.max_rounding_uv, worst);
    assert!(worst > 0.0004 && worst <= 0.0005 + 1e-12, "{worst}");
    // Halves away from zero.
    assert_eq!(back.raw.data()[[0, 1]], 0.001);
    assert_eq!(back.raw.data()[[0, 2]], -0.001);
}

#[test]
fn events_the_file_cannot_hold_are_counted() {
    let data = Array2::zeros((1, 10));
    let events = Events::new(vec![
        Event::new(1, 4),
        Event::new(1, 5),   // same sample: the later one is written
        Event::new(2, 5),   // same code on the sample before: read back as one
        Event::new(4, 0),   // code 0 marks nothing
        Event::new(6, 255), // NIC's lost-packet flag: skipped by the reader
        Event::new(8, 9),
    ]);
    let raw = Raw::new(data, 100.0, vec!["Cz".into()], events).unwrap();
    let tmp = TempDir::new("easy-events");
    let path = tmp.path().join("e.easy");
    let s = write_easy(&path, &raw, &EasyWriteOptions::default()).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(
        back.easy().unwrap().triggers,
        [0, 5, 5, 0, 0, 0, 255, 0, 9, 0]
    );
    let ev: Vec<_> = back
        .raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code))
        .collect();
    assert_eq!(ev, vec![(1, 5), (8, 9)]);
    assert_eq!(s.n_triggers, 4);
    assert_eq!(s.events_lost, 4);
}

fn arb_raw() -> impl Strategy<Value = Raw> {
    (
        1usize..7,
        1usize..60,
        prop::sample::select(vec![125.0, 250.0, 256.0, 500.0, 1000.0, 333.25, 2048.0]),
    )
        .prop_flat_map(|(n_ch, n, sfreq)| {
            (
                prop::collection::vec(-i32::MAX..=i32::MAX, n_ch * n),
                prop::collection::vec((0..n, 1u32..400), 0..8),
                Just((n_ch, n, sfreq)),
            )
        })
        .prop_map(|(nv, events, (n_ch, n, sfreq))| {
            let data = Array2::from_shape_vec(
                (n_ch, n),
                nv.iter().map(|&k| f64::from(k) / 1000.0).collect(),
            )
            .unwrap();
            let names = (0..n_ch).map(|c| format!("E {c}")).collect();
            let events = events.into_iter().map(|(t, c)| Event::new(t, c)).collect();
            Raw::new(data, sfreq, names, events).unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_recordings_round_trip(raw in arb_raw(), start in 0u64..2_000_000_000_000) {
        let tmp = TempDir::new("easy-prop");
        let path = tmp.path().join("p.easy");
        let o = EasyWriteOptions { start_ms: start, device_class: "ENOBIO".into(), ..Default::default() };
        let s = write_easy(&path, &raw, &o).unwrap();
        prop_assert_eq!(s.max_rounding_uv, 0.0);
        let back = read(&path).unwrap();
        prop_assert_eq!(back.raw.data(), raw.data());
        prop_assert_eq!(back.raw.ch_names(), raw.ch_names());
        prop_assert_eq!(back.raw.sfreq().to_bits(), raw.sfreq().to_bits());
        // Expected events: the written trigger column read by the rule in the module doc.
        let mut trig = vec![0u32; raw.n_times()];
        for e in raw.events() {
            trig[e.onset] = e.code;
        }
        let want: Vec<Event> = (0..trig.len())
            .filter(|&t| trig[t] != 0 && trig[t] != 255 && (t == 0 || trig[t - 1] != trig[t]))
            .map(|t| Event::new(t, trig[t]))
            .collect();
        prop_assert_eq!(back.raw.events().as_slice(), want.as_slice());
        prop_assert_eq!(s.events_lost, raw.events().len() - want.len());
        let info = back.easy().unwrap();
        prop_assert_eq!(&info.triggers, &trig);
        prop_assert_eq!(info.timestamps_ms[0], start);
        prop_assert_eq!(info.device_class.as_deref(), Some("ENOBIO"));
    }
}

#[test]
fn rate_from_timestamps_without_info() {
    let o = EasyOptions::default();
    let r = parse(&table(20, 8, 0, 4), None, &o).unwrap();
    assert_eq!(r.raw.sfreq(), 250.0);
    let info = r.easy().unwrap();
    assert_eq!(info.sfreq_source, EasySfreqSource::Timestamps);
    assert_eq!(info.estimated_sfreq, Some(250.0));

    // A gap of lost packets does not change the rate; jittery 1-ms timestamps average out.
    let mut text = String::new();
    for (i, t) in [0u64, 2, 4, 6, 16, 18, 20, 22].iter().enumerate() {
        text += &format!("{}\t1\t2\t3\t4\t5\t6\t7\t0\t{}\n", i, 5000 + t);
    }
    assert_eq!(parse(&text, None, &o).unwrap().raw.sfreq(), 500.0);
    let text: String = (0..200)
        .map(|i| {
            format!(
                "1\t2\t3\t4\t5\t6\t7\t8\t0\t{}\n",
                (i as f64 * 1000.0 / 256.0).round()
            )
        })
        .collect();
    assert_eq!(parse(&text, None, &o).unwrap().raw.sfreq(), 256.0);

    // Refused: one sample, time standing still or going back (named by line and column).
    let e = parse(&table(1, 8, 0, 4), None, &o).unwrap_err();
    assert_eq!(pos(&e), ("t.easy".into(), 1, 10));
    assert!(e.to_string().contains("at least two samples"), "{e}");
    let mut lines: Vec<String> = table(6, 8, 0, 2).lines().map(String::from).collect();
    lines[3] = lines[3].replace("\t1006", "\t1004");
    let text = lines.join("\n") + "\n";
    let e = parse(&text, None, &o).unwrap_err();
    assert_eq!(pos(&e), ("t.easy".into(), 4, 10));
    assert!(
        e.to_string().contains("after the previous line's 1004"),
        "{e}"
    );
    let e = parse(&table(5, 8, 0, 0), None, &o).unwrap_err();
    assert_eq!(pos(&e), ("t.easy".into(), 2, 10));
    // With a rate from the options or a .info, such timestamps are only kept.
    let with_rate = EasyOptions {
        sfreq: Some(100.0),
        ..Default::default()
    };
    let r = parse(&text, None, &with_rate).unwrap();
    assert_eq!(r.easy().unwrap().estimated_sfreq, None);
    assert_eq!(r.easy().unwrap().timestamps_ms[3], 1004);
    let r = parse(&text, Some("EEG sampling rate: 125.5 Hz\n"), &o).unwrap();
    assert_eq!(r.raw.sfreq(), 125.5);
}

#[test]
fn layouts_with_accelerometer_and_add_sensor() {
    let o = EasyOptions::default();
    for (n_eeg, extra, acc, add) in [
        (8, 0, false, false),
        (8, 1, false, true),
        (8, 3, true, false),
        (8, 4, true, true),
        (20, 0, false, false),
        (20, 4, true, true),
        (32, 3, true, false),
        (32, 1, false, true),
    ] {
        let r = parse(&table(4, n_eeg, extra, 2), None, &o).unwrap();
        let info = r.easy().unwrap();
        let what = format!("{n_eeg} EEG + {extra}");
        assert_eq!(r.raw.n_channels(), n_eeg, "{what}");
        assert_eq!(r.raw.ch_names()[n_eeg - 1], format!("Ch{n_eeg}"), "{what}");
        assert_eq!(
            (info.layout.accelerometer, info.layout.add_sensor),
            (acc, add)
        );
        assert_eq!(
            r.raw.data()[[n_eeg - 1, 3]],
            (30 + n_eeg - 1) as f64 / 1000.0
        );
        assert_eq!(info.accelerometer.is_some(), acc);
        if let Some(a) = &info.accelerometer {
            assert_eq!(a.dim(), (3, 4));
            assert_eq!(a.column(2).to_vec(), vec![-100.0, -101.0, -102.0]);
        }
        if let Some(s) = &info.add_sensor {
            assert_eq!(s, &vec![if acc { -103.0 } else { -100.0 }; 4]);
        }
        assert_eq!(info.triggers, [0, 3, 0, 0]);
        assert_eq!(r.raw.events().as_slice(), &[Event::new(1, 3)]);
    }

    // 4 EEG channels + accelerometer = 9 cells: no device layout, so the .info or the options
    // decide.
    let text = table(3, 4, 3, 2);
    let e = parse(&text, None, &o).unwrap_err();
    assert_eq!(pos(&e), ("t.easy".into(), 1, 1));
    assert!(e.to_string().contains("EasyOptions::n_channels"), "{e}");
    let r = parse(&text, Some("Accelerometer data: ON\n"), &o).unwrap();
    assert_eq!(r.raw.n_channels(), 4);
    assert!(r.easy().unwrap().layout.accelerometer);
    let r = parse(&text, Some("accelerometer DATA:off\n"), &o).unwrap();
    assert_eq!(r.raw.n_channels(), 7);
    let r = parse(
        &table(3, 4, 4, 2),
        Some("Accelerometer data: ON\nAdditional channel status: ON\n"),
        &o,
    )
    .unwrap();
    assert_eq!(r.raw.n_channels(), 4);
    assert!(r.easy().unwrap().layout.add_sensor);
    let n4 = EasyOptions {
        n_channels: Some(4),
        ..Default::default()
    };
    let r = parse(&text, None, &n4).unwrap();
    assert!(r.easy().unwrap().layout.accelerometer);
    // The .info's channel count beats the device sizes; a count that does not fit is an error
    // that names the .info line.
    let info = "Number of EEG channels: 6\nTotal number of channels: 4\n";
    assert_eq!(parse(&text, Some(info), &o).unwrap().raw.n_channels(), 4);
    let e = parse(
        &table(3, 20, 0, 2),
        Some("Total number of channels: 8\n"),
        &o,
    )
    .unwrap_err();
    assert_eq!(pos(&e), ("t.easy".into(), 1, 1));
    assert!(e.to_string().contains("t.info line 1"), "{e}");
    assert!(e.to_string().contains("22 cells"), "{e}");
}

#[test]
fn info_files_are_read_tolerantly() {
    let text = table(3, 8, 0, 2);
    let info = "\u{feff}Step Details\r\n  DEVICE   class :  Enobio  \r\n\
        EEG Settings\r\nTotal number of channels: 8\r\n\
        EEG sampling rate: 500.000000 Samples/second\r\n\
        Channel 1:\r\n Position: C3\r\n Type: EEG Recording\r\n\
        channel 2: position: C4\r\n\tChannel 3: Pz\r\nChannel 4: \r\n\
        Channel 5: Left mastoid\r\nSome line without colon\r\n";
    let info = [info.as_bytes(), b"Latin-1 note: caf\xe9\r\n"].concat();
    let r = parse_easy(
        text.as_bytes(),
        Path::new("t.easy"),
        Some((&info, Path::new("t.info"))),
        &EasyOptions::default(),
    )
    .unwrap();
    assert_eq!(
        r.raw.ch_names(),
        ["C3", "C4", "Pz", "Ch4", "Left mastoid", "Ch6", "Ch7", "Ch8"]
    );
    assert_eq!(r.raw.sfreq(), 500.0);
    let e = r.easy().unwrap();
    assert_eq!(e.device_class.as_deref(), Some("Enobio"));
    assert_eq!(e.info_value("device class"), Some("Enobio"));
    assert_eq!(e.info_value("Latin-1 note"), Some("caf\u{fffd}"));
    assert!(!e.info.iter().any(|(k, _)| k.contains("without colon")));

    // EEG units change the factor.
    let r = parse(&text, Some("EEG units: uV\n"), &EasyOptions::default()).unwrap();
    assert_eq!(r.raw.data()[[1, 2]], 21.0);
    let r = parse(&text, Some("EEG units: mV\n"), &EasyOptions::default()).unwrap();
    assert_eq!(r.raw.data()[[1, 2]], 21_000.0);
    let o = EasyOptions {
        scale_to_uv: Some(2.0),
        ..Default::default()
    };
    assert_eq!(
        parse(&text, Some("EEG units: mV\n"), &o)
            .unwrap()
            .raw
            .data()[[1, 2]],
        42.0
    );
}

/// Line and column of the error `text` (with `info`, default options) gives, and a check that the
/// message names the file, the line and the column.
fn err_at(text: &str, info: Option<&str>) -> (String, usize, usize) {
    let e = parse(text, info, &EasyOptions::default()).unwrap_err();
    let p = pos(&e);
    let msg = e.to_string();
    assert!(msg.contains(&p.0), "{msg}");
    assert!(
        msg.contains(&format!("line {}, column {}", p.1, p.2)),
        "{msg}"
    );
    p
}

#[test]
fn errors_name_line_and_column() {
    let good = table(4, 8, 0, 2);
    let lines: Vec<&str> = good.lines().collect();
    // Line 3 with cell `col` (1-based) replaced.
    let with = |col: usize, cell: &str| {
        let mut cells: Vec<&str> = lines[2].split('\t').collect();
        cells[col - 1] = cell;
        let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
        l[2] = cells.join("\t");
        l.join("\n") + "\n"
    };
    let at = |line, col| ("t.easy".to_string(), line, col);
    for (col, cell, what) in [
        (3, "x", "a finite number"),
        (3, "", "a finite number"),
        (5, "inf", "a finite number"),
        (5, "NaN", "a finite number"),
        (1, "2147483648", "int32 range"),
        (2, "-2147483648", "int32 range"),
        (1, "1e300", "int32 range"),
        (9, "-1", "integer trigger"),
        (9, "1.5", "integer trigger"),
        (9, "4294967296", "integer trigger"),
        (9, "two", "integer trigger"),
        (10, "-5", "Unix time"),
        (10, "9007199254740993", "Unix time"),
        (10, "12:00", "Unix time"),
    ] {
        let text = with(col, cell);
        assert_eq!(err_at(&text, None), at(3, col), "{cell:?}");
        let e = parse(&text, None, &EasyOptions::default()).unwrap_err();
        assert!(e.to_string().contains(what), "{cell:?}: {e}");
    }
    // The cell names its column: EEG channel (with the .info name), trigger, timestamp.
    let e = parse(
        &with(2, "?"),
        Some("Channel 2: Cz\n"),
        &EasyOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("EEG channel 2 (Cz)"), "{e}");
    // Accepted: integers written as floats, spaces around cells, a trailing TAB, CRLF.
    let ok = with(9, " 7.0 ").replace('\n', "\t\r\n");
    let r = parse(&ok, None, &EasyOptions::default()).unwrap();
    assert_eq!(r.easy().unwrap().triggers[2], 7);

    // Too many and too few cells compared with the first line.
    let text = good.replacen("\t1004\n", "\t1004\t5\n", 1);
    assert_eq!(err_at(&text, None), at(3, 11));
    let text = good.replacen("\t0\t1004\n", "\n", 1);
    assert_eq!(err_at(&text, None), at(3, 9));
    let e = parse(&text, None, &EasyOptions::default()).unwrap_err();
    assert!(e.to_string().contains("too short"), "{e}");
    // A first line that fits no layout.
    assert_eq!(err_at("1\t2\t3\t4\n", None), at(1, 1));
    // Invalid UTF-8 (in cell 2).
    let e = parse_easy(
        b"1\t2\t3\t4\t5\t6\t7\t8\t0\t1000\n1\t2\xff\n",
        Path::new("t.easy"),
        None,
        &EasyOptions::default(),
    )
    .unwrap_err();
    assert_eq!(pos(&e), at(2, 2));
    // Empty and blank files.
    assert_eq!(err_at("", None), at(1, 1));
    let e = parse("\n \r\n\t\n", None, &EasyOptions::default()).unwrap_err();
    assert_eq!(pos(&e), at(1, 1));
    assert!(e.to_string().contains("only blank lines"), "{e}");
    // Blank lines are skipped (and counted in line numbers).
    let text = format!("\n{}", with(1, "x"));
    assert_eq!(err_at(&text, None), at(4, 1));
    // The last line without a line end.
    let cut = good.trim_end_matches('\n');
    assert_eq!(err_at(cut, None), at(4, 10));
    // The .info's record count.
    assert_eq!(
        err_at(&good, Some("Number of records of EEG: 5\n")),
        at(5, 1)
    );

    // .info errors name the .info file.
    let info_at = |line, col| ("t.info".to_string(), line, col);
    assert_eq!(
        err_at(
            &good,
            Some("Device class: X\nEEG sampling rate: 0 Samples/second\n")
        ),
        info_at(2, 20)
    );
    assert_eq!(
        err_at(&good, Some("EEG sampling rate: 2e6 Hz\n")),
        info_at(1, 20)
    );
    assert_eq!(
        err_at(&good, Some("Total number of channels: 8x\n")),
        info_at(1, 27)
    );
    assert_eq!(err_at(&good, Some("EEG units: furlongs\n")), info_at(1, 12));
    assert_eq!(err_at(&good, Some("x\nChannel 9: Oz\n")), info_at(2, 1));
    assert_eq!(
        err_at(&good, Some("Number of records of EEG: 4.5\n")),
        info_at(1, 27)
    );

    // Options that cannot be used.
    for o in [
        EasyOptions {
            sfreq: Some(0.0),
            ..Default::default()
        },
        EasyOptions {
            n_channels: Some(0),
            ..Default::default()
        },
        EasyOptions {
            scale_to_uv: Some(f64::NAN),
            ..Default::default()
        },
    ] {
        let e = parse(&good, None, &o).unwrap_err();
        assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    }
}

#[test]
fn writer_refusals_name_channel_and_sample_and_leave_no_file() {
    let tmp = TempDir::new("easy-refuse");
    let path = tmp.path().join("w.easy");
    let o = EasyWriteOptions::default();
    let raw = |x: f64, name: &str| {
        let mut data = Array2::zeros((3, 10));
        data[[2, 7]] = x;
        Raw::new(
            data,
            500.0,
            vec!["Fz".into(), name.into(), "Pz".into()],
            Events::default(),
        )
        .unwrap()
    };
    for (x, reason) in [
        (f64::NAN, "not a finite number"),
        (f64::INFINITY, "not a finite number"),
        (2_147_483.647_5, "int32"),
        (-2_147_483.648, "int32"),
    ] {
        let e = write_easy(&path, &raw(x, "Cz"), &o).unwrap_err();
        match &e {
            IoError::UnwritableSample {
                channel,
                channel_index,
                sample,
                reason: r,
                ..
            } => {
                assert_eq!((channel.as_str(), *channel_index, *sample), ("Pz", 2, 7));
                assert!(r.contains(reason), "{e}");
            }
            other => panic!("{other}"),
        }
    }
    // The extremes of the int32 range are written and read back.
    write_easy(&path, &raw(-2_147_483.647, "Cz"), &o).unwrap();
    assert_eq!(read(&path).unwrap().raw.data()[[2, 7]], -2_147_483.647);
    std::fs::remove_file(&path).unwrap();
    std::fs::remove_file(info_path_for(&path)).unwrap();

    for name in ["", " Cz", "C\tz", "C\nz"] {
        let e = write_easy(&path, &raw(0.0, name), &o).unwrap_err();
        assert!(matches!(e, IoError::Unsupported { .. }), "{name:?}: {e}");
        assert!(e.to_string().contains("channel 1"), "{e}");
    }
    let bad_class = EasyWriteOptions {
        device_class: "STAR\nSTIM".into(),
        ..Default::default()
    };
    assert!(write_easy(&path, &raw(0.0, "Cz"), &bad_class).is_err());
    let late = EasyWriteOptions {
        start_ms: (1 << 53) - 5,
        ..Default::default()
    };
    let e = write_easy(&path, &raw(0.0, "Cz"), &late).unwrap_err();
    assert!(e.to_string().contains("2^53"), "{e}");
    let e = write_easy(tmp.path().join("w.info"), &raw(0.0, "Cz"), &o).unwrap_err();
    assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    let empty = Raw::new(
        Array2::zeros((2, 0)),
        500.0,
        vec!["a".into(), "b".into()],
        Events::default(),
    )
    .unwrap();
    assert!(write_easy(&path, &empty, &o).is_err());
    let e = write_easy(tmp.path().join("no/such/dir/x.easy"), &raw(0.0, "Cz"), &o).unwrap_err();
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
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

fn mutate(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    const BITS: &[&[u8]] = &[
        b"0",
        b"255",
        b"99999999999",
        b"\t",
        b"\n",
        b"\r\n",
        b"-",
        b"1e308",
        b"nan",
        b"\xff",
        b":",
        b"Channel 99: X\n",
        b"Total number of channels: 3\n",
        b" ",
    ];
    common::mutate(rng, base, BITS)
}

#[test]
fn mutated_files_never_panic() {
    let easy = std::fs::read(fixture("nic_small.easy")).unwrap();
    let info = std::fs::read(fixture("nic_small.info")).unwrap();
    let noinfo = std::fs::read(fixture("nic_small_noinfo.easy")).unwrap();
    let n: usize = std::env::var("ODDBALL_FUZZ_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000);
    let mut rng = Rng(0x5EED_E457);
    let (pe, pi) = (Path::new("m.easy"), Path::new("m.info"));
    let o = EasyOptions::default();
    let (mut ok, mut err) = (0, 0);
    for _ in 0..n {
        let results = [
            parse_easy(&mutate(&mut rng, &easy), pe, Some((&info, pi)), &o),
            parse_easy(&easy, pe, Some((&mutate(&mut rng, &info), pi)), &o),
            parse_easy(&mutate(&mut rng, &noinfo), pe, None, &o),
        ];
        for r in results {
            match r {
                Ok(rec) => {
                    ok += 1;
                    assert!(rec.raw.data().iter().all(|x| x.is_finite()));
                }
                Err(e) => {
                    err += 1;
                    assert!(!e.to_string().is_empty());
                }
            }
        }
    }
    assert!(ok > 0 && err > 0, "{ok} read, {err} refused");
}

#[test]
fn read_dispatches_easy_files() {
    let tmp = TempDir::new("easy-dispatch");
    let p: PathBuf = tmp.write("X.EASY", &std::fs::read(fixture("nic_small.easy")).unwrap());
    tmp.write("X.info", &std::fs::read(fixture("nic_small.info")).unwrap());
    let rec = read(&p).unwrap();
    assert_eq!(rec.format, Format::Easy);
    assert_eq!(rec.raw.ch_names()[0], "Fz");
    assert!(rec.csv().is_none() && rec.bci2000().is_none() && rec.edf().is_none());
    let e = read(tmp.path().join("missing.easy")).unwrap_err();
    assert!(matches!(e, IoError::NotFound { .. }), "{e}");
}

#[test]
fn held_changed_and_ignored_triggers() {
    let trig = [5u32, 5, 255, 5, 0, 3, 4, 4, 0, 255, 255, 6];
    let text: String = trig
        .iter()
        .enumerate()
        .map(|(i, c)| format!("1\t2\t3\t4\t5\t6\t7\t8\t{c}\t{}\n", 100 + 2 * i))
        .collect();
    let r = parse(&text, None, &EasyOptions::default()).unwrap();
    let ev: Vec<_> = r.raw.events().iter().map(|e| (e.onset, e.code)).collect();
    // 5 held over two samples is one event; 255 gives none but breaks the hold; 3 → 4 directly
    // is a new event.
    assert_eq!(ev, vec![(0, 5), (3, 5), (5, 3), (6, 4), (11, 6)]);
    assert_eq!(r.easy().unwrap().triggers, trig);
}
