//! What a FIF raw file holds besides the EEG samples and events ([`FifInfo`]).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// One channel record (`FIFF_CH_INFO`, with the extended `FIFFB_CH_INFO` block applied).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FifChannel {
    /// The full name (the extended block's `FIFF_CH_DACQ_NAME` when there is one; the record
    /// itself holds at most 15 characters).
    pub name: String,
    /// `FIFFV_*_CH`: 1 MEG, 2 EEG, 3 STIM, 202 EOG, 302 EMG, 402 ECG, 502 MISC, …
    pub kind: i32,
    pub scan_no: i32,
    pub logical_no: i32,
    /// Stored value × `range` × `cal` = the value in the channel's unit.
    pub range: f32,
    pub cal: f32,
    pub coil_type: i32,
    /// `FIFF_UNIT_*`: 107 = volt, -1 = none, …
    pub unit: i32,
    /// Unit exponent (`FIFF_UNITM_*`: 0, -3, -6, …).
    pub unit_mul: i32,
}

impl FifChannel {
    /// `FIFFV_EEG_CH`.
    pub const EEG: i32 = 2;
    /// `FIFFV_STIM_CH`.
    pub const STIM: i32 = 3;
    /// `FIFF_UNIT_V`.
    pub const VOLT: i32 = 107;

    /// MNE's name for the channel kind (`eeg`, `stim`, `eog`, …, or the number).
    pub fn kind_name(&self) -> String {
        match self.kind {
            1 => "meg".into(),
            2 => "eeg".into(),
            3 => "stim".into(),
            102 => "bio".into(),
            201 => "mcg".into(),
            202 => "eog".into(),
            301 => "ref_meg".into(),
            302 => "emg".into(),
            402 => "ecg".into(),
            502 => "misc".into(),
            602 => "resp".into(),
            802 => "seeg".into(),
            803 => "dbs".into(),
            900 => "syst".into(),
            902 => "ecog".into(),
            910 => "ias".into(),
            920 => "exci".into(),
            1100 => "fnirs".into(),
            1200 => "temperature".into(),
            1300 => "gsr".into(),
            1400 => "eyetrack".into(),
            k => format!("kind {k}"),
        }
    }
}

/// One MNE annotation as stored (`FIFFB_MNE_ANNOTATIONS`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FifAnnotation {
    /// Seconds from the annotations' `orig_time` (the measurement date), or, in a file without
    /// one, from sample 0 of the acquisition (so `first_samp / sfreq` is the first sample read).
    pub onset: f64,
    /// Seconds (`FIFF_MNE_BASELINE_MAX` − onset, as MNE computes it).
    pub duration: f64,
    pub description: String,
    /// The recording's sample it falls on (MNE's `events_from_annotations` rounding, an
    /// annotation that starts before the first sample but reaches it clipped to sample 0);
    /// `None` when outside the recording. Those with a sample are events.
    pub sample: Option<usize>,
}

/// A stretch of the recording that the file leaves out (`FIFF_DATA_SKIP`), read as zeros as MNE
/// reads it (MNE also annotates it `BAD_ACQ_SKIP`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FifSkip {
    /// First zero-filled sample, from the recording's first sample.
    pub start: usize,
    /// Number of samples.
    pub len: usize,
}

/// The number type of the data buffers (MNE's `orig_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FifDataType {
    /// `FIFFT_SHORT` or `FIFFT_DAU_PACK16` (16-bit integers; MNE's `fmt="short"`).
    Short,
    /// `FIFFT_INT` (32-bit integers).
    Int,
    /// `FIFFT_FLOAT` (float32; MNE's default `fmt="single"`).
    Float,
    /// `FIFFT_DOUBLE` (float64).
    Double,
}

/// What a FIF raw file held besides the EEG samples and events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FifInfo {
    /// Every channel of the file, in file order.
    pub channels: Vec<FifChannel>,
    /// The STIM channels the events were found on (see the module docs).
    pub stim_channels: Vec<String>,
    /// Channels not kept: every kind but EEG, and the STIM channels not used for events.
    pub dropped_channels: Vec<String>,
    /// Kept EEG channels whose unit is not the volt: their values are not scaled to µV.
    pub non_voltage_channels: Vec<String>,
    /// The acquisition sample number of the first sample read (`FIFF_FIRST_SAMPLE`, plus an
    /// initial skip).
    pub first_samp: i64,
    /// `FIFF_MEAS_DATE` of the measurement info: seconds and microseconds since 1970 (UTC).
    pub meas_date: Option<(i64, i64)>,
    /// The annotations' `orig_time`, microseconds since 1970, when stored.
    pub annotations_orig_time: Option<i64>,
    /// Every annotation of the (first) file, including those outside the recording.
    pub annotations: Vec<FifAnnotation>,
    /// The code given to each annotation text that is not of the form `CODE [target|nontarget]`.
    pub label_codes: BTreeMap<String, u32>,
    /// Zero-filled acquisition skips.
    pub skips: Vec<FifSkip>,
    /// The number type of the first data buffer.
    pub data_type: FifDataType,
    /// Every file read: the one given, then the split parts it names (`FIFFB_REF`).
    pub parts: Vec<PathBuf>,
}
