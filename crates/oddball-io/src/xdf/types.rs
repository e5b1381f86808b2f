//! What the XDF writer and reader share: the magic code, chunk tags and limits, the number
//! types of stream values ([`XdfFormat`]) and a stream to write ([`XdfStream`]).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use serde::{Deserialize, Serialize};

/// The four bytes every XDF file starts with.
pub const MAGIC: &[u8; 4] = b"XDF:";

/// The content of every Boundary chunk (a fixed UUID readers can search for).
pub const BOUNDARY_UUID: [u8; 16] = [
    0x43, 0xA5, 0x46, 0xDC, 0xCB, 0xF5, 0x41, 0x0F, 0xB3, 0x0E, 0xD5, 0x46, 0x73, 0x83, 0xCB, 0xE4,
];

/// The most channels a stream may have (read or written).
pub const MAX_CHANNELS: usize = 10_000;

/// Seconds of data between the Boundary chunks [`XdfWriter`](super::XdfWriter) writes.
pub const BOUNDARY_INTERVAL_S: f64 = 10.0;

pub(super) const TAG_FILE_HEADER: u16 = 1;
pub(super) const TAG_STREAM_HEADER: u16 = 2;
pub(super) const TAG_SAMPLES: u16 = 3;
pub(super) const TAG_CLOCK_OFFSET: u16 = 4;
pub(super) const TAG_BOUNDARY: u16 = 5;
pub(super) const TAG_STREAM_FOOTER: u16 = 6;

/// The deepest XML nesting read.
pub(super) const MAX_XML_DEPTH: usize = 64;

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

/// Whether the file at `path` starts with the XDF magic code.
pub(crate) fn has_magic(path: &Path) -> bool {
    let mut head = [0u8; 4];
    File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .map(|()| &head == MAGIC)
        .unwrap_or(false)
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
    /// `(a, b)` of the clock correction `t + a + b·t` applied by `read_xdf` (when
    /// synchronizing and the stream has clock offsets).
    pub clock_fit: Option<(f64, f64)>,
    pub footer: Option<XdfFooter>,
}

/// A StreamFooter's values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfFooter {
    pub first_timestamp: Option<f64>,
    pub last_timestamp: Option<f64>,
    pub sample_count: Option<u64>,
    /// The footer XML as written.
    pub xml: String,
}
