//! Hostile EEGLAB input: a `.fdt` cut at every byte or too long, `.set` files cut at every
//! byte, absurd `nbchan` / `pnts` / `srate` (refused before anything is allocated), data of the
//! wrong shape, a data file name leaving the folder, and thousands of seeded random mutations.
//! Never a panic, never a recording with fewer samples than `EEG.pnts`.

mod common;

use std::path::Path;

use common::{fixture, Rng, TempDir};
use oddball_io::{parse_eeglab, read, IoError};

const INTERESTING: &[&[u8]] = &[
    b"\x00\x00\x00\x00\x00\x00\xf0\x7f",
    b"\xff\xff\xff\xff",
    b"\x00\x00\x00\x00",
    b"\x01",
    b"\x0e\x00\x00\x00",
    b"\x02",
    b"\x06",
];

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(fixture(&format!("eeglab/{name}"))).unwrap()
}

/// `hay` with the little-endian f64 `from` (which must occur exactly once) replaced by `to`.
fn patch_f64(hay: &[u8], from: f64, to: f64) -> Vec<u8> {
    let f = from.to_le_bytes();
    let at: Vec<usize> = hay
        .windows(8)
        .enumerate()
        .filter(|(_, w)| *w == f)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(at.len(), 1, "{from} occurs {} times", at.len());
    let mut out = hay.to_vec();
    out[at[0]..at[0] + 8].copy_from_slice(&to.to_le_bytes());
    out
}

#[test]
fn an_fdt_cut_anywhere_is_an_error_naming_the_sample() {
    let set = bytes("struct_fdt.set");
    let fdt = bytes("struct_fdt.fdt");
    let p = fixture("eeglab/struct_fdt.set");
    let frame = 3 * 4;
    assert_eq!(fdt.len(), frame * 50);
    for k in 0..fdt.len() {
        let e = parse_eeglab(&set, &p, Some(&fdt[..k])).unwrap_err();
        assert!(matches!(e, IoError::Truncated { .. }), "cut at {k}: {e}");
        assert_eq!(e.offset(), Some((k / frame * frame) as u64), "{e}");
        assert!(
            e.to_string()
                .contains(&format!("sample {} of 50", k / frame)),
            "{e}"
        );
        assert!(e.to_string().contains("struct_fdt.fdt"), "{e}");
    }
    let mut long = fdt.clone();
    long.push(0);
    let e = parse_eeglab(&set, &p, Some(&long)).unwrap_err();
    assert!(matches!(e, IoError::InvalidField { .. }), "{e}");
    assert_eq!(e.offset(), Some(fdt.len() as u64));
    let e = parse_eeglab(&set, &p, None).unwrap_err();
    assert!(matches!(e, IoError::Missing { .. }), "{e}");
}

#[test]
fn a_set_cut_anywhere_never_panics_nor_loses_samples() {
    // The struct layout is one variable: any cut is an error.
    let set = bytes("struct_fdt.set");
    let fdt = bytes("struct_fdt.fdt");
    let p = Path::new("cut.set");
    for k in 0..set.len() {
        let e = parse_eeglab(&set[..k], p, Some(&fdt)).unwrap_err();
        if let Some(at) = e.offset() {
            assert!(at <= k as u64, "cut at {k}: {e}");
        }
    }
    // Top-level variables: MAT files hold no count of variables, so a cut exactly between two
    // variables after the required ones reads; the samples are then all there.
    let set = bytes("mne_export.set");
    let (mut ok, mut err) = (0, 0);
    for k in 0..set.len() {
        match parse_eeglab(&set[..k], p, None) {
            Ok(rec) => {
                ok += 1;
                assert_eq!((rec.raw.n_channels(), rec.raw.n_times()), (4, 120));
            }
            Err(e) => {
                err += 1;
                assert!(e.to_string().contains("cut.set"), "{e}");
            }
        }
    }
    assert!(ok < 10 && err > set.len() - 10, "{ok} cuts read");
}

