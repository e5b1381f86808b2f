//! The options of the `.easy` reader and what a file and its `.info` held besides the EEG.

use std::path::PathBuf;

use ndarray::Array2;
use serde::{Deserialize, Serialize};

/// The EEG channel counts of Neuroelectrics devices, used to find the layout of a file read
/// without a channel count from the `.info` or the options.
pub const STANDARD_CHANNEL_COUNTS: [usize; 3] = [8, 20, 32];

/// The trigger value NIC writes when packets were lost (skipped as an event by default).
pub const NIC_PACKET_LOSS_CODE: u32 = 255;

/// The largest timestamp read or written, in ms: 2⁵³ (every value up to it is exact in `f64`).
pub const MAX_TIMESTAMP_MS: u64 = 1 << 53;

/// The largest |EEG value| read or written, in µV: the int32 range of nV.
pub(super) const MAX_ABS_UV: f64 = i32::MAX as f64 / 1000.0;

/// The largest channel count a `.info` may state.
pub(super) const MAX_INFO_CHANNELS: usize = 1024;

/// The largest sampling rate a `.info` may state, in Hz.
pub(super) const MAX_INFO_SFREQ: f64 = oddball_signal::SFREQ_MAX;

/// Which `.info` file [`read_easy_with`](super::read_easy_with) reads.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum EasyInfoFile {
    /// The file beside the `.easy` with the same stem and extension `.info`, when it exists.
    #[default]
    Beside,
    /// This file (an error when it cannot be read).
    At(PathBuf),
    /// None: channel names, layout and rate from the options, the defaults and the timestamps.
    Ignore,
}

/// How to read a `.easy` file.
#[derive(Debug, Clone, PartialEq)]
pub struct EasyOptions {
    /// Which `.info` to read.
    pub info: EasyInfoFile,
    /// Sampling rate in Hz; overrides the `.info` and the timestamps.
    pub sfreq: Option<f64>,
    /// Number of EEG columns; overrides the `.info` and the device sizes.
    pub n_channels: Option<usize>,
    /// Factor from the file's EEG values to µV; overrides the `.info`'s `EEG units` (default nV,
    /// i.e. a division by 1000).
    pub scale_to_uv: Option<f64>,
    /// Trigger values that give no event (default: 255, NIC's lost-packet flag).
    pub ignore_codes: Vec<u32>,
    /// Trigger values whose events are targets.
    pub target_codes: Vec<u32>,
    /// Trigger values whose events are non-targets.
    pub nontarget_codes: Vec<u32>,
    /// Reject a file whose last line has no line end (a sign of truncation).
    pub require_final_newline: bool,
    /// Reject a file with another number of samples than the `.info`'s `Number of records of EEG`.
    pub check_record_count: bool,
}

impl Default for EasyOptions {
    fn default() -> Self {
        Self {
            info: EasyInfoFile::Beside,
            sfreq: None,
            n_channels: None,
            scale_to_uv: None,
            ignore_codes: vec![NIC_PACKET_LOSS_CODE],
            target_codes: Vec::new(),
            nontarget_codes: Vec::new(),
            require_final_newline: true,
            check_record_count: true,
        }
    }
}

/// The columns of a `.easy` file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct EasyLayout {
    pub n_eeg: usize,
    /// Three accelerometer columns after the EEG.
    pub accelerometer: bool,
    /// The external AddSensor column before the trigger.
    pub add_sensor: bool,
}

impl EasyLayout {
    /// The layout of `n_columns` cells with `n_eeg` EEG channels, if there is one.
    pub fn for_columns(n_columns: usize, n_eeg: usize) -> Option<Self> {
        if n_eeg == 0 {
            return None;
        }
        let (accelerometer, add_sensor) = match n_columns.checked_sub(n_eeg + 2)? {
            0 => (false, false),
            1 => (false, true),
            3 => (true, false),
            4 => (true, true),
            _ => return None,
        };
        Some(Self {
            n_eeg,
            accelerometer,
            add_sensor,
        })
    }

    /// Cells per line.
    pub fn n_columns(&self) -> usize {
        self.n_eeg + 2 + 3 * usize::from(self.accelerometer) + usize::from(self.add_sensor)
    }
}

/// Where [`Raw::sfreq`](oddball_signal::Raw::sfreq) of a `.easy` recording came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum EasySfreqSource {
    /// [`EasyOptions::sfreq`].
    Options,
    /// The `.info`'s `EEG sampling rate`.
    Info,
    /// Estimated from the timestamps (see the module documentation).
    Timestamps,
}

/// What a `.easy` file and its `.info` held besides the EEG and the events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EasyInfo {
    pub layout: EasyLayout,
    /// The `.info`'s `Device class`, e.g. `STARSTIM` or `ENOBIO`.
    pub device_class: Option<String>,
    /// `(3, n_times)`: x, y, z as written (NIC: mm/s²), when the file has them.
    pub accelerometer: Option<Array2<f64>>,
    /// The AddSensor column as written, when the file has it.
    pub add_sensor: Option<Vec<f64>>,
    /// The trigger column, one value per sample.
    pub triggers: Vec<u32>,
    /// The timestamp column: Unix time in ms, one per sample.
    pub timestamps_ms: Vec<u64>,
    pub sfreq_source: EasySfreqSource,
    /// The rate the timestamps give (unrounded), when they are strictly increasing.
    pub estimated_sfreq: Option<f64>,
    /// The `.info` file read, if any.
    pub info_path: Option<PathBuf>,
    /// Every `Key: value` line of the `.info`, in file order, key and value trimmed (split at the
    /// first colon; lines without a colon are left out).
    pub info: Vec<(String, String)>,
}

impl EasyInfo {
    /// The first `.info` value whose key matches `key` case-insensitively (runs of whitespace
    /// count as one space).
    pub fn info_value(&self, key: &str) -> Option<&str> {
        let key = normalize_key(key);
        self.info
            .iter()
            .find(|(k, _)| normalize_key(k) == key)
            .map(|(_, v)| v.as_str())
    }

    /// Every `.info` value by key, for many look-ups ([`EasyInfo::info_value`] scans the
    /// lines; a session's 50,000 trial lines looked up one by one took minutes).
    pub fn info_index(&self) -> InfoIndex<'_> {
        let mut map = std::collections::HashMap::with_capacity(self.info.len());
        for (k, v) in &self.info {
            map.entry(normalize_key(k)).or_insert(v.as_str());
        }
        InfoIndex { map }
    }
}

/// `.info` values by key, matched as [`EasyInfo::info_value`] matches them (first value wins).
#[derive(Debug, Clone)]
pub struct InfoIndex<'a> {
    map: std::collections::HashMap<String, &'a str>,
}

impl<'a> InfoIndex<'a> {
    pub fn get(&self, key: &str) -> Option<&'a str> {
        self.map.get(&normalize_key(key)).copied()
    }
}

/// Lower case, runs of whitespace as one space.
pub(super) fn normalize_key(k: &str) -> String {
    k.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_lowercase()
}
