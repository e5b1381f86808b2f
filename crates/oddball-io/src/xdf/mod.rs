//! XDF (Extensible Data Format), the recording format of the Lab Streaming Layer (LabRecorder):
//! a writer made for live sessions ([`XdfWriter`]), an offline writer ([`write_xdf`]) and a
//! reader ([`read_xdf`], [`read_xdf_file`]), written from scratch.
//!
//! # Why here
//! One Rust crate reads XDF, `xdf` (0.1.0 on crates.io, 2024; judged from its docs and GitHub
//! source): `XDFFile::from_bytes` does read a file from memory, but it parses the chunks with a
//! `nom` `many0` loop, so the bytes of a chunk cut by a killed recorder are left over and only
//! logged as a `tracing` warning (the caller gets no flag), and its errors (`XDFError`) carry no
//! byte offset or field; it needs `nom`, `xmltree` and `tracing`, and 0.1.0 writes nothing. XDF
//! is a handful of chunk types, so this module parses them itself, keeps every complete chunk of
//! a cut file, reports the cut, and names the byte offset and field of anything corrupt. The XML
//! of headers and footers is read with `roxmltree` (well kept, no dependencies); its errors'
//! (row, column) positions are turned back into byte offsets from the file start, so a bad
//! header still names the byte at fault. It is checked against a file written by an independent
//! Python `struct` writer and against pyxdf (`tools/golden/xdf/`).
//!
//! # Format (XDF 1.0, <https://github.com/sccn/xdf/wiki/Specifications>)
//! The magic code `XDF:`, then chunks `[NumLengthBytes u8: 1, 4 or 8][Length, little-endian,
//! counting tag and content][Tag u16][content]`:
//!
//! | tag | chunk | content |
//! |---|---|---|
//! | 1 | FileHeader | XML `<info><version>1.0</version></info>` |
//! | 2 | StreamHeader | `u32` StreamId, XML `<info>` (name, type, channel_count, nominal_srate, channel_format, source_id, created_at, desc/channels/channel/{label, unit, type}) |
//! | 3 | Samples | `u32` StreamId, varlen NumSamples, per sample: `u8` TimeStampBytes (0 or 8), [`f64` timestamp], the values (numbers little-endian; strings: varlen byte length + UTF-8) |
//! | 4 | ClockOffset | `u32` StreamId, `f64` CollectionTime, `f64` OffsetValue |
//! | 5 | Boundary | 16 fixed bytes ([`BOUNDARY_UUID`]) |
//! | 6 | StreamFooter | `u32` StreamId, XML `<info>` (first_timestamp, last_timestamp, sample_count, clock_offsets) |
//!
//! A varlen integer is `[1, 4 or 8][that many bytes, little-endian]`. A sample without a
//! timestamp has the previous sample's timestamp plus `1 / nominal_srate` (pyxdf's rule; plus 0
//! for irregular streams, 0 before the first).
//!
//! # Writing a live session ([`XdfWriter`])
//! [`XdfWriter::create`] writes the magic code and the FileHeader at once. Streams are added
//! with [`XdfWriter::add_stream`] (stream ids 1, 2, …); samples go into memory with
//! [`XdfWriter::push_numeric`] and [`XdfWriter::push_strings`] (every sample with its own 8-byte
//! timestamp). [`XdfWriter::flush_block`] turns everything buffered into whole chunks (StreamHeaders
//! not yet written, one Samples chunk per stream with new samples, ClockOffsets, and a Boundary
//! chunk when 10 s of data have passed since the last one) and hands them to the operating
//! system with one `write_all` and a `flush`: a process killed at any moment (`kill -9`) leaves
//! the chunks of every completed block on disk and loses only what was buffered since; a kill
//! inside the `write` system call can leave one partial chunk at the end, which the reader drops
//! and reports. (The OS writes its cache to the disk later; [`XdfWriter::sync`] forces that, for
//! power failures.) [`XdfWriter::finish`] flushes, writes one StreamFooter per stream and syncs.
//! Dropping an unfinished writer flushes what it holds (without footers). Every push is checked
//! before anything is buffered: non-finite timestamps, a wrong channel or sample count, a value
//! that does not fit the stream's number type (integers: finite and in range after rounding;
//! float32: within its range; NaN and ±inf are stored as they are in float formats).
//!
//! [`write_xdf`] writes a [`Raw`](oddball_signal::Raw) (and its events as a string marker stream, each as
//! [`crate::edf::event_annotation_text`]) to a temporary file renamed into place.
//!
//! # Reading ([`read_xdf`], [`read_xdf_file`])
//! [`read_xdf_file`] / [`parse_xdf_file`] give every stream with its timestamps and values
//! ([`XdfFile`]). [`read_xdf`] makes a [`Recording`](crate::Recording) of it:
//! * **EEG**: the stream [`XdfOptions::eeg_stream`] names; else the numeric stream of type
//!   `EEG` (case-insensitive) with the most channels; else the regular-rate numeric stream with
//!   the most channels (ties: the first). Its nominal rate is the [`Raw`](oddball_signal::Raw)'s `sfreq`; channel
//!   names are the `desc/channels/channel/label`s (`Ch1` … for missing ones); each channel is
//!   converted to µV from its unit by [`crate::units::stream_microvolts_per`] (`volts`/`V` × 10⁶,
//!   `millivolts`/`mV` × 10³, `microvolts`/`µV`/`uV` × 1, `nanovolts`/`nV` × 10⁻³, any letter
//!   case, so `MV` is millivolts; no unit: µV; any other unit: kept unscaled, factor 1, see
//!   [`XdfInfo::scale_to_uv`]).
//! * **Clocks**: with [`XdfOptions::synchronize_clocks`] (default), each stream's ClockOffsets
//!   are fitted by least squares with `offset = a + b·t` and its timestamps become `t + a + b·t`
//!   (pyxdf's model, without its robust fit and clock-reset detection).
//! * **Events** from every string stream and every one-channel irregular numeric stream whose
//!   type mentions markers, events, triggers or stimuli: each marker goes to the EEG sample whose
//!   timestamp is nearest (markers more than half a sample outside the EEG's time span give no
//!   event). Its text gives the code: `CODE [target|nontarget][: LABEL]` (what [`write_xdf`]
//!   writes) gives code, target flag and label; a text ending in a number after a space, `_`,
//!   `:`, `=` or `#` (`flash 3`, `S  12`) gives that number; any other text gets one code per
//!   distinct text, in order of first appearance, counting up from one above the largest numeric
//!   code. Every marker, with its full text, timestamp and sample, is in [`XdfInfo::markers`].
//! * **Cut files**: a file that ends inside a chunk (a recorder killed while writing) is read up
//!   to its last complete chunk and reported with [`XdfInfo::truncated`] (or refused with
//!   [`IoError::Truncated`](crate::IoError::Truncated) when [`XdfOptions::allow_truncated`] is off). A file cut between
//!   chunks cannot be told from a complete one by its bytes, except that its streams have no
//!   StreamFooter ([`XdfInfo::finished`]).
//! * **Corrupt, not cut**: a chunk whose Length runs past the file's end is a cut only if its
//!   bytes could be the start of that chunk; the file is refused
//!   ([`IoError::InvalidField`](crate::IoError::InvalidField), the Length's byte) when a Boundary
//!   chunk's 16 bytes follow (the file goes on: the live writer puts one every
//!   [`BOUNDARY_INTERVAL_S`] of data), when a Samples chunk's samples end before the file does
//!   or hold a byte no sample can, when a ClockOffset or Boundary chunk claims another length than
//!   its fixed one, or when the chunk names a stream without StreamHeader. So bytes overwritten
//!   in the middle of a recording never read as a recording cut short. In a finished file, each
//!   StreamFooter's `sample_count` must match the samples read (±1, LabRecorder's footers were
//!   one short until 2025): a Samples chunk whose tag was corrupted into an unknown one (skipped)
//!   is found there. See `cut.rs`.
//! * **Errors** ([`IoError::InvalidField`](crate::IoError::InvalidField) with the byte offset from the file start and the
//!   field): a wrong magic code, NumLengthBytes other than 1/4/8, a Length below 2, a chunk whose
//!   content does not fill its Length exactly, TimeStampBytes other than 0/8, a Samples,
//!   ClockOffset or StreamFooter chunk for a stream without StreamHeader, a second StreamHeader
//!   or StreamFooter for one stream, a Boundary chunk without the Boundary bytes, XML that is not
//!   well-formed, a header without `channel_count` (1 to 10 000), `nominal_srate` (finite, ≥ 0) or
//!   a known `channel_format`, a StreamFooter `sample_count` other than the samples read (±1),
//!   a corrupt chunk taken for a cut one (above). Counts are checked against the bytes left in their chunk before
//!   anything is allocated (a NumSamples of 10¹² in a small chunk is an error). Chunks with
//!   unknown tags are skipped and counted ([`XdfFile::n_unknown_chunks`]). Numbers are kept as
//!   `f64` (int64 values beyond 2⁵³ lose their last digits); invalid UTF-8 in string samples is
//!   replaced with U+FFFD (as pyxdf does); XML must be UTF-8.

