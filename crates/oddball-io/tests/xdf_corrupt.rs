//! XDF files corrupt in the middle (bytes overwritten, the length unchanged) are refused, naming
//! the byte and the field, where they used to read as a recording cut short; a file cut by its
//! end (a recorder killed while writing) still reads up to its last complete chunk. The file is
//! written as a live session writes it: 8 float32 channels at 500 Hz in blocks of 20 samples,
//! a marker every fifth block, a Boundary chunk every 10 s, footers at the end.

mod common;

use std::path::Path;

use common::{Rng, TempDir};
use ndarray::Array2;
use oddball_io::xdf::BOUNDARY_UUID;
use oddball_io::{parse_xdf, parse_xdf_file, IoError, XdfStream, XdfWriter};

const SFREQ: f64 = 500.0;
const BLOCK: usize = 20;

/// A session-like recording of `seconds`, its bytes and where its footers start.
fn session(dir: &TempDir, seconds: usize) -> (Vec<u8>, usize) {
    let path = dir.path().join(format!("s{seconds}.xdf"));
    let mut w = XdfWriter::create(&path).unwrap();
    let labels = (1..=8).map(|c| format!("E{c}")).collect();
    let e = w.add_stream(&XdfStream::eeg("EEG", labels, SFREQ)).unwrap();
    let m = w.add_stream(&XdfStream::markers("Markers")).unwrap();
    for b in 0..seconds * SFREQ as usize / BLOCK {
        let ts: Vec<f64> = (0..BLOCK).map(|i| (b * BLOCK + i) as f64 / SFREQ).collect();
        let d = Array2::from_shape_fn((8, BLOCK), |(c, i)| {
            ((b * BLOCK + i) as f64 * 0.01 + c as f64).sin() * 20.0
        });
        w.push_numeric(e, &ts, d.view()).unwrap();
        if b % 5 == 0 {
            w.push_strings(m, &[ts[0]], &["flash 1 target"]).unwrap();
        }
        w.flush_block().unwrap();
    }
    let footers = w.bytes_written() as usize;
    w.finish().unwrap();
    (std::fs::read(&path).unwrap(), footers)
}

/// Every chunk: (start, NumLengthBytes, Length, tag), walked independently of the reader.
fn chunks(b: &[u8]) -> Vec<(usize, usize, u64, u16)> {
    let mut out = Vec::new();
    let mut p = 4;
    while p < b.len() {
        let nlb = b[p] as usize;
        let mut len = [0u8; 8];
        len[..nlb].copy_from_slice(&b[p + 1..p + 1 + nlb]);
        let length = u64::from_le_bytes(len);
        let tag = u16::from_le_bytes([b[p + 1 + nlb], b[p + 2 + nlb]]);
        out.push((p, nlb, length, tag));
        p += 1 + nlb + length as usize;
    }
    assert_eq!(p, b.len());
    out
}

fn invalid_field(r: Result<oddball_io::Recording, IoError>) -> (u64, String, String) {
    match r {
        Err(e @ IoError::InvalidField { .. }) => {
            let text = e.to_string();
            let IoError::InvalidField { offset, field, .. } = e else {
                unreachable!()
            };
            (offset, field, text)
        }
        Err(e) => panic!("expected an invalid field, got {e}"),
        Ok(r) => panic!(
            "expected an error, read {} samples (truncated {})",
            r.raw.n_times(),
            r.xdf().unwrap().truncated
        ),
    }
}

