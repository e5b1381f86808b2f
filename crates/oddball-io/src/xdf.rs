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
//! is a handful of chunk types, so this module parses them itself (with a small XML reader for
//! the headers), keeps every complete chunk of a cut file, reports the cut, and names the byte
//! offset and field of anything corrupt. It is checked against a file written by an independent
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
//! [`write_xdf`] writes a [`Raw`] (and its events as a string marker stream, each as
//! [`crate::edf::event_annotation_text`]) to a temporary file renamed into place.
//!
//! # Reading ([`read_xdf`], [`read_xdf_file`])
//! [`read_xdf_file`] / [`parse_xdf_file`] give every stream with its timestamps and values
//! ([`XdfFile`]). [`read_xdf`] makes a [`Recording`] of it:
//! * **EEG**: the stream [`XdfOptions::eeg_stream`] names; else the numeric stream of type
//!   `EEG` (case-insensitive) with the most channels; else the regular-rate numeric stream with
//!   the most channels (ties: the first). Its nominal rate is the [`Raw`]'s `sfreq`; channel
//!   names are the `desc/channels/channel/label`s (`Ch1` … for missing ones); each channel is
//!   converted to µV from its unit (`volts`/`V` × 10⁶, `millivolts`/`mV` × 10³,
//!   `microvolts`/`µV`/`uV` × 1, `nanovolts`/`nV` × 10⁻³, case-insensitive; any other or no unit:
//!   taken as µV, factor 1, see [`XdfInfo::scale_to_uv`]).
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
//!   [`IoError::Truncated`] when [`XdfOptions::allow_truncated`] is off). A file cut between
//!   chunks cannot be told from a complete one by its bytes, except that its streams have no
//!   StreamFooter ([`XdfInfo::finished`]).
//! * **Errors** ([`IoError::InvalidField`] with the byte offset from the file start and the
//!   field): a wrong magic code, NumLengthBytes other than 1/4/8, a Length below 2, a chunk whose
//!   content does not fill its Length exactly, TimeStampBytes other than 0/8, a Samples,
//!   ClockOffset or StreamFooter chunk for a stream without StreamHeader, a second StreamHeader
//!   or StreamFooter for one stream, a Boundary chunk without the Boundary bytes, XML that is not
//!   well-formed, a header without `channel_count` (1 to 10 000), `nominal_srate` (finite, ≥ 0) or
//!   a known `channel_format`. Counts are checked against the bytes left in their chunk before
//!   anything is allocated (a NumSamples of 10¹² in a small chunk is an error). Chunks with
//!   unknown tags are skipped and counted ([`XdfFile::n_unknown_chunks`]). Numbers are kept as
//!   `f64` (int64 values beyond 2⁵³ lose their last digits); invalid UTF-8 in string samples is
//!   replaced with U+FFFD (as pyxdf does); XML must be UTF-8.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use ndarray::{Array2, ArrayView2};
use oddball_signal::{Event, Events, Raw};
use serde::{Deserialize, Serialize};

use crate::edf::event_annotation_text;
use crate::error::read_file;
use crate::tempfile::{check_not_empty, check_writable, TempFile};
use crate::units::volt_factor_to_uv;
use crate::{Details, Format, IoError, Recording};

/// The four bytes every XDF file starts with.
pub const MAGIC: &[u8; 4] = b"XDF:";

/// The content of every Boundary chunk (a fixed UUID readers can search for).
pub const BOUNDARY_UUID: [u8; 16] = [
    0x43, 0xA5, 0x46, 0xDC, 0xCB, 0xF5, 0x41, 0x0F, 0xB3, 0x0E, 0xD5, 0x46, 0x73, 0x83, 0xCB, 0xE4,
];

/// The most channels a stream may have (read or written).
pub const MAX_CHANNELS: usize = 10_000;

/// Seconds of data between the Boundary chunks [`XdfWriter`] writes.
pub const BOUNDARY_INTERVAL_S: f64 = 10.0;

const TAG_FILE_HEADER: u16 = 1;
const TAG_STREAM_HEADER: u16 = 2;
const TAG_SAMPLES: u16 = 3;
const TAG_CLOCK_OFFSET: u16 = 4;
const TAG_BOUNDARY: u16 = 5;
const TAG_STREAM_FOOTER: u16 = 6;

/// The deepest XML nesting read.
const MAX_XML_DEPTH: usize = 64;

// ---------------------------------------------------------------------------------------------
// Types shared by the writer and the reader
// ---------------------------------------------------------------------------------------------

/// The number type of a stream's values (`channel_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum XdfFormat {
    Int8,
    Int16,
    Int32,
    Int64,
    Float32,
    Double64,
    /// Text (one string per channel and sample); markers.
    String,
}

impl XdfFormat {
    /// The `channel_format` text: `int8`, …, `float32`, `double64`, `string`.
    pub fn name(self) -> &'static str {
        match self {
            XdfFormat::Int8 => "int8",
            XdfFormat::Int16 => "int16",
            XdfFormat::Int32 => "int32",
            XdfFormat::Int64 => "int64",
            XdfFormat::Float32 => "float32",
            XdfFormat::Double64 => "double64",
            XdfFormat::String => "string",
        }
    }

    /// The format a `channel_format` text names (trimmed, case-insensitive).
    pub fn from_name(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase();
        [
            XdfFormat::Int8,
            XdfFormat::Int16,
            XdfFormat::Int32,
            XdfFormat::Int64,
            XdfFormat::Float32,
            XdfFormat::Double64,
            XdfFormat::String,
        ]
        .into_iter()
        .find(|f| f.name() == s)
    }

    /// Bytes per value; `None` for strings.
    pub fn value_bytes(self) -> Option<usize> {
        match self {
            XdfFormat::Int8 => Some(1),
            XdfFormat::Int16 => Some(2),
            XdfFormat::Int32 | XdfFormat::Float32 => Some(4),
            XdfFormat::Int64 | XdfFormat::Double64 => Some(8),
            XdfFormat::String => None,
        }
    }

    pub fn is_numeric(self) -> bool {
        self != XdfFormat::String
    }
}

/// A stream to write: what goes into its StreamHeader.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfStream {
    pub name: String,
    /// The content type, e.g. `EEG` or `Markers`.
    pub stream_type: String,
    /// One label per channel (a string stream has exactly one channel).
    pub channel_labels: Vec<String>,
    /// The unit of every channel, e.g. `microvolts` (empty for markers).
    pub unit: String,
    /// Samples per second; 0 for an irregular stream (markers).
    pub nominal_srate: f64,
    pub format: XdfFormat,
    /// A unique id of the source device, e.g. its serial number (may be empty).
    pub source_id: String,
}

impl XdfStream {
    /// A float32 EEG stream in microvolts.
    pub fn eeg(name: impl Into<String>, channel_labels: Vec<String>, nominal_srate: f64) -> Self {
        Self {
            name: name.into(),
            stream_type: "EEG".into(),
            channel_labels,
            unit: "microvolts".into(),
            nominal_srate,
            format: XdfFormat::Float32,
            source_id: String::new(),
        }
    }

    /// An irregular one-channel string stream of type `Markers`.
    pub fn markers(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            stream_type: "Markers".into(),
            channel_labels: vec!["marker".into()],
            unit: String::new(),
            nominal_srate: 0.0,
            format: XdfFormat::String,
            source_id: String::new(),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Encoding helpers
// ---------------------------------------------------------------------------------------------

fn put_varlen(out: &mut Vec<u8>, n: u64) {
    if n <= u64::from(u8::MAX) {
        out.push(1);
        out.push(n as u8);
    } else if n <= u64::from(u32::MAX) {
        out.push(4);
        out.extend_from_slice(&(n as u32).to_le_bytes());
    } else {
        out.push(8);
        out.extend_from_slice(&n.to_le_bytes());
    }
}

/// Appends one chunk: `[NumLengthBytes][Length][tag][parts…]`.
fn put_chunk(out: &mut Vec<u8>, tag: u16, parts: &[&[u8]]) {
    let len = 2 + parts.iter().map(|p| p.len() as u64).sum::<u64>();
    put_varlen(out, len);
    out.extend_from_slice(&tag.to_le_bytes());
    for p in parts {
        out.extend_from_slice(p);
    }
}

fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c => o.push(c),
        }
    }
    o
}

/// Why `s` cannot go into the XML header, if it cannot.
fn xml_text_problem(s: &str) -> Option<&'static str> {
    if s.chars()
        .any(|c| c.is_control() || c == '\u{FFFE}' || c == '\u{FFFF}')
    {
        Some("contains a control character (not allowed in XML 1.0 text)")
    } else {
        None
    }
}

fn stream_header_xml(spec: &XdfStream, created_at: Option<f64>) -> String {
    let mut x = String::from("<?xml version=\"1.0\"?>\n<info>");
    let _ = write!(
        x,
        "<name>{}</name><type>{}</type><channel_count>{}</channel_count>\
         <channel_format>{}</channel_format><source_id>{}</source_id>\
         <nominal_srate>{}</nominal_srate>",
        xml_escape(&spec.name),
        xml_escape(&spec.stream_type),
        spec.channel_labels.len(),
        spec.format.name(),
        xml_escape(&spec.source_id),
        spec.nominal_srate,
    );
    if let Some(t) = created_at {
        let _ = write!(x, "<created_at>{t}</created_at>");
    }
    x.push_str("<desc><channels>");
    for label in &spec.channel_labels {
        let _ = write!(
            x,
            "<channel><label>{}</label><unit>{}</unit><type>{}</type></channel>",
            xml_escape(label),
            xml_escape(&spec.unit),
            xml_escape(&spec.stream_type)
        );
    }
    let _ = writeln!(
        x,
        "</channels><acquisition><manufacturer>oddball-io {}</manufacturer></acquisition></desc></info>",
        env!("CARGO_PKG_VERSION")
    );
    x
}

