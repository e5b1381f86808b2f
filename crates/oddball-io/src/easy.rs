//! Neuroelectrics NIC `.easy` recordings (Enobio, Starstim) and their `.info` files: a reader and
//! a writer, written from scratch.
//!
//! # Why here
//! One Rust crate reads `.easy` files, `easy-rs` (0.0.6, early 2025): its errors are
//! `anyhow` text, not a typed error carrying file, line and column; it depends on the `cargo`
//! crate, `chrono`, `regex`, `csv` and `flate2`; and it writes nothing. The format is one table
//! of integers, so a small reader that knows where each value came from (1-based line and column
//! in every error, like [`crate::csv`]) and a writer beside it serve this crate's error rule
//! better, without new dependencies.
//!
//! # The `.easy` file
//! NIC's plain-text recording: one line per sample, TAB-separated cells:
//!
//! ```text
//! Ch1 … ChN (nV) [aX aY aZ] [AddSensor] trigger timestamp
//! ```
//!
//! The `N` EEG channels are integers in nanovolts (`N` is 8, 20 or 32 on Neuroelectrics
//! devices), then optionally three accelerometer columns, optionally the external "AddSensor"
//! column, then the trigger/flags column (uint32; 0 = no marker; NIC writes 255 when packets
//! were lost), then a Unix timestamp in milliseconds. So an 8-channel file has 10 cells per line
//! (no accelerometer, no AddSensor), 11 (AddSensor), 13 (accelerometer) or 14 (both); 20
//! channels: 22, 23, 25, 26; 32 channels: 34, 35, 37, 38.
//!
//! # The `.info` file
//! A text file with the same stem, one `Key: value` per line, for example (NIC 1 and NIC 2 write
//! somewhat different sets of keys; each line is trimmed, keys are compared case-insensitively
//! with runs of spaces collapsed, and lines this reader does not know are kept in
//! [`EasyInfo::info`] and otherwise ignored):
//!
//! ```text
//! Device class: STARSTIM
//! Total number of channels: 8
//! Number of EEG channels: 8
//! Number of records of EEG: 15000
//! EEG sampling rate: 500 Samples/second
//! EEG units: nV
//! Accelerometer data: ON
//! Channel 1: Position: C3        (NIC 1 also puts "Position: C3" on the line after "Channel 1:")
//! Channel 2: C4                  (NIC 2)
//! ```
//!
//! # Reading ([`read_easy`], [`read_easy_with`], [`parse_easy`])
//! * **Layout.** The number of cells on the first line decides, given the EEG channel count `N`:
//!   `N + 2`, `+ 3` (AddSensor), `+ 5` (accelerometer) or `+ 6` (both). `N` comes from
//!   [`EasyOptions::n_channels`]; else from the `.info`'s `Total number of channels` (a Starstim
//!   that stimulates on some channels records all of them; `Number of EEG channels` counts only
//!   the recording ones) or, without it, `Number of EEG channels`; else, when the `.info` says
//!   `Accelerometer data: ON/OFF` (and `Additional channel status: ON/OFF` or
//!   `Additional channel: NONE`), from those flags; else from the device sizes 8, 20 and 32 (the
//!   cell counts above do not overlap). The `.info`'s accelerometer flag does not override a
//!   layout the channel count gives. Every later line must have as many cells as the first.
//! * **Samples.** EEG cells are numbers (NIC writes integers) in nV, divided by 1000 to µV (so a
//!   whole number of nV reads back as the `f64` nearest to its µV value); `EEG units` in the
//!   `.info` (`nV`, `uV`, `mV`, `V`) or [`EasyOptions::scale_to_uv`] change the factor. A value
//!   beyond ±2 147 483 647 nV (the int32 range, ±2.1 V) is refused as absurd. Accelerometer and
//!   AddSensor values are kept as written in [`EasyInfo::accelerometer`] and
//!   [`EasyInfo::add_sensor`] (NIC documents the accelerometer in mm/s²).
//! * **Channel names** from the `.info`'s `Channel k:` lines (`Channel k: Position: X`,
//!   `Channel k: X`, or `Channel k:` followed by a `Position: X` line). Channels without one are
//!   named `Ch1` … `ChN`: that is what NIC itself writes for an electrode without a position (and
//!   what Neuroelectrics' EEGLAB plugin treats as an unused channel). No default montage is
//!   assumed: an Enobio/Starstim 8 has none (the electrodes go wherever the cap is set up), so a
//!   guessed list of positions would be wrong as often as right.
//! * **Sampling rate:** [`EasyOptions::sfreq`] when given; else the `.info`'s
//!   `EEG sampling rate`; else from the timestamps: the median interval `m`, then the mean of the
//!   intervals within `[m/2, 3m/2]` (which ignores the gaps of lost packets and averages out
//!   timestamps rounded to 1 ms), `1000 / mean` rounded to whole Hz (device rates are whole Hz; the
//!   unrounded estimate is kept in [`EasyInfo::estimated_sfreq`]). Deriving the rate needs at least
//!   two samples with strictly increasing timestamps; otherwise the reader refuses, naming the
//!   line where the time stands still or goes back.
//! * **Events** at each sample whose trigger is non-zero and differs from the previous sample's
//!   (a trigger held over several samples is one event, at its first sample; a change from one
//!   code straight to another is a new event). The code is the trigger value; `target` is
//!   `Some(true)`/`Some(false)` for [`EasyOptions::target_codes`] /
//!   [`EasyOptions::nontarget_codes`], else `None`. Codes in [`EasyOptions::ignore_codes`]
//!   (by default 255, NIC's lost-packet flag) give no event but still count as the previous
//!   sample's value (`5 255 5` gives two events). The whole trigger column is kept in
//!   [`EasyInfo::triggers`].
//! * **Errors** ([`IoError::Csv`], the crate's line-and-column variant, with the path of the
//!   `.easy` or `.info` file at fault; lines count from 1, blank lines included; in a `.easy`
//!   the column is the 1-based TAB-separated cell, in a `.info` the character where the value
//!   starts): a cell that is not a number, an integer trigger
//!   (0 ..= 4 294 967 295) or an integer timestamp (0 ..= 2⁵³ ms); an absurd value; a line with
//!   more or fewer cells than the first; a first line that fits no layout; invalid UTF-8; an empty
//!   file; a last line without a line end (a file cut inside its last line; see
//!   [`EasyOptions::require_final_newline`]); fewer or more lines than the `.info`'s
//!   `Number of records of EEG` (a file cut at a line end; see
//!   [`EasyOptions::check_record_count`]); a `.info` value this reader needs that it cannot read.
//!   Blank lines are skipped, `\r\n` line ends and a UTF-8 byte-order mark are accepted, and
//!   spaces around cells and trailing whitespace (a trailing TAB) are ignored.
//!
//! # Writing ([`write_easy`])
//! The `.easy` and a `.info` beside it (same stem, extension `.info`), each written to a
//! temporary file in the same directory and renamed into place (`.info` first): a failed write
//! never leaves a partial file under either name (should the second rename fail, the new
//! `.info` sits beside the old `.easy`; the reader refuses that pair unless their sample counts
//! agree). The `.easy` holds, per sample, the EEG in whole nV (`round(µV × 1000)`, halves away
//! from zero; the largest rounding is reported), no accelerometer or AddSensor columns, the
//! trigger and the timestamp. The trigger is the code of each of the [`Raw`]'s events at its
//! onset sample only, 0 elsewhere. Timestamp of sample `i`: `start_ms + round(i × 1000 /
//! sfreq)` ms, rounded to the nearest ms (halves away from zero) and computed from `i` each
//! time, so the error never exceeds 0.5 ms and does not accumulate (above 1000 Hz successive
//! timestamps can be equal; the `.info` carries the exact rate). The `.info` is in NIC 2's form
//! (`Channel k: NAME` lines, which Neuroelectrics' EEGLAB plugin reads) with the device class
//! (`STARSTIM` by default), channel count, record count, the rate (Rust's shortest round-trip
//! decimal, so it reads back bit-exact), `EEG units: nV` and `Accelerometer data: OFF`.

