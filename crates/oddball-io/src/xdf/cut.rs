//! Telling a file cut by its end from a corrupt one.
//!
//! A recorder killed while writing leaves one partial chunk at the end of its file: the bytes
//! after that chunk's header are a prefix of its content, and nothing follows. When a chunk's
//! Length runs past the end of the file, its bytes are checked for what a cut chunk cannot
//! hold, and any of these makes the file corrupt, not cut (an [`IoError::InvalidField`] naming
//! the byte and the field) where it would otherwise read as a shorter recording:
//!
//! * the 16 bytes of a Boundary chunk anywhere after the chunk's header: the file goes on (the
//!   live writer puts one every [`BOUNDARY_INTERVAL_S`] of data, so a Length corrupted
//!   anywhere but in a recording's last seconds is found this way);
//! * a Samples chunk whose samples, walked one by one, end before the file does or hold a
//!   byte no sample can (a TimeStampBytes other than 0 or 8, a bad varlen integer): its
//!   Length disagrees with its own content;
//! * a ClockOffset or Boundary chunk whose Length is not the fixed length of its kind;
//! * a Samples, ClockOffset or StreamFooter chunk for a stream without StreamHeader.
//!
//! And once every chunk is read, a StreamFooter's `sample_count` must agree with the samples
//! read for its stream, give or take one (LabRecorder's footers counted one sample short before
//! its pull request 123 of 2025): a chunk lost on the way (a corrupt tag read as an unknown
//! chunk and skipped) does not go unnoticed in a finished file.

use std::collections::BTreeMap;

use crate::IoError;

use super::acc::{Acc, Ctx};
use super::chunk::{le_u32, varlen};
use super::types::*;

/// How the samples of a chunk cut by the file's end lie in the bytes there are.
enum Extent {
    /// The samples end at this offset in the content.
    Ends(usize),
    /// The bytes end inside a sample: a cut.
    Cut,
    /// A byte no sample can hold: (offset in the content, field, expected, found).
    Bad(usize, String, &'static str, String),
}

/// Walks the samples of a Samples chunk's `content` (stream id first) as far as its bytes go.
fn samples_extent(content: &[u8], acc: &Acc) -> Extent {
    let n_ch = acc.info.channel_count;
    let format = acc.info.format;
    let at_varlen = |p: usize, what: String| -> Result<(u64, usize), Extent> {
        match content.get(p) {
            None => Err(Extent::Cut),
            Some(1 | 4 | 8) => varlen(content, p).map_err(|_| Extent::Cut),
            Some(&b) => Err(Extent::Bad(
                p,
                what,
                "a varlen integer (1, 4 or 8 bytes)",
                format!("byte count {b}"),
            )),
        }
    };
    let (n, mut p) = match at_varlen(4, "NumSamples".into()) {
        Ok(v) => v,
        Err(e) => return e,
    };
    // Every sample takes at least one byte: the walk ends within the content's length.
    for k in 0..n {
        let Some(&tsb) = content.get(p) else {
            return Extent::Cut;
        };
        p += match tsb {
            0 => 1,
            8 => 9,
            other => {
                return Extent::Bad(
                    p,
                    format!("sample {k} TimeStampBytes"),
                    "0 or 8",
                    other.to_string(),
                )
            }
        };
        match format.value_bytes() {
            Some(vb) => p += n_ch * vb,
            None => {
                for c in 0..n_ch {
                    let (len, q) =
                        match at_varlen(p, format!("sample {k} channel {c} string length")) {
                            Ok(v) => v,
                            Err(e) => return e,
                        };
                    let Some(end) = usize::try_from(len).ok().and_then(|l| q.checked_add(l)) else {
                        return Extent::Cut;
                    };
                    p = end;
                    if p > content.len() {
                        return Extent::Cut;
                    }
                }
            }
        }
        if p > content.len() {
            return Extent::Cut;
        }
    }
    Extent::Ends(p)
}

/// Whether the chunk starting at byte `start` (its tag at `header_end`), whose `length` runs
/// past the end of `bytes`, is a chunk cut by the file's end; `Err` when its bytes say the
/// file is corrupt there (see the module documentation).
pub(super) fn check_cut_chunk(
    ctx: &Ctx<'_>,
    bytes: &[u8],
    start: usize,
    header_end: usize,
    length: u64,
    index: &BTreeMap<u32, usize>,
    accs: &[Acc],
) -> Result<(), IoError> {
    let left = bytes.len() - header_end;
    let length_at = start + 1;
    if let Some(q) = bytes[header_end..]
        .windows(BOUNDARY_UUID.len())
        .position(|w| w == BOUNDARY_UUID)
    {
        return Err(ctx.invalid(
            length_at,
            "chunk Length",
            format!(
                "at most the {left} bytes left in the file (a chunk cut by the file's end is its last, but this file goes on: a Boundary chunk's bytes at byte offset {})",
                header_end + q
            ),
            length.to_string(),
        ));
    }
    let tag = u16::from_le_bytes([bytes[header_end], bytes[header_end + 1]]);
    let cbase = header_end + 2;
    let content = &bytes[cbase..];
    let fixed = match tag {
        TAG_CLOCK_OFFSET => Some(("ClockOffset", 22)),
        TAG_BOUNDARY => Some(("Boundary", 18)),
        _ => None,
    };
    if let Some((what, want)) = fixed.filter(|&(_, want)| length != want) {
        return Err(ctx.invalid(
            length_at,
            format!("{what} chunk Length"),
            format!("{want} (a {what} chunk has a fixed length)"),
            length.to_string(),
        ));
    }
    if !matches!(tag, TAG_SAMPLES | TAG_STREAM_FOOTER) || content.len() < 4 {
        return Ok(());
    }
    let id = le_u32(content, 0);
    let what = if tag == TAG_SAMPLES {
        "Samples"
    } else {
        "StreamFooter"
    };
    let Some(&k) = index.get(&id) else {
        return Err(ctx.invalid(
            cbase,
            format!("{what} StreamId"),
            "the id of a stream whose StreamHeader came before",
            id.to_string(),
        ));
    };
    if tag != TAG_SAMPLES {
        return Ok(());
    }
    let field = |f: &str| format!("Samples (stream {id}) {f}");
    match samples_extent(content, &accs[k]) {
        Extent::Cut => Ok(()),
        Extent::Ends(p) => Err(ctx.invalid(
            length_at,
            "chunk Length",
            format!(
                "{} (tag and content: the chunk's samples end at byte offset {}, and the file goes on to byte {})",
                p + 2,
                cbase + p,
                bytes.len()
            ),
            length.to_string(),
        )),
        Extent::Bad(at, f, expected, found) => {
            Err(ctx.invalid(cbase + at, field(&f), expected, found))
        }
    }
}

/// A StreamFooter's `sample_count` agrees with the samples read, give or take one.
pub(super) fn check_footer_count(ctx: &Ctx<'_>, acc: &Acc) -> Result<(), IoError> {
    let info = &acc.info;
    let (Some(count), Some(at)) = (
        info.footer.as_ref().and_then(|f| f.sample_count),
        acc.footer_count_at,
    ) else {
        return Ok(());
    };
    let read = info.n_samples as u64;
    if count.abs_diff(read) > 1 {
        return Err(ctx.invalid(
            at,
            format!("StreamFooter (stream {}) sample_count", info.id),
            format!(
                "the {read} samples read from the stream's {} Samples chunks (±1): chunks of it are missing or corrupt",
                info.n_sample_chunks
            ),
            count.to_string(),
        ));
    }
    Ok(())
}