/// Appends `x` in `format`; `Err(reason)` when it does not fit.
fn put_value(out: &mut Vec<u8>, format: XdfFormat, x: f64) -> Result<(), &'static str> {
    fn int(x: f64, min: f64, max: f64) -> Result<f64, &'static str> {
        if !x.is_finite() {
            return Err("not a finite number (the stream stores integers)");
        }
        let r = x.round();
        if r < min || r > max {
            return Err("beyond the range of the stream's integer type");
        }
        Ok(r)
    }
    match format {
        XdfFormat::Int8 => out.push(int(x, -128.0, 127.0)? as i8 as u8),
        XdfFormat::Int16 => {
            out.extend_from_slice(&(int(x, -32768.0, 32767.0)? as i16).to_le_bytes())
        }
        XdfFormat::Int32 => out.extend_from_slice(
            &(int(x, f64::from(i32::MIN), f64::from(i32::MAX))? as i32).to_le_bytes(),
        ),
        XdfFormat::Int64 => {
            // 2^63 is exactly representable; every f64 below it fits.
            let r = int(x, -9_223_372_036_854_775_808.0, 9_223_372_036_854_774_784.0)?;
            out.extend_from_slice(&(r as i64).to_le_bytes())
        }
        XdfFormat::Float32 => {
            let y = x as f32;
            if x.is_finite() && !y.is_finite() {
                return Err("beyond the float32 range");
            }
            out.extend_from_slice(&y.to_le_bytes())
        }
        XdfFormat::Double64 => out.extend_from_slice(&x.to_le_bytes()),
        XdfFormat::String => return Err("a number for a string stream"),
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The live writer
// ---------------------------------------------------------------------------------------------

#[derive(Debug)]
struct WriterStream {
    id: u32,
    spec: XdfStream,
    header_written: bool,
    /// Sample bytes (timestamp byte, timestamp, values) since the last flush.
    pending: Vec<u8>,
    pending_n: u64,
    /// ClockOffset pairs since the last flush.
    pending_clock: Vec<(f64, f64)>,
    clock_offsets: Vec<(f64, f64)>,
    first_timestamp: Option<f64>,
    last_timestamp: Option<f64>,
    sample_count: u64,
}

/// Writes an XDF file as a session runs (see the module documentation).
#[derive(Debug)]
pub struct XdfWriter {
    path: PathBuf,
    /// `None` once finished.
    file: Option<File>,
    streams: Vec<WriterStream>,
    bytes_written: u64,
    /// A write failed: the file may end in a partial chunk, so nothing more is appended.
    failed: bool,
    last_boundary: Option<f64>,
    max_timestamp: Option<f64>,
}

impl XdfWriter {
    /// Creates the file (refusing to replace an existing one: a recorder must not destroy an
    /// earlier session) and writes the magic code and the FileHeader chunk at once.
    pub fn create(path: impl AsRef<Path>) -> Result<XdfWriter, IoError> {
        let path = path.as_ref();
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|source| IoError::Io {
                path: path.to_path_buf(),
                action: "create",
                source,
            })?;
        Self::start(file, path.to_path_buf())
    }

    fn start(file: File, path: PathBuf) -> Result<XdfWriter, IoError> {
        let mut w = XdfWriter {
            path,
            file: Some(file),
            streams: Vec::new(),
            bytes_written: 0,
            failed: false,
            last_boundary: None,
            max_timestamp: None,
        };
        let mut block = MAGIC.to_vec();
        let xml = format!(
            "<?xml version=\"1.0\"?>\n<info><version>1.0</version><writer>oddball-io {}</writer></info>\n",
            env!("CARGO_PKG_VERSION")
        );
        put_chunk(&mut block, TAG_FILE_HEADER, &[xml.as_bytes()]);
        w.write_block(&block)?;
        Ok(w)
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes handed to the operating system so far (the file's size).
    pub fn bytes_written(&self) -> u64 {
        self.bytes_written
    }

    /// Bytes of samples buffered since the last flush.
    pub fn pending_bytes(&self) -> usize {
        self.streams.iter().map(|s| s.pending.len()).sum()
    }

    /// Samples written so far (buffered ones included) to stream `id`.
    pub fn sample_count(&self, id: u32) -> Option<u64> {
        self.streams
            .iter()
            .find(|s| s.id == id)
            .map(|s| s.sample_count)
    }

    fn unsupported(&self, what: String) -> IoError {
        IoError::Unsupported {
            path: self.path.clone(),
            what,
        }
    }

    fn check_usable(&self) -> Result<(), IoError> {
        if self.failed {
            return Err(self.unsupported(
                "writing to an XDF file after a failed write (it may end in a partial chunk)"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Adds a stream and returns its id (1, 2, …). Its StreamHeader is written at the next
    /// flush. Refused: no channel or more than [`MAX_CHANNELS`], a string stream with more than
    /// one channel, a negative or non-finite rate, text with control characters.
    pub fn add_stream(&mut self, stream: &XdfStream) -> Result<u32, IoError> {
        self.check_usable()?;
        let n = stream.channel_labels.len();
        if n == 0 || n > MAX_CHANNELS {
            return Err(self.unsupported(format!(
                "stream {:?} with {n} channels (1 to {MAX_CHANNELS})",
                stream.name
            )));
        }
        if stream.format == XdfFormat::String && n != 1 {
            return Err(self.unsupported(format!(
                "string stream {:?} with {n} channels (this writer writes one-channel string streams)",
                stream.name
            )));
        }
        if !(stream.nominal_srate.is_finite() && stream.nominal_srate >= 0.0) {
            return Err(self.unsupported(format!(
                "stream {:?} with nominal_srate {} (finite and >= 0; 0 = irregular)",
                stream.name, stream.nominal_srate
            )));
        }
        let texts = [
            ("name", &stream.name),
            ("type", &stream.stream_type),
            ("unit", &stream.unit),
            ("source_id", &stream.source_id),
        ];
        for (what, text) in texts
            .into_iter()
            .chain(stream.channel_labels.iter().map(|l| ("channel label", l)))
        {
            if let Some(p) = xml_text_problem(text) {
                return Err(self.unsupported(format!("stream {what} {text:?} {p}")));
            }
        }
        let id = self.streams.len() as u32 + 1;
        self.streams.push(WriterStream {
            id,
            spec: stream.clone(),
            header_written: false,
            pending: Vec::new(),
            pending_n: 0,
            pending_clock: Vec::new(),
            clock_offsets: Vec::new(),
            first_timestamp: None,
            last_timestamp: None,
            sample_count: 0,
        });
        Ok(id)
    }

    fn stream_index(&self, id: u32) -> Result<usize, IoError> {
        self.streams
            .iter()
            .position(|s| s.id == id)
            .ok_or_else(|| IoError::Missing {
                path: self.path.clone(),
                what: "XDF stream id",
                name: id.to_string(),
                available: self.streams.iter().map(|s| s.id.to_string()).collect(),
            })
    }

    fn check_timestamps(&self, k: usize, timestamps: &[f64], n: usize) -> Result<(), IoError> {
        let s = &self.streams[k];
        if timestamps.len() != n {
            return Err(self.unsupported(format!(
                "stream {} ({:?}): {} timestamps for {n} samples",
                s.id,
                s.spec.name,
                timestamps.len()
            )));
        }
        if let Some(i) = timestamps.iter().position(|t| !t.is_finite()) {
            return Err(self.unsupported(format!(
                "stream {} ({:?}): timestamp {i} is {} (timestamps must be finite)",
                s.id, s.spec.name, timestamps[i]
            )));
        }
        Ok(())
    }

    fn note_timestamps(&mut self, k: usize, timestamps: &[f64]) {
        let (Some(&first), Some(&last)) = (timestamps.first(), timestamps.last()) else {
            return;
        };
        let max = timestamps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let s = &mut self.streams[k];
        s.first_timestamp.get_or_insert(first);
        s.last_timestamp = Some(last);
        s.sample_count += timestamps.len() as u64;
        s.pending_n += timestamps.len() as u64;
        self.max_timestamp = Some(self.max_timestamp.map_or(max, |m| m.max(max)));
        self.last_boundary.get_or_insert(first);
    }

    /// Buffers samples of numeric stream `id`: `data` is `(n_channels, n_samples)`, one
    /// timestamp (seconds) per sample. Nothing is buffered when any check fails.
    pub fn push_numeric(
        &mut self,
        id: u32,
        timestamps: &[f64],
        data: ArrayView2<'_, f64>,
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        let s = &self.streams[k];
        let format = s.spec.format;
        if !format.is_numeric() {
            return Err(self.unsupported(format!(
                "push_numeric to string stream {id} ({:?}); use push_strings",
                s.spec.name
            )));
        }
        let n_ch = s.spec.channel_labels.len();
        if data.nrows() != n_ch {
            return Err(self.unsupported(format!(
                "stream {id} ({:?}) has {n_ch} channels, but the data has {} rows",
                s.spec.name,
                data.nrows()
            )));
        }
        self.check_timestamps(k, timestamps, data.ncols())?;
        let s = &mut self.streams[k];
        let start = s.pending.len();
        let vb = format.value_bytes().unwrap_or(8);
        s.pending.reserve(timestamps.len() * (9 + n_ch * vb));
        for (t, (&ts, col)) in timestamps.iter().zip(data.columns()).enumerate() {
            s.pending.push(8);
            s.pending.extend_from_slice(&ts.to_le_bytes());
            for (c, &x) in col.iter().enumerate() {
                if let Err(reason) = put_value(&mut s.pending, format, x) {
                    s.pending.truncate(start);
                    return Err(IoError::UnwritableSample {
                        path: self.path.clone(),
                        channel: s.spec.channel_labels[c].clone(),
                        channel_index: c,
                        sample: t,
                        value: x,
                        reason,
                    });
                }
            }
        }
        self.note_timestamps(k, timestamps);
        Ok(())
    }

    /// Buffers samples of a (one-channel) string stream `id`: one text per timestamp.
    pub fn push_strings(
        &mut self,
        id: u32,
        timestamps: &[f64],
        values: &[&str],
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        let s = &self.streams[k];
        if s.spec.format != XdfFormat::String {
            return Err(self.unsupported(format!(
                "push_strings to {} stream {id} ({:?}); use push_numeric",
                s.spec.format.name(),
                s.spec.name
            )));
        }
        self.check_timestamps(k, timestamps, values.len())?;
        let s = &mut self.streams[k];
        for (&ts, v) in timestamps.iter().zip(values) {
            s.pending.push(8);
            s.pending.extend_from_slice(&ts.to_le_bytes());
            put_varlen(&mut s.pending, v.len() as u64);
            s.pending.extend_from_slice(v.as_bytes());
        }
        self.note_timestamps(k, timestamps);
        Ok(())
    }

    /// Buffers a ClockOffset chunk for stream `id`: at `collection_time` (the recorder's clock)
    /// the stream's clock was `offset` seconds behind (both finite).
    pub fn push_clock_offset(
        &mut self,
        id: u32,
        collection_time: f64,
        offset: f64,
    ) -> Result<(), IoError> {
        self.check_usable()?;
        let k = self.stream_index(id)?;
        if !(collection_time.is_finite() && offset.is_finite()) {
            return Err(self.unsupported(format!(
                "stream {id}: clock offset {offset} at {collection_time} (both must be finite)"
            )));
        }
        self.streams[k]
            .pending_clock
            .push((collection_time, offset));
        Ok(())
    }

    /// Everything buffered, as whole chunks; with `footers`, a StreamFooter per stream after it.
    fn take_block(&mut self, footers: bool) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.pending_bytes() + 64 * self.streams.len());
        for s in &mut self.streams {
            if !s.header_written {
                let xml = stream_header_xml(&s.spec, s.first_timestamp);
                put_chunk(
                    &mut out,
                    TAG_STREAM_HEADER,
                    &[&s.id.to_le_bytes(), xml.as_bytes()],
                );
                s.header_written = true;
            }
        }
        for s in &mut self.streams {
            if s.pending_n > 0 {
                let mut head = s.id.to_le_bytes().to_vec();
                put_varlen(&mut head, s.pending_n);
                put_chunk(&mut out, TAG_SAMPLES, &[&head, &s.pending]);
                s.pending.clear();
                s.pending_n = 0;
            }
        }
        for s in &mut self.streams {
            for (t, v) in s.pending_clock.drain(..) {
                put_chunk(
                    &mut out,
                    TAG_CLOCK_OFFSET,
                    &[&s.id.to_le_bytes(), &t.to_le_bytes(), &v.to_le_bytes()],
                );
                s.clock_offsets.push((t, v));
            }
        }
        if let (Some(max), Some(last)) = (self.max_timestamp, self.last_boundary) {
            if max - last >= BOUNDARY_INTERVAL_S {
                put_chunk(&mut out, TAG_BOUNDARY, &[&BOUNDARY_UUID]);
                self.last_boundary = Some(max);
            }
        }
        if footers {
            for s in &self.streams {
                let mut x = String::from("<?xml version=\"1.0\"?>\n<info>");
                if let (Some(f), Some(l)) = (s.first_timestamp, s.last_timestamp) {
                    let _ = write!(
                        x,
                        "<first_timestamp>{f}</first_timestamp><last_timestamp>{l}</last_timestamp>"
                    );
                }
                let _ = write!(x, "<sample_count>{}</sample_count>", s.sample_count);
                x.push_str("<clock_offsets>");
                for (t, v) in &s.clock_offsets {
                    let _ = write!(x, "<offset><time>{t}</time><value>{v}</value></offset>");
                }
                x.push_str("</clock_offsets></info>\n");
                put_chunk(
                    &mut out,
                    TAG_STREAM_FOOTER,
                    &[&s.id.to_le_bytes(), x.as_bytes()],
                );
            }
        }
        out
    }

    fn write_block(&mut self, block: &[u8]) -> Result<usize, IoError> {
        if block.is_empty() {
            return Ok(0);
        }
        let Some(file) = self.file.as_mut() else {
            return Err(self.unsupported("writing to a finished XDF file".into()));
        };
        if let Err(source) = file.write_all(block).and_then(|()| file.flush()) {
            self.failed = true;
            return Err(IoError::Io {
                path: self.path.clone(),
                action: "write",
                source,
            });
        }
        self.bytes_written += block.len() as u64;
        Ok(block.len())
    }

    /// Writes every chunk buffered since the last flush with one `write_all`, then `flush`.
    /// Returns the bytes written (0 when nothing was buffered).
    pub fn flush_block(&mut self) -> Result<usize, IoError> {
        self.check_usable()?;
        let block = self.take_block(false);
        self.write_block(&block)
    }

    /// Asks the operating system to put the written bytes on the disk (`fsync`).
    pub fn sync(&mut self) -> Result<(), IoError> {
        if let Some(f) = self.file.as_mut() {
            f.sync_data().map_err(|source| IoError::Io {
                path: self.path.clone(),
                action: "write",
                source,
            })?;
        }
        Ok(())
    }

    /// Flushes, writes a StreamFooter per stream (first and last timestamp, sample count, clock
    /// offsets), syncs and closes the file. Returns the file size in bytes.
    pub fn finish(mut self) -> Result<u64, IoError> {
        self.check_usable()?;
        let block = self.take_block(true);
        self.write_block(&block)?;
        self.sync()?;
        self.file = None;
        Ok(self.bytes_written)
    }
}

impl Drop for XdfWriter {
    fn drop(&mut self) {
        if self.file.is_some() && !self.failed {
            let _ = self.flush_block();
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The offline writer
// ---------------------------------------------------------------------------------------------

/// Options of [`write_xdf`].
#[derive(Debug, Clone, PartialEq)]
pub struct XdfWriteOptions {
    /// The EEG stream's name; default `oddball EEG`.
    pub stream_name: String,
    /// Default `""`.
    pub source_id: String,
    /// Default [`XdfFormat::Double64`] (bit-exact); [`XdfFormat::Float32`] halves the size.
    pub format: XdfFormat,
    /// Timestamp of the first sample in seconds; sample `i` is at `start_time + i / sfreq`.
    pub start_time: f64,
    /// Write the events as a string stream `oddball markers` (type `Markers`); default true.
    pub markers: bool,
    /// Samples per Samples chunk; default 500.
    pub samples_per_chunk: usize,
}

impl Default for XdfWriteOptions {
    fn default() -> Self {
        Self {
            stream_name: "oddball EEG".into(),
            source_id: String::new(),
            format: XdfFormat::Double64,
            start_time: 0.0,
            markers: true,
            samples_per_chunk: 500,
        }
    }
}

/// What [`write_xdf`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfWriteSummary {
    pub n_samples: usize,
    pub n_channels: usize,
    pub n_markers: usize,
    pub bytes: u64,
    /// The largest `|stored − x|` over all samples, in µV (0 for double64).
    pub max_rounding_uv: f64,
}

/// The timestamp [`write_xdf`] gives sample `i`: `start_time + i / sfreq`.
pub fn sample_timestamp(start_time: f64, i: usize, sfreq: f64) -> f64 {
    start_time + i as f64 / sfreq
}

/// Writes `raw` as an XDF file: one EEG stream (unit microvolts, each sample with its
/// timestamp) and, with [`XdfWriteOptions::markers`], the events as a string stream (each as
/// [`event_annotation_text`] at its onset's timestamp), then footers. The file is written to
/// a temporary file beside `path` and renamed into place. Refused before anything is written:
/// an empty recording, a string format, a non-finite start time, a sample that does not fit the
/// format ([`IoError::UnwritableSample`]), names with control characters.
pub fn write_xdf(
    path: impl AsRef<Path>,
    raw: &Raw,
    options: &XdfWriteOptions,
) -> Result<XdfWriteSummary, IoError> {
    let path = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    check_not_empty(path, raw, "XDF")?;
    if !options.format.is_numeric() {
        return Err(unsupported("an EEG stream in string format".into()));
    }
    if !options.start_time.is_finite() {
        return Err(unsupported(format!(
            "start time {} (must be finite)",
            options.start_time
        )));
    }
    let format = options.format;
    let max_rounding = check_writable(
        path,
        raw,
        "beyond the range of the stream's number type",
        |x| {
            let mut b = Vec::with_capacity(8);
            put_value(&mut b, format, x).ok()?;
            Some(match format {
                XdfFormat::Float32 => f64::from(x as f32),
                XdfFormat::Double64 => x,
                _ => x.round(),
            })
        },
    )?;
    let sfreq = raw.sfreq();
    let n_times = raw.n_times();
    let eeg = XdfStream {
        name: options.stream_name.clone(),
        stream_type: "EEG".into(),
        channel_labels: raw.ch_names().to_vec(),
        unit: "microvolts".into(),
        nominal_srate: sfreq,
        format,
        source_id: options.source_id.clone(),
    };

    let (tmp, file) = TempFile::create(path)?;
    let mut w = XdfWriter::start(file, tmp.path.clone())?;
    let eeg_id = w.add_stream(&eeg)?;
    let marker_id = if options.markers {
        Some(w.add_stream(&XdfStream::markers("oddball markers"))?)
    } else {
        None
    };
    let events = raw.events().as_slice();
    let mut next_event = 0;
    let step = options.samples_per_chunk.max(1);
    let mut start = 0;
    while start < n_times {
        let end = (start + step).min(n_times);
        let ts: Vec<f64> = (start..end)
            .map(|i| sample_timestamp(options.start_time, i, sfreq))
            .collect();
        w.push_numeric(eeg_id, &ts, raw.data().slice(ndarray::s![.., start..end]))?;
        if let Some(mid) = marker_id {
            let mut mts = Vec::new();
            let mut texts = Vec::new();
            while next_event < events.len() && events[next_event].onset < end {
                let e = &events[next_event];
                mts.push(sample_timestamp(options.start_time, e.onset, sfreq));
                texts.push(event_annotation_text(e));
                next_event += 1;
            }
            let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
            w.push_strings(mid, &mts, &refs)?;
        }
        w.flush_block()?;
        start = end;
    }
    let bytes = w.finish()?;
    tmp.persist(path)?;
    Ok(XdfWriteSummary {
        n_samples: n_times,
        n_channels: raw.n_channels(),
        n_markers: if options.markers { events.len() } else { 0 },
        bytes,
        max_rounding_uv: max_rounding,
    })
}

// ---------------------------------------------------------------------------------------------
// A small XML reader (elements, text, entities; attributes are skipped)
// ---------------------------------------------------------------------------------------------

#[derive(Debug, Clone, Default)]
struct XmlNode {
    name: String,
    text: String,
    /// Byte offset (in the XML text) of the element's first non-blank text, else of its start.
    text_offset: usize,
    children: Vec<XmlNode>,
}

impl XmlNode {
    fn child(&self, name: &str) -> Option<&XmlNode> {
        self.children.iter().find(|c| c.name == name)
    }

    fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a XmlNode> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }

    fn child_text(&self, name: &str) -> Option<&str> {
        self.child(name).map(|c| c.text.trim())
    }
}

#[derive(Debug)]
struct XmlError {
    offset: usize,
    expected: &'static str,
    found: String,
}

fn snippet(s: &str, at: usize) -> String {
    s.get(at..)
        .unwrap_or("")
        .chars()
        .take(20)
        .collect::<String>()
}

fn decode_entities(raw: &str, base: usize, out: &mut String) -> Result<(), XmlError> {
    let mut rest = raw;
    let mut pos = base;
    while let Some(amp) = rest.find('&') {
        out.push_str(&rest[..amp]);
        let after = &rest[amp + 1..];
        let semi = after
            .find(';')
            .filter(|&i| i <= 10)
            .ok_or_else(|| XmlError {
                offset: pos + amp,
                expected: "an entity (&amp; &lt; &gt; &quot; &apos; &#N;)",
                found: snippet(rest, amp),
            })?;
        let name = &after[..semi];
        let c = match name {
            "amp" => Some('&'),
            "lt" => Some('<'),
            "gt" => Some('>'),
            "quot" => Some('"'),
            "apos" => Some('\''),
            _ => {
                let num =
                    if let Some(h) = name.strip_prefix("#x").or_else(|| name.strip_prefix("#X")) {
                        u32::from_str_radix(h, 16).ok()
                    } else if let Some(d) = name.strip_prefix('#') {
                        d.parse::<u32>().ok()
                    } else {
                        None
                    };
                num.and_then(char::from_u32)
            }
        };
        let c = c.ok_or_else(|| XmlError {
            offset: pos + amp,
            expected: "an entity (&amp; &lt; &gt; &quot; &apos; &#N;)",
            found: format!("&{name};"),
        })?;
        out.push(c);
        pos += amp + 1 + semi + 1;
        rest = &after[semi + 1..];
    }
    out.push_str(rest);
    Ok(())
}

fn is_name_end(b: u8) -> bool {
    b.is_ascii_whitespace() || b == b'/' || b == b'>' || b == b'='
}

/// Parses one XML document into its root element.
fn parse_xml(s: &str) -> Result<XmlNode, XmlError> {
    let b = s.as_bytes();
    let err = |offset: usize, expected: &'static str| XmlError {
        offset,
        expected,
        found: snippet(s, offset),
    };
    let mut i = if s.starts_with('\u{feff}') { 3 } else { 0 };
    let mut stack: Vec<XmlNode> = Vec::new();
    let mut root: Option<XmlNode> = None;
    while i < b.len() {
        if b[i] != b'<' {
            let end = s[i..].find('<').map_or(b.len(), |j| i + j);
            let raw = &s[i..end];
            match stack.last_mut() {
                Some(top) => {
                    if top.text.trim().is_empty() {
                        if let Some(k) = raw.find(|c: char| !c.is_whitespace()) {
                            top.text_offset = i + k;
                        }
                    }
                    decode_entities(raw, i, &mut top.text)?;
                }
                None => {
                    if let Some(k) = raw.find(|c: char| !c.is_whitespace()) {
                        return Err(err(i + k, "an element (text outside the root element)"));
                    }
                }
            }
            i = end;
            continue;
        }
        let rest = &s[i..];
        if rest.starts_with("<?") {
            let j = rest
                .find("?>")
                .ok_or_else(|| err(i, "the end ?> of <?...?>"))?;
            i += j + 2;
        } else if let Some(r) = rest.strip_prefix("<!--") {
            let j = r
                .find("-->")
                .ok_or_else(|| err(i, "the end --> of a comment"))?;
            i += 4 + j + 3;
        } else if let Some(r) = rest.strip_prefix("<![CDATA[") {
            let j = r
                .find("]]>")
                .ok_or_else(|| err(i, "the end ]]> of CDATA"))?;
            let top = stack
                .last_mut()
                .ok_or_else(|| err(i, "CDATA inside an element"))?;
            if top.text.trim().is_empty() {
                top.text_offset = i + 9;
            }
            top.text.push_str(&r[..j]);
            i += 9 + j + 3;
        } else if rest.starts_with("<!") {
            if !stack.is_empty() || root.is_some() {
                return Err(err(i, "an element (<! declaration inside the document)"));
            }
            let j = rest
                .find('>')
                .ok_or_else(|| err(i, "the end > of <!...>"))?;
            if rest[..j].contains('[') {
                return Err(err(i, "a DOCTYPE without internal subset"));
            }
            i += j + 1;
        } else if let Some(r) = rest.strip_prefix("</") {
            let n = r.bytes().position(is_name_end).unwrap_or(r.len());
            let name = &r[..n];
            let mut j = i + 2 + n;
            while j < b.len() && b[j].is_ascii_whitespace() {
                j += 1;
            }
            if b.get(j) != Some(&b'>') {
                return Err(err(j, "> closing an end tag"));
            }
            let node = stack
                .pop()
                .ok_or_else(|| err(i, "no end tag without a start tag"))?;
            if node.name != name {
                return Err(XmlError {
                    offset: i,
                    expected: "the end tag of the open element",
                    found: format!("</{name}> closing <{}>", node.name),
                });
            }
            match stack.last_mut() {
                Some(top) => top.children.push(node),
                None => root = Some(node),
            }
            i = j + 1;
        } else {
            let r = &rest[1..];
            let n = r.bytes().position(is_name_end).unwrap_or(r.len());
            if n == 0 {
                return Err(err(i + 1, "an element name"));
            }
            if root.is_some() {
                return Err(err(i, "nothing after the root element"));
            }
            if stack.len() >= MAX_XML_DEPTH {
                return Err(err(i, "at most 64 nested elements"));
            }
            let name = r[..n].to_string();
            let mut j = i + 1 + n;
            // Attributes: name = "value" (skipped).
            let self_closing = loop {
                while j < b.len() && b[j].is_ascii_whitespace() {
                    j += 1;
                }
                match b.get(j) {
                    None => return Err(err(j, "> closing a start tag")),
                    Some(b'>') => break false,
                    Some(b'/') => {
                        if b.get(j + 1) != Some(&b'>') {
                            return Err(err(j, "/> closing an empty element"));
                        }
                        j += 1;
                        break true;
                    }
                    Some(_) => {
                        let a = s[j..].bytes().position(is_name_end).unwrap_or(b.len() - j);
                        if a == 0 {
                            return Err(err(j, "an attribute name"));
                        }
                        j += a;
                        while j < b.len() && b[j].is_ascii_whitespace() {
                            j += 1;
                        }
                        if b.get(j) != Some(&b'=') {
                            return Err(err(j, "= after an attribute name"));
                        }
                        j += 1;
                        while j < b.len() && b[j].is_ascii_whitespace() {
                            j += 1;
                        }
                        let q = match b.get(j) {
                            Some(&q @ (b'"' | b'\'')) => q,
                            _ => return Err(err(j, "a quoted attribute value")),
                        };
                        let close = s[j + 1..]
                            .bytes()
                            .position(|c| c == q)
                            .ok_or_else(|| err(j, "the closing quote of an attribute value"))?;
                        j += 1 + close + 1;
                    }
                }
            };
            let node = XmlNode {
                name,
                text: String::new(),
                text_offset: i,
                children: Vec::new(),
            };
            i = j + 1;
            if self_closing {
                match stack.last_mut() {
                    Some(top) => top.children.push(node),
                    None => root = Some(node),
                }
            } else {
                stack.push(node);
            }
        }
    }
    if let Some(open) = stack.last() {
        return Err(XmlError {
            offset: b.len(),
            expected: "the end tag of every element",
            found: format!("end of text inside <{}>", open.name),
        });
    }
    root.ok_or_else(|| err(b.len(), "a root element"))
}

// ---------------------------------------------------------------------------------------------
// The reader
// ---------------------------------------------------------------------------------------------

/// A StreamFooter's values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfFooter {
    pub first_timestamp: Option<f64>,
    pub last_timestamp: Option<f64>,
    pub sample_count: Option<u64>,
    /// The footer XML as written.
    pub xml: String,
}

/// One stream's header and what was read of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfStreamInfo {
    pub id: u32,
    pub name: String,
    pub stream_type: String,
    pub channel_count: usize,
    pub nominal_srate: f64,
    pub format: XdfFormat,
    pub source_id: String,
    pub created_at: Option<f64>,
    /// `desc/channels/channel/label`, `unit` and `type`, as many as the header has (empty text
    /// where a channel lacks one).
    pub channel_labels: Vec<String>,
    pub channel_units: Vec<String>,
    pub channel_types: Vec<String>,
    /// The StreamHeader XML as written.
    pub header_xml: String,
    pub n_samples: usize,
    pub n_sample_chunks: usize,
    /// Timestamps of the first and last sample, as in the file.
    pub first_timestamp: Option<f64>,
    pub last_timestamp: Option<f64>,
    /// `(collection time, offset value)` of each ClockOffset chunk.
    pub clock_offsets: Vec<(f64, f64)>,
    /// `(a, b)` of the clock correction `t + a + b·t` applied by [`read_xdf`] (when
    /// synchronizing and the stream has clock offsets).
    pub clock_fit: Option<(f64, f64)>,
    pub footer: Option<XdfFooter>,
}

/// A stream's values.
#[derive(Debug, Clone, PartialEq)]
pub enum XdfValues {
    /// `(n_channels, n_samples)`, as stored (no unit conversion).
    Numeric(Array2<f64>),
    /// `[sample][channel]`.
    Strings(Vec<Vec<String>>),
}

/// One stream with its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfStreamData {
    pub info: XdfStreamInfo,
    /// One per sample, as in the file (or deduced; see the module documentation).
    pub timestamps: Vec<f64>,
    pub values: XdfValues,
}

/// Every chunk of an XDF file, by stream.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfFile {
    /// The FileHeader XML, when the file has one.
    pub header_xml: Option<String>,
    /// The FileHeader's `version`.
    pub version: Option<String>,
    /// In the order of their StreamHeaders.
    pub streams: Vec<XdfStreamData>,
    /// Complete chunks read (all tags).
    pub n_chunks: usize,
    pub n_boundaries: usize,
    /// Complete chunks with a tag this reader does not know (skipped).
    pub n_unknown_chunks: usize,
    /// The file ends inside a chunk (or inside the magic code).
    pub truncated: bool,
    /// Where the incomplete chunk starts.
    pub truncated_at: Option<u64>,
    pub file_len: u64,
}