use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use ndarray::Array2;
use oddball_signal::{Event, Events, Raw};
use serde::{Deserialize, Serialize};

use crate::csv::csv_err;
use crate::error::read_file;
use crate::tempfile::{check_writable, TempFile};
use crate::units::{split_number_unit, volt_factor_to_uv};
use crate::{Details, Format, IoError, Recording};

/// The EEG channel counts of Neuroelectrics devices, used to find the layout of a file read
/// without a channel count from the `.info` or the options.
pub const STANDARD_CHANNEL_COUNTS: [usize; 3] = [8, 20, 32];

/// The trigger value NIC writes when packets were lost (skipped as an event by default).
pub const NIC_PACKET_LOSS_CODE: u32 = 255;

/// The largest timestamp read or written, in ms: 2⁵³ (every value up to it is exact in `f64`).
pub const MAX_TIMESTAMP_MS: u64 = 1 << 53;

/// The largest |EEG value| read or written, in µV: the int32 range of nV.
const MAX_ABS_UV: f64 = i32::MAX as f64 / 1000.0;

/// The largest channel count a `.info` may state.
const MAX_INFO_CHANNELS: usize = 1024;

/// The largest sampling rate a `.info` may state, in Hz.
const MAX_INFO_SFREQ: f64 = 1e6;

/// Which `.info` file [`read_easy_with`] reads.
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

/// Where [`Raw::sfreq`] of a `.easy` recording came from.
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
}

/// Reads a `.easy` recording and the `.info` beside it with default options.
pub fn read_easy(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_easy_with(path, &EasyOptions::default())
}

/// Reads a `.easy` recording with the given options.
pub fn read_easy_with(path: impl AsRef<Path>, options: &EasyOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    let info_path = match &options.info {
        EasyInfoFile::Beside => {
            let p = info_path_for(path);
            p.is_file().then_some(p)
        }
        EasyInfoFile::At(p) => Some(p.clone()),
        EasyInfoFile::Ignore => None,
    };
    let info_bytes = info_path.as_deref().map(read_file).transpose()?;
    let info = info_path.as_deref().zip(info_bytes.as_deref());
    parse_easy(&bytes, path, info.map(|(p, b)| (b, p)), options)
}

/// The `.info` file that belongs to a `.easy` file: same stem, extension `.info`.
pub fn info_path_for(easy: &Path) -> PathBuf {
    easy.with_extension("info")
}

fn line_text<'a>(raw: &'a [u8], path: &Path, line: usize) -> Result<&'a str, IoError> {
    let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
    std::str::from_utf8(raw).map_err(|e| {
        // The cell holding the invalid byte.
        let col = raw[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\t')
            .count()
            + 1;
        csv_err(
            path,
            line,
            col,
            "text",
            "UTF-8 text",
            format!("byte 0x{:02x}", raw[e.valid_up_to()]),
        )
    })
}

fn shorten(s: &str) -> String {
    s.chars().take(80).collect()
}

/// Lower case, runs of whitespace as one space.
fn normalize_key(k: &str) -> String {
    k.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_lowercase()
}

