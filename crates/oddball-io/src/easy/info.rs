//! The `.info` file beside a `.easy`: its lines parsed into what the reader needs.

use std::path::Path;

use crate::csv::csv_err;
use crate::units::{microvolts_per, split_number_unit};
use crate::IoError;

use super::types::*;

/// The cell (1-based, tab-separated) after the bytes `valid` of a line.
pub(super) fn cell_column(valid: &[u8]) -> usize {
    valid.iter().filter(|&&b| b == b'\t').count() + 1
}

pub(super) fn shorten(s: &str) -> String {
    s.chars().take(80).collect()
}

/// How EEG values become µV: a division keeps whole nV bit-exact (`1234 / 1000` is the `f64`
/// nearest to 1.234, `1234 × 0.001` is not always).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Scale {
    DivideBy(f64),
    Times(f64),
}

impl Scale {
    pub(super) fn from_factor(f: f64) -> Self {
        if f < 1.0 {
            let d = (1.0 / f).round();
            if 1.0 / d == f {
                return Scale::DivideBy(d);
            }
        }
        Scale::Times(f)
    }

    pub(super) fn to_uv(self, v: f64) -> f64 {
        match self {
            Scale::DivideBy(d) => v / d,
            Scale::Times(f) => v * f,
        }
    }
}

/// A value from a `.info` line, with the line it came from.
#[derive(Debug, Clone, Copy)]
pub(super) struct At<T> {
    pub(super) value: T,
    pub(super) line: usize,
}

/// What the reader takes from a `.info` file.
#[derive(Debug, Default)]
pub(super) struct ParsedInfo {
    pub(super) entries: Vec<(String, String)>,
    pub(super) device_class: Option<String>,
    pub(super) total_channels: Option<At<usize>>,
    pub(super) eeg_channels: Option<At<usize>>,
    pub(super) sfreq: Option<At<f64>>,
    pub(super) accelerometer: Option<bool>,
    pub(super) add_sensor: Option<bool>,
    pub(super) n_records: Option<At<usize>>,
    pub(super) scale: Option<Scale>,
    /// (1-based channel number, name, line).
    pub(super) names: Vec<(usize, String, usize)>,
}

pub(super) fn on_off(v: &str) -> Option<bool> {
    match v.to_ascii_lowercase().as_str() {
        "on" | "yes" | "true" => Some(true),
        "off" | "no" | "false" | "none" => Some(false),
        _ => None,
    }
}

/// Parses a `.info` file (see the module documentation); `path` names it in errors.
pub(super) fn parse_info(bytes: &[u8], path: &Path) -> Result<ParsedInfo, IoError> {
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
                let f = microvolts_per(value)
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
