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
    /// CSV: the EEG columns, in this order; MAT: the names of the signal's columns; any other
    /// format: the channels kept, in this order (matched by name, case aside).
    pub channels: Option<Vec<String>>,
    /// A montage file naming the file's channels in order (an EEGLAB `.loc`, e.g. BCI2000's
    /// `eeg64.loc`, see [`crate::montage`]); applied before `channels` picks.
    #[serde(default)]
    pub montage: Option<std::path::PathBuf>,
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
    let Some(montage) = &options.montage else {
        return read_tabular(path, options);
    };
    let names = crate::montage::read_montage(montage)?;
    // The montage names the file's channels first; `channels` then picks among those names.
    let mut rec = read_tabular(
        path,
        &ReadOptions {
            montage: None,
            channels: None,
            ..options.clone()
        },
    )?;
    let n = rec.raw.n_channels();
    if names.len() != n {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "the montage {} names {} channels, the file holds {n}",
                montage.display(),
                names.len()
            ),
        });
    }
    rec.raw = rec
        .raw
        .with_ch_names(names)
        .map_err(|source| IoError::Signal {
            path: path.to_path_buf(),
            source,
        })?;
    if let Some(ch) = &options.channels {
        rec.raw = pick(&rec.raw, ch, path)?;
    }
    Ok(rec)
}

/// `raw`'s channels named `names`, in that order.
fn pick(
    raw: &oddball_signal::Raw,
    names: &[String],
    path: &Path,
) -> Result<oddball_signal::Raw, IoError> {
    raw.pick_channels(names).map_err(|source| IoError::Signal {
        path: path.to_path_buf(),
        source,
    })
}

/// [`read_with`] without a montage.
fn read_tabular(path: &Path, options: &ReadOptions) -> Result<Recording, IoError> {
    if options.is_empty() {
        return crate::read(path);
    }
    let unsupported = |what: &str| {
        IoError::Unsupported {
        path: path.to_path_buf(),
        what: format!("{what} (reading options other than the channels kept and a montage apply to .csv and .mat files)"),
    }
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
                (options.time_column.is_some(), "a time column"),
                (options.events.is_some(), "an events column or variable"),
                (options.data.is_some(), "a data variable"),
            ] {
                if set {
                    given.push(name);
                }
            }
            if !given.is_empty() {
                return Err(unsupported(&format!(
                    "{} given for a file that records its own layout",
                    given.join(", ")
                )));
            }
            let rec = crate::read(path)?;
            match &options.channels {
                Some(ch) => {
                    let raw = pick(&rec.raw, ch, path)?;
                    Ok(Recording { raw, ..rec })
                }
                None => Ok(rec),
            }
        }
    }
}