/// How EEG values become µV: a division keeps whole nV bit-exact (`1234 / 1000` is the `f64`
/// nearest to 1.234, `1234 × 0.001` is not always).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scale {
    DivideBy(f64),
    Times(f64),
}

impl Scale {
    fn from_factor(f: f64) -> Self {
        if f < 1.0 {
            let d = (1.0 / f).round();
            if 1.0 / d == f {
                return Scale::DivideBy(d);
            }
        }
        Scale::Times(f)
    }

    fn to_uv(self, v: f64) -> f64 {
        match self {
            Scale::DivideBy(d) => v / d,
            Scale::Times(f) => v * f,
        }
    }
}

/// A value from a `.info` line, with the line it came from.
#[derive(Debug, Clone, Copy)]
struct At<T> {
    value: T,
    line: usize,
}

/// What the reader takes from a `.info` file.
#[derive(Debug, Default)]
struct ParsedInfo {
    entries: Vec<(String, String)>,
    device_class: Option<String>,
    total_channels: Option<At<usize>>,
    eeg_channels: Option<At<usize>>,
    sfreq: Option<At<f64>>,
    accelerometer: Option<bool>,
    add_sensor: Option<bool>,
    n_records: Option<At<usize>>,
    scale: Option<Scale>,
    /// (1-based channel number, name, line).
    names: Vec<(usize, String, usize)>,
}

fn on_off(v: &str) -> Option<bool> {
    match v.to_ascii_lowercase().as_str() {
        "on" | "yes" | "true" => Some(true),
        "off" | "no" | "false" | "none" => Some(false),
        _ => None,
    }
}

/// Parses a `.info` file (see the module documentation); `path` names it in errors.
fn parse_info(bytes: &[u8], path: &Path) -> Result<ParsedInfo, IoError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut out = ParsedInfo::default();
    let mut current_channel: Option<usize> = None;
    for (idx, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = idx + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        // Tolerant: a .info written on Windows may hold Latin-1 text in values this reader
        // does not use.
        let text = String::from_utf8_lossy(raw);
        let Some((key_raw, value_raw)) = text.split_once(':') else {
            continue;
        };
        let key = key_raw.trim();
        let value = value_raw.trim();
        // 1-based column where the value starts.
        let value_col = key_raw.chars().count()
            + 2
            + (value_raw.chars().count() - value_raw.trim_start().chars().count());
        out.entries.push((key.to_string(), value.to_string()));
        let norm = normalize_key(key);
        let bad = |expected: &str| csv_err(path, line_no, value_col, key, expected, shorten(value));
        let count = || -> Result<usize, IoError> {
            value
                .split_whitespace()
                .next()
                .and_then(|v| v.parse::<usize>().ok())
                .filter(|n| (1..=MAX_INFO_CHANNELS).contains(n))
                .ok_or_else(|| bad("a channel count from 1 to 1024"))
        };
        match norm.as_str() {
            "device class" if !value.is_empty() => {
                out.device_class.get_or_insert_with(|| value.to_string());
            }
            "total number of channels" => {
                out.total_channels = Some(At {
                    value: count()?,
                    line: line_no,
                })
            }
            "number of eeg channels" => {
                out.eeg_channels = Some(At {
                    value: count()?,
                    line: line_no,
                })
            }
            "eeg sampling rate" => {
                let f = split_number_unit(value)
                    .map(|(f, _)| f)
                    .filter(|f| f.is_finite() && *f > 0.0 && *f <= MAX_INFO_SFREQ)
                    .ok_or_else(|| bad("a sampling rate above 0 and up to 1 MHz"))?;
                out.sfreq = Some(At {
                    value: f,
                    line: line_no,
                });
            }
            "number of records of eeg" => {
                let n = value
                    .split_whitespace()
                    .next()
                    .and_then(|v| v.parse::<usize>().ok())
                    .ok_or_else(|| bad("a whole number of samples"))?;
                out.n_records = Some(At {
                    value: n,
                    line: line_no,
                });
            }
            "eeg units" => {
                let f = volt_factor_to_uv(value)
                    .ok_or_else(|| bad("a voltage unit (nV, uV, µV, mV, V)"))?;
                out.scale = Some(Scale::from_factor(f));
            }
            "accelerometer data" => {
                if let Some(b) = on_off(value) {
                    out.accelerometer = Some(b);
                }
            }
            "additional channel status" | "additional channel" => {
                if let Some(b) = on_off(value) {
                    out.add_sensor = Some(b);
                }
            }
            "position" => {
                if let Some(k) = current_channel {
                    if !value.is_empty() && !out.names.iter().any(|n| n.0 == k) {
                        out.names.push((k, value.to_string(), line_no));
                    }
                }
            }
            _ => {
                let Some(k) = norm
                    .strip_prefix("channel ")
                    .and_then(|n| n.parse::<usize>().ok())
                else {
                    continue;
                };
                if k == 0 {
                    return Err(csv_err(
                        path,
                        line_no,
                        1,
                        key,
                        "a channel number from 1",
                        shorten(key),
                    ));
                }
                current_channel = Some(k);
                let name = match value.get(..9) {
                    Some(p) if p.eq_ignore_ascii_case("position:") => value[9..].trim(),
                    _ => value,
                };
                if !name.is_empty() && !out.names.iter().any(|n| n.0 == k) {
                    out.names.push((k, name.to_string(), line_no));
                }
            }
        }
    }
    Ok(out)
}

