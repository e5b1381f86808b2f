//! The FIF reader on cut, corrupted and absurd files: an error naming the file and the byte
//! offset (or the missing part), never a panic, never a recording with fewer samples; counts and
//! sizes refused before anything is allocated by them.

mod common;

use std::path::Path;

use common::{fixture, mutate, Rng, TempDir};
use oddball_io::{parse_fif, read, read_fif, IoError};

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(fixture(&format!("fif/{name}"))).unwrap()
}

/// `(kind, type, size, header byte)` of every tag of an MNE-written file (all `next` = 0 but the
/// last).
fn tags(b: &[u8]) -> Vec<(i32, u32, usize, usize)> {
    let be = |at: usize| i32::from_be_bytes(b[at..at + 4].try_into().unwrap());
    let mut out = Vec::new();
    let mut pos = 0;
    while pos + 16 <= b.len() {
        let size = be(pos + 8) as usize;
        out.push((be(pos), be(pos + 4) as u32, size, pos));
        if be(pos + 12) == -1 {
            break;
        }
        pos += 16 + size;
    }
    out
}

/// The header byte of the `n`-th tag of kind `kind`.
fn tag_at(b: &[u8], kind: i32, n: usize) -> usize {
    tags(b)
        .into_iter()
        .filter(|t| t.0 == kind)
        .nth(n)
        .unwrap_or_else(|| panic!("no tag {n} of kind {kind}"))
        .3
}

fn put_i32(b: &mut [u8], at: usize, v: i32) {
    b[at..at + 4].copy_from_slice(&v.to_be_bytes());
}

#[test]
fn every_cut_is_an_error_with_an_offset_or_the_whole_recording() {
    for name in [
        "float_raw.fif",
        "short_raw.fif",
        "skip_raw.fif",
        "cropped_raw.fif",
    ] {
        let full = bytes(name);
        let whole = parse_fif(&full, Path::new(name)).unwrap();
        let mut ok = Vec::new();
        for cut in 0..full.len() {
            match parse_fif(&full[..cut], Path::new(name)) {
                Ok(rec) => {
                    // Only the closing NOP tag may go: every block is closed before it.
                    assert_eq!(rec.raw, whole.raw, "{name} cut at {cut}");
                    ok.push(cut);
                }
                Err(e) => {
                    let text = e.to_string();
                    assert!(text.contains(name), "{text}");
                    assert!(e.offset().is_some(), "{name} cut at {cut}: {text}");
                    assert!(
                        e.offset().unwrap() <= cut as u64,
                        "{name} cut at {cut}: {text}"
                    );
                }
            }
        }
        assert_eq!(ok, [full.len() - 16], "{name}");
    }
}

#[test]
fn random_mutations_never_panic() {
    let mut rng = Rng(0x0F1F_2026);
    let interesting: [&[u8]; 6] = [
        &[0x7f, 0xff, 0xff, 0xff],
        &[0xff, 0xff, 0xff, 0xff],
        &[0, 0, 0, 0],
        &[0, 0, 1, 44],
        &[0, 0, 0, 104],
        &[0, 0, 0, 105],
    ];
    for name in [
        "float_raw.fif",
        "short_raw.fif",
        "skip_raw.fif",
        "split_raw-1.fif",
    ] {
        let base = bytes(name);
        for _ in 0..1500 {
            let b = mutate(&mut rng, &base, &interesting);
            match parse_fif(&b, Path::new(name)) {
                Ok(rec) => assert!(rec.raw.n_times() > 0 && rec.fif().is_some()),
                Err(e) => assert!(e.to_string().contains(name), "{e}"),
            }
        }
    }
}

#[test]
fn absurd_sizes_and_counts_are_refused_at_their_byte() {
    let base = bytes("float_raw.fif");
    let t0 = std::time::Instant::now();

    // A data buffer claiming 2 GB: cut, at its header.
    let mut b = base.clone();
    let at = tag_at(&b, 300, 0);
    put_i32(&mut b, at + 8, i32::MAX);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
    assert_eq!(e.offset(), Some(at as u64), "{e}");

    // A negative size.
    put_i32(&mut b, at + 8, -16);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 8), "{e}");

    // A million channels announced, five records.
    let mut b = base.clone();
    let at = tag_at(&b, 200, 0);
    put_i32(&mut b, at + 16, 1_000_000);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 16), "{e}");
    assert!(e.to_string().contains("FIFF_NCHAN"), "{e}");

    // A buffer that is not whole samples (one byte more, the chain kept whole).
    let mut b = base.clone();
    let (_, _, size, at) = tags(&b).into_iter().filter(|t| t.0 == 300).nth(1).unwrap();
    b.insert(at + 16, 0);
    put_i32(&mut b, at + 8, size as i32 + 1);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 8), "{e}");
    assert!(e.to_string().contains("multiple of 5 channels"), "{e}");

    // `next` pointing back: a loop, refused at the field.
    let mut b = base.clone();
    let at = tag_at(&b, 203, 2);
    put_i32(&mut b, at + 12, 36);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 12), "{e}");
    // `next` pointing past the end of the file.
    put_i32(&mut b, at + 12, i32::MAX);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");

    // A block closed with another block's kind.
    let mut b = base.clone();
    let at = tag_at(&b, 105, 0);
    put_i32(&mut b, at + 16, 7);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 16), "{e}");

    // Not a FIF file.
    let e = parse_fif(b"0       not fif at all.........", Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(0), "{e}");
    let e = parse_fif(b"", Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(0), "{e}");

    // A non-finite calibration of an EEG channel: in its record, then in the extended block
    // MNE writes for long names (FIFF_CH_CAL, 254), which replaces the record's.
    let mut b = base.clone();
    let at = tag_at(&b, 203, 0);
    b[at + 16 + 16..at + 16 + 20].copy_from_slice(&f32::NAN.to_be_bytes());
    assert!(parse_fif(&b, Path::new("x.fif")).is_ok());
    let at = tag_at(&b, 254, 0);
    b[at + 16..at + 20].copy_from_slice(&f32::NAN.to_be_bytes());
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 16), "{e}");
    assert!(e.to_string().contains("\"Fz\""), "{e}");

    assert!(t0.elapsed().as_secs() < 5);
}

