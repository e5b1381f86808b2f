//! Event-related potentials: the band-passed, baseline-corrected epochs of recordings split
//! into targets and non-targets, whose averages `oddball inspect --plot` draws.

use std::path::PathBuf;

use oddball_io::Recording;
use oddball_signal::detrend::DetrendKind;
use oddball_signal::epochs::EpochsParams;
use oddball_signal::filter::{Band, ButterworthParams};
use oddball_signal::preprocess::{Filtering, PreprocessParams};
use oddball_signal::{Epochs, SignalError};
use thiserror::Error;

/// Why there are no ERPs to draw.
#[derive(Debug, Error)]
pub enum ErpError {
    #[error(
        "{} has other channels or another sampling rate than {}: plot them one at a time",
        path.display(),
        first.display()
    )]
    Layout { path: PathBuf, first: PathBuf },
    #[error(
        "no ERP to plot: {targets} target and {nontargets} non-target epochs (the files must \
         flag targets)"
    )]
    Unlabelled { targets: usize, nontargets: usize },
    #[error(transparent)]
    Signal(#[from] SignalError),
}

/// The band-pass (a 4th-order zero-phase Butterworth after a linear detrend) and the epoch
/// window (s from the onset; the baseline is `tmin`..0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErpParams {
    pub l_freq: f64,
    pub h_freq: f64,
    pub tmin: f64,
    pub tmax: f64,
}

impl ErpParams {
    /// The band, as a plot's legend says it (`1–15 Hz`).
    pub fn band(&self) -> String {
        format!("{}–{} Hz", self.l_freq, self.h_freq)
    }

    fn preprocess(&self) -> PreprocessParams {
        PreprocessParams {
            band: ButterworthParams {
                order: 4,
                band: Band::Bandpass {
                    l_freq: self.l_freq,
                    h_freq: self.h_freq,
                },
            },
            filtering: Filtering::ZeroPhase {
                detrend: Some(DetrendKind::Linear),
            },
            epochs: EpochsParams::new(self.tmin, self.tmax).with_baseline(self.tmin.min(0.0), 0.0),
        }
    }

    /// The epochs of all `recordings` (which must share channels and rate), split into targets
    /// and non-targets: windows into the recordings, each filtered in its own memory (no copy
    /// of the samples).
    pub fn epochs(&self, recordings: Vec<Recording>) -> Result<(Epochs, Epochs), ErpError> {
        let params = self.preprocess();
        let Some(first) = recordings.first() else {
            return Err(ErpError::Unlabelled {
                targets: 0,
                nontargets: 0,
            });
        };
        let (first_path, first_names, first_sfreq) = (
            first.path.clone(),
            first.raw.ch_names().to_vec(),
            first.raw.sfreq(),
        );
        let mut target = Vec::new();
        let mut nontarget = Vec::new();
        for rec in recordings {
            let raw = rec.raw;
            if raw.ch_names() != first_names || raw.sfreq() != first_sfreq {
                return Err(ErpError::Layout {
                    path: rec.path,
                    first: first_path,
                });
            }
            let (epochs, _) = params.epochs_owned(raw)?;
            let idx = |want: bool| -> Vec<usize> {
                (0..epochs.n_epochs())
                    .filter(|&i| epochs.events()[i].target == Some(want))
                    .collect()
            };
            target.push(epochs.select(&idx(true)));
            nontarget.push(epochs.select(&idx(false)));
        }
        let target = Epochs::concatenate(&target)?;
        let nontarget = Epochs::concatenate(&nontarget)?;
        if target.is_empty() || nontarget.is_empty() {
            return Err(ErpError::Unlabelled {
                targets: target.n_epochs(),
                nontargets: nontarget.n_epochs(),
            });
        }
        Ok((target, nontarget))
    }
}
