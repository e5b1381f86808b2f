//! The EEGLAB reader against MNE 1.13.2 (`mne.io.read_raw_eeglab`, `events_from_annotations`)
//! on the fixtures of tools/golden/eeglab/make_fixtures.py: an `export_raw(fmt="eeglab")` file
//! (eeglabio: top-level variables, data inside) and a `scipy.io.savemat` struct `EEG` whose data
//! are in a `.fdt`; values to 1e-6 µV, names, rate, event samples (fractional latencies rounded
//! as MNE rounds them), codes and labels; the epoched file MNE refuses is refused.

mod common;

use common::{fixture, golden, TempDir};
use oddball_io::eeglab::EeglabEventType;
use oddball_io::{read, Format, IoError};
use serde_json::Value;

fn check(g: &Value) -> f64 {
    let file = g["file"].as_str().unwrap();
    let rec = read(fixture(&format!("eeglab/{file}"))).unwrap();
    assert_eq!(rec.format, Format::Eeglab);
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
    assert_eq!(raw.n_times(), n_times);
    let mut max_diff = 0.0f64;
    for (c, row) in g["data"].as_array().unwrap().iter().enumerate() {
        for (t, v) in row.as_array().unwrap().iter().enumerate() {
            let (ours, mne) = (raw.data()[[c, t]], v.as_f64().unwrap());
            let diff = (ours - mne).abs();
            assert!(diff <= 1e-6, "{file}: [{c}, {t}]: {ours} vs MNE {mne}");
            max_diff = max_diff.max(diff);
        }
    }

    let info = rec.eeglab().unwrap();
    let mne_events = g["events"].as_array().unwrap();
    let ours = raw.events().as_slice();
    assert_eq!(ours.len(), mne_events.len(), "{file}: number of events");
    for (e, m) in ours.iter().zip(mne_events) {
        let sample = m[0].as_u64().unwrap() as usize;
        let desc = m[1].as_str().unwrap();
        assert_eq!(e.onset, sample, "{file}: onset of {desc:?}");
        match desc.parse::<f64>() {
            Ok(v) => {
                assert_eq!(f64::from(e.code), v, "{file}: {desc}");
                assert_eq!(e.label, None);
            }
            Err(_) if desc == "3 nontarget: A" => {
                assert_eq!(
                    (e.code, e.target, e.label.as_deref()),
                    (3, Some(false), Some("A"))
                );
            }
            Err(_) => {
                assert_eq!(e.label.as_deref(), Some(desc), "{file}");
                assert_eq!(e.code, info.label_codes[desc], "{file}: {desc}");
                assert_eq!(e.target, None);
            }
        }
    }
    max_diff
}

#[test]
fn fixtures_read_as_mne_reads_them() {
    let gold = golden("eeglab/golden.json");
    let mut worst = 0.0f64;
    for g in gold["fixtures"].as_array().unwrap() {
        worst = worst.max(check(g));
    }
    eprintln!("EEGLAB vs MNE: max abs diff {worst:e} µV");
}

#[test]
fn eeglabio_layout() {
    let rec = read(fixture("eeglab/mne_export.set")).unwrap();
    let info = rec.eeglab().unwrap();
    assert!(!info.in_eeg_struct);
    assert_eq!(info.data_file, None);
    assert_eq!(info.setname.as_deref(), Some("mne_export"));
    assert_eq!(info.header.version, 0x0100);
    // Numeric codes up to 7 (the text "7" and "3 nontarget: A"); the other texts from 8 on.
    let codes: Vec<(&str, u32)> = info
        .label_codes
        .iter()
        .map(|(k, v)| (k.as_str(), *v))
        .collect();
    assert_eq!(codes, [("last", 10), ("stim", 8), ("target", 9)]);
    assert_eq!(info.events.len(), 6);
    assert!(info.events.iter().all(|e| e.onset.is_some()));
    // The onset between samples: latency 31.3 → sample 30.
    assert_eq!(info.events[2].onset, Some(30));
}

#[test]
fn struct_layout_with_fdt() {
    let rec = read(fixture("eeglab/struct_fdt.set")).unwrap();
    let info = rec.eeglab().unwrap();
    assert!(info.in_eeg_struct);
    assert!(info.data_file.as_ref().unwrap().ends_with("struct_fdt.fdt"));
    assert_eq!(info.stale_data_name, None);
    assert_eq!(info.setname.as_deref(), Some("struct layout"));
    assert_eq!(info.reference.as_deref(), Some("common"));
    assert_eq!(info.events[0].kind, EeglabEventType::Number(1.0));
    assert_eq!(info.events[1].kind, EeglabEventType::Text("target".into()));
    // Latency 12.7 → 11.7 → 12; 30.5 → 29.5 → 30 (half to even, as numpy and MNE round).
    assert_eq!(info.events[1].onset, Some(12));
    assert_eq!(info.events[3].onset, Some(30));
    assert_eq!(info.label_codes["target"], 3);
    assert_eq!(info.label_codes["boundary"], 4);
}

#[test]
fn renamed_set_reads_its_own_fdt() {
    let dir = TempDir::new("eeglab_renamed");
    let set = dir.write(
        "renamed.set",
        &std::fs::read(fixture("eeglab/struct_fdt.set")).unwrap(),
    );
    dir.write(
        "renamed.fdt",
        &std::fs::read(fixture("eeglab/struct_fdt.fdt")).unwrap(),
    );
    let rec = read(&set).unwrap();
    let info = rec.eeglab().unwrap();
    assert_eq!(info.stale_data_name.as_deref(), Some("struct_fdt.fdt"));
    assert!(info.data_file.as_ref().unwrap().ends_with("renamed.fdt"));
    let orig = read(fixture("eeglab/struct_fdt.set")).unwrap();
    assert_eq!(rec.raw.data(), orig.raw.data());
    // With neither file there: the named one is not found.
    std::fs::remove_file(dir.join("renamed.fdt")).unwrap();
    let e = read(&set).unwrap_err();
    assert!(matches!(e, IoError::NotFound { .. }), "{e}");
    assert!(e.to_string().contains("struct_fdt.fdt"), "{e}");
}

#[test]
fn epoched_is_refused_as_mne_refuses_it() {
    let gold = golden("eeglab/golden.json");
    assert!(gold["epoched_mne"]
        .as_str()
        .unwrap()
        .contains("number of trials is 2"));
    let e = read(fixture("eeglab/epoched.set")).unwrap_err();
    assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    assert!(e.to_string().contains("EEG.trials = 2"), "{e}");
}

#[test]
fn mat_v73_set_names_the_version() {
    let dir = TempDir::new("eeglab_v73");
    let set = dir.write("hdf5.set", &std::fs::read(fixture("mat/v73.mat")).unwrap());
    let e = read(&set).unwrap_err();
    assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    assert!(e.to_string().contains("7.3"), "{e}");
}
