//! What the readers cannot find out from a file by themselves, given by the user (MNE's
//! `read_raw_*` arguments): the sampling rate, which CSV columns or MAT variables hold the
//! samples, the time and the events. On the command line (`--sfreq`, `--channels`,
//! `--time-column`, `--events-from`, `--data-from`) and in a manifest's `[read]` table.

use std::path::Path;

use serde::Deserialize;

use crate::csv::{parse_csv_with_detected, CsvOptions};
use crate::mat::{read_mat_with, MatOptions};
use crate::{IoError, Recording};

/// Reading options; every field `None` reads as [`crate::read`] does.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReadOptions {
    /// The sampling rate, Hz: for CSV (instead of the time column's estimate) and MAT (instead
    /// of the file's rate variable or the competitions' 240 Hz).
    pub sfreq: Option<f64>,
    /// CSV: the EEG columns, in this order; MAT: the names of the signal's columns.
    pub channels: Option<Vec<String>>,
    /// CSV: the time column (seconds).
    pub time_column: Option<String>,
    /// CSV: the marker column; MAT: the per-sample stimulus code variable.
    pub events: Option<String>,
    /// MAT: the variable holding the samples (`n_times × n_channels`).
    pub data: Option<String>,
}

impl ReadOptions {
    /// Whether no option is set.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// A plausible sampling rate, when one is given.
    pub fn check(&self) -> Result<(), String> {
        if let Some(f) = self.sfreq {
            if !(f.is_finite() && f > 0.0 && f <= 1e6) {
                return Err(format!("sfreq {f}: a sampling rate must be in (0, 1e6] Hz"));
            }
        }
        if self.channels.as_ref().is_some_and(|c| c.is_empty()) {
            return Err("channels: the list is empty".into());
        }
        Ok(())
    }
}

/// Reads a recording with `options` (see [`ReadOptions`]); an option that the file's format
/// does not take is an error naming both.
pub fn read_with(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    if options.is_empty() {
        return crate::read(path);
    }
    let unsupported = |what: &str| IoError::Unsupported {
        path: path.to_path_buf(),
        what: format!("{what} (reading options apply to .csv and .mat files)"),
    };
    if let Err(why) = options.check() {
        return Err(unsupported(&why));
    }
    crate::check_file(path)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("csv") => parse_csv_with_detected(path, |detected: CsvOptions| CsvOptions {
            sfreq: options.sfreq.or(detected.sfreq),
            channels: options.channels.clone().or(detected.channels),
            time_column: options.time_column.clone().or(detected.time_column),
            marker_column: options.events.clone().or(detected.marker_column),
            ..detected
        }),
        Some("mat") => {
            let d = MatOptions::default();
            read_mat_with(
                path,
                &MatOptions {
                    sfreq: options.sfreq,
                    signal: options.data.clone().unwrap_or(d.signal),
                    code: options.events.clone().unwrap_or(d.code),
                    ch_names: options.channels.clone(),
                    ..MatOptions::default()
                },
            )
        }
        _ => {
            let mut given = Vec::new();
            for (set, name) in [
                (options.sfreq.is_some(), "a sampling rate"),
                (options.channels.is_some(), "channel columns"),
                (options.time_column.is_some(), "a time column"),
                (options.events.is_some(), "an events column or variable"),
                (options.data.is_some(), "a data variable"),
            ] {
                if set {
                    given.push(name);
                }
            }
            Err(unsupported(&format!(
                "{} given for a file that records its own layout",
                given.join(", ")
            )))
        }
    }
}