/// The layout of a first line of `n_cols` cells (see the module documentation).
fn resolve_layout(
    n_cols: usize,
    info: Option<(&ParsedInfo, &Path)>,
    options: &EasyOptions,
    path: &Path,
    line: usize,
) -> Result<EasyLayout, IoError> {
    let found = format!("{n_cols} cells");
    let fixed = |c: usize, why: String| {
        EasyLayout::for_columns(n_cols, c).ok_or_else(|| {
            csv_err(
                path,
                line,
                1,
                "layout",
                format!(
                    "{}, {}, {} or {} cells for {c} EEG channels ({why})",
                    c + 2,
                    c + 3,
                    c + 5,
                    c + 6
                ),
                found.clone(),
            )
        })
    };
    if let Some(c) = options.n_channels {
        return fixed(c, "EasyOptions::n_channels".into());
    }
    if let Some((info, info_path)) = info {
        if let Some(c) = info.total_channels.or(info.eeg_channels) {
            return fixed(c.value, format!("{} line {}", info_path.display(), c.line));
        }
        if let Some(acc) = info.accelerometer {
            let add = info.add_sensor.unwrap_or(false);
            let extra = 2 + 3 * usize::from(acc) + usize::from(add);
            return match n_cols.checked_sub(extra).filter(|&c| c > 0) {
                Some(c) => Ok(EasyLayout {
                    n_eeg: c,
                    accelerometer: acc,
                    add_sensor: add,
                }),
                None => Err(csv_err(
                    path,
                    line,
                    1,
                    "layout",
                    format!(
                        "more than {extra} cells (accelerometer {}, AddSensor {} in {})",
                        if acc { "on" } else { "off" },
                        if add { "on" } else { "off" },
                        info_path.display()
                    ),
                    found,
                )),
            };
        }
    }
    STANDARD_CHANNEL_COUNTS
        .iter()
        .find_map(|&c| EasyLayout::for_columns(n_cols, c))
        .ok_or_else(|| {
            csv_err(
                path,
                line,
                1,
                "layout",
                "10, 11, 13 or 14 cells (8 EEG channels), 22, 23, 25 or 26 (20 channels), \
                 34, 35, 37 or 38 (32 channels); other channel counts need a .info or \
                 EasyOptions::n_channels",
                found,
            )
        })
}

/// What each cell of a line holds.
#[derive(Debug, Clone, Copy)]
enum Role {
    Eeg(usize),
    Acc(usize),
    AddSensor,
    Trigger,
    Timestamp,
}

fn roles(layout: &EasyLayout) -> Vec<Role> {
    let mut r: Vec<Role> = (0..layout.n_eeg).map(Role::Eeg).collect();
    if layout.accelerometer {
        r.extend((0..3).map(Role::Acc));
    }
    if layout.add_sensor {
        r.push(Role::AddSensor);
    }
    r.push(Role::Trigger);
    r.push(Role::Timestamp);
    r
}

fn parse_trigger(cell: &str) -> Option<u32> {
    cell.parse::<u32>().ok().or_else(|| {
        let v: f64 = cell.parse().ok()?;
        (v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX)).then_some(v as u32)
    })
}

fn parse_timestamp(cell: &str) -> Option<u64> {
    let v = cell.parse::<u64>().ok().or_else(|| {
        let v: f64 = cell.parse().ok()?;
        (v >= 0.0 && v.fract() == 0.0 && v <= MAX_TIMESTAMP_MS as f64).then_some(v as u64)
    })?;
    (v <= MAX_TIMESTAMP_MS).then_some(v)
}

/// The rate the timestamps give, unrounded: `None` for fewer than two samples or timestamps
/// that do not strictly increase.
pub fn estimate_sfreq(timestamps_ms: &[u64]) -> Option<f64> {
    let mut d: Vec<u64> = timestamps_ms
        .windows(2)
        .map(|w| w[1].checked_sub(w[0]).filter(|&d| d > 0))
        .collect::<Option<_>>()?;
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let m = *d.select_nth_unstable(mid).1 as f64;
    let (sum, count) = d
        .iter()
        .map(|&x| x as f64)
        .filter(|&x| x >= m / 2.0 && x <= 1.5 * m)
        .fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    Some(1000.0 * count as f64 / sum)
}

/// The estimate rounded to whole Hz (left as it is below 1 Hz).
fn round_sfreq(f: f64) -> f64 {
    if f >= 1.0 {
        f.round()
    } else {
        f
    }
}