impl XdfFile {
    /// The stream with this id.
    pub fn stream(&self, id: u32) -> Option<&XdfStreamData> {
        self.streams.iter().find(|s| s.info.id == id)
    }

    /// The first stream with this name.
    pub fn stream_named(&self, name: &str) -> Option<&XdfStreamData> {
        self.streams.iter().find(|s| s.info.name == name)
    }
}

/// How to read an XDF file into a [`Recording`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct XdfOptions {
    /// The name of the stream to read as EEG (default: see the module documentation).
    pub eeg_stream: Option<String>,
    /// Apply each stream's ClockOffsets (default true).
    pub synchronize_clocks: bool,
    /// Read a file that ends inside a chunk up to its last complete chunk (default true);
    /// otherwise such a file is an [`IoError::Truncated`].
    pub allow_truncated: bool,
}

impl Default for XdfOptions {
    fn default() -> Self {
        Self {
            eeg_stream: None,
            synchronize_clocks: true,
            allow_truncated: true,
        }
    }
}

/// One marker (a string sample or a marker-stream number).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfMarker {
    pub stream_id: u32,
    /// As in the file (before clock synchronization).
    pub timestamp: f64,
    /// The full text (channels joined with TAB; a number as Rust prints it).
    pub text: String,
    /// The event code given to it.
    pub code: u32,
    pub target: Option<bool>,
    /// The EEG sample it was put at; `None` when outside the EEG's time span.
    pub sample: Option<usize>,
}