/// The probe of issue #30: a Length overwritten a third into a 120 s recording read as 40 s of
/// it, with no word. Now: refused, naming the Length's byte and the Boundary chunk that follows.
#[test]
fn a_length_corrupt_a_third_in_is_refused_naming_the_byte_and_field() {
    let dir = TempDir::new("xdf-corrupt-third");
    let (good, _) = session(&dir, 120);
    assert_eq!(
        parse_xdf(&good, Path::new("good.xdf"))
            .unwrap()
            .raw
            .n_times(),
        60_000
    );
    let all = chunks(&good);
    let &(start, nlb, _, _) = all
        .iter()
        .find(|c| c.0 > good.len() / 3 && c.3 == 3)
        .unwrap();
    let mut bad = good.clone();
    bad[start + 1..start + 1 + nlb].fill(0xff);
    assert_eq!(bad.len(), good.len());
    let (offset, field, text) = invalid_field(parse_xdf(&bad, Path::new("bad.xdf")));
    eprintln!("{text}");
    assert_eq!(
        (offset, field.as_str()),
        ((start + 1) as u64, "chunk Length")
    );
    let boundary = all.iter().find(|c| c.0 > start && c.3 == 5).unwrap().0;
    assert!(
        text.contains(&format!(
            "Boundary chunk's bytes at byte offset {}",
            boundary + 4
        )),
        "{text}"
    );
    // From a file, through the one entry point: the same error.
    let path = dir.path().join("bad.xdf");
    std::fs::write(&path, &bad).unwrap();
    let err = oddball_io::read(&path).unwrap_err();
    assert!(err.to_string().contains("chunk Length"), "{err}");
}

/// Overwriting bytes a third into the file (1 to 1024 bytes of zeros, 0xff or noise): every
/// copy is refused or reads all of its 120 s; none reads as a recording cut short.
#[test]
fn overwrites_mid_file_never_read_as_a_shorter_recording() {
    let dir = TempDir::new("xdf-corrupt-overwrite");
    let (good, _) = session(&dir, 120);
    let mut rng = Rng(0x0dd_ba11_c0de);
    let (mut read, mut refused) = (0, 0);
    for k in 0..300 {
        let mut b = good.clone();
        let at = good.len() / 3 + rng.below(20_000);
        let len = [1usize, 3, 8, 64, 1024][k % 5];
        for x in &mut b[at..at + len] {
            *x = match k % 3 {
                0 => 0,
                1 => 0xff,
                _ => rng.next() as u8,
            };
        }
        match parse_xdf(&b, Path::new("m.xdf")) {
            Ok(r) => {
                assert!(!r.xdf().unwrap().truncated, "copy {k}: read as cut");
                assert_eq!(r.raw.n_times(), 60_000, "copy {k}");
                read += 1;
            }
            Err(_) => refused += 1,
        }
    }
    eprintln!("300 overwritten copies: {read} read whole (values changed), {refused} refused");
    assert!(refused > 0 && read > 0);
}

/// After the last Boundary chunk a corrupt Samples Length is found by the chunk's own samples:
/// they end before the file does.
#[test]
fn a_corrupt_length_after_the_last_boundary_is_found_by_its_samples() {
    let dir = TempDir::new("xdf-corrupt-last");
    let (good, footers) = session(&dir, 12);
    let all = chunks(&good);
    let last_boundary = all.iter().rfind(|c| c.3 == 5).unwrap().0;
    let &(start, nlb, length, _) = all
        .iter()
        .rfind(|c| c.0 > last_boundary && c.0 < footers && c.3 == 3)
        .unwrap();
    let mut bad = good.clone();
    bad[start + 1..start + 1 + nlb].copy_from_slice(&(1u32 << 30).to_le_bytes()[..nlb]);
    let (offset, field, text) = invalid_field(parse_xdf(&bad, Path::new("bad.xdf")));
    assert_eq!(
        (offset, field.as_str()),
        ((start + 1) as u64, "chunk Length")
    );
    let end = start + 1 + nlb + length as usize;
    assert!(
        text.contains(&format!("expected {length} "))
            && text.contains(&format!("byte offset {end},")),
        "{text}"
    );
    // A TimeStampBytes no sample can have inside such a chunk names that byte.
    let mut bad2 = bad.clone();
    let first_sample = start + 1 + nlb + 2 + 4 + 2;
    bad2[first_sample] = 7;
    let (offset, field, _) = invalid_field(parse_xdf(&bad2, Path::new("bad2.xdf")));
    assert_eq!(
        (offset, field.as_str()),
        (
            first_sample as u64,
            "Samples (stream 1) sample 0 TimeStampBytes"
        )
    );
}