/// Parses the bytes of a `.easy` file and, when given, of its `.info` file (`(bytes, path)`);
/// the paths are used in error messages and the result.
pub fn parse_easy(
    bytes: &[u8],
    path: &Path,
    info: Option<(&[u8], &Path)>,
    options: &EasyOptions,
) -> Result<Recording, IoError> {
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    if let Some(f) = options.sfreq.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(unsupported(format!(
            "sampling rate {f} Hz in EasyOptions::sfreq"
        )));
    }
    if options.n_channels == Some(0) {
        return Err(unsupported("EasyOptions::n_channels = 0".into()));
    }
    if let Some(f) = options
        .scale_to_uv
        .filter(|f| !(f.is_finite() && *f != 0.0))
    {
        return Err(unsupported(format!("EasyOptions::scale_to_uv = {f}")));
    }
    let parsed = info.map(|(b, p)| parse_info(b, p)).transpose()?;
    // The parsed .info with its path, for errors that name it.
    let info_ref = parsed.as_ref().zip(info.map(|(_, p)| p));
    let scale = options
        .scale_to_uv
        .map(Scale::from_factor)
        .or(parsed.as_ref().and_then(|i| i.scale))
        .unwrap_or(Scale::DivideBy(1000.0));

    let ends_with_newline = bytes.last() == Some(&b'\n');
    let mut lines = bytes.split(|&b| b == b'\n').enumerate().peekable();

    // Set from the first data line.
    let mut layout: Option<EasyLayout> = None;
    let mut role: Vec<Role> = Vec::new();
    let mut fields: Vec<String> = Vec::new();
    let mut ch_names: Vec<String> = Vec::new();
    let mut first_line = 0usize;

    let mut eeg: Vec<Vec<f64>> = Vec::new();
    let mut acc: [Vec<f64>; 3] = Default::default();
    let mut add: Vec<f64> = Vec::new();
    let mut triggers: Vec<u32> = Vec::new();
    let mut timestamps: Vec<u64> = Vec::new();
    let mut events: Vec<Event> = Vec::new();
    let mut prev_trigger = 0u32;
    // The first line whose timestamp does not exceed the one before: (line, column, before, now).
    let mut not_increasing: Option<(usize, usize, u64, u64)> = None;
    let mut last_line = 0usize;

    while let Some((idx, raw)) = lines.next() {
        let line_no = idx + 1;
        let is_last = lines.peek().is_none();
        if is_last && raw.is_empty() {
            break; // the text after the final line end
        }
        let raw = if idx == 0 {
            raw.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(raw)
        } else {
            raw
        };
        let text = line_text(raw, path, line_no)?;
        if text.trim().is_empty() {
            continue;
        }
        if is_last && !ends_with_newline && options.require_final_newline {
            return Err(csv_err(
                path,
                line_no,
                text.split('\t').count(),
                "line end",
                "a line end after the last line (the file looks cut inside it)",
                shorten(text),
            ));
        }
        let text = text.trim_end();
        last_line = line_no;
        let lay = match layout {
            Some(l) => l,
            None => {
                let l = resolve_layout(text.split('\t').count(), info_ref, options, path, line_no)?;
                ch_names = channel_names(&l, info_ref)?;
                role = roles(&l);
                fields = role
                    .iter()
                    .map(|r| match *r {
                        Role::Eeg(c) => format!("EEG channel {} ({})", c + 1, ch_names[c]),
                        Role::Acc(k) => format!("accelerometer {}", ["x", "y", "z"][k]),
                        Role::AddSensor => "AddSensor".into(),
                        Role::Trigger => "trigger".into(),
                        Role::Timestamp => "timestamp (ms)".into(),
                    })
                    .collect();
                let hint = bytes.len() / (8 * l.n_columns() + 1) + 1;
                eeg = (0..l.n_eeg).map(|_| Vec::with_capacity(hint)).collect();
                first_line = line_no;
                layout = Some(l);
                l
            }
        };
        let n_cols = lay.n_columns();
        let mut n_cells = 0usize;
        for (j, cell) in text.split('\t').enumerate() {
            n_cells += 1;
            if j >= n_cols {
                return Err(csv_err(
                    path,
                    line_no,
                    j + 1,
                    "line",
                    format!("{n_cols} cells, as on line {first_line}"),
                    format!("{} cells", text.split('\t').count()),
                ));
            }
            let cell = cell.trim();
            let bad = |expected: &str| {
                csv_err(
                    path,
                    line_no,
                    j + 1,
                    fields[j].clone(),
                    expected,
                    shorten(cell),
                )
            };
            match role[j] {
                Role::Eeg(c) => {
                    let v: f64 = cell
                        .parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?;
                    let uv = scale.to_uv(v);
                    if uv.abs() > MAX_ABS_UV {
                        return Err(bad(
                            "an EEG value within ±2147483647 nV (the int32 range, ±2.1 V)",
                        ));
                    }
                    eeg[c].push(uv);
                }
                Role::Acc(k) => acc[k].push(
                    cell.parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?,
                ),
                Role::AddSensor => add.push(
                    cell.parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?,
                ),
                Role::Trigger => {
                    let code = parse_trigger(cell)
                        .ok_or_else(|| bad("an integer trigger from 0 to 4294967295"))?;
                    if code != 0 && code != prev_trigger && !options.ignore_codes.contains(&code) {
                        let target = if options.target_codes.contains(&code) {
                            Some(true)
                        } else if options.nontarget_codes.contains(&code) {
                            Some(false)
                        } else {
                            None
                        };
                        events.push(Event {
                            onset: triggers.len(),
                            code,
                            target,
                            label: None,
                        });
                    }
                    prev_trigger = code;
                    triggers.push(code);
                }
                Role::Timestamp => {
                    let ts = parse_timestamp(cell)
                        .ok_or_else(|| bad("an integer Unix time in ms from 0 to 2^53"))?;
                    if let Some(&prev) = timestamps.last() {
                        if ts <= prev && not_increasing.is_none() {
                            not_increasing = Some((line_no, j + 1, prev, ts));
                        }
                    }
                    timestamps.push(ts);
                }
            }
        }
        if n_cells < n_cols {
            return Err(csv_err(
                path,
                line_no,
                n_cells + 1,
                "line",
                format!("{n_cols} cells, as on line {first_line} (the line is too short)"),
                format!("{n_cells} cells"),
            ));
        }
    }
    let Some(layout) = layout else {
        return Err(csv_err(
            path,
            1,
            1,
            "data",
            "at least one sample line",
            if bytes.is_empty() {
                "an empty file"
            } else {
                "only blank lines"
            },
        ));
    };
    let n_times = timestamps.len();

    if let (true, Some((info, info_path))) = (options.check_record_count, info_ref) {
        if let Some(n) = info.n_records.filter(|n| n.value != n_times) {
            return Err(csv_err(
                path,
                last_line + 1,
                1,
                "data",
                format!(
                    "{} sample lines (\"Number of records of EEG\" in {} line {}; the .easy \
                     may be cut short)",
                    n.value,
                    info_path.display(),
                    n.line
                ),
                format!("{n_times} sample lines"),
            ));
        }
    }

    let estimated_sfreq = estimate_sfreq(&timestamps);
    let (sfreq, sfreq_source) = if let Some(f) = options.sfreq {
        (f, EasySfreqSource::Options)
    } else if let Some(f) = parsed.as_ref().and_then(|i| i.sfreq) {
        (f.value, EasySfreqSource::Info)
    } else if let Some(f) = estimated_sfreq {
        (round_sfreq(f), EasySfreqSource::Timestamps)
    } else {
        let ts_col = layout.n_columns();
        let why = "(no EasyOptions::sfreq and no \"EEG sampling rate\" in a .info, so the rate \
                   comes from the timestamps)";
        return Err(match not_increasing {
            Some((line, col, before, now)) => csv_err(
                path,
                line,
                col,
                "timestamp (ms)",
                format!("a timestamp after the previous line's {before} {why}"),
                now.to_string(),
            ),
            None => csv_err(
                path,
                last_line,
                ts_col,
                "timestamp (ms)",
                format!("at least two samples {why}"),
                format!("{n_times} sample"),
            ),
        });
    };

    let flat: Vec<f64> = eeg.into_iter().flatten().collect();
    let data = Array2::from_shape_vec((layout.n_eeg, n_times), flat).map_err(|e| {
        IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(".easy layout: {e}"),
        }
    })?;
    let accelerometer = if layout.accelerometer {
        let flat: Vec<f64> = acc.into_iter().flatten().collect();
        Some(
            Array2::from_shape_vec((3, n_times), flat).map_err(|e| IoError::Unsupported {
                path: path.to_path_buf(),
                what: format!(".easy accelerometer layout: {e}"),
            })?,
        )
    } else {
        None
    };
    let raw =
        Raw::new(data, sfreq, ch_names, Events::new(events)).map_err(|source| IoError::Signal {
            path: path.to_path_buf(),
            source,
        })?;
    let (device_class, entries) = match parsed {
        Some(p) => (p.device_class, p.entries),
        None => (None, Vec::new()),
    };
    Ok(Recording {
        raw,
        format: Format::Easy,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Easy(EasyInfo {
            layout,
            device_class,
            accelerometer,
            add_sensor: layout.add_sensor.then_some(add),
            triggers,
            timestamps_ms: timestamps,
            sfreq_source,
            estimated_sfreq,
            info_path: info.map(|(_, p)| p.to_path_buf()),
            info: entries,
        }),
    })
}