#[test]
fn a_huge_skip_is_refused_before_its_zeros_are_allocated() {
    let mut b = bytes("skip_raw.fif");
    let at = tag_at(&b, 301, 0);
    put_i32(&mut b, at + 16, i32::MAX);
    let t0 = std::time::Instant::now();
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 16), "{e}");
    assert!(e.to_string().contains("FIFF_DATA_SKIP"), "{e}");
    assert!(t0.elapsed().as_secs() < 5);
    put_i32(&mut b, at + 16, -1);
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert_eq!(e.offset(), Some(at as u64 + 16), "{e}");
}

#[test]
fn split_parts_missing_cut_or_read_alone_are_errors_naming_them() {
    let dir = TempDir::new("fif-split");
    let names = [
        "split_raw.fif",
        "split_raw-1.fif",
        "split_raw-2.fif",
        "split_raw-3.fif",
    ];
    for n in names {
        dir.write(n, &bytes(n));
    }
    let whole = read(dir.join("split_raw.fif")).unwrap();
    assert_eq!(whole.raw.n_times(), 256);

    // From memory, a part that names a next one is refused.
    let e = parse_fif(&bytes("split_raw.fif"), Path::new("split_raw.fif")).unwrap_err();
    assert!(e.to_string().contains("split_raw-1.fif"), "{e}");

    // A cut part: the error names it.
    let b = bytes("split_raw-2.fif");
    dir.write("split_raw-2.fif", &b[..b.len() - 700]);
    let e = read_fif(dir.join("split_raw.fif")).unwrap_err();
    assert!(e.path().ends_with("split_raw-2.fif"), "{e}");
    assert!(e.offset().is_some(), "{e}");

    // A missing part: the error names it.
    std::fs::remove_file(dir.join("split_raw-2.fif")).unwrap();
    let e = read_fif(dir.join("split_raw.fif")).unwrap_err();
    assert!(e.to_string().contains("split_raw-2.fif"), "{e}");

    // A part that does not continue the one before (part 3 in place of part 2).
    dir.write("split_raw-2.fif", &bytes("split_raw-3.fif"));
    let e = read_fif(dir.join("split_raw.fif")).unwrap_err();
    assert!(e.to_string().contains("not 128"), "{e}");
}

#[test]
fn compressed_fif_is_refused_with_what_to_do() {
    let dir = TempDir::new("fif-gz");
    let gz = dir.write("rec_raw.fif.gz", &[0x1f, 0x8b, 8, 0, 0, 0, 0, 0]);
    let e = read(&gz).unwrap_err();
    assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    assert!(e.to_string().contains("decompress"), "{e}");
    let renamed = dir.write("rec_raw.fif", &[0x1f, 0x8b, 8, 0, 0, 0, 0, 0]);
    let e = read(&renamed).unwrap_err();
    assert!(e.to_string().contains("decompress"), "{e}");
}

#[test]
fn a_file_without_eeg_or_raw_data_says_so() {
    // Every channel made EOG (kind 202): nothing to keep.
    let mut b = bytes("float_raw.fif");
    let n = tags(&b).iter().filter(|t| t.0 == 203).count();
    for k in 0..n {
        let at = tag_at(&b, 203, k);
        if i32::from_be_bytes(b[at + 24..at + 28].try_into().unwrap()) == 2 {
            put_i32(&mut b, at + 24, 202);
        }
    }
    // The extended blocks (FIFF_CH_KIND, 252) say the kind again.
    for (kind, _, _, at) in tags(&b.clone()) {
        if kind == 252 && i32::from_be_bytes(b[at + 16..at + 20].try_into().unwrap()) == 2 {
            put_i32(&mut b, at + 16, 202);
        }
    }
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert!(e.to_string().contains("no EEG channel"), "{e}");

    // The raw data block renamed (as in an epochs file): no raw data.
    let mut b = bytes("float_raw.fif");
    for (kind, _, _, at) in tags(&b.clone()) {
        if (kind == 104 || kind == 105)
            && i32::from_be_bytes(b[at + 16..at + 20].try_into().unwrap()) == 102
        {
            put_i32(&mut b, at + 16, 104);
        }
    }
    let e = parse_fif(&b, Path::new("x.fif")).unwrap_err();
    assert!(e.to_string().contains("FIFFB_RAW_DATA"), "{e}");
}
