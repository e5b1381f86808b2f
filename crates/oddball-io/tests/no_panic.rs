//! Corrupted input never panics: thousands of seeded random mutations (byte changes, cuts,
//! insertions, deletions) of small valid files of every format go through the parsers, which
//! must return `Ok` or `Err`. `ODDBALL_FUZZ_N` sets the mutations per file (default 4000).
//! Also: dispatch by extension.

mod common;

use std::path::Path;

use common::{fixture, Rng, TempDir};
use oddball_io::{
    bci2000::parse_bci2000, csv::parse_csv, edf::parse_edf, read, Bci2000Options, CsvOptions,
    EdfOptions, IoError,
};

const INTERESTING: &[&[u8]] = &[
    b"0",
    b"-1",
    b"99999999",
    b"-99999999",
    b"18446744073709551616",
    b"%",
    b"{",
    b"}",
    b"\x14",
    b"\x15",
    b"\x00",
    b"\n",
    b"\r\n",
    b",",
    b"nan",
    b"1e308",
    b" ",
    b"\xff",
];

fn mutate(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    common::mutate(rng, base, INTERESTING)
}

/// A small BCI2000 v1.1 file: 2 int16 channels, 3 states, 40 samples, speller parameters.
fn small_bci2000() -> Vec<u8> {
    let rest = "[ State Vector Definition ]\r\n\
        StimulusCode 5 0 0 0\r\nStimulusType 1 0 0 5\r\nPhaseInSequence 2 0 0 6\r\n\
        [ Parameter Definition ]\r\n\
        Source int SamplingRate= 100Hz 256Hz 1 % // rate\r\n\
        Source list ChannelNames= 2 Cz Pz // names\r\n\
        Source floatlist SourceChGain= 2 0.1 0.2muV 0 % % // gain\r\n\
        Source floatlist SourceChOffset= 1 3 // offset\r\n\
        App matrix TargetDefinitions= 4 { Display Enter } A A B B C C D D // t\r\n\
        App intlist NumMatrixRows= 1 2 // r\r\nApp intlist NumMatrixColumns= 1 2 // c\r\n\
        App int NumberOfSequences= 2 // n\r\nApp string TextToSpell= AD // t\r\n\
        App matrix M= { a b } { c } %20 { x { y } } // nested\r\n\r\n";
    let first = |n: usize| {
        format!("BCI2000V= 1.1 HeaderLen= {n} SourceCh= 2 StatevectorLen= 1 DataFormat= int16\r\n")
    };
    let mut n = first(0).len() + rest.len();
    while first(n).len() + rest.len() != n {
        n = first(n).len() + rest.len();
    }
    let mut out = (first(n) + rest).into_bytes();
    for t in 0..40u32 {
        out.extend((t as i16 * 3).to_le_bytes());
        out.extend((-(t as i16)).to_le_bytes());
        let code = if t % 4 == 1 { (t / 4) % 4 + 1 } else { 0 };
        let typ = u32::from(code == 1 || code == 4);
        out.push((code | typ << 5 | 2 << 6) as u8);
    }
    out
}

fn small_csv() -> Vec<u8> {
    let mut s = String::from("timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n");
    for t in 0..30 {
        let m = [0, 1, 0, 2, 0][t % 5];
        s += &format!(
            "{:.3},{},{},-3.5,4e1,0,{m}\n",
            100.0 + t as f64 / 256.0,
            t,
            t * 2
        );
    }
    s.into_bytes()
}

#[test]
fn small_files_are_valid() {
    let p = Path::new("small.dat");
    let rec = parse_bci2000(&small_bci2000(), p, &Bci2000Options::default()).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Cz", "Pz"]);
    assert_eq!(rec.raw.sfreq(), 100.0);
    assert_eq!(rec.raw.n_times(), 40);
    // µV = (raw - 3) × gain.
    assert_eq!(rec.raw.data()[[0, 2]], (6.0 - 3.0) * 0.1);
    assert_eq!(rec.raw.data()[[1, 2]], (-2.0 - 3.0) * 0.2);
    assert_eq!(rec.raw.events().len(), 10);
    let sp = rec.speller.as_ref().unwrap();
    assert_eq!(
        (sp.n_rows(), sp.n_cols(), sp.flashes_per_character),
        (2, 2, Some(8))
    );
    assert_eq!(sp.text_to_spell.as_deref(), Some("AD"));
    let phase = rec
        .bci2000()
        .unwrap()
        .states
        .get("PhaseInSequence")
        .unwrap();
    assert!(phase.iter().all(|&v| v == 2));
    let m = rec.bci2000().unwrap().parameters.get("M").unwrap();
    assert_eq!(m.matrix_rows().unwrap().len(), 2);
    parse_csv(&small_csv(), Path::new("small.csv"), &CsvOptions::muse()).unwrap();
}

