//! Mutated MAT files never panic, and every error about the bytes names an offset inside them:
//! proptest mutations (cuts, byte flips, element tags and lengths overwritten with absurd
//! 32-bit values, zlib streams damaged) of every MAT fixture and of the real BCI Competition
//! run, through the container parser and the BCI Competition layout.

mod common;

use std::path::Path;

use common::{data_file, fixture};
use oddball_io::{parse_mat, parse_mat_file, IoError, MatOptions};
use proptest::prelude::*;

const FIXTURES: [&str; 7] = [
    "v5.mat",
    "v7.mat",
    "narrow.mat",
    "narrow_be.mat",
    "bci_small.mat",
    "v73.mat",
    // A cut-off v5 file: its last variables are missing.
    "v5.mat#1200",
];

fn fixture_bytes(name: &str) -> Vec<u8> {
    let (file, cut) = match name.split_once('#') {
        Some((f, c)) => (f, c.parse::<usize>().ok()),
        None => (name, None),
    };
    let mut b = std::fs::read(fixture(&format!("mat/{file}"))).unwrap();
    if let Some(c) = cut {
        b.truncate(c);
    }
    b
}

#[derive(Debug, Clone)]
enum Mutation {
    /// Keep only the first `frac` of the bytes.
    Cut(f64),
    /// XOR the byte at `frac` of the length with `mask`.
    Flip(f64, u8),
    /// Overwrite the 8-aligned 32-bit word at `frac` of the length (a tag's type or length,
    /// array flags, dimensions …) with `value`.
    Word(f64, u32),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let words = prop_oneof![
        Just(0u32),
        Just(1),
        Just(4),
        Just(5),
        Just(8),
        Just(14),
        Just(15),
        Just(0x0004_0001),
        Just(0x7fff_ffff),
        Just(0xffff_fff8),
        Just(u32::MAX),
        any::<u32>(),
    ];
    prop_oneof![
        (0.0..1.0f64).prop_map(Mutation::Cut),
        (0.0..1.0f64, 1..=255u8).prop_map(|(f, m)| Mutation::Flip(f, m)),
        (0.0..1.0f64, words).prop_map(|(f, w)| Mutation::Word(f, w)),
    ]
}

fn apply(base: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut b = base.to_vec();
    for m in muts {
        let len = b.len();
        let at = |f: f64| ((f * len as f64) as usize).min(len.saturating_sub(1));
        match *m {
            Mutation::Cut(f) => b.truncate(at(f)),
            Mutation::Flip(f, mask) if len > 0 => b[at(f)] ^= mask,
            Mutation::Word(f, w) if len >= 4 => {
                let i = (at(f) / 4 * 4).min(len - 4);
                b[i..i + 4].copy_from_slice(&w.to_le_bytes());
            }
            _ => {}
        }
    }
    b
}

/// Parses `b` both ways; every byte-level error names an offset inside the bytes and the file.
fn check(b: &[u8]) {
    let path = Path::new("mutated.mat");
    let check_err = |e: &IoError| {
        assert!(e.to_string().contains("mutated.mat"), "{e}");
        if let IoError::Truncated { .. } | IoError::InvalidField { .. } = e {
            let offset = e.offset().expect("offset");
            assert!(
                offset <= b.len() as u64,
                "offset {offset} of {}: {e}",
                b.len()
            );
            assert!(e.to_string().contains("byte"), "{e}");
        }
    };
    if let Err(e) = parse_mat_file(b, path) {
        check_err(&e);
    }
    if let Err(e) = parse_mat(b, path, &MatOptions::default()) {
        check_err(&e);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn mutated_fixtures_never_panic(
        which in 0..FIXTURES.len(),
        muts in prop::collection::vec(mutation(), 1..4),
    ) {
        check(&apply(&fixture_bytes(FIXTURES[which]), &muts));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(120))]

    /// The whole real file (4 MB), so that mutations reach every variable and the signal.
    #[test]
    fn mutated_real_file_never_panics(muts in prop::collection::vec(mutation(), 1..3)) {
        let Some(path) = data_file("mutated_real", "bci-competition-ii-iib/AAS010R01.mat") else {
            return Ok(());
        };
        let bytes = std::fs::read(path).unwrap();
        check(&apply(&bytes, &muts));
    }
}

/// Every prefix of the compressed fixture (each cut lands in a tag, a zlib stream or between
/// variables) is a valid shorter file or an error with an offset.
#[test]
fn every_prefix_of_a_compressed_file() {
    let b = fixture_bytes("v7.mat");
    for cut in 0..b.len() {
        check(&b[..cut]);
    }
    let b = fixture_bytes("narrow_be.mat");
    for cut in 0..b.len() {
        check(&b[..cut]);
    }
}

/// A MAT file of one hand-built `miMATRIX` holding `body` (little-endian).
fn one_matrix(body: &[u8]) -> Vec<u8> {
    let mut b = b"MATLAB 5.0 MAT-file, hand-made".to_vec();
    b.resize(116, b' ');
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&[0x00, 0x01, b'I', b'M']);
    b.extend_from_slice(&14u32.to_le_bytes());
    b.extend_from_slice(&(body.len() as u32).to_le_bytes());
    b.extend_from_slice(body);
    b
}

fn words(w: &[u32]) -> Vec<u8> {
    w.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A struct with no fields claiming 2³¹−1 × 2³¹−1 elements reads at once as an empty struct
/// (it once looped over every element); a cell of that size is an error at its first cell.
#[test]
fn absurd_sizes_without_data_are_quick() {
    let head = |class: u32| {
        words(&[
            6,
            8,
            class,
            0,
            5,
            8,
            0x7fff_ffff,
            0x7fff_ffff,
            (1 << 16) | 1,
            u32::from(b's'),
        ])
    };
    let mut st = head(2);
    st.extend(words(&[(4 << 16) | 5, 1, 1, 0]));
    let file = parse_mat_file(&one_matrix(&st), Path::new("s.mat")).unwrap();
    let v = &file.get("s").unwrap().array;
    assert_eq!(v.dims, [0x7fff_ffff, 0x7fff_ffff]);
    assert!(
        matches!(&v.value, oddball_io::mat::MatValue::Struct { fields, values }
        if fields.is_empty() && values.is_empty())
    );

    let cell = one_matrix(&head(1));
    let err = parse_mat_file(&cell, Path::new("c.mat")).unwrap_err();
    assert_eq!(err.offset(), Some(128 + 8 + 40), "{err}");
    assert!(err.to_string().contains("cell 1"), "{err}");

    // The same size as doubles with no bytes: an error, no allocation.
    let mut num = head(6);
    num.extend(words(&[9, 0]));
    let err = parse_mat_file(&one_matrix(&num), Path::new("n.mat")).unwrap_err();
    assert!(err.to_string().contains("number of values"), "{err}");
}