/// `Ch1` … `ChN`, replaced by the `.info`'s names; a `.info` channel beyond `N` is an error.
fn channel_names(
    layout: &EasyLayout,
    info: Option<(&ParsedInfo, &Path)>,
) -> Result<Vec<String>, IoError> {
    let mut names: Vec<String> = (1..=layout.n_eeg).map(|k| format!("Ch{k}")).collect();
    if let Some((info, info_path)) = info {
        for (k, name, line) in &info.names {
            if *k > layout.n_eeg {
                return Err(csv_err(
                    info_path,
                    *line,
                    1,
                    format!("Channel {k}"),
                    format!(
                        "a channel number from 1 to {} (the EEG columns of the .easy)",
                        layout.n_eeg
                    ),
                    format!("channel {k}"),
                ));
            }
            names[k - 1] = name.clone();
        }
    }
    Ok(names)
}

/// Options of [`write_easy`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EasyWriteOptions {
    /// Unix time of the first sample in ms (`StartDate` in the `.info`); default 0.
    pub start_ms: u64,
    /// `Device class` in the `.info`; default `STARSTIM`. One line of printable text.
    pub device_class: String,
    /// More `key: value` lines for the end of the `.info` (one line each, no line breaks);
    /// the reader returns them with the others in [`EasyInfo::info`].
    pub extra_info: Vec<(String, String)>,
}

impl Default for EasyWriteOptions {
    fn default() -> Self {
        Self {
            start_ms: 0,
            device_class: "STARSTIM".into(),
            extra_info: Vec::new(),
        }
    }
}

/// What [`write_easy`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct EasyWriteSummary {
    pub n_samples: usize,
    pub n_channels: usize,
    /// Size of the `.easy` file in bytes.
    pub bytes: u64,
    /// The `.info` file written beside it.
    pub info_path: PathBuf,
    /// The largest `|round(x × 1000) / 1000 − x|` over all samples, in µV (at most 0.0005).
    pub max_rounding_uv: f64,
    /// Samples with a non-zero trigger.
    pub n_triggers: usize,
    /// Events of the [`Raw`] that [`read_easy`] with default options does not give back: code 0,
    /// code 255 (NIC's lost-packet flag), another event at the same sample (the later one is
    /// written), or the same code on the sample before (read back as one held trigger).
    pub events_lost: usize,
}

/// The timestamp [`write_easy`] writes for `sample`: `start_ms + round(sample × 1000 / sfreq)`,
/// rounded to the nearest ms with halves away from zero.
pub fn timestamp_ms(start_ms: u64, sample: usize, sfreq: f64) -> u64 {
    start_ms.saturating_add((sample as f64 * 1000.0 / sfreq).round() as u64)
}

/// Whether `s` is one line of printable text without surrounding whitespace.
fn text_problem(s: &str) -> Option<&'static str> {
    if s.is_empty() {
        Some("empty")
    } else if s.chars().any(char::is_control) {
        Some("contains a control character (TAB, line end, ...)")
    } else if s.trim() != s {
        Some("starts or ends with whitespace")
    } else {
        None
    }
}

