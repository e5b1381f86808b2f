//! The one channel and rate policy of a run: every recording is matched to one [`Layout`] (a
//! model's, or the first training recording's) by channel name (any order, extra channels left
//! out) and resampled to its rate (`oddball_signal::resample`, polyphase as MNE's resample)
//! before anything is filtered. `evaluate` and `train` match each file to it; `benchmark` matches
//! a subject's runs to its first run's and refuses cross-subject pairs that differ.

use oddball_decode::model::Model;
use oddball_io::Recording;
use oddball_signal::SignalError;
use thiserror::Error;

/// Why a recording could not be matched to a layout.
#[derive(Debug, Error)]
pub enum LayoutError {
    /// A channel of the layout is missing from the recording (or the names cannot be matched).
    #[error("matching the channels of {recording} to those of {of}")]
    Channels {
        recording: String,
        of: String,
        #[source]
        source: oddball_decode::DecodeError,
    },
    /// Picking or renaming the matched channels failed.
    #[error("matching the channels of {recording} to those of {of}")]
    Pick {
        recording: String,
        of: String,
        #[source]
        source: SignalError,
    },
    /// Resampling to the layout's rate failed.
    #[error("{recording} is sampled at {from} Hz, {of} at {to} Hz; resampling it")]
    Resample {
        recording: String,
        of: String,
        from: f64,
        to: f64,
        #[source]
        source: SignalError,
    },
}

/// The channels (by name, in order) and the rate every recording of a run must have.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub ch_names: Vec<String>,
    pub sfreq: f64,
    /// What it is, for messages ("the model model.json", "the training file a.dat").
    pub of: String,
}

/// A recording resampled to a layout's rate: from and to (Hz), for a note to the user.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resampled {
    pub from: f64,
    pub to: f64,
}

impl Layout {
    /// The layout of `model`, saved at `path` (named in messages).
    pub fn of_model(model: &Model, path: &std::path::Path) -> Self {
        Self {
            ch_names: model.ch_names.clone(),
            sfreq: model.sfreq,
            of: format!("the model {}", path.display()),
        }
    }

    /// The layout of a training recording.
    pub fn of_recording(rec: &Recording) -> Self {
        Self {
            ch_names: rec.raw.ch_names().to_vec(),
            sfreq: rec.raw.sfreq(),
            of: format!("the training file {}", rec.path.display()),
        }
    }

    /// `rec` with this layout's channels in its order, at its rate; whether it was resampled.
    pub fn fit(&self, mut rec: Recording) -> Result<(Recording, Option<Resampled>), LayoutError> {
        let recording = rec.path.display().to_string();
        let raw = &rec.raw;
        if raw.ch_names() != self.ch_names.as_slice() {
            let order = oddball_decode::model::match_channels(&self.ch_names, raw.ch_names())
                .map_err(|source| LayoutError::Channels {
                    recording: recording.clone(),
                    of: self.of.clone(),
                    source,
                })?;
            let names: Vec<&str> = order.iter().map(|&i| raw.ch_names()[i].as_str()).collect();
            rec.raw = raw
                .pick_channels(&names)
                .and_then(|r| r.with_ch_names(self.ch_names.clone()))
                .map_err(|source| LayoutError::Pick {
                    recording: recording.clone(),
                    of: self.of.clone(),
                    source,
                })?;
        }
        let from = rec.raw.sfreq();
        if oddball_signal::rate::same_sfreq(from, self.sfreq) {
            return Ok((rec, None));
        }
        // Another rate is resampled (polyphase, as MNE's resample), not refused.
        rec.raw =
            oddball_signal::resample::resample_raw(&rec.raw, self.sfreq).map_err(|source| {
                LayoutError::Resample {
                    recording,
                    of: self.of.clone(),
                    from,
                    to: self.sfreq,
                    source,
                }
            })?;
        Ok((
            rec,
            Some(Resampled {
                from,
                to: self.sfreq,
            }),
        ))
    }
}

impl Layout {
    /// The layout of epochs (their channels and rate), named `of` in messages.
    pub fn of_epochs(epochs: &oddball_signal::Epochs, of: String) -> Self {
        Self {
            ch_names: epochs.ch_names().to_vec(),
            sfreq: epochs.sfreq(),
            of,
        }
    }

    /// How `other` differs from this layout, if it does ("their channels", or the two rates),
    /// when one must be scored by a model of the other without matching.
    pub fn differs(&self, other: &Layout) -> Option<String> {
        if self.ch_names != other.ch_names {
            Some("their channels".to_string())
        } else if self.sfreq != other.sfreq {
            Some(format!(
                "sampling rate ({} and {} Hz)",
                self.sfreq, other.sfreq
            ))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;
    use oddball_signal::{Events, Raw};

    fn rec(names: &[&str], sfreq: f64) -> Recording {
        let n = names.len();
        let data = Array2::from_shape_fn((n, 512), |(c, t)| (c * 1000 + t) as f64);
        let raw = Raw::new(
            data,
            sfreq,
            names.iter().map(|s| s.to_string()).collect(),
            Events::new(vec![]),
        )
        .unwrap();
        Recording {
            raw,
            format: oddball_io::Format::Csv,
            path: "r.csv".into(),
            speller: None,
            details: oddball_io::Details::Csv(oddball_io::csv::CsvInfo {
                columns: vec![],
                time_column: None,
                marker_column: None,
                timestamps: None,
                estimated_sfreq: None,
                sfreq_from_timestamps: false,
            }),
        }
    }

    #[test]
    fn channels_are_matched_by_name_and_rates_resampled() {
        let layout = Layout::of_recording(&rec(&["Cz", "Pz"], 256.0));
        let (same, note) = layout.fit(rec(&["Cz", "Pz"], 256.0)).unwrap();
        assert!(note.is_none());
        assert_eq!(same.raw.ch_names(), ["Cz", "Pz"]);
        let (swapped, _) = layout.fit(rec(&["Pz", "Oz", "Cz"], 256.0)).unwrap();
        assert_eq!(swapped.raw.ch_names(), ["Cz", "Pz"]);
        // Cz was channel 2 of the file: its samples come first now.
        assert_eq!(swapped.raw.data()[[0, 1]], 2001.0);
        let (slow, note) = layout.fit(rec(&["Cz", "Pz"], 128.0)).unwrap();
        assert_eq!(
            note,
            Some(Resampled {
                from: 128.0,
                to: 256.0
            })
        );
        assert_eq!(slow.raw.sfreq(), 256.0);
        let err = layout.fit(rec(&["Cz"], 256.0)).unwrap_err();
        assert!(matches!(err, LayoutError::Channels { .. }), "{err}");
        let other = Layout::of_recording(&rec(&["Cz", "Pz"], 128.0));
        assert_eq!(
            layout.differs(&other).as_deref(),
            Some("sampling rate (256 and 128 Hz)")
        );
        assert_eq!(layout.differs(&layout), None);
    }
}
