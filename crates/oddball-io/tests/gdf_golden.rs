//! The GDF reader against MNE's (`mne.io.read_raw_gdf` 1.13.2) on GDF 1.25 and 2.20 files
//! written by `tools/golden/gdf/make_gdf_fixtures.py` (`tests/fixtures/gdf/golden.json`): samples
//! to 1e-6 µV, names, rate, the event table and the events; a file of every data type MNE
//! refuses, against the script's own values; and hostile input: every truncation, absurd counts,
//! corrupt fields and random mutations give errors naming the file and the byte offset, never a
//! panic and never a shortened recording.

mod common;

use std::path::Path;

use common::{fixture, golden, mutate, Rng};
use oddball_io::gdf::{parse_gdf, GdfOptions, GdfType};
use oddball_io::{read, Format, IoError, Recording};
use serde_json::Value;

fn gold(name: &str) -> Value {
    golden("gdf/golden.json")[name].clone()
}

fn bytes_of(name: &str) -> Vec<u8> {
    std::fs::read(fixture(&format!("gdf/{name}"))).unwrap()
}

fn parse(b: &[u8]) -> Result<Recording, IoError> {
    parse_gdf(b, Path::new("t.gdf"), &GdfOptions::default())
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Samples to 1e-6 µV, names, rate and length as the golden entry has them; the largest
/// difference.
fn assert_samples(rec: &Recording, g: &Value, what: &str) -> f64 {
    let raw = &rec.raw;
    let names: Vec<String> = g["ch_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    assert_eq!(raw.ch_names(), names.as_slice(), "{what}");
    assert_eq!(raw.sfreq(), g["sfreq"].as_f64().unwrap(), "{what}");
    assert_eq!(
        raw.n_times() as u64,
        g["n_times"].as_u64().unwrap(),
        "{what}"
    );
    let mut worst = 0.0f64;
    for (c, row) in g["data_uV"].as_array().unwrap().iter().enumerate() {
        for (t, want) in f64s(row).into_iter().enumerate() {
            let got = raw.data()[[c, t]];
            let d = (got - want).abs();
            assert!(d <= 1e-6, "{what}: channel {c} sample {t}: {got} vs {want}");
            worst = worst.max(d);
        }
    }
    worst
}

/// The stored event table equals MNE's (MNE's positions are the file's minus one in uint32, so
/// position 0 wraps to 2³² − 1; its durations are at least 1).
fn assert_table(rec: &Recording, g: &Value) {
    let table = rec.gdf().unwrap().event_table.as_ref().unwrap();
    let t = &g["event_table"];
    let pos0 = t["pos0"].as_array().unwrap();
    assert_eq!(table.events.len(), pos0.len());
    for (k, e) in table.events.iter().enumerate() {
        let want = pos0[k].as_u64().unwrap();
        assert_eq!(u64::from(e.position.wrapping_sub(1)), want, "event {k}");
        assert_eq!(
            u64::from(e.typ),
            t["type"][k].as_u64().unwrap(),
            "event {k}"
        );
        assert_eq!(u64::from(e.channel), t["channel"][k].as_u64().unwrap());
        assert_eq!(
            u64::from(e.duration.max(1)),
            t["duration"][k].as_u64().unwrap()
        );
    }
}

#[test]
fn gdf2_int32_with_units_and_mode3_events_reads_as_mne_reads_it() {
    let g = gold("small_v2.gdf");
    let rec = read(fixture("gdf/small_v2.gdf")).unwrap();
    assert_eq!(rec.format, Format::Gdf);
    let worst = assert_samples(&rec, &g, "small_v2");
    eprintln!("small_v2: max |diff| vs MNE {worst:e} µV");
    let info = rec.gdf().unwrap();
    assert_eq!(info.header.major, 2);
    assert_eq!(info.header.version, "2.20");
    assert_eq!(info.header.record_duration, (1, 4));
    let dims: Vec<&str> = info
        .header
        .channels
        .iter()
        .map(|c| c.dimension.as_str())
        .collect();
    assert_eq!(dims, ["uV", "mV", "V", "uV"]);
    assert!(info.non_voltage_channels.is_empty());
    assert!(info.openvibe.is_none());
    assert_eq!(info.header.channels[0].filters, Some([30.0, 0.1, 50.0]));
    let table = info.event_table.as_ref().unwrap();
    assert_eq!((table.mode, table.sample_rate), (3, 128.0));
    assert_table(&rec, &g);

    // Plain codes: the events are MNE's annotations (onset × rate, description = code).
    let a = &g["annotations"];
    let sfreq = rec.raw.sfreq();
    let mut want: Vec<(usize, u32)> = f64s(&a["onset_s"])
        .iter()
        .zip(a["description"].as_array().unwrap())
        .map(|(o, d)| {
            (
                (o * sfreq).round() as usize,
                d.as_str().unwrap().parse().unwrap(),
            )
        })
        .collect();
    want.sort();
    let mut got: Vec<(usize, u32)> = rec.raw.events().iter().map(|e| (e.onset, e.code)).collect();
    got.sort();
    assert_eq!(got, want);
    assert_eq!(got.len(), 6);
    assert!(rec.raw.events().iter().all(|e| e.target.is_none()));
    assert!(got.contains(&(10, 0x0300)) && got.contains(&(159, 0x0114)));
}

#[test]
fn gdf1_int16_with_openvibe_codes_reads_as_mne_reads_it_and_pairs_flags_by_time() {
    let g = gold("small_v1.gdf");
    let rec = read(fixture("gdf/small_v1.gdf")).unwrap();
    let worst = assert_samples(&rec, &g, "small_v1");
    eprintln!("small_v1: max |diff| vs MNE {worst:e} µV");
    let info = rec.gdf().unwrap();
    assert_eq!(
        (info.header.major, info.header.version.as_str()),
        (1, "1.25")
    );
    assert_eq!(info.header.start, "2024010212304500");
    assert_eq!(info.header.channels[0].prefiltering, "HP:0.1Hz LP:40Hz");
    let table = info.event_table.as_ref().unwrap();
    assert_eq!((table.mode, table.sample_rate), (1, 256.0));
    assert_table(&rec, &g);
    // Position 0 and the two past the end are outside (MNE drops them from its annotations).
    assert_eq!(info.events_outside, 3);
    assert_eq!(
        g["annotations"]["onset_s"].as_array().unwrap().len(),
        table.events.len() - 3
    );

    // The flashes the script derived from MNE's table.
    let ov = &g["openvibe"];
    let want: Vec<(usize, u32, Option<bool>)> = ov["flashes"]
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
    let got: Vec<(usize, u32, Option<bool>)> = rec
        .raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target))
        .collect();
    assert_eq!(got, want);
    assert_eq!(
        got,
        [
            (20, 1, Some(false)),
            (40, 3, Some(true)),
            (60, 2, Some(false)),
            (80, 8, Some(true)),
            (100, 2, Some(false)),
            (120, 4, None),
            (160, 9, Some(true)),
            (180, 14, None),
        ]
    );
    let o = info.openvibe.as_ref().unwrap();
    assert_eq!(
        o.duplicate_labels as u64,
        ov["duplicate_labels"].as_u64().unwrap()
    );
    assert_eq!(o.orphan_flags as u64, ov["orphan_flags"].as_u64().unwrap());
    assert_eq!(
        (o.duplicate_labels, o.orphan_flags, o.unflagged_labels),
        (1, 3, 2)
    );
    assert_eq!(o.trial_starts, [10]);
    assert_eq!(o.flashes_per_trial, [8]);
    assert_eq!(o.other_codes[&0x8001], 2);
    assert_eq!(o.other_codes[&0x800B], 2);
}

