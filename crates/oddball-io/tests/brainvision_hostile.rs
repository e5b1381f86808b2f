//! Hostile BrainVision input: a data file cut at every byte, header and marker files cut at
//! every byte, absurd counts and rates, bad fields (each error naming its byte offset), data and
//! marker files that leave the header's folder or are not regular files, and thousands of seeded
//! random mutations of all three files. Never a panic, never a recording with fewer samples than
//! the header says.

mod common;

use std::path::Path;

use common::{fixture, Rng, TempDir};
use oddball_io::{parse_brainvision, read, IoError};

const INTERESTING: &[&[u8]] = &[
    b"0",
    b"-1",
    b"99999999999999999999",
    b"\\1",
    b",",
    b"=",
    b"\r\n",
    b"\n[Channel Infos]\n",
    b"\n[Marker Infos]\n",
    b"nan",
    b"\xb5",
    b"\xff",
    b"Mk99=Stimulus,S  1,",
    b"Ch9=",
];

fn files(stem: &str) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let f = |ext: &str| std::fs::read(fixture(&format!("brainvision/{stem}.{ext}"))).unwrap();
    (f("vhdr"), f("vmrk"), f("eeg"))
}

fn path(stem: &str) -> std::path::PathBuf {
    fixture(&format!("brainvision/{stem}.vhdr"))
}

/// `text` with `from` (which must occur exactly once) replaced by `to`.
fn replace(text: &[u8], from: &str, to: &str) -> Vec<u8> {
    let s = std::str::from_utf8(text).expect("a UTF-8 fixture");
    assert_eq!(s.matches(from).count(), 1, "{from:?}");
    s.replacen(from, to, 1).into_bytes()
}

/// The byte offset of `needle` in `hay`.
fn find(hay: &[u8], needle: &str) -> u64 {
    hay.windows(needle.len())
        .position(|w| w == needle.as_bytes())
        .unwrap() as u64
}

#[test]
fn a_data_file_cut_anywhere_is_an_error_naming_the_sample() {
    // With DataPoints (and VECTORIZED INT_32): every cut is an error.
    let (vhdr, vmrk, eeg) = files("hand_int32_vec");
    let p = path("hand_int32_vec");
    for k in 0..eeg.len() {
        let e = parse_brainvision(&vhdr, &p, &eeg[..k], Some(&vmrk)).unwrap_err();
        assert!(matches!(e, IoError::Truncated { .. }), "cut at {k}: {e}");
        assert_eq!(e.offset(), Some(k as u64), "{e}");
        assert!(e.to_string().contains("hand_int32_vec.eeg"), "{e}");
    }
    let mut long = eeg.clone();
    long.extend_from_slice(&[0; 4]);
    let e = parse_brainvision(&vhdr, &p, &long, Some(&vmrk)).unwrap_err();
    assert_eq!(e.offset(), Some(eeg.len() as u64), "{e}");

    // Without DataPoints (pybv, MULTIPLEXED float32): a cut inside a sample is an error naming
    // the sample's byte offset; the file's length is all that says how long the recording is,
    // so a cut between samples reads as exactly the samples that are there.
    let (vhdr, vmrk, eeg) = files("mne_float32");
    let p = path("mne_float32");
    let frame = 5 * 4;
    for k in 0..eeg.len() {
        match parse_brainvision(&vhdr, &p, &eeg[..k], Some(&vmrk)) {
            Ok(rec) => {
                assert_eq!(k % frame, 0, "cut at {k} accepted");
                assert_eq!(rec.raw.n_times(), k / frame);
            }
            Err(e) => {
                if k % frame != 0 {
                    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
                    assert_eq!(e.offset(), Some((k / frame * frame) as u64), "{e}");
                    assert!(
                        e.to_string().contains(&format!("sample {}", k / frame)),
                        "{e}"
                    );
                }
            }
        }
    }
}

#[test]
fn header_and_marker_files_cut_anywhere_never_panic_nor_lose_samples() {
    for stem in ["mne_float32", "pybv_int16", "hand_int32_vec"] {
        let (vhdr, vmrk, eeg) = files(stem);
        let p = path(stem);
        let full = parse_brainvision(&vhdr, &p, &eeg, Some(&vmrk)).unwrap();
        let (n_ch, n_times) = (full.raw.n_channels(), full.raw.n_times());
        for k in 0..vhdr.len() {
            match parse_brainvision(&vhdr[..k], &p, &eeg, Some(&vmrk)) {
                Ok(rec) => {
                    assert_eq!((rec.raw.n_channels(), rec.raw.n_times()), (n_ch, n_times));
                }
                Err(e) => {
                    if let Some(at) = e.offset() {
                        assert!(at <= vhdr.len() as u64 + eeg.len() as u64, "{e}");
                    }
                }
            }
        }
        for k in 0..vmrk.len() {
            match parse_brainvision(&vhdr, &p, &eeg, Some(&vmrk[..k])) {
                Ok(rec) => {
                    assert_eq!(rec.raw.n_times(), n_times);
                    assert!(rec.raw.events().len() <= full.raw.events().len());
                }
                Err(e) => {
                    if let Some(at) = e.offset() {
                        assert!(at <= k as u64, "{stem} cut at {k}: {e}");
                    }
                }
            }
        }
    }
}

