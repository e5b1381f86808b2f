//! What a GDF file holds besides the samples ([`GdfInfo`]: headers, the event table, what
//! OpenViBE's stimulation codes made of it), the data types, and the options of the reader.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The number type of a channel's samples (`GDFTYP`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GdfType {
    Int8,
    Uint8,
    Int16,
    Uint16,
    /// Signed 24-bit integer (`GDFTYP` 279 = 255 + 24).
    Int24,
    /// Unsigned 24-bit integer (`GDFTYP` 535 = 511 + 24).
    Uint24,
    Int32,
    Uint32,
    Int64,
    Uint64,
    Float32,
    Float64,
}

impl GdfType {
    /// The type of a `GDFTYP` code, if this reader reads it.
    pub fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            1 => GdfType::Int8,
            2 => GdfType::Uint8,
            3 => GdfType::Int16,
            4 => GdfType::Uint16,
            5 => GdfType::Int32,
            6 => GdfType::Uint32,
            7 => GdfType::Int64,
            8 => GdfType::Uint64,
            16 => GdfType::Float32,
            17 => GdfType::Float64,
            279 => GdfType::Int24,
            535 => GdfType::Uint24,
            _ => return None,
        })
    }

    /// The `GDFTYP` code.
    pub fn code(self) -> u32 {
        match self {
            GdfType::Int8 => 1,
            GdfType::Uint8 => 2,
            GdfType::Int16 => 3,
            GdfType::Uint16 => 4,
            GdfType::Int32 => 5,
            GdfType::Uint32 => 6,
            GdfType::Int64 => 7,
            GdfType::Uint64 => 8,
            GdfType::Float32 => 16,
            GdfType::Float64 => 17,
            GdfType::Int24 => 279,
            GdfType::Uint24 => 535,
        }
    }

    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            GdfType::Int8 | GdfType::Uint8 => 1,
            GdfType::Int16 | GdfType::Uint16 => 2,
            GdfType::Int24 | GdfType::Uint24 => 3,
            GdfType::Int32 | GdfType::Uint32 | GdfType::Float32 => 4,
            GdfType::Int64 | GdfType::Uint64 | GdfType::Float64 => 8,
        }
    }

    /// The value of one little-endian sample; `b` holds exactly [`GdfType::bytes`] bytes.
    /// 64-bit integers beyond ±2⁵³ are rounded to the nearest `f64`.
    pub(super) fn decode(self, b: &[u8]) -> f64 {
        let mut w = [0u8; 8];
        w[..b.len()].copy_from_slice(b);
        match self {
            GdfType::Int8 => f64::from(w[0] as i8),
            GdfType::Uint8 => f64::from(w[0]),
            GdfType::Int16 => f64::from(i16::from_le_bytes([w[0], w[1]])),
            GdfType::Uint16 => f64::from(u16::from_le_bytes([w[0], w[1]])),
            GdfType::Int24 => f64::from(i32::from_le_bytes([0, w[0], w[1], w[2]]) >> 8),
            GdfType::Uint24 => f64::from(u32::from_le_bytes([w[0], w[1], w[2], 0])),
            GdfType::Int32 => f64::from(i32::from_le_bytes([w[0], w[1], w[2], w[3]])),
            GdfType::Uint32 => f64::from(u32::from_le_bytes([w[0], w[1], w[2], w[3]])),
            GdfType::Float32 => f64::from(f32::from_le_bytes([w[0], w[1], w[2], w[3]])),
            GdfType::Int64 => i64::from_le_bytes(w) as f64,
            GdfType::Uint64 => u64::from_le_bytes(w) as f64,
            GdfType::Float64 => f64::from_le_bytes(w),
        }
    }
}

