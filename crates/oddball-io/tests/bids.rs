//! BIDS-EEG out and in on a synthetic recording: the run written by `ExportPlan` reads back
//! through `oddball_io::read` with its events, targets, codes and channels; hostile or broken
//! sidecars are errors naming the file and the place, never a panic or a silent change.

use std::path::{Path, PathBuf};

use oddball_io::bids::{
    dataset_manifest, BidsError, ExportFormat, ExportOptions, ExportPlan, RunData,
};
use oddball_io::{EventMapping, IoError, Recording};

/// A 3-channel synthetic oddball CSV (markers 2 = target, 1 = non-target), read and labelled.
fn recording(dir: &Path) -> Recording {
    let csv = dir.join("rec.csv");
    let (data, markers, sfreq) = oddball_testkit::synthetic_oddball(3, 9);
    oddball_testkit::write_codes_csv(&csv, &data, &markers, sfreq);
    let mut rec = oddball_io::read(&csv).unwrap();
    rec.map_events(&EventMapping::parse("2", "1").unwrap())
        .unwrap();
    rec
}

/// Exports `rec` as sub-1's only run under `dir/bids`; returns the EDF's path.
fn export(dir: &Path, rec: &Recording) -> PathBuf {
    export_as(dir, rec, ExportFormat::Edf, true).unwrap()
}

/// Exports `rec` as sub-1's only run under `dir/bids` in `format`; returns the data file's path.
fn export_as(
    dir: &Path,
    rec: &Recording,
    format: ExportFormat,
    overwrite: bool,
) -> Result<PathBuf, IoError> {
    let root = dir.join("bids");
    let plan = ExportPlan::new(
        &root,
        std::slice::from_ref(&rec.path),
        ExportOptions {
            subject: "1".into(),
            task: Some("oddball".into()),
            overwrite,
            power_line_frequency: Some(50.0),
            format,
            ..ExportOptions::default()
        },
    )?;
    let s = plan.write_run(0, rec)?;
    assert_eq!(
        matches!(s.data, RunData::BrainVision(_)),
        format == ExportFormat::BrainVision
    );
    plan.finish()?;
    Ok(plan.runs[0].eeg_path(&root))
}

fn sidecar(eeg: &Path, suffix: &str) -> PathBuf {
    let name = eeg.file_name().unwrap().to_str().unwrap();
    eeg.with_file_name(name.replace("eeg.edf", suffix))
}

fn error_of(eeg: &Path) -> String {
    let e: IoError = oddball_io::read(eeg).unwrap_err();
    e.to_string()
}