#[test]
fn every_data_type_mne_reads_gives_mnes_values() {
    let names = [
        "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32",
        "float64",
    ];
    for name in names {
        let key = format!("types/v2_{name}.gdf");
        let g = gold(&key);
        let rec = read(fixture(&format!("gdf/{key}"))).unwrap();
        assert_samples(&rec, &g, &key);
        let info = rec.gdf().unwrap();
        let ty = info.header.channels[0].data_type;
        assert_eq!(u64::from(ty.code()), g["type"].as_u64().unwrap(), "{key}");
        // These files end with their data: no event table (MNE finds none either).
        assert!(g["event_table"].is_null());
        assert!(info.event_table.is_none());
        assert!(rec.raw.events().is_empty());
    }
}

#[test]
fn mixed_types_and_24_bit_give_the_writers_values() {
    let g = gold("mixed_types_v2.gdf");
    // MNE reads every channel with the first one's type, so it refuses this file.
    assert!(g["mne_refused"].is_string());
    let rec = read(fixture("gdf/mixed_types_v2.gdf")).unwrap();
    assert_samples(&rec, &g, "mixed_types");
    let info = rec.gdf().unwrap();
    let types: Vec<u64> = info
        .header
        .channels
        .iter()
        .map(|c| u64::from(c.data_type.code()))
        .collect();
    let want: Vec<u64> = g["types"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_u64().unwrap())
        .collect();
    assert_eq!(types, want);
    assert!(types.contains(&u64::from(GdfType::Int24.code())));
    assert_eq!(info.non_voltage_channels, ["T535"]);
    assert_eq!(info.header.channels[11].dimension, "code 6048");
    let ev: Vec<(usize, u32)> = rec.raw.events().iter().map(|e| (e.onset, e.code)).collect();
    assert_eq!(ev, [(2, 0x0300), (19, 0x0301)]);
}