/// What an XDF file held besides the EEG samples and events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfInfo {
    pub version: Option<String>,
    pub header_xml: Option<String>,
    /// Every stream (header, counts, timestamps of first and last sample, clock offsets, footer).
    pub streams: Vec<XdfStreamInfo>,
    /// Index in [`XdfInfo::streams`] of the stream read as EEG.
    pub eeg_stream: usize,
    /// The EEG samples' timestamps (after clock synchronization).
    pub eeg_timestamps: Vec<f64>,
    /// The unit of each EEG channel and the factor applied to reach µV.
    pub eeg_units: Vec<String>,
    pub scale_to_uv: Vec<f64>,
    /// Markers of all marker streams, stream after stream, each in file order.
    pub markers: Vec<XdfMarker>,
    /// The file ends inside a chunk (a recorder stopped while writing).
    pub truncated: bool,
    pub truncated_at: Option<u64>,
    pub n_chunks: usize,
    pub n_boundaries: usize,
    pub n_unknown_chunks: usize,
}

impl XdfInfo {
    /// The recording was closed properly: not cut inside a chunk and every stream has a
    /// StreamFooter.
    pub fn finished(&self) -> bool {
        !self.truncated && self.streams.iter().all(|s| s.footer.is_some())
    }

    /// The stream read as EEG.
    pub fn eeg(&self) -> &XdfStreamInfo {
        &self.streams[self.eeg_stream]
    }
}