fn fuzz(
    name: &str,
    base: &[u8],
    n: usize,
    seed: u64,
    parse: impl Fn(&[u8]) -> Result<(), IoError>,
) {
    assert!(parse(base).is_ok(), "{name}: the unmutated file must parse");
    let n = std::env::var("ODDBALL_FUZZ_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(n);
    let mut rng = Rng(seed);
    let (mut ok, mut err) = (0, 0);
    for _ in 0..n {
        let b = mutate(&mut rng, base);
        match parse(&b) {
            Ok(()) => ok += 1,
            Err(e) => {
                // Every error names the file.
                assert!(e.to_string().contains(name), "{e}");
                err += 1;
            }
        }
    }
    assert!(
        err > n / 4,
        "{name}: only {err} of {n} mutations were rejected ({ok} accepted)"
    );
}

#[test]
fn mutated_bci2000_never_panics() {
    let base = small_bci2000();
    fuzz("small.dat", &base, 4000, 0x5EED_0001, |b| {
        parse_bci2000(b, Path::new("small.dat"), &Bci2000Options::default()).map(|_| ())
    });
}

#[test]
fn mutated_csv_never_panics() {
    let base = small_csv();
    fuzz("small.csv", &base, 4000, 0x5EED_0002, |b| {
        parse_csv(b, Path::new("small.csv"), &CsvOptions::muse()).map(|_| ())?;
        parse_csv(b, Path::new("small.csv"), &CsvOptions::default())
            .map(|_| ())
            .or(Ok(()))
    });
}

#[test]
fn mutated_edf_and_bdf_never_panic() {
    for (name, seed) in [
        ("pyedflib_small.edf", 0x5EED_0003),
        ("numpy_small.bdf", 0x5EED_0004),
    ] {
        let base = std::fs::read(fixture(name)).unwrap();
        fuzz(name, &base, 4000, seed, |b| {
            parse_edf(b, Path::new(name), &EdfOptions::default()).map(|_| ())
        });
    }
}

#[test]
fn read_dispatches_by_extension() {
    let tmp = TempDir::new("dispatch");
    let dat = tmp.write("x.DAT", &small_bci2000());
    assert_eq!(read(&dat).unwrap().format, oddball_io::Format::Bci2000);
    let csv = tmp.write("x.csv", &small_csv());
    let rec = read(&csv).unwrap();
    assert_eq!(rec.raw.ch_names(), ["TP9", "AF7", "AF8", "TP10"]);
    assert_eq!(rec.raw.events().n_targets(), 6);
    let bdf = tmp.write("x.bdf", &std::fs::read(fixture("numpy_small.bdf")).unwrap());
    assert_eq!(read(&bdf).unwrap().format, oddball_io::Format::BdfPlus);
    let e = read(tmp.write("x.gdf", b"")).unwrap_err();
    assert!(matches!(&e, IoError::Truncated { offset: 0, .. }), "{e}");
    let e = read(tmp.write("x.qqq", b"")).unwrap_err();
    assert!(
        matches!(&e, IoError::UnknownFormat { extension: Some(x), .. } if x == "qqq"),
        "{e}"
    );
    assert!(e.to_string().contains("extension .qqq"), "{e}");
    let e = read(tmp.write("noext", b"")).unwrap_err();
    assert!(e.to_string().contains("(no extension)"), "{e}");
    let e = read(tmp.path().join("missing.edf")).unwrap_err();
    assert!(matches!(e, IoError::NotFound { .. }), "{e}");
    assert!(e.to_string().ends_with("missing.edf: no such file"), "{e}");
    // A folder names the recordings inside it instead of an unknown extension.
    let e = read(tmp.path()).unwrap_err();
    match &e {
        IoError::IsDirectory { recordings, .. } => {
            assert_eq!(recordings, &["x.DAT", "x.bdf", "x.csv"], "{e}")
        }
        other => panic!("expected IsDirectory, got {other}"),
    }
    assert!(e.to_string().contains("is a directory"), "{e}");
}
