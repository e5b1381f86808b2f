//! The GDF reader on the real OpenViBE P300 speller recording (`$ODDBALL_DATA` or
//! ../shared/data, `openvibe-p300-gdf/data_sample_8ch.gdf`, GDF 1.25): 8 channels at 256 Hz,
//! 700 flashes of 14 codes with 100 targets, the target label pair of each of its 5 trials, and
//! the samples of the first and last 32 samples of every channel as MNE 1.13.2 reads them
//! (`tests/fixtures/gdf/real_openvibe.json`, made by `tools/golden/gdf/make_gdf_fixtures.py`).

mod common;

use std::collections::BTreeSet;

use common::{data_file, golden};
use oddball_io::gdf::parse_gdf;
use oddball_io::{read, Format, GdfOptions, IoError};

fn real_file(test: &str) -> Option<std::path::PathBuf> {
    data_file(test, "openvibe-p300-gdf/data_sample_8ch.gdf")
}

#[test]
fn openvibe_recording_reads_as_700_flashes_of_14_codes_with_100_targets() {
    let Some(path) =
        real_file("openvibe_recording_reads_as_700_flashes_of_14_codes_with_100_targets")
    else {
        return;
    };
    let g = golden("gdf/real_openvibe.json");
    let rec = read(&path).unwrap();
    assert_eq!(rec.format, Format::Gdf);
    let raw = &rec.raw;
    let names: Vec<String> = (1..=8).map(|k| format!("Channel {k}")).collect();
    assert_eq!(raw.ch_names(), names.as_slice());
    assert_eq!(raw.sfreq(), 256.0);
    assert_eq!(raw.n_times(), 50688);
    assert_eq!(raw.n_times() as u64, g["n_times"].as_u64().unwrap());

    let ev = raw.events();
    assert_eq!(ev.len(), 700);
    assert_eq!(ev.n_targets(), 100);
    assert_eq!(ev.n_nontargets(), 600);
    let counts = ev.counts_by_code();
    assert_eq!(
        counts.keys().copied().collect::<Vec<_>>(),
        (1..=14).collect::<Vec<u32>>()
    );
    assert!(counts.values().all(|&n| n == 50), "{counts:?}");

    // Every flash as the script pairs MNE's table.
    let want: Vec<(usize, u32, Option<bool>)> = g["flashes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f[0].as_u64().unwrap() as usize,
                f[1].as_u64().unwrap() as u32,
                f[2].as_bool(),
            )
        })
        .collect();
    let got: Vec<(usize, u32, Option<bool>)> =
        ev.iter().map(|e| (e.onset, e.code, e.target)).collect();
    assert_eq!(got, want);

    // The target label pair of each trial.
    let info = rec.gdf().unwrap();
    assert_eq!(info.header.version, "1.25");
    let ov = info.openvibe.as_ref().expect("OpenViBE codes");
    assert_eq!(ov.trial_starts.len(), 5);
    assert_eq!(ov.flashes_per_trial, [140; 5]);
    let pairs: Vec<BTreeSet<u32>> = ov
        .trial_starts
        .iter()
        .enumerate()
        .map(|(k, &start)| {
            let end = ov.trial_starts.get(k + 1).copied().unwrap_or(usize::MAX);
            ev.iter()
                .filter(|e| e.onset >= start && e.onset < end && e.target == Some(true))
                .map(|e| e.code)
                .collect()
        })
        .collect();
    let expected: Vec<BTreeSet<u32>> = [[1, 8], [2, 8], [5, 13], [4, 14], [2, 11]]
        .iter()
        .map(|p| p.iter().copied().collect())
        .collect();
    assert_eq!(pairs, expected);
    // Each trial: 10 repetitions of the 14 codes, two of them (one row, one column) targets.
    for (k, pair) in pairs.iter().enumerate() {
        let (lo, hi): (Vec<u32>, Vec<u32>) = pair.iter().partition(|&&c| c <= 7);
        assert_eq!((lo.len(), hi.len()), (1, 1), "trial {k}: {pair:?}");
    }

    // What was not a flash: one repeated label, its extra flag, no unflagged label; the
    // trial, visual stimulation and other codes with their counts.
    assert_eq!(ov.duplicate_labels, 1);
    assert_eq!(ov.orphan_flags, 1);
    assert_eq!(ov.unflagged_labels, 0);
    assert_eq!(ov.other_codes[&0x800B], 700);
    assert_eq!(ov.other_codes[&0x800C], 700);
    assert_eq!(ov.other_codes[&0x8005], 5);
    assert_eq!(ov.other_codes[&0x8006], 4);
    let table = info.event_table.as_ref().unwrap();
    assert_eq!(
        table.events.len() as u64,
        g["n_table_events"].as_u64().unwrap()
    );
    assert_eq!(table.sample_rate, 0.0);
    // Position 0 (before the first sample, 1-based) is outside.
    assert_eq!(info.events_outside, 1);
    assert_eq!(info.trailing_bytes, 4);
    for (code, n) in g["event_type_counts"].as_object().unwrap() {
        let code: u16 = code.parse().unwrap();
        let mine = table.events.iter().filter(|e| e.typ == code).count();
        assert_eq!(mine as u64, n.as_u64().unwrap(), "code {code}");
    }
    assert!(rec.speller.is_none());

    // The first and last 32 samples of every channel, as MNE reads them.
    let data = raw.data();
    let n = raw.n_times();
    let mut worst = 0.0f64;
    for (key, first) in [("first_uV", 0), ("last_uV", n - 32)] {
        for (c, row) in g[key].as_array().unwrap().iter().enumerate() {
            for (k, want) in row.as_array().unwrap().iter().enumerate() {
                let (got, want) = (data[[c, first + k]], want.as_f64().unwrap());
                assert!(
                    (got - want).abs() <= 1e-6,
                    "{key} channel {c} sample {}: {got} vs {want}",
                    first + k
                );
                worst = worst.max((got - want).abs());
            }
        }
    }
    eprintln!("real file: max |diff| vs MNE over 512 samples {worst:e} µV");
}

#[test]
fn cut_copies_of_the_real_file_are_errors_with_offsets() {
    let Some(path) = real_file("cut_copies_of_the_real_file_are_errors_with_offsets") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let data_end = 2304 + 50688 * 64;
    for cut in [
        0,
        100,
        255,
        256,
        2303,
        2304,
        2305,
        1_000_000,
        data_end - 1,
        data_end + 1,
        data_end + 7,
        data_end + 8,
        bytes.len() - 10,
    ] {
        let e = parse_gdf(&bytes[..cut], &path, &GdfOptions::default()).unwrap_err();
        assert!(matches!(e, IoError::Truncated { .. }), "cut {cut}: {e}");
        assert!(
            e.offset().is_some_and(|o| o <= cut as u64),
            "cut {cut}: {e}"
        );
    }
    // Cut right after the data: every sample, no event table, no events.
    let rec = parse_gdf(&bytes[..data_end], &path, &GdfOptions::default()).unwrap();
    assert_eq!(rec.raw.n_times(), 50688);
    assert!(rec.raw.events().is_empty());
    assert!(rec.gdf().unwrap().event_table.is_none());
}