struct Acc {
    info: XdfStreamInfo,
    timestamps: Vec<f64>,
    numeric: Vec<f64>,
    strings: Vec<Vec<String>>,
    last_ts: f64,
    tdiff: f64,
}

struct Ctx<'a> {
    path: &'a Path,
}

impl Ctx<'_> {
    fn invalid(
        &self,
        offset: usize,
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> IoError {
        IoError::InvalidField {
            path: self.path.to_path_buf(),
            field: field.into(),
            offset: offset as u64,
            expected: expected.into(),
            found: found.into(),
        }
    }

    /// Parses XML `bytes` starting at file offset `base`.
    fn xml(&self, bytes: &[u8], base: usize, what: &str) -> Result<(String, XmlNode), IoError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            self.invalid(
                base + e.valid_up_to(),
                format!("{what} XML"),
                "UTF-8 text",
                format!("byte {:#04x}", bytes[e.valid_up_to()]),
            )
        })?;
        let root = parse_xml(text).map_err(|e| {
            self.invalid(base + e.offset, format!("{what} XML"), e.expected, e.found)
        })?;
        Ok((text.to_string(), root))
    }
}

fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    u64::from_le_bytes(a)
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn le_f64(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap_or([0; 8]))
}

/// Reads a varlen integer at `content[p]`; `Err((offset in content, problem))`.
fn varlen(content: &[u8], p: usize) -> Result<(u64, usize), (usize, String)> {
    let Some(&n) = content.get(p) else {
        return Err((p, "the end of the chunk".into()));
    };
    if !matches!(n, 1 | 4 | 8) {
        return Err((p, format!("byte count {n}")));
    }
    let n = n as usize;
    let bytes = content
        .get(p + 1..p + 1 + n)
        .ok_or_else(|| (p, "the end of the chunk".to_string()))?;
    Ok((le_u64(bytes), p + 1 + n))
}

fn parse_f64_text(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok()
}

fn parse_stream_header(
    ctx: &Ctx<'_>,
    id: u32,
    xml: &[u8],
    base: usize,
) -> Result<XdfStreamInfo, IoError> {
    let (text, root) = ctx.xml(xml, base, "StreamHeader")?;
    let field = |name: &str| format!("StreamHeader (stream {id}) {name}");
    if root.name != "info" {
        return Err(ctx.invalid(
            base,
            field("root element"),
            "<info>",
            format!("<{}>", root.name),
        ));
    }
    let required = |name: &str| {
        root.child(name)
            .ok_or_else(|| ctx.invalid(base, field(name), format!("a <{name}> element"), "none"))
    };
    let cc = required("channel_count")?;
    let channel_count = cc
        .text
        .trim()
        .parse::<usize>()
        .ok()
        .filter(|&n| (1..=MAX_CHANNELS).contains(&n))
        .ok_or_else(|| {
            ctx.invalid(
                base + cc.text_offset,
                field("channel_count"),
                format!("a whole number from 1 to {MAX_CHANNELS}"),
                cc.text.trim(),
            )
        })?;
    let sr = required("nominal_srate")?;
    let nominal_srate = parse_f64_text(&sr.text)
        .filter(|r| r.is_finite() && *r >= 0.0)
        .ok_or_else(|| {
            ctx.invalid(
                base + sr.text_offset,
                field("nominal_srate"),
                "a finite rate >= 0 (0 = irregular)",
                sr.text.trim(),
            )
        })?;
    let cf = required("channel_format")?;
    let format = XdfFormat::from_name(&cf.text).ok_or_else(|| {
        ctx.invalid(
            base + cf.text_offset,
            field("channel_format"),
            "int8, int16, int32, int64, float32, double64 or string",
            cf.text.trim(),
        )
    })?;
    let text_of = |name: &str| root.child_text(name).unwrap_or("").to_string();
    let mut labels = Vec::new();
    let mut units = Vec::new();
    let mut types = Vec::new();
    if let Some(chs) = root.child("desc").and_then(|d| d.child("channels")) {
        for ch in chs.children_named("channel") {
            labels.push(ch.child_text("label").unwrap_or("").to_string());
            units.push(ch.child_text("unit").unwrap_or("").to_string());
            types.push(ch.child_text("type").unwrap_or("").to_string());
        }
    }
    Ok(XdfStreamInfo {
        id,
        name: text_of("name"),
        stream_type: text_of("type"),
        channel_count,
        nominal_srate,
        format,
        source_id: text_of("source_id"),
        created_at: root.child_text("created_at").and_then(parse_f64_text),
        channel_labels: labels,
        channel_units: units,
        channel_types: types,
        header_xml: text,
        n_samples: 0,
        n_sample_chunks: 0,
        first_timestamp: None,
        last_timestamp: None,
        clock_offsets: Vec::new(),
        clock_fit: None,
        footer: None,
    })
}