//!
//! # Layout
//! By job, bottom up: what writer and reader share (`types.rs`: magic code, tags, limits,
//! [`XdfFormat`], [`XdfStream`]), the binary layer (`chunk.rs`: varlen integers, chunks,
//! values), the XML of headers and footers (`xml.rs`, read with the `roxmltree` crate), the
//! writers (`writer.rs`), reading chunks into streams and StreamHeaders into [`XdfStreamInfo`]
//! (`read.rs`), telling a cut file from a corrupt one (`cut.rs`), what a recording keeps ([`XdfInfo`], `info.rs`) and making a
//! [`Recording`](crate::Recording) (`recording.rs`: EEG stream, clocks, markers).

mod acc;
mod chunk;
mod cut;
mod info;
mod read;
mod recording;
pub mod session_markers;
mod types;
mod writer;
mod xml;

pub use info::{XdfInfo, XdfMarker};
pub use read::{parse_xdf_file, read_xdf_file, XdfFile, XdfStreamData, XdfValues};
pub use recording::{parse_xdf, parse_xdf_with, read_xdf, read_xdf_with, XdfOptions};
pub(crate) use types::has_magic;
pub use types::{
    XdfFooter, XdfFormat, XdfStream, XdfStreamInfo, BOUNDARY_INTERVAL_S, BOUNDARY_UUID, MAGIC,
    MAX_CHANNELS,
};
pub use writer::{sample_timestamp, write_xdf, XdfWriteOptions, XdfWriteSummary, XdfWriter};