#[test]
fn absurd_counts_rates_and_bad_fields_are_refused_at_their_offset() {
    let (vhdr, vmrk, eeg) = files("mne_float32");
    let p = path("mne_float32");
    let header_cases = [
        (
            "NumberOfChannels=5",
            "NumberOfChannels=4000000000",
            "NumberOfChannels",
        ),
        (
            "NumberOfChannels=5",
            "NumberOfChannels=0",
            "NumberOfChannels",
        ),
        (
            "NumberOfChannels=5",
            "NumberOfChannels=6",
            "NumberOfChannels",
        ),
        (
            "NumberOfChannels=5",
            "NumberOfChannels=-5",
            "NumberOfChannels",
        ),
        (
            "SamplingInterval=2000.0",
            "SamplingInterval=0",
            "SamplingInterval",
        ),
        (
            "SamplingInterval=2000.0",
            "SamplingInterval=-4",
            "SamplingInterval",
        ),
        (
            "SamplingInterval=2000.0",
            "SamplingInterval=nan",
            "SamplingInterval",
        ),
        (
            "SamplingInterval=2000.0",
            "SamplingInterval=inf",
            "SamplingInterval",
        ),
        (
            "BinaryFormat=IEEE_FLOAT_32",
            "BinaryFormat=INT_64",
            "BinaryFormat",
        ),
        (
            "DataOrientation=MULTIPLEXED",
            "DataOrientation=SIDEWAYS",
            "DataOrientation",
        ),
        ("DataFormat=BINARY", "DataFormat=PACKED", "DataFormat"),
        ("Ch3=Cz,,0.1,µV", "Ch3=Cz,,zero,µV", "Ch3=Cz,,"),
        ("Ch3=Cz,,0.1,µV", "Ch3=,,0.1,µV", "Ch3="),
        ("Ch3=Cz,,0.1,µV", "Ch3=Cz,,1e999,µV", "Ch3=Cz,,"),
        ("DataFile=mne_float32.eeg", "DataFile=", "DataFile"),
    ];
    for (from, to, key) in header_cases {
        let bad = replace(&vhdr, from, to);
        let e = parse_brainvision(&bad, &p, &eeg, Some(&vmrk)).unwrap_err();
        let value_at = find(&bad, key) + key.len() as u64 + u64::from(!key.ends_with(['=', ',']));
        assert!(matches!(e, IoError::InvalidField { .. }), "{to}: {e}");
        assert_eq!(e.offset(), Some(value_at), "{to}: {e}");
    }
    // A header count of samples far beyond the file: refused from the length alone.
    let bad = replace(
        &vhdr,
        "NumberOfChannels=5",
        "NumberOfChannels=5\nDataPoints=18446744073709551615",
    );
    let e = parse_brainvision(&bad, &p, &eeg, Some(&vmrk)).unwrap_err();
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
    let e = parse_brainvision(&replace(&vhdr, "BINARY", "ASCII"), &p, &eeg, None).unwrap_err();
    assert!(matches!(e, IoError::Unsupported { .. }), "{e}");
    let bad = replace(&vhdr, "Ch5=Oz,,0.1,µV", "");
    let e = parse_brainvision(&bad, &p, &eeg, None).unwrap_err();
    assert!(e.to_string().contains("NumberOfChannels"), "{e}");
    let e = parse_brainvision(b"Not a header\n", &p, &eeg, None).unwrap_err();
    assert_eq!(e.offset(), Some(0), "{e}");

    let marker_cases = [
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,0,1,0",
            "Mk2=Stimulus,S  1,",
        ),
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,-3,1,0",
            "Mk2=Stimulus,S  1,",
        ),
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,x,1,0",
            "Mk2=Stimulus,S  1,",
        ),
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,99999999999999999999,1,0",
            "Mk2=Stimulus,S  1,",
        ),
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,11,-1,0",
            "Mk2=Stimulus,S  1,11,",
        ),
        (
            "Mk2=Stimulus,S  1,11,1,0",
            "Mk2=Stimulus,S  1,11,1,q",
            "Mk2=Stimulus,S  1,11,1,",
        ),
        ("Mk2=Stimulus,S  1,11,1,0", "Mk2=Stimulus,S  1", "Mk2="),
    ];
    for (from, to, key) in marker_cases {
        let bad = replace(&vmrk, from, to);
        let e = parse_brainvision(&vhdr, &p, &eeg, Some(&bad)).unwrap_err();
        assert!(matches!(e, IoError::InvalidField { .. }), "{to}: {e}");
        assert_eq!(
            e.offset(),
            Some(find(&bad, key) + key.len() as u64),
            "{to}: {e}"
        );
        assert!(e.to_string().contains("mne_float32.vmrk"), "{e}");
    }
    // A marker beyond the data is kept, but is no event.
    let far = replace(&vmrk, "Mk6=Stimulus,S  1,76,", "Mk6=Stimulus,S  1,1000,");
    let rec = parse_brainvision(&vhdr, &p, &eeg, Some(&far)).unwrap();
    assert_eq!(rec.raw.events().len(), 3);
    assert_eq!(rec.brainvision().unwrap().markers[5].onset, 999);
}