/// Parses a Samples chunk's content (after the stream id, which starts at file offset `base`).
fn parse_samples(ctx: &Ctx<'_>, content: &[u8], base: usize, acc: &mut Acc) -> Result<(), IoError> {
    let id = acc.info.id;
    let field = |what: String| format!("Samples (stream {id}) {what}");
    let (n, mut p) = varlen(content, 4).map_err(|(at, found)| {
        ctx.invalid(
            base + at,
            field("NumSamples".into()),
            "a varlen integer (1, 4 or 8 bytes)",
            found,
        )
    })?;
    let n_ch = acc.info.channel_count;
    let format = acc.info.format;
    let min_per_sample = 1 + n_ch * format.value_bytes().unwrap_or(2);
    let room = (content.len() - p) / min_per_sample;
    if n > room as u64 {
        return Err(ctx.invalid(
            base + 4,
            field("NumSamples".into()),
            format!(
                "at most {room} samples of {n_ch} {} channels in the {} bytes left in the chunk",
                format.name(),
                content.len() - p
            ),
            n.to_string(),
        ));
    }
    let n = n as usize;
    acc.timestamps.reserve(n);
    if format.is_numeric() {
        acc.numeric.reserve(n * n_ch);
    } else {
        acc.strings.reserve(n);
    }
    let vb = format.value_bytes().unwrap_or(0);
    for k in 0..n {
        let tsb = content[p];
        let ts = match tsb {
            0 => {
                p += 1;
                acc.last_ts + acc.tdiff
            }
            8 => {
                if p + 9 > content.len() {
                    return Err(ctx.invalid(
                        base + p,
                        field(format!("sample {k} timestamp")),
                        "8 bytes inside the chunk",
                        "the end of the chunk",
                    ));
                }
                let t = le_f64(content, p + 1);
                p += 9;
                t
            }
            other => {
                return Err(ctx.invalid(
                    base + p,
                    field(format!("sample {k} TimeStampBytes")),
                    "0 or 8",
                    other.to_string(),
                ))
            }
        };
        acc.last_ts = ts;
        acc.timestamps.push(ts);
        if format.is_numeric() {
            let need = n_ch * vb;
            let vals = content.get(p..p + need).ok_or_else(|| {
                ctx.invalid(
                    base + p,
                    field(format!("sample {k} values")),
                    format!("{need} bytes inside the chunk"),
                    format!("{} bytes", content.len() - p),
                )
            })?;
            for v in vals.chunks_exact(vb) {
                let x = match format {
                    XdfFormat::Int8 => f64::from(v[0] as i8),
                    XdfFormat::Int16 => f64::from(i16::from_le_bytes([v[0], v[1]])),
                    XdfFormat::Int32 => f64::from(i32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                    XdfFormat::Int64 => le_u64(v) as i64 as f64,
                    XdfFormat::Float32 => f64::from(f32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                    _ => le_f64(v, 0),
                };
                acc.numeric.push(x);
            }
            p += need;
        } else {
            let mut sample = Vec::with_capacity(n_ch);
            for c in 0..n_ch {
                let (len, q) = varlen(content, p).map_err(|(at, found)| {
                    ctx.invalid(
                        base + at,
                        field(format!("sample {k} channel {c} string length")),
                        "a varlen integer (1, 4 or 8 bytes)",
                        found,
                    )
                })?;
                let left = content.len() - q;
                if len > left as u64 {
                    return Err(ctx.invalid(
                        base + p,
                        field(format!("sample {k} channel {c} string length")),
                        format!("at most the {left} bytes left in the chunk"),
                        len.to_string(),
                    ));
                }
                let len = len as usize;
                sample.push(String::from_utf8_lossy(&content[q..q + len]).into_owned());
                p = q + len;
            }
            acc.strings.push(sample);
        }
        if k + 1 < n && p >= content.len() {
            return Err(ctx.invalid(
                base + p,
                field(format!("sample {}", k + 1)),
                format!("{n} samples inside the chunk"),
                "the end of the chunk",
            ));
        }
    }
    if p != content.len() {
        return Err(ctx.invalid(
            base + p,
            field("end".into()),
            format!("the chunk to end after its {n} samples"),
            format!("{} more bytes", content.len() - p),
        ));
    }
    acc.info.n_samples += n;
    acc.info.n_sample_chunks += 1;
    Ok(())
}

fn parse_footer(ctx: &Ctx<'_>, id: u32, xml: &[u8], base: usize) -> Result<XdfFooter, IoError> {
    let (text, root) = ctx.xml(xml, base, "StreamFooter")?;
    let num = |name: &str| -> Result<Option<f64>, IoError> {
        match root.child(name) {
            None => Ok(None),
            Some(n) => parse_f64_text(&n.text).map(Some).ok_or_else(|| {
                ctx.invalid(
                    base + n.text_offset,
                    format!("StreamFooter (stream {id}) {name}"),
                    "a number",
                    n.text.trim(),
                )
            }),
        }
    };
    let first_timestamp = num("first_timestamp")?;
    let last_timestamp = num("last_timestamp")?;
    let sample_count = match root.child("sample_count") {
        None => None,
        Some(n) => Some(n.text.trim().parse::<u64>().map_err(|_| {
            ctx.invalid(
                base + n.text_offset,
                format!("StreamFooter (stream {id}) sample_count"),
                "a whole number",
                n.text.trim(),
            )
        })?),
    };
    Ok(XdfFooter {
        first_timestamp,
        last_timestamp,
        sample_count,
        xml: text,
    })
}

/// Reads an XDF file (every stream with its samples).
pub fn read_xdf_file(path: impl AsRef<Path>) -> Result<XdfFile, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_xdf_file(&bytes, path)
}

/// Parses the bytes of an XDF file; `path` is used in error messages. A file that ends inside a
/// chunk gives every complete chunk and [`XdfFile::truncated`].
pub fn parse_xdf_file(bytes: &[u8], path: &Path) -> Result<XdfFile, IoError> {
    let ctx = Ctx { path };
    let len = bytes.len();
    let mut out = XdfFile {
        header_xml: None,
        version: None,
        streams: Vec::new(),
        n_chunks: 0,
        n_boundaries: 0,
        n_unknown_chunks: 0,
        truncated: false,
        truncated_at: None,
        file_len: len as u64,
    };
    if len < MAGIC.len() && MAGIC.starts_with(bytes) {
        out.truncated = true;
        out.truncated_at = Some(0);
        return Ok(out);
    }
    if len < MAGIC.len() || &bytes[..4] != MAGIC {
        return Err(ctx.invalid(
            0,
            "magic code",
            "\"XDF:\"",
            String::from_utf8_lossy(&bytes[..len.min(4)]),
        ));
    }
    let mut accs: Vec<Acc> = Vec::new();
    let mut index: BTreeMap<u32, usize> = BTreeMap::new();
    let mut pos = MAGIC.len();
    while pos < len {
        let start = pos;
        let nlb = bytes[pos];
        if !matches!(nlb, 1 | 4 | 8) {
            return Err(ctx.invalid(pos, "chunk NumLengthBytes", "1, 4 or 8", nlb.to_string()));
        }
        let nlb = nlb as usize;
        let header_end = pos + 1 + nlb;
        if header_end + 2 > len {
            out.truncated = true;
            out.truncated_at = Some(start as u64);
            break;
        }
        let length = le_u64(&bytes[pos + 1..header_end]);
        if length < 2 {
            return Err(ctx.invalid(
                pos + 1,
                "chunk Length",
                "at least 2 (the tag)",
                length.to_string(),
            ));
        }
        if length > (len - header_end) as u64 {
            out.truncated = true;
            out.truncated_at = Some(start as u64);
            break;
        }
        let end = header_end + length as usize;
        let tag = u16::from_le_bytes([bytes[header_end], bytes[header_end + 1]]);
        let cbase = header_end + 2;
        let content = &bytes[cbase..end];
        let stream_id = |what: &str| -> Result<u32, IoError> {
            if content.len() < 4 {
                return Err(ctx.invalid(
                    cbase,
                    format!("{what} StreamId"),
                    "4 bytes inside the chunk",
                    format!("{} bytes", content.len()),
                ));
            }
            Ok(le_u32(content, 0))
        };
        let known = |id: u32, what: &str, index: &BTreeMap<u32, usize>| -> Result<usize, IoError> {
            index.get(&id).copied().ok_or_else(|| {
                ctx.invalid(
                    cbase,
                    format!("{what} StreamId"),
                    "the id of a stream whose StreamHeader came before",
                    id.to_string(),
                )
            })
        };
        match tag {
            TAG_FILE_HEADER => {
                if out.header_xml.is_some() {
                    return Err(ctx.invalid(
                        start,
                        "FileHeader",
                        "one FileHeader chunk",
                        "a second one",
                    ));
                }
                let (text, root) = ctx.xml(content, cbase, "FileHeader")?;
                out.version = root.child_text("version").map(str::to_string);
                out.header_xml = Some(text);
            }
            TAG_STREAM_HEADER => {
                let id = stream_id("StreamHeader")?;
                if index.contains_key(&id) {
                    return Err(ctx.invalid(
                        cbase,
                        "StreamHeader StreamId",
                        "one StreamHeader per stream",
                        format!("a second one for stream {id}"),
                    ));
                }
                let info = parse_stream_header(&ctx, id, &content[4..], cbase + 4)?;
                let tdiff = if info.nominal_srate > 0.0 {
                    1.0 / info.nominal_srate
                } else {
                    0.0
                };
                index.insert(id, accs.len());
                accs.push(Acc {
                    info,
                    timestamps: Vec::new(),
                    numeric: Vec::new(),
                    strings: Vec::new(),
                    last_ts: 0.0,
                    tdiff,
                });
            }
            TAG_SAMPLES => {
                let id = stream_id("Samples")?;
                let k = known(id, "Samples", &index)?;
                parse_samples(&ctx, content, cbase, &mut accs[k])?;
            }
            TAG_CLOCK_OFFSET => {
                let id = stream_id("ClockOffset")?;
                let k = known(id, "ClockOffset", &index)?;
                if content.len() != 20 {
                    return Err(ctx.invalid(
                        start,
                        "ClockOffset chunk Length",
                        "22 (tag, StreamId, two f64)",
                        (content.len() + 2).to_string(),
                    ));
                }
                accs[k]
                    .info
                    .clock_offsets
                    .push((le_f64(content, 4), le_f64(content, 12)));
            }
            TAG_BOUNDARY => {
                if content != BOUNDARY_UUID {
                    return Err(ctx.invalid(
                        cbase,
                        "Boundary chunk",
                        "the 16 Boundary bytes 43 A5 46 DC …",
                        format!("{} other bytes", content.len()),
                    ));
                }
                out.n_boundaries += 1;
            }
            TAG_STREAM_FOOTER => {
                let id = stream_id("StreamFooter")?;
                let k = known(id, "StreamFooter", &index)?;
                if accs[k].info.footer.is_some() {
                    return Err(ctx.invalid(
                        cbase,
                        "StreamFooter StreamId",
                        "one StreamFooter per stream",
                        format!("a second one for stream {id}"),
                    ));
                }
                accs[k].info.footer = Some(parse_footer(&ctx, id, &content[4..], cbase + 4)?);
            }
            _ => out.n_unknown_chunks += 1,
        }
        out.n_chunks += 1;
        pos = end;
    }

    for acc in accs {
        let Acc {
            mut info,
            timestamps,
            numeric,
            strings,
            ..
        } = acc;
        info.first_timestamp = timestamps.first().copied();
        info.last_timestamp = timestamps.last().copied();
        let values = if info.format.is_numeric() {
            let n_ch = info.channel_count;
            let n_s = timestamps.len();
            let a = Array2::from_shape_vec((n_s, n_ch), numeric)
                .map_err(|e| ctx.invalid(0, "Samples", "whole samples", e.to_string()))?;
            XdfValues::Numeric(a.reversed_axes().as_standard_layout().into_owned())
        } else {
            XdfValues::Strings(strings)
        };
        out.streams.push(XdfStreamData {
            info,
            timestamps,
            values,
        });
    }
    Ok(out)
}

/// Reads an XDF recording with default options (see the module documentation).
pub fn read_xdf(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_xdf_with(path, &XdfOptions::default())
}

/// Reads an XDF recording with the given options.
pub fn read_xdf_with(path: impl AsRef<Path>, options: &XdfOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_xdf_with(&bytes, path, options)
}

/// Parses the bytes of an XDF recording with default options; `path` is used in error messages
/// and the result.
pub fn parse_xdf(bytes: &[u8], path: &Path) -> Result<Recording, IoError> {
    parse_xdf_with(bytes, path, &XdfOptions::default())
}

/// The factor from an XDF channel unit to µV (`None`: not a voltage unit).
pub fn unit_factor_to_uv(unit: &str) -> Option<f64> {
    let u = unit.trim();
    match u.to_ascii_lowercase().as_str() {
        "volt" | "volts" => Some(1e6),
        "millivolt" | "millivolts" => Some(1e3),
        "microvolt" | "microvolts" => Some(1.0),
        "nanovolt" | "nanovolts" => Some(1e-3),
        _ => volt_factor_to_uv(u),
    }
}

/// `(a, b)` of the least-squares line `offset = a + b·t` through the finite clock offsets.
fn clock_fit(offsets: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = offsets
        .iter()
        .copied()
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .collect();
    if pts.is_empty() {
        return None;
    }
    let n = pts.len() as f64;
    let mt = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let mv = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let stt: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
    let stv: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
    let b = if stt > 0.0 { stv / stt } else { 0.0 };
    let (a, b) = (mv - b * mt, b);
    (a.is_finite() && b.is_finite()).then_some((a, b))
}

/// The number a text ends in, after a space, `_`, `:`, `=` or `#` (`flash 3` → 3).
fn trailing_code(text: &str) -> Option<u32> {
    let t = text.trim_end();
    let digits = t.len() - t.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 || digits == t.len() {
        return None;
    }
    let before = t[..t.len() - digits].chars().next_back()?;
    if !(before.is_whitespace() || matches!(before, '_' | ':' | '=' | '#')) {
        return None;
    }
    t[t.len() - digits..].parse().ok()
}

fn is_marker_type(t: &str) -> bool {
    let t = t.to_ascii_lowercase();
    ["marker", "event", "trigger", "stim"]
        .iter()
        .any(|k| t.contains(k))
}

/// The sample whose timestamp is nearest `t`; `None` outside the span (± half a sample).
fn nearest_sample(times: &[f64], monotonic: bool, sfreq: f64, t: f64) -> Option<usize> {
    let (&first, &last) = (times.first()?, times.last()?);
    if !t.is_finite() {
        return None;
    }
    let half = 0.5 / sfreq;
    if monotonic {
        if t < first - half || t > last + half {
            return None;
        }
        let i = times.partition_point(|&x| x < t);
        if i == 0 {
            return Some(0);
        }
        if i == times.len() {
            return Some(times.len() - 1);
        }
        Some(if t - times[i - 1] <= times[i] - t {
            i - 1
        } else {
            i
        })
    } else {
        let pos = ((t - first) * sfreq).round();
        (pos >= 0.0 && pos < times.len() as f64).then_some(pos as usize)
    }
}

/// Parses the bytes of an XDF recording with the given options.
pub fn parse_xdf_with(
    bytes: &[u8],
    path: &Path,
    options: &XdfOptions,
) -> Result<Recording, IoError> {
    let mut file = parse_xdf_file(bytes, path)?;
    if file.truncated && !options.allow_truncated {
        let at = file.truncated_at.unwrap_or(0);
        return Err(IoError::Truncated {
            path: path.to_path_buf(),
            field: "chunk".into(),
            offset: at,
            needed: at + 1,
            file_len: file.file_len,
        });
    }
    let names: Vec<String> = file.streams.iter().map(|s| s.info.name.clone()).collect();
    let numeric = |s: &&XdfStreamData| s.info.format.is_numeric();
    let first_max = |it: &mut dyn Iterator<Item = usize>| -> Option<usize> {
        let mut best: Option<usize> = None;
        for k in it {
            if best.is_none_or(|b| {
                file.streams[k].info.channel_count > file.streams[b].info.channel_count
            }) {
                best = Some(k);
            }
        }
        best
    };
    let eeg = match &options.eeg_stream {
        Some(name) => file
            .streams
            .iter()
            .position(|s| &s.info.name == name && s.info.format.is_numeric())
            .ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "numeric XDF stream",
                name: name.clone(),
                available: names.clone(),
            })?,
        None => {
            let typed = first_max(
                &mut file
                    .streams
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| numeric(s) && s.info.stream_type.eq_ignore_ascii_case("EEG"))
                    .map(|(k, _)| k),
            );
            let regular = || {
                first_max(
                    &mut file
                        .streams
                        .iter()
                        .enumerate()
                        .filter(|(_, s)| numeric(s) && s.info.nominal_srate > 0.0)
                        .map(|(k, _)| k),
                )
            };
            typed.or_else(regular).ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "XDF EEG stream",
                name: "type EEG or a regular-rate numeric stream".into(),
                available: names.clone(),
            })?
        }
    };
    let sfreq = file.streams[eeg].info.nominal_srate;
    if sfreq <= 0.0 {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "stream {:?} as EEG: its rate is irregular (nominal_srate 0)",
                file.streams[eeg].info.name
            ),
        });
    }

    // Clock synchronization.
    let mut synced: Vec<Vec<f64>> = Vec::with_capacity(file.streams.len());
    for s in &mut file.streams {
        let fit = if options.synchronize_clocks {
            clock_fit(&s.info.clock_offsets)
        } else {
            None
        };
        s.info.clock_fit = fit;
        synced.push(match fit {
            Some((a, b)) => s.timestamps.iter().map(|&t| t + a + b * t).collect(),
            None => s.timestamps.clone(),
        });
    }

    // The EEG.
    let eeg_stream = &file.streams[eeg];
    let n_ch = eeg_stream.info.channel_count;
    let XdfValues::Numeric(values) = &eeg_stream.values else {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "a string stream as EEG".into(),
        });
    };
    let mut data = values.clone();
    let mut eeg_units = Vec::with_capacity(n_ch);
    let mut scale_to_uv = Vec::with_capacity(n_ch);
    let mut ch_names = Vec::with_capacity(n_ch);
    for c in 0..n_ch {
        let label = eeg_stream
            .info
            .channel_labels
            .get(c)
            .map(|l| l.trim())
            .unwrap_or("");
        ch_names.push(if label.is_empty() {
            format!("Ch{}", c + 1)
        } else {
            label.to_string()
        });
        let unit = eeg_stream
            .info
            .channel_units
            .get(c)
            .cloned()
            .unwrap_or_default();
        let f = unit_factor_to_uv(&unit).unwrap_or(1.0);
        if f != 1.0 {
            data.row_mut(c).mapv_inplace(|x| x * f);
        }
        eeg_units.push(unit);
        scale_to_uv.push(f);
    }
    let eeg_times = &synced[eeg];
    let monotonic = eeg_times.windows(2).all(|w| w[0] <= w[1]);

    // Markers.
    struct Raw1 {
        stream_id: u32,
        timestamp: f64,
        synced: f64,
        text: String,
    }
    let mut raw_markers = Vec::new();
    for (k, s) in file.streams.iter().enumerate() {
        if k == eeg {
            continue;
        }
        match &s.values {
            XdfValues::Strings(v) => {
                for (i, sample) in v.iter().enumerate() {
                    raw_markers.push(Raw1 {
                        stream_id: s.info.id,
                        timestamp: s.timestamps[i],
                        synced: synced[k][i],
                        text: sample.join("\t"),
                    });
                }
            }
            XdfValues::Numeric(a)
                if s.info.channel_count == 1
                    && s.info.nominal_srate == 0.0
                    && is_marker_type(&s.info.stream_type) =>
            {
                for (i, &x) in a.row(0).iter().enumerate() {
                    raw_markers.push(Raw1 {
                        stream_id: s.info.id,
                        timestamp: s.timestamps[i],
                        synced: synced[k][i],
                        text: format!("{x}"),
                    });
                }
            }
            XdfValues::Numeric(_) => {}
        }
    }
    let parsed: Vec<Option<crate::edf::EventText>> = raw_markers
        .iter()
        .map(|m| {
            crate::edf::parse_event_text(&m.text)
                .or_else(|| trailing_code(&m.text).map(|c| (c, None, Some(m.text.clone()))))
        })
        .collect();
    let max_code = parsed.iter().flatten().map(|p| p.0).max().unwrap_or(0);
    let mut text_codes: BTreeMap<String, u32> = BTreeMap::new();
    let mut next = max_code.saturating_add(1);
    let mut markers = Vec::with_capacity(raw_markers.len());
    let mut events = Vec::new();
    for (m, p) in raw_markers.into_iter().zip(parsed) {
        let (code, target, label) = match p {
            Some(p) => p,
            None => {
                let code = *text_codes.entry(m.text.clone()).or_insert_with(|| {
                    let c = next;
                    next = next.saturating_add(1);
                    c
                });
                (code, None, Some(m.text.clone()))
            }
        };
        let sample = nearest_sample(eeg_times, monotonic, sfreq, m.synced);
        if let Some(onset) = sample {
            events.push(Event {
                onset,
                code,
                target,
                label,
            });
        }
        markers.push(XdfMarker {
            stream_id: m.stream_id,
            timestamp: m.timestamp,
            text: m.text,
            code,
            target,
            sample,
        });
    }

    let raw =
        Raw::new(data, sfreq, ch_names, Events::new(events)).map_err(|source| IoError::Signal {
            path: path.to_path_buf(),
            source,
        })?;
    let eeg_timestamps = synced.swap_remove(eeg);
    let info = XdfInfo {
        version: file.version,
        header_xml: file.header_xml,
        streams: file.streams.into_iter().map(|s| s.info).collect(),
        eeg_stream: eeg,
        eeg_timestamps,
        eeg_units,
        scale_to_uv,
        markers,
        truncated: file.truncated,
        truncated_at: file.truncated_at,
        n_chunks: file.n_chunks,
        n_boundaries: file.n_boundaries,
        n_unknown_chunks: file.n_unknown_chunks,
    };
    Ok(Recording {
        raw,
        format: Format::Xdf,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Xdf(Box::new(info)),
    })
}