#[test]
fn absurd_counts_and_rates_are_refused_before_allocation() {
    let set = bytes("struct_fdt.set");
    let fdt = bytes("struct_fdt.fdt");
    let p = fixture("eeglab/struct_fdt.set");
    // nbchan × pnts far beyond the .fdt: the length check refuses it, nothing allocated.
    for (from, to) in [(50.0, 4e9), (3.0, 4e9)] {
        let bad = patch_f64(&set, from, to);
        let e = parse_eeglab(&bad, &p, Some(&fdt)).unwrap_err();
        assert!(matches!(e, IoError::Truncated { .. }), "{to}: {e}");
    }
    for (from, to, field) in [
        (50.0, 0.0, "EEG.pnts"),
        (50.0, 2.5, "EEG.pnts"),
        (50.0, f64::NAN, "EEG.pnts"),
        (50.0, 1e300, "EEG.pnts"),
        (3.0, -3.0, "EEG.nbchan"),
        (200.0, 0.0, "EEG.srate"),
        (200.0, f64::INFINITY, "EEG.srate"),
        (200.0, -200.0, "EEG.srate"),
    ] {
        let bad = patch_f64(&set, from, to);
        let e = parse_eeglab(&bad, &p, Some(&fdt)).unwrap_err();
        assert!(matches!(e, IoError::InvalidField { .. }), "{to}: {e}");
        assert!(e.to_string().contains(field), "{e}");
        // The struct variable EEG starts right after the 128-byte header.
        assert_eq!(e.offset(), Some(128), "{e}");
    }
    // Data inside the .set of another shape than nbchan × pnts.
    let set = bytes("mne_export.set");
    for (from, to) in [(120.0, 121.0), (4.0, 5.0), (120.0, 60.0)] {
        let bad = patch_f64(&set, from, to);
        let e = parse_eeglab(&bad, Path::new("x.set"), None).unwrap_err();
        assert!(matches!(e, IoError::InvalidField { .. }), "{to}: {e}");
        assert!(
            e.to_string().contains("EEG.data") || e.to_string().contains("chanlocs"),
            "{e}"
        );
    }
}

#[test]
fn a_data_name_leaving_the_folder_is_refused() {
    let set = bytes("struct_fdt.set");
    let dir = TempDir::new("eeglab_paths");
    // Same length as "struct_fdt.fdt", so the MAT layout stays valid.
    for name in ["../struct_f.fdt", "/etc/hostnamee"] {
        let name = &name[..14.min(name.len())];
        let mut bad = set.clone();
        let at = set
            .windows(14)
            .position(|w| w == b"struct_fdt.fdt")
            .unwrap();
        bad[at..at + 14].copy_from_slice(format!("{name:<14}").as_bytes());
        let p = dir.write("x.set", &bad);
        let e = read(&p).unwrap_err();
        assert!(matches!(e, IoError::InvalidField { .. }), "{name}: {e}");
        assert!(e.to_string().contains("no `..`"), "{e}");
    }
}

#[test]
fn mutated_files_never_panic() {
    let n = std::env::var("ODDBALL_FUZZ_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000usize);
    let mut rng = Rng(0xEE_0001);
    let fdt = bytes("struct_fdt.fdt");
    let p = Path::new("fuzz.set");
    let (mut ok, mut err) = (0, 0);
    for name in ["struct_fdt.set", "mne_export.set"] {
        let set = bytes(name);
        for i in 0..n {
            let (s, f) = if i % 4 == 3 {
                (set.clone(), common::mutate(&mut rng, &fdt, INTERESTING))
            } else {
                (common::mutate(&mut rng, &set, INTERESTING), fdt.clone())
            };
            match parse_eeglab(&s, p, Some(&f)) {
                Ok(rec) => {
                    ok += 1;
                    assert!(rec.raw.events().iter().all(|e| e.onset < rec.raw.n_times()));
                }
                Err(e) => {
                    err += 1;
                    // The .set's name, or the .fdt's for an error in the .fdt.
                    let s = e.to_string();
                    assert!(
                        s.contains("fuzz.set") || s.contains("struct_fdt.fdt"),
                        "{s}"
                    );
                }
            }
        }
    }
    assert!(err > 0 && ok > 0, "{ok} accepted, {err} refused");
}
