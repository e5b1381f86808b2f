//! The FIF reader against MNE 1.13.2: files written by `Raw.save` (float32, short, int, double,
//! a crop with first_samp 128 with and without a measurement date, an acquisition skip, a split
//! recording) and what `mne.io.read_raw_fif` reads from them (`tools/golden/fif/make_golden.py`,
//! fixtures in `tests/fixtures/fif/`).

mod common;

use std::collections::BTreeMap;

use common::{fixture, golden};
use oddball_io::{read, FifDataType, Format};
use serde_json::Value;

const FIXTURES: [&str; 8] = [
    "float_raw",
    "short_raw",
    "int_raw",
    "double_raw",
    "cropped_raw",
    "nodate_raw",
    "skip_raw",
    "split_raw",
];

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

fn pairs(v: &Value) -> Vec<(usize, Value)> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| (p[0].as_u64().unwrap() as usize, p[1].clone()))
        .collect()
}

/// Reads one fixture and checks it against MNE's reading; returns the largest |µV difference|.
fn check(stem: &str) -> f64 {
    let gold = golden(&format!("fif/{stem}.json"));
    let rec = read(fixture(&format!("fif/{stem}.fif"))).unwrap();
    assert_eq!(rec.format, Format::Fif);
    let info = rec.fif().unwrap();
    let raw = &rec.raw;

    assert_eq!(raw.sfreq(), gold["sfreq"].as_f64().unwrap(), "{stem}");
    assert_eq!(raw.ch_names(), strings(&gold["eeg_names"]), "{stem}");
    let all: Vec<String> = info.channels.iter().map(|c| c.name.clone()).collect();
    assert_eq!(all, strings(&gold["ch_names"]), "{stem}");
    let kinds: Vec<String> = info.channels.iter().map(|c| c.kind_name()).collect();
    assert_eq!(kinds, strings(&gold["ch_types"]), "{stem}");
    for (c, cal) in info.channels.iter().zip(gold["cals"].as_array().unwrap()) {
        assert_eq!(
            c.range as f64 * c.cal as f64,
            cal.as_f64().unwrap(),
            "{stem}"
        );
    }
    assert_eq!(info.stim_channels, ["STI 014"], "{stem}");
    assert_eq!(info.dropped_channels, ["EOG1"], "{stem}");
    assert!(info.non_voltage_channels.is_empty(), "{stem}");
    assert_eq!(
        info.first_samp,
        gold["first_samp"].as_i64().unwrap(),
        "{stem}"
    );
    let n_times = gold["n_times"].as_u64().unwrap() as usize;
    assert_eq!(raw.n_times(), n_times, "{stem}");
    match gold["meas_date"].as_array() {
        None => assert_eq!(info.meas_date, None, "{stem}"),
        Some(d) => assert_eq!(
            info.meas_date,
            Some((d[0].as_i64().unwrap(), d[1].as_i64().unwrap())),
            "{stem}"
        ),
    }
    let data_type = match gold["orig_format"].as_str().unwrap() {
        "single" => FifDataType::Float,
        "double" => FifDataType::Double,
        "int" => FifDataType::Int,
        "short" => FifDataType::Short,
        other => panic!("{other}"),
    };
    assert_eq!(info.data_type, data_type, "{stem}");

    // Samples in µV.
    let mut max_diff = 0.0f64;
    let data = raw.data();
    for (c, row) in gold["eeg_uv"].as_array().unwrap().iter().enumerate() {
        let row = row.as_array().unwrap();
        assert_eq!(row.len(), n_times);
        for (t, v) in row.iter().enumerate() {
            let d = (data[[c, t]] - v.as_f64().unwrap()).abs();
            assert!(d <= 1e-6, "{stem} [{c}, {t}]: {} vs {v}", data[[c, t]]);
            max_diff = max_diff.max(d);
        }
    }

    // Skips.
    let skips: Vec<(usize, usize)> = info.skips.iter().map(|s| (s.start, s.len)).collect();
    let want: Vec<(usize, usize)> = pairs(&gold["skips"])
        .into_iter()
        .map(|(s, l)| (s, l.as_u64().unwrap() as usize))
        .collect();
    assert_eq!(skips, want, "{stem}");

    // Annotations as stored, and the samples MNE gives those in the recording.
    let stored = &gold["annotations"];
    let descriptions: Vec<String> = info
        .annotations
        .iter()
        .map(|a| a.description.clone())
        .collect();
    assert_eq!(descriptions, strings(&stored["description"]), "{stem}");
    for (i, a) in info.annotations.iter().enumerate() {
        assert_eq!(a.onset, stored["onset"][i].as_f64().unwrap(), "{stem}");
        assert_eq!(
            a.duration,
            stored["duration"][i].as_f64().unwrap(),
            "{stem}"
        );
    }
    let orig = stored["orig_time"]
        .as_f64()
        .map(|t| (t * 1e6).round() as i64);
    assert_eq!(info.annotations_orig_time, orig, "{stem}");
    let mut placed: Vec<(usize, String)> = info
        .annotations
        .iter()
        .filter_map(|a| a.sample.map(|s| (s, a.description.clone())))
        .collect();
    placed.sort();
    let mut want: Vec<(usize, String)> = pairs(&gold["annotation_events"])
        .into_iter()
        .map(|(s, d)| (s, d.as_str().unwrap().to_string()))
        .collect();
    want.sort();
    assert_eq!(placed, want, "{stem}");

    // Events: the trigger steps, then the annotations (codes by the EDF+ text rule).
    let stim: Vec<(usize, u32)> = pairs(&gold["stim_events"])
        .into_iter()
        .map(|(s, c)| (s, c.as_u64().unwrap() as u32))
        .collect();
    let mut expected: Vec<(usize, u32, Option<bool>, Option<String>)> =
        stim.iter().map(|&(s, c)| (s, c, None, None)).collect();
    for (s, d) in &want {
        match d.as_str() {
            "7 target" => expected.push((*s, 7, Some(true), None)),
            _ => expected.push((*s, info.label_codes[d], None, Some(d.clone()))),
        }
    }
    expected.sort();
    let mut got: Vec<(usize, u32, Option<bool>, Option<String>)> = raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target, e.label.clone()))
        .collect();
    got.sort();
    assert_eq!(got, expected, "{stem}");
    // Label codes count up from above every trigger code.
    let max_stim = stim.iter().map(|&(_, c)| c).max().unwrap_or(0);
    assert!(info.label_codes.values().all(|&c| c > max_stim), "{stem}");
    max_diff
}