// ---- hostile input --------------------------------------------------------------------------

/// The byte where a fixture's data records end (its event table starts).
fn data_end(b: &[u8]) -> usize {
    let rec = parse(b).unwrap();
    let info = rec.gdf().unwrap();
    let h = &info.header;
    let per_record: usize = h
        .channels
        .iter()
        .map(|c| c.samples_per_record * c.data_type.bytes())
        .sum();
    h.header_bytes + h.n_records * per_record
}

#[test]
fn every_truncation_is_an_error_with_an_offset_or_keeps_all_samples() {
    for name in ["small_v1.gdf", "small_v2.gdf", "mixed_types_v2.gdf"] {
        let b = bytes_of(name);
        let full = parse(&b).unwrap();
        let end = data_end(&b);
        for cut in 0..b.len() {
            match parse(&b[..cut]) {
                Ok(rec) => {
                    // Only a cut right after the data records reads: a file without event table.
                    assert_eq!(cut, end, "{name}: cut at {cut} read");
                    assert_eq!(rec.raw.data(), full.raw.data());
                    assert!(rec.gdf().unwrap().event_table.is_none());
                }
                Err(e) => {
                    assert!(e.offset().is_some(), "{name} cut at {cut}: {e}");
                    assert!(
                        e.offset().unwrap() <= cut as u64,
                        "{name} cut at {cut}: {e}"
                    );
                    assert!(e.to_string().contains("t.gdf"), "{e}");
                    assert!(matches!(e, IoError::Truncated { .. }), "{name} {cut}: {e}");
                }
            }
        }
    }
}

fn patched(name: &str, at: usize, value: &[u8]) -> Vec<u8> {
    let mut b = bytes_of(name);
    b[at..at + value.len()].copy_from_slice(value);
    b
}

fn expect_err(b: &[u8], offset: u64, text: &str) {
    let t0 = std::time::Instant::now();
    let e = parse(b).expect_err(text);
    assert!(t0.elapsed().as_secs_f64() < 1.0, "{text}: took long");
    assert_eq!(e.offset(), Some(offset), "{text}: {e}");
    assert!(e.to_string().contains(text), "{text}: {e}");
}

