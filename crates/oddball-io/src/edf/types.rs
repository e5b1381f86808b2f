//! What an EDF/BDF file holds besides the samples ([`EdfInfo`]: headers, annotations), and the
//! options of the reader.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One signal header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdfSignal {
    pub label: String,
    pub transducer: String,
    /// Physical dimension, e.g. `uV`.
    pub dimension: String,
    pub physical_min: f64,
    pub physical_max: f64,
    pub digital_min: i32,
    pub digital_max: i32,
    pub prefiltering: String,
    pub samples_per_record: usize,
    pub reserved: String,
}

impl EdfSignal {
    /// Whether this is an `EDF Annotations` / `BDF Annotations` signal.
    pub fn is_annotation(&self) -> bool {
        self.label == "EDF Annotations" || self.label == "BDF Annotations"
    }
}

/// The fixed header and the signal headers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdfHeader {
    /// `0` for EDF, `BIOSEMI` for BDF (the leading 0xFF byte dropped).
    pub version: String,
    pub patient: String,
    pub recording: String,
    /// `dd.mm.yy` as stored.
    pub start_date: String,
    /// `hh.mm.ss` as stored.
    pub start_time: String,
    pub header_bytes: usize,
    /// The reserved field: `EDF+C`, `EDF+D`, `BDF+C`, `24BIT`, or blank.
    pub reserved: String,
    pub n_records: usize,
    /// Seconds per data record.
    pub record_duration: f64,
    pub signals: Vec<EdfSignal>,
}

/// One EDF+ annotation (time stamps excluded).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Annotation {
    /// Seconds from the file's start date/time.
    pub onset: f64,
    /// Seconds, when the TAL gives one.
    pub duration: Option<f64>,
    pub text: String,
}

/// What an EDF/BDF file held besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdfInfo {
    pub header: EdfHeader,
    /// Every annotation, including those outside the recording (which are not events).
    pub annotations: Vec<Annotation>,
    /// The code given to each non-numeric annotation text.
    pub label_codes: BTreeMap<String, u32>,
    /// Seconds from the start date/time to the first sample (EDF+ time stamp of record 0).
    pub start_offset: f64,
    /// Data signals left out for their sample rate ([`EdfOptions::drop_mismatched_rates`]).
    pub dropped_signals: Vec<String>,
    /// Kept signals whose dimension is not a voltage: their values are not scaled to µV.
    pub non_voltage_signals: Vec<String>,
}

/// Options of [`read_edf_with`](super::read_edf_with).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EdfOptions {
    /// Drop data signals whose samples per record differ from the first data signal's, instead
    /// of failing.
    pub drop_mismatched_rates: bool,
    /// Signal labels to leave out (e.g. a BioSemi `Status` channel).
    pub exclude: Vec<String>,
}