#[test]
fn linked_files_stay_in_the_folder_and_must_be_regular_files() {
    let (vhdr, vmrk, eeg) = files("mne_float32");
    let dir = TempDir::new("bv_paths");
    dir.write("rec.eeg", &eeg);
    dir.write("rec.vmrk", &vmrk);
    let header = |data: &str, marker: &str| {
        let h = replace(
            &vhdr,
            "DataFile=mne_float32.eeg",
            &format!("DataFile={data}"),
        );
        replace(
            &h,
            "MarkerFile=mne_float32.vmrk",
            &format!("MarkerFile={marker}"),
        )
    };
    let good = dir.write("good.vhdr", &header("rec.eeg", "rec.vmrk"));
    let rec = read(&good).unwrap();
    assert_eq!(rec.raw.n_times(), 100);
    assert_eq!(rec.raw.events().len(), 4);

    for (data, marker) in [
        ("../rec.eeg", "rec.vmrk"),
        ("/etc/hostname", "rec.vmrk"),
        ("rec.eeg", "../rec.vmrk"),
        ("rec.eeg", "/dev/null"),
    ] {
        let p = dir.write("bad.vhdr", &header(data, marker));
        let e = read(&p).unwrap_err();
        assert!(
            matches!(e, IoError::InvalidField { .. }),
            "{data} {marker}: {e}"
        );
        assert!(e.to_string().contains("no `..`"), "{e}");
    }
    let p = dir.write("missing.vhdr", &header("rec.eeg", "gone.vmrk"));
    let e = read(&p).unwrap_err();
    assert!(matches!(e, IoError::NotFound { .. }), "{e}");
    assert!(e.to_string().contains("gone.vmrk"), "{e}");
    let p = dir.write(
        "nomarkers.vhdr",
        &replace(&vhdr, "MarkerFile=mne_float32.vmrk", ""),
    );
    std::fs::copy(dir.join("rec.eeg"), dir.join("mne_float32.eeg")).unwrap();
    let rec = read(&p).unwrap();
    assert!(rec.raw.events().is_empty());
    assert_eq!(rec.brainvision().unwrap().marker_file, None);
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.eeg")).unwrap();
        let p = dir.write("zero.vhdr", &header("zero.eeg", "rec.vmrk"));
        let e = read(&p).unwrap_err();
        assert!(matches!(e, IoError::NotRegular { .. }), "{e}");
    }
}

#[test]
fn mutated_files_never_panic() {
    let n = std::env::var("ODDBALL_FUZZ_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000usize);
    let mut rng = Rng(0xB7_0001);
    let (mut ok, mut err) = (0, 0);
    for stem in ["mne_float32", "pybv_int16", "hand_int32_vec"] {
        let (vhdr, vmrk, eeg) = files(stem);
        let p = Path::new("fuzz.vhdr");
        for i in 0..n {
            let (h, m, d) = match i % 3 {
                0 => (
                    common::mutate(&mut rng, &vhdr, INTERESTING),
                    vmrk.clone(),
                    eeg.clone(),
                ),
                1 => (
                    vhdr.clone(),
                    common::mutate(&mut rng, &vmrk, INTERESTING),
                    eeg.clone(),
                ),
                _ => (
                    vhdr.clone(),
                    vmrk.clone(),
                    common::mutate(&mut rng, &eeg, INTERESTING),
                ),
            };
            match parse_brainvision(&h, p, &d, Some(&m)) {
                Ok(rec) => {
                    ok += 1;
                    assert!(rec.raw.events().iter().all(|e| e.onset < rec.raw.n_times()));
                }
                Err(e) => {
                    err += 1;
                    let s = e.to_string();
                    assert!(s.contains("fuzz") || s.contains(stem), "{s}");
                }
            }
        }
    }
    assert!(err > 0 && ok > 0, "{ok} accepted, {err} refused");
}
