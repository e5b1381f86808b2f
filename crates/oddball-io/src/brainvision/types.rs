//! What a BrainVision recording holds besides the samples ([`BrainVisionInfo`]: the header's
//! settings, the channels and every marker).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// `[Binary Infos] BinaryFormat`: the number type of the data file (little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BvBinaryFormat {
    /// `INT_16`: two-byte signed integers.
    Int16,
    /// `INT_32`: four-byte signed integers.
    Int32,
    /// `IEEE_FLOAT_32`: four-byte floats.
    Float32,
}

impl BvBinaryFormat {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Self::Int16 => 2,
            Self::Int32 | Self::Float32 => 4,
        }
    }

    /// The header's spelling (`INT_16`, `INT_32`, `IEEE_FLOAT_32`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Int16 => "INT_16",
            Self::Int32 => "INT_32",
            Self::Float32 => "IEEE_FLOAT_32",
        }
    }
}

/// `[Common Infos] DataOrientation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BvOrientation {
    /// `MULTIPLEXED` (the default): all channels of sample 0, then of sample 1, …
    Multiplexed,
    /// `VECTORIZED`: all samples of channel 0, then of channel 1, …
    Vectorized,
}

/// One `[Channel Infos]` entry: `ChN=Name,Reference,Resolution,Unit`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BvChannel {
    /// The name, `\1` turned back into a comma.
    pub name: String,
    /// The reference channel's name (often empty).
    pub reference: String,
    /// Units per stored value (an empty field is 1).
    pub resolution: f64,
    /// The unit as written (an empty field is µV).
    pub unit: String,
}

/// One `[Marker Infos]` entry: `MkN=Type,Description,Position,Size,Channel[,Date]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BvMarker {
    /// `Stimulus`, `Response`, `New Segment`, `Comment` …
    pub kind: String,
    /// `S  1`, `R  3`, free text …
    pub description: String,
    /// The 0-based sample (the file's 1-based position minus one).
    pub onset: usize,
    /// Length in samples (an empty field is 0).
    pub size: u64,
    /// The channel it belongs to, 0 for all (an empty field is 0).
    pub channel: i64,
    /// The date of a `New Segment` marker (`YYYYMMDDhhmmssuuuuuu`), when given.
    pub date: Option<String>,
    /// The event it became, if any: its code.
    pub code: Option<u32>,
}

/// What a BrainVision recording held besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrainVisionInfo {
    /// The first line of the header file (`Brain Vision Data Exchange Header File Version 1.0`).
    pub version_line: String,
    /// The text encoding the header was read in: `UTF-8`, `Latin-1` or `cp1252`.
    pub encoding: String,
    /// The binary data file (`DataFile`, beside the header).
    pub data_file: PathBuf,
    /// The marker file (`MarkerFile`), when the header names one.
    pub marker_file: Option<PathBuf>,
    pub binary_format: BvBinaryFormat,
    pub orientation: BvOrientation,
    /// `SamplingInterval` in µs.
    pub sampling_interval_us: f64,
    pub channels: Vec<BvChannel>,
    /// Every marker of the marker file, in file order (those beyond the data included).
    pub markers: Vec<BvMarker>,
    /// The code given to each `Stimulus`/`Response` description that is not a number.
    pub label_codes: BTreeMap<String, u32>,
    /// Channels whose unit is not a voltage: their values are only multiplied by the
    /// resolution, not scaled to µV.
    pub non_voltage_channels: Vec<String>,
}
