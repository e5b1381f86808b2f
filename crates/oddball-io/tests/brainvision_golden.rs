//! The BrainVision reader against MNE 1.13.2 (`mne.io.read_raw_brainvision` and
//! `mne.events_from_annotations`) on the fixtures of tools/golden/brainvision/make_fixtures.py:
//! an `export_raw(fmt="brainvision")` float32 file, a pybv INT_16 file (one channel in mV) and a
//! hand-written INT_32 VECTORIZED cp1252 file (`\1` comma, empty resolution, °C channel, text
//! stimulus descriptions, a marker beyond the data). Values to 1e-6 µV; names, rate, events.

mod common;

use common::{fixture, golden};
use oddball_io::brainvision::{BvBinaryFormat, BvOrientation};
use oddball_io::{read, Format};
use serde_json::Value;

/// MNE numbers BrainVision markers it does not know from 10001 on; those codes are MNE's own.
const MNE_OTHER: u64 = 10001;

fn check(g: &Value) -> f64 {
    let file = g["file"].as_str().unwrap();
    let rec = read(fixture(&format!("brainvision/{file}"))).unwrap();
    assert_eq!(rec.format, Format::BrainVision, "{file}");
    let raw = &rec.raw;
    let names: Vec<&str> = g["ch_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(raw.ch_names(), names, "{file}: names");
    assert_eq!(raw.sfreq(), g["sfreq"].as_f64().unwrap(), "{file}: rate");
    let n_times = g["n_times"].as_u64().unwrap() as usize;
    assert_eq!(raw.n_times(), n_times, "{file}: samples");

    let mut max_diff = 0.0f64;
    for (c, row) in g["data"].as_array().unwrap().iter().enumerate() {
        let row = row.as_array().unwrap();
        assert_eq!(row.len(), n_times);
        for (t, v) in row.iter().enumerate() {
            let (ours, mne) = (raw.data()[[c, t]], v.as_f64().unwrap());
            let diff = (ours - mne).abs();
            assert!(diff <= 1e-6, "{file}: [{c}, {t}]: {ours} vs MNE {mne}");
            max_diff = max_diff.max(diff);
        }
    }

    // Events: every MNE Stimulus/Response event inside the recording, same sample; the codes
    // MNE gives S n / R n are ours, the text ones get ours from label_codes.
    let info = rec.brainvision().unwrap();
    let ours = raw.events().as_slice();
    let annotations = g["annotations"].as_array().unwrap();
    let mut expected = Vec::new();
    for (a, e) in annotations.iter().zip(g["events"].as_array().unwrap()) {
        let desc = a["description"].as_str().unwrap();
        let sample = e[0].as_u64().unwrap() as usize;
        assert_eq!(sample as u64, a["sample"].as_u64().unwrap());
        if !(desc.starts_with("Stimulus/") || desc.starts_with("Response/")) || sample >= n_times {
            continue;
        }
        let mne_code = e[1].as_u64().unwrap();
        let code = if mne_code >= MNE_OTHER {
            info.label_codes[desc]
        } else {
            mne_code as u32
        };
        expected.push((sample, code, desc.to_string()));
    }
    let got: Vec<(usize, u32, String)> = ours
        .iter()
        .map(|e| (e.onset, e.code, e.label.clone().unwrap()))
        .collect();
    assert_eq!(got, expected, "{file}: events");
    assert!(ours.iter().all(|e| e.target.is_none()));

    // Every annotation is a marker (MNE drops the first New Segment, which holds the date).
    let markers: Vec<String> = info
        .markers
        .iter()
        .skip_while(|m| m.kind == "New Segment")
        .map(|m| format!("{}/{}", m.kind, m.description))
        .collect();
    let descs: Vec<&str> = annotations
        .iter()
        .map(|a| a["description"].as_str().unwrap())
        .collect();
    assert_eq!(markers, descs, "{file}: markers");
    max_diff
}

#[test]
fn fixtures_read_as_mne_reads_them() {
    let gold = golden("brainvision/golden.json");
    let fixtures = gold["fixtures"].as_array().unwrap();
    assert_eq!(fixtures.len(), 3);
    let mut worst = 0.0f64;
    for g in fixtures {
        worst = worst.max(check(g));
    }
    eprintln!("BrainVision vs MNE: max abs diff {worst:e} µV");
}

#[test]
fn hand_written_file_details() {
    let rec = read(fixture("brainvision/hand_int32_vec.vhdr")).unwrap();
    let info = rec.brainvision().unwrap();
    assert_eq!(info.encoding, "cp1252");
    assert_eq!(info.binary_format, BvBinaryFormat::Int32);
    assert_eq!(info.orientation, BvOrientation::Vectorized);
    assert_eq!(info.sampling_interval_us, 1953.125);
    assert_eq!(rec.raw.sfreq(), 512.0);
    assert_eq!(info.channels[0].name, "Fz,a");
    assert_eq!(info.channels[0].reference, "Cz");
    assert_eq!(info.channels[0].unit, "µV");
    assert_eq!(info.channels[1].resolution, 1.0);
    assert_eq!(info.channels[2].unit, "");
    assert_eq!(info.channels[3].unit, "°C");
    assert_eq!(info.non_voltage_channels, ["Temp"]);
    // The int32 extremes, exactly: 2147483647 × 0.25 µV and -2147483648 × 1 mV.
    assert_eq!(rec.raw.data()[[0, 0]], 2147483647.0 * 0.25);
    assert_eq!(rec.raw.data()[[1, 1]], -2147483648.0 * 1000.0);
    // Text descriptions: codes from one above the largest numeric code (R 2 → 1002).
    assert_eq!(info.label_codes["Stimulus/Target"], 1003);
    assert_eq!(info.label_codes["Stimulus/Non target"], 1004);
    assert_eq!(info.label_codes.len(), 2);
    let seg = &info.markers[0];
    assert_eq!(seg.kind, "New Segment");
    assert_eq!(seg.date.as_deref(), Some("20240102030405678901"));
    assert_eq!(seg.code, None);
    let last = info.markers.last().unwrap();
    assert_eq!((last.onset, last.code), (40, Some(4)));
    assert_eq!(
        rec.raw.events().len(),
        6,
        "S 4 at sample 40 is beyond the 40 samples"
    );
    let comment = info.markers.iter().find(|m| m.kind == "Comment").unwrap();
    assert_eq!(comment.description, "a,b");
    assert_eq!(comment.code, None);
}

#[test]
fn pybv_files() {
    let rec = read(fixture("brainvision/pybv_int16.vhdr")).unwrap();
    let info = rec.brainvision().unwrap();
    assert_eq!(info.binary_format, BvBinaryFormat::Int16);
    assert_eq!(info.orientation, BvOrientation::Multiplexed);
    assert_eq!(info.encoding, "UTF-8");
    assert!(info.version_line.contains("Header File Version 1.0"));
    assert!(info.data_file.ends_with("pybv_int16.eeg"));
    assert!(info
        .marker_file
        .as_ref()
        .unwrap()
        .ends_with("pybv_int16.vmrk"));
    let codes: Vec<u32> = rec.raw.events().iter().map(|e| e.code).collect();
    assert_eq!(codes, [2, 1007, 2, 255], "R 7 is 1007");
    assert_eq!(rec.raw.data()[[0, 5]], 16000.0);
    assert_eq!(rec.raw.data()[[0, 6]], -16000.0);
}