/// Whether the file at `path` starts with the XDF magic code.
pub(crate) fn has_magic(path: &Path) -> bool {
    let mut head = [0u8; 4];
    File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .map(|()| &head == MAGIC)
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_reader() {
        let x = "\u{feff}<?xml version=\"1.0\"?>\n<!-- c --><info a='1' b = \"x>y\"><name>A &amp; B &#x263A;</name>\
                 <desc/><n><![CDATA[<raw>]]></n><channels><channel><label> Cz </label></channel>\
                 <channel><label>Pz</label></channel></channels></info>\n";
        let r = parse_xml(x).unwrap();
        assert_eq!(r.name, "info");
        assert_eq!(r.child_text("name"), Some("A & B \u{263A}"));
        assert_eq!(r.child_text("n"), Some("<raw>"));
        assert!(r.child("desc").unwrap().children.is_empty());
        let labels: Vec<_> = r
            .child("channels")
            .unwrap()
            .children_named("channel")
            .map(|c| c.child_text("label").unwrap())
            .collect();
        assert_eq!(labels, ["Cz", "Pz"]);
        let cz = &r.child("channels").unwrap().children[0].children[0];
        assert_eq!(&x[cz.text_offset..cz.text_offset + 2], "Cz");
        for bad in [
            "<a><b></a>",
            "<a>",
            "x<a/>",
            "<a/><b/>",
            "<a>&bogus;</a>",
            "<a x=1/>",
            "<a></a>z",
            "",
            "<",
            "</a>",
            "<a><!--</a>",
        ] {
            assert!(parse_xml(bad).is_err(), "{bad:?}");
        }
        let deep = "<a>".repeat(100);
        assert!(parse_xml(&deep).is_err());
    }

    #[test]
    fn varlen_and_chunks() {
        for n in [
            0u64,
            255,
            256,
            65_536,
            u64::from(u32::MAX),
            u64::from(u32::MAX) + 1,
        ] {
            let mut b = Vec::new();
            put_varlen(&mut b, n);
            assert_eq!(varlen(&b, 0).unwrap(), (n, b.len()));
        }
        assert!(varlen(&[2, 0, 0], 0).is_err());
        assert!(varlen(&[4, 0, 0], 0).is_err());
        assert!(varlen(&[], 0).is_err());
    }

    #[test]
    fn marker_texts() {
        assert_eq!(
            crate::edf::parse_event_text("3 target: Ä b"),
            Some((3, Some(true), Some("Ä b".into())))
        );
        assert_eq!(crate::edf::parse_event_text("12"), Some((12, None, None)));
        assert_eq!(crate::edf::parse_event_text("flash 3"), None);
        assert_eq!(trailing_code("flash 3"), Some(3));
        assert_eq!(trailing_code("S  12"), Some(12));
        assert_eq!(trailing_code("stim:7"), Some(7));
        assert_eq!(trailing_code("P300"), None);
        assert_eq!(trailing_code("-1"), None);
        assert_eq!(trailing_code("42"), None);
        assert_eq!(trailing_code("flash 99999999999"), None);
    }

    #[test]
    fn units() {
        assert_eq!(unit_factor_to_uv("microvolts"), Some(1.0));
        assert_eq!(unit_factor_to_uv("Volts"), Some(1e6));
        assert_eq!(unit_factor_to_uv("millivolts"), Some(1e3));
        assert_eq!(unit_factor_to_uv("nanovolts"), Some(1e-3));
        assert_eq!(unit_factor_to_uv("uV"), Some(1.0));
        assert_eq!(unit_factor_to_uv("µV"), Some(1.0));
        assert_eq!(unit_factor_to_uv("degC"), None);
        assert_eq!(unit_factor_to_uv(""), None);
    }

    #[test]
    fn clock_fits() {
        assert_eq!(clock_fit(&[]), None);
        assert_eq!(clock_fit(&[(5.0, 0.25)]), Some((0.25, 0.0)));
        let (a, b) = clock_fit(&[(0.0, 1.0), (10.0, 2.0), (20.0, 3.0)]).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 0.1).abs() < 1e-12);
    }

    #[test]
    fn nearest() {
        let t = [1.0, 1.5, 2.0, 3.0];
        assert_eq!(nearest_sample(&t, true, 2.0, 1.2), Some(0));
        assert_eq!(nearest_sample(&t, true, 2.0, 1.3), Some(1));
        assert_eq!(nearest_sample(&t, true, 2.0, 2.6), Some(3));
        assert_eq!(nearest_sample(&t, true, 2.0, 0.75), Some(0));
        assert_eq!(nearest_sample(&t, true, 2.0, 0.7499), None);
        assert_eq!(nearest_sample(&t, true, 2.0, 3.3), None);
        assert_eq!(nearest_sample(&t, true, 2.0, f64::NAN), None);
        assert_eq!(nearest_sample(&[], true, 2.0, 1.0), None);
        assert_eq!(nearest_sample(&[2.0, 1.0], false, 1.0, 2.0), Some(0));
    }
}
