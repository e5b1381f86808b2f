//! The MAT reader on the real BCI Competition II IIb runs (`$ODDBALL_DATA` or ../shared/data):
//! the recording the BCI Competition layout makes of them, checked against scipy's reading
//! (`real` in tests/fixtures/mat/golden.json), and errors on truncated and corrupted copies.

mod common;

use common::{data_file, golden, TempDir};
use oddball_io::mat::BCI_COMPETITION_SFREQ;
use oddball_io::speller::UNDECIDED;
use oddball_io::{read, read_mat_with, CodeOrder, Format, IoError, MatOptions};

fn competition_file(test: &str, name: &str) -> Option<std::path::PathBuf> {
    data_file(test, &format!("bci-competition-ii-iib/{name}"))
}

#[test]
fn training_run_reads_as_a_labelled_speller_recording() {
    let Some(path) = competition_file("training_run", "AAS010R01.mat") else {
        return;
    };
    let gold = &golden("mat/golden.json")["real"]["AAS010R01.mat"];
    let rec = read(&path).unwrap();
    assert_eq!(rec.format, Format::Mat);
    let raw = &rec.raw;
    assert_eq!(raw.n_channels(), 64);
    assert_eq!(raw.n_times(), 26328);
    assert_eq!(raw.sfreq(), 240.0);
    assert_eq!(raw.ch_names()[10], "Cz");
    assert_eq!(raw.ch_names()[50], "Pz");
    assert_eq!(raw.events().len(), 540);
    assert_eq!(raw.events().n_targets(), 90);
    assert_eq!(raw.events().n_nontargets(), 450);
    let counts = raw.events().counts_by_code();
    assert_eq!(
        counts.keys().copied().collect::<Vec<_>>(),
        (1..=12).collect::<Vec<u32>>()
    );
    assert!(counts.values().all(|&n| n == 45), "{counts:?}");

    // Samples as scipy reads them (raw amplifier units, unscaled).
    let data = raw.data();
    for p in gold["signal_at"].as_array().unwrap() {
        let p = p.as_array().unwrap();
        let (t, ch, v) = (
            p[0].as_u64().unwrap() as usize,
            p[1].as_u64().unwrap() as usize,
            p[2].as_f64().unwrap(),
        );
        assert_eq!(data[[ch, t]], v, "signal[{t}, {ch}]");
    }
    let sum: f64 = data.iter().sum();
    assert_eq!(sum, gold["signal_sum"].as_f64().unwrap());
    let abs: f64 = data.iter().map(|x| x.abs()).sum();
    assert_eq!(abs, gold["signal_abs_sum"].as_f64().unwrap());
    let first: Vec<f64> = (0..5).map(|c| data[[c, 0]]).collect();
    let want: Vec<f64> = gold["signal_first_row"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(first, want);
    for (i, o) in gold["first_onsets"].as_array().unwrap().iter().enumerate() {
        let e = &raw.events().as_slice()[i];
        assert_eq!(e.onset as u64, o[0].as_u64().unwrap());
        assert_eq!(u64::from(e.code), o[1].as_u64().unwrap());
    }

    // The speller: columns first, 180 flashes per character, CAT.
    let sp = rec.speller.as_ref().expect("speller");
    assert_eq!(sp.code_order, CodeOrder::ColumnsFirst);
    assert_eq!(sp.flashes_per_character, Some(180));
    assert_eq!(sp.text_to_spell, None);
    assert_eq!(sp.decode(raw.events()), gold["text"].as_str().unwrap());
    assert_eq!(sp.decode(raw.events()), "CAT");

    // The details: states as scipy sums them, the variables, the default rate, raw units.
    let info = rec.mat().unwrap();
    assert!(!info.sfreq_given);
    assert!(info.units.contains("raw amplifier units"));
    for (name, s) in gold["state_sums"].as_object().unwrap() {
        let ours: f64 = info.states[name].iter().sum();
        assert_eq!(ours, s.as_f64().unwrap(), "{name}");
    }
    let mut names: Vec<&str> = info.variables.iter().map(|v| v.name.as_str()).collect();
    names.sort_unstable();
    let want: Vec<&str> = gold["variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names, want);
    let sig = info.variables.iter().find(|v| v.name == "signal").unwrap();
    assert_eq!(sig.dims, [26328, 64]);
    assert_eq!(sig.kind, "Double stored as Int16");
}

#[test]
fn test_run_has_events_without_labels() {
    let Some(path) = competition_file("test_run", "AAS012R03.mat") else {
        return;
    };
    let gold = &golden("mat/golden.json")["real"]["AAS012R03.mat"];
    let rec = read(&path).unwrap();
    let raw = &rec.raw;
    assert_eq!(raw.events().len(), 540);
    assert!(raw.events().iter().all(|e| e.target.is_none()));
    assert_eq!(raw.data()[[50, 20000]], -544.0);
    let sum: f64 = raw.data().iter().sum();
    assert_eq!(sum, gold["signal_sum"].as_f64().unwrap());
    let sp = rec.speller.as_ref().unwrap();
    assert_eq!(sp.decode(raw.events()), UNDECIDED.to_string().repeat(3));
    let info = rec.mat().unwrap();
    assert_eq!(info.strings["filename"], "AAS012R03.mat");
    assert_eq!(info.strings["evalstring"], "save AAS012R03.mat");

    // The user supplies the text and may override the rate.
    let options = MatOptions {
        text_to_spell: Some("HAM".into()),
        sfreq: Some(BCI_COMPETITION_SFREQ),
        ..MatOptions::default()
    };
    let rec = read_mat_with(&path, &options).unwrap();
    assert_eq!(
        rec.speller.as_ref().unwrap().text_to_spell.as_deref(),
        Some("HAM")
    );
    assert!(rec.mat().unwrap().sfreq_given);
}

#[test]
fn a_missing_signal_variable_names_what_is_there() {
    let Some(path) = competition_file("missing_signal", "AAS010R01.mat") else {
        return;
    };
    let options = MatOptions {
        signal: "eeg".into(),
        ..MatOptions::default()
    };
    let err = read_mat_with(&path, &options).unwrap_err();
    let IoError::Missing {
        name, available, ..
    } = &err
    else {
        panic!("{err:?}")
    };
    assert_eq!(name, "eeg");
    assert!(available.iter().any(|a| a == "signal"), "{err}");
}

/// Cut at many points (in the header, inside tags, inside the big signal, one byte short),
/// every copy is an error naming a byte offset, and the offset lies inside the file.
#[test]
fn truncated_copies_name_a_byte_offset() {
    let Some(path) = competition_file("truncated", "AAS010R01.mat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let tmp = TempDir::new("mat-trunc");
    let n = bytes.len();
    let mut cuts = vec![
        0,
        1,
        60,
        127,
        129,
        131,
        136,
        140,
        150,
        200,
        1000,
        n / 2,
        n - 1,
    ];
    cuts.extend((1..40).map(|i| i * n / 40 + i * 7));
    for cut in cuts {
        let p = tmp.write("cut.mat", &bytes[..cut]);
        let err = read(&p).expect_err(&format!("cut at {cut}"));
        let offset = err
            .offset()
            .unwrap_or_else(|| panic!("cut at {cut}: no offset in {err}"));
        assert!(offset <= cut as u64, "cut at {cut}: {err}");
        assert!(err.to_string().contains("byte"), "{err}");
    }
    // A cut exactly between variables leaves a valid file with fewer variables; a cut after
    // `signal` is still a recording, but losing `Flashing` or `StimulusCode` is noticed.
    let p = tmp.write("cut.mat", &bytes[..128]);
    assert!(matches!(read(&p), Err(IoError::Missing { .. })));
}

#[test]
fn corrupted_lengths_and_types_name_a_byte_offset() {
    let Some(path) = competition_file("corrupted", "AAS010R01.mat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let tmp = TempDir::new("mat-corrupt");
    // The first variable's tag: its type, its length (huge), the array flags' type and the
    // dimensions' length.
    for (at, value) in [(128usize, 99u32), (132, u32::MAX), (136, 3), (152, 1 << 30)] {
        let mut b = bytes.clone();
        b[at..at + 4].copy_from_slice(&value.to_le_bytes());
        let p = tmp.write("bad.mat", &b);
        let err = read(&p).expect_err(&format!("{value} at {at}"));
        let offset = err.offset().unwrap_or_else(|| panic!("{err}"));
        assert!((128..=160).contains(&offset), "{value} at {at}: {err}");
    }
    // The version field, and an HDF5 file's header.
    let mut b = bytes.clone();
    b[124..126].copy_from_slice(&[0x00, 0x02]);
    let err = read(tmp.write("v73.mat", &b)).unwrap_err();
    assert!(err.to_string().contains("7.3"), "{err}");
    let mut b = bytes.clone();
    b[124..126].copy_from_slice(&[0x05, 0x00]);
    let err = read(tmp.write("v5bad.mat", &b)).unwrap_err();
    assert_eq!(err.offset(), Some(124), "{err}");
}