/// A file cut anywhere in its last blocks (a recorder killed while writing) still reads, up to
/// its last complete chunk, and says it was cut.
#[test]
fn a_cut_in_the_last_blocks_still_reads() {
    let dir = TempDir::new("xdf-cut-end");
    let (good, footers) = session(&dir, 12);
    let all = chunks(&good);
    let ends: Vec<usize> = all.iter().map(|c| c.0 + 1 + c.1 + c.2 as usize).collect();
    let boundary = all.iter().rfind(|c| c.3 == 5).unwrap().0;
    for cut in (boundary - 600..boundary + 600).chain(footers - 2000..footers) {
        let rec = parse_xdf(&good[..cut], Path::new("cut.xdf"))
            .unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        let info = rec.xdf().unwrap();
        assert_eq!(info.truncated, !ends.contains(&cut), "cut at {cut}");
        assert_eq!(rec.raw.n_times() % BLOCK, 0, "cut at {cut}");
        assert!(!info.finished());
    }
}

/// ClockOffset and Boundary chunks have one length each: another one cut by the file's end is
/// corrupt; the right one cut is a cut.
#[test]
fn fixed_length_chunks_cut_by_the_end() {
    let dir = TempDir::new("xdf-fixed");
    let (good, footers) = session(&dir, 1);
    let body = &good[..footers];
    let with = |tail: &[u8]| [body, tail].concat();
    // A ClockOffset of 22 bytes, 9 of them there: cut.
    let f = parse_xdf_file(&with(&[1, 22, 4, 0, 1, 0, 0, 0, 0]), Path::new("c.xdf")).unwrap();
    assert!(f.truncated && f.truncated_at == Some(footers as u64));
    // A ClockOffset claiming 200 bytes: corrupt.
    let (offset, field, _) = invalid_field(parse_xdf(
        &with(&[1, 200, 4, 0, 1, 0, 0, 0, 0]),
        Path::new("c.xdf"),
    ));
    assert_eq!(
        (offset, field.as_str()),
        (footers as u64 + 1, "ClockOffset chunk Length")
    );
    // A Boundary of 18 bytes cut in its UUID: cut; claiming 100 bytes: corrupt.
    let mut t = vec![1, 18, 5, 0];
    t.extend_from_slice(&BOUNDARY_UUID[..7]);
    assert!(
        parse_xdf_file(&with(&t), Path::new("b.xdf"))
            .unwrap()
            .truncated
    );
    t[1] = 100;
    let (_, field, _) = invalid_field(parse_xdf(&with(&t), Path::new("b.xdf")));
    assert_eq!(field, "Boundary chunk Length");
    // A cut Samples chunk for a stream with no header: corrupt.
    let (_, field, _) = invalid_field(parse_xdf(
        &with(&[4, 0, 1, 0, 0, 3, 0, 9, 0, 0, 0, 1]),
        Path::new("s.xdf"),
    ));
    assert_eq!(field, "Samples StreamId");
}

/// A Samples chunk whose tag is corrupted into one the reader does not know is skipped: in a
/// finished file the footer's sample count then disagrees with the samples read, and the file
/// is refused; in a file without footers it is counted as an unknown chunk (all a reader can
/// tell).
#[test]
fn a_samples_chunk_lost_to_a_corrupt_tag_is_found_by_the_footer_count() {
    let dir = TempDir::new("xdf-lost-chunk");
    let (good, footers) = session(&dir, 12);
    let all = chunks(&good);
    let &(start, nlb, _, _) = all
        .iter()
        .find(|c| c.0 > good.len() / 2 && c.3 == 3)
        .unwrap();
    let mut bad = good.clone();
    bad[start + 1 + nlb] = 77;
    let (offset, field, text) = invalid_field(parse_xdf(&bad, Path::new("lost.xdf")));
    assert_eq!(field, "StreamFooter (stream 1) sample_count");
    let at = footers
        + good[footers..]
            .windows(14)
            .position(|w| w == b"<sample_count>")
            .unwrap()
        + 14;
    assert_eq!(offset, at as u64);
    assert!(
        text.contains("the 5980 samples read") && text.ends_with("found \"6000\""),
        "{text}"
    );
    let unfinished = parse_xdf_file(&bad[..footers], Path::new("lost.xdf")).unwrap();
    assert_eq!(unfinished.n_unknown_chunks, 1);
    assert_eq!(unfinished.stream(1).unwrap().timestamps.len(), 5980);
}