/// Writes `raw` as a `.easy` file at `path` and a `.info` file beside it (see the module
/// documentation for what is written).
///
/// Refused with an [`IoError`] before anything is written: an empty recording; a channel name or
/// device class that is empty, has surrounding whitespace or a control character; a `path` that
/// is its own `.info` path; timestamps beyond 2⁵³ ms; a sample that is not finite or whose nV
/// value is beyond the int32 range ([`IoError::UnwritableSample`], naming channel and sample).
pub fn write_easy(
    path: impl AsRef<Path>,
    raw: &Raw,
    options: &EasyWriteOptions,
) -> Result<EasyWriteSummary, IoError> {
    let path = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    crate::tempfile::check_not_empty(path, raw, ".easy")?;
    let (n_ch, n_times) = (raw.n_channels(), raw.n_times());
    for (c, name) in raw.ch_names().iter().enumerate() {
        if let Some(problem) = text_problem(name) {
            return Err(unsupported(format!(
                "channel {c} name {name:?} {problem} (it goes on a .info line)"
            )));
        }
    }
    if let Some(problem) = text_problem(&options.device_class) {
        return Err(unsupported(format!(
            "device class {:?} {problem}",
            options.device_class
        )));
    }
    let info_path = info_path_for(path);
    if info_path == path {
        return Err(unsupported(
            "a .easy path that is its own .info path (give the file another extension)".into(),
        ));
    }
    let sfreq = raw.sfreq();
    let last = timestamp_ms(options.start_ms, n_times - 1, sfreq);
    if options.start_ms > MAX_TIMESTAMP_MS || last > MAX_TIMESTAMP_MS {
        return Err(unsupported(format!(
            "timestamps from {} to {last} ms (at most 2^53 ms)",
            options.start_ms
        )));
    }

    // Samples: finite and within int32 nV; the largest rounding is reported.
    let data = raw.data();
    let nv = |x: f64| (x * 1000.0).round();
    let max_rounding = check_writable(
        path,
        raw,
        "beyond ±2147483647 nV, the int32 range of .easy samples",
        |x| (nv(x).abs() <= f64::from(i32::MAX)).then(|| nv(x) / 1000.0),
    )?;

    // Triggers: each event's code at its onset only (the later of two at one sample wins).
    let mut trig = vec![0u32; n_times];
    for e in raw.events() {
        if let Some(t) = trig.get_mut(e.onset) {
            *t = e.code;
        }
    }
    let n_triggers = trig.iter().filter(|&&c| c != 0).count();
    let readable = (0..n_times)
        .filter(|&t| {
            let c = trig[t];
            c != 0 && c != NIC_PACKET_LOSS_CODE && (t == 0 || trig[t - 1] != c)
        })
        .count();
    let events_lost = raw.events().len().saturating_sub(readable);

    // The .info (NIC 2's form).
    let mut info = String::new();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let _ = writeln!(info, "Step Details");
    let _ = writeln!(info, "Step name: {}", stem.replace(['\r', '\n'], " "));
    let _ = writeln!(info, "StartDate (firstEEGtimestamp): {}", options.start_ms);
    let _ = writeln!(info, "Device class: {}", options.device_class);
    let _ = writeln!(
        info,
        "Software's version: oddball-io {}",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(info, "Additional channel: NONE");
    let _ = writeln!(info);
    let _ = writeln!(info, "EEG Settings");
    let _ = writeln!(info, "Total number of channels: {n_ch}");
    let _ = writeln!(info, "Number of EEG channels: {n_ch}");
    let _ = writeln!(info, "Number of records of EEG: {n_times}");
    let _ = writeln!(info, "EEG sampling rate: {sfreq} Samples/second");
    let _ = writeln!(info, "EEG units: nV");
    let _ = writeln!(info, "Accelerometer data: OFF");
    let _ = writeln!(info, "EEG montage:");
    for (k, name) in raw.ch_names().iter().enumerate() {
        let _ = writeln!(info, "\tChannel {}: {name}", k + 1);
    }
    if !options.extra_info.is_empty() {
        let _ = writeln!(info);
        for (key, value) in &options.extra_info {
            let clean = |t: &str| t.replace(['\r', '\n'], " ");
            let _ = writeln!(info, "{}: {}", clean(key).replace(':', ";"), clean(value));
        }
    }

    // The .easy, then both renamed into place (.info first).
    let (easy_tmp, file) = TempFile::create(path)?;
    let write_err = |p: &Path, source| IoError::Io {
        path: p.to_path_buf(),
        action: "write",
        source,
    };
    let mut w = BufWriter::with_capacity(1 << 16, file);
    let mut line = String::with_capacity(12 * (n_ch + 2));
    let mut bytes = 0u64;
    for (t, code) in trig.iter().enumerate() {
        line.clear();
        for x in data.column(t) {
            let _ = write!(line, "{}\t", nv(*x) as i32);
        }
        let _ = writeln!(line, "{code}\t{}", timestamp_ms(options.start_ms, t, sfreq));
        w.write_all(line.as_bytes())
            .map_err(|e| write_err(&easy_tmp.path, e))?;
        bytes += line.len() as u64;
    }
    let file = w
        .into_inner()
        .map_err(|e| write_err(&easy_tmp.path, e.into_error()))?;
    file.sync_all().map_err(|e| write_err(&easy_tmp.path, e))?;
    drop(file);

    let (info_tmp, mut file) = TempFile::create(&info_path)?;
    file.write_all(info.as_bytes())
        .and_then(|()| file.sync_all())
        .map_err(|e| write_err(&info_tmp.path, e))?;
    drop(file);
    info_tmp.persist(&info_path)?;
    easy_tmp.persist(path)?;
    Ok(EasyWriteSummary {
        n_samples: n_times,
        n_channels: n_ch,
        bytes,
        info_path,
        max_rounding_uv: max_rounding,
        n_triggers,
        events_lost,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts() {
        let l = |n, c| EasyLayout::for_columns(n, c).map(|l| (l.accelerometer, l.add_sensor));
        assert_eq!(l(10, 8), Some((false, false)));
        assert_eq!(l(11, 8), Some((false, true)));
        assert_eq!(l(13, 8), Some((true, false)));
        assert_eq!(l(14, 8), Some((true, true)));
        assert_eq!(l(12, 8), None);
        assert_eq!(l(9, 8), None);
        assert_eq!(l(15, 8), None);
        assert_eq!(l(2, 0), None);
        assert_eq!(l(26, 20), Some((true, true)));
        for n in [10, 11, 13, 14, 22, 23, 25, 26, 34, 35, 37, 38] {
            let found: Vec<_> = STANDARD_CHANNEL_COUNTS
                .iter()
                .filter_map(|&c| EasyLayout::for_columns(n, c))
                .collect();
            assert_eq!(found.len(), 1, "{n} columns");
            assert_eq!(found[0].n_columns(), n);
        }
    }

    #[test]
    fn rate_estimates() {
        let ts = |steps: &[u64]| {
            let mut t = vec![1_000u64];
            for s in steps {
                t.push(t.last().unwrap() + s);
            }
            t
        };
        assert_eq!(estimate_sfreq(&ts(&[2; 9])), Some(500.0));
        // A lost-packet gap is left out of the mean.
        assert_eq!(estimate_sfreq(&ts(&[2, 2, 2, 10, 2, 2])), Some(500.0));
        // 256 Hz with timestamps rounded to 1 ms: steps of 3.90625 ms on average.
        let t: Vec<u64> = (0..513)
            .map(|i| (i as f64 * 1000.0 / 256.0).round() as u64)
            .collect();
        let f = estimate_sfreq(&t).unwrap();
        assert!((f - 256.0).abs() < 0.01, "{f}");
        assert_eq!(round_sfreq(f), 256.0);
        assert_eq!(estimate_sfreq(&[5]), None);
        assert_eq!(estimate_sfreq(&[]), None);
        assert_eq!(estimate_sfreq(&[5, 5]), None);
        assert_eq!(estimate_sfreq(&[5, 7, 6]), None);
        assert_eq!(round_sfreq(0.25), 0.25);
    }

    #[test]
    fn scales_keep_whole_nanovolts_exact() {
        assert_eq!(Scale::from_factor(1e-3), Scale::DivideBy(1000.0));
        assert_eq!(Scale::from_factor(1.0), Scale::Times(1.0));
        assert_eq!(Scale::from_factor(1e3), Scale::Times(1e3));
        for k in [1234i64, -1, 7, 2_147_483_647, -999_999_999] {
            let s = format!("{}", k as f64 / 1000.0);
            assert_eq!(
                Scale::DivideBy(1000.0).to_uv(k as f64),
                s.parse::<f64>().unwrap()
            );
        }
    }

    #[test]
    fn info_lines() {
        let text = "\u{feff}Device CLASS :  STARSTIM \r\n\
            Device Mac: 00:07:80:58:9C:1A\r\n\
            total   number of channels: 8\r\n\
            EEG sampling rate: 500 Samples/second\r\n\
            eeg units: nV\r\n\
            Accelerometer data: on\r\n\
            Channel 1:\r\n Position: C3\r\n Type: EEG Recording\r\n\
            Channel 2: Position: C4\r\n\
            \tChannel 3: Pz\r\n\
            Channel 4:\r\nTrigger information:\r\n1 Subject moved\r\n";
        let p = parse_info(text.as_bytes(), Path::new("x.info")).unwrap();
        assert_eq!(p.device_class.as_deref(), Some("STARSTIM"));
        assert_eq!(p.total_channels.unwrap().value, 8);
        assert_eq!(p.total_channels.unwrap().line, 3);
        assert_eq!(p.sfreq.unwrap().value, 500.0);
        assert_eq!(p.accelerometer, Some(true));
        assert_eq!(p.scale, Some(Scale::DivideBy(1000.0)));
        let names: Vec<_> = p.names.iter().map(|n| (n.0, n.1.as_str())).collect();
        assert_eq!(names, vec![(1, "C3"), (2, "C4"), (3, "Pz")]);
        assert_eq!(p.entries[0], ("Device CLASS".into(), "STARSTIM".into()));
        assert_eq!(p.entries[1].1, "00:07:80:58:9C:1A");
        assert!(p
            .entries
            .iter()
            .any(|(k, v)| k == "Channel 4" && v.is_empty()));

        let err = |text: &str| match parse_info(text.as_bytes(), Path::new("x.info")) {
            Err(IoError::Csv { line, column, .. }) => (line, column),
            other => panic!("{other:?}"),
        };
        assert_eq!(err("a: b\nEEG sampling rate: fast\n"), (2, 20));
        assert_eq!(err("EEG sampling rate:   -5 Hz\n"), (1, 22));
        assert_eq!(err("Total number of channels: 0\n"), (1, 27));
        assert_eq!(err("Number of EEG channels: many\n"), (1, 25));
        assert_eq!(err("Number of records of EEG: -1\n"), (1, 27));
        assert_eq!(err("EEG units: degC\n"), (1, 12));
        assert_eq!(err("Channel 0: Fz\n"), (1, 1));
    }
}