#[test]
fn every_fixture_reads_as_mne_reads_it() {
    let mut worst = 0.0f64;
    for stem in FIXTURES {
        let d = check(stem);
        eprintln!("{stem}: max |µV difference| {d:e}");
        worst = worst.max(d);
    }
    eprintln!("all fixtures: max |µV difference| {worst:e}");
}

#[test]
fn label_codes_follow_first_appearance_above_the_trigger_codes() {
    let rec = read(fixture("fif/float_raw.fif")).unwrap();
    let info = rec.fif().unwrap();
    let want: BTreeMap<String, u32> = [("Target", 10), ("NonTarget", 11), ("a: b", 12)]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    assert_eq!(info.label_codes, want);
    // The `CODE target` text gives its code and flag.
    let e = rec.raw.events().iter().find(|e| e.onset == 128).unwrap();
    assert_eq!(
        (e.code, e.target, e.label.as_deref()),
        (7, Some(true), None)
    );
    // The channel record holds 15 characters; the extended block the whole name.
    assert_eq!(rec.raw.ch_names()[2], "Pz-long-channel-name");
}

#[test]
fn split_parts_are_read_in_turn() {
    let rec = read(fixture("fif/split_raw.fif")).unwrap();
    let parts: Vec<String> = rec
        .fif()
        .unwrap()
        .parts
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        parts,
        [
            "split_raw.fif",
            "split_raw-1.fif",
            "split_raw-2.fif",
            "split_raw-3.fif"
        ]
    );
    // Four parts of 64 samples each make the one recording MNE reads (checked in full above).
    assert_eq!(rec.raw.n_times(), 256);
}