/// One channel header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GdfChannel {
    pub label: String,
    pub transducer: String,
    /// The physical dimension as text: GDF 1.x's field (e.g. `uV`); in GDF 2.x the unit of
    /// [`GdfChannel::dimension_code`] (`kV`, `V`, `mV`, `uV`, `nV` for volts, else the code as
    /// text), or the obsolete text field when the code is 0.
    pub dimension: String,
    /// GDF 2.x physical dimension code (4256 = V, 4274 = mV, 4275 = µV, …); `None` in GDF 1.x.
    pub dimension_code: Option<u16>,
    pub physical_min: f64,
    pub physical_max: f64,
    pub digital_min: f64,
    pub digital_max: f64,
    /// GDF 1.x prefiltering text (empty in GDF 2.x, which gives the three filters below).
    pub prefiltering: String,
    /// GDF 2.x low-pass, high-pass and notch frequencies in Hz, as stored (`None` in GDF 1.x).
    pub filters: Option<[f32; 3]>,
    pub samples_per_record: usize,
    pub data_type: GdfType,
}

/// The fixed header and the channel headers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GdfHeader {
    /// The version after `GDF `, e.g. `1.25` or `2.20`.
    pub version: String,
    /// 1 or 2.
    pub major: u8,
    pub patient: String,
    pub recording: String,
    /// GDF 1.x start date and time as stored (`YYYYMMDDhhmmsscc`); GDF 2.x: the 64-bit start
    /// date as decimal text (days since year 0 × 2³²; `0` when unknown).
    pub start: String,
    /// Bytes before the first data record (fixed header, channel headers and, in GDF 2.x, the
    /// tag-length-value header 3, which is skipped).
    pub header_bytes: usize,
    pub n_records: usize,
    /// Duration of a data record in seconds, as the stored fraction (numerator, denominator).
    pub record_duration: (u32, u32),
    pub channels: Vec<GdfChannel>,
}

/// One entry of the event table, as stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GdfEvent {
    /// Position in samples of the event table's rate, **1-based** as stored (position 1 is
    /// the first sample).
    pub position: u32,
    /// Event type (`TYP`): a GDF event code, or an OpenViBE stimulation code.
    pub typ: u16,
    /// Channel (0 = all), mode 3 only; 0 in mode 1.
    pub channel: u16,
    /// Duration in samples, mode 3 only; 0 in mode 1.
    pub duration: u32,
}

/// The event table after the data records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GdfEventTable {
    /// 1 (position, type) or 3 (position, type, channel, duration).
    pub mode: u8,
    /// The table's sample rate in Hz as stored; 0 means the data's rate.
    pub sample_rate: f64,
    pub events: Vec<GdfEvent>,
}

/// What the OpenViBE stimulation codes of a file made (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OpenVibeEvents {
    /// Label codes given twice at the same sample (each pair made one flash).
    pub duplicate_labels: usize,
    /// Target / non-target flags with no label within 2 samples.
    pub orphan_flags: usize,
    /// Flashes with no target / non-target flag (their target is unknown).
    pub unflagged_labels: usize,
    /// Samples of the trial starts (0x8005), in order.
    pub trial_starts: Vec<usize>,
    /// Flashes from each trial start to the next (the last: to the end of the recording).
    pub flashes_per_trial: Vec<usize>,
    /// How many table entries carry each code that is not a flash (label) or a flag
    /// (0x8001 experiment start, 0x8005/0x8006 trial start/stop, 0x800B/0x800C visual
    /// stimulation start/stop, …), outside the recording included.
    pub other_codes: BTreeMap<u16, usize>,
}

/// What a GDF file held besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GdfInfo {
    pub header: GdfHeader,
    /// The event table; `None` when the file ends with the data records.
    pub event_table: Option<GdfEventTable>,
    /// Table entries whose position lies outside the recording (not events).
    pub events_outside: usize,
    /// Set when the table holds OpenViBE stimulation codes and the events are its flashes.
    pub openvibe: Option<OpenVibeEvents>,
    /// Bytes after the event table (read past and counted).
    pub trailing_bytes: usize,
    /// Channels left out for their sample rate ([`GdfOptions::drop_mismatched_rates`]).
    pub dropped_channels: Vec<String>,
    /// Kept channels whose dimension is not a voltage: their values are not scaled to µV.
    pub non_voltage_channels: Vec<String>,
}

/// Options of [`read_gdf_with`](super::read_gdf_with).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GdfOptions {
    /// Drop channels whose samples per record differ from the first kept channel's, instead
    /// of failing.
    pub drop_mismatched_rates: bool,
    /// Channel labels to leave out.
    pub exclude: Vec<String>,
}
