//! Absurd header values are refused with an error naming the field, before any allocation
//! sized by them: a negative or 10¹² number of records, a record of 0 s (0 Hz), a BCI2000
//! file of 0 Hz or a negative channel count. Each must return quickly and never abort.

use std::path::Path;

use oddball_io::edf::{parse_edf, EdfOptions};

fn edf_fixture() -> Vec<u8> {
    std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/pyedflib_small.edf"
    ))
    .unwrap()
}

/// Writes `value` left-aligned into the 8-byte ASCII field at `at`.
fn patch(bytes: &mut [u8], at: usize, width: usize, value: &str) {
    let field = format!("{value:<width$}");
    assert_eq!(field.len(), width, "{value}");
    bytes[at..at + width].copy_from_slice(field.as_bytes());
}

#[test]
fn edf_record_counts_and_durations_that_make_no_sense_are_refused() {
    // Header: 236..244 number of data records, 244..252 duration of a record (s).
    for (at, value, field) in [
        (236, "-5", "record"),
        (236, "1e12", "record"),
        (236, "99999999", "record"),
        (244, "0", "duration"),
        (244, "-1", "duration"),
        (244, "nan", "duration"),
    ] {
        let mut b = edf_fixture();
        patch(&mut b, at, 8, value);
        let t0 = std::time::Instant::now();
        let err = parse_edf(&b, Path::new("absurd.edf"), &EdfOptions::default())
            .expect_err(value)
            .to_string()
            .to_lowercase();
        assert!(t0.elapsed().as_secs_f64() < 1.0, "{value}: took long");
        assert!(err.contains(field), "{value}: {err}");
    }
}

#[test]
fn bci2000_zero_hz_negative_channel_counts_and_zero_columns_are_refused() {
    let Some(path) = oddball_testkit::data_file(
        "bci2000_zero_hz_negative_channel_counts_and_zero_columns_are_refused",
        "bci2000-samplefiles-p300/eeg3_1.dat",
    ) else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let header_end = bytes.windows(2).position(|w| w == b"\r\n").unwrap();
    let first = String::from_utf8_lossy(&bytes[..header_end]).to_string();
    let dir = oddball_testkit::TempDir::new("absurd");
    let cases: Vec<(Vec<u8>, &str)> = vec![
        // SamplingRate= 256 → 0 (same length keeps the header length right).
        (
            replace_once(&bytes, b"SamplingRate= 256", b"SamplingRate= 0  "),
            "samplingrate",
        ),
        // SourceCh= 8 → -8.
        (
            replace_once(
                &bytes,
                first.as_bytes(),
                first.replace("SourceCh= 8", "SourceCh=-8").as_bytes(),
            ),
            "sourcech",
        ),
        // A speller matrix of 0 columns.
        (
            replace_once(&bytes, b"NumMatrixColumns= 1 6", b"NumMatrixColumns= 1 0"),
            "nummatrixcolumns",
        ),
    ];
    for (i, (b, field)) in cases.into_iter().enumerate() {
        let p = dir.join(format!("case{i}.dat"));
        std::fs::write(&p, &b).unwrap();
        let err = oddball_io::read(&p)
            .expect_err(field)
            .to_string()
            .to_lowercase();
        assert!(err.contains(field), "{field}: {err}");
    }
}

/// Found by `cargo fuzz run bci2000`: a speller with no targets made the layout split its
/// targets into rows of 0 and panicked (the fixture is the fuzzer's file, synthetic). An
/// explicit 0 columns is refused as a count (the BCI2000 test above).
#[test]
fn a_speller_of_no_targets_is_refused() {
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/fuzz/bci2000_no_targets.dat"
    ));
    let bytes = std::fs::read(path).unwrap();
    let options = oddball_io::Bci2000Options::default();
    let err = oddball_io::bci2000::parse_bci2000(&bytes, path, &options)
        .expect_err("no targets")
        .to_string();
    assert!(err.contains("TargetDefinitions"), "{err}");
}

fn replace_once(haystack: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let at = haystack
        .windows(from.len())
        .position(|w| w == from)
        .unwrap_or_else(|| panic!("{:?} not found", String::from_utf8_lossy(from)));
    let mut out = haystack.to_vec();
    out[at..at + from.len()].copy_from_slice(to);
    out
}