#[test]
fn a_run_reads_back_and_broken_sidecars_are_named() {
    let dir = oddball_testkit::TempDir::new("bids-io");
    let rec = recording(dir.path());
    let eeg = export(dir.path(), &rec);
    let back = oddball_io::read(&eeg).unwrap();
    assert_eq!(back.raw.n_times(), rec.raw.n_times());
    assert_eq!(back.raw.ch_names(), rec.raw.ch_names());
    let key = |r: &Recording| {
        r.raw
            .events()
            .iter()
            .map(|e| (e.onset, e.code, e.target))
            .collect::<Vec<_>>()
    };
    assert_eq!(key(&back), key(&rec));
    let json = std::fs::read_to_string(sidecar(&eeg, "eeg.json")).unwrap();
    assert!(json.contains("\"PowerLineFrequency\": 50.0"), "{json}");
    let m = dataset_manifest(&dir.join("bids")).unwrap();
    assert_eq!(m.subjects.len(), 1);
    assert_eq!(m.subjects[0].train, std::slice::from_ref(&eeg));

    // A bad channel and a MISC channel are left out.
    let channels = sidecar(&eeg, "channels.tsv");
    let good = std::fs::read_to_string(&channels).unwrap();
    let edited = good
        .replacen("ch0\tEEG\tµV\tgood", "ch0\tEEG\tµV\tbad", 1)
        .replacen("ch2\tEEG", "ch2\tMISC", 1);
    std::fs::write(&channels, edited).unwrap();
    assert_eq!(oddball_io::read(&eeg).unwrap().raw.ch_names(), ["ch1"]);
    std::fs::write(&channels, good.replacen("ch1", "Cz", 1)).unwrap();
    let e = error_of(&eeg);
    assert!(
        e.contains("channels.tsv: line 3, column \"name\"") && e.contains("\"Cz\""),
        "{e}"
    );
    std::fs::write(&channels, good).unwrap();

    // Events: a code that is not a number, a sample past the end, a missing column.
    let events = sidecar(&eeg, "events.tsv");
    let good = std::fs::read_to_string(&events).unwrap();
    std::fs::write(&events, good.replacen("\ttarget\t2\n", "\ttarget\t-2\n", 1)).unwrap();
    let e = error_of(&eeg);
    assert!(
        e.contains("events.tsv: line") && e.contains("column \"value\""),
        "{e}"
    );
    let n = rec.raw.n_times();
    std::fs::write(&events, format!("{good}999\t0\t{n}\ttarget\t2\n")).unwrap();
    assert!(error_of(&eeg).contains("past the recording"));
    std::fs::write(&events, good.replacen("onset", "start", 1)).unwrap();
    assert!(error_of(&eeg).contains("required column missing"));
    std::fs::write(&events, &good).unwrap();

    // The speller sidecar and the duration.
    let ev_json = sidecar(&eeg, "events.json");
    std::fs::write(
        &ev_json,
        r#"{"oddball": {"speller": {"matrix": [["A","B"],["C"]]}}}"#,
    )
    .unwrap();
    assert!(error_of(&eeg).contains("rows of different lengths"));
    std::fs::write(&ev_json, "{not json").unwrap();
    assert!(error_of(&eeg).contains("not JSON"));
    std::fs::write(&ev_json, "{}").unwrap();
    let eeg_json = sidecar(&eeg, "eeg.json");
    std::fs::write(&eeg_json, r#"{"RecordingDuration": "long"}"#).unwrap();
    assert!(error_of(&eeg).contains("RecordingDuration"));
    // A sidecar too large to be read is refused before it is read.
    let f = std::fs::File::create(&eeg_json).unwrap();
    f.set_len(oddball_io::bids::MAX_SIDECAR_BYTES + 1).unwrap();
    assert!(error_of(&eeg).contains("more than"));
}

#[test]
fn a_folder_without_a_description_or_runs_is_not_a_data_set() {
    let dir = oddball_testkit::TempDir::new("bids-empty");
    let e = dataset_manifest(dir.path()).unwrap_err().to_string();
    assert!(e.contains("no dataset_description.json"), "{e}");
    std::fs::write(dir.join("dataset_description.json"), r#"{"Name": "x"}"#).unwrap();
    let e = dataset_manifest(dir.path()).unwrap_err().to_string();
    assert!(e.contains("no EEG run"), "{e}");
}

#[test]
fn a_brainvision_run_reads_back_to_f32_and_one_format_replaces_the_other() {
    let dir = oddball_testkit::TempDir::new("bids-bv");
    let rec = recording(dir.path());
    let vhdr = export_as(dir.path(), &rec, ExportFormat::BrainVision, false).unwrap();
    assert!(vhdr.ends_with("sub-1/eeg/sub-1_task-oddball_eeg.vhdr"));
    for ext in ["vmrk", "eeg"] {
        assert!(vhdr.with_extension(ext).is_file(), "{ext}");
    }
    let back = oddball_io::read(&vhdr).unwrap();
    assert_eq!(back.raw.ch_names(), rec.raw.ch_names());
    assert_eq!(back.raw.sfreq(), rec.raw.sfreq());
    for (a, b) in rec.raw.data().iter().zip(back.raw.data().iter()) {
        assert_eq!(*b, f64::from(*a as f32));
    }
    let key = |r: &Recording| {
        r.raw
            .events()
            .iter()
            .map(|e| (e.onset, e.code, e.target))
            .collect::<Vec<_>>()
    };
    assert_eq!(key(&back), key(&rec));
    let m = dataset_manifest(&dir.join("bids")).unwrap();
    assert_eq!(m.subjects[0].train, std::slice::from_ref(&vhdr));

    // The run is there (in the other format): refused without overwrite, replaced with it.
    let e = export_as(dir.path(), &rec, ExportFormat::Edf, false).unwrap_err();
    assert!(
        matches!(&e, IoError::Bids(b) if matches!(**b, BidsError::Exists { ref path } if path == &vhdr)),
        "{e}"
    );
    let edf = export_as(dir.path(), &rec, ExportFormat::Edf, true).unwrap();
    for ext in ["vhdr", "vmrk", "eeg"] {
        assert!(
            !vhdr.with_extension(ext).exists(),
            "{ext} left beside the EDF"
        );
    }
    let m = dataset_manifest(&dir.join("bids")).unwrap();
    assert_eq!(m.subjects[0].train, std::slice::from_ref(&edf));
}