#[test]
fn absurd_counts_are_refused_before_allocation() {
    // Records: int64 at 236.
    for n in [i64::MAX, 1 << 40, 1_000_000] {
        expect_err(
            &patched("small_v1.gdf", 236, &n.to_le_bytes()),
            256 * 4,
            "data records",
        );
        expect_err(
            &patched("small_v2.gdf", 236, &n.to_le_bytes()),
            256 * 5,
            "data records",
        );
    }
    expect_err(
        &patched("small_v1.gdf", 236, &(-1i64).to_le_bytes()),
        236,
        "number of data records",
    );
    // Channels: uint32 (1.x) / uint16 (2.x) at 252.
    expect_err(
        &patched("small_v1.gdf", 252, &u32::MAX.to_le_bytes()),
        256,
        "channel headers",
    );
    expect_err(
        &patched("small_v2.gdf", 252, &u16::MAX.to_le_bytes()),
        256,
        "channel headers",
    );
    expect_err(
        &patched("small_v1.gdf", 252, &0u32.to_le_bytes()),
        252,
        "number of channels",
    );
    // Samples per record of every channel 2³² − 1, and records of (2³² − 1)/16 s (so 16 Hz):
    // 1.x fields at 256 + 3 × 216, 2.x at 256 + 4 × 216.
    for (name, ns, at) in [
        ("small_v1.gdf", 3, 256 + 3 * 216),
        ("small_v2.gdf", 4, 256 + 4 * 216),
    ] {
        let mut b = patched(name, 244, &u32::MAX.to_le_bytes());
        for c in 0..ns {
            b[at + 4 * c..at + 4 * c + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        }
        expect_err(&b, 256 * (ns as u64 + 1), "data records");
    }
    // Event counts: 1.x uint32 at table + 4; 2.x 24-bit at table + 1.
    let b = bytes_of("small_v1.gdf");
    let at = data_end(&b);
    expect_err(
        &patched("small_v1.gdf", at + 4, &u32::MAX.to_le_bytes()),
        at as u64,
        "event table",
    );
    let b = bytes_of("small_v2.gdf");
    let at = data_end(&b);
    expect_err(
        &patched("small_v2.gdf", at + 1, &[0xFF, 0xFF, 0xFF]),
        at as u64,
        "event table",
    );
}

#[test]
fn corrupt_fields_name_their_byte_offset() {
    expect_err(&patched("small_v1.gdf", 0, b"GDF 3.00"), 0, "version");
    expect_err(&patched("small_v1.gdf", 0, b"0       "), 0, "version");
    // Header length: 1.x int64 at 184, 2.x uint16 blocks at 184.
    expect_err(
        &patched("small_v1.gdf", 184, &1000i64.to_le_bytes()),
        184,
        "bytes in header",
    );
    expect_err(
        &patched("small_v2.gdf", 184, &2u16.to_le_bytes()),
        184,
        "header length",
    );
    expect_err(
        &patched("small_v2.gdf", 184, &60000u16.to_le_bytes()),
        0,
        "header",
    );
    // Record duration 0/4 and 1/0.
    expect_err(
        &patched("small_v2.gdf", 244, &0u32.to_le_bytes()),
        244,
        "duration",
    );
    expect_err(
        &patched("small_v2.gdf", 248, &0u32.to_le_bytes()),
        244,
        "duration",
    );
    // Channel 2's data type (1.x: 256 + 3 × 220 + 4); 2.x channel 3's (256 + 4 × 220 + 8).
    expect_err(
        &patched("small_v1.gdf", 256 + 3 * 220 + 4, &99u32.to_le_bytes()),
        (256 + 3 * 220 + 4) as u64,
        "channel 2 (Pz) data type",
    );
    expect_err(
        &patched("small_v2.gdf", 256 + 4 * 220 + 8, &0u32.to_le_bytes()),
        (256 + 4 * 220 + 8) as u64,
        "channel 3 (Pz) data type",
    );
    // 2.x physical minimum of channel 1 NaN (at 256 + 4 × 104); digital max = min (channel 1).
    expect_err(
        &patched("small_v2.gdf", 256 + 4 * 104, &f64::NAN.to_le_bytes()),
        (256 + 4 * 104) as u64,
        "physical minimum",
    );
    let b = bytes_of("small_v2.gdf");
    let dmin = b[256 + 4 * 120..256 + 4 * 128].to_vec();
    expect_err(
        &patched("small_v2.gdf", 256 + 4 * 128, &dmin),
        (256 + 4 * 128) as u64,
        "digital maximum",
    );
    // Event table mode 2; a 2.x table rate of -1 Hz.
    let b = bytes_of("small_v2.gdf");
    let at = data_end(&b);
    expect_err(
        &patched("small_v2.gdf", at, &[2]),
        at as u64,
        "event table mode",
    );
    expect_err(
        &patched("small_v2.gdf", at + 4, &(-1f32).to_le_bytes()),
        (at + 4) as u64,
        "event table sample rate",
    );
}

#[test]
fn mixed_rates_are_refused_unless_dropped_and_exclusion_works() {
    // Channel 2 (Pz) of small_v1 at 8 samples per record instead of 16 (field at 256 + 3 × 216
    // + 4): refused, or dropped on request. Records are then 80 bytes: cut the file after 16 of
    // them (no event table) so that it is whole.
    let mut b = bytes_of("small_v1.gdf");
    b[256 + 3 * 216 + 4..256 + 3 * 216 + 8].copy_from_slice(&8u32.to_le_bytes());
    let b = &b[..1024 + 16 * 80];
    let e = parse(b).unwrap_err();
    assert!(e.to_string().contains("mixed sample rates"), "{e}");
    let opts = GdfOptions {
        drop_mismatched_rates: true,
        exclude: vec![],
    };
    let rec = parse_gdf(b, Path::new("t.gdf"), &opts).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Cz", "Oz"]);
    assert_eq!(rec.gdf().unwrap().dropped_channels, ["Pz"]);
    assert_eq!(rec.raw.n_times(), 256);
    let full = parse(&bytes_of("small_v1.gdf")).unwrap();
    // The first record of Cz is where it was.
    for t in 0..16 {
        assert_eq!(rec.raw.data()[[0, t]], full.raw.data()[[0, t]]);
    }

    let opts = GdfOptions {
        drop_mismatched_rates: false,
        exclude: vec!["Pz".into()],
    };
    let rec = parse_gdf(&bytes_of("small_v1.gdf"), Path::new("t.gdf"), &opts).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Cz", "Oz"]);
    assert_eq!(rec.raw.data().row(1), full.raw.data().row(2));
}

#[test]
fn random_mutations_never_panic() {
    let interesting: [&[u8]; 6] = [
        &[0xFF, 0xFF, 0xFF, 0xFF],
        &[0, 0, 0, 0],
        &[0x01, 0x81],
        b"GDF 2.20",
        &[0x05, 0x82],
        &[0, 0, 0, 0, 0, 0, 0xF0, 0x7F],
    ];
    let mut rng = Rng(0x9DF_2026);
    for name in ["small_v1.gdf", "small_v2.gdf", "mixed_types_v2.gdf"] {
        let base = bytes_of(name);
        for _ in 0..1500 {
            let b = mutate(&mut rng, &base, &interesting);
            match parse(&b) {
                Ok(rec) => {
                    let n = rec.raw.n_times();
                    assert!(rec.raw.events().iter().all(|e| e.onset < n));
                }
                Err(e) => assert!(e.to_string().contains("t.gdf"), "{e}"),
            }
        }
    }
}
